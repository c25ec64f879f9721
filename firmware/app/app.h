/* SPDX-License-Identifier: Apache-2.0 */
/* The firmware application: the fixed-rate control loop, the state machine,
 * the safety supervisor's enforcement, parameters and storage, and the CAN
 * protocol (firmware/protocol/pma_proto.dbc, docs/protocol.md). Portable: it
 * calls only the HAL (pma/hal.h); the same code runs on the host port
 * (pma-fw-host) and on the board.
 *
 * State machine (docs/protocol.md has the full table):
 *
 *   BOOT --init--> IDLE --ARM--> ARMED --START--> RUNNING
 *                   ^  <-DISARM-   |   <--STOP---    |
 *                   |  <---------DISARM---------------
 *                   +--CLEAR_FAULTS-- FAULT <-- any fault, ESTOP (from any state)
 *
 *   BOOT     loading parameters; output safe.       (a watchdog reset boots into
 *   IDLE     output safe (safety.safe_mode).         FAULT, WATCHDOG_RESET)
 *   ARMED    output active, u = 0: the preset pressure act.p0_kpa (slew-limited).
 *   RUNNING  output active: the selected controller tracks the reference.
 *   FAULT    output safe, the first fault code latched until CLEAR_FAULTS.
 *
 * The loop (pma_app_step): wait for the tick, handle every received frame,
 * run the tick (sensor, controller, supervisor, output, telemetry), then
 * housekeeping (heartbeat, CAN bus-off), then kick the watchdog. A fault found
 * in a tick puts the safe output out in that same tick; one raised by a frame
 * (ESTOP) or by bus-off is applied at the next tick.
 *
 * No dynamic allocation, no globals: everything is in pma_app_t. */
#ifndef PMA_APP_H
#define PMA_APP_H

#include <stdint.h>

#include "clock_q16.h"
#include "controller.h"
#include "io_q16.h"
#include "params.h"
#include "pma/hal.h"
#include "pstore.h"
#include "supervisor.h"

typedef enum pma_app_state {
    PMA_STATE_BOOT = 0,
    PMA_STATE_IDLE = 1,
    PMA_STATE_ARMED = 2,
    PMA_STATE_RUNNING = 3,
    PMA_STATE_FAULT = 4,
} pma_app_state_t;

/* COMMAND frame, Command signal. */
typedef enum pma_command {
    PMA_CMD_ARM = 1,
    PMA_CMD_DISARM = 2,
    PMA_CMD_START = 3,
    PMA_CMD_STOP = 4,
    PMA_CMD_ESTOP = 5,
    PMA_CMD_CLEAR_FAULTS = 6,
    PMA_CMD_SELECT_CONTROLLER = 7, /* Arg: ctrl.mode */
    PMA_CMD_SELECT_REFERENCE = 8,  /* Arg: ref.kind */
    PMA_CMD_RESTART = 9,           /* software reset after the reply; output inactive only */
} pma_command_t;

/* PARAM_REQ Op signal. */
typedef enum pma_param_op {
    PMA_PARAM_OP_GET = 0,
    PMA_PARAM_OP_SET = 1,
    PMA_PARAM_OP_SAVE = 2,
    PMA_PARAM_OP_RESTORE_DEFAULTS = 3,
    PMA_PARAM_OP_GET_MIN = 4,
    PMA_PARAM_OP_GET_MAX = 5,
    PMA_PARAM_OP_GET_DEFAULT = 6,
    PMA_PARAM_OP_NEXT_ID = 7,
    PMA_PARAM_OP_LOAD = 8,
    PMA_PARAM_OP_GET_STATUS = 9,   /* a counter or status value by Id (PMA_STATUS_*) */
} pma_param_op_t;

/* HEARTBEAT Flags signal. */
#define PMA_HB_OUTPUT_ACTIVE   0x0001u
#define PMA_HB_PLANT_BRIDGE    0x0002u
#define PMA_HB_LOCKSTEP        0x0004u
#define PMA_HB_PARAMS_CHANGED  0x0008u /* set since the last load or save */
#define PMA_HB_PARAMS_DEFAULT  0x0010u /* storage held no record at start-up */
#define PMA_HB_CAN_PASSIVE     0x0020u
#define PMA_HB_SENSOR_VALID    0x0040u
#define PMA_HB_REF_ACTIVE      0x0080u
#define PMA_HB_SAVE_FAILED     0x0100u /* the last SAVE failed */
#define PMA_HB_GUARANTEE_LOST  0x0200u /* PPC: the guarantee was lost since START (controller.h) */
#define PMA_HB_FALLBACK        0x0400u /* PPC: MFAC is in charge (ppc.fallback MFAC or WIDEN) */

