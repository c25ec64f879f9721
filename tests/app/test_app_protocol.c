/* SPDX-License-Identifier: Apache-2.0 */
/* The CAN protocol as a host sees it (frames built and read with the codec
 * generated from pma_proto.dbc):
 *   - PARAM_REQ: every op (GET, SET, SAVE, RESTORE_DEFAULTS, GET_MIN, GET_MAX,
 *     GET_DEFAULT, NEXT_ID, LOAD) and every error (unknown id, wrong type,
 *     NaN, infinity, out of range, forbidden state, reserved byte, unknown op,
 *     wrong length), a rejected SET changing nothing (SAVE / LOAD with
 *     storage: test_app_storage.c; here the platform has none);
 *   - HEARTBEAT: period sys.heartbeat_ms on the fake clock, contents, flags;
 *   - TELEM_A..E: every telem.decimation ticks while RUNNING only, telem.mask;
 *   - plant bridge: PLANT_SENSOR in, PLANT_ACTUATOR out every tick, Seq echo,
 *     Sample NEW / REPEATED / GAP / NONE, duplicates;
 *   - PLANT_SENSOR, SETPOINT, HOST_HEARTBEAT of the wrong length dropped;
 *   - SETPOINT for the STREAM reference. */
#include "app_test.h"

static uint32_t saved_crc; /* CRC-32 of the parameter set before a request */

/* ------------------------------------------------------------ PARAM_REQ -- */

/* Every parameter through the protocol: NEXT_ID from 0 visits each id once,
 * in order; GET gives the default and the type; GET_MIN / MAX / DEFAULT give
 * the table's values. */
static void test_param_enumerate_get_min_max_default(void)
{
    to_idle(0);
    uint16_t id = 0;
    size_t n = 0;
    for (;;) {
        const presp_t r = param_req(PMA_PARAM_OP_NEXT_ID, PMA_PARAM_U32, id, vu(0));
        if (r.result == PMA_ERR_EMPTY) break;
        assert_status(r.result, PMA_OK);
        TEST_ASSERT_EQUAL_INT(PMA_PARAM_U32, r.type);
        TEST_ASSERT_LESS_THAN(PMA_PARAM_COUNT, n);
        const pma_param_desc_t *d = &pma_param_table[n];
        TEST_ASSERT_EQUAL_INT(d->id, r.v.u32);
        id = (uint16_t)r.v.u32;

        presp_t g = param_req(PMA_PARAM_OP_GET, 0, id, vu(0));
        assert_status(g.result, PMA_OK);
        TEST_ASSERT_EQUAL_INT(d->type, g.type);
        TEST_ASSERT_EQUAL_INT(d->def.u32, g.v.u32);
        g = param_req(PMA_PARAM_OP_GET_MIN, 0, id, vu(0));
        assert_status(g.result, PMA_OK);
        TEST_ASSERT_EQUAL_INT(d->type, g.type);
        TEST_ASSERT_EQUAL_INT(d->min.u32, g.v.u32);
        g = param_req(PMA_PARAM_OP_GET_MAX, 0, id, vu(0));
        assert_status(g.result, PMA_OK);
        TEST_ASSERT_EQUAL_INT(d->max.u32, g.v.u32);
        g = param_req(PMA_PARAM_OP_GET_DEFAULT, 0, id, vu(0));
        assert_status(g.result, PMA_OK);
        TEST_ASSERT_EQUAL_INT(d->def.u32, g.v.u32);
        ++n;
    }
    TEST_ASSERT_EQUAL_INT(PMA_PARAM_COUNT, n);
    /* unknown ids */
    const uint8_t ops[] = {PMA_PARAM_OP_GET, PMA_PARAM_OP_GET_MIN, PMA_PARAM_OP_GET_MAX,
                           PMA_PARAM_OP_GET_DEFAULT, PMA_PARAM_OP_SET};
    for (size_t i = 0; i < sizeof ops / sizeof ops[0]; ++i) {
        assert_status(param_req(ops[i], PMA_PARAM_U32, 6, vu(1)).result, PMA_ERR_UNKNOWN_ID);
        assert_status(param_req(ops[i], PMA_PARAM_F32, 0xFFFF, vf(1.0f)).result,
                      PMA_ERR_UNKNOWN_ID);
    }
    assert_status(param_req(PMA_PARAM_OP_NEXT_ID, 0, 0xFFFF, vu(0)).result, PMA_ERR_EMPTY);
}

/* SET of each type; the reply carries the value now. */
static void test_param_set_each_type(void)
{
    to_idle(0);
    presp_t r = param_req(PMA_PARAM_OP_SET, PMA_PARAM_F32, PMA_PARAM_PPC_C, vf(3.5f));
    assert_status(r.result, PMA_OK);
    TEST_ASSERT_EQUAL_INT(PMA_PARAM_F32, r.type);
    TEST_ASSERT_TRUE(r.v.f32 == 3.5f);
    TEST_ASSERT_TRUE(app.params.ppc_c == 3.5f);
    TEST_ASSERT_TRUE(param_req(PMA_PARAM_OP_GET, 0, PMA_PARAM_PPC_C, vu(0)).v.f32 == 3.5f);

    r = param_req(PMA_PARAM_OP_SET, PMA_PARAM_U32, PMA_PARAM_TELEM_MASK, vu(5));
    assert_status(r.result, PMA_OK);
    TEST_ASSERT_EQUAL_INT(PMA_PARAM_U32, r.type);
    TEST_ASSERT_EQUAL_INT(5, r.v.u32);
    TEST_ASSERT_EQUAL_INT(5, app.params.telem_mask);

    r = param_req(PMA_PARAM_OP_SET, PMA_PARAM_I32, PMA_PARAM_ACT_POLARITY, vi(-1));
    assert_status(r.result, PMA_OK);
    TEST_ASSERT_EQUAL_INT(PMA_PARAM_I32, r.type);
    TEST_ASSERT_EQUAL_INT(-1, r.v.i32);
    TEST_ASSERT_EQUAL_INT(-1, app.params.act_polarity);
    r = param_req(PMA_PARAM_OP_GET, PMA_PARAM_F32 /* the request's type does not matter */,
                  PMA_PARAM_ACT_POLARITY, vu(0));
    TEST_ASSERT_EQUAL_INT(PMA_PARAM_I32, r.type);
    TEST_ASSERT_EQUAL_INT(-1, r.v.i32);
    /* the edges are inside */
    assert_status(set_param(PMA_PARAM_ACT_POLARITY, vi(1)), PMA_OK);
    assert_status(set_param(PMA_PARAM_SYS_HEARTBEAT_MS, vu(10000)), PMA_OK);
    assert_status(set_param(PMA_PARAM_CTRL_OPENLOOP_U, vf(-10000.0f)), PMA_OK);
}

