/* SPDX-License-Identifier: Apache-2.0 */
/* pma-fw-host: the firmware application on the Linux host port (SocketCAN).
 * The same application code as the board's; the position sensor and the
 * pressure output are bridged over CAN (PLANT_SENSOR in, PLANT_ACTUATOR out)
 * to a plant simulator such as the HIL rig (hil/), which in lockstep mode also
 * clocks the control loop: one tick per sensor sample.
 *
 * Usage: see usage() below, or pma-fw-host --help. */
#define _XOPEN_SOURCE 700 /* realpath, gethostname */
#include <errno.h>
#include <getopt.h>
#include <limits.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "app.h"
#include "crc32.h"
#include "generated/pma_proto.h"
#include "pma_hal_linux.h"

#define EXIT_USAGE 2    /* bad command line */
#define EXIT_INIT 1     /* the HAL or the application could not start */
#define EXIT_RUNTIME 3  /* the loop failed */

/* NVM layout of the host build: 4 blocks of 2 KB, two per parameter slot. */
#define HOST_NVM_BLOCK_SIZE 2048u
#define HOST_NVM_BLOCKS 4u

static volatile sig_atomic_t stop_requested;

static void on_signal(int sig)
{
    (void)sig;
    stop_requested = 1;
}

static void usage(FILE *out)
{
    fprintf(out,
        "Usage: pma-fw-host --can IFACE [options]\n"
        "The PMA firmware application on SocketCAN. Position samples arrive in\n"
        "PLANT_SENSOR frames and pressure commands leave in PLANT_ACTUATOR frames\n"
        "(docs/protocol.md); everything else is set over CAN (pmactl, docs/parameters.md).\n"
        "\n"
        "Options:\n"
        "  --can IFACE         SocketCAN interface, e.g. vcan0 or can0 (required)\n"
        "  --node ID           CAN node id 0..15 (default: the stored sys.node_id, else 0)\n"
        "  --storage PATH      file holding the parameter storage (created erased when\n"
        "                      absent; default: none, SAVE then answers PMA_ERR_NOT_IMPLEMENTED)\n"
        "  --lockstep          one control tick per received PLANT_SENSOR frame, instead of\n"
        "                      real time at sys.tick_hz: deterministic HIL runs at any speed\n"
        "  --uid HEX           the device's 12-byte unique id, 24 hex digits (DEVICE_INFO);\n"
        "                      default: derived from the --storage file's path, else from the\n"
        "                      host name and process id\n"
        "  --watchdog-ms MS    software watchdog timeout, 1..60000 (default 1000); on expiry\n"
        "                      the program restarts itself and reports WATCHDOG_RESET\n"
        "  --verbose           log state changes and faults to stderr\n"
        "  --help              this text\n"
        "Test hooks (for the integration tests; never in production):\n"
        "  --test-nvm-cut-after N       the (N+1)-th storage program/erase is cut short\n"
        "                               and the process exits with status %d (a power cut)\n"
        "  --test-nvm-cut-permille P    how much of that operation is written, 0..1000\n"
        "  --test-stall-after-ticks N   stop serving the loop after N ticks (the watchdog fires)\n"
        "Exit status: 0 stopped by SIGINT/SIGTERM, 1 start-up failed (e.g. no such\n"
        "interface), 2 bad command line, 3 the loop failed.\n",
        PMA_HAL_LINUX_EXIT_POWER_CUT);
}

/* Whole-string decimal in [lo, hi], else 0. */
static int parse_long(const char *s, long lo, long hi, long *out)
{
    if (s == NULL || *s == '\0') return 0;
    char *end = NULL;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (errno != 0 || end == s || *end != '\0' || v < lo || v > hi) return 0;
    *out = v;
    return 1;
}

/* Exactly 2 * PMA_DEVICE_UID_BYTES hex digits into uid, else 0. */
static int parse_uid(const char *s, uint8_t uid[PMA_DEVICE_UID_BYTES])
{
    if (s == NULL || strlen(s) != 2u * PMA_DEVICE_UID_BYTES) return 0;
    for (unsigned k = 0; k < PMA_DEVICE_UID_BYTES; ++k) {
        unsigned v = 0;
        for (unsigned h = 0; h < 2u; ++h) {
            const char c = s[2u * k + h];
            unsigned d;
            if (c >= '0' && c <= '9') d = (unsigned)(c - '0');
            else if (c >= 'a' && c <= 'f') d = (unsigned)(c - 'a' + 10);
            else if (c >= 'A' && c <= 'F') d = (unsigned)(c - 'A' + 10);
            else return 0;
            v = (v << 4) | d;
        }
        uid[k] = (uint8_t)v;
    }
    return 1;
}

