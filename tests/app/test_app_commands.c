/* SPDX-License-Identifier: Apache-2.0 */
/* The state machine through COMMAND frames, exactly as a host drives it:
 * every command (ARM, DISARM, START, STOP, ESTOP, CLEAR_FAULTS,
 * SELECT_CONTROLLER, SELECT_REFERENCE, RESTART, undefined ones) in every state (IDLE,
 * ARMED, RUNNING, FAULT; BOOT through pma_app_command), with the COMMAND_ACK
 * result and state; ESTOP and ESTOP_ALL frames from every state; the reasons
 * ARM and START are refused; malformed COMMAND frames; other nodes' frames.
 * Runs in ADC mode and, for the tables, also in plant-bridge mode. */
#include "app_test.h"

/* 1,256 bytes (x86-64) with the PPC's fallback MFAC beside the law, its funnel widening, the
 * reference feedforward's play operator with its adapted height and the command's low-pass (controller.h) and the supervisor's limits kept from
 * ARM (with their Q16.16 envelope); the Q16.16 slot adds its
 * fixed-point copies of the signals and limits, the fixed-point input and output stages with
 * the parameters they were built from (io_q16.h) and the control time in integers (1,472 bytes) */
#if PMA_CTRL_Q16
_Static_assert(sizeof(pma_app_t) <= 1472u, "pma_app_t must stay small (Cortex-M0: 16 KB RAM)");
#else
_Static_assert(sizeof(pma_app_t) <= 1256u, "pma_app_t must stay small (Cortex-M0: 16 KB RAM)");
#endif

typedef enum { S_IDLE, S_ARMED, S_RUNNING, S_FAULT, S_COUNT } setup_state_t;

static const uint8_t state_of[S_COUNT] = {PMA_STATE_IDLE, PMA_STATE_ARMED, PMA_STATE_RUNNING,
                                          PMA_STATE_FAULT};

static void enter(setup_state_t s, uint8_t bridge)
{
    switch (s) {
    case S_IDLE: to_idle(bridge); break;
    case S_ARMED: to_armed(bridge); break;
    case S_RUNNING: to_running(bridge); break;
    default: to_fault(bridge); break;
    }
    assert_state(app.state, state_of[s]);
}

typedef struct expect {
    uint8_t cmd, arg;
    int result[S_COUNT];
    uint8_t after[S_COUNT];
} expect_t;

#define I PMA_STATE_IDLE
#define A PMA_STATE_ARMED
#define R PMA_STATE_RUNNING
#define F PMA_STATE_FAULT

/* What docs/protocol.md and app.h say, per state IDLE, ARMED, RUNNING, FAULT. */
static const expect_t table[] = {
    {PMA_CMD_ARM, 0, {PMA_OK, PMA_OK, PMA_ERR_STATE, PMA_ERR_FAULT}, {A, A, R, F}},
    {PMA_CMD_DISARM, 0, {PMA_OK, PMA_OK, PMA_OK, PMA_ERR_FAULT}, {I, I, I, F}},
    {PMA_CMD_START, 0, {PMA_ERR_STATE, PMA_OK, PMA_ERR_STATE, PMA_ERR_FAULT}, {I, R, R, F}},
    {PMA_CMD_STOP, 0, {PMA_ERR_STATE, PMA_OK, PMA_OK, PMA_ERR_FAULT}, {I, A, A, F}},
    {PMA_CMD_ESTOP, 0, {PMA_OK, PMA_OK, PMA_OK, PMA_OK}, {F, F, F, F}},
    {PMA_CMD_CLEAR_FAULTS, 0, {PMA_OK, PMA_OK, PMA_OK, PMA_OK}, {I, A, R, I}},
    {PMA_CMD_SELECT_CONTROLLER, PMA_CTRL_MODE_PID,
     {PMA_OK, PMA_OK, PMA_ERR_STATE, PMA_OK}, {I, A, R, F}},
    {PMA_CMD_SELECT_REFERENCE, PMA_REF_KIND_SINE,
     {PMA_OK, PMA_OK, PMA_ERR_STATE, PMA_OK}, {I, A, R, F}},
    {PMA_CMD_SELECT_CONTROLLER, 5 /* no such controller */,
     {PMA_ERR_RANGE, PMA_ERR_RANGE, PMA_ERR_RANGE, PMA_ERR_RANGE}, {I, A, R, F}},
    {PMA_CMD_SELECT_REFERENCE, 7 /* no such reference */,
     {PMA_ERR_RANGE, PMA_ERR_RANGE, PMA_ERR_RANGE, PMA_ERR_RANGE}, {I, A, R, F}},
    /* RESTART only schedules the reset (the fake's is a no-op): test_app_storage.c */
    {PMA_CMD_RESTART, 0, {PMA_OK, PMA_ERR_STATE, PMA_ERR_STATE, PMA_OK}, {I, A, R, F}},
    {0, 0, {PMA_ERR_UNKNOWN_COMMAND, PMA_ERR_UNKNOWN_COMMAND, PMA_ERR_UNKNOWN_COMMAND,
            PMA_ERR_UNKNOWN_COMMAND}, {I, A, R, F}},
    {10, 1, {PMA_ERR_UNKNOWN_COMMAND, PMA_ERR_UNKNOWN_COMMAND, PMA_ERR_UNKNOWN_COMMAND,
            PMA_ERR_UNKNOWN_COMMAND}, {I, A, R, F}},
    {255, 255, {PMA_ERR_UNKNOWN_COMMAND, PMA_ERR_UNKNOWN_COMMAND, PMA_ERR_UNKNOWN_COMMAND,
                PMA_ERR_UNKNOWN_COMMAND}, {I, A, R, F}},
};

