/* SPDX-License-Identifier: Apache-2.0 */
/* Helper program of test_hal_linux_reset.c: does the things that end or
 * replace a process (watchdog reset, power cut), so that the test can
 * run it and check its exit status and output. Not a test by itself.
 *
 *   cause                      print the reset cause and the environment variable
 *   watchdog TIMEOUT_MS ARGV   start the watchdog, never kick; ARGV 1: init with
 *                              argv (the expiry re-executes this program, which
 *                              then reports the new cause and exits 0), 0: without
 *   kick TIMEOUT_MS RUN_MS FILE  kick every 2 ms for RUN_MS, note the last kick
 *                              in FILE, stop kicking; after the reset, check that it
 *                              came no earlier than TIMEOUT_MS after that kick
 *   shorten                    watchdog 60000 ms, then 20 ms: must expire soon
 *   powercut PATH AFTER PERMILLE   NVM 2 x 64 bytes with the power-cut hook, then
 *                              op0 program(0, 0, 64 B), op1 program(1, 0, 64 B),
 *                              op2 erase(0), op3 program(0, 8, 16 B)
 *
 * Exit status 0: done as planned; 3: the expected reset did not come within
 * 10 s; 4: a reset came when none was expected; 2: usage or HAL error. */
#define _GNU_SOURCE

#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "pma/hal.h"
#include "pma_hal_linux.h"

#define GIVE_UP_US 10000000u /* an expected reset that takes longer: failure */

static char **saved_argv;

static void sleep_ms(unsigned ms)
{
    const struct timespec ts = {.tv_sec = (time_t)(ms / 1000u),
                                .tv_nsec = (long)(ms % 1000u) * 1000000L};
    (void)clock_nanosleep(CLOCK_MONOTONIC, 0, &ts, NULL);
}

static int init(const char *storage, int32_t cut_after, uint32_t permille, int with_argv)
{
    pma_hal_linux_config_t c = PMA_HAL_LINUX_CONFIG_INIT;
    c.no_can = 1;
    c.storage_path = storage;
    c.nvm_block_size = 64;
    c.nvm_block_count = 2;
    c.nvm_cut_after_ops = cut_after;
    c.nvm_cut_permille = permille;
    c.argv = with_argv ? saved_argv : NULL;
    const pma_hal_config_t cfg = {.can_bitrate_bps = 0, .port = &c};
    const int rc = pma_hal_init(&cfg);
    if (rc != PMA_OK) printf("init failed: %s\n", pma_hal_linux_last_error());
    return rc;
}

static const char *env_or_unset(void)
{
    const char *v = getenv(PMA_HAL_LINUX_RESET_CAUSE_ENV);
    return v != NULL ? v : "(unset)";
}

/* Waits for the watchdog; returns 3 when it never comes. */
static int wait_for_reset(void)
{
    const uint64_t t0 = pma_hal_time_us();
    while (pma_hal_time_us() - t0 < GIVE_UP_US) sleep_ms(1);
    printf("no reset\n");
    return 3;
}

static int mode_watchdog(unsigned timeout_ms, int with_argv)
{
    const pma_reset_cause_t cause = pma_hal_reset_cause();
    printf("start cause=%d\n", (int)cause);
    if (cause == PMA_RESET_WATCHDOG) {
        printf("after reset env=%s\n", env_or_unset());
        return 0;
    }
    if (init(NULL, -1, 0, with_argv) != PMA_OK) return 2;
    if (pma_hal_watchdog_start(timeout_ms) != PMA_OK) return 2;
    printf("started\n");
    return wait_for_reset();
}

