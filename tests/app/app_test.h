/* SPDX-License-Identifier: Apache-2.0 */
/* Shared harness of the application tests (Unity, fake HAL).
 *
 * The application under test is one static pma_app_t (`app`, 744 bytes at the
 * time of writing; test_app_commands.c prints it), driven as on a board: frames built with the generated
 * codec (firmware/protocol/generated/pma_proto.h) are injected into the fake
 * CAN controller, pma_app_step() runs one main-loop iteration (tick wait,
 * frames, tick, housekeeping, watchdog kick), and what the node sent is
 * popped from the fake's TX log after every step (the log keeps only 16
 * frames) into `cap`: per message kind a count and the last frame.
 *
 * Everything large is static: the Cortex-M0 test board has 16 KB of RAM. */
#ifndef PMA_APP_TEST_H
#define PMA_APP_TEST_H

#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "actuator.h"
#include "app.h"
#include "crc32.h"
#include "generated/pma_proto.h"
#include "params.h"
#include "pma/hal.h"
#include "scaling.h"
#include "pma/status.h"
#include "pma_hal_fake.h"
#include "pma_test.h"
#include "supervisor.h"

/* ------------------------------------------------------------ the rig -- */

/* RAM: on the Cortex-M0 board newlib, Unity and the fake HAL leave about
 * 2 KB of .data/.bss to a test (16 KB minus 6 KB stack, 4 KB minimum heap,
 * 3.3 KB libraries and board support, 0.8 KB fake devices): pma_app_t
 * (~740 bytes), the capture below (~150) and, only in the tests that need
 * storage, the fake NVM. A test file that stores parameters defines
 * T_NVM_BPS (blocks per slot) before including this header; the others run
 * without storage (store_blocks_per_slot 0, as a platform without NVM).
 * Parameter sets are compared by their CRC-32 rather than kept as copies. */
/* The controller slot's resolution (PMA_CTRL_Q16, firmware/app/controller.h): one Q16.16 LSB
 * (2^-16 = 1.5e-5) where the slot computes in fixed point, 0 in float. Tolerances on the
 * slot's signals add it. */
#if PMA_CTRL_Q16
#define CTRL_LSB (1.0 / 65536.0)
#define CTRL_F32(v) pma_q16_to_f32(v)   /* a Q16.16 state of the slot, in float */
#else
#define CTRL_LSB 0.0
#define CTRL_F32(v) (v)
#endif

#define T_NODE 3u          /* node id of the device under test (not 0: addressing matters) */
#define T_OTHER_NODE 5u    /* another node on the same bus */
#define T_BLOCK 16u        /* fake NVM: 16-byte blocks, 8-byte program unit */
#define T_PROG 8u
#define T_FIRST 0u         /* slot A from block 0, slot B right after */
#define T_WATCHDOG_MS 100u

/* Default scaling (params.toml): 1 kHz tick; x = 7.5 - 0.0030525 * counts;
 * 4.55 DAC counts per kPa; the preset pressure 300 kPa is 1365 counts. */
#define T_PERIOD_US 1000u
#define T_P0_COUNTS 1365u

static pma_app_t app;
static pma_app_platform_t plat;

#ifdef T_NVM_BPS
#define T_BLOCKS (2u * T_NVM_BPS)
static uint8_t nvm_mem[T_BLOCK * T_BLOCKS];
#define T_BPS ((uint32_t)T_NVM_BPS)
#else
#define T_BPS 0u
#endif

static inline pma_app_platform_t platform(uint8_t bridge)
{
    const pma_app_platform_t p = {
        .plant_bridge = bridge, .lockstep = 0, .node_id = (int16_t)T_NODE,
        .store_first_block = T_FIRST, .store_blocks_per_slot = T_BPS,
        .watchdog_ms = T_WATCHDOG_MS,
    };
    return p;
}

static inline uint32_t params_crc(const pma_params_t *p)
{
    return pma_crc32(p, sizeof *p);
}

/* Sensor counts for a position, by the scaling parameters the app has now. */
static inline uint16_t counts_at(float x_cm)
{
    const pma_params_t *p = &app.params;
    const pma_adc_scaling_t s = {
        .offset_cm = p->adc_offset_cm, .gain_cm_per_count = p->adc_gain_cm_per_count,
        .raw_min_counts = (uint16_t)p->adc_raw_min_counts,
        .raw_max_counts = (uint16_t)p->adc_raw_max_counts,
        .wire_break_below_counts = (uint16_t)p->adc_wire_break_below_counts,
    };
    uint16_t raw = 0;
    assert_status(pma_adc_cm_to_counts(&s, x_cm, &raw), PMA_OK);
    return raw;
}