static void run_table(uint8_t bridge)
{
    uint32_t cases = 0;
    for (size_t k = 0; k < sizeof table / sizeof table[0]; ++k) {
        const expect_t *e = &table[k];
        for (int s = 0; s < S_COUNT; ++s) {
            enter((setup_state_t)s, bridge);
            const uint8_t fault_before = app.fault;
            const uint32_t mode_before = app.params.ctrl_mode, ref_before = app.params.ref_kind;
            /* the command alone, no tick: the ACK's state is the state after it */
            const pma_can_frame_t f = frame_of(PMA_PROTO_COMMAND_FRAME_ID, T_NODE, 2,
                                               (const uint8_t[]){e->cmd, e->arg});
            cap_clear();
            pma_app_handle_frame(&app, &f);
            drain();
            TEST_ASSERT_EQUAL_INT(1, cap.total);
            TEST_ASSERT_EQUAL_INT(1, sent(PMA_PROTO_COMMAND_ACK_FRAME_ID));
            struct pma_proto_command_ack_t a;
            const pma_can_frame_t *r = last_frame(PMA_PROTO_COMMAND_ACK_FRAME_ID);
            TEST_ASSERT_EQUAL_INT(0, pma_proto_command_ack_unpack(&a, r->data, r->dlc));
            if (a.result != e->result[s] || a.state != e->after[s]) {
                pma_test_fail("%s: command %u arg %u in %s: result %s state %s, expected %s %s",
                              bridge ? "bridge" : "adc", e->cmd, e->arg,
                              pma_app_state_name(state_of[s]), pma_status_name(a.result),
                              pma_app_state_name(a.state), pma_status_name(e->result[s]),
                              pma_app_state_name(e->after[s]));
            }
            TEST_ASSERT_EQUAL_INT(e->cmd, a.command);
            TEST_ASSERT_EQUAL_INT(e->arg, a.arg);
            assert_state(app.state, e->after[s]);
            /* fault codes: ESTOP from a non-fault state latches ESTOP; in FAULT the
             * first code stays; CLEAR_FAULTS clears it */
            if (e->cmd == PMA_CMD_ESTOP) {
                assert_fault(app.fault, s == S_FAULT ? fault_before : PMA_FAULT_ESTOP);
            } else if (e->cmd == PMA_CMD_CLEAR_FAULTS) {
                assert_fault(app.fault, PMA_FAULT_NONE);
            } else {
                assert_fault(app.fault, fault_before);
            }
            /* SELECT_* changes the parameter exactly when accepted */
            if (e->cmd == PMA_CMD_SELECT_CONTROLLER) {
                TEST_ASSERT_EQUAL_INT(e->result[s] == PMA_OK ? e->arg : mode_before,
                                      app.params.ctrl_mode);
            } else {
                TEST_ASSERT_EQUAL_INT(mode_before, app.params.ctrl_mode);
            }
            if (e->cmd == PMA_CMD_SELECT_REFERENCE) {
                TEST_ASSERT_EQUAL_INT(e->result[s] == PMA_OK ? e->arg : ref_before,
                                      app.params.ref_kind);
            } else {
                TEST_ASSERT_EQUAL_INT(ref_before, app.params.ref_kind);
            }
            /* a tick later the state holds (nothing faults on its own) */
            if (bridge) send_sample((uint8_t)(app.bridge.seq + 1u), counts_at(-1.5f));
            cap_clear();
            step();
            assert_state(app.state, e->after[s]);
            ++cases;
        }
    }
    TEST_ASSERT_EQUAL_INT(S_COUNT * (sizeof table / sizeof table[0]), cases);
}

static void test_every_command_in_every_state_adc(void)
{
    run_table(0);
}

static void test_every_command_in_every_state_bridge(void)
{
    run_table(1);
}

/* BOOT exists only before pma_app_init() has finished: commands act on the
 * struct as pma_app_init() leaves it before loading (state BOOT). */