/* pma_app_t.tx_due: the frames a tick or poll of the core has to send (the step
 * has the frames adapter send them). */
#define PMA_APP_TX_ACTUATOR  0x01u /* PLANT_ACTUATOR (plant bridge) */
#define PMA_APP_TX_TELEMETRY 0x02u /* TELEM_A..E (telem.mask) */
#define PMA_APP_TX_HEARTBEAT 0x04u /* HEARTBEAT */

/* telem.mask bits: which telemetry frames a telemetry tick sends. */
#define PMA_TELEM_MASK_A 0x01u /* TELEM_A: run time, x */
#define PMA_TELEM_MASK_B 0x02u /* TELEM_B: x_r, e */
#define PMA_TELEM_MASK_C 0x04u /* TELEM_C: u, x' */
#define PMA_TELEM_MASK_D 0x08u /* TELEM_D: the controller's internals */
#define PMA_TELEM_MASK_E 0x10u /* TELEM_E: pressure, control flags, clamps */

/* PLANT_ACTUATOR Sample signal. */
#define PMA_SAMPLE_NEW      0u
#define PMA_SAMPLE_REPEATED 1u
#define PMA_SAMPLE_GAP      2u
#define PMA_SAMPLE_NONE     3u

/* Bytes of the unique device id (DEVICE_INFO UidLow: bytes 0..6, UidHigh: 7..11). */
#define PMA_DEVICE_UID_BYTES 12u

/* Node addressing: frame id = base id + node id. */
#define PMA_NODE_ID_MASK 0x00Fu
#define PMA_BASE_ID_MASK 0x7F0u

/* Frames taken from the CAN RX queue per loop iteration at most (bounds the
 * loop under a flood; the rest wait in the RX queue for the next iteration).
 * Taking one is cheap: a PARAM_REQ is only queued (below), every other frame
 * (emergency stops, plant bridge, commands, set-points, host heartbeats) is
 * handled at once, so the control-relevant frames never wait for requests. */
#define PMA_APP_RX_PER_STEP 128u
/* Requests (COMMAND, PARAM_REQ: the frames that are answered) handled per loop
 * iteration at most (a reply, perhaps a flash write, each), in the order received,
 * and the depth of the queue of those that wait for a later iteration; a request
 * that finds the queue full is dropped without a reply (counted: GET_STATUS
 * RX_DEFERRED, RX_DROPPED; docs/protocol.md). */
#define PMA_APP_PARAM_REQ_PER_STEP 8u
#define PMA_APP_PARAM_REQ_QUEUE 16u

/* Rules between parameters (docs/parameters.md "Rules between parameters"):
 * the number GET_STATUS LAST_RULE reports for the last SET, ARM or START that
 * one of them refused with PMA_ERR_RANGE. */
enum {
    PMA_RULE_NONE = 0,
    PMA_RULE_ADC_GAIN = 1,         /* adc.gain_cm_per_count != 0 */
    PMA_RULE_ADC_RAW_ORDER = 2,    /* adc.raw_min_counts <= adc.raw_max_counts */
    PMA_RULE_ADC_WIRE_BREAK = 3,   /* adc.wire_break_below_counts <= adc.raw_min_counts */
    PMA_RULE_DAC_GAIN = 4,         /* dac.counts_per_kpa != 0 */
    PMA_RULE_DAC_ORDER = 5,        /* dac.min_counts <= dac.max_counts */
    PMA_RULE_ACT_POLARITY = 6,     /* act.polarity is -1 or +1 */
    PMA_RULE_ACT_P_ORDER = 7,      /* 0 <= act.p_min_kpa < act.p_max_kpa */
    PMA_RULE_ACT_P0 = 8,           /* act.p_min_kpa <= act.p0_kpa <= act.p_max_kpa */
    PMA_RULE_SAFE_KPA = 9,         /* safety.safe_mode FIXED: safety.safe_kpa <= act.p_max_kpa */
    PMA_RULE_X_ORDER = 10,         /* safety.x_min_cm < safety.x_max_cm */
    PMA_RULE_U_ORDER = 11,         /* ctrl.u_min < ctrl.u_max */
    PMA_RULE_U_PRESSURE = 12,      /* p(ctrl.u_min), p(ctrl.u_max) in act.p_min_kpa..act.p_max_kpa */
};