/* A SET that must fail with want: the reply carries the unchanged value and
 * the parameter's own type; nothing in the parameter set changes. */
static void set_rejected(uint8_t type, uint16_t id, pma_param_value_t v, int want)
{
    saved_crc = params_crc(&app.params);
    const uint8_t changed = app.storage.params_changed;
    const pma_param_desc_t *d = pma_param_find(id);
    pma_param_type_t t;
    pma_param_value_t before;
    before.u32 = 0;
    if (d != NULL) assert_status(pma_param_get(&app.params, id, &t, &before), PMA_OK);
    const presp_t r = param_req(PMA_PARAM_OP_SET, type, id, v);
    if (r.result != want) {
        pma_test_fail("SET id %u type %u raw 0x%08lx in %s: %s, expected %s", id, type,
                      (unsigned long)v.u32, pma_app_state_name(app.state),
                      pma_status_name(r.result), pma_status_name(want));
    }
    TEST_ASSERT_EQUAL_INT(saved_crc, params_crc(&app.params));
    TEST_ASSERT_EQUAL_INT(changed, app.storage.params_changed);
    if (d != NULL) {
        TEST_ASSERT_EQUAL_INT(d->type, r.type);
        TEST_ASSERT_EQUAL_INT(before.u32, r.v.u32);
    }
}

static void test_param_set_errors_change_nothing(void)
{
    to_idle(0);
    /* wrong type */
    set_rejected(PMA_PARAM_U32, PMA_PARAM_PPC_C, vu(3), PMA_ERR_TYPE);
    set_rejected(PMA_PARAM_I32, PMA_PARAM_PPC_C, vi(3), PMA_ERR_TYPE);
    set_rejected(PMA_PARAM_F32, PMA_PARAM_TELEM_MASK, vf(3.0f), PMA_ERR_TYPE);
    set_rejected(PMA_PARAM_U32, PMA_PARAM_ACT_POLARITY, vu(1), PMA_ERR_TYPE);
    set_rejected(3, PMA_PARAM_PPC_C, vu(0x40400000u), PMA_ERR_TYPE);   /* no such type */
    set_rejected(15, PMA_PARAM_TELEM_MASK, vu(1), PMA_ERR_TYPE);
    /* NaN and infinities */
    set_rejected(PMA_PARAM_F32, PMA_PARAM_CTRL_OPENLOOP_U, vf(NAN), PMA_ERR_NOT_FINITE);
    set_rejected(PMA_PARAM_F32, PMA_PARAM_CTRL_OPENLOOP_U, vf(INFINITY), PMA_ERR_NOT_FINITE);
    set_rejected(PMA_PARAM_F32, PMA_PARAM_PPC_C, vf(-INFINITY), PMA_ERR_NOT_FINITE);
    set_rejected(PMA_PARAM_F32, PMA_PARAM_PPC_C, vu(0x7FC00001u) /* a payload NaN */,
                 PMA_ERR_NOT_FINITE);
    /* below min / above max */
    set_rejected(PMA_PARAM_F32, PMA_PARAM_PPC_C, vf(0.0f), PMA_ERR_RANGE);
    set_rejected(PMA_PARAM_F32, PMA_PARAM_PPC_C, vf(1.5e6f), PMA_ERR_RANGE);
    set_rejected(PMA_PARAM_U32, PMA_PARAM_SYS_TICK_HZ, vu(49), PMA_ERR_RANGE);
    set_rejected(PMA_PARAM_U32, PMA_PARAM_SYS_TICK_HZ, vu(5001), PMA_ERR_RANGE);
    set_rejected(PMA_PARAM_U32, PMA_PARAM_TELEM_MASK, vu(32), PMA_ERR_RANGE);
    set_rejected(PMA_PARAM_I32, PMA_PARAM_ACT_POLARITY, vi(2), PMA_ERR_RANGE);
    set_rejected(PMA_PARAM_I32, PMA_PARAM_ACT_POLARITY, vi(-2), PMA_ERR_RANGE);
    set_rejected(PMA_PARAM_U32, PMA_PARAM_CTRL_MODE, vu(5), PMA_ERR_RANGE);
    /* unknown id */
    set_rejected(PMA_PARAM_F32, 6, vf(1.0f), PMA_ERR_UNKNOWN_ID);
    TEST_ASSERT_EQUAL_INT(0, app.storage.params_changed);

    /* state rules: idle parameters while ARMED and RUNNING, stopped ones while
     * RUNNING; live ones always */
    to_armed(0);
    set_rejected(PMA_PARAM_F32, PMA_PARAM_SAFETY_X_MAX_CM, vf(-0.5f), PMA_ERR_STATE);
    set_rejected(PMA_PARAM_U32, PMA_PARAM_SAFETY_SAFE_MODE, vu(1), PMA_ERR_STATE);
    set_rejected(PMA_PARAM_U32, PMA_PARAM_SYS_TICK_HZ, vu(500), PMA_ERR_STATE);
    set_rejected(PMA_PARAM_I32, PMA_PARAM_ACT_POLARITY, vi(-1), PMA_ERR_STATE);
    assert_status(set_param(PMA_PARAM_PPC_C, vf(2.5f)), PMA_OK);          /* stopped */
    to_running(0);
    set_rejected(PMA_PARAM_F32, PMA_PARAM_SAFETY_X_MIN_CM, vf(-2.0f), PMA_ERR_STATE);
    set_rejected(PMA_PARAM_F32, PMA_PARAM_SAFETY_SAFE_KPA, vf(10.0f), PMA_ERR_STATE);
    set_rejected(PMA_PARAM_U32, PMA_PARAM_SAFETY_BARRIER_TICKS, vu(0), PMA_ERR_STATE);
    set_rejected(PMA_PARAM_F32, PMA_PARAM_PPC_C, vf(2.5f), PMA_ERR_STATE);
    set_rejected(PMA_PARAM_U32, PMA_PARAM_CTRL_MODE, vu(PMA_CTRL_MODE_PID), PMA_ERR_STATE);
    set_rejected(PMA_PARAM_U32, PMA_PARAM_REF_KIND, vu(PMA_REF_KIND_SINE), PMA_ERR_STATE);
    /* a value out of range while RUNNING: refused either way, nothing changes */
    set_rejected(PMA_PARAM_F32, PMA_PARAM_SAFETY_X_MIN_CM, vf(-2000.0f), PMA_ERR_RANGE);
    assert_status(set_param(PMA_PARAM_CTRL_OPENLOOP_U, vf(12.0f)), PMA_OK); /* live */
    assert_status(set_param(PMA_PARAM_TELEM_DECIMATION, vu(20)), PMA_OK);
    assert_status(set_param(PMA_PARAM_SYS_HEARTBEAT_MS, vu(50)), PMA_OK);
    assert_state(app.state, PMA_STATE_RUNNING);
    /* FAULT is inactive: idle parameters may be set */
    command_ok(PMA_CMD_ESTOP, 0, PMA_OK);
    assert_status(set_param(PMA_PARAM_SAFETY_X_MIN_CM, vf(-2.0f)), PMA_OK);
}