static void test_commands_in_boot(void)
{
    start_with(0, -1.5f);
    static const struct { uint8_t cmd; int rc; uint8_t after; } boot[] = {
        {PMA_CMD_ARM, PMA_ERR_STATE, PMA_STATE_BOOT},
        {PMA_CMD_DISARM, PMA_ERR_STATE, PMA_STATE_BOOT},
        {PMA_CMD_START, PMA_ERR_STATE, PMA_STATE_BOOT},
        {PMA_CMD_STOP, PMA_ERR_STATE, PMA_STATE_BOOT},
        {PMA_CMD_CLEAR_FAULTS, PMA_OK, PMA_STATE_BOOT},
        {42, PMA_ERR_UNKNOWN_COMMAND, PMA_STATE_BOOT},
        {PMA_CMD_ESTOP, PMA_OK, PMA_STATE_FAULT},
    };
    for (size_t i = 0; i < sizeof boot / sizeof boot[0]; ++i) {
        app.state = PMA_STATE_BOOT;
        app.fault = PMA_FAULT_NONE;
        assert_status(pma_app_command(&app, boot[i].cmd, 0), boot[i].rc);
        assert_state(app.state, boot[i].after);
    }
    assert_fault(app.fault, PMA_FAULT_ESTOP);
    assert_status(pma_app_command(NULL, PMA_CMD_ARM, 0), PMA_ERR_NULL);
    /* a tick in BOOT does nothing */
    app.state = PMA_STATE_BOOT;
    const uint32_t writes = pma_fake_dac_write_count();
    pma_app_tick(&app, 0);
    TEST_ASSERT_EQUAL_INT(writes, pma_fake_dac_write_count());
    assert_state(app.state, PMA_STATE_BOOT);
}

/* ESTOP (this node) and ESTOP_ALL (broadcast), of any length, from every
 * state: FAULT with code ESTOP and the safe output in the same step; no
 * reply. From FAULT the first code stays latched. */
static void test_estop_frames_from_every_state(void)
{
    const uint16_t ids[2] = {PMA_PROTO_ESTOP_FRAME_ID | T_NODE, PMA_PROTO_ESTOP_ALL_FRAME_ID};
    const uint8_t dlcs[3] = {0, 1, 8};
    uint32_t cases = 0;
    for (int bridge = 0; bridge < 2; ++bridge) {
        for (int s = 0; s < S_COUNT; ++s) {
            for (int w = 0; w < 2; ++w) {
                for (int l = 0; l < 3; ++l) {
                    enter((setup_state_t)s, (uint8_t)bridge);
                    if (s == S_FAULT) {
                        /* a fault other than ESTOP first, to see which one stays */
                        assert_status(pma_app_command(&app, PMA_CMD_CLEAR_FAULTS, 0), PMA_OK);
                        pma_app_raise_fault(&app, PMA_FAULT_TICK_OVERRUN);
                    }
                    pma_can_frame_t f = frame_of(0, 0, dlcs[l], (const uint8_t[8]){1, 2, 3});
                    f.id = ids[w];
                    assert_status(pma_fake_can_inject(&f), PMA_OK);
                    cap_clear();
                    step();
                    assert_state(app.state, PMA_STATE_FAULT);
                    assert_fault(app.fault, s == S_FAULT ? PMA_FAULT_TICK_OVERRUN
                                                         : PMA_FAULT_ESTOP);
                    if (bridge) {
                        const struct pma_proto_plant_actuator_t m = last_actuator();
                        TEST_ASSERT_EQUAL_INT(0, m.dac_counts);
                        TEST_ASSERT_EQUAL_INT(0, m.output_active);
                        TEST_ASSERT_EQUAL_INT(1, cap.total); /* the actuator frame, no reply */
                    } else {
                        TEST_ASSERT_EQUAL_INT(0, dac_now());
                        TEST_ASSERT_EQUAL_INT(0, cap.total);
                    }
                    ++cases;
                }
            }
        }
    }
    TEST_ASSERT_EQUAL_INT(2u * S_COUNT * 2u * 3u, cases);
}

