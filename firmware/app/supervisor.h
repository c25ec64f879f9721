/* SPDX-License-Identifier: Apache-2.0 */
/* The safety supervisor: a pure function from what the loop observed in one
 * tick to a fault code, independent of the controllers (it reads their output
 * and flags, never their state). The application latches the first fault,
 * applies the safe output in the same tick, and keeps it until CLEAR_FAULTS.
 *
 * CAN bus-off is checked in every state. Then, while the output is active
 * (ARMED, RUNNING), in this order (the first that holds is reported): no new
 * sensor sample (plant bridge), sensor wire break, sensor out of range, sensor
 * read error, position beyond the constraints by more than the margin, tick
 * overrun; and while RUNNING: host heartbeat lost, controller error,
 * non-finite controller output, barrier clamped for too many consecutive
 * ticks. */
#ifndef PMA_SUPERVISOR_H
#define PMA_SUPERVISOR_H

#include <stddef.h>
#include <stdint.h>

#include "pma/finite.h"
#include "pma/status.h"

/* Fault codes: the HEARTBEAT FaultCode register (firmware/protocol/pma_proto.dbc). */
typedef enum pma_fault {
    PMA_FAULT_NONE = 0,
    PMA_FAULT_ESTOP = 1,               /* ESTOP or ESTOP_ALL received, or the ESTOP command */
    PMA_FAULT_POSITION_LIMIT = 2,      /* x outside [x_min - margin, x_max + margin] */
    PMA_FAULT_SENSOR_RANGE = 3,        /* sample outside the valid counts */
    PMA_FAULT_SENSOR_WIRE_BREAK = 4,   /* sample below the wire-break level */
    PMA_FAULT_SENSOR_READ = 5,         /* the ADC failed */
    PMA_FAULT_SENSOR_TIMEOUT = 6,      /* plant bridge: no new sample for too long */
    PMA_FAULT_BARRIER = 7,             /* PPC barrier clamped for too many consecutive ticks */
    PMA_FAULT_NOT_FINITE = 8,          /* NaN or infinity in the controller output */
    PMA_FAULT_TICK_OVERRUN = 9,        /* a tick served too late */
    PMA_FAULT_HOST_HEARTBEAT_LOST = 10,/* no HOST_HEARTBEAT while RUNNING for too long */
    PMA_FAULT_CAN_BUS_OFF = 11,        /* the CAN controller went bus-off */
    PMA_FAULT_CONTROLLER = 12,         /* a controller step returned an error */
    PMA_FAULT_WATCHDOG_RESET = 13,     /* the program was restarted by the watchdog */
    PMA_FAULT_OUTPUT = 14,             /* the DAC refused or failed a write (board; in the plant-bridge
                                          mode a PLANT_ACTUATOR frame that cannot be queued is
                                          counted, and the rig times out) */
    PMA_FAULT_INIT = 15,               /* start-up failed (CAN filters or the tick could not be set) */
} pma_fault_t;

typedef struct pma_supervisor_limits {
    float x_lo_cm, x_hi_cm;            /* the position envelope: safety.x_min_cm - x_margin_cm ..
                                          safety.x_max_cm + x_margin_cm [cm] */
    int32_t x_lo_q16, x_hi_q16;        /* the same for a position in Q16.16 [cm]: exactly the q
                                          whose pma_q16_to_f32(q) lies in the float envelope
                                          (pma_supervisor_limits_q16; empty: lo > hi) */
    uint32_t sensor_timeout_ticks;     /* >= 1 */
    uint32_t max_late_ticks;
    uint32_t host_timeout_ticks;       /* 0: disabled */
    uint32_t barrier_ticks;            /* 0: disabled */
} pma_supervisor_limits_t;

typedef struct pma_supervisor_input {
    uint8_t output_active;             /* ARMED or RUNNING */
    uint8_t running;
    uint8_t bus_off;
    int sensor_status;                 /* PMA_OK or the error of the sample's conversion */
    float x_cm;                        /* meaningful when sensor_status is PMA_OK */
    uint8_t x_in_q16;                  /* 1: the position is x_q16, checked against the
                                          Q16.16 envelope (the same answer as its float's) */
    int32_t x_q16;                     /* [cm] Q16.16 */
    uint32_t ticks_since_sample;       /* plant bridge; 0 when sampling the ADC */
    uint32_t late_ticks;               /* from pma_hal_tick_wait() */
    uint32_t ticks_since_host_heartbeat;
    uint8_t controller_error;          /* the step returned an error */
    float u;                           /* controller output (RUNNING) */
    uint32_t barrier_run;              /* consecutive ticks with a barrier clamp */
} pma_supervisor_input_t;

/* Inline: the application's tick builds `in` and this reads it at once, so that the compiler
 * keeps the fields in registers and loads only what the checks before the first fault need. */
static inline pma_fault_t pma_supervisor_check(const pma_supervisor_limits_t *lim,
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
    const int within = in->x_in_q16 ? (in->x_q16 >= lim->x_lo_q16 && in->x_q16 <= lim->x_hi_q16)
                                    : pma_f32_within(in->x_cm, lim->x_lo_cm, lim->x_hi_cm);
    if (!within) return PMA_FAULT_POSITION_LIMIT;
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

/* Sets lim->x_lo_q16 / x_hi_q16 from lim->x_lo_cm / x_hi_cm: q lies in them exactly where
 * pma_q16_to_f32(q) lies in the float envelope (that conversion is monotonic: two bisections,
 * at ARM, so that a tick in Q16.16 checks the position without converting it). */
void pma_supervisor_limits_q16(pma_supervisor_limits_t *lim);

/* Short name of a fault code, e.g. "SENSOR_WIRE_BREAK" (never NULL). */
const char *pma_fault_name(int fault);

#endif /* PMA_SUPERVISOR_H */