static int mode_kick(unsigned timeout_ms, unsigned run_ms, const char *file)
{
    if (pma_hal_reset_cause() == PMA_RESET_WATCHDOG) {
        const uint64_t now = pma_hal_time_us();
        FILE *f = fopen(file, "r");
        unsigned long long last_kick_us = 0;
        if (f == NULL || fscanf(f, "%llu", &last_kick_us) != 1) {
            printf("reset while kicking\n");
            return 4;
        }
        (void)fclose(f);
        printf("reset %s the timeout after the last kick\n",
               now - last_kick_us >= (uint64_t)timeout_ms * 1000u ? "no earlier than" : "before");
        return 0;
    }
    if (init(NULL, -1, 0, 1) != PMA_OK) return 2;
    if (pma_hal_watchdog_start(timeout_ms) != PMA_OK) return 2;
    const uint64_t t0 = pma_hal_time_us();
    while (pma_hal_time_us() - t0 < (uint64_t)run_ms * 1000u) {
        pma_hal_watchdog_kick();
        sleep_ms(2);
    }
    printf("kicked for %u ms\n", run_ms);
    /* Read before the last kick: the kick's own clock reading is no earlier,
     * so the reset comes more than timeout_ms after this. */
    const uint64_t last_kick = pma_hal_time_us();
    pma_hal_watchdog_kick();
    FILE *f = fopen(file, "w");
    if (f == NULL) return 2;
    fprintf(f, "%llu\n", (unsigned long long)last_kick);
    (void)fclose(f);
    return wait_for_reset();
}

static int mode_shorten(void)
{
    if (pma_hal_watchdog_start(60000) != PMA_OK) return 2;
    if (pma_hal_watchdog_start(20) != PMA_OK) return 2;
    printf("shortened\n");
    return wait_for_reset();
}

static int mode_powercut(const char *path, int32_t after, uint32_t permille)
{
    if (init(path, after, permille, 0) != PMA_OK) return 2;
    uint8_t a[64], b[64];
    for (unsigned i = 0; i < 64; ++i) {
        a[i] = (uint8_t)i;
        b[i] = (uint8_t)(0x40u + i);
    }
    int rc = pma_hal_nvm_program(0, 0, a, 64);
    printf("op0 %d\n", rc);
    if (rc == PMA_OK) rc = pma_hal_nvm_program(1, 0, b, 64);
    printf("op1 %d\n", rc);
    if (rc == PMA_OK) rc = pma_hal_nvm_erase(0);
    printf("op2 %d\n", rc);
    if (rc == PMA_OK) rc = pma_hal_nvm_program(0, 8, a, 16);
    printf("op3 %d\n", rc);
    return rc == PMA_OK ? 0 : 2;
}

int main(int argc, char **argv)
{
    setvbuf(stdout, NULL, _IONBF, 0); /* a reset or power cut loses buffered output */
    saved_argv = argv;
    if (argc == 2 && strcmp(argv[1], "cause") == 0) {
        const pma_reset_cause_t cause = pma_hal_reset_cause();
        printf("cause=%d env=%s\n", (int)cause, env_or_unset());
        /* init latches nothing new */
        if (init(NULL, -1, 0, 0) != PMA_OK) return 2;
        printf("after init cause=%d\n", (int)pma_hal_reset_cause());
        return 0;
    }
    if (argc == 4 && strcmp(argv[1], "watchdog") == 0) {
        return mode_watchdog((unsigned)strtoul(argv[2], NULL, 10), atoi(argv[3]));
    }
    if (argc == 5 && strcmp(argv[1], "kick") == 0) {
        return mode_kick((unsigned)strtoul(argv[2], NULL, 10),
                         (unsigned)strtoul(argv[3], NULL, 10), argv[4]);
    }
    if (argc == 2 && strcmp(argv[1], "shorten") == 0) return mode_shorten();
    if (argc == 5 && strcmp(argv[1], "powercut") == 0) {
        return mode_powercut(argv[2], (int32_t)strtol(argv[3], NULL, 10),
                             (uint32_t)strtoul(argv[4], NULL, 10));
    }
    fprintf(stderr, "usage: see tests/hal/test_hal_linux_helper.c\n");
    return 2;
}
