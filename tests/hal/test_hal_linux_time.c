/* SPDX-License-Identifier: Apache-2.0 */
/* Linux port, time and the real-time tick: a monotonic clock, and ticks on
 * absolute deadlines with the late_ticks semantics of pma/hal.h. Only lower
 * bounds of elapsed time are asserted, the ones guaranteed by construction
 * (a sleep on CLOCK_MONOTONIC never ends early); how late a busy machine
 * wakes us is never asserted. Lockstep ticks need CAN: test_hal_linux_can.c. */
#define _GNU_SOURCE

#include "test_hal_linux.h"

#include <time.h>

#define PERIOD_US 2000u

/* The fixture of the tick tests: the port up without CAN (the clock test
 * needs none). */
static void init_no_can(void)
{
    pma_hal_linux_config_t c = PMA_HAL_LINUX_CONFIG_INIT;
    c.no_can = 1;
    const pma_hal_config_t cfg = {.can_bitrate_bps = 0, .port = &c};
    assert_status(pma_hal_init(&cfg), PMA_OK);
}

/* After every test, also one that failed: the port down (a no-op when it was
 * not up). */
void tearDown(void)
{
    pma_hal_deinit();
}

/* Sleeps at least dt_us on CLOCK_MONOTONIC (the clock of pma_hal_time_us). */
static void sleep_us(uint64_t dt_us)
{
    const struct timespec ts = {.tv_sec = (time_t)(dt_us / 1000000u),
                                .tv_nsec = (long)(dt_us % 1000000u) * 1000L};
    struct timespec left = ts;
    while (clock_nanosleep(CLOCK_MONOTONIC, 0, &left, &left) != 0) {
    }
}

static void test_time_monotonic(void)
{
    uint64_t prev = pma_hal_time_us();
    for (int i = 0; i < 100000; ++i) {
        const uint64_t now = pma_hal_time_us();
        TEST_ASSERT_GREATER_OR_EQUAL_UINT64(prev, now);
        prev = now;
    }
    const uint64_t t0 = pma_hal_time_us();
    sleep_us(3000);
    TEST_ASSERT_GREATER_OR_EQUAL_UINT64(3000u, pma_hal_time_us() - t0);
}

static void test_tick_rules(void)
{
    init_no_can();
    uint32_t late = 99;
    assert_status(pma_hal_tick_wait(&late), PMA_ERR_NOT_READY); /* not started */
    TEST_ASSERT_EQUAL_INT(99, late);
    assert_status(pma_hal_tick_start(0), PMA_ERR_RANGE);
    assert_status(pma_hal_tick_wait(&late), PMA_ERR_NOT_READY);
    assert_status(pma_hal_tick_start(PERIOD_US), PMA_OK);
    assert_status(pma_hal_tick_wait(NULL), PMA_OK); /* late_ticks may be NULL */
    pma_hal_deinit();
    assert_status(pma_hal_tick_wait(&late), PMA_ERR_NOT_READY);
    assert_status(pma_hal_tick_start(PERIOD_US), PMA_ERR_NOT_READY);
}

/* The first tick falls one period after the start; each call serves one
 * boundary when it slept or was 1 late, n boundaries when n - 1 were skipped:
 * after calls with late_ticks l_i the clock has passed
 * start + period x sum(max(1, l_i)). */
static void test_tick_boundaries(void)
{
    init_no_can();
    const uint64_t before_start = pma_hal_time_us();
    assert_status(pma_hal_tick_start(PERIOD_US), PMA_OK);
    uint64_t boundaries = 0;
    for (int i = 0; i < 20; ++i) {
        uint32_t late = 0;
        assert_status(pma_hal_tick_wait(&late), PMA_OK);
        boundaries += late > 0 ? late : 1u;
        TEST_ASSERT_GREATER_OR_EQUAL_UINT64(before_start + boundaries * PERIOD_US,
                                            pma_hal_time_us());
    }
}

/* tick_start reads the clock (t0) and sets the first boundary to t0 + P; the
 * test then sleeps at least 5 P, so tick_wait sees now >= t0 + 5 P: the
 * boundaries t0 + P .. t0 + 5 P have passed, late_ticks >= 5 (four ticks
 * skipped, the fifth served late). */
static void test_tick_late(void)
{
    init_no_can();
    const uint64_t before_start = pma_hal_time_us();
    assert_status(pma_hal_tick_start(PERIOD_US), PMA_OK);
    sleep_us(5u * PERIOD_US);
    uint32_t late = 0;
    assert_status(pma_hal_tick_wait(&late), PMA_OK);
    printf("late_ticks after sleeping 5 periods: %u\n", (unsigned)late);
    TEST_ASSERT_GREATER_OR_EQUAL_UINT32(5u, late);
    /* it served the latest boundary passed; the next call serves a later one */
    uint64_t boundaries = late;
    assert_status(pma_hal_tick_wait(&late), PMA_OK);
    boundaries += late > 0 ? late : 1u;
    TEST_ASSERT_GREATER_OR_EQUAL_UINT64(before_start + boundaries * PERIOD_US, pma_hal_time_us());

    /* restarting re-bases the boundaries on the new start */
    const uint64_t before_restart = pma_hal_time_us();
    assert_status(pma_hal_tick_start(3u * PERIOD_US), PMA_OK);
    assert_status(pma_hal_tick_wait(&late), PMA_OK);
    TEST_ASSERT_GREATER_OR_EQUAL_UINT64(before_restart + 3u * PERIOD_US, pma_hal_time_us());
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_time_monotonic);
    RUN_TEST(test_tick_rules);
    RUN_TEST(test_tick_boundaries);
    RUN_TEST(test_tick_late);
    return UNITY_END();
}