/* Malformed requests: wrong DLC (PMA_ERR_LENGTH), reserved byte not 0,
 * unknown op (PMA_ERR_UNKNOWN_COMMAND); nothing changes. */
static void test_param_malformed_requests(void)
{
    to_idle(0);
    saved_crc = params_crc(&app.params);
    /* a SET of telem.mask = 3 cut short / padded */
    struct pma_proto_param_req_t m;
    memset(&m, 0, sizeof m);
    m.op = PMA_PARAM_OP_SET;
    m.type = PMA_PARAM_U32;
    m.id = PMA_PARAM_TELEM_MASK;
    m.value_u32 = 3;
    uint8_t d[8];
    TEST_ASSERT_EQUAL_INT(8, pma_proto_param_req_pack(d, &m, sizeof d));
    const uint8_t dlcs[] = {0, 1, 3, 7};
    for (size_t i = 0; i < sizeof dlcs / sizeof dlcs[0]; ++i) {
        inject(PMA_PROTO_PARAM_REQ_FRAME_ID, dlcs[i], d);
        cap_clear();
        step();
        TEST_ASSERT_EQUAL_INT(1, sent(PMA_PROTO_PARAM_RESP_FRAME_ID));
        const presp_t r = decode_param_resp(last_frame(PMA_PROTO_PARAM_RESP_FRAME_ID));
        assert_status(r.result, PMA_ERR_LENGTH);
        /* what could be read of op and id is echoed */
        TEST_ASSERT_EQUAL_INT(dlcs[i] > 0 ? PMA_PARAM_OP_SET : 0, r.op);
        TEST_ASSERT_EQUAL_INT(dlcs[i] > 2 ? PMA_PARAM_TELEM_MASK : 0, r.id);
    }
    TEST_ASSERT_EQUAL_INT(4u, app.counters.frames_bad);
    /* reserved byte */
    for (unsigned reserved = 1; reserved < 256u; reserved += 127u) {
        const presp_t r = param_req_raw(PMA_PARAM_OP_SET, PMA_PARAM_U32, PMA_PARAM_TELEM_MASK,
                                        vu(3), (uint8_t)reserved);
        assert_status(r.result, PMA_ERR_UNKNOWN_COMMAND);
        const presp_t g = param_req_raw(PMA_PARAM_OP_SAVE, 0, 0, vu(0), (uint8_t)reserved);
        assert_status(g.result, PMA_ERR_UNKNOWN_COMMAND);
    }
    /* unknown ops 10..15 (9 is GET_STATUS) */
    for (uint8_t op = 10; op <= 15; ++op) {
        const presp_t r = param_req(op, PMA_PARAM_U32, PMA_PARAM_TELEM_MASK, vu(3));
        assert_status(r.result, PMA_ERR_UNKNOWN_COMMAND);
    }
    TEST_ASSERT_EQUAL_INT(saved_crc, params_crc(&app.params));
    TEST_ASSERT_EQUAL_INT(0, app.storage.params_changed);
    /* the well-formed request works */
    assert_status(param_req(PMA_PARAM_OP_SET, PMA_PARAM_U32, PMA_PARAM_TELEM_MASK, vu(3)).result,
                  PMA_OK);
    TEST_ASSERT_EQUAL_INT(3, app.params.telem_mask);
}

/* Whole-set ops on a platform without storage: SAVE and LOAD are not
 * implemented, RESTORE_DEFAULTS works; all three refused while ARMED and
 * RUNNING. (With storage: test_app_storage.c.) */
static void test_param_whole_set_ops_without_storage(void)
{
    to_idle(0);
    TEST_ASSERT_EQUAL_INT(0, plat.store_blocks_per_slot);
    set_f32(PMA_PARAM_PPC_C, 7.0f);
    assert_status(whole_op(PMA_PARAM_OP_SAVE), PMA_ERR_NOT_IMPLEMENTED);
    TEST_ASSERT_EQUAL_INT(0, app.storage.save_failed); /* nothing was attempted */
    assert_status(whole_op(PMA_PARAM_OP_LOAD), PMA_ERR_NOT_IMPLEMENTED);
    TEST_ASSERT_TRUE(app.params.ppc_c == 7.0f);
    TEST_ASSERT_EQUAL_INT(1, app.storage.params_changed);
    /* RESTORE_DEFAULTS: the table's defaults, in RAM */
    assert_status(whole_op(PMA_PARAM_OP_RESTORE_DEFAULTS), PMA_OK);
    pma_params_t def;
    pma_params_defaults(&def);
    TEST_ASSERT_EQUAL_MEMORY(&def, &app.params, sizeof def);
    TEST_ASSERT_EQUAL_INT(1, app.storage.params_changed);

    /* refused while the output is active, nothing changes */
    to_armed(0);
    set_f32(PMA_PARAM_PPC_C, 3.0f);
    saved_crc = params_crc(&app.params);
    const uint8_t ops[] = {PMA_PARAM_OP_SAVE, PMA_PARAM_OP_LOAD, PMA_PARAM_OP_RESTORE_DEFAULTS};
    for (size_t i = 0; i < 3; ++i) assert_status(whole_op(ops[i]), PMA_ERR_STATE);
    command_ok(PMA_CMD_START, 0, PMA_OK);
    for (size_t i = 0; i < 3; ++i) assert_status(whole_op(ops[i]), PMA_ERR_STATE);
    TEST_ASSERT_EQUAL_INT(saved_crc, params_crc(&app.params));
    /* allowed again in FAULT (output safe) */
    command_ok(PMA_CMD_ESTOP, 0, PMA_OK);
    assert_status(whole_op(PMA_PARAM_OP_RESTORE_DEFAULTS), PMA_OK);
    TEST_ASSERT_TRUE(app.params.ppc_c == 2.0f);
}

