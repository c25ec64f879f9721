/* SPDX-License-Identifier: Apache-2.0 */
/* The Linux host port of pma/hal.h: CAN on SocketCAN, time from
 * CLOCK_MONOTONIC, the control tick from an absolute-deadline sleep (real
 * time) or from received frames (lockstep), NVM in a file with flash
 * semantics, and a software watchdog that "resets" the program by
 * re-executing it. Link `pma_hal_linux` (host builds on Linux only).
 * docs/hal.md, section "Linux host port", describes it for users.
 *
 * Pass a pma_hal_linux_config_t as pma_hal_config_t.port:
 *
 *     pma_hal_linux_config_t lc = PMA_HAL_LINUX_CONFIG_INIT;
 *     lc.can_ifname = "vcan0";
 *     lc.storage_path = "pma-nvm.bin";
 *     lc.argv = argv;                  (main's argv: the watchdog re-executes it)
 *     const pma_hal_config_t cfg = {.port = &lc};
 *     if (pma_hal_init(&cfg) != PMA_OK) fprintf(stderr, "%s\n", pma_hal_linux_last_error());
 *
 * Start from PMA_HAL_LINUX_CONFIG_INIT: a zero-initialised config has
 * nvm_cut_after_ops = 0, which cuts the power at the first NVM operation.
 * pma_hal_init(NULL) (or .port NULL) uses PMA_HAL_LINUX_CONFIG_INIT as is.
 *
 * ADC and DAC: pma_hal_adc_read() and pma_hal_dac_write() return
 * PMA_ERR_NOT_IMPLEMENTED. The host has no converters: in the host build the
 * application receives the position sample and sends the pressure command
 * over CAN (a simulator or the HIL rig bridges them).
 *
 * Like every port, the device state is static (one device set per process)
 * and the pma_hal_* functions are called from one thread. The watchdog runs
 * in a thread of its own, which the port starts at the first
 * pma_hal_watchdog_start(); it shares only atomics with the caller. */
#ifndef PMA_HAL_LINUX_H
#define PMA_HAL_LINUX_H

#include <stdint.h>

#include "pma/hal.h"

/* Defaults for the zero values of the config fields below. */
#define PMA_HAL_LINUX_DEFAULT_IFNAME "vcan0"          /* only when no config is given */
#define PMA_HAL_LINUX_DEFAULT_NVM_BLOCK_SIZE 2048u    /* bytes: one STM32G4 page */
#define PMA_HAL_LINUX_DEFAULT_NVM_BLOCK_COUNT 4u
#define PMA_HAL_LINUX_DEFAULT_IDLE_WAKE_MS 10u
#define PMA_HAL_LINUX_NVM_PROGRAM_SIZE 8u             /* bytes, as on the STM32G4 */
#define PMA_HAL_LINUX_NVM_MAX_BYTES (64u * 1024u * 1024u) /* block_size x block_count */
#define PMA_HAL_LINUX_WATCHDOG_MAX_MS 60000u          /* pma_hal_watchdog_start() range 1..this */
#define PMA_HAL_LINUX_CAN_RX_DEPTH 256u               /* frames in the port's RX ring */
#define PMA_HAL_LINUX_CAN_RCVBUF_BYTES (1024 * 1024) /* the socket's receive buffer (best effort) */

/* Exit statuses of the process (chosen clear of the shell's 126/127, of
 * 128 + signal numbers and of hil/with-vcan's 2 and 125). */
#define PMA_HAL_LINUX_EXIT_WATCHDOG 84   /* watchdog expired and no argv to re-execute */
#define PMA_HAL_LINUX_EXIT_POWER_CUT 85  /* the nvm_cut_after_ops test hook cut the power */
#define PMA_HAL_LINUX_EXIT_RESET 86      /* pma_hal_system_reset() and no argv to re-execute */