/* DAC counts of a pressure, by the scaling parameters the app has now. */
static inline uint16_t dac_counts_of(float p_kpa)
{
    const pma_params_t *p = &app.params;
    const pma_dac_scaling_t s = {
        .counts_at_zero_kpa = p->dac_counts_at_zero_kpa, .counts_per_kpa = p->dac_counts_per_kpa,
        .min_counts = (uint16_t)p->dac_min_counts, .max_counts = (uint16_t)p->dac_max_counts,
    };
    uint16_t c = 0;
    assert_status(pma_dac_kpa_to_counts(&s, p_kpa, &c), PMA_OK);
    return c;
}

/* ---------------------------------------------------- what the node sent -- */

#define KIND(base_id) ((unsigned)((base_id) >> 4) & 0x0Fu)

/* Kinds whose last frame is kept: PLANT_ACTUATOR (3), COMMAND_ACK (5),
 * PARAM_RESP (8), HEARTBEAT (10), TELEM_A..E (11..15). */
static const int8_t keep_slot[16] = {-1, -1, -1, 0, -1, 1, -1, -1, 2, -1, 3, 4, 5, 6, 7, 8};

typedef struct capture {
    uint16_t count[16];            /* frames per base id / 16 */
    pma_can_frame_t kept[9];       /* the last frame of the kinds above */
    uint16_t total;
    uint16_t foreign;              /* frames not carrying this node's id */
} capture_t;

static capture_t cap;

static inline void cap_clear(void)
{
    memset(&cap, 0, sizeof cap);
}

/* Pops everything the node put on the bus into cap. */
static inline void drain(void)
{
    pma_can_frame_t f;
    while (pma_fake_can_tx_pop(&f) == PMA_OK) {
        const unsigned k = KIND(f.id);
        cap.count[k]++;
        if (keep_slot[k] >= 0) cap.kept[keep_slot[k]] = f;
        cap.total++;
        if ((f.id & PMA_NODE_ID_MASK) != app.node_id) cap.foreign++;
    }
    TEST_ASSERT_EQUAL_INT(0, pma_fake_can_tx_overwritten()); /* nothing lost from the log */
}

static inline uint32_t sent(uint16_t base_id)
{
    return cap.count[KIND(base_id)];
}

/* The last frame of a kept kind. */
static inline const pma_can_frame_t *last_frame(uint16_t base_id)
{
    const int8_t slot = keep_slot[KIND(base_id)];
    TEST_ASSERT_GREATER_OR_EQUAL(0, slot);
    return &cap.kept[slot];
}

/* ------------------------------------------------------------- start-up -- */

/* Fresh world: fake reset, NVM attached (erased) if the test has one, HAL up, the sensor at x_cm
 * (default scaling), the application started. The BOOT heartbeat is popped. */
static inline void start_with(uint8_t bridge, float x_cm)
{
    pma_fake_reset();
#ifdef T_NVM_BPS
    const pma_nvm_geometry_t g = {.block_size = T_BLOCK, .block_count = T_BLOCKS,
                                  .program_size = T_PROG};
    assert_status(pma_fake_nvm_attach(nvm_mem, sizeof nvm_mem, &g), PMA_OK);
#endif
    assert_status(pma_hal_init(NULL), PMA_OK);
    plat = platform(bridge);
    pma_params_defaults(&app.params); /* for counts_at() before init */
    pma_fake_adc_set(counts_at(x_cm));
    assert_status(pma_app_init(&app, &plat), PMA_OK);
    cap_clear();
    drain();
}

/* The MCU restarts (after pma_fake_reboot() or pma_fake_power_on()): HAL and
 * application start again on the same NVM contents. Returns pma_app_init's
 * result; the frames sent (the BOOT heartbeat) are in cap. */
static inline int restart_app(void)
{
    assert_status(pma_hal_init(NULL), PMA_OK);
    const int rc = pma_app_init(&app, &plat);
    cap_clear();
    drain();
    return rc;
}