/* ESTOP for another node: not received (filters), and ignored if it were. */
static void test_other_nodes_frames_ignored(void)
{
    to_armed(0);
    const pma_app_counters_t before = app.counters;
    const uint32_t params_before = params_crc(&app.params);
    const uint16_t bases[] = {PMA_PROTO_ESTOP_FRAME_ID, PMA_PROTO_COMMAND_FRAME_ID,
                              PMA_PROTO_PARAM_REQ_FRAME_ID, PMA_PROTO_SETPOINT_FRAME_ID,
                              PMA_PROTO_HOST_HEARTBEAT_FRAME_ID, PMA_PROTO_PLANT_SENSOR_FRAME_ID};
    const uint8_t dlcs[] = {0, 2, 8, 4, 1, 3};
    for (size_t i = 0; i < sizeof bases / sizeof bases[0]; ++i) {
        pma_can_frame_t f = frame_of(bases[i], T_OTHER_NODE, dlcs[i],
                                     (const uint8_t[8]){PMA_CMD_ESTOP, 0, 0, 0, 0, 0, 0, 0});
        TEST_ASSERT_EQUAL_INT(PMA_FAKE_CAN_FILTERED, pma_fake_can_inject(&f));
        /* even handed over directly: ignored, no reply */
        cap_clear();
        pma_app_handle_frame(&app, &f);
        drain();
        TEST_ASSERT_EQUAL_INT(0, cap.total);
    }
    TEST_ASSERT_EQUAL_INT(before.frames_ignored + 6u, app.counters.frames_ignored);
    assert_state(app.state, PMA_STATE_ARMED);
    TEST_ASSERT_EQUAL_INT(params_before, params_crc(&app.params));
    /* the node's own outputs and undefined base ids addressed to it: ignored */
    const uint16_t own[] = {PMA_PROTO_HEARTBEAT_FRAME_ID, PMA_PROTO_COMMAND_ACK_FRAME_ID,
                            PMA_PROTO_TELEM_E_FRAME_ID, 0x100, 0x7F0};
    for (size_t i = 0; i < sizeof own / sizeof own[0]; ++i) {
        pma_can_frame_t f = frame_of(own[i], T_NODE, 8, (const uint8_t[8]){PMA_CMD_ESTOP});
        assert_status(pma_fake_can_inject(&f), PMA_OK);
    }
    cap_clear();
    step();
    TEST_ASSERT_EQUAL_INT(0, sent(PMA_PROTO_COMMAND_ACK_FRAME_ID) +
                                 sent(PMA_PROTO_PARAM_RESP_FRAME_ID));
    assert_state(app.state, PMA_STATE_ARMED);
    TEST_ASSERT_EQUAL_INT(before.frames_ignored + 11u, app.counters.frames_ignored);
    /* invalid frames handed over directly (the HAL never delivers them) */
    pma_can_frame_t bad = frame_of(0x800u, 0, 0, NULL);
    pma_app_handle_frame(&app, &bad);
    bad = frame_of(PMA_PROTO_COMMAND_FRAME_ID, T_NODE, 9, (const uint8_t[8]){PMA_CMD_START});
    pma_app_handle_frame(&app, &bad);
    pma_app_handle_frame(&app, NULL);
    pma_app_handle_frame(NULL, &bad);
    TEST_ASSERT_EQUAL_INT(before.frames_bad + 2u, app.counters.frames_bad);
    assert_state(app.state, PMA_STATE_ARMED);
    /* but an ESTOP is obeyed whatever its length, even an invalid one */
    bad = frame_of(PMA_PROTO_ESTOP_FRAME_ID, T_NODE, 9, NULL);
    pma_app_handle_frame(&app, &bad);
    assert_state(app.state, PMA_STATE_FAULT);
    TEST_ASSERT_EQUAL_INT(PMA_FAULT_ESTOP, app.fault);
}

/* COMMAND with the wrong length: PMA_ERR_LENGTH, nothing changes. */
static void test_command_wrong_length(void)
{
    to_idle(0);
    const uint8_t dlcs[] = {0, 1, 3, 8};
    for (size_t i = 0; i < sizeof dlcs / sizeof dlcs[0]; ++i) {
        inject(PMA_PROTO_COMMAND_FRAME_ID, dlcs[i], (const uint8_t[8]){PMA_CMD_ARM, 0, 0});
        cap_clear();
        step();
        TEST_ASSERT_EQUAL_INT(1, sent(PMA_PROTO_COMMAND_ACK_FRAME_ID));
        struct pma_proto_command_ack_t a;
        const pma_can_frame_t *r = last_frame(PMA_PROTO_COMMAND_ACK_FRAME_ID);
        TEST_ASSERT_EQUAL_INT(0, pma_proto_command_ack_unpack(&a, r->data, r->dlc));
        assert_status(a.result, PMA_ERR_LENGTH);
        TEST_ASSERT_EQUAL_INT(dlcs[i] > 0 ? PMA_CMD_ARM : 0, a.command);
        TEST_ASSERT_EQUAL_INT(PMA_STATE_IDLE, a.state);
        assert_state(app.state, PMA_STATE_IDLE);
    }
    TEST_ASSERT_EQUAL_INT(4u, app.counters.frames_bad);
    /* the same command with the right length is obeyed */
    command_ok(PMA_CMD_ARM, 0, PMA_OK);
    assert_state(app.state, PMA_STATE_ARMED);
}