/* SET sys.tick_hz restarts the tick at the new period at once. */
static void test_param_tick_rate(void)
{
    to_idle(0);
    set_u32(PMA_PARAM_SYS_TICK_HZ, 250);
    uint64_t t0 = pma_hal_time_us();
    step();
    TEST_ASSERT_EQUAL_INT(4000u, pma_hal_time_us() - t0);
    TEST_ASSERT_EQUAL_INT(4000u, app.timing.period_us);
    /* RESTORE_DEFAULTS brings back 1 kHz */
    assert_status(whole_op(PMA_PARAM_OP_RESTORE_DEFAULTS), PMA_OK);
    t0 = pma_hal_time_us();
    step();
    TEST_ASSERT_EQUAL_INT(1000u, pma_hal_time_us() - t0);
}

/* ------------------------------------------------------------ HEARTBEAT -- */

static void test_heartbeat_period_and_contents(void)
{
    start_with(0, -1.5f); /* cap holds what pma_app_init sent: the BOOT heartbeat */
    struct pma_proto_heartbeat_t h = last_heartbeat();
    TEST_ASSERT_EQUAL_INT(1, cap.total);
    TEST_ASSERT_EQUAL_INT(PMA_STATE_BOOT, h.state);
    TEST_ASSERT_EQUAL_INT(0, h.fault_code);
    TEST_ASSERT_EQUAL_INT(PMA_RESET_POWER_ON, h.reset_cause);
    TEST_ASSERT_EQUAL_INT(0, h.counter);
    TEST_ASSERT_EQUAL_INT(PMA_CTRL_MODE_PPC, h.controller);
    TEST_ASSERT_EQUAL_INT(PMA_REF_KIND_HOLD, h.reference);
    TEST_ASSERT_EQUAL_HEX16(PMA_HB_PARAMS_DEFAULT, h.flags);

    /* every 100 ms of the fake clock: 99 ticks nothing, the 100th one */
    cap_clear();
    steps(99);
    TEST_ASSERT_EQUAL_INT(0, sent(PMA_PROTO_HEARTBEAT_FRAME_ID));
    step();
    TEST_ASSERT_EQUAL_INT(1, sent(PMA_PROTO_HEARTBEAT_FRAME_ID));
    TEST_ASSERT_EQUAL_INT(100000u, pma_hal_time_us());
    h = last_heartbeat();
    TEST_ASSERT_EQUAL_INT(PMA_STATE_IDLE, h.state);
    TEST_ASSERT_EQUAL_INT(1, h.counter);
    TEST_ASSERT_EQUAL_HEX16(PMA_HB_PARAMS_DEFAULT | PMA_HB_SENSOR_VALID, h.flags);
    cap_clear();
    steps(1000);
    TEST_ASSERT_EQUAL_INT(10, sent(PMA_PROTO_HEARTBEAT_FRAME_ID));
    TEST_ASSERT_EQUAL_INT(11, last_heartbeat().counter);
    TEST_ASSERT_EQUAL_INT(0, cap.foreign);

    /* without ticks: pma_app_poll on the clock alone */
    cap_clear();
    pma_fake_time_advance_us(99999u);
    pma_app_poll(&app);
    drain();
    TEST_ASSERT_EQUAL_INT(0, sent(PMA_PROTO_HEARTBEAT_FRAME_ID));
    pma_fake_time_advance_us(1u);
    pma_app_poll(&app);
    pma_app_poll(&app);
    drain();
    TEST_ASSERT_EQUAL_INT(1, sent(PMA_PROTO_HEARTBEAT_FRAME_ID));
    /* a long stall: one heartbeat, not a burst; the next a period later */
    cap_clear();
    pma_fake_time_advance_us(450000u);
    pma_app_poll(&app);
    drain();
    TEST_ASSERT_EQUAL_INT(1, sent(PMA_PROTO_HEARTBEAT_FRAME_ID));
    pma_fake_time_advance_us(99999u);
    pma_app_poll(&app);
    drain();
    TEST_ASSERT_EQUAL_INT(1, sent(PMA_PROTO_HEARTBEAT_FRAME_ID));
    pma_fake_time_advance_us(1u);
    pma_app_poll(&app);
    drain();
    TEST_ASSERT_EQUAL_INT(2, sent(PMA_PROTO_HEARTBEAT_FRAME_ID));

    /* sys.heartbeat_ms is live: 20 ms from the next period on */
    set_u32(PMA_PARAM_SYS_HEARTBEAT_MS, 20);
    (void)next_heartbeat();
    uint64_t t0 = pma_hal_time_us();
    (void)next_heartbeat();
    TEST_ASSERT_EQUAL_INT(20000u, pma_hal_time_us() - t0);
    t0 = pma_hal_time_us();
    (void)next_heartbeat();
    TEST_ASSERT_EQUAL_INT(20000u, pma_hal_time_us() - t0);
}