/* PARAM_REQ Op GET_STATUS (9): Id selects one of the node's counters or status
 * values, answered as U32 (docs/protocol.md "Status values"). */
enum {
    PMA_STATUS_LAST_RULE = 1,      /* PMA_RULE_* of the last refusal by a rule, 0: none */
    PMA_STATUS_RX_OVERRUNS = 2,    /* frames lost in the CAN RX queue (controller, driver, socket) */
    PMA_STATUS_RX_DEFERRED = 3,    /* requests (COMMAND, PARAM_REQ) answered in a later loop iteration */
    PMA_STATUS_RX_DROPPED = 4,     /* requests dropped unanswered (request queue full) */
    PMA_STATUS_FRAMES_BAD = 5,     /* this node's frames with a wrong length or undecodable */
    PMA_STATUS_TICKS = 6,          /* control ticks since start-up (mod 2^32) */
    PMA_STATUS_FRAMES_RX = 7,      /* frames handled since start-up (mod 2^32) */
    PMA_STATUS_GUARANTEE_LOST_TICKS = 8, /* PPC: lost ticks since START (saturates at 2^32-1) */
    PMA_STATUS_GUARANTEE_LOST_AT_MS = 9, /* PPC: control time of the first, 0xFFFFFFFF: none */
    PMA_STATUS_BARRIER_BREACHES = 10,    /* PPC: ticks with a barrier clamp since START (saturates) */
};

/* While bus-off, recovery is requested at most this often (a request may
 * cost a netlink message or a controller re-initialisation). */
#define PMA_APP_RECOVER_INTERVAL_US 100000u

typedef struct pma_app_platform {
    uint8_t plant_bridge;          /* 1: the bridge is forced on (host build: no ADC or DAC);
                                      0: the parameter sys.plant_bridge decides (board) */
    uint8_t lockstep;              /* the port ticks on sensor frames (reported in the heartbeat) */
    int16_t node_id;               /* 0..15: overrides sys.node_id; -1: use the parameter */
    uint32_t store_first_block;    /* parameter storage: two slots of */
    uint32_t store_blocks_per_slot;/* this many NVM blocks; 0: no storage */
    uint32_t watchdog_ms;          /* 0: watchdog not started */
    uint8_t device_uid[PMA_DEVICE_UID_BYTES]; /* the device's unique id (DEVICE_INFO pages 3-4):
                                      the STM32's 96-bit UID; on the host from --uid or the
                                      storage file; all zero: unknown */
} pma_app_platform_t;

typedef struct pma_app_counters {
    uint32_t frames_rx;            /* frames handled */
    uint32_t frames_ignored;       /* other nodes' or unknown ids */
    uint32_t frames_bad;           /* ours, but wrong length or malformed (answered or dropped) */
    uint32_t tx_failed;            /* frames the HAL did not queue */
    uint32_t bridge_gaps, bridge_repeats;
    uint32_t setpoints_rejected;
    uint32_t req_deferred;         /* requests (COMMAND, PARAM_REQ) answered in a later iteration */
    uint32_t req_dropped;          /* requests dropped: the queue was full */
} pma_app_counters_t;

/* The parameter store and how RAM stands against it. */
typedef struct pma_app_storage {
    pma_pstore_t pstore;           /* the A/B slots (firmware/storage) */
    uint8_t ready;                 /* the store is configured (plat.store_blocks_per_slot > 0) */
    uint8_t params_changed;        /* RAM parameters differ from the saved set (heartbeat flag) */
    uint8_t params_default;        /* RAM holds the defaults: nothing valid was stored */
    uint8_t save_failed;           /* the last SAVE failed (the stored set is the one before) */
} pma_app_storage_t;

/* Time: the tick period and the counters and deadlines that run on it. */
typedef struct pma_app_timing {
    uint32_t period_us;            /* tick period, from sys.tick_hz */
    float period_s;
    uint64_t ticks;                /* since start-up */
    uint64_t run_ticks;            /* since START */
    uint32_t ticks_since_host_heartbeat;
    uint32_t late_ticks;           /* the late ticks the port reported at the last tick */
    uint64_t next_heartbeat_us;
    uint64_t next_recover_us;      /* bus-off: next recovery request */
    uint8_t heartbeat_counter;
    uint8_t tick_started;          /* the port's tick runs at period_us */
#if PMA_CTRL_Q16
    pma_clock_q16_t clock;         /* the control time run_ticks / sys.tick_hz, Q16.16 [s] */
#endif
} pma_app_timing_t;

