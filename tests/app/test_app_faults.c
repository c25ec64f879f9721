/* SPDX-License-Identifier: Apache-2.0 */
/* Every fault drives the output to the configured safe state within the tick
 * that detects it, and latches its code (HEARTBEAT FaultCode) until
 * CLEAR_FAULTS:
 *   sensor wire break, out of range, read error (fake ADC faults), sensor
 *   timeout in bridge mode (no more PLANT_SENSOR), position beyond the limits
 *   plus margin, tick overrun (late ticks from the fake clock and given to
 *   pma_app_tick), host heartbeat lost while RUNNING (never while ARMED),
 *   non-finite controller output, PPC barrier held for safety.barrier_ticks,
 *   DAC write failure, CAN bus-off (CLEAR_FAULTS refused while bus-off),
 *   watchdog reset (boots into FAULT WATCHDOG_RESET), ESTOP.
 * The output is read where it leaves the node: the fake DAC's log in ADC mode
 * (the write of this very step), the PLANT_ACTUATOR frame in bridge mode. The
 * safe modes VENT, HOLD and FIXED are each checked. */
#include "app_test.h"

/* The safe output of the current parameters, as counts. */
static uint16_t safe_counts(uint16_t active_counts)
{
    switch (app.params.safety_safe_mode) {
    case PMA_SAFETY_SAFE_MODE_HOLD: return active_counts;
    case PMA_SAFETY_SAFE_MODE_FIXED: return dac_counts_of(app.params.safety_safe_kpa);
    default: return 0;
    }
}

/* The output this step (ADC mode: the DAC write of this step; bridge: the
 * PLANT_ACTUATOR frame of this step). */
static uint16_t output_now(void)
{
    if (plat.plant_bridge) {
        TEST_ASSERT_EQUAL_INT(1, sent(PMA_PROTO_PLANT_ACTUATOR_FRAME_ID));
        return last_actuator().dac_counts;
    }
    return dac_now();
}

/* One step in which the fault must be found: before it the output is active,
 * after it the node is in FAULT with `want`, and this same step put out the
 * safe counts. */
static void expect_fault_this_step(pma_fault_t want)
{
    TEST_ASSERT_TRUE(app.state == PMA_STATE_ARMED || app.state == PMA_STATE_RUNNING);
    const uint16_t active = app.output.dac_counts;
    cap_clear();
    step();
    assert_state(app.state, PMA_STATE_FAULT);
    assert_fault(app.fault, want);
    TEST_ASSERT_EQUAL_INT(safe_counts(active), output_now());
    if (plat.plant_bridge) TEST_ASSERT_EQUAL_INT(0, last_actuator().output_active);
}

/* The fault stays latched (even when its cause is gone, even when others
 * come), the output stays safe, the heartbeat reports it; CLEAR_FAULTS
 * returns to IDLE (fault 0), and the node can be armed again. */
static void expect_latched_then_clear(pma_fault_t want, uint8_t bridge)
{
    const uint16_t out = app.output.dac_counts;
    pma_app_raise_fault(&app, PMA_FAULT_ESTOP); /* a later fault does not replace it */
    uint8_t seq = (uint8_t)(app.bridge.seq + 1u);
    for (int i = 0; i < 3; ++i) {
        if (bridge) send_sample(seq++, counts_at(-1.5f));
        cap_clear();
        step();
        assert_state(app.state, PMA_STATE_FAULT);
        assert_fault(app.fault, want);
        TEST_ASSERT_EQUAL_INT(out, output_now());
    }
    struct pma_proto_heartbeat_t h = next_heartbeat();
    TEST_ASSERT_EQUAL_INT(PMA_STATE_FAULT, h.state);
    TEST_ASSERT_EQUAL_INT(want, h.fault_code);
    TEST_ASSERT_FALSE(h.flags & PMA_HB_OUTPUT_ACTIVE);
    if (bridge) send_sample(seq++, counts_at(-1.5f));
    const struct pma_proto_command_ack_t a = command(PMA_CMD_CLEAR_FAULTS, 0);
    assert_status(a.result, PMA_OK);
    TEST_ASSERT_EQUAL_INT(PMA_STATE_IDLE, a.state);
    assert_fault(app.fault, PMA_FAULT_NONE);
    h = next_heartbeat();
    TEST_ASSERT_EQUAL_INT(PMA_STATE_IDLE, h.state);
    TEST_ASSERT_EQUAL_INT(0, h.fault_code);
}

/* ----------------------------------------------------------- the sensor -- */

static void test_sensor_faults_adc(void)
{
    static const struct { int kind; pma_fault_t fault; } cases[] = {
        {0, PMA_FAULT_SENSOR_WIRE_BREAK}, {1, PMA_FAULT_SENSOR_RANGE},
        {2, PMA_FAULT_SENSOR_RANGE}, {3, PMA_FAULT_SENSOR_READ},
    };
    for (int running = 0; running < 2; ++running) {
        for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
            if (running) {
                to_running(0);
            } else {
                to_armed(0);
            }
            TEST_ASSERT_EQUAL_INT(T_P0_COUNTS, app.output.dac_counts);
            switch (cases[i].kind) {
            case 0: pma_fake_adc_wire_break(); break;
            case 1: pma_fake_adc_out_of_range(4095); break;  /* the clipped ADC */
            case 2: pma_fake_adc_out_of_range(760); break;   /* below raw_min, above wire break */
            default: pma_fake_adc_read_error(); break;
            }
            expect_fault_this_step(cases[i].fault);
            pma_fake_adc_clear_fault();
            expect_latched_then_clear(cases[i].fault, 0);
            command_ok(PMA_CMD_ARM, 0, PMA_OK);
        }
    }
}

