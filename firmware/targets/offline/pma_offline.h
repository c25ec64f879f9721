/* SPDX-License-Identifier: Apache-2.0 */
/* libpma_offline: the firmware application on the fake port, as a shared
 * library for closed-loop runs without CAN (hil/offline.py loads it with
 * ctypes and steps it against the simulated rig, hil/rig.py).
 *
 * It runs what pma-fw-host --lockstep runs: the same application (app.c,
 * app_frames.c, the control library), the plant bridge forced on, one control
 * tick per PLANT_SENSOR frame. Everything reaches the application as CAN
 * frames through the fake CAN controller and one main-loop iteration
 * (pma_app_step()), and everything it says comes back as the frames it sent:
 *
 *   parameters  PARAM_REQ SET / GET, answered by PARAM_RESP (the application's
 *               own checks: type, NaN, range, state, the scaling groups);
 *   commands    COMMAND, answered by COMMAND_ACK (ARM, START, STOP, ...);
 *   a tick      [HOST_HEARTBEAT,] PLANT_SENSOR (the sample's counts, the next
 *               sequence number), answered by PLANT_ACTUATOR (the DAC counts)
 *               and, every telem.decimation ticks while RUNNING, TELEM_A..E.
 *
 * A parameter or command costs one loop iteration without a tick (as a frame
 * between two samples does in lockstep on the host). The fake's clock moves
 * one tick period per tick only, so the heartbeat (sys.heartbeat_ms) follows
 * control time here, the wall clock on the host: it changes no control
 * figure. No storage (SAVE answers NOT_IMPLEMENTED), no watchdog.
 *
 * One node per process: the fake port's state is static (pma_hal_fake.h).
 * Not thread-safe. Return codes are pma_status_t (0 PMA_OK, negative errors;
 * pma_offline_status_name()). */
#ifndef PMA_OFFLINE_H
#define PMA_OFFLINE_H

#include <stdint.h>

/* Bumped whenever a function or a struct below changes (hil/offline.py checks it). */
#define PMA_OFFLINE_API_VERSION 3

/* What one tick sent: the PLANT_ACTUATOR frame decoded, and the telemetry
 * frames if the tick sent them (telem_frames: bit i = TELEM_A + i, the values
 * exactly as on the bus), plus internals of the application after the tick
 * that no frame carries. */
typedef struct pma_offline_tick {
    /* PLANT_ACTUATOR (always one per tick) */
    uint32_t dac_counts;
    uint32_t seq;                 /* the sample's sequence number it answers */
    uint32_t sample_status;       /* 0 new, 1 repeated, 2 gap, 3 none (PMA_SAMPLE_*) */
    uint32_t output_active;
    /* TELEM_A..E */
    uint32_t telem_frames;        /* bit 0: TELEM_A ... bit 4: TELEM_E */
    uint32_t telem_time_ms;       /* A */
    float telem_x_cm;             /* A */
    float telem_xr_cm, telem_e_cm;            /* B */
    float telem_u, telem_v_cm_s;              /* C */
    float telem_internal1, telem_internal2;   /* D */
    float telem_pressure_kpa;                 /* E */
    uint32_t telem_ctrl_flags, telem_breaches; /* E */
    /* the application after the tick (pma_app_t) */
    uint32_t state;               /* pma_app_state_t */
    uint32_t fault;               /* pma_fault_t, latched */
    int32_t sensor_status;        /* PMA_OK or the conversion's error */
    float x_cm;                   /* the position the tick used */
    float u;                      /* the controller's output */
    float p_kpa;                  /* the pressure command */
    uint32_t barrier_run;         /* consecutive PPC barrier ticks */
    uint32_t other_frames;        /* other frames the tick sent (heartbeats) */
} pma_offline_tick_t;

int pma_offline_api_version(void);

/* The controller slot's arithmetic this library was built with (PMA_CTRL_ARITH,
 * docs/fixed-point.md): "f32" (preset host-offline) or "q16" (host-offline-q16). */
const char *pma_offline_ctrl_arith(void);