static void test_heartbeat_flags_by_state(void)
{
    to_armed(0);
    struct pma_proto_heartbeat_t h = next_heartbeat();
    TEST_ASSERT_EQUAL_INT(PMA_STATE_ARMED, h.state);
    TEST_ASSERT_EQUAL_HEX16(PMA_HB_OUTPUT_ACTIVE | PMA_HB_SENSOR_VALID | PMA_HB_PARAMS_DEFAULT,
                            h.flags);
    command_ok(PMA_CMD_START, 0, PMA_OK);
    send_host_heartbeat(0);
    h = next_heartbeat();
    TEST_ASSERT_EQUAL_INT(PMA_STATE_RUNNING, h.state);
    TEST_ASSERT_EQUAL_HEX16(PMA_HB_OUTPUT_ACTIVE | PMA_HB_SENSOR_VALID | PMA_HB_PARAMS_DEFAULT |
                                PMA_HB_REF_ACTIVE,
                            h.flags);
    /* a live SET: PARAMS_CHANGED */
    set_u32(PMA_PARAM_TELEM_DECIMATION, 50);
    send_host_heartbeat(1);
    h = next_heartbeat();
    TEST_ASSERT_TRUE(h.flags & PMA_HB_PARAMS_CHANGED);
    command_ok(PMA_CMD_ESTOP, 0, PMA_OK);
    pma_fake_adc_wire_break();
    h = next_heartbeat();
    TEST_ASSERT_EQUAL_INT(PMA_STATE_FAULT, h.state);
    TEST_ASSERT_EQUAL_INT(PMA_FAULT_ESTOP, h.fault_code);
    /* sensor invalid */
    TEST_ASSERT_EQUAL_HEX16(PMA_HB_PARAMS_DEFAULT | PMA_HB_PARAMS_CHANGED, h.flags);
    /* CAN error-passive */
    pma_fake_adc_clear_fault();
    pma_fake_can_set_error_counters(140, 0);
    h = next_heartbeat();
    TEST_ASSERT_TRUE(h.flags & PMA_HB_CAN_PASSIVE);
    TEST_ASSERT_TRUE(h.flags & PMA_HB_SENSOR_VALID);
    pma_fake_can_set_error_counters(0, 130);
    h = next_heartbeat();
    TEST_ASSERT_TRUE(h.flags & PMA_HB_CAN_PASSIVE);
    pma_fake_can_set_error_counters(0, 0);
    h = next_heartbeat();
    TEST_ASSERT_FALSE(h.flags & PMA_HB_CAN_PASSIVE);
    /* controller and reference follow the parameters */
    command_ok(PMA_CMD_CLEAR_FAULTS, 0, PMA_OK);
    command_ok(PMA_CMD_SELECT_CONTROLLER, PMA_CTRL_MODE_MFAC, PMA_OK);
    command_ok(PMA_CMD_SELECT_REFERENCE, PMA_REF_KIND_CASE3, PMA_OK);
    h = next_heartbeat();
    TEST_ASSERT_EQUAL_INT(PMA_CTRL_MODE_MFAC, h.controller);
    TEST_ASSERT_EQUAL_INT(PMA_REF_KIND_CASE3, h.reference);
    TEST_ASSERT_EQUAL_INT(0, h.fault_code);

    /* plant bridge and lockstep bits come from the platform */
    start_with(1, -1.5f);
    h = next_heartbeat();
    /* no sample yet */
    TEST_ASSERT_EQUAL_HEX16(PMA_HB_PLANT_BRIDGE | PMA_HB_PARAMS_DEFAULT, h.flags);
    plat.lockstep = 1;
    assert_status(pma_app_init(&app, &plat), PMA_OK);
    cap_clear();
    drain();
    send_sample(0, counts_at(-1.0f));
    /* the heartbeat comes 100 ticks later: without newer samples the one
     * sample is too old (safety.sensor_timeout_ticks) to count as valid */
    h = next_heartbeat();
    TEST_ASSERT_EQUAL_HEX16(PMA_HB_PLANT_BRIDGE | PMA_HB_LOCKSTEP | PMA_HB_PARAMS_DEFAULT, h.flags);
}

/* ------------------------------------------------------------ telemetry -- */

static void test_telemetry_running_only_decimation_and_mask(void)
{
    to_armed(0);
    cap_clear();
    steps(100);
    TEST_ASSERT_EQUAL_INT(0, sent(PMA_PROTO_TELEM_A_FRAME_ID) + sent(PMA_PROTO_TELEM_E_FRAME_ID));
    command_ok(PMA_CMD_START, 0, PMA_OK); /* its step is run tick 1 */
    cap_clear();
    steps(8);
    TEST_ASSERT_EQUAL_INT(0, sent(PMA_PROTO_TELEM_A_FRAME_ID));
    step(); /* run tick 10 */
    const uint16_t ids[5] = {PMA_PROTO_TELEM_A_FRAME_ID, PMA_PROTO_TELEM_B_FRAME_ID,
                             PMA_PROTO_TELEM_C_FRAME_ID, PMA_PROTO_TELEM_D_FRAME_ID,
                             PMA_PROTO_TELEM_E_FRAME_ID};
    for (int i = 0; i < 5; ++i) {
        TEST_ASSERT_EQUAL_INT(1, sent(ids[i]));
        TEST_ASSERT_EQUAL_INT(ids[i] | T_NODE, last_frame(ids[i])->id);
        TEST_ASSERT_EQUAL_INT(8, last_frame(ids[i])->dlc);
    }
    struct pma_proto_telem_a_t ta;
    struct pma_proto_telem_b_t tb;
    struct pma_proto_telem_e_t te;
    TEST_ASSERT_EQUAL_INT(0, pma_proto_telem_a_unpack(&ta, last_frame(ids[0])->data, 8));
    TEST_ASSERT_EQUAL_INT(0, pma_proto_telem_b_unpack(&tb, last_frame(ids[1])->data, 8));
    TEST_ASSERT_EQUAL_INT(0, pma_proto_telem_e_unpack(&te, last_frame(ids[4])->data, 8));
    /* run time since START: the control time of this (10th) step, t = 0 at START's */
    TEST_ASSERT_EQUAL_INT(9, ta.time_ms);
    assert_near(pma_ctrl_out(&app.ctrl)->t_s, 0.009, 1e-6 + CTRL_LSB);
    assert_near(ta.x_cm, -1.5f, 0.002);
    assert_near(tb.xr_cm, -1.5f, 1e-6);
    assert_near(tb.e_cm, ta.x_cm - tb.xr_cm, 1e-6);
    assert_near(te.pressure_kpa, pma_app_pressure_kpa(&app), 0.0);
    /* 1 s of running: 100 sets */
    cap_clear();
    steps_hb(1000);
    for (int i = 0; i < 5; ++i) TEST_ASSERT_EQUAL_INT(100, sent(ids[i]));
    TEST_ASSERT_EQUAL_INT(0, pma_proto_telem_a_unpack(&ta, last_frame(ids[0])->data, 8));
    TEST_ASSERT_EQUAL_INT(1009, ta.time_ms);
    /* mask: A and C only; decimation 3 */
    set_u32(PMA_PARAM_TELEM_MASK, 0x05);
    set_u32(PMA_PARAM_TELEM_DECIMATION, 3);
    cap_clear();
    steps_hb(300);
    TEST_ASSERT_EQUAL_INT(100, sent(ids[0]));
    TEST_ASSERT_EQUAL_INT(0, sent(ids[1]));
    TEST_ASSERT_EQUAL_INT(100, sent(ids[2]));
    TEST_ASSERT_EQUAL_INT(0, sent(ids[3]) + sent(ids[4]));
    /* decimation 0: none; mask 0: none */
    set_u32(PMA_PARAM_TELEM_DECIMATION, 0);
    cap_clear();
    steps(100);
    TEST_ASSERT_EQUAL_INT(0, sent(ids[0]) + sent(ids[2]));
    set_u32(PMA_PARAM_TELEM_DECIMATION, 1);
    set_u32(PMA_PARAM_TELEM_MASK, 0);
    cap_clear();
    steps_hb(100);
    for (int i = 0; i < 5; ++i) TEST_ASSERT_EQUAL_INT(0, sent(ids[i]));
    /* every tick, all five; none after STOP */
    set_u32(PMA_PARAM_TELEM_MASK, 31);
    cap_clear();
    steps(10);
    for (int i = 0; i < 5; ++i) TEST_ASSERT_EQUAL_INT(10, sent(ids[i]));
    command_ok(PMA_CMD_STOP, 0, PMA_OK);
    cap_clear();
    steps(50);
    for (int i = 0; i < 5; ++i) TEST_ASSERT_EQUAL_INT(0, sent(ids[i]));
}