/* --------------------------------------------------------------- frames -- */

static inline pma_can_frame_t frame_of(uint16_t base_id, uint8_t node, uint8_t dlc,
                                       const uint8_t *data)
{
    pma_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = (uint16_t)(base_id | node);
    f.dlc = dlc;
    if (data != NULL && dlc > 0) memcpy(f.data, data, dlc > 8 ? 8 : dlc);
    return f;
}

/* A frame from the host to this node, through the fake bus (must be accepted). */
static inline void inject(uint16_t base_id, uint8_t dlc, const uint8_t *data)
{
    const pma_can_frame_t f = frame_of(base_id, (uint8_t)app.node_id, dlc, data);
    assert_status(pma_fake_can_inject(&f), PMA_OK);
}

/* One main-loop iteration; what the node sent goes to cap (not cleared). */
static inline void step(void)
{
    assert_status(pma_app_step(&app), PMA_OK);
    drain();
}

static inline void steps(uint32_t n)
{
    for (uint32_t i = 0; i < n; ++i) step();
}

static inline void send_host_heartbeat(uint8_t counter);

/* n steps as a host keeps a RUNNING node alive: a HOST_HEARTBEAT every 100. */
static inline void steps_hb(uint32_t n)
{
    for (uint32_t i = 0; i < n; ++i) {
        if (i % 100u == 0) send_host_heartbeat((uint8_t)(i / 100u));
        step();
    }
}

/* ---------------------------------------------------------------- replies -- */

/* Sends a COMMAND frame, runs one step and returns its COMMAND_ACK (exactly
 * one must come, echoing command and arg). */
static inline struct pma_proto_command_ack_t command(uint8_t cmd, uint8_t arg)
{
    struct pma_proto_command_t m = {.command = cmd, .arg = arg};
    uint8_t d[8];
    TEST_ASSERT_EQUAL_INT(PMA_PROTO_COMMAND_LENGTH, pma_proto_command_pack(d, &m, sizeof d));
    inject(PMA_PROTO_COMMAND_FRAME_ID, PMA_PROTO_COMMAND_LENGTH, d);
    cap_clear();
    step();
    TEST_ASSERT_EQUAL_INT(1, sent(PMA_PROTO_COMMAND_ACK_FRAME_ID));
    const pma_can_frame_t *f = last_frame(PMA_PROTO_COMMAND_ACK_FRAME_ID);
    TEST_ASSERT_EQUAL_HEX16(PMA_PROTO_COMMAND_ACK_FRAME_ID | app.node_id, f->id);
    TEST_ASSERT_EQUAL_INT(PMA_PROTO_COMMAND_ACK_LENGTH, f->dlc);
    struct pma_proto_command_ack_t a;
    memset(&a, 0, sizeof a);
    TEST_ASSERT_EQUAL_INT(0, pma_proto_command_ack_unpack(&a, f->data, f->dlc));
    TEST_ASSERT_EQUAL_INT(cmd, a.command);
    TEST_ASSERT_EQUAL_INT(arg, a.arg);
    return a;
}

/* command(), and its result must be want. */
static inline void command_ok(uint8_t cmd, uint8_t arg, int want)
{
    const struct pma_proto_command_ack_t a = command(cmd, arg);
    assert_status(a.result, want);
}

typedef struct presp {
    uint8_t op, type;
    uint16_t id;
    int result;
    pma_param_value_t v;
} presp_t;

static inline presp_t decode_param_resp(const pma_can_frame_t *f)
{
    TEST_ASSERT_EQUAL_HEX16(PMA_PROTO_PARAM_RESP_FRAME_ID | app.node_id, f->id);
    TEST_ASSERT_EQUAL_INT(PMA_PROTO_PARAM_RESP_LENGTH, f->dlc);
    struct pma_proto_param_resp_t m;
    memset(&m, 0, sizeof m);
    TEST_ASSERT_EQUAL_INT(0, pma_proto_param_resp_unpack(&m, f->data, f->dlc));
    presp_t r;
    memset(&r, 0, sizeof r);
    r.op = m.op;
    r.type = m.type;
    r.id = m.id;
    r.result = m.result;
    switch (m.type) {
    case PMA_PARAM_F32: r.v.f32 = m.value_f32; break;
    case PMA_PARAM_U32: r.v.u32 = m.value_u32; break;
    case PMA_PARAM_I32: r.v.i32 = m.value_i32; break;
    default: r.v.u32 = 0; break;
    }
    return r;
}