/* Bridge: a sample at the wire-break level or out of range. */
static void test_sensor_faults_bridge(void)
{
    to_running(1);
    send_sample(22, 100); /* below the wire-break level 737 */
    expect_fault_this_step(PMA_FAULT_SENSOR_WIRE_BREAK);
    expect_latched_then_clear(PMA_FAULT_SENSOR_WIRE_BREAK, 1);
    to_armed(1);
    send_sample(21, 4095);
    expect_fault_this_step(PMA_FAULT_SENSOR_RANGE);
}

/* Bridge: no new sample for safety.sensor_timeout_ticks ticks while the
 * output is active (repeated samples do not count as new). */
static void test_sensor_timeout_bridge(void)
{
    for (int running = 0; running < 2; ++running) {
        if (running) {
            to_running(1);
        } else {
            to_armed(1);
        }
        send_sample((uint8_t)(app.bridge.seq + 1u), counts_at(-1.5f));
        cap_clear();
        step();
        TEST_ASSERT_EQUAL_INT(PMA_SAMPLE_NEW, last_actuator().sample);
        /* 9 ticks without a new sample (one of them a duplicate): still fine */
        for (int i = 1; i < 10; ++i) {
            if (i == 5) send_sample(app.bridge.seq, counts_at(-1.5f));
            cap_clear();
            step();
            assert_state(app.state, running ? PMA_STATE_RUNNING : PMA_STATE_ARMED);
            TEST_ASSERT_EQUAL_INT(PMA_SAMPLE_REPEATED, last_actuator().sample);
            TEST_ASSERT_EQUAL_INT(T_P0_COUNTS, last_actuator().dac_counts);
        }
        /* the 10th */
        expect_fault_this_step(PMA_FAULT_SENSOR_TIMEOUT);
        send_sample((uint8_t)(app.bridge.seq + 1u), counts_at(-1.5f));
        expect_latched_then_clear(PMA_FAULT_SENSOR_TIMEOUT, 1);
    }
    /* while IDLE nothing times out */
    to_idle(1);
    cap_clear();
    steps(100);
    assert_state(app.state, PMA_STATE_IDLE);
    /* a longer timeout */
    to_armed(1);
    send_sample(30, counts_at(-1.5f));
    step();
    command_ok(PMA_CMD_DISARM, 0, PMA_OK);
    set_u32(PMA_PARAM_SAFETY_SENSOR_TIMEOUT_TICKS, 50);
    send_sample(31, counts_at(-1.5f));
    command_ok(PMA_CMD_ARM, 0, PMA_OK); /* sample 31 is 0 ticks old */
    steps(49);
    assert_state(app.state, PMA_STATE_ARMED);
    expect_fault_this_step(PMA_FAULT_SENSOR_TIMEOUT);
}

/* ------------------------------------------------------------- position -- */

static void test_position_limit(void)
{
    static const float bad[] = {0.55f, -3.55f, 2.0f};
    for (int bridge = 0; bridge < 2; ++bridge) {
        for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
            to_armed((uint8_t)bridge);
            /* inside the margin: fine */
            const float ok = bad[i] > 0.0f ? 0.45f : -3.45f;
            if (bridge) {
                send_sample(21, counts_at(ok));
            } else {
                pma_fake_adc_set(counts_at(ok));
            }
            cap_clear();
            step();
            assert_state(app.state, PMA_STATE_ARMED);
            if (bridge) {
                send_sample(22, counts_at(bad[i]));
            } else {
                pma_fake_adc_set(counts_at(bad[i]));
            }
            expect_fault_this_step(PMA_FAULT_POSITION_LIMIT);
            if (!bridge) pma_fake_adc_set(counts_at(-1.5f));
            expect_latched_then_clear(PMA_FAULT_POSITION_LIMIT, (uint8_t)bridge);
        }
    }
    /* a smaller margin moves the trip point */
    to_idle(0);
    set_f32(PMA_PARAM_SAFETY_X_MARGIN_CM, 0.1f);
    command_ok(PMA_CMD_ARM, 0, PMA_OK);
    pma_fake_adc_set(counts_at(0.2f));
    expect_fault_this_step(PMA_FAULT_POSITION_LIMIT);
}

/* ---------------------------------------------------------- tick overrun -- */

static void test_tick_overrun(void)
{
    /* from the fake clock: the loop was late by 2 periods (allowed), then 3 */
    to_running(0);
    pma_fake_time_advance_us(2u * T_PERIOD_US);
    cap_clear();
    step();
    TEST_ASSERT_EQUAL_INT(2, app.timing.late_ticks);
    assert_state(app.state, PMA_STATE_RUNNING);
    pma_fake_time_advance_us(3u * T_PERIOD_US);
    TEST_ASSERT_EQUAL_INT(PMA_STATE_RUNNING, app.state);
    expect_fault_this_step(PMA_FAULT_TICK_OVERRUN);
    TEST_ASSERT_EQUAL_INT(3, app.timing.late_ticks);
    expect_latched_then_clear(PMA_FAULT_TICK_OVERRUN, 0);

    /* given directly to pma_app_tick, in ARMED */
    to_armed(0);
    pma_app_tick(&app, 2);
    assert_state(app.state, PMA_STATE_ARMED);
    pma_app_tick(&app, 3);
    assert_state(app.state, PMA_STATE_FAULT);
    assert_fault(app.fault, PMA_FAULT_TICK_OVERRUN);
    TEST_ASSERT_EQUAL_INT(0, dac_now());

    /* safety.max_late_ticks 0: one late tick trips */
    to_idle(0);
    set_u32(PMA_PARAM_SAFETY_MAX_LATE_TICKS, 0);
    command_ok(PMA_CMD_ARM, 0, PMA_OK);
    pma_fake_time_advance_us(T_PERIOD_US);
    expect_fault_this_step(PMA_FAULT_TICK_OVERRUN);

    /* late ticks while IDLE are no fault */
    to_idle(0);
    pma_fake_time_advance_us(50u * T_PERIOD_US);
    step();
    assert_state(app.state, PMA_STATE_IDLE);
}