/* ---------------------------------------------------------- plant bridge -- */

static void test_bridge_sample_status_and_seq(void)
{
    start_with(1, -1.5f);
    /* no sample yet: NONE, safe output */
    cap_clear();
    step();
    TEST_ASSERT_EQUAL_INT(1, sent(PMA_PROTO_PLANT_ACTUATOR_FRAME_ID));
    struct pma_proto_plant_actuator_t m = last_actuator();
    TEST_ASSERT_EQUAL_INT(PMA_SAMPLE_NONE, m.sample);
    TEST_ASSERT_EQUAL_INT(0, m.output_active);
    TEST_ASSERT_EQUAL_INT(0, m.dac_counts);
    TEST_ASSERT_EQUAL_INT(0, pma_fake_dac_write_count()); /* the DAC is not used in bridge mode */
    /* NEW, echoed seq */
    send_sample(200, counts_at(-1.5f));
    cap_clear();
    step();
    m = last_actuator();
    TEST_ASSERT_EQUAL_INT(200, m.seq);
    TEST_ASSERT_EQUAL_INT(PMA_SAMPLE_NEW, m.sample);
    assert_near(pma_app_position_cm(&app), -1.5f, 0.002);
    /* no new sample: REPEATED, same seq */
    cap_clear();
    step();
    m = last_actuator();
    TEST_ASSERT_EQUAL_INT(200, m.seq);
    TEST_ASSERT_EQUAL_INT(PMA_SAMPLE_REPEATED, m.sample);
    /* the next one: NEW */
    send_sample(201, counts_at(-1.0f));
    cap_clear();
    step();
    m = last_actuator();
    TEST_ASSERT_EQUAL_INT(201, m.seq);
    TEST_ASSERT_EQUAL_INT(PMA_SAMPLE_NEW, m.sample);
    assert_near(pma_app_position_cm(&app), -1.0f, 0.002);
    /* a duplicate of 201: not a new sample */
    send_sample(201, counts_at(-2.0f));
    cap_clear();
    step();
    m = last_actuator();
    TEST_ASSERT_EQUAL_INT(PMA_SAMPLE_REPEATED, m.sample);
    assert_near(pma_app_position_cm(&app), -1.0f, 0.002);
    TEST_ASSERT_EQUAL_INT(1, app.counters.bridge_repeats);
    /* 202 and 203 lost: 204 is NEW after a GAP */
    send_sample(204, counts_at(-2.0f));
    cap_clear();
    step();
    m = last_actuator();
    TEST_ASSERT_EQUAL_INT(204, m.seq);
    TEST_ASSERT_EQUAL_INT(PMA_SAMPLE_GAP, m.sample);
    TEST_ASSERT_EQUAL_INT(1, app.counters.bridge_gaps);
    assert_near(pma_app_position_cm(&app), -2.0f, 0.002);
    /* wrap-around 255 -> 0 is no gap */
    send_sample(255, counts_at(-2.0f));
    step();
    send_sample(0, counts_at(-2.0f));
    cap_clear();
    step();
    m = last_actuator();
    TEST_ASSERT_EQUAL_INT(0, m.seq);
    TEST_ASSERT_EQUAL_INT(PMA_SAMPLE_NEW, m.sample);
    TEST_ASSERT_EQUAL_INT(2, app.counters.bridge_gaps); /* 204 -> 255 was one */
    /* two samples in one step: the newer one counts */
    send_sample(1, counts_at(-2.2f));
    send_sample(2, counts_at(-2.4f));
    cap_clear();
    step();
    m = last_actuator();
    TEST_ASSERT_EQUAL_INT(2, m.seq);
    TEST_ASSERT_EQUAL_INT(PMA_SAMPLE_NEW, m.sample);
    assert_near(pma_app_position_cm(&app), -2.4f, 0.002);
    /* ARMED: the pressure command goes out in the actuator frame */
    command_ok(PMA_CMD_ARM, 0, PMA_OK);
    for (uint8_t s = 3; s < 30; ++s) {
        send_sample(s, counts_at(-2.4f));
        cap_clear();
        step();
        m = last_actuator();
        TEST_ASSERT_EQUAL_INT(s, m.seq);
        TEST_ASSERT_EQUAL_INT(1, m.output_active);
        TEST_ASSERT_EQUAL_INT(app.output.dac_counts, m.dac_counts);
    }
    TEST_ASSERT_EQUAL_INT(T_P0_COUNTS, m.dac_counts);
    TEST_ASSERT_EQUAL_INT(0, pma_fake_dac_write_count());
    TEST_ASSERT_EQUAL_INT(0, cap.foreign);
}

/* sys.plant_bridge (the board's switch between ADC/DAC and the bridge):
 * settable only with the output inactive; off, PLANT_SENSOR frames are
 * ignored (counted as bad, nothing used, no PLANT_ACTUATOR) and the ADC and
 * DAC work; on, the bridge replaces them; a platform that forces the bridge
 * (the host build) keeps it whatever the parameter says. */