/* The default unique id: three CRC-32s of what identifies this device, each salted with its
 * index. The storage file is the device (its parameters live there), so the same file gives the
 * same id across restarts; without one, the host name and process id (a watchdog restart
 * re-executes in the same process, so it keeps its id). */
static void derive_uid(const char *storage, uint8_t uid[PMA_DEVICE_UID_BYTES])
{
    char what[PATH_MAX + 64];
    char resolved[PATH_MAX];
    if (storage != NULL && realpath(storage, resolved) != NULL) {
        snprintf(what, sizeof what, "storage:%s", resolved);
    } else {
        char host[64] = "";
        (void)gethostname(host, sizeof host - 1u);
        snprintf(what, sizeof what, "process:%s:%ld", host, (long)getpid());
    }
    for (unsigned k = 0; k < PMA_DEVICE_UID_BYTES / 4u; ++k) {
        const uint8_t salt = (uint8_t)k;
        const uint32_t c = pma_crc32_update(pma_crc32(&salt, 1u), what, strlen(what));
        for (unsigned b = 0; b < 4u; ++b) uid[4u * k + b] = (uint8_t)(c >> (8u * b));
    }
}

typedef struct options {
    const char *can, *storage;
    uint8_t uid[PMA_DEVICE_UID_BYTES];
    int have_uid;
    long node, watchdog_ms, cut_after, cut_permille, stall_after;
    int lockstep, verbose;
} options_t;

static int parse_options(int argc, char **argv, options_t *o)
{
    enum { OPT_WATCHDOG = 256, OPT_VERBOSE, OPT_CUT, OPT_PERMILLE, OPT_STALL, OPT_UID };
    static const struct option longopts[] = {
        {"can", required_argument, NULL, 'c'},
        {"node", required_argument, NULL, 'n'},
        {"storage", required_argument, NULL, 's'},
        {"lockstep", no_argument, NULL, 'l'},
        {"help", no_argument, NULL, 'h'},
        {"watchdog-ms", required_argument, NULL, OPT_WATCHDOG},
        {"uid", required_argument, NULL, OPT_UID},
        {"verbose", no_argument, NULL, OPT_VERBOSE},
        {"test-nvm-cut-after", required_argument, NULL, OPT_CUT},
        {"test-nvm-cut-permille", required_argument, NULL, OPT_PERMILLE},
        {"test-stall-after-ticks", required_argument, NULL, OPT_STALL},
        {NULL, 0, NULL, 0},
    };
    *o = (options_t){.node = -1, .watchdog_ms = 1000, .cut_after = -1, .cut_permille = 500,
                     .stall_after = -1};
    opterr = 0;
    int c;
    while ((c = getopt_long(argc, argv, ":", longopts, NULL)) != -1) {
        const char *bad = NULL;
        switch (c) {
        case 'c': o->can = optarg; break;
        case 's': o->storage = optarg; break;
        case 'l': o->lockstep = 1; break;
        case 'h': usage(stdout); exit(0);
        case OPT_VERBOSE: o->verbose = 1; break;
        case 'n': if (!parse_long(optarg, 0, 15, &o->node)) bad = "--node wants 0..15"; break;
        case OPT_UID:
            if (!parse_uid(optarg, o->uid)) bad = "--uid wants 24 hexadecimal digits (12 bytes)";
            o->have_uid = 1;
            break;
        case OPT_WATCHDOG:
            if (!parse_long(optarg, 1, PMA_HAL_LINUX_WATCHDOG_MAX_MS, &o->watchdog_ms)) {
                bad = "--watchdog-ms wants 1..60000";
            }
            break;
        case OPT_CUT:
            if (!parse_long(optarg, 0, INT32_MAX, &o->cut_after)) bad = "--test-nvm-cut-after wants N >= 0";
            break;
        case OPT_PERMILLE:
            if (!parse_long(optarg, 0, 1000, &o->cut_permille)) bad = "--test-nvm-cut-permille wants 0..1000";
            break;
        case OPT_STALL:
            if (!parse_long(optarg, 0, LONG_MAX, &o->stall_after)) bad = "--test-stall-after-ticks wants N >= 0";
            break;
        case ':':
            fprintf(stderr, "pma-fw-host: option %s needs a value\n", argv[optind - 1]);
            return 0;
        default:
            fprintf(stderr, "pma-fw-host: unknown option %s (try --help)\n", argv[optind - 1]);
            return 0;
        }
        if (bad != NULL) {
            fprintf(stderr, "pma-fw-host: bad value '%s': %s\n", optarg, bad);
            return 0;
        }
    }
    if (optind < argc) {
        fprintf(stderr, "pma-fw-host: unexpected argument '%s' (try --help)\n", argv[optind]);
        return 0;
    }
    if (o->can == NULL) {
        fprintf(stderr, "pma-fw-host: --can IFACE is required (try --help)\n");
        return 0;
    }
    return 1;
}