/* ----------------------------------------------------------- host heartbeat -- */

static void test_host_heartbeat_lost(void)
{
    /* ARMED: no host heartbeat needed */
    to_armed(0);
    steps(2000);
    assert_state(app.state, PMA_STATE_ARMED);
    /* RUNNING with heartbeats every 100 ms: fine for 3 s */
    command_ok(PMA_CMD_START, 0, PMA_OK);
    steps_hb(3000);
    assert_state(app.state, PMA_STATE_RUNNING);
    /* the last one came 100 ticks ago (steps_hb sends at the start of each
     * hundred); the 500th tick without one (500 ms) trips */
    steps(399);
    assert_state(app.state, PMA_STATE_RUNNING);
    expect_fault_this_step(PMA_FAULT_HOST_HEARTBEAT_LOST);
    expect_latched_then_clear(PMA_FAULT_HOST_HEARTBEAT_LOST, 0);

    /* the timer starts at START, not at the last heartbeat before it */
    to_armed(0);
    send_host_heartbeat(0);
    steps(1000);
    command_ok(PMA_CMD_START, 0, PMA_OK); /* run tick 1 */
    steps(498);
    assert_state(app.state, PMA_STATE_RUNNING);
    expect_fault_this_step(PMA_FAULT_HOST_HEARTBEAT_LOST);

    /* STOP and START again: the time RUNNING before the STOP does not count */
    to_running(0);
    steps(400);
    command_ok(PMA_CMD_STOP, 0, PMA_OK);
    steps(100);
    command_ok(PMA_CMD_START, 0, PMA_OK);
    steps(498);
    assert_state(app.state, PMA_STATE_RUNNING);
    expect_fault_this_step(PMA_FAULT_HOST_HEARTBEAT_LOST);

    /* 0 disables it */
    to_idle(0);
    set_u32(PMA_PARAM_SAFETY_HOST_TIMEOUT_MS, 0);
    command_ok(PMA_CMD_ARM, 0, PMA_OK);
    command_ok(PMA_CMD_START, 0, PMA_OK);
    steps(3000);
    assert_state(app.state, PMA_STATE_RUNNING);
}

/* --------------------------------------------------------------- NaN -- */

/* A NaN cannot be set (PARAM_REQ refuses it) and the controllers never
 * produce one from finite inputs; this stands for a corrupted value: the
 * OPEN_LOOP controller passes ctrl.openloop_u through, and a NaN there must
 * fault NOT_FINITE with the safe output in that tick. */
static void test_non_finite_output(void)
{
    to_armed(0);
    command_ok(PMA_CMD_SELECT_CONTROLLER, PMA_CTRL_MODE_OPEN_LOOP, PMA_OK);
    assert_status(set_param(PMA_PARAM_CTRL_OPENLOOP_U, vf(NAN)), PMA_ERR_NOT_FINITE);
    set_f32(PMA_PARAM_CTRL_OPENLOOP_U, 30.0f);
    command_ok(PMA_CMD_START, 0, PMA_OK);
    steps(10);
    TEST_ASSERT_EQUAL_INT(dac_counts_of(330.0f), dac_now()); /* p0 + u */
    app.params.ctrl_openloop_u = NAN; /* corruption, not through the protocol */
    expect_fault_this_step(PMA_FAULT_NOT_FINITE);
    app.params.ctrl_openloop_u = 0.0f;
    expect_latched_then_clear(PMA_FAULT_NOT_FINITE, 0);
    /* infinity likewise */
    command_ok(PMA_CMD_ARM, 0, PMA_OK);
    command_ok(PMA_CMD_START, 0, PMA_OK);
    app.params.ctrl_openloop_u = -INFINITY;
    expect_fault_this_step(PMA_FAULT_NOT_FINITE);
}

/* ------------------------------------------------------------- barrier -- */

static uint32_t status_value(uint16_t id)
{
    const presp_t r = param_req(PMA_PARAM_OP_GET_STATUS, PMA_PARAM_U32, id, vu(0));
    assert_status(r.result, PMA_OK);
    return r.v.u32;
}

/* PPC without the fallback (ppc.fallback 0, the BARRIER fault asked for): the
 * position held far from the reference drives lambda1 into its barrier;
 * safety.barrier_ticks consecutive clamped ticks fault. */
static void test_barrier(void)
{
    to_armed(0);
    set_u32(PMA_PARAM_PPC_FALLBACK, 0);
    command_ok(PMA_CMD_START, 0, PMA_OK);
    pma_fake_adc_set(counts_at(-0.2f)); /* e = 1.3 cm >> w1 = 0.2 cm, inside the band */
    uint32_t run = 0, t = 0;
    while (app.state == PMA_STATE_RUNNING && t < 3000) {
        if (t % 100 == 0) send_host_heartbeat((uint8_t)t);
        const uint16_t active = app.output.dac_counts;
        cap_clear();
        step();
        ++t;
        run = pma_ctrl_out(&app.ctrl)->barrier ? run + 1u : 0u;
        if (run < 100u) {
            assert_state(app.state, PMA_STATE_RUNNING);
        } else {
            /* the 100th consecutive clamped tick */
            assert_state(app.state, PMA_STATE_FAULT);
            assert_fault(app.fault, PMA_FAULT_BARRIER);
            TEST_ASSERT_EQUAL_INT(safe_counts(active), dac_now());
        }
    }
    TEST_ASSERT_EQUAL_INT(100u, run);
    TEST_ASSERT_GREATER_OR_EQUAL(100u, app.ctrl.breaches);
    expect_latched_then_clear(PMA_FAULT_BARRIER, 0);

    /* 0 disables the check */
    set_u32(PMA_PARAM_SAFETY_BARRIER_TICKS, 0);
    pma_fake_adc_set(counts_at(-1.5f));
    step();
    command_ok(PMA_CMD_ARM, 0, PMA_OK);
    command_ok(PMA_CMD_START, 0, PMA_OK);
    pma_fake_adc_set(counts_at(-0.2f));
    uint32_t longest = 0;
    run = 0;
    for (t = 0; t < 1500; ++t) {
        if (t % 100 == 0) send_host_heartbeat((uint8_t)t);
        step();
        run = pma_ctrl_out(&app.ctrl)->barrier ? run + 1u : 0u;
        if (run > longest) longest = run;
    }
    assert_state(app.state, PMA_STATE_RUNNING);
    TEST_ASSERT_GREATER_THAN(500u, longest); /* far beyond the 100 that trip when enabled */
}