#define PMA_APP_INPUT_KEY_WORDS 5u
/* The fixed-point input stage (io_q16.h) of the Q16.16 builds, built from the parameters in
 * `key` (their bits) while the output is inactive, kept while it is active (adc.* are
 * idle-only); ok: it represents them (else the float function runs). */
typedef struct pma_app_input_q16 {
    pma_input_q16_t stage;
    uint32_t key[PMA_APP_INPUT_KEY_WORDS];
    uint8_t built, ok;
} pma_app_input_q16_t;

/* This tick's position sample, from the ADC or the plant bridge. */
typedef struct pma_app_sensor {
    uint16_t raw_counts;
    int status;                    /* PMA_OK or the conversion's error */
    float x_cm;                    /* read it with pma_app_position_cm(): stale where x_in_q16 */
#if PMA_CTRL_Q16
    pma_q16_t x_q16;               /* the position in Q16.16: the controller slot's input */
    pma_app_input_q16_t q16;
#endif
    uint8_t sample_status;         /* pma_sample_status_t: how this tick's sample came */
#if PMA_CTRL_Q16
    uint8_t x_in_q16;              /* 1: the fixed-point stage made the sample, x_q16 is the
                                      position and its float is made only when read */
#endif
    uint32_t ticks_since_sample;   /* since the last new sample (saturates at UINT32_MAX) */
} pma_app_sensor_t;

/* The plant bridge's receive side (on: pma_app_bridge_on()). */
typedef struct pma_app_bridge {
    uint8_t active;                /* the bridge setting the state below belongs to */
    uint8_t have;                  /* a PLANT_SENSOR frame has come since the bridge went on */
    uint8_t fresh;                 /* one has come since the last tick */
    uint8_t gap;                   /* its sequence number skipped one or more */
    uint8_t seq;                   /* the last frame's sequence number */
    uint16_t raw_counts;           /* the last frame's sensor counts */
} pma_app_bridge_t;

/* The fixed-point output stage (io_q16.h) of the Q16.16 builds, built at the first active tick
 * after ARM (its parameters are idle-only); ok: it represents them (else the float functions
 * run). */
typedef struct pma_app_output_q16 {
    pma_output_q16_t stage;
    pma_q16_t p_kpa;               /* p_kpa as the stage wrote it, where p_valid */
    uint8_t built, ok, p_valid;
} pma_app_output_q16_t;

/* What the actuator is driven with. */
typedef struct pma_app_output {
    float u;                       /* the controller's output (its own units: kPa about p0);
                                      read it with pma_app_output_u(): stale where u_in_q16 */
#if PMA_CTRL_Q16
    pma_q16_t u_q16;               /* u in Q16.16, the slot's own number (always u's value) */
#endif
    float p_kpa;                   /* the pressure command; read it with pma_app_pressure_kpa():
                                      stale where the fixed-point stage wrote it (q16.p_valid) */
    uint16_t dac_counts;           /* and its DAC code */
#if PMA_CTRL_Q16
    uint8_t u_in_q16;              /* 1: u_q16 is the output and its float is made only when
                                      read (every mode but OPEN_LOOP, whose output is a float) */
    pma_app_output_q16_t q16;
#endif
} pma_app_output_t;

/* Requests waiting to be handled (a ring), in the order received. */
typedef struct pma_app_requests {
    pma_can_frame_t q[PMA_APP_PARAM_REQ_QUEUE];
    uint8_t head, count;
} pma_app_requests_t;

typedef struct pma_app {
    pma_app_platform_t plat;
    pma_params_t params;
    uint8_t state;                 /* pma_app_state_t */
    uint8_t fault;                 /* pma_fault_t, latched */
    uint8_t node_id;
    uint8_t reset_cause;
    uint8_t restart_pending;       /* RESTART accepted: pma_hal_system_reset() ends this step */
    uint8_t tx_due;                /* PMA_APP_TX_*: what the core's tick and poll have to send */
    uint8_t last_rule;             /* PMA_RULE_* of the last refusal by a rule */
    pma_app_storage_t storage;
    pma_app_timing_t timing;
    pma_supervisor_limits_t limits;  /* the supervisor's, built at ARM (app.c supervisor_limits) */
    pma_app_sensor_t sensor;
    pma_app_bridge_t bridge;
    pma_ctrl_t ctrl;
    uint32_t telem_count;          /* ticks since the last telemetry frame set */
    pma_app_output_t output;
    pma_app_counters_t counters;
    pma_app_requests_t requests;
} pma_app_t;