/* Sends a PARAM_REQ (value in the signal Type selects), runs one step and
 * returns its PARAM_RESP (exactly one must come). */
static inline presp_t param_req_raw(uint8_t op, uint8_t type, uint16_t id, pma_param_value_t v,
                                    uint8_t reserved)
{
    struct pma_proto_param_req_t m;
    memset(&m, 0, sizeof m);
    m.op = op;
    m.type = type;
    m.id = id;
    m.reserved = reserved;
    m.value_f32 = v.f32;
    m.value_u32 = v.u32;
    m.value_i32 = v.i32;
    uint8_t d[8];
    TEST_ASSERT_EQUAL_INT(PMA_PROTO_PARAM_REQ_LENGTH, pma_proto_param_req_pack(d, &m, sizeof d));
    inject(PMA_PROTO_PARAM_REQ_FRAME_ID, PMA_PROTO_PARAM_REQ_LENGTH, d);
    cap_clear();
    step();
    TEST_ASSERT_EQUAL_INT(1, sent(PMA_PROTO_PARAM_RESP_FRAME_ID));
    const presp_t r = decode_param_resp(last_frame(PMA_PROTO_PARAM_RESP_FRAME_ID));
    TEST_ASSERT_EQUAL_INT(op, r.op);
    TEST_ASSERT_EQUAL_INT(id, r.id);
    return r;
}

static inline presp_t param_req(uint8_t op, uint8_t type, uint16_t id, pma_param_value_t v)
{
    return param_req_raw(op, type, id, v, 0);
}

static inline pma_param_value_t vf(float x)
{
    pma_param_value_t v;
    v.f32 = x;
    return v;
}

static inline pma_param_value_t vu(uint32_t x)
{
    pma_param_value_t v;
    v.u32 = x;
    return v;
}

static inline pma_param_value_t vi(int32_t x)
{
    pma_param_value_t v;
    v.i32 = x;
    return v;
}

/* SET through the protocol with the parameter's own type; returns the result. */
static inline int set_param(uint16_t id, pma_param_value_t v)
{
    const pma_param_desc_t *d = pma_param_find(id);
    TEST_ASSERT_NOT_NULL(d);
    return param_req(PMA_PARAM_OP_SET, d->type, id, v).result;
}

static inline void set_f32(uint16_t id, float x)
{
    assert_status(set_param(id, vf(x)), PMA_OK);
}

static inline void set_u32(uint16_t id, uint32_t x)
{
    assert_status(set_param(id, vu(x)), PMA_OK);
}

static inline void set_i32(uint16_t id, int32_t x)
{
    assert_status(set_param(id, vi(x)), PMA_OK);
}

static inline int whole_op(uint8_t op)
{
    return param_req(op, 0, 0, vu(0)).result;
}

/* The last HEARTBEAT in cap (one must have been sent). */
static inline struct pma_proto_heartbeat_t last_heartbeat(void)
{
    TEST_ASSERT_GREATER_THAN(0, sent(PMA_PROTO_HEARTBEAT_FRAME_ID));
    const pma_can_frame_t *f = last_frame(PMA_PROTO_HEARTBEAT_FRAME_ID);
    TEST_ASSERT_EQUAL_HEX16(PMA_PROTO_HEARTBEAT_FRAME_ID | app.node_id, f->id);
    TEST_ASSERT_EQUAL_INT(PMA_PROTO_HEARTBEAT_LENGTH, f->dlc);
    struct pma_proto_heartbeat_t h;
    memset(&h, 0, sizeof h);
    TEST_ASSERT_EQUAL_INT(0, pma_proto_heartbeat_unpack(&h, f->data, f->dlc));
    return h;
}

/* Steps until the next heartbeat (at most 10 s of ticks, the longest
 * sys.heartbeat_ms) and returns it. */
static inline struct pma_proto_heartbeat_t next_heartbeat(void)
{
    cap_clear();
    const uint32_t limit = 10u * app.params.sys_tick_hz + 2u;
    for (uint32_t i = 0; i < limit && sent(PMA_PROTO_HEARTBEAT_FRAME_ID) == 0; ++i) step();
    return last_heartbeat();
}

