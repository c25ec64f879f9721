/* SPDX-License-Identifier: Apache-2.0 */
/* Fake port: the test's clock, the control tick, the watchdog and the reset
 * cause. Time passes only when the test advances it or a tick wait sleeps. */
#include "fake_internal.h"

#include <stddef.h>

static struct {
    uint64_t now_us;
    /* tick */
    bool tick_running;
    uint32_t tick_period_us;
    uint64_t next_tick_us;       /* the next tick boundary not yet served */
    bool lockstep;               /* pma_fake_tick_lockstep() */
    bool granted;                /* lockstep: the next pma_hal_tick_wait() ticks */
    /* watchdog */
    bool wd_running;
    bool wd_expired;
    uint32_t wd_timeout_ms;
    uint64_t wd_kick_us;         /* last kick (or start) */
    pma_reset_cause_t reset_cause;   /* reported now */
    pma_reset_cause_t next_cause;    /* latched at the next restart */
    uint32_t reset_requests;         /* pma_hal_system_reset() calls since the last restart */
} t = {.reset_cause = PMA_RESET_POWER_ON, .next_cause = PMA_RESET_POWER_ON};

void pma_fake_set_reset_cause_(pma_reset_cause_t cause)
{
    t.next_cause = cause;
}

void pma_fake_time_reset_(pma_fake_reset_depth_t depth)
{
    t.tick_running = false;
    t.granted = false;
    if (depth >= PMA_FAKE_RESET_RESTART) {
        t.wd_running = false;
        t.wd_expired = false;
        t.reset_cause = t.next_cause;
        t.reset_requests = 0;
    }
    if (depth >= PMA_FAKE_RESET_ALL) {
        t.now_us = 0;
        t.lockstep = false;
    }
}

void pma_fake_tick_lockstep(bool on)
{
    t.lockstep = on;
    t.granted = false;
}

void pma_fake_tick_grant(void)
{
    t.granted = true;
}

static void watchdog_check(void)
{
    if (t.wd_running && !t.wd_expired &&
        t.now_us - t.wd_kick_us > (uint64_t)t.wd_timeout_ms * 1000u) {
        t.wd_expired = true;
    }
}

void pma_fake_time_advance_us(uint64_t dt_us)
{
    t.now_us += dt_us;
    watchdog_check();
}

uint64_t pma_hal_time_us(void)
{
    return t.now_us;
}

int pma_hal_tick_start(uint32_t period_us)
{
    if (!pma_fake_initialised()) return PMA_ERR_NOT_READY;
    if (period_us == 0) return PMA_ERR_RANGE;
    t.tick_period_us = period_us;
    t.next_tick_us = t.now_us + period_us;
    t.tick_running = true;
    return PMA_OK;
}

int pma_hal_tick_wait(uint32_t *late_ticks)
{
    if (!pma_fake_initialised() || !t.tick_running) return PMA_ERR_NOT_READY;
    if (t.lockstep) {
        if (late_ticks != NULL) *late_ticks = 0;
        if (!t.granted) return PMA_ERR_EMPTY;
        t.granted = false;
        if (t.now_us < t.next_tick_us) pma_fake_time_advance_us(t.next_tick_us - t.now_us);
        t.next_tick_us = t.now_us + t.tick_period_us;
        return PMA_OK;
    }
    uint64_t late = 0;
    if (t.now_us < t.next_tick_us) {
        pma_fake_time_advance_us(t.next_tick_us - t.now_us); /* sleep until the tick */
    } else {
        late = (t.now_us - t.next_tick_us) / t.tick_period_us + 1u; /* boundaries passed */
        t.next_tick_us += (late - 1u) * t.tick_period_us;           /* serve the latest */
    }
    t.next_tick_us += t.tick_period_us;
    if (late_ticks != NULL) *late_ticks = late > UINT32_MAX ? UINT32_MAX : (uint32_t)late;
    return PMA_OK;
}

int pma_hal_watchdog_start(uint32_t timeout_ms)
{
    if (timeout_ms == 0 || timeout_ms > PMA_FAKE_WATCHDOG_MAX_MS) return PMA_ERR_RANGE;
    /* like hardware, it runs whether or not the port was initialised */
    if (t.wd_expired) return PMA_OK;
    t.wd_timeout_ms = timeout_ms;
    t.wd_kick_us = t.now_us;
    t.wd_running = true;
    return PMA_OK;
}

void pma_hal_watchdog_kick(void)
{
    if (t.wd_running && !t.wd_expired) t.wd_kick_us = t.now_us;
}

pma_reset_cause_t pma_hal_reset_cause(void)
{
    return t.reset_cause;
}

void pma_hal_system_reset(void)
{
    ++t.reset_requests; /* the frames already sent are in the TX log: nothing to wait for */
}

uint32_t pma_fake_system_reset_requests(void)
{
    return t.reset_requests;
}

bool pma_fake_watchdog_expired(void)
{
    return t.wd_expired;
}

bool pma_fake_watchdog_running(void)
{
    return t.wd_running;
}