/* ARM needs a valid position: none before the first tick. */
static void test_arm_refused_without_sample(void)
{
    /* ADC mode: the first step handles the frame before its tick reads the ADC */
    start_with(0, -1.5f);
    const struct pma_proto_command_ack_t a = command(PMA_CMD_ARM, 0);
    assert_status(a.result, PMA_ERR_NOT_READY);
    TEST_ASSERT_EQUAL_INT(PMA_STATE_IDLE, a.state);
    command_ok(PMA_CMD_ARM, 0, PMA_OK); /* the tick has read it now */

    /* plant bridge: no PLANT_SENSOR yet */
    start_with(1, -1.5f);
    steps(20);
    command_ok(PMA_CMD_ARM, 0, PMA_ERR_NOT_READY);
    assert_state(app.state, PMA_STATE_IDLE);
    const struct pma_proto_plant_actuator_t m = last_actuator();
    TEST_ASSERT_EQUAL_INT(PMA_SAMPLE_NONE, m.sample);
    TEST_ASSERT_EQUAL_INT(0, m.output_active);
    send_sample(0, counts_at(-1.5f));
    step();
    command_ok(PMA_CMD_ARM, 0, PMA_OK);
    assert_state(app.state, PMA_STATE_ARMED);
}

/* ARM refused with the sensor's error while it reads a fault. */
static void test_arm_refused_with_sensor_fault(void)
{
    to_idle(0);
    pma_fake_adc_wire_break();
    step();
    command_ok(PMA_CMD_ARM, 0, PMA_ERR_WIRE_BREAK);
    pma_fake_adc_out_of_range(4095);
    step();
    command_ok(PMA_CMD_ARM, 0, PMA_ERR_RANGE);
    pma_fake_adc_out_of_range(750); /* between the wire-break level and raw_min */
    step();
    command_ok(PMA_CMD_ARM, 0, PMA_ERR_RANGE);
    pma_fake_adc_read_error();
    step();
    command_ok(PMA_CMD_ARM, 0, PMA_ERR_IO);
    assert_state(app.state, PMA_STATE_IDLE);
    TEST_ASSERT_EQUAL_INT(0, dac_now());
    pma_fake_adc_clear_fault();
    step();
    command_ok(PMA_CMD_ARM, 0, PMA_OK);
}

/* ARM refused out of position: beyond the constraints by more than the margin. */
static void test_arm_refused_out_of_position(void)
{
    static const struct { float x; int rc; } cases[] = {
        {0.6f, PMA_ERR_RANGE}, {-3.6f, PMA_ERR_RANGE}, {3.0f, PMA_ERR_RANGE},
        {0.4f, PMA_OK}, {-3.4f, PMA_OK}, {-0.01f, PMA_OK},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        to_idle(0);
        pma_fake_adc_set(counts_at(cases[i].x));
        step();
        const struct pma_proto_command_ack_t a = command(PMA_CMD_ARM, 0);
        if (a.result != cases[i].rc) {
            pma_test_fail("ARM at x = %.2f cm: %s, expected %s", (double)cases[i].x,
                          pma_status_name(a.result), pma_status_name(cases[i].rc));
        }
        assert_state(app.state, cases[i].rc == PMA_OK ? PMA_STATE_ARMED : PMA_STATE_IDLE);
    }
}

/* ARM refused when a cross-parameter rule fails (each rule on its own),
 * nothing activated; fixed again, ARM works. */