/* A fresh node: the fake port reset (clock 0) and initialised, the
 * application started with its defaults as node node_id (0..15), the BOOT
 * heartbeat discarded. PMA_ERR_RANGE for a bad node id, else pma_app_init()'s
 * result. */
int pma_offline_init(uint8_t node_id);

/* The parameter table (the application's, generated from params.toml). */
int pma_offline_param_count(void);
/* The id of a parameter by name; PMA_ERR_UNKNOWN_ID (or PMA_ERR_NULL). */
int pma_offline_param_id(const char *name);
/* The name of the index-th parameter (0 ..count-1), or NULL; its id in *id. */
const char *pma_offline_param_at(int index, uint16_t *id);
/* The parameter's type (0 f32, 1 u32, 2 i32) or PMA_ERR_UNKNOWN_ID. */
int pma_offline_param_type(uint16_t id);

/* PARAM_REQ SET of id with the parameter's own type: f32 parameters take
 * (float)value, integer ones value when it is a whole number inside the
 * type's range (else PMA_ERR_TYPE, nothing sent). Returns the PARAM_RESP
 * result; *now (may be NULL) is the value the node has afterwards. */
int pma_offline_param_set(uint16_t id, double value, double *now);
/* PARAM_REQ GET: the PARAM_RESP result, the value in *value. */
int pma_offline_param_get(uint16_t id, double *value);

/* COMMAND (pma_command_t, arg): the COMMAND_ACK result; the state after it in
 * *state (may be NULL). */
int pma_offline_command(uint8_t command, uint8_t arg, uint8_t *state);

/* HOST_HEARTBEAT: queued, handled with the next tick's frames (before its
 * sample), as the HIL runner sends it. */
int pma_offline_host_heartbeat(uint8_t counter);

/* One tick: PLANT_SENSOR with the next sequence number and raw_counts, one
 * loop iteration; *out what it sent. PMA_ERR_IO when no PLANT_ACTUATOR came
 * back (cannot happen unless the application is broken), else PMA_OK or the
 * loop's error. */
int pma_offline_tick(uint16_t raw_counts, pma_offline_tick_t *out);

/* Raw frames, for a host that speaks the protocol itself (hil/offline_bus.py: a python-can
 * bus whose other end is this node, so pmactl's client runs against the real firmware
 * without CAN). With the host queue on, every frame the node sends (also during a tick,
 * except the tick's PLANT_ACTUATOR, which the caller gets in pma_offline_tick_t) is kept
 * for pma_offline_frame_out, up to PMA_OFFLINE_HOST_QUEUE frames (then the newest are
 * dropped and counted, as a full socket buffer drops them). */
#define PMA_OFFLINE_HOST_QUEUE 512
void pma_offline_host_queue(int on);   /* off after pma_offline_init */
/* A frame from the host (11-bit id, dlc 0..8): queued in the node's receive queue, handled by
 * the next loop iteration (pma_offline_loop or a tick). PMA_ERR_RANGE for a bad id or dlc,
 * PMA_ERR_FULL when the receive queue is full. */
int pma_offline_frame_in(uint16_t id, uint8_t dlc, const uint8_t *data);
/* One main-loop iteration without a tick: the queued frames are handled. */
int pma_offline_loop(void);
/* The oldest frame the node sent that the host has not taken: PMA_OK, or PMA_ERR_EMPTY. */
int pma_offline_frame_out(uint16_t *id, uint8_t *dlc, uint8_t *data);
/* Frames dropped because the host queue was full, since init. */
uint32_t pma_offline_host_dropped(void);

int pma_offline_state(void);  /* pma_app_state_t */
int pma_offline_fault(void);  /* pma_fault_t */
uint64_t pma_offline_ticks(void);      /* ticks since init */
uint64_t pma_offline_time_us(void);    /* the fake clock */

const char *pma_offline_status_name(int rc);
const char *pma_offline_state_name(int state);
const char *pma_offline_fault_name(int fault);

#endif /* PMA_OFFLINE_H */