int main(int argc, char **argv)
{
    options_t o;
    if (!parse_options(argc, argv, &o)) return EXIT_USAGE;

    /* first: a stop request during start-up must end the program cleanly too */
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);

    pma_hal_linux_config_t lc = PMA_HAL_LINUX_CONFIG_INIT;
    lc.can_ifname = o.can;
    lc.storage_path = o.storage;
    lc.nvm_block_size = HOST_NVM_BLOCK_SIZE;
    lc.nvm_block_count = HOST_NVM_BLOCKS;
    lc.lockstep = o.lockstep;
    lc.nvm_cut_after_ops = (int32_t)o.cut_after;
    lc.nvm_cut_permille = (uint32_t)o.cut_permille;
    lc.argv = argv;
    /* the node id is known only after the parameters are loaded: tick on
     * PLANT_SENSOR of any node here, the application's filters then keep
     * only its own (another node's sample is not received at all) */
    lc.tick_can_id = PMA_PROTO_PLANT_SENSOR_FRAME_ID;
    lc.tick_can_mask = PMA_BASE_ID_MASK;
    lc.tick_can_dlc = PMA_PROTO_PLANT_SENSOR_LENGTH; /* a malformed sample is no tick */
    const pma_hal_config_t hc = {.can_bitrate_bps = 0, .port = &lc};
    if (pma_hal_init(&hc) != PMA_OK) {
        fprintf(stderr, "pma-fw-host: %s\n", pma_hal_linux_last_error());
        return EXIT_INIT;
    }

    static pma_app_t app; /* static: the board has no heap either */
    pma_app_platform_t plat = {
        .plant_bridge = 1,
        .lockstep = (uint8_t)o.lockstep,
        .node_id = (int16_t)o.node,
        .store_first_block = 0,
        .store_blocks_per_slot = o.storage != NULL ? HOST_NVM_BLOCKS / 2u : 0u,
        .watchdog_ms = (uint32_t)o.watchdog_ms,
    };
    if (o.have_uid) {
        memcpy(plat.device_uid, o.uid, sizeof plat.device_uid);
    } else {
        derive_uid(o.storage, plat.device_uid); /* after pma_hal_init: the file exists now */
    }
    int rc = pma_app_init(&app, &plat);
    if (rc != PMA_OK) {
        fprintf(stderr, "pma-fw-host: start-up failed: %s (%s)\n", pma_status_name(rc),
                pma_hal_linux_last_error());
        pma_hal_deinit();
        return EXIT_INIT;
    }
    fprintf(stderr, "pma-fw-host: node %u on %s, %s, %u Hz, parameters %s%s\n", app.node_id, o.can,
            o.lockstep ? "lockstep" : "real time", (unsigned)app.params.sys_tick_hz,
            app.storage.params_default ? "defaults" : "loaded from ", app.storage.params_default ? "" : o.storage);

    uint8_t last_state = app.state, last_fault = app.fault;
    if (o.verbose) fprintf(stderr, "pma-fw-host: state %s\n", pma_app_state_name(app.state));
    int status = 0;
    while (!stop_requested) {
        rc = pma_app_step(&app);
        if (rc != PMA_OK) {
            fprintf(stderr, "pma-fw-host: control loop failed: %s\n", pma_status_name(rc));
            status = EXIT_RUNTIME;
            break;
        }
        if (o.verbose && (app.state != last_state || app.fault != last_fault)) {
            fprintf(stderr, "pma-fw-host: state %s, fault %s\n", pma_app_state_name(app.state),
                    pma_fault_name(app.fault));
            last_state = app.state;
            last_fault = app.fault;
        }
        if (o.stall_after >= 0 && app.timing.ticks >= (uint64_t)o.stall_after) {
            fprintf(stderr, "pma-fw-host: stalling the loop (--test-stall-after-ticks)\n");
            for (;;) pause(); /* the watchdog restarts the program */
        }
    }
    pma_hal_deinit();
    return status;
}