/* Starts the application on an initialised HAL (pma_hal_init() first): BOOT,
 * loads the parameters (defaults when storage holds none), sets the CAN
 * filters for the node id, starts the tick and the watchdog, sends a BOOT
 * heartbeat, and enters IDLE (FAULT WATCHDOG_RESET after a watchdog reset).
 * Returns PMA_OK or a HAL error from the filters or the tick (the state is
 * then FAULT); a storage failure is not an error (defaults are used; the
 * heartbeat shows it). */
int pma_app_init(pma_app_t *app, const pma_app_platform_t *plat);

/* Handles one received frame (the libFuzzer target). Never fails: bad frames
 * are answered with an error or dropped per docs/protocol.md. */
void pma_app_handle_frame(pma_app_t *app, const pma_can_frame_t *frame);

/* Runs one control tick; late_ticks from pma_hal_tick_wait(). */
void pma_app_tick(pma_app_t *app, uint32_t late_ticks);

/* Housekeeping outside the tick: heartbeat (by pma_hal_time_us), CAN bus-off. */
void pma_app_poll(pma_app_t *app);

/* One main-loop iteration: tick_wait, frames, tick, poll, watchdog kick, and
 * after an accepted RESTART (its COMMAND_ACK sent) pma_hal_system_reset(),
 * which returns only on the fake and template ports. Returns PMA_OK, or the error of pma_hal_tick_wait() other than
 * PMA_ERR_EMPTY (e.g. PMA_ERR_NOT_READY). */
int pma_app_step(pma_app_t *app);

/* A command as if received in a COMMAND frame (no reply sent); returns its
 * result code. RESTART only schedules the reset for the end of the step;
 * until then every other command but ESTOP is refused (PMA_ERR_STATE). */
int pma_app_command(pma_app_t *app, uint8_t command, uint8_t arg);

/* The parameter API (app_params.c): every transport's access to the parameters,
 * by id, with the application's policy; PARAM_REQ only decodes and encodes it.
 * set: the value checked against the table's range and access class for the
 * state, then on a trial copy against the rules between parameters that every
 * SET enforces (the sensor and DAC scalings as a group; a refusal records the
 * rule for GET_STATUS LAST_RULE); a new tick or heartbeat period applies at
 * once. get: the value and its type. save / load / restore_defaults: the
 * whole set to storage, from storage, to the defaults in RAM (not while the
 * output is active). status: a counter or status value by id (PMA_STATUS_*).
 * Each returns PMA_OK or a negative pma_status_t; a refused call changes
 * nothing. */
int pma_app_param_set(pma_app_t *app, uint16_t id, pma_param_type_t type, pma_param_value_t value);
int pma_app_param_get(const pma_app_t *app, uint16_t id, pma_param_type_t *type, pma_param_value_t *value);
int pma_app_params_save(pma_app_t *app);
int pma_app_params_load(pma_app_t *app);
int pma_app_params_restore_defaults(pma_app_t *app);
int pma_app_status_value(const pma_app_t *app, uint16_t id, uint32_t *value);

/* Latches a fault (the first one wins) and enters FAULT. */
void pma_app_raise_fault(pma_app_t *app, pma_fault_t fault);

const char *pma_app_state_name(int state);

/* 1 when the position comes from PLANT_SENSOR frames and the pressure command
 * leaves in PLANT_ACTUATOR frames instead of the ADC and DAC: forced on by
 * the platform (plat.plant_bridge, host build) or enabled by the parameter
 * sys.plant_bridge (board; settable only while the output is inactive). */
static inline int pma_app_bridge_on(const pma_app_t *app)   /* inline: several times a tick */
{
    return app->plat.plant_bridge != 0 || app->params.sys_plant_bridge != 0;
}

/* This tick's position [cm], the controller's output [its unit] and the pressure command [kPa]
 * in float. In the Q16.16 builds the fixed-point stages and the controller slot keep them in
 * Q16.16 and these make the float (pma_q16_to_f32) when read, not in every tick: read them
 * here, never from the fields. */
float pma_app_position_cm(const pma_app_t *app);
float pma_app_output_u(const pma_app_t *app);
float pma_app_pressure_kpa(const pma_app_t *app);

#endif /* PMA_APP_H */