static void test_arm_refused_cross_params(void)
{
    static const struct {
        uint16_t id;
        uint8_t type;
        pma_param_value_t bad;
    } cases[] = {
        {PMA_PARAM_CTRL_U_MIN, PMA_PARAM_F32, {.f32 = 400.0f}},      /* u_min == u_max */
        {PMA_PARAM_CTRL_U_MIN, PMA_PARAM_F32, {.f32 = 500.0f}},      /* u_min > u_max */
        {PMA_PARAM_CTRL_U_MAX, PMA_PARAM_F32, {.f32 = -400.0f}},
        {PMA_PARAM_ACT_POLARITY, PMA_PARAM_I32, {.i32 = 0}},          /* settable, refused here */
        {PMA_PARAM_ACT_P_MIN_KPA, PMA_PARAM_F32, {.f32 = 600.0f}},   /* p_min >= p_max */
        {PMA_PARAM_ACT_P_MAX_KPA, PMA_PARAM_F32, {.f32 = 200.0f}},   /* p0 above p_max */
        {PMA_PARAM_ACT_P_MIN_KPA, PMA_PARAM_F32, {.f32 = 350.0f}},   /* p0 below p_min */
        {PMA_PARAM_SAFETY_X_MIN_CM, PMA_PARAM_F32, {.f32 = 0.0f}},   /* x_min >= x_max */
        {PMA_PARAM_SAFETY_X_MAX_CM, PMA_PARAM_F32, {.f32 = -5.0f}},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        to_idle(0);
        const presp_t r = param_req(PMA_PARAM_OP_SET, cases[i].type, cases[i].id, cases[i].bad);
        assert_status(r.result, PMA_OK);
        const struct pma_proto_command_ack_t a = command(PMA_CMD_ARM, 0);
        if (a.result != PMA_ERR_RANGE) {
            pma_test_fail("case %lu (param %u): ARM gave %s, expected PMA_ERR_RANGE",
                          (unsigned long)i, cases[i].id, pma_status_name(a.result));
        }
        TEST_ASSERT_EQUAL_INT(PMA_STATE_IDLE, a.state);
        TEST_ASSERT_EQUAL_INT(0, dac_now()); /* still vented */
    }
    /* the scalings (adc.*, dac.*) are kept valid at every SET instead: refused
     * there with PMA_ERR_RANGE, nothing changes, ARM still works */
    static const struct {
        uint16_t id;
        uint8_t type;
        pma_param_value_t bad;
    } at_set[] = {
        {PMA_PARAM_ADC_GAIN_CM_PER_COUNT, PMA_PARAM_F32, {.f32 = 0.0f}},
        {PMA_PARAM_ADC_RAW_MIN_COUNTS, PMA_PARAM_U32, {.u32 = 4095}}, /* raw_min > raw_max */
        {PMA_PARAM_ADC_WIRE_BREAK_BELOW_COUNTS, PMA_PARAM_U32, {.u32 = 800}}, /* > raw_min */
        {PMA_PARAM_DAC_COUNTS_PER_KPA, PMA_PARAM_F32, {.f32 = 0.0f}},
        {PMA_PARAM_DAC_MIN_COUNTS, PMA_PARAM_U32, {.u32 = 4096}},     /* min > max */
    };
    for (size_t i = 0; i < sizeof at_set / sizeof at_set[0]; ++i) {
        to_idle(0);
        pma_param_type_t t;
        pma_param_value_t was, now;
        assert_status(pma_param_get(&app.params, at_set[i].id, &t, &was), PMA_OK);
        const presp_t r = param_req(PMA_PARAM_OP_SET, at_set[i].type, at_set[i].id, at_set[i].bad);
        assert_status(r.result, PMA_ERR_RANGE);
        assert_status(pma_param_get(&app.params, at_set[i].id, &t, &now), PMA_OK);
        TEST_ASSERT_EQUAL_INT(was.u32, now.u32);
        command_ok(PMA_CMD_ARM, 0, PMA_OK);
    }
    /* FIXED safe pressure above p_max */
    to_idle(0);
    set_u32(PMA_PARAM_SAFETY_SAFE_MODE, PMA_SAFETY_SAFE_MODE_FIXED);
    set_f32(PMA_PARAM_SAFETY_SAFE_KPA, 700.0f);
    command_ok(PMA_CMD_ARM, 0, PMA_ERR_RANGE);
    set_f32(PMA_PARAM_SAFETY_SAFE_KPA, 100.0f);
    command_ok(PMA_CMD_ARM, 0, PMA_OK);
}

/* START refused when the reference breaks the band check (eq. 14 with w1 for
 * PPC): PMA_ERR_BAND and the node stays ARMED, output at the preset. */
static void test_start_refused_band_check(void)
{
    to_armed(0);
    /* HOLD at -0.1 cm: inside -3 < x < 0, but not by w1 = 0.2 */
    set_f32(PMA_PARAM_REF_OFFSET_CM, -0.1f);
    command_ok(PMA_CMD_START, 0, PMA_ERR_BAND);
    assert_state(app.state, PMA_STATE_ARMED);
    step();
    TEST_ASSERT_EQUAL_INT(T_P0_COUNTS, dac_now());
    /* at -2.85: too close to the lower edge */
    set_f32(PMA_PARAM_REF_OFFSET_CM, -2.85f);
    command_ok(PMA_CMD_START, 0, PMA_ERR_BAND);
    /* a sine whose swing leaves the band */
    set_f32(PMA_PARAM_REF_OFFSET_CM, -1.5f);
    set_u32(PMA_PARAM_REF_KIND, PMA_REF_KIND_SINE);
    set_f32(PMA_PARAM_REF_AMPLITUDE_CM, 1.4f);
    command_ok(PMA_CMD_START, 0, PMA_ERR_BAND);
    set_f32(PMA_PARAM_REF_AMPLITUDE_CM, 1.2f);
    command_ok(PMA_CMD_START, 0, PMA_OK);
    command_ok(PMA_CMD_STOP, 0, PMA_OK);
    /* without the band check the PPC accepts -0.1 (only the band itself) */
    set_u32(PMA_PARAM_REF_KIND, PMA_REF_KIND_HOLD);
    set_f32(PMA_PARAM_REF_OFFSET_CM, -0.1f);
    set_u32(PMA_PARAM_PPC_BAND_CHECK, 0);
    command_ok(PMA_CMD_START, 0, PMA_OK);
    command_ok(PMA_CMD_STOP, 0, PMA_OK);
    /* a reference outside the band entirely: refused for every controller */
    set_f32(PMA_PARAM_REF_OFFSET_CM, 0.5f);
    for (uint8_t mode = 0; mode <= PMA_CTRL_MODE_OPEN_LOOP; ++mode) {
        command_ok(PMA_CMD_SELECT_CONTROLLER, mode, PMA_OK);
        command_ok(PMA_CMD_START, 0, PMA_ERR_BAND);
        assert_state(app.state, PMA_STATE_ARMED);
    }
    /* the paper's CASE1 (-0.5 sin t - 2) with w1 = 0.2 passes the band check */
    command_ok(PMA_CMD_SELECT_CONTROLLER, PMA_CTRL_MODE_PPC, PMA_OK);
    set_u32(PMA_PARAM_PPC_BAND_CHECK, 1);
    command_ok(PMA_CMD_SELECT_REFERENCE, PMA_REF_KIND_CASE1, PMA_OK);
    command_ok(PMA_CMD_START, 0, PMA_OK);
    assert_state(app.state, PMA_STATE_RUNNING);
}