/* The same task with ppc.fallback 1 (MFAC): no fault; the 100th consecutive clamped tick
 * (safety.barrier_ticks) loses the guarantee and hands the loop to MFAC, which starts from
 * the holding input by the static map (ppc.ff_init here: no reference feedforward), not from
 * the law's clamped input, and from phi(1); the loss is flagged in the
 * heartbeat and in TELEM_E, counted (GET_STATUS 8, and every tick after t_u with |e| >= w1),
 * and its time kept (GET_STATUS 9); the supervisor's limits still apply. */
static void test_barrier_hands_over_to_mfac(void)
{
    to_armed(0);
    set_u32(PMA_PARAM_PPC_FALLBACK, PMA_PPC_FALLBACK_MFAC);
    const float ff_init = 37.5f;   /* the holding input at the reference's start, a Q16.16 value */
    set_f32(PMA_PARAM_PPC_FF_INIT, ff_init);
    command_ok(PMA_CMD_START, 0, PMA_OK);
    TEST_ASSERT_EQUAL_HEX32(UINT32_MAX, status_value(PMA_STATUS_GUARANTEE_LOST_AT_MS));
    TEST_ASSERT_EQUAL_INT(0u, status_value(PMA_STATUS_GUARANTEE_LOST_TICKS));
    pma_fake_adc_set(counts_at(-0.2f)); /* e = 1.3 cm >> w1 = 0.2 cm, inside the band */
    uint32_t run = 0, t = 0, handover_tick = 0, lost = 0;
    float handover_t_s = 0.0f;
    const float t_u_s = app.params.ppc_t_u_s;
    while (t < 3000) {
        if (t % 100 == 0) send_host_heartbeat((uint8_t)t);
        const float u_before = pma_app_output_u(&app);
        step();
        ++t;
        assert_state(app.state, PMA_STATE_RUNNING);
        const pma_ctrl_out_t *o = pma_ctrl_out(&app.ctrl);
        if (handover_tick == 0) {
            run = o->barrier ? run + 1u : 0u;
            if (run < 100u) {
                TEST_ASSERT_FALSE(app.ctrl.fallback_active);
                TEST_ASSERT_FALSE(o->flags & PMA_CTRL_FLAG_FALLBACK);
                continue;
            }
            handover_tick = t;
            handover_t_s = o->t_s;
            TEST_ASSERT_TRUE(app.ctrl.lost && app.ctrl.fallback_active);
            /* MFAC's first step starts from ff_init and phi(1), not from the law's input at
             * its limit */
            TEST_ASSERT_TRUE(u_before <= app.params.ctrl_u_min || u_before >= app.params.ctrl_u_max);
            TEST_ASSERT_FLOAT_WITHIN((float)CTRL_LSB, ff_init, CTRL_F32(app.ctrl.shadow.u2));
            TEST_ASSERT_TRUE(app.ctrl.shadow.flags & PMA_MFAC_FLAG_RESET);
        }
        TEST_ASSERT_TRUE(o->flags & PMA_CTRL_FLAG_FALLBACK);
        TEST_ASSERT_TRUE(o->flags & PMA_CTRL_FLAG_GUARANTEE_LOST);
        TEST_ASSERT_TRUE(pma_app_output_u(&app) >= app.params.ctrl_u_min && pma_app_output_u(&app) <= app.params.ctrl_u_max);
        if (o->t_s >= t_u_s && fabsf(o->e_cm) >= app.params.ppc_w1_cm) ++lost;
    }
    TEST_ASSERT_GREATER_THAN(0u, handover_tick);
    TEST_ASSERT_GREATER_THAN(0u, lost);
    /* the run's last tick counts, then every tick after t_u outside w1 */
    TEST_ASSERT_EQUAL_INT(1u + lost, status_value(PMA_STATUS_GUARANTEE_LOST_TICKS));
    /* the control time of the hand-over tick, in ms */
    TEST_ASSERT_EQUAL_INT(lroundf(handover_t_s * 1000.0f), status_value(PMA_STATUS_GUARANTEE_LOST_AT_MS));
    TEST_ASSERT_EQUAL_INT(app.ctrl.breaches, status_value(PMA_STATUS_BARRIER_BREACHES));
    const struct pma_proto_heartbeat_t h = next_heartbeat();
    TEST_ASSERT_TRUE(h.flags & PMA_HB_GUARANTEE_LOST);
    TEST_ASSERT_TRUE(h.flags & PMA_HB_FALLBACK);
    TEST_ASSERT_EQUAL_INT(PMA_FAULT_NONE, h.fault_code);
    /* the safety limits stay: the position leaves the band -> POSITION_LIMIT */
    pma_fake_adc_set(counts_at(1.0f));
    step();
    assert_fault(app.fault, PMA_FAULT_POSITION_LIMIT);
    /* the next START clears the monitor */
    command_ok(PMA_CMD_CLEAR_FAULTS, 0, PMA_OK);
    pma_fake_adc_set(counts_at(-1.5f));
    to_running(0);
    TEST_ASSERT_FALSE(app.ctrl.lost || app.ctrl.fallback_active);
    TEST_ASSERT_EQUAL_HEX32(UINT32_MAX, status_value(PMA_STATUS_GUARANTEE_LOST_AT_MS));
}