static void test_bridge_parameter(void)
{
    const pma_param_desc_t *d = pma_param_find(PMA_PARAM_SYS_PLANT_BRIDGE);
    TEST_ASSERT_NOT_NULL(d);
    TEST_ASSERT_EQUAL_INT(PMA_PARAM_U32, d->type);
    TEST_ASSERT_EQUAL_INT(0u, d->def.u32); /* off by default */

    /* off (default, board platform): the ADC is read, bridge frames ignored */
    start_with(0, -1.5f);
    TEST_ASSERT_EQUAL_INT(0u, app.params.sys_plant_bridge);
    TEST_ASSERT_EQUAL_INT(0, pma_app_bridge_on(&app));
    const uint32_t bad_before = app.counters.frames_bad;
    send_sample(7, counts_at(-2.5f));
    cap_clear();
    step();
    TEST_ASSERT_EQUAL_INT(bad_before + 1u, app.counters.frames_bad);
    TEST_ASSERT_EQUAL_INT(0, app.bridge.have);
    assert_near(pma_app_position_cm(&app), -1.5f, 0.002); /* the ADC's position, not the frame's */
    TEST_ASSERT_EQUAL_INT(0, sent(PMA_PROTO_PLANT_ACTUATOR_FRAME_ID));
    TEST_ASSERT_EQUAL_INT(0u, dac_now()); /* the DAC is written every tick (safe: 0 kPa) */
    struct pma_proto_heartbeat_t h = next_heartbeat();
    TEST_ASSERT_EQUAL_HEX16(0, h.flags & PMA_HB_PLANT_BRIDGE);

    /* refused while ARMED and RUNNING, with the state error; nothing changes */
    command_ok(PMA_CMD_ARM, 0, PMA_OK);
    assert_status(set_param(PMA_PARAM_SYS_PLANT_BRIDGE, vu(1)), PMA_ERR_STATE);
    command_ok(PMA_CMD_START, 0, PMA_OK);
    assert_state(app.state, PMA_STATE_RUNNING);
    assert_status(set_param(PMA_PARAM_SYS_PLANT_BRIDGE, vu(1)), PMA_ERR_STATE);
    TEST_ASSERT_EQUAL_INT(0u, app.params.sys_plant_bridge);
    TEST_ASSERT_EQUAL_INT(0, pma_app_bridge_on(&app));
    /* out of range: refused in IDLE too */
    command_ok(PMA_CMD_DISARM, 0, PMA_OK);
    assert_status(set_param(PMA_PARAM_SYS_PLANT_BRIDGE, vu(2)), PMA_ERR_RANGE);

    /* accepted while disarmed: the bridge takes over at once */
    const uint32_t dac_writes = pma_fake_dac_write_count();
    set_u32(PMA_PARAM_SYS_PLANT_BRIDGE, 1u);
    TEST_ASSERT_EQUAL_INT(1, pma_app_bridge_on(&app));
    cap_clear();
    step();
    struct pma_proto_plant_actuator_t m = last_actuator();
    TEST_ASSERT_EQUAL_INT(PMA_SAMPLE_NONE, m.sample); /* the ADC's sample does not count as one */
    assert_status(app.sensor.status, PMA_ERR_NOT_READY);
    command_ok(PMA_CMD_ARM, 0, PMA_ERR_NOT_READY); /* no bridge sample yet */
    send_sample(40, counts_at(-2.0f));
    cap_clear();
    step();
    m = last_actuator();
    TEST_ASSERT_EQUAL_INT(40, m.seq);
    TEST_ASSERT_EQUAL_INT(PMA_SAMPLE_NEW, m.sample);
    assert_near(pma_app_position_cm(&app), -2.0f, 0.002);
    h = next_heartbeat();
    TEST_ASSERT_TRUE(h.flags & PMA_HB_PLANT_BRIDGE);
    /* ARMED over the bridge: the pressure leaves in frames, the DAC is left alone */
    send_sample(41, counts_at(-2.0f));
    step(); /* ARM wants the sample of the tick before */
    command_ok(PMA_CMD_ARM, 0, PMA_OK);
    for (uint8_t s = 42; s < 62; ++s) {
        send_sample(s, counts_at(-2.0f));
        cap_clear();
        step();
    }
    m = last_actuator();
    TEST_ASSERT_EQUAL_INT(1, m.output_active);
    TEST_ASSERT_EQUAL_INT(T_P0_COUNTS, m.dac_counts);
    TEST_ASSERT_EQUAL_INT(dac_writes, pma_fake_dac_write_count());
    assert_status(set_param(PMA_PARAM_SYS_PLANT_BRIDGE, vu(0)), PMA_ERR_STATE);
    TEST_ASSERT_EQUAL_INT(1, pma_app_bridge_on(&app));

    /* back off while disarmed: the ADC and DAC again, bridge frames ignored */
    command_ok(PMA_CMD_DISARM, 0, PMA_OK);
    set_u32(PMA_PARAM_SYS_PLANT_BRIDGE, 0u);
    pma_fake_adc_set(counts_at(-1.0f));
    send_sample(62, counts_at(-2.5f));
    cap_clear();
    step();
    assert_near(pma_app_position_cm(&app), -1.0f, 0.002);
    TEST_ASSERT_EQUAL_INT(0, sent(PMA_PROTO_PLANT_ACTUATOR_FRAME_ID));
    TEST_ASSERT_GREATER_THAN(dac_writes, pma_fake_dac_write_count());

    /* the host build forces the bridge: the parameter at 0 does not turn it off */
    start_with(1, -1.5f);
    TEST_ASSERT_EQUAL_INT(0u, app.params.sys_plant_bridge);
    TEST_ASSERT_EQUAL_INT(1, pma_app_bridge_on(&app));
    send_sample(1, counts_at(-2.0f));
    cap_clear();
    step();
    TEST_ASSERT_EQUAL_INT(PMA_SAMPLE_NEW, last_actuator().sample);
    TEST_ASSERT_EQUAL_INT(0, pma_fake_dac_write_count());
}

/* PLANT_SENSOR (also in ADC mode), SETPOINT and HOST_HEARTBEAT of the wrong
 * length: dropped, counted, no reply, as if never received. */