/* The last PLANT_ACTUATOR in cap (one must have been sent). */
static inline struct pma_proto_plant_actuator_t last_actuator(void)
{
    TEST_ASSERT_GREATER_THAN(0, sent(PMA_PROTO_PLANT_ACTUATOR_FRAME_ID));
    const pma_can_frame_t *f = last_frame(PMA_PROTO_PLANT_ACTUATOR_FRAME_ID);
    TEST_ASSERT_EQUAL_HEX16(PMA_PROTO_PLANT_ACTUATOR_FRAME_ID | app.node_id, f->id);
    TEST_ASSERT_EQUAL_INT(PMA_PROTO_PLANT_ACTUATOR_LENGTH, f->dlc);
    struct pma_proto_plant_actuator_t m;
    memset(&m, 0, sizeof m);
    TEST_ASSERT_EQUAL_INT(0, pma_proto_plant_actuator_unpack(&m, f->data, f->dlc));
    return m;
}

/* Plant bridge: one PLANT_SENSOR sample. */
static inline void send_sample(uint8_t seq, uint16_t raw)
{
    struct pma_proto_plant_sensor_t m = {.seq = seq, .raw_counts = raw};
    uint8_t d[8];
    TEST_ASSERT_EQUAL_INT(PMA_PROTO_PLANT_SENSOR_LENGTH,
                          pma_proto_plant_sensor_pack(d, &m, sizeof d));
    inject(PMA_PROTO_PLANT_SENSOR_FRAME_ID, PMA_PROTO_PLANT_SENSOR_LENGTH, d);
}

static inline void send_host_heartbeat(uint8_t counter)
{
    struct pma_proto_host_heartbeat_t m = {.counter = counter};
    uint8_t d[8];
    TEST_ASSERT_EQUAL_INT(PMA_PROTO_HOST_HEARTBEAT_LENGTH,
                          pma_proto_host_heartbeat_pack(d, &m, sizeof d));
    inject(PMA_PROTO_HOST_HEARTBEAT_FRAME_ID, PMA_PROTO_HOST_HEARTBEAT_LENGTH, d);
}

/* ------------------------------------------------------------------ DAC -- */

/* The newest DAC write; it must have happened at the current time (in the
 * step just run). */
static inline uint16_t dac_now(void)
{
    pma_fake_dac_write_t w;
    assert_status(pma_fake_dac_log(0, &w), PMA_OK);
    TEST_ASSERT_EQUAL_UINT64(pma_hal_time_us(), w.time_us);
    return w.counts;
}

/* The DAC write before the newest. */
static inline uint16_t dac_before(void)
{
    pma_fake_dac_write_t w;
    assert_status(pma_fake_dac_log(1, &w), PMA_OK);
    return w.counts;
}

/* ------------------------------------------------------- state set-ups -- */

/* IDLE with a valid sample (one tick run). */
static inline void to_idle(uint8_t bridge)
{
    start_with(bridge, -1.5f);
    if (bridge) send_sample(0, counts_at(-1.5f));
    step();
    assert_state(app.state, PMA_STATE_IDLE);
    assert_status(app.sensor.status, PMA_OK);
}

/* ARMED, the pressure settled at the preset (slew 20 kPa per tick: 15 ticks). */
static inline void to_armed(uint8_t bridge)
{
    to_idle(bridge);
    command_ok(PMA_CMD_ARM, 0, PMA_OK);
    for (uint8_t i = 0; i < 20u; ++i) {
        if (bridge) send_sample((uint8_t)(i + 1u), counts_at(-1.5f));
        step();
    }
    assert_state(app.state, PMA_STATE_ARMED);
}

/* RUNNING the default controller (PPC, HOLD at -1.5 cm) at x = -1.5 cm. */
static inline void to_running(uint8_t bridge)
{
    to_armed(bridge);
    if (bridge) send_sample(21, counts_at(-1.5f));
    command_ok(PMA_CMD_START, 0, PMA_OK);
    assert_state(app.state, PMA_STATE_RUNNING);
}

/* FAULT by ESTOP from IDLE. */
static inline void to_fault(uint8_t bridge)
{
    to_idle(bridge);
    command_ok(PMA_CMD_ESTOP, 0, PMA_OK);
    assert_state(app.state, PMA_STATE_FAULT);
}

#endif /* PMA_APP_TEST_H */
