/* SPDX-License-Identifier: Apache-2.0 */
/* libFuzzer target: the application's CAN frame handler (pma_app_handle_frame)
 * and the loop around it, on one application instance per input, against the
 * fake HAL, with invariants checked after every operation.
 *
 * Input format (tests/fuzz/make_corpus.py writes seeds in it):
 *
 *   byte 0      platform: bit 0 plant bridge, bit 1 lockstep flag,
 *               bits 2-3 storage (0 none, 1: 2 KB blocks, 1 block per slot,
 *               2: 64-byte blocks, 7 per slot, 3: 64-byte blocks, 6 per slot:
 *               too small for the parameter blob), bit 4 watchdog (100 ms),
 *               bits 5-7 node id override (NODE_MAP below; 7: -1, the parameter)
 *   then records of REC_BYTES bytes: [op][a][b][c][d0..d7] (a short last
 *   record is zero-padded). op % OP_COUNT selects:
 *
 *   OP_FRAME       deliver {id, dlc, d} to pma_app_handle_frame: id = a | (b & 7) << 8
 *                  (b & 0x80: bits above 0x7FF too, an invalid id), dlc = c & 0x0F
 *                  (c & 0x80: dlc = c, up to 255): dlc > 8 and id > 0x7FF are exercised
 *   OP_FRAME_NODE  the same to this node: id = (a & 0x7F) << 4 | node id
 *   OP_TICK        1 + b ticks: clock += period, watchdog kick, [plant sample
 *                  (c & 1): d0|d1<<8 + i * (int8)d2 as ADC value or PLANT_SENSOR frame],
 *                  [HOST_HEARTBEAT frame (c & 2)], pma_app_tick(late), pma_app_poll;
 *                  late of the first tick: a & 0x80 ? a & 0x7F : 0 (a == 0xFF: UINT32_MAX)
 *   OP_STEP        1 + b loop iterations written out as pma_app_step does them
 *                  (tick_wait, received frames, tick, poll, kick), checked at each stage
 *   OP_REAL_STEP   1 + (b & 7) calls of pma_app_step itself
 *   OP_INJECT      a frame arrives on the fake bus (filters, RX queue): as OP_FRAME,
 *                  or node-relative when b & 0x40
 *   OP_ADVANCE     clock += a | b << 8 | (c & 0x3F) << 16 us, then pma_app_poll
 *   OP_POLL        pma_app_poll
 *   OP_ADC         c % 8: set a|b<<8, stuck, out of range a|b<<8, wire break, read error, clear;
 *                  the DAC fails every write (6) or works again (7)
 *   OP_CAN         c % 8: bus-off, error counters, bus errors, TX blocked, recovery delay,
 *                  drop, duplicate, all cleared
 *   OP_NVM         c % 3: power cut after a operations (b * 4 permille), ECC, stuck byte
 *   OP_REBOOT      c % 2: software/watchdog reboot or power-on, then pma_hal_init and
 *                  pma_app_init again (storage and the world outside the MCU are kept)
 *   OP_COMMAND     pma_app_command(a, b) (no reply)
 *   OP_PARAM       PARAM_REQ frame: Op a & 0x0F, id of table entry b, its type, value by
 *                  c % 5: d0..d3 raw, min, max, default, min + (max - min) * d0 / 255
 *   OP_SENSOR      position sample at x_min - margin + (x_max - x_min + 2 margin) * a / 255
 *                  (ADC value or PLANT_SENSOR frame)
 *   OP_SETPOINT    SETPOINT frame at x_min + (x_max - x_min) * a / 255
 *
 * At most MAX_RECORDS records and MAX_TICKS control ticks run per input.
 * The invariants are explained where they are checked: drain() (frames the
 * node sends), check_always(), check_command(), check_param_req(), deliver()
 * (frames), do_tick() (the output and the supervisor), do_poll(), start_app().
 * A violation prints the invariant and the record and calls __builtin_trap(),
 * which libFuzzer reports as a crash. */
#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "actuator.h"
#include "app.h"
#include "generated/pma_proto.h"
#include "generated/pma_proto_senders.h"
#include "scaling.h"
#include "params.h"
#include "pma/hal.h"
#include "pma_hal_fake.h"
#include "supervisor.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define REC_BYTES 12u
#define MAX_RECORDS 400u       /* longer inputs are cut: keeps one input fast */
#define MAX_TICKS 4096u        /* control ticks per input, all ops together */

enum {
    OP_FRAME, OP_FRAME_NODE, OP_TICK, OP_STEP, OP_REAL_STEP, OP_INJECT, OP_ADVANCE, OP_POLL,
    OP_ADC, OP_CAN, OP_NVM, OP_REBOOT, OP_COMMAND, OP_PARAM, OP_SENSOR, OP_SETPOINT,
    OP_COUNT
};

static const int16_t NODE_MAP[8] = {0, 1, 7, 15, 3, 10, 12, -1};

/* The sensor at x = -1.5 cm (the default reference) with the default ADC scaling. */
#define START_RAW_COUNTS 2948u

/* ------------------------------------------------------------ failure -- */

static uint32_t g_op_index; /* record being run, for the report */
static int g_op;

static void fail(int line, const char *what)
{
    fprintf(stderr, "\nfuzz_frames: INVARIANT VIOLATED (fuzz_frames.c:%d): %s\n"
                    "  at record %u (op %d)\n", line, what, (unsigned)g_op_index, g_op);
    __builtin_trap();
}