/* The same task with the default ppc.fallback 2 (WIDEN): the law never clamps its position
 * funnel and its velocity funnel's clamp only for less than safety.barrier_ticks in a row;
 * instead it widens the funnel (flags WIDEN1/2, then WIDE), which is the first lost tick
 * (flagged, counted, its time kept); no BARRIER fault. The muscle jumps between both sides of
 * the reference, so the position funnel, shrinking back, meets the error again within t_u with
 * the input no longer at the limit it held: that second widening hands the loop to MFAC,
 * which starts from the holding input by the static map (ppc.ff_init, 0 by default) and
 * phi(1). */
static void test_widening_instead_of_the_clamp(void)
{
    to_running(0);
    TEST_ASSERT_EQUAL_INT(PMA_PPC_FALLBACK_WIDEN, app.params.ppc_fallback);
    const uint32_t widen_flags = PMA_PPC_FLAG_WIDEN1 | PMA_PPC_FLAG_WIDEN2;
    uint32_t t = 0, widen1 = 0, handover_tick = 0, first_lost_tick = 0, run2 = 0;
    float first_lost_t_s = 0.0f, widen1_t_s = 0.0f;
    const float t_u_s = app.params.ppc_t_u_s;
    while (t < 3000) {
        if (t % 100 == 0) send_host_heartbeat((uint8_t)t);
        /* e = +-1.3 cm >> w1 = 0.2 cm, inside the band, the side changing every 0.4 s */
        pma_fake_adc_set(counts_at((t / 400u) % 2u ? -2.8f : -0.2f));
        const float u_before = pma_app_output_u(&app);
        step();
        ++t;
        assert_state(app.state, PMA_STATE_RUNNING);
        const pma_ctrl_out_t *o = pma_ctrl_out(&app.ctrl);
        TEST_ASSERT_TRUE(pma_app_output_u(&app) >= app.params.ctrl_u_min && pma_app_output_u(&app) <= app.params.ctrl_u_max);
        if (handover_tick != 0) {
            TEST_ASSERT_TRUE(o->flags & PMA_CTRL_FLAG_FALLBACK);
            continue;
        }
        /* the position funnel widened, never clamped; the velocity funnel's clamp in runs
         * shorter than safety.barrier_ticks (its widening ends them) */
        TEST_ASSERT_FALSE(app.ctrl.c.ppc.out.flags & PMA_PPC_FLAG_BARRIER1);
        run2 = (app.ctrl.c.ppc.out.flags & PMA_PPC_FLAG_BARRIER2) ? run2 + 1u : 0u;
        TEST_ASSERT_LESS_THAN(app.params.safety_barrier_ticks, run2);
        if (first_lost_tick == 0) {
            if (!(o->flags & widen_flags)) {
                TEST_ASSERT_FALSE(app.ctrl.lost || (o->flags & PMA_CTRL_FLAG_GUARANTEE_LOST));
                continue;
            }
            first_lost_tick = t;
            first_lost_t_s = o->t_s;
        }
        TEST_ASSERT_TRUE(app.ctrl.lost && (o->flags & PMA_CTRL_FLAG_GUARANTEE_LOST));
        if (app.ctrl.fallback_active) {
            /* a widening of the position funnel within t_u of the last, after the muscle
             * changed sides (the law's flags: the tick's own are MFAC's from now on) */
            TEST_ASSERT_TRUE(app.ctrl.c.ppc.out.flags & PMA_PPC_FLAG_WIDEN1);
            TEST_ASSERT_TRUE(o->flags & PMA_CTRL_FLAG_FALLBACK);
            TEST_ASSERT_GREATER_OR_EQUAL(1u, widen1);
            TEST_ASSERT_GREATER_OR_EQUAL(400u, t);
            TEST_ASSERT_TRUE(o->t_s - widen1_t_s < t_u_s);
            TEST_ASSERT_FLOAT_WITHIN((float)CTRL_LSB, app.params.ppc_ff_init, CTRL_F32(app.ctrl.shadow.u2));
            TEST_ASSERT_TRUE(fabsf(u_before - app.params.ppc_ff_init) > 1.0f);   /* not the law's */
            TEST_ASSERT_TRUE(app.ctrl.shadow.flags & PMA_MFAC_FLAG_RESET);
            handover_tick = t;
            continue;
        }
        TEST_ASSERT_TRUE(o->flags & PMA_PPC_FLAG_WIDE);
        TEST_ASSERT_FALSE(o->flags & PMA_CTRL_FLAG_FALLBACK);
        if (o->flags & PMA_PPC_FLAG_WIDEN1) {
            ++widen1;
            widen1_t_s = o->t_s;
        }
    }
    TEST_ASSERT_GREATER_THAN(0u, first_lost_tick);
    TEST_ASSERT_GREATER_THAN(first_lost_tick, handover_tick);
    TEST_ASSERT_EQUAL_INT(lroundf(first_lost_t_s * 1000.0f), status_value(PMA_STATUS_GUARANTEE_LOST_AT_MS));
    TEST_ASSERT_GREATER_THAN(0u, status_value(PMA_STATUS_GUARANTEE_LOST_TICKS));
    const struct pma_proto_heartbeat_t h = next_heartbeat();
    TEST_ASSERT_TRUE(h.flags & PMA_HB_GUARANTEE_LOST);
    TEST_ASSERT_TRUE(h.flags & PMA_HB_FALLBACK);
    TEST_ASSERT_EQUAL_INT(PMA_FAULT_NONE, h.fault_code);
}

/* A stuck muscle with an input range far too small to reach the reference (ctrl.u_min, u_max
 * +-0.001 input units): the law's input stays at one limit, even with the lower gain of its
 * widened funnel, and the funnel, shrinking back, widens again and again within t_u. That is a
 * reference beyond what the input gives, where MFAC would be held at the limit too: the law
 * stays in charge (no hand-over, no fault), the loss flagged and counted. */