/* Environment variable carrying the reset cause across a re-execution:
 * "WATCHDOG" and "SOFTWARE" (what the port sets: the watchdog, and
 * pma_hal_system_reset()), also "POWER_ON", "PIN", "BROWNOUT"; anything else reads as PMA_RESET_UNKNOWN,
 * absent as PMA_RESET_POWER_ON. The port reads and removes it (unsetenv) at
 * the first pma_hal_init() or pma_hal_reset_cause(), whichever comes first. */
#define PMA_HAL_LINUX_RESET_CAUSE_ENV "PMA_HAL_LINUX_RESET_CAUSE"

typedef struct pma_hal_linux_config {
    const char *can_ifname;        /* SocketCAN interface, e.g. "vcan0", "can0", which must be
                                      up (a controller with its bit rate: `ip link set can0 up
                                      type can bitrate 1000000 restart-ms 100`); required unless
                                      no_can */
    const char *storage_path;      /* file backing the NVM, created erased (0xFF) when absent;
                                      NULL: no NVM, its functions return
                                      PMA_ERR_NOT_IMPLEMENTED */
    uint32_t nvm_block_size;       /* bytes, a multiple of 8; 0: default 2048 */
    uint32_t nvm_block_count;      /* 0: default 4 */
    int lockstep;                  /* 0: real-time ticks (a clock); 1: a tick is a received frame
                                      with (id & tick_can_mask) == (tick_can_id & tick_can_mask) */
    uint16_t tick_can_id, tick_can_mask; /* lockstep only; 11 bits */
    int tick_can_dlc;              /* lockstep only: a tick frame must also have this data length
                                      (0..8); -1: any length */
    uint32_t lockstep_idle_wake_ms;/* lockstep: tick_wait returns PMA_ERR_EMPTY after this long
                                      without any frame; 0: default 10 */
    int32_t nvm_cut_after_ops;     /* test hook, -1: off. N >= 0: the (N+1)-th NVM program or
                                      erase applies only the first nvm_cut_permille/1000 of its
                                      bytes (synced to the file), then the process _exit()s
                                      with PMA_HAL_LINUX_EXIT_POWER_CUT, as a power cut would */
    uint32_t nvm_cut_permille;     /* 0..1000, see above (0: none of the bytes) */
    char *const *argv;             /* main's argv (must stay valid): the watchdog and
                                      pma_hal_system_reset() re-execute /proc/self/exe with it;
                                      NULL: they _exit() with PMA_HAL_LINUX_EXIT_WATCHDOG /
                                      PMA_HAL_LINUX_EXIT_RESET instead */
    int no_can;                    /* 1: no CAN device (can_ifname ignored, CAN functions return
                                      PMA_ERR_NOT_IMPLEMENTED; not with lockstep): for programs and
                                      tests of the other devices on kernels without SocketCAN */
} pma_hal_linux_config_t;

/* Every field at its default; nvm_cut_after_ops off. */
#define PMA_HAL_LINUX_CONFIG_INIT                                                            \
    {                                                                                         \
        .can_ifname = PMA_HAL_LINUX_DEFAULT_IFNAME, .storage_path = NULL,                    \
        .nvm_block_size = 0, .nvm_block_count = 0, .lockstep = 0, .tick_can_id = 0,           \
        .tick_can_mask = 0, .tick_can_dlc = -1, .lockstep_idle_wake_ms = 0,                   \
        .nvm_cut_after_ops = -1, .nvm_cut_permille = 0, .argv = NULL, .no_can = 0             \
    }

/* Why the last pma_hal_init() failed, in words, e.g. "CAN interface vcan7:
 * No such device (...)"; also set by later failures that have a reason
 * beyond their status code (CAN TX full: ENOBUFS or EAGAIN, socket and file
 * errors, a refused bus-off restart). "" after a successful pma_hal_init().
 * Never NULL; the text changes with the next failure. */
const char *pma_hal_linux_last_error(void);

#endif /* PMA_HAL_LINUX_H */