/* START refused by other parameter problems, state stays ARMED. */
static void test_start_refused_bad_params(void)
{
    to_armed(0);
    /* ctrl.u_min is a "stopped" parameter: settable while ARMED */
    set_f32(PMA_PARAM_CTRL_U_MIN, 400.0f);
    command_ok(PMA_CMD_START, 0, PMA_ERR_RANGE);
    assert_state(app.state, PMA_STATE_ARMED);
    set_f32(PMA_PARAM_CTRL_U_MIN, -300.0f);
    /* velocity estimator bandwidth above half the tick rate */
    set_f32(PMA_PARAM_VEL_FC_HZ, 600.0f);
    TEST_ASSERT_LESS_THAN(0, command(PMA_CMD_START, 0).result);
    assert_state(app.state, PMA_STATE_ARMED);
    set_f32(PMA_PARAM_VEL_FC_HZ, 30.0f);
    /* ppc.widen_r must lie below the clamp, 1 - ppc.barrier_margin (with ppc.fallback WIDEN);
     * the paper's law without widening (ppc.fallback 0) takes the wide margin */
    set_f32(PMA_PARAM_PPC_BARRIER_MARGIN, 0.5f);
    command_ok(PMA_CMD_START, 0, PMA_ERR_RANGE);
    assert_state(app.state, PMA_STATE_ARMED);
    set_u32(PMA_PARAM_PPC_FALLBACK, PMA_PPC_FALLBACK_NONE);
    command_ok(PMA_CMD_START, 0, PMA_OK);
    command_ok(PMA_CMD_STOP, 0, PMA_OK);
    set_u32(PMA_PARAM_PPC_FALLBACK, PMA_PPC_FALLBACK_WIDEN);
    set_f32(PMA_PARAM_PPC_BARRIER_MARGIN, 1e-3f);
    command_ok(PMA_CMD_START, 0, PMA_OK);
}

/* Values valid in float that Q16.16 cannot hold (docs/fixed-point.md): the Q16.16 slot refuses
 * START with FIXED_RANGE and stays ARMED at the preset pressure; the float slot starts. */
static void test_start_refused_outside_fixed_point(void)
{
    static const struct {
        uint16_t id;
        float bad, good;
    } cases[] = {
        {PMA_PARAM_PPC_W1_CM, 0.01f, 0.2f},       /* w1 < 1/64: 1/w1 does not fit Q8.24 */
        {PMA_PARAM_PPC_REF_FF, 40000.0f, 0.0f},   /* beyond +-32767 */
        {PMA_PARAM_MFAC_LAMBDA, 1e-4f, 0.03f},    /* MFAC's lambda < 1/1024 (PPC's fallback) */
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        to_armed(0);
        const uint16_t dac_armed = app.output.dac_counts;
        set_f32(cases[i].id, cases[i].bad);
        const int rc = command(PMA_CMD_START, 0).result;
#if PMA_CTRL_Q16
        assert_status(rc, PMA_ERR_FIXED_RANGE);
        assert_state(app.state, PMA_STATE_ARMED);
        step();
        TEST_ASSERT_EQUAL_UINT16(dac_armed, app.output.dac_counts);
        set_f32(cases[i].id, cases[i].good);
        command_ok(PMA_CMD_START, 0, PMA_OK);
#else
        (void)dac_armed;
        assert_status(rc, PMA_OK);
#endif
        command_ok(PMA_CMD_STOP, 0, PMA_OK);
        command_ok(PMA_CMD_DISARM, 0, PMA_OK);
        set_f32(cases[i].id, cases[i].good);
    }
}

/* STOP from RUNNING returns to the preset pressure, DISARM to the safe one. */
static void test_stop_and_disarm_outputs(void)
{
    to_running(0);
    assert_status(set_param(PMA_PARAM_CTRL_MODE, vu(0)), PMA_ERR_STATE); /* not while RUNNING */
    command_ok(PMA_CMD_STOP, 0, PMA_OK);
    steps(20);
    assert_state(app.state, PMA_STATE_ARMED);
    TEST_ASSERT_EQUAL_INT(T_P0_COUNTS, dac_now());
    command_ok(PMA_CMD_DISARM, 0, PMA_OK);
    assert_state(app.state, PMA_STATE_IDLE);
    TEST_ASSERT_EQUAL_INT(0, dac_now()); /* vented at once, in the step of the command */
    /* DISARM straight from RUNNING */
    to_running(0);
    command_ok(PMA_CMD_DISARM, 0, PMA_OK);
    assert_state(app.state, PMA_STATE_IDLE);
    TEST_ASSERT_EQUAL_INT(0, dac_now());
}