static void test_wrong_length_frames_dropped(void)
{
    start_with(1, -1.5f);
    const uint8_t bad_sensor[] = {0, 2, 4, 8};
    for (size_t i = 0; i < sizeof bad_sensor / sizeof bad_sensor[0]; ++i) {
        inject(PMA_PROTO_PLANT_SENSOR_FRAME_ID, bad_sensor[i], (const uint8_t[8]){7, 0x80, 0x0B});
        cap_clear();
        step();
        TEST_ASSERT_EQUAL_INT(1, cap.total); /* the actuator frame only */
        TEST_ASSERT_EQUAL_INT(PMA_SAMPLE_NONE, last_actuator().sample);
    }
    TEST_ASSERT_EQUAL_INT(4, app.counters.frames_bad);
    command_ok(PMA_CMD_ARM, 0, PMA_ERR_NOT_READY);
    /* in ADC mode a PLANT_SENSOR is not expected at all */
    to_idle(0);
    send_sample(1, counts_at(-0.2f));
    cap_clear();
    step();
    TEST_ASSERT_EQUAL_INT(0, cap.total);
    TEST_ASSERT_EQUAL_INT(1, app.counters.frames_bad);
    assert_near(pma_app_position_cm(&app), -1.5f, 0.002);

    /* HOST_HEARTBEAT of the wrong length does not feed the host timeout */
    to_running(0);
    const uint8_t bad_hb[] = {0, 2, 8};
    for (uint32_t t = 0; t < 499; ++t) {
        if (t % 100 == 50) {
            inject(PMA_PROTO_HOST_HEARTBEAT_FRAME_ID, bad_hb[(t / 100) % 3], (const uint8_t[8]){1});
        }
        cap_clear();
        step();
        TEST_ASSERT_EQUAL_INT(0, sent(PMA_PROTO_COMMAND_ACK_FRAME_ID) +
                                     sent(PMA_PROTO_PARAM_RESP_FRAME_ID));
        if (app.state != PMA_STATE_RUNNING) break;
    }
    TEST_ASSERT_EQUAL_INT(5, app.counters.frames_bad);
    assert_state(app.state, PMA_STATE_FAULT);
    assert_fault(app.fault, PMA_FAULT_HOST_HEARTBEAT_LOST);

    /* SETPOINT of the wrong length: the STREAM target does not move */
    to_armed(0);
    set_u32(PMA_PARAM_CTRL_MODE, PMA_CTRL_MODE_OFF); /* x stays put: no barrier */
    set_u32(PMA_PARAM_REF_KIND, PMA_REF_KIND_STREAM);
    set_f32(PMA_PARAM_REF_RATE_CM_S, 0.0f); /* jump to the target */
    command_ok(PMA_CMD_START, 0, PMA_OK);
    uint8_t d[8];
    struct pma_proto_setpoint_t sp = {.xr_cm = -1.0f};
    TEST_ASSERT_EQUAL_INT(4, pma_proto_setpoint_pack(d, &sp, sizeof d));
    const uint8_t bad_sp[] = {0, 3, 5, 8};
    for (size_t i = 0; i < sizeof bad_sp / sizeof bad_sp[0]; ++i) {
        inject(PMA_PROTO_SETPOINT_FRAME_ID, bad_sp[i], d);
        cap_clear();
        step();
        TEST_ASSERT_EQUAL_INT(0, sent(PMA_PROTO_COMMAND_ACK_FRAME_ID) +
                                     sent(PMA_PROTO_PARAM_RESP_FRAME_ID));
        assert_near(pma_ctrl_out(&app.ctrl)->xr_cm, -1.5f, 1e-6);
    }
    TEST_ASSERT_EQUAL_INT(4, app.counters.frames_bad);
    TEST_ASSERT_EQUAL_INT(0, app.counters.setpoints_rejected);
    inject(PMA_PROTO_SETPOINT_FRAME_ID, 4, d);
    step();
    assert_near(pma_ctrl_out(&app.ctrl)->xr_cm, -1.0f, 1e-6);
}

/* SETPOINT: used by the STREAM reference while RUNNING, inside the band. */
static void test_setpoint_stream(void)
{
    to_armed(0);
    uint8_t d[8];
    struct pma_proto_setpoint_t sp = {.xr_cm = -1.0f};
    TEST_ASSERT_EQUAL_INT(4, pma_proto_setpoint_pack(d, &sp, sizeof d));
    /* not RUNNING: rejected */
    inject(PMA_PROTO_SETPOINT_FRAME_ID, 4, d);
    step();
    TEST_ASSERT_EQUAL_INT(1, app.counters.setpoints_rejected);
    /* RUNNING a HOLD reference: rejected */
    command_ok(PMA_CMD_START, 0, PMA_OK);
    inject(PMA_PROTO_SETPOINT_FRAME_ID, 4, d);
    step();
    TEST_ASSERT_EQUAL_INT(2, app.counters.setpoints_rejected);
    assert_near(pma_ctrl_out(&app.ctrl)->xr_cm, -1.5f, 1e-6);
    command_ok(PMA_CMD_STOP, 0, PMA_OK);
    /* STREAM at 0.5 cm/s from the offset -1.5 (controller OFF: the position
     * stays put, the reference is what is watched) */
    set_u32(PMA_PARAM_CTRL_MODE, PMA_CTRL_MODE_OFF);
    set_u32(PMA_PARAM_REF_KIND, PMA_REF_KIND_STREAM);
    set_f32(PMA_PARAM_REF_RATE_CM_S, 0.5f);
    command_ok(PMA_CMD_START, 0, PMA_OK);
    assert_near(pma_ctrl_out(&app.ctrl)->xr_cm, -1.5f, 1e-6);
    inject(PMA_PROTO_SETPOINT_FRAME_ID, 4, d);
    steps(100);
    assert_near(pma_ctrl_out(&app.ctrl)->xr_cm, -1.45f, 1e-3); /* 0.05 cm in 0.1 s */
    TEST_ASSERT_EQUAL_INT(2, app.counters.setpoints_rejected);
    /* outside the band (or on its edge), NaN, infinity: rejected, target kept */
    const float bad[] = {0.0f, 0.5f, -3.0f, -10.0f, NAN, INFINITY};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        sp.xr_cm = bad[i];
        TEST_ASSERT_EQUAL_INT(4, pma_proto_setpoint_pack(d, &sp, sizeof d));
        inject(PMA_PROTO_SETPOINT_FRAME_ID, 4, d);
        send_host_heartbeat((uint8_t)i);
        step();
        TEST_ASSERT_EQUAL_INT(3u + i, app.counters.setpoints_rejected);
    }
    steps_hb(1000);
    assert_near(pma_ctrl_out(&app.ctrl)->xr_cm, -1.0f, 1e-3);
    assert_state(app.state, PMA_STATE_RUNNING);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_param_enumerate_get_min_max_default);
    RUN_TEST(test_param_set_each_type);
    RUN_TEST(test_param_set_errors_change_nothing);
    RUN_TEST(test_param_malformed_requests);
    RUN_TEST(test_param_whole_set_ops_without_storage);
    RUN_TEST(test_param_tick_rate);
    RUN_TEST(test_heartbeat_period_and_contents);
    RUN_TEST(test_heartbeat_flags_by_state);
    RUN_TEST(test_telemetry_running_only_decimation_and_mask);
    RUN_TEST(test_bridge_sample_status_and_seq);
    RUN_TEST(test_bridge_parameter);
    RUN_TEST(test_wrong_length_frames_dropped);
    RUN_TEST(test_setpoint_stream);
    return UNITY_END();
}