static void test_widening_at_a_held_input_limit_keeps_the_law(void)
{
    to_armed(0);
    set_f32(PMA_PARAM_CTRL_U_MIN, -0.001f);
    set_f32(PMA_PARAM_CTRL_U_MAX, 0.001f);
    set_f32(PMA_PARAM_PPC_FF_INIT, 0.0f);
    command_ok(PMA_CMD_START, 0, PMA_OK);
    pma_fake_adc_set(counts_at(-0.2f)); /* e = 1.3 cm >> w1 = 0.2 cm, inside the band */
    const float t_u_s = app.params.ppc_t_u_s;
    uint32_t widen1 = 0, close_widenings = 0, sat = 0;
    float last_widen_s = -1.0f;
    for (uint32_t t = 0; t < 3000; ++t) {
        if (t % 100 == 0) send_host_heartbeat((uint8_t)t);
        step();
        assert_state(app.state, PMA_STATE_RUNNING);
        const pma_ctrl_out_t *o = pma_ctrl_out(&app.ctrl);
        TEST_ASSERT_FALSE(app.ctrl.fallback_active || (o->flags & PMA_CTRL_FLAG_FALLBACK));
        const uint32_t law = app.ctrl.c.ppc.out.flags;
        if (law & PMA_PPC_FLAG_WIDEN1) {
            /* every widening at the same limit */
            if (widen1 == 0) sat = law & PMA_CTRL_SAT_FLAGS;
            TEST_ASSERT_EQUAL_HEX32(sat, law & PMA_CTRL_SAT_FLAGS);
            if (last_widen_s >= 0.0f && o->t_s - last_widen_s < t_u_s) ++close_widenings;
            last_widen_s = o->t_s;
            ++widen1;
        }
    }
    TEST_ASSERT_NOT_EQUAL(0u, sat);                    /* at a limit */
    TEST_ASSERT_GREATER_OR_EQUAL(2u, close_widenings); /* each a hand-over from anywhere else */
    TEST_ASSERT_TRUE(app.ctrl.lost);
    TEST_ASSERT_GREATER_THAN(0u, status_value(PMA_STATUS_GUARANTEE_LOST_TICKS));
    const struct pma_proto_heartbeat_t h = next_heartbeat();
    TEST_ASSERT_TRUE(h.flags & PMA_HB_GUARANTEE_LOST);
    TEST_ASSERT_FALSE(h.flags & PMA_HB_FALLBACK);
    TEST_ASSERT_EQUAL_INT(PMA_FAULT_NONE, h.fault_code);
}

/* ---------------------------------------------------------------- DAC -- */

/* The DAC refuses the counts (beyond the fake's 12 bits while dac.max_counts
 * allows them): OUTPUT fault, and the safe value is written instead. */
static void test_dac_failure(void)
{
    /* dac.max_counts cannot exceed the 12-bit DAC (the table's range) */
    to_idle(0);
    assert_status(set_param(PMA_PARAM_DAC_MAX_COUNTS, vu(4096)), PMA_ERR_RANGE);
    /* a converter that fails while ARMED: OUTPUT fault in that tick; once it
     * works again the safe value (VENT: 0 counts) is what it gets */
    command_ok(PMA_CMD_ARM, 0, PMA_OK);
    steps(20);
    TEST_ASSERT_GREATER_THAN(0, dac_now());
    pma_fake_dac_fail(true);
    step();
    assert_state(app.state, PMA_STATE_FAULT);
    assert_fault(app.fault, PMA_FAULT_OUTPUT);
    pma_fake_dac_fail(false);
    step();
    TEST_ASSERT_EQUAL_INT(0, dac_now());
    /* a failing DAC while IDLE is reported too (the safe value may not be out) */
    command_ok(PMA_CMD_CLEAR_FAULTS, 0, PMA_OK);
    pma_fake_dac_fail(true);
    step();
    assert_fault(app.fault, PMA_FAULT_OUTPUT);
    pma_fake_dac_fail(false);
}

/* -------------------------------------------------------------- bus-off -- */

static void test_bus_off(void)
{
    /* RUNNING, the bus breaks: the node's own sends push it bus-off */
    to_running(0);
    set_u32(PMA_PARAM_TELEM_DECIMATION, 1); /* 5 frames per tick */
    pma_fake_can_set_recovery(0, true);     /* the bus stays broken */
    pma_fake_can_bus_errors(true);
    uint32_t t = 0;
    pma_can_status_t cs;
    for (;;) {
        assert_status(pma_hal_can_status(&cs), PMA_OK);
        if (cs.state == PMA_CAN_BUS_OFF) break;
        assert_state(app.state, PMA_STATE_RUNNING);
        step();
        ++t;
        TEST_ASSERT_LESS_THAN(20, t);
    }
    /* it went bus-off in the telemetry of the last tick: the fault is raised
     * in that step's housekeeping and the output goes safe in the next tick */
    assert_state(app.state, PMA_STATE_FAULT);
    assert_fault(app.fault, PMA_FAULT_CAN_BUS_OFF);
    step();
    TEST_ASSERT_EQUAL_INT(0, dac_now());
    /* CLEAR_FAULTS refused while bus-off (no frame arrives now: called directly) */
    assert_status(pma_app_command(&app, PMA_CMD_CLEAR_FAULTS, 0), PMA_ERR_BUS_OFF);
    assert_state(app.state, PMA_STATE_FAULT);
    pma_can_frame_t f = frame_of(PMA_PROTO_COMMAND_FRAME_ID, T_NODE, 2,
                                 (const uint8_t[]){PMA_CMD_CLEAR_FAULTS, 0});
    assert_status(pma_fake_can_inject(&f), PMA_ERR_BUS_OFF);
    const uint32_t failed = app.counters.tx_failed;
    pma_app_handle_frame(&app, &f); /* its ACK cannot be sent */
    TEST_ASSERT_EQUAL_INT(failed + 1u, app.counters.tx_failed);
    assert_state(app.state, PMA_STATE_FAULT);
    steps(10);
    assert_state(app.state, PMA_STATE_FAULT);
    /* the bus is repaired: the requested recovery completes */
    pma_fake_can_bus_errors(false);
    pma_fake_can_set_recovery(0, false);
    step();
    assert_status(pma_hal_can_status(&cs), PMA_OK);
    TEST_ASSERT_EQUAL_INT(PMA_CAN_ERROR_ACTIVE, cs.state);
    assert_fault(app.fault, PMA_FAULT_CAN_BUS_OFF);
    expect_latched_then_clear(PMA_FAULT_CAN_BUS_OFF, 0);

    /* bus-off while IDLE faults too; in ARMED the output goes safe in the
     * tick that sees it */
    to_armed(0);
    pma_fake_can_set_recovery(5000, false); /* rejoins 5 ms after the request */
    pma_fake_can_set_error_counters(256, 0);
    expect_fault_this_step(PMA_FAULT_CAN_BUS_OFF);
    assert_status(pma_app_command(&app, PMA_CMD_CLEAR_FAULTS, 0), PMA_ERR_BUS_OFF);
    steps(5);
    assert_status(pma_app_command(&app, PMA_CMD_CLEAR_FAULTS, 0), PMA_OK);
    assert_state(app.state, PMA_STATE_IDLE);
    pma_fake_can_set_error_counters(256, 0);
    step();
    assert_state(app.state, PMA_STATE_FAULT);
    assert_fault(app.fault, PMA_FAULT_CAN_BUS_OFF);
}