/* The sensor's and the actuator's scalings changed while IDLE take effect: the position at the
 * next tick, the pressure at the next ARM (the Q16.16 builds' fixed-point stages are rebuilt
 * then, their parameters being idle-only), and SET refuses them while the output is active. */
static void test_idle_changes_reach_the_stages_at_arm(void)
{
    start_with(0, -1.5f);
    steps(5);                                      /* a sample */
    command_ok(PMA_CMD_ARM, 0, PMA_OK);
    steps(400);
    TEST_ASSERT_EQUAL_INT(T_P0_COUNTS, dac_now());
    const float cpk = app.params.dac_counts_per_kpa * 1.1f;
    assert_status(set_param(PMA_PARAM_DAC_COUNTS_PER_KPA, vf(cpk)), PMA_ERR_STATE);
    assert_status(set_param(PMA_PARAM_ADC_OFFSET_CM, vf(app.params.adc_offset_cm + 0.3f)), PMA_ERR_STATE);
    command_ok(PMA_CMD_DISARM, 0, PMA_OK);
    assert_status(set_param(PMA_PARAM_DAC_COUNTS_PER_KPA, vf(cpk)), PMA_OK);
    assert_status(set_param(PMA_PARAM_ADC_OFFSET_CM, vf(app.params.adc_offset_cm + 0.3f)), PMA_OK);
    step();
    assert_near(pma_app_position_cm(&app), -1.2f, 0.002);   /* the same counts, 0.3 cm further */
    command_ok(PMA_CMD_ARM, 0, PMA_OK);
    steps(400);                                    /* the slew from 0 kPa */
    TEST_ASSERT_EQUAL_INT(dac_counts_of(app.params.act_p0_kpa), dac_now());   /* the new DAC scaling */
    TEST_ASSERT_NOT_EQUAL(T_P0_COUNTS, dac_now());
    assert_near(pma_app_position_cm(&app), -1.2f, 0.002);
}

/* pma_app_init on a HAL that is not up: the error, state FAULT, no loop. */
static void test_init_errors(void)
{
    pma_fake_reset(); /* pma_hal_init() not called */
    plat = platform(0);
    assert_status(pma_app_init(NULL, &plat), PMA_ERR_NULL);
    assert_status(pma_app_init(&app, NULL), PMA_ERR_NULL);
    assert_status(pma_app_init(&app, &plat), PMA_ERR_NOT_READY);
    assert_state(app.state, PMA_STATE_FAULT);
    TEST_ASSERT_TRUE(app.fault != PMA_FAULT_NONE);
    assert_status(pma_app_step(&app), PMA_ERR_NOT_READY);
    assert_status(pma_app_step(NULL), PMA_ERR_NULL);
    assert_state(app.state, PMA_STATE_FAULT);
    TEST_ASSERT_EQUAL_INT(0, pma_fake_dac_write_count());
}

static void test_state_names(void)
{
    TEST_ASSERT_EQUAL_STRING("BOOT", pma_app_state_name(PMA_STATE_BOOT));
    TEST_ASSERT_EQUAL_STRING("RUNNING", pma_app_state_name(PMA_STATE_RUNNING));
    TEST_ASSERT_EQUAL_STRING("FAULT", pma_app_state_name(PMA_STATE_FAULT));
    TEST_ASSERT_EQUAL_STRING("UNKNOWN", pma_app_state_name(5));
    TEST_ASSERT_EQUAL_STRING("UNKNOWN", pma_app_state_name(-1));
    printf("sizeof(pma_app_t) = %lu bytes\n", (unsigned long)sizeof(pma_app_t));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_every_command_in_every_state_adc);
    RUN_TEST(test_every_command_in_every_state_bridge);
    RUN_TEST(test_commands_in_boot);
    RUN_TEST(test_estop_frames_from_every_state);
    RUN_TEST(test_other_nodes_frames_ignored);
    RUN_TEST(test_command_wrong_length);
    RUN_TEST(test_arm_refused_without_sample);
    RUN_TEST(test_arm_refused_with_sensor_fault);
    RUN_TEST(test_arm_refused_out_of_position);
    RUN_TEST(test_arm_refused_cross_params);
    RUN_TEST(test_start_refused_band_check);
    RUN_TEST(test_start_refused_bad_params);
    RUN_TEST(test_start_refused_outside_fixed_point);
    RUN_TEST(test_stop_and_disarm_outputs);
    RUN_TEST(test_idle_changes_reach_the_stages_at_arm);
    RUN_TEST(test_init_errors);
    RUN_TEST(test_state_names);
    return UNITY_END();
}
