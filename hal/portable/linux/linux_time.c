/* SPDX-License-Identifier: Apache-2.0 */
/* Linux port: the clock (CLOCK_MONOTONIC) and the control tick, either in
 * real time (absolute deadlines, so that lateness never accumulates) or in
 * lockstep with received frames (linux_can.c decides what a tick frame is). */
#define _GNU_SOURCE

#include "linux_internal.h"

#include <errno.h>
#include <time.h>

/* Static: one tick per process, used from the main loop only. */
static struct {
    bool lockstep;
    uint32_t idle_wake_ms;
    bool running;
    uint32_t period_us;
    uint64_t next_tick_us;         /* real time: the next tick boundary not yet served */
} tick;

uint64_t pma_hal_time_us(void)
{
    struct timespec ts;
    (void)clock_gettime(CLOCK_MONOTONIC, &ts); /* cannot fail for this clock */
    return (uint64_t)ts.tv_sec * 1000000u + (uint64_t)ts.tv_nsec / 1000u;
}

void pma_linux_tick_configure(bool lockstep, uint32_t idle_wake_ms)
{
    pma_linux_tick_stop();
    tick.lockstep = lockstep;
    tick.idle_wake_ms = idle_wake_ms;
}

void pma_linux_tick_stop(void)
{
    tick.running = false;
    pma_linux_can_tick_disarm();
}

int pma_hal_tick_start(uint32_t period_us)
{
    if (!pma_linux_initialised()) return PMA_ERR_NOT_READY;
    if (period_us == 0) return PMA_ERR_RANGE;
    tick.period_us = period_us; /* lockstep: the simulator's business, unused here */
    tick.next_tick_us = pma_hal_time_us() + period_us;
    tick.running = true;
    if (tick.lockstep) pma_linux_can_tick_arm();
    return PMA_OK;
}

/* Sleeps until CLOCK_MONOTONIC reaches deadline_us (absolute: a signal that
 * interrupts the sleep does not stretch it). */
static void sleep_until_us(uint64_t deadline_us)
{
    const struct timespec at = {.tv_sec = (time_t)(deadline_us / 1000000u),
                                .tv_nsec = (long)(deadline_us % 1000000u) * 1000L};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &at, NULL) == EINTR) {
    }
}

int pma_hal_tick_wait(uint32_t *late_ticks)
{
    if (!pma_linux_initialised() || !tick.running) return PMA_ERR_NOT_READY;
    if (tick.lockstep) {
        /* Simulated time: a tick is a sample frame, one per frame, and
         * nothing is ever late (the simulator waits for the controller). */
        if (late_ticks != NULL) *late_ticks = 0;
        return pma_linux_can_tick_wait(tick.idle_wake_ms);
    }
    const uint64_t now_us = pma_hal_time_us();
    uint64_t late = 0;
    if (now_us < tick.next_tick_us) {
        sleep_until_us(tick.next_tick_us);
    } else {
        late = (now_us - tick.next_tick_us) / tick.period_us + 1u; /* boundaries passed */
        tick.next_tick_us += (late - 1u) * tick.period_us;         /* serve the latest */
    }
    tick.next_tick_us += tick.period_us;
    if (late_ticks != NULL) *late_ticks = late > UINT32_MAX ? UINT32_MAX : (uint32_t)late;
    return PMA_OK;
}