/* In bridge mode the fault is visible in the PLANT_ACTUATOR frame of the
 * tick (once the bus is back: nothing is sent while bus-off). */
static void test_bridge_fault_frame(void)
{
    to_running(1);
    send_sample(22, counts_at(-1.5f));
    cap_clear();
    step();
    struct pma_proto_plant_actuator_t m = last_actuator();
    TEST_ASSERT_EQUAL_INT(1, m.output_active);
    TEST_ASSERT_EQUAL_INT(22, m.seq);
    TEST_ASSERT_GREATER_THAN(0, m.dac_counts);
    /* ESTOP frame then a sample in the same step: the actuator frame of this
     * tick already carries the safe output and echoes the new seq */
    pma_can_frame_t f = frame_of(PMA_PROTO_ESTOP_FRAME_ID, T_NODE, 0, NULL);
    assert_status(pma_fake_can_inject(&f), PMA_OK);
    send_sample(23, counts_at(-1.5f));
    cap_clear();
    step();
    m = last_actuator();
    TEST_ASSERT_EQUAL_INT(0, m.output_active);
    TEST_ASSERT_EQUAL_INT(0, m.dac_counts);
    TEST_ASSERT_EQUAL_INT(23, m.seq);
    TEST_ASSERT_EQUAL_INT(PMA_SAMPLE_NEW, m.sample);
    assert_fault(app.fault, PMA_FAULT_ESTOP);
}

/* Bridge: a PLANT_ACTUATOR frame that cannot be queued is counted, not a
 * fault (supervisor.h, PMA_FAULT_OUTPUT); the rig, getting no commands, is
 * the one that times out. */
static void test_bridge_actuator_frame_failure_counted(void)
{
    to_running(1);
    pma_fake_can_block_tx(true); /* nothing leaves; the 4-frame queue fills */
    uint8_t s = 22;
    for (int i = 0; i < 20; ++i) {
        send_sample(s++, counts_at(-1.5f));
        step();
    }
    TEST_ASSERT_GREATER_OR_EQUAL(16u, app.counters.tx_failed);
    assert_state(app.state, PMA_STATE_RUNNING);
    pma_fake_can_block_tx(false); /* the four queued frames go out */
    cap_clear();
    drain();
    TEST_ASSERT_EQUAL_INT(4, sent(PMA_PROTO_PLANT_ACTUATOR_FRAME_ID));
    send_sample(s, counts_at(-1.5f));
    cap_clear();
    step();
    TEST_ASSERT_EQUAL_INT(s, last_actuator().seq);
    TEST_ASSERT_EQUAL_INT(1, last_actuator().output_active);
}

/* ----------------------------------------------------------- watchdog -- */

static void test_watchdog_reset(void)
{
    to_running(0);
    TEST_ASSERT_TRUE(pma_fake_watchdog_running());
    /* the loop hangs: no step (no kick) for longer than the timeout */
    pma_fake_time_advance_us(T_WATCHDOG_MS * 1000u + 1u);
    TEST_ASSERT_TRUE(pma_fake_watchdog_expired());
    pma_fake_reboot();
    assert_status(restart_app(), PMA_OK);
    /* the BOOT heartbeat tells the host why */
    struct pma_proto_heartbeat_t h = last_heartbeat();
    TEST_ASSERT_EQUAL_INT(PMA_STATE_BOOT, h.state);
    TEST_ASSERT_EQUAL_INT(PMA_RESET_WATCHDOG, h.reset_cause);
    assert_state(app.state, PMA_STATE_FAULT);
    assert_fault(app.fault, PMA_FAULT_WATCHDOG_RESET);
    /* the first tick puts out the safe value */
    cap_clear();
    step();
    TEST_ASSERT_EQUAL_INT(0, dac_now());
    TEST_ASSERT_TRUE(pma_fake_watchdog_running()); /* started again */
    command_ok(PMA_CMD_ARM, 0, PMA_ERR_FAULT);
    h = next_heartbeat();
    TEST_ASSERT_EQUAL_INT(PMA_FAULT_WATCHDOG_RESET, h.fault_code);
    TEST_ASSERT_EQUAL_INT(PMA_RESET_WATCHDOG, h.reset_cause);
    expect_latched_then_clear(PMA_FAULT_WATCHDOG_RESET, 0);
    command_ok(PMA_CMD_ARM, 0, PMA_OK);

    /* kicked in time (the loop keeps stepping): no reset */
    steps(1000);
    TEST_ASSERT_FALSE(pma_fake_watchdog_expired());
    /* a software reset is no fault */
    pma_fake_reboot();
    assert_status(restart_app(), PMA_OK);
    TEST_ASSERT_EQUAL_INT(PMA_RESET_SOFTWARE, last_heartbeat().reset_cause);
    assert_state(app.state, PMA_STATE_IDLE);
}

