/* SPDX-License-Identifier: Apache-2.0 */
/* The safety supervisor: see supervisor.h. */
#include "supervisor.h"

#include <math.h>
#include <stddef.h>

#include "pma/status.h"
#include "pma/finite.h"
#include "pma/fixed.h"

/* The first q in [lo, hi] (int64: hi + 1 where none) with pma_q16_to_f32(q) >= x_cm
 * (at_least) or > x_cm; the predicate is monotonic in q, as the conversion is. */
static int64_t first_q(int64_t lo, int64_t hi, float x_cm, int at_least)
{
    const float inf = INFINITY;
    while (lo <= hi) {
        const int64_t mid = lo + (hi - lo) / 2;
        const float f = pma_q16_to_f32((pma_q16_t)mid);
        const int holds = at_least ? pma_f32_within(f, x_cm, inf) : !pma_f32_within(f, -inf, x_cm);
        if (holds) {
            hi = mid - 1;
        } else {
            lo = mid + 1;
        }
    }
    return lo;
}

void pma_supervisor_limits_q16(pma_supervisor_limits_t *lim)
{
    if (lim == NULL) return;
    const int64_t qmin = INT32_MIN, qmax = INT32_MAX;
    /* a NaN bound makes the range empty by itself: no comparison with it holds */
    const int64_t lo = first_q(qmin, qmax, lim->x_lo_cm, 1);       /* f(q) >= x_lo_cm from here */
    const int64_t hi = first_q(qmin, qmax, lim->x_hi_cm, 0) - 1;   /* f(q) <= x_hi_cm up to here */
    const int empty = lo > hi;   /* also where either end lies beyond int32 */
    lim->x_lo_q16 = empty ? 1 : (int32_t)lo;
    lim->x_hi_q16 = empty ? 0 : (int32_t)hi;
}

const char *pma_fault_name(int fault)
{
    static const char *const names[] = {
        "NONE", "ESTOP", "POSITION_LIMIT", "SENSOR_RANGE", "SENSOR_WIRE_BREAK", "SENSOR_READ",
        "SENSOR_TIMEOUT", "BARRIER", "NOT_FINITE", "TICK_OVERRUN", "HOST_HEARTBEAT_LOST",
        "CAN_BUS_OFF", "CONTROLLER", "WATCHDOG_RESET", "OUTPUT", "INIT",
    };
    if (fault < 0 || (size_t)fault >= sizeof names / sizeof names[0]) return "UNKNOWN";
    return names[fault];
}