#define CHECK(cond)                                \
    do {                                           \
        if (!(cond)) fail(__LINE__, #cond);        \
    } while (0)

/* The check of the firmware bug found first (tests/fuzz/crashes/README.md:
 * after a fault the safe output did not reach the DAC and the active pressure
 * stayed on). Should it come back, PMA_FUZZ_DEFINES=PMA_FUZZ_SKIP_LEFT_ACTIVE
 * switches this one check off to look for other bugs meanwhile; CI runs
 * without it. */
#ifdef PMA_FUZZ_SKIP_LEFT_ACTIVE
#define CHECK_NOT_LEFT_ACTIVE() ((void)0)
#else
#define CHECK_NOT_LEFT_ACTIVE() CHECK(w.phys != PHYS_ACTIVE)
#endif

/* --------------------------------------------------------------- world -- */

/* Physical output as the harness knows it (non-bridge: the fake DAC's newest
 * accepted write; bridge: the newest PLANT_ACTUATOR frame on the bus). */
typedef enum phys {
    PHYS_SAFE = 0,    /* never written since the MCU started, or written by a tick
                         that ended with the output inactive */
    PHYS_ACTIVE = 1,  /* written by a tick with the output active */
    PHYS_UNKNOWN = 2, /* written inside pma_app_step (not observable stage by stage) */
} phys_t;

static struct {
    pma_app_t app;
    pma_app_platform_t plat;
    uint8_t node;
    uint8_t seq;               /* plant bridge: next PLANT_SENSOR Seq */
    uint8_t tx_faults;         /* drop/duplicate/blocked/bus errors were set in this input */
    uint8_t dac_broken;        /* pma_fake_dac_fail(true) in force */
    phys_t phys;
    uint32_t ticks;            /* budget */
    /* TX frames popped by drain() since reset_tx_seen() */
    struct {
        uint32_t total, ack, resp, actuator, heartbeat, telem, info;
        struct pma_proto_command_ack_t last_ack;
        uint8_t last_resp[8];
        struct pma_proto_plant_actuator_t act[8];
        uint32_t act_kept;
    } tx;
} w;

static uint8_t nvm_mem[2048u * 3u];

/* ------------------------------------------------------------- helpers -- */

/* The plant bridge is on when the platform forces it (input byte 0, bit 0) or
 * when sys.plant_bridge is 1: a parameter a PARAM SET, LOAD or RESTORE_DEFAULTS
 * may change, only while the output is inactive (check_param_req() checks
 * that for every idle-access parameter). Frames, sensor samples and the
 * output follow the parameter from the next tick on. */
static bool bridge_on(void)
{
    return w.plat.plant_bridge != 0 || w.app.params.sys_plant_bridge != 0;
}

static bool is_active(uint8_t state)
{
    return state == PMA_STATE_ARMED || state == PMA_STATE_RUNNING;
}

static uint32_t rd32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static void wr32(uint8_t *p, uint32_t v)
{
    for (int i = 0; i < 4; ++i) p[i] = (uint8_t)(v >> (8 * i));
}

static uint32_t field_bits(const pma_params_t *p, const pma_param_desc_t *d)
{
    uint32_t v;
    memcpy(&v, (const uint8_t *)p + d->offset, 4u);
    return v;
}

static bool near(float a, float b)
{
    const float scale = fmaxf(1.0f, fmaxf(fabsf(a), fabsf(b)));
    return fabsf(a - b) <= 1e-5f * scale;
}

/* Parameters that differ between two sets: how many, and the first one's id. */
static unsigned params_diff(const pma_params_t *a, const pma_params_t *b, uint16_t *first)
{
    if (memcmp(a, b, sizeof *a) == 0) return 0; /* the usual case, fast */
    unsigned n = 0;
    for (size_t i = 0; i < PMA_PARAM_COUNT; ++i) {
        const pma_param_desc_t *d = &pma_param_table[i];
        if (field_bits(a, d) != field_bits(b, d)) {
            if (n++ == 0 && first != NULL) *first = d->id;
        }
    }
    return n;
}

/* --------------------------------------------------- documented oracles -- */

/* Safe state (actuator.h, docs/parameters.md safety.safe_mode): VENT 0 kPa,
 * HOLD the previous command (0 if that is not a usable pressure), FIXED
 * min(safety.safe_kpa, act.p_max_kpa); at once, no slew limit. */
static float oracle_safe_kpa(const pma_params_t *p, float prev)
{
    switch (p->safety_safe_mode) {
    case PMA_SAFETY_SAFE_MODE_HOLD: return (isfinite(prev) && prev >= 0.0f) ? prev : 0.0f;
    case PMA_SAFETY_SAFE_MODE_FIXED:
        return p->safety_safe_kpa < p->act_p_max_kpa ? p->safety_safe_kpa : p->act_p_max_kpa;
    default: return 0.0f;
    }
}

/* Active output (actuator.h): p = clamp(p0 + polarity kpa_per_u u, p_min, p_max),
 * then at most slew * period from the previous command. */
static float oracle_active_kpa(const pma_params_t *p, float u, float prev, float period_s)
{
    if (!isfinite(u) || !isfinite(prev)) return oracle_safe_kpa(p, prev);
    float t = p->act_p0_kpa + (float)p->act_polarity * p->act_kpa_per_u * u;
    if (t < p->act_p_min_kpa) t = p->act_p_min_kpa;
    if (t > p->act_p_max_kpa) t = p->act_p_max_kpa;
    if (p->act_slew_kpa_s > 0.0f) {
        const float step = p->act_slew_kpa_s * period_s;
        if (t > prev + step) t = prev + step;
        if (t < prev - step) t = prev - step;
    }
    return t;
}

/* DAC counts (firmware/app/scaling.h): clamp(round(counts_at_zero + counts_per_kpa p),
 * min, max); false when the scaling is invalid (counts_per_kpa 0, min > max). */
static bool oracle_counts(const pma_params_t *p, float kpa, uint16_t *counts)
{
    if (p->dac_counts_per_kpa == 0.0f || p->dac_min_counts > p->dac_max_counts) return false;
    if (!isfinite(kpa)) return false;
    const uint16_t lo = (uint16_t)p->dac_min_counts, hi = (uint16_t)p->dac_max_counts;
    const float v = p->dac_counts_at_zero_kpa + p->dac_counts_per_kpa * kpa;
    if (!(v > (float)lo)) {
        *counts = lo;
    } else if (!(v < (float)hi)) {
        *counts = hi;
    } else {
        *counts = (uint16_t)(v + 0.5f);
    }
    return true;
}

/* The sensor and DAC scalings (params.toml: they act even while the output is
 * inactive, so every SET, LOAD and start-up keeps each valid as a whole). */
static bool scalings_valid(const pma_params_t *p)
{
    const bool adc = p->adc_gain_cm_per_count != 0.0f &&
                     p->adc_raw_min_counts <= p->adc_raw_max_counts &&
                     p->adc_wire_break_below_counts <= p->adc_raw_min_counts;
    const bool dac = p->dac_counts_per_kpa != 0.0f && p->dac_min_counts <= p->dac_max_counts;
    return adc && dac;
}

/* The rules between parameters that ARM checks (docs/parameters.md, actuator.h,
 * scaling.h), except ctrl.u_min < u_max, which is a "stopped" pair that
 * may be changed while ARMED (START checks it again). */
static bool config_armable(const pma_params_t *p)
{
    const bool act = (p->act_polarity == 1 || p->act_polarity == -1) &&
                     p->act_p_min_kpa >= 0.0f && p->act_p_min_kpa < p->act_p_max_kpa &&
                     p->act_p0_kpa >= p->act_p_min_kpa && p->act_p0_kpa <= p->act_p_max_kpa &&
                     p->act_kpa_per_u > 0.0f && p->act_slew_kpa_s >= 0.0f &&
                     p->safety_safe_mode <= PMA_SAFETY_SAFE_MODE_FIXED &&
                     (p->safety_safe_mode != PMA_SAFETY_SAFE_MODE_FIXED ||
                      (p->safety_safe_kpa >= 0.0f && p->safety_safe_kpa <= p->act_p_max_kpa));
    return act && scalings_valid(p) && p->safety_x_min_cm < p->safety_x_max_cm;
}

/* ---------------------------------------------------------------- TX log -- */

static void reset_tx_seen(void)
{
    memset(&w.tx, 0, sizeof w.tx);
}

/* The DBC's length of a message this node (DBC node PMA) sends; 0xFF for any other id
 * (the list is generated from the DBC: generated/pma_proto_senders.h). */
static uint8_t dbc_length(uint16_t base)
{
    switch (base) {
#define PMA_FUZZ_TX_LENGTH(name, id, length) \
    case (id): return (length);
        PMA_PROTO_PMA_TX_MESSAGES(PMA_FUZZ_TX_LENGTH)
#undef PMA_FUZZ_TX_LENGTH
    default: return 0xFFu; /* not a message this node sends */
    }
}

/* Pops every frame the node put on the bus and checks each one:
 *  - its id is one of the messages the DBC has PMA send, for this node
 *    (frame id = base id + node id), with the DBC's length;
 *  - a HEARTBEAT reports a consistent state: State is BOOT..FAULT, FaultCode is
 *    non-zero exactly in FAULT, the output-active flag only in ARMED/RUNNING,
 *    the plant-bridge flag as configured;
 *  - PLANT_ACTUATOR only in plant-bridge mode. */
static void drain(void)
{
    pma_can_frame_t f;
    while (pma_fake_can_tx_pop(&f) == PMA_OK) {
        CHECK(f.id <= PMA_CAN_ID_MAX && f.dlc <= PMA_CAN_DLC_MAX);
        CHECK((f.id & PMA_NODE_ID_MASK) == w.node);
        const uint16_t base = (uint16_t)(f.id & PMA_BASE_ID_MASK);
        CHECK(dbc_length(base) != 0xFFu);
        CHECK(f.dlc == dbc_length(base));
        ++w.tx.total;
        switch (base) {
        case PMA_PROTO_COMMAND_ACK_FRAME_ID:
            CHECK(pma_proto_command_ack_unpack(&w.tx.last_ack, f.data, f.dlc) == 0);
            CHECK(w.tx.last_ack.result <= 0);
            CHECK(w.tx.last_ack.state <= PMA_STATE_FAULT);
            ++w.tx.ack;
            break;
        case PMA_PROTO_PARAM_RESP_FRAME_ID:
            memcpy(w.tx.last_resp, f.data, 8u);
            CHECK((int8_t)f.data[3] <= 0);
            ++w.tx.resp;
            break;
        case PMA_PROTO_HEARTBEAT_FRAME_ID: {
            struct pma_proto_heartbeat_t hb;
            CHECK(pma_proto_heartbeat_unpack(&hb, f.data, f.dlc) == 0);
            CHECK(hb.state <= PMA_STATE_FAULT);
            CHECK((hb.state == PMA_STATE_FAULT) == (hb.fault_code != 0));
            CHECK(strcmp(pma_fault_name(hb.fault_code), "UNKNOWN") != 0);
            CHECK(((hb.flags & PMA_HB_OUTPUT_ACTIVE) != 0) == is_active(hb.state));
            CHECK(((hb.flags & PMA_HB_PLANT_BRIDGE) != 0) == bridge_on());
            ++w.tx.heartbeat;
            break;
        }
        case PMA_PROTO_PLANT_ACTUATOR_FRAME_ID: {
            CHECK(bridge_on());
            struct pma_proto_plant_actuator_t a;
            CHECK(pma_proto_plant_actuator_unpack(&a, f.data, f.dlc) == 0);
            if (w.tx.act_kept < 8u) w.tx.act[w.tx.act_kept++] = a;
            ++w.tx.actuator;
            break;
        }
        case PMA_PROTO_DEVICE_INFO_FRAME_ID: {
            struct pma_proto_device_info_t di;
            CHECK(pma_proto_device_info_unpack(&di, f.data, f.dlc) == 0);
            CHECK(di.page <= 4u); /* the DBC's pages 0 to 4 */
            ++w.tx.info;
            break;
        }
        default:
            ++w.tx.telem;
            break;
        }
    }
}

/* ------------------------------------------------------ state invariants -- */

typedef struct snap {
    uint8_t state, fault;
    pma_params_t params;
    float p_kpa;
    uint16_t dac_counts;
    uint32_t dac_writes;
    pma_app_counters_t counters;
    uint8_t bus_off;           /* the CAN controller was bus-off */
} snap_t;

static void take(snap_t *s)
{
    s->state = w.app.state;
    s->fault = w.app.fault;
    s->params = w.app.params;
    s->p_kpa = pma_app_pressure_kpa(&w.app);
    s->dac_counts = w.app.output.dac_counts;
    s->dac_writes = pma_fake_dac_write_count();
    s->counters = w.app.counters;
    pma_can_status_t cs;
    s->bus_off = (uint8_t)(pma_hal_can_status(&cs) == PMA_OK && cs.state == PMA_CAN_BUS_OFF);
}

/* After every operation:
 *  - the state is IDLE..FAULT (BOOT exists only inside pma_app_init, which
 *    succeeded);
 *  - a fault code is latched exactly in FAULT (app.h: FAULT latches the first
 *    fault until CLEAR_FAULTS, which leaves FAULT with the code cleared), and
 *    it is one of pma_fault_t;
 *  - every parameter is inside its table range and finite: pma_param_set()
 *    checks each value and nothing else writes the parameters
 *    (RESTORE_DEFAULTS, LOAD and loading at start-up go through the table);
 *  - the node id is the one chosen at start-up (sys.node_id "takes effect at
 *    the next start-up");
 *  - the tick period is round(1e6 / sys.tick_hz) and the tick runs;
 *  - the pressure command is finite and within [0, 1000] kPa: safe values are
 *    0, safety.safe_kpa (0..1000) or a held earlier command; active ones lie
 *    between an earlier command and a target clamped to act.p_min..p_max
 *    (both within 0..1000);
 *  - the sensor and DAC scalings are valid in every state (params.toml);
 *  - while the output is active (ARMED, RUNNING) the parameters satisfy the
 *    rules ARM checked: the actuator, sensor and DAC settings and the safety
 *    limits are "idle" parameters, which no SET, RESTORE_DEFAULTS or LOAD may
 *    change while the output is active. */
static void check_always(void)
{
    const pma_app_t *a = &w.app;
    CHECK(a->state >= PMA_STATE_IDLE && a->state <= PMA_STATE_FAULT);
    CHECK((a->state == PMA_STATE_FAULT) == (a->fault != PMA_FAULT_NONE));
    CHECK(strcmp(pma_fault_name(a->fault), "UNKNOWN") != 0); /* a defined pma_fault_t */
    /* (parameters checked again only when they changed since the last check) */
    static pma_params_t checked;
    static uint8_t checked_valid;
    const bool recheck = !checked_valid || memcmp(&checked, &a->params, sizeof checked) != 0;
    for (size_t i = 0; recheck && i < PMA_PARAM_COUNT; ++i) {
        const pma_param_desc_t *d = &pma_param_table[i];
        pma_param_value_t v;
        v.u32 = field_bits(&a->params, d);
        switch (d->type) {
        case PMA_PARAM_F32:
            CHECK(isfinite(v.f32));
            CHECK(v.f32 >= d->min.f32 && v.f32 <= d->max.f32);
            break;
        case PMA_PARAM_U32:
            CHECK(v.u32 >= d->min.u32 && v.u32 <= d->max.u32);
            break;
        default:
            CHECK(v.i32 >= d->min.i32 && v.i32 <= d->max.i32);
            break;
        }
    }
    if (recheck) CHECK(scalings_valid(&a->params));
    checked = a->params;
    checked_valid = 1;
    CHECK(a->node_id == w.node);
    const uint32_t hz = a->params.sys_tick_hz;
    CHECK(a->timing.period_us == (1000000u + hz / 2u) / hz);
    CHECK(a->timing.tick_started);
    CHECK(isfinite(pma_app_pressure_kpa(a)) && pma_app_pressure_kpa(a) >= 0.0f && pma_app_pressure_kpa(a) <= 1000.0f);
    if (is_active(a->state)) CHECK(config_armable(&a->params));
}

/* Frames and housekeeping never touch the output: it changes only in a tick
 * ("a fault raised by a frame or by bus-off is applied at the next tick"). */
static void check_output_untouched(const snap_t *s)
{
    CHECK(pma_fake_dac_write_count() == s->dac_writes);
    CHECK(pma_app_pressure_kpa(&w.app) == s->p_kpa || (isnan(pma_app_pressure_kpa(&w.app)) && isnan(s->p_kpa)));
    CHECK(w.app.output.dac_counts == s->dac_counts);
    CHECK(w.tx.actuator == 0);
}

/* ------------------------------------------------------------ commands -- */

/* A command's effect (app.h state machine; docs/protocol.md: a refused
 * command changes nothing):
 *   ARM       IDLE -> ARMED (or ARMED stays), only with a valid sensor sample
 *             inside the position limits (plant bridge: not older than
 *             safety.sensor_timeout_ticks) and the parameter rules holding
 *   DISARM    IDLE/ARMED/RUNNING -> IDLE
 *   START     ARMED -> RUNNING, the parameter rules holding (checked again)
 *   STOP      RUNNING/ARMED -> ARMED
 *   ESTOP     any -> FAULT (ESTOP, unless a fault is already latched)
 *   CLEAR     FAULT -> IDLE (not while bus-off), else nothing
 *   SELECT_*  ctrl.mode / ref.kind = Arg, not while RUNNING ("stopped")
 *   RESTART   only with the output inactive; nothing changes until the step
 *             ends, then the system reset (serve_reset: the MCU starts again) */
static void check_command(const snap_t *s, uint8_t cmd, uint8_t arg, int result)
{
    const pma_app_t *a = &w.app;
    uint16_t changed = 0;
    const unsigned nchanged = params_diff(&s->params, &a->params, &changed);
    if (result != PMA_OK) {
        CHECK(a->state == s->state && a->fault == s->fault && nchanged == 0);
        return;
    }
    switch (cmd) {
    case PMA_CMD_ARM:
        CHECK(s->state == PMA_STATE_IDLE || s->state == PMA_STATE_ARMED);
        CHECK(a->state == PMA_STATE_ARMED);
        if (s->state == PMA_STATE_IDLE) {
            const pma_params_t *p = &a->params;
            CHECK(a->sensor.status == PMA_OK);
            CHECK(pma_app_position_cm(a) >= p->safety_x_min_cm - p->safety_x_margin_cm &&
                  pma_app_position_cm(a) <= p->safety_x_max_cm + p->safety_x_margin_cm);
            CHECK(config_armable(p) && p->ctrl_u_min < p->ctrl_u_max);
            if (bridge_on()) CHECK(a->sensor.ticks_since_sample < p->safety_sensor_timeout_ticks);
        }
        break;
    case PMA_CMD_DISARM:
        CHECK(s->state != PMA_STATE_FAULT && a->state == PMA_STATE_IDLE);
        break;
    case PMA_CMD_START:
        CHECK(s->state == PMA_STATE_ARMED && a->state == PMA_STATE_RUNNING);
        CHECK(config_armable(&a->params) && a->params.ctrl_u_min < a->params.ctrl_u_max);
        break;
    case PMA_CMD_STOP:
        CHECK(is_active(s->state) && a->state == PMA_STATE_ARMED);
        break;
    case PMA_CMD_ESTOP:
        CHECK(a->state == PMA_STATE_FAULT);
        CHECK(a->fault == (s->state == PMA_STATE_FAULT ? s->fault : PMA_FAULT_ESTOP));
        break;
    case PMA_CMD_CLEAR_FAULTS:
        if (s->state == PMA_STATE_FAULT) {
            /* (the bus state before: sending the reply may itself end in bus-off) */
            CHECK(a->state == PMA_STATE_IDLE && a->fault == PMA_FAULT_NONE);
            CHECK(!s->bus_off);
        } else {
            CHECK(a->state == s->state);
        }
        break;
    case PMA_CMD_SELECT_CONTROLLER:
    case PMA_CMD_SELECT_REFERENCE: {
        const uint16_t id = cmd == PMA_CMD_SELECT_CONTROLLER ? PMA_PARAM_CTRL_MODE
                                                             : PMA_PARAM_REF_KIND;
        CHECK(a->state == s->state && s->state != PMA_STATE_RUNNING);
        CHECK(nchanged == 0 || (nchanged == 1 && changed == id));
        CHECK(field_bits(&a->params, pma_param_find(id)) == arg);
        break;
    }
    case PMA_CMD_RESTART:
        CHECK(!is_active(s->state) && a->state == s->state && a->restart_pending);
        break;
    default:
        CHECK(!"an unknown command succeeded");
    }
    if (cmd != PMA_CMD_SELECT_CONTROLLER && cmd != PMA_CMD_SELECT_REFERENCE) {
        CHECK(nchanged == 0);
    }
    if (cmd != PMA_CMD_ESTOP && cmd != PMA_CMD_CLEAR_FAULTS) CHECK(a->fault == s->fault);
}

/* ------------------------------------------------------ frame delivery -- */

/* How many replies one frame may produce on the bus: exactly one when the bus
 * is healthy and no TX fault was injected (the reply may also fail to queue,
 * counted in tx_failed); 0..2 with injected drops/duplicates/blocking. */
static void check_reply_count(uint32_t n, const snap_t *s)
{
    if (w.tx_faults) {
        CHECK(n <= 2u);
    } else {
        CHECK(n == 1u || (n == 0u && w.app.counters.tx_failed == s->counters.tx_failed + 1u));
    }
}

/* PARAM_REQ (docs/parameters.md): answered by one PARAM_RESP echoing Op and
 * Id; SET changes exactly the one parameter to the requested bits, only when
 * its access class allows it in the current state (live: always; stopped: not
 * RUNNING; idle: output inactive); SAVE/LOAD/RESTORE_DEFAULTS only with the
 * output inactive; a refused request changes nothing; GET and SET report the
 * current value. A PARAM_REQ never changes the state. */
static void check_param_req(const snap_t *s, const pma_can_frame_t *f)
{
    const pma_app_t *a = &w.app;
    CHECK(a->state == s->state && a->fault == s->fault);
    check_reply_count(w.tx.resp, s);
    CHECK(w.tx.ack == 0 && w.tx.total == w.tx.resp);
    uint16_t changed = 0;
    const unsigned nchanged = params_diff(&s->params, &a->params, &changed);
    const uint8_t op = f->dlc > 0 ? (uint8_t)(f->data[0] & 0x0Fu) : 0u;
    const uint16_t id = f->dlc > 2 ? (uint16_t)(f->data[1] | (f->data[2] << 8)) : 0u;
    const pma_param_desc_t *d = pma_param_find(id);
    const bool inactive = !is_active(s->state);
    int result = PMA_OK;
    if (w.tx.resp == 1u) {
        const uint8_t *r = w.tx.last_resp;
        CHECK((r[0] & 0x0Fu) == op);
        CHECK((uint16_t)(r[1] | (r[2] << 8)) == id);
        result = (int8_t)r[3];
        if (f->dlc != PMA_PROTO_PARAM_REQ_LENGTH) CHECK(result == PMA_ERR_LENGTH);
        if (d != NULL && (op == PMA_PARAM_OP_GET || op == PMA_PARAM_OP_SET) &&
            f->dlc == PMA_PROTO_PARAM_REQ_LENGTH && f->data[3] == 0) {
            CHECK((r[0] >> 4) == d->type);
            CHECK(rd32(r + 4) == field_bits(&a->params, d));
        }
    }
    if (f->dlc != PMA_PROTO_PARAM_REQ_LENGTH || f->data[3] != 0) {
        CHECK(nchanged == 0);
        return;
    }
    switch (op) {
    case PMA_PARAM_OP_SET:
        if (nchanged > 0) {
            CHECK(d != NULL && nchanged == 1 && changed == id);
            CHECK((f->data[0] >> 4) == d->type);
            CHECK(field_bits(&a->params, d) == rd32(f->data + 4));
        }
        if (nchanged > 0 || (w.tx.resp == 1u && result == PMA_OK)) {
            CHECK(d != NULL);
            if (d->access == PMA_PARAM_IDLE) CHECK(inactive);
            if (d->access == PMA_PARAM_STOPPED) CHECK(s->state != PMA_STATE_RUNNING);
            CHECK(field_bits(&a->params, d) == rd32(f->data + 4));
        }
        break;
    case PMA_PARAM_OP_RESTORE_DEFAULTS:
    case PMA_PARAM_OP_LOAD:
        if (nchanged > 0) CHECK(inactive);
        if (w.tx.resp == 1u && result == PMA_OK) CHECK(inactive);
        break;
    case PMA_PARAM_OP_SAVE:
        CHECK(nchanged == 0);
        if (w.tx.resp == 1u && result == PMA_OK) CHECK(inactive);
        break;
    default:
        CHECK(nchanged == 0);
        break;
    }
}

/* Delivers one frame to pma_app_handle_frame and checks what it did
 * (firmware/app/app_frames.c header, docs/protocol.md):
 *  - every call counts in frames_rx; the output is not touched;
 *  - invalid frames (dlc > 8, id > 0x7FF), other nodes' frames and ids this
 *    node does not receive change nothing and are not answered;
 *  - ESTOP_ALL (id 0) and this node's ESTOP, whatever their length, enter
 *    FAULT (code ESTOP unless a fault is already latched); nothing answered;
 *    with an invalid DLC (> 8) either that or nothing at all (fail safe);
 *  - COMMAND: one COMMAND_ACK echoing Command and Arg with the state after it;
 *    wrong length: PMA_ERR_LENGTH and nothing changes; see check_command();
 *  - PARAM_REQ: check_param_req();
 *  - PLANT_SENSOR, SETPOINT, HOST_HEARTBEAT: no reply, no state or parameter
 *    change. */
static void deliver(const pma_can_frame_t *f)
{
    snap_t s;
    drain();
    take(&s);
    reset_tx_seen();
    pma_app_handle_frame(&w.app, f);
    drain();

    const pma_app_t *a = &w.app;
    CHECK(a->counters.frames_rx == s.counters.frames_rx + 1u);
    check_output_untouched(&s);
    CHECK(w.tx.heartbeat == 0 && w.tx.telem == 0);

    const bool valid = f->dlc <= PMA_CAN_DLC_MAX && f->id <= PMA_CAN_ID_MAX;
    const bool ours = valid && (f->id & PMA_NODE_ID_MASK) == w.node;
    const uint16_t base = (uint16_t)(f->id & PMA_BASE_ID_MASK);
    const bool estop_id = f->id == PMA_PROTO_ESTOP_ALL_FRAME_ID ||
                          f->id == (uint16_t)(PMA_PROTO_ESTOP_FRAME_ID | w.node);
    const bool estop = estop_id && (valid || a->state != s.state || a->fault != s.fault);
    if (estop) {
        CHECK(a->state == PMA_STATE_FAULT);
        CHECK(a->fault == (s.state == PMA_STATE_FAULT ? s.fault : PMA_FAULT_ESTOP));
        CHECK(params_diff(&s.params, &a->params, NULL) == 0);
        CHECK(w.tx.total == 0);
        check_always();
        return;
    }
    if (ours && base == PMA_PROTO_COMMAND_FRAME_ID) {
        check_reply_count(w.tx.ack, &s);
        CHECK(w.tx.resp == 0 && w.tx.total == w.tx.ack);
        const uint8_t cmd = f->dlc > 0 ? f->data[0] : 0u;
        const uint8_t arg = f->dlc > 1 ? f->data[1] : 0u;
        if (f->dlc != PMA_PROTO_COMMAND_LENGTH) {
            CHECK(a->state == s.state && a->fault == s.fault);
            CHECK(params_diff(&s.params, &a->params, NULL) == 0);
            if (w.tx.ack == 1u) CHECK(w.tx.last_ack.result == PMA_ERR_LENGTH);
        } else if (w.tx.ack == 1u) {
            CHECK(w.tx.last_ack.command == cmd && w.tx.last_ack.arg == arg);
            CHECK(w.tx.last_ack.state == a->state);
            check_command(&s, cmd, arg, w.tx.last_ack.result);
        } else {
            /* reply lost: the transition must still be one the table allows */
            if (a->state != s.state || params_diff(&s.params, &a->params, NULL) != 0) {
                check_command(&s, cmd, arg, PMA_OK);
            }
        }
        check_always();
        return;
    }
    if (ours && base == PMA_PROTO_PARAM_REQ_FRAME_ID) {
        check_param_req(&s, f);
        check_always();
        return;
    }
    const bool info_req = valid && (f->id == PMA_PROTO_DEVICE_INFO_REQ_ALL_FRAME_ID ||
                                    (ours && base == PMA_PROTO_DEVICE_INFO_REQ_FRAME_ID));
    if (info_req) {
        /* the identity: DEVICE_INFO pages only (at most one of each, fewer when the TX
         * queue is full), nothing else changes; another length is dropped and counted */
        if (!w.tx_faults) { /* frames held by a blocked TX, duplicates: not this request's */
            CHECK(w.tx.total == w.tx.info);
            CHECK(w.tx.info <= PMA_PROTO_DEVICE_INFO_PAGE_UID_HIGH_CHOICE + 1u);
        }
        CHECK(a->state == s.state && a->fault == s.fault);
        CHECK(params_diff(&s.params, &a->params, NULL) == 0);
        if (f->dlc != PMA_PROTO_DEVICE_INFO_REQ_LENGTH) {
            CHECK(w.tx.info == 0);
            CHECK(a->counters.frames_bad == s.counters.frames_bad + 1u);
        }
        check_always();
        return;
    }
    /* everything else: no reply, no state or parameter change */
    CHECK(w.tx.total == 0);
    CHECK(a->state == s.state && a->fault == s.fault);
    CHECK(params_diff(&s.params, &a->params, NULL) == 0);
    if (estop_id) {
        /* an emergency stop's id is obeyed before the DLC check: not counted as bad */
    } else if (!valid) {
        CHECK(a->counters.frames_bad == s.counters.frames_bad + 1u);
    } else if (!ours) {
        CHECK(a->counters.frames_ignored == s.counters.frames_ignored + 1u);
    }
    check_always();
}

/* ------------------------------------------------------------ the tick -- */

/* One pma_app_tick and its output:
 *  - a tick never changes a parameter, and changes the state only into FAULT
 *    (the supervisor's faults);
 *  - a tick writes the output exactly once: the DAC (one accepted write; the
 *    plant bridge writes no DAC but sends PLANT_ACTUATOR); telemetry only
 *    while RUNNING;
 *  - output active after the tick (ARMED, RUNNING): the pressure equals the
 *    actuator law for u from the previous command, so it lies between the
 *    previous command and the target clamped to [act.p_min, act.p_max] and
 *    moves at most act.slew_kpa_s * period per tick; ARMED has u = 0; RUNNING
 *    has a finite u within [ctrl.u_min, ctrl.u_max] (OFF: u = 0); the DAC
 *    write (or the PLANT_ACTUATOR frame, OutputActive 1) carries the counts
 *    of that pressure;
 *  - output inactive after the tick (IDLE, FAULT; a fault found in the tick is
 *    applied in that same tick): the pressure is the safe value of the current
 *    parameters from the previous command; the DAC write (PLANT_ACTUATOR:
 *    OutputActive 0) carries its counts. A write the DAC refuses or fails
 *    faults OUTPUT and the firmware falls back to the safe value of the
 *    command it tried (for an active one: from that command), and, if that is
 *    refused too, 0 counts (0 V / 0 mA). Only a broken DAC may end a tick
 *    unwritten; never is an active command left on the output (the bug of
 *    tests/fuzz/crashes/README.md). */
static void do_tick(uint32_t late)
{
    snap_t s;
    drain();
    take(&s);
    reset_tx_seen();
    ++w.ticks;
    pma_app_tick(&w.app, late);
    drain();

    const pma_app_t *a = &w.app;
    const pma_params_t *p = &a->params;
    CHECK(params_diff(&s.params, &a->params, NULL) == 0);
    CHECK(a->state == s.state || a->state == PMA_STATE_FAULT);
    if (s.state == PMA_STATE_FAULT) CHECK(a->fault == s.fault);
    CHECK(w.tx.ack == 0 && w.tx.resp == 0);
    if (w.tx.telem > 0) CHECK(a->state == PMA_STATE_RUNNING);

    const uint32_t writes = pma_fake_dac_write_count() - s.dac_writes;
    pma_fake_dac_write_t newest = {0, 0};
    const bool have_newest = pma_fake_dac_log(0, &newest) == PMA_OK;
    if (bridge_on()) {
        CHECK(writes == 0);
        if (!w.tx_faults) CHECK(w.tx.actuator <= 1u);
    } else {
        CHECK(writes <= 1u);
        CHECK(w.tx.actuator == 0);
    }
    const float period_s = 1.0f / (float)p->sys_tick_hz;

    /* The supervisor (supervisor.h) runs in every tick and its fault is
     * applied in that same tick: CAN bus-off faults in every state; with the
     * output active, so do a sensor that is not valid (wire break, read
     * error, out of range, no sample), a position beyond the limits by more
     * than the margin (NaN included), a tick served more than
     * safety.max_late_ticks late, and, plant bridge, no new sample for
     * safety.sensor_timeout_ticks; while RUNNING also no host heartbeat for
     * safety.host_timeout_ms of control time (ceil(ms * tick_hz / 1000)
     * ticks; 0 disables) and safety.barrier_ticks consecutive barrier clamps
     * (0 disables). So an output still active after a tick implies none of
     * them holds. */
    /* (bus-off before the tick: the frames the tick sends may end in bus-off
     * after the supervisor has looked, which the next tick handles) */
    if (s.bus_off) CHECK(a->state == PMA_STATE_FAULT);
    if (is_active(a->state)) {
        CHECK(a->sensor.status == PMA_OK);
        CHECK(pma_app_position_cm(a) >= p->safety_x_min_cm - p->safety_x_margin_cm &&
              pma_app_position_cm(a) <= p->safety_x_max_cm + p->safety_x_margin_cm);
        CHECK(late <= p->safety_max_late_ticks);
        if (bridge_on()) CHECK(a->sensor.ticks_since_sample < p->safety_sensor_timeout_ticks);
        if (a->state == PMA_STATE_RUNNING) {
            if (p->safety_host_timeout_ms != 0) {
                const uint64_t t = ((uint64_t)p->safety_host_timeout_ms * p->sys_tick_hz + 999u) / 1000u;
                CHECK(a->timing.ticks_since_host_heartbeat < t);
            }
            /* the supervisor's clamp run (none once MFAC is in charge: the run hands over) */
            if (p->safety_barrier_ticks != 0 && !a->ctrl.fallback_active) {
                CHECK(a->ctrl.barrier_run < p->safety_barrier_ticks);
            }
        }
    }

    if (is_active(a->state)) {
        const float prev = s.p_kpa, pk = pma_app_pressure_kpa(a);
        CHECK(isfinite(pk) && pk >= 0.0f);
        const float lo = fminf(prev, p->act_p_min_kpa), hi = fmaxf(prev, p->act_p_max_kpa);
        CHECK(pk >= lo && pk <= hi);
        if (p->act_slew_kpa_s > 0.0f) {
            const float step = p->act_slew_kpa_s * period_s;
            CHECK(fabsf(pk - prev) <= step * (1.0f + 1e-5f) + 1e-4f * fmaxf(1.0f, fabsf(prev)));
        }
        if (a->state == PMA_STATE_ARMED) {
            CHECK(pma_app_output_u(a) == 0.0f);
        } else {
            CHECK(isfinite(pma_app_output_u(a)));
            if (p->ctrl_mode == PMA_CTRL_MODE_OFF) {
                CHECK(pma_app_output_u(a) == 0.0f);
            } else {
                CHECK(pma_app_output_u(a) >= p->ctrl_u_min && pma_app_output_u(a) <= p->ctrl_u_max);
            }
        }
        CHECK(near(pk, oracle_active_kpa(p, pma_app_output_u(a), prev, period_s)));
        uint16_t c = 0;
        CHECK(oracle_counts(p, pk, &c));
        CHECK(a->output.dac_counts == c);
        if (bridge_on()) {
            for (uint32_t i = 0; i < w.tx.act_kept; ++i) {
                CHECK(w.tx.act[i].dac_counts == c && w.tx.act[i].output_active == 1u);
                CHECK(w.tx.act[i].seq == a->bridge.seq);
                CHECK(w.tx.act[i].sample == a->sensor.sample_status);
            }
            if (w.tx.actuator > 0) w.phys = PHYS_ACTIVE;
        } else {
            CHECK(writes == 1u && have_newest && newest.counts == c);
            w.phys = PHYS_ACTIVE;
        }
    } else {
        /* a DAC write refused or failed in this tick faults OUTPUT (the first
         * fault wins: an ESTOP latched before stays) and the safe value of
         * the command that was to be written is applied */
        const bool output_fault = s.state != PMA_STATE_FAULT && a->fault == PMA_FAULT_OUTPUT;
        if (output_fault && is_active(s.state)) {
            CHECK(!bridge_on());
            CHECK(near(pma_app_pressure_kpa(a), oracle_safe_kpa(p, oracle_active_kpa(p, pma_app_output_u(a), s.p_kpa, period_s))));
        } else {
            CHECK(pma_app_pressure_kpa(a) == oracle_safe_kpa(p, s.p_kpa));
        }
        /* the counts of that pressure; if the DAC refuses them (or they cannot
         * be computed), 0 counts (0 V / 0 mA), in FAULT */
        uint16_t c = 0;
        const bool convertible = oracle_counts(p, pma_app_pressure_kpa(a), &c);
        if (convertible) {
            CHECK(a->output.dac_counts == c || (a->output.dac_counts == 0u && a->state == PMA_STATE_FAULT));
        } else {
            CHECK(a->output.dac_counts == 0u && a->state == PMA_STATE_FAULT);
        }
        if (bridge_on()) {
            for (uint32_t i = 0; i < w.tx.act_kept; ++i) {
                CHECK(w.tx.act[i].output_active == 0u);
                CHECK(w.tx.act[i].dac_counts == a->output.dac_counts);
            }
            if (w.tx.actuator > 0) w.phys = PHYS_SAFE;
        } else if (writes == 1u) {
            CHECK(have_newest && newest.counts == a->output.dac_counts);
            w.phys = PHYS_SAFE;
        } else {
            /* nothing written: only a broken DAC refuses everything, 0 counts
             * included; the output then stays where it was, and the fault is
             * latched. A working DAC left at an active command is the bug of
             * tests/fuzz/crashes/regression-dac-refuses-safe-counts. */
            if (!w.dac_broken) CHECK_NOT_LEFT_ACTIVE();
            CHECK(w.dac_broken);
            CHECK(a->state == PMA_STATE_FAULT);
        }
    }
    check_always();
}

/* pma_app_poll: heartbeat and CAN bus-off. It changes the state only into
 * FAULT (CAN_BUS_OFF), never a parameter, never the output; it sends at most
 * heartbeats (one per call). */
static void do_poll(void)
{
    snap_t s;
    drain();
    take(&s);
    reset_tx_seen();
    pma_app_poll(&w.app);
    drain();
    const pma_app_t *a = &w.app;
    CHECK(a->state == s.state || a->state == PMA_STATE_FAULT);
    if (s.state == PMA_STATE_FAULT) CHECK(a->fault == s.fault);
    if (a->state != s.state) CHECK(a->fault == PMA_FAULT_CAN_BUS_OFF);
    CHECK(params_diff(&s.params, &a->params, NULL) == 0);
    check_output_untouched(&s);
    CHECK(w.tx.total == w.tx.heartbeat);
    if (!w.tx_faults) CHECK(w.tx.heartbeat <= 1u);
    check_always();
}

/* -------------------------------------------------------------- set-up -- */

static void attach_nvm(unsigned storage)
{
    if (storage == 0) return;
    const pma_nvm_geometry_t big = {.block_size = 2048u, .block_count = 3u, .program_size = 8u};
    const pma_nvm_geometry_t small = {.block_size = 64u, .block_count = 16u, .program_size = 8u};
    CHECK(pma_fake_nvm_attach(nvm_mem, sizeof nvm_mem, storage == 1 ? &big : &small) == PMA_OK);
}

/* pma_app_init on an initialised HAL: succeeds, ends in IDLE (FAULT
 * WATCHDOG_RESET after a watchdog reset), node id as configured, the output
 * pressure at the safe value. */
static void start_app(void)
{
    CHECK(pma_hal_init(NULL) == PMA_OK);
    const int rc = pma_app_init(&w.app, &w.plat);
    CHECK(rc == PMA_OK);
    const pma_app_t *a = &w.app;
    if (pma_hal_reset_cause() == PMA_RESET_WATCHDOG) {
        CHECK(a->state == PMA_STATE_FAULT && a->fault == PMA_FAULT_WATCHDOG_RESET);
    } else {
        CHECK(a->state == PMA_STATE_IDLE && a->fault == PMA_FAULT_NONE);
    }
    w.node = (uint8_t)(w.plat.node_id >= 0 ? (uint32_t)w.plat.node_id : a->params.sys_node_id);
    CHECK(pma_app_pressure_kpa(a) == oracle_safe_kpa(&a->params, 0.0f));
    w.phys = PHYS_SAFE; /* the MCU (re)started: its DAC output was reset */
    reset_tx_seen();
    drain();
    CHECK(w.tx.heartbeat == 1u || w.tx_faults); /* the BOOT heartbeat */
    check_always();
}

static void setup(uint8_t cfg)
{
    memset(&w, 0, sizeof w);
    const unsigned storage = (cfg >> 2) & 3u;
    w.plat = (pma_app_platform_t){
        .plant_bridge = (uint8_t)(cfg & 1u),
        .lockstep = (uint8_t)((cfg >> 1) & 1u),
        .node_id = NODE_MAP[(cfg >> 5) & 7u],
        .store_first_block = storage == 0 ? 0u : 1u,
        .store_blocks_per_slot = storage == 0 ? 0u : (storage == 1 ? 1u : (storage == 2 ? 7u : 6u)),
        .watchdog_ms = (cfg & 0x10u) ? 100u : 0u,
    };
    pma_fake_reset();
    CHECK(pma_hal_init(NULL) == PMA_OK);
    attach_nvm(storage);
    pma_fake_adc_set(START_RAW_COUNTS);
    start_app();
}

/* ------------------------------------------------------------- the ops -- */

static pma_can_frame_t make_frame(uint16_t id, uint8_t dlc, const uint8_t *d)
{
    pma_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.dlc = dlc;
    memcpy(f.data, d, 8u);
    return f;
}

static uint16_t raw_id(uint8_t a, uint8_t b)
{
    uint16_t id = (uint16_t)(a | ((b & 0x07u) << 8));
    if (b & 0x80u) id = (uint16_t)(id | 0x0800u | ((b & 0x78u) << 8));
    return id;
}

static uint8_t raw_dlc(uint8_t c)
{
    return (c & 0x80u) ? c : (uint8_t)(c & 0x0Fu);
}

static void send_sensor_counts(uint16_t raw)
{
    if (bridge_on()) {
        uint8_t d[8] = {0};
        d[0] = w.seq++;
        d[1] = (uint8_t)raw;
        d[2] = (uint8_t)(raw >> 8);
        const pma_can_frame_t f = make_frame(
            (uint16_t)(PMA_PROTO_PLANT_SENSOR_FRAME_ID | w.node), PMA_PROTO_PLANT_SENSOR_LENGTH, d);
        deliver(&f);
    } else {
        pma_fake_adc_set(raw);
    }
}

static void host_heartbeat(void)
{
    const uint8_t d[8] = {0};
    const pma_can_frame_t f = make_frame(
        (uint16_t)(PMA_PROTO_HOST_HEARTBEAT_FRAME_ID | w.node), PMA_PROTO_HOST_HEARTBEAT_LENGTH, d);
    deliver(&f);
}

static void op_tick(uint8_t a, uint8_t b, uint8_t c, const uint8_t *d)
{
    const unsigned n = 1u + b;
    uint32_t late = (a & 0x80u) ? (a & 0x7Fu) : 0u;
    if (a == 0xFFu) late = UINT32_MAX;
    const int32_t base = d[0] | (d[1] << 8);
    const int32_t slope = (int8_t)d[2];
    for (unsigned i = 0; i < n && w.ticks < MAX_TICKS; ++i) {
        pma_fake_time_advance_us(w.app.timing.period_us);
        pma_hal_watchdog_kick();
        if (c & 1u) {
            int32_t raw = base + (int32_t)i * slope;
            raw = raw < 0 ? 0 : (raw > 0xFFFF ? 0xFFFF : raw);
            send_sensor_counts((uint16_t)raw);
        }
        if (c & 2u) host_heartbeat();
        do_tick(i == 0 ? late : 0u);
        do_poll();
    }
}

/* After a step: a RESTART it accepted asked for the system reset at its end
 * (the fake only counts it): the output was inactive, and the MCU starts again
 * as after any software reset. */
static void serve_reset(void)
{
    if (pma_fake_system_reset_requests() == 0) return;
    CHECK(pma_fake_system_reset_requests() == 1u && !is_active(w.app.state) && !w.app.restart_pending);
    drain();
    pma_fake_reboot(); /* SOFTWARE (WATCHDOG if the watchdog expired meanwhile) */
    start_app();
}

/* pma_app_step written out stage by stage (same order, same bound). */
static void op_step(uint8_t b)
{
    const unsigned n = 1u + b;
    for (unsigned i = 0; i < n && w.ticks < MAX_TICKS; ++i) {
        uint32_t late = 0;
        const int rc = pma_hal_tick_wait(&late);
        CHECK(rc == PMA_OK); /* the fake's tick never wakes without one */
        pma_can_frame_t f;
        for (unsigned k = 0; k < PMA_APP_RX_PER_STEP && pma_hal_can_recv(&f) == PMA_OK; ++k) {
            deliver(&f);
        }
        do_tick(late);
        do_poll();
        pma_hal_watchdog_kick();
        if (w.app.restart_pending) {
            w.app.restart_pending = 0;
            pma_hal_system_reset();
        }
        serve_reset();
    }
}

/* The real pma_app_step: only the invariants that hold between iterations;
 * the output written inside it is not attributed to a stage. */
static void op_real_step(uint8_t b)
{
    const unsigned n = 1u + (b & 7u);
    for (unsigned i = 0; i < n && w.ticks < MAX_TICKS; ++i) {
        const uint32_t writes = pma_fake_dac_write_count();
        drain();
        reset_tx_seen();
        ++w.ticks;
        CHECK(pma_app_step(&w.app) == PMA_OK);
        drain();
        if (pma_fake_dac_write_count() != writes || w.tx.actuator > 0) w.phys = PHYS_UNKNOWN;
        check_always();
        serve_reset();
    }
}

static void op_can(uint8_t a, uint8_t b, uint8_t c, const uint8_t *d)
{
    switch (c % 8u) {
    case 0: pma_fake_can_set_error_counters(256u, 0u); break;
    case 1: pma_fake_can_set_error_counters((uint16_t)(a | ((b & 1u) << 8)), d[0]); break;
    case 2: pma_fake_can_bus_errors(a & 1u); w.tx_faults = 1; break;
    case 3:
        /* frames held while blocked go out later, outside the tick that made
         * them: their contents are not attributed */
        pma_fake_can_block_tx(a & 1u);
        w.tx_faults = 1;
        break;
    case 4: pma_fake_can_set_recovery((uint32_t)a * 100u, b & 1u); break;
    case 5: pma_fake_can_drop((a & 1u) ? PMA_FAKE_CAN_TX : PMA_FAKE_CAN_RX, b & 3u); w.tx_faults = 1; break;
    case 6: pma_fake_can_duplicate((a & 1u) ? PMA_FAKE_CAN_TX : PMA_FAKE_CAN_RX, b & 3u); w.tx_faults = 1; break;
    default:
        pma_fake_can_bus_errors(false);
        pma_fake_can_block_tx(false);
        pma_fake_can_set_recovery(0u, false);
        pma_fake_can_drop(PMA_FAKE_CAN_TX, 0u);
        pma_fake_can_drop(PMA_FAKE_CAN_RX, 0u);
        pma_fake_can_duplicate(PMA_FAKE_CAN_TX, 0u);
        pma_fake_can_duplicate(PMA_FAKE_CAN_RX, 0u);
        break;
    }
    reset_tx_seen();
    drain(); /* unblocking may flush held frames */
    check_always();
}

static void op_nvm(uint8_t a, uint8_t b, uint8_t c, const uint8_t *d)
{
    if (w.plat.store_blocks_per_slot == 0) return;
    switch (c % 3u) {
    case 0: pma_fake_nvm_cut_power(a, (uint32_t)b * 4u > 1000u ? 1000u : (uint32_t)b * 4u); break;
    case 1: pma_fake_nvm_ecc(a & 1u); break;
    default: {
        const uint32_t blocks = w.plat.store_blocks_per_slot == 1 ? 3u : 16u;
        const uint32_t bsize = w.plat.store_blocks_per_slot == 1 ? 2048u : 64u;
        pma_fake_nvm_stuck_byte(a % blocks, (uint32_t)(b | (d[0] << 8)) % bsize, d[1] & 1u);
        break;
    }
    }
}

static void op_reboot(uint8_t c)
{
    drain();
    if (c & 1u) {
        pma_fake_power_on();
    } else {
        pma_fake_reboot(); /* WATCHDOG when the watchdog expired, else SOFTWARE */
    }
    start_app();
}

static void op_command(uint8_t a, uint8_t b)
{
    snap_t s;
    drain();
    take(&s);
    reset_tx_seen();
    const int rc = pma_app_command(&w.app, a, b);
    drain();
    CHECK(rc <= 0);
    CHECK(w.tx.total == 0); /* no reply */
    check_output_untouched(&s);
    check_command(&s, a, b, rc);
    check_always();
}

static void op_param(uint8_t a, uint8_t b, uint8_t c, const uint8_t *d)
{
    const pma_param_desc_t *desc = &pma_param_table[b % PMA_PARAM_COUNT];
    pma_param_value_t v;
    switch (c % 5u) {
    case 0: v.u32 = rd32(d); break;
    case 1: v = desc->min; break;
    case 2: v = desc->max; break;
    case 3: v = desc->def; break;
    default: {
        const float t = (float)d[0] / 255.0f;
        switch (desc->type) {
        case PMA_PARAM_F32: v.f32 = desc->min.f32 + (desc->max.f32 - desc->min.f32) * t; break;
        case PMA_PARAM_U32:
            v.u32 = desc->min.u32 + (uint32_t)((double)(desc->max.u32 - desc->min.u32) * t);
            break;
        default:
            v.i32 = desc->min.i32 + (int32_t)((double)((int64_t)desc->max.i32 - desc->min.i32) * t);
            break;
        }
        break;
    }
    }
    uint8_t data[8];
    data[0] = (uint8_t)((a & 0x0Fu) | (desc->type << 4));
    data[1] = (uint8_t)desc->id;
    data[2] = (uint8_t)(desc->id >> 8);
    data[3] = 0;
    wr32(data + 4, v.u32);
    const pma_can_frame_t f = make_frame((uint16_t)(PMA_PROTO_PARAM_REQ_FRAME_ID | w.node),
                                         PMA_PROTO_PARAM_REQ_LENGTH, data);
    deliver(&f);
}

static void op_sensor(uint8_t a)
{
    const pma_params_t *p = &w.app.params;
    const float lo = p->safety_x_min_cm - p->safety_x_margin_cm;
    const float hi = p->safety_x_max_cm + p->safety_x_margin_cm;
    const float x = lo + (hi - lo) * ((float)a / 255.0f);
    const pma_adc_scaling_t sc = {
        .offset_cm = p->adc_offset_cm, .gain_cm_per_count = p->adc_gain_cm_per_count,
        .raw_min_counts = (uint16_t)p->adc_raw_min_counts,
        .raw_max_counts = (uint16_t)p->adc_raw_max_counts,
        .wire_break_below_counts = (uint16_t)p->adc_wire_break_below_counts,
    };
    uint16_t raw = 0;
    if (pma_adc_cm_to_counts(&sc, x, &raw) != PMA_OK) raw = (uint16_t)(a << 4);
    send_sensor_counts(raw);
}

static void op_setpoint(uint8_t a)
{
    const pma_params_t *p = &w.app.params;
    const float x = p->safety_x_min_cm +
                    (p->safety_x_max_cm - p->safety_x_min_cm) * ((float)a / 255.0f);
    uint8_t d[8] = {0};
    uint32_t bits;
    memcpy(&bits, &x, 4u);
    wr32(d, bits);
    const pma_can_frame_t f = make_frame((uint16_t)(PMA_PROTO_SETPOINT_FRAME_ID | w.node),
                                         PMA_PROTO_SETPOINT_LENGTH, d);
    deliver(&f);
}

static void run_op(const uint8_t *r)
{
    const uint8_t a = r[1], b = r[2], c = r[3];
    const uint8_t *d = r + 4;
    g_op = r[0] % OP_COUNT;
    switch (g_op) {
    case OP_FRAME: {
        const pma_can_frame_t f = make_frame(raw_id(a, b), raw_dlc(c), d);
        deliver(&f);
        break;
    }
    case OP_FRAME_NODE: {
        const pma_can_frame_t f = make_frame((uint16_t)(((a & 0x7Fu) << 4) | w.node), raw_dlc(c), d);
        deliver(&f);
        break;
    }
    case OP_TICK: op_tick(a, b, c, d); break;
    case OP_STEP: op_step(b); break;
    case OP_REAL_STEP: op_real_step(b); break;
    case OP_INJECT: {
        const uint16_t id = (b & 0x40u) ? (uint16_t)(((a & 0x7Fu) << 4) | w.node) : raw_id(a, b);
        const pma_can_frame_t f = make_frame(id, (uint8_t)(c & 0x0Fu), d);
        const int rc = pma_fake_can_inject(&f);
        CHECK(rc == PMA_OK || rc == PMA_FAKE_CAN_FILTERED || rc == PMA_FAKE_CAN_DROPPED ||
              rc == PMA_ERR_FULL || rc == PMA_ERR_BUS_OFF || rc == PMA_ERR_RANGE);
        /* the filters pass this node's ids and ESTOP_ALL */
        if (rc == PMA_FAKE_CAN_FILTERED) {
            CHECK((f.id & PMA_NODE_ID_MASK) != w.node && f.id != PMA_PROTO_ESTOP_ALL_FRAME_ID);
        }
        break;
    }
    case OP_ADVANCE:
        pma_fake_time_advance_us((uint64_t)a | ((uint64_t)b << 8) | ((uint64_t)(c & 0x3Fu) << 16));
        do_poll();
        break;
    case OP_POLL: do_poll(); break;
    case OP_ADC:
        switch (c % 8u) {
        case 0: pma_fake_adc_set((uint16_t)(a | (b << 8))); break;
        case 1: pma_fake_adc_stuck(); break;
        case 2: pma_fake_adc_out_of_range((uint16_t)(a | (b << 8))); break;
        case 3: pma_fake_adc_wire_break(); break;
        case 4: pma_fake_adc_read_error(); break;
        case 5: pma_fake_adc_clear_fault(); break;
        case 6: pma_fake_dac_fail(true); w.dac_broken = 1; break;
        default: pma_fake_dac_fail(false); w.dac_broken = 0; break;
        }
        break;
    case OP_CAN: op_can(a, b, c, d); break;
    case OP_NVM: op_nvm(a, b, c, d); break;
    case OP_REBOOT: op_reboot(c); break;
    case OP_COMMAND: op_command(a, b); break;
    case OP_PARAM: op_param(a, b, c, d); break;
    case OP_SENSOR: op_sensor(a); break;
    default: op_setpoint(a); break;
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1) return 0;
    g_op_index = 0;
    g_op = -1;
    setup(data[0]);
    size_t off = 1;
    for (uint32_t i = 0; off < size && i < MAX_RECORDS; ++i, off += REC_BYTES) {
        uint8_t r[REC_BYTES] = {0};
        const size_t n = size - off < REC_BYTES ? size - off : REC_BYTES;
        memcpy(r, data + off, n);
        g_op_index = i;
        run_op(r);
#ifdef PMA_FUZZ_TRACE
        /* build with PMA_FUZZ_DEFINES=PMA_FUZZ_TRACE to follow an input record by record */
        fprintf(stderr, "rec %3u op %2d [%02x %02x %02x %02x %02x..]: %-7s fault %-19s p %8.3f "
                "kPa dac %5u u %g x %g sensor %d ticks %u\n",
                (unsigned)i, g_op, r[0], r[1], r[2], r[3], r[4],
                pma_app_state_name(w.app.state), pma_fault_name(w.app.fault),
                (double)pma_app_pressure_kpa(&w.app), w.app.output.dac_counts, (double)pma_app_output_u(&w.app), (double)pma_app_position_cm(&w.app),
                w.app.sensor.status, (unsigned)w.ticks);
#endif
    }
    return 0;
}