/* ----------------------------------------------------------- safe modes -- */

/* VENT, HOLD and FIXED, each with a sensor fault while RUNNING, with ESTOP,
 * and in IDLE after DISARM. */
static void test_safe_modes(void)
{
    static const struct { uint32_t mode; float kpa; } modes[] = {
        {PMA_SAFETY_SAFE_MODE_VENT, 0.0f},
        {PMA_SAFETY_SAFE_MODE_HOLD, 0.0f},
        {PMA_SAFETY_SAFE_MODE_FIXED, 100.0f},
        {PMA_SAFETY_SAFE_MODE_FIXED, 600.0f},
    };
    for (int bridge = 0; bridge < 2; ++bridge) {
        for (size_t i = 0; i < sizeof modes / sizeof modes[0]; ++i) {
            to_idle((uint8_t)bridge);
            set_u32(PMA_PARAM_SAFETY_SAFE_MODE, modes[i].mode);
            set_f32(PMA_PARAM_SAFETY_SAFE_KPA, modes[i].kpa);
            /* OPEN_LOOP u = 40: 340 kPa, 1547 counts */
            command_ok(PMA_CMD_SELECT_CONTROLLER, PMA_CTRL_MODE_OPEN_LOOP, PMA_OK);
            set_f32(PMA_PARAM_CTRL_OPENLOOP_U, 40.0f);
            /* IDLE puts out the safe state already */
            cap_clear();
            if (bridge) send_sample(1, counts_at(-1.5f));
            step();
            const uint16_t idle = modes[i].mode == PMA_SAFETY_SAFE_MODE_FIXED
                                      ? dac_counts_of(modes[i].kpa) : 0u;
            TEST_ASSERT_EQUAL_INT(idle, output_now());
            command_ok(PMA_CMD_ARM, 0, PMA_OK);
            command_ok(PMA_CMD_START, 0, PMA_OK);
            for (uint8_t s = 2; s < 60; ++s) {
                if (bridge) send_sample(s, counts_at(-1.5f));
                step();
            }
            TEST_ASSERT_EQUAL_INT(dac_counts_of(340.0f), app.output.dac_counts);
            /* the fault */
            if (bridge) {
                send_sample(60, 10);
            } else {
                pma_fake_adc_wire_break();
            }
            expect_fault_this_step(PMA_FAULT_SENSOR_WIRE_BREAK);
            const uint16_t want = modes[i].mode == PMA_SAFETY_SAFE_MODE_VENT ? 0u
                                  : modes[i].mode == PMA_SAFETY_SAFE_MODE_HOLD
                                      ? dac_counts_of(340.0f)
                                      : dac_counts_of(modes[i].kpa);
            TEST_ASSERT_EQUAL_INT(want, app.output.dac_counts);
            /* held there, not slewed */
            for (uint8_t s = 61; s < 70; ++s) {
                if (bridge) send_sample(s, counts_at(-1.5f));
                cap_clear();
                step();
                TEST_ASSERT_EQUAL_INT(want, output_now());
            }
            pma_fake_adc_clear_fault();
            /* ESTOP from ARMED at the preset */
            command_ok(PMA_CMD_CLEAR_FAULTS, 0, PMA_OK);
            uint8_t s = 70;
            if (bridge) send_sample(s++, counts_at(-1.5f));
            command_ok(PMA_CMD_ARM, 0, PMA_OK);
            for (int k = 0; k < 40; ++k) {
                if (bridge) send_sample(s++, counts_at(-1.5f));
                step();
            }
            TEST_ASSERT_EQUAL_INT(T_P0_COUNTS, app.output.dac_counts);
            pma_can_frame_t f = frame_of(PMA_PROTO_ESTOP_ALL_FRAME_ID, 0, 0, NULL);
            assert_status(pma_fake_can_inject(&f), PMA_OK);
            expect_fault_this_step(PMA_FAULT_ESTOP);
            const uint16_t want2 = modes[i].mode == PMA_SAFETY_SAFE_MODE_VENT ? 0u
                                   : modes[i].mode == PMA_SAFETY_SAFE_MODE_HOLD
                                       ? T_P0_COUNTS
                                       : dac_counts_of(modes[i].kpa);
            TEST_ASSERT_EQUAL_INT(want2, app.output.dac_counts);
        }
    }
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_sensor_faults_adc);
    RUN_TEST(test_sensor_faults_bridge);
    RUN_TEST(test_sensor_timeout_bridge);
    RUN_TEST(test_position_limit);
    RUN_TEST(test_tick_overrun);
    RUN_TEST(test_host_heartbeat_lost);
    RUN_TEST(test_non_finite_output);
    RUN_TEST(test_barrier);
    RUN_TEST(test_barrier_hands_over_to_mfac);
    RUN_TEST(test_widening_instead_of_the_clamp);
    RUN_TEST(test_widening_at_a_held_input_limit_keeps_the_law);
    RUN_TEST(test_dac_failure);
    RUN_TEST(test_bus_off);
    RUN_TEST(test_bridge_fault_frame);
    RUN_TEST(test_bridge_actuator_frame_failure_counted);
    RUN_TEST(test_watchdog_reset);
    RUN_TEST(test_safe_modes);
    return UNITY_END();
}
