/* SPDX-License-Identifier: Apache-2.0 */
/* The safety supervisor: see supervisor.h. */
#include "supervisor.h"

#include <math.h>
#include <stddef.h>

#include "pma/status.h"
#include "pma/finite.h"

pma_fault_t pma_supervisor_check(const pma_supervisor_limits_t *lim,
                                 const pma_supervisor_input_t *in)
{
    if (lim == NULL || in == NULL) return PMA_FAULT_CONTROLLER;
    if (in->bus_off) return PMA_FAULT_CAN_BUS_OFF;
    if (!in->output_active) return PMA_FAULT_NONE;

    if (in->ticks_since_sample >= lim->sensor_timeout_ticks) return PMA_FAULT_SENSOR_TIMEOUT;
    switch (in->sensor_status) {
    case PMA_OK: break;
    case PMA_ERR_WIRE_BREAK: return PMA_FAULT_SENSOR_WIRE_BREAK;
    case PMA_ERR_RANGE: return PMA_FAULT_SENSOR_RANGE;
    default: return PMA_FAULT_SENSOR_READ;
    }
    /* a NaN position also trips */
    if (!pma_f32_within(in->x_cm, lim->x_lo_cm, lim->x_hi_cm)) {
        return PMA_FAULT_POSITION_LIMIT;
    }
    if (in->late_ticks > lim->max_late_ticks) return PMA_FAULT_TICK_OVERRUN;
    if (!in->running) return PMA_FAULT_NONE;

    if (lim->host_timeout_ticks != 0 && in->ticks_since_host_heartbeat >= lim->host_timeout_ticks) {
        return PMA_FAULT_HOST_HEARTBEAT_LOST;
    }
    if (in->controller_error) return PMA_FAULT_CONTROLLER;
    if (!pma_isfinite_f32(in->u)) return PMA_FAULT_NOT_FINITE;
    if (lim->barrier_ticks != 0 && in->barrier_run >= lim->barrier_ticks) return PMA_FAULT_BARRIER;
    return PMA_FAULT_NONE;
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
