/* SPDX-License-Identifier: Apache-2.0 */
/* Plant in the loop (in the manner of moteus' simulation_fixture.h): the
 * application, driven through the fake HAL exactly as on the rig, closes the
 * loop around a small model of a pneumatic muscle in this test.
 *
 * Plant: a critically damped second-order lag from the regulator pressure p
 * (kPa, from the DAC counts the node puts out: p = counts / 4.55, the default
 * dac.* scaling) to the position x (cm):
 *     x'' = G (x_eq(p) - x) - D x',   x_eq(p) = X_VENT + K p,
 *     G = 100 1/s^2, D = 20 1/s (omega_n = 10 rad/s), K = 1.7/150 cm/kPa,
 * so the muscle sits at -3.2 cm vented and at -1.5 cm at the preset pressure
 * act.p0_kpa = 150 kPa; holding x = -2.5 cm takes u = -88 kPa. Integrated with
 * RK4 (two sub-steps per 1 ms tick, zero-order hold on p). The position is
 * sampled with the default sensor scaling (0.003 cm per count).
 *
 * Runs: the paper's controller (PPC) on the paper's CASE1 reference
 * (x_r = -0.5 sin t - 2, w1 = 0.2 cm, t_u = 2 s: it passes the band check
 * -3 < x_r -+ w1 < 0) over the plant bridge (PLANT_SENSOR in, PLANT_ACTUATOR
 * out, Seq echoed), then PPC, MFAC and PID holding -2 cm in ADC mode. Each
 * asserts RUNNING without a fault throughout, |e| < w1 after t_u (PPC), and
 * the hold error at the end. The control time is 10 s for CASE1 (6 s for the
 * holds) on every core.
 *
 * The board's main-loop glue (firmware/targets/stm32g474/board_app.c, the
 * part of the STM32G474 firmware that is not register access) runs the last
 * two: board_start() brings the node up with the board's platform
 * (watchdog first, ADC/DAC, storage in one block per slot), every plant tick
 * goes through board_step(), and the status LED it drives is checked against
 * the state at every tick. Once on the ADC (PID hold), once over the plant
 * bridge enabled by the parameter sys.plant_bridge while disarmed (PPC on
 * CASE1, the DAC left alone), as true HIL with a board does. Under the
 * cortex-m4f preset this is the board's own code compiled for its core. */
#include "app_test.h"
#include "board_app.h"

#define G_PLANT 100.0
#define D_PLANT 20.0
#define K_PLANT (1.7 / 150.0)
#define X_VENT (-3.2)
#define T_S 1e-3

typedef struct plant {
    double x, v;
} plant_t;

static plant_t pl;

static double accel(double x, double v, double p)
{
    return G_PLANT * (X_VENT + K_PLANT * p - x) - D_PLANT * v;
}

static void plant_advance(double p_kpa)
{
    const double h = T_S / 2.0;
    for (int i = 0; i < 2; ++i) {
        const double x = pl.x, v = pl.v;
        const double k1x = v, k1v = accel(x, v, p_kpa);
        const double k2x = v + 0.5 * h * k1v, k2v = accel(x + 0.5 * h * k1x, v + 0.5 * h * k1v, p_kpa);
        const double k3x = v + 0.5 * h * k2v, k3v = accel(x + 0.5 * h * k2x, v + 0.5 * h * k2v, p_kpa);
        const double k4x = v + h * k3v, k4v = accel(x + h * k3x, v + h * k3v, p_kpa);
        pl.x = x + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
        pl.v = v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
    }
}

static uint8_t seq;
static uint32_t hb_count;

/* the board glue in the loop (0: pma_app_step() directly) */
static int use_board;
static board_t board;
static uint32_t led_writes;
static int led_level = -1;

/* A failed assertion ends a test before its own `use_board = 0`: the next test must not
 * inherit the board glue. */
void tearDown(void)
{
    use_board = 0;
}

void board_led_write(int on)
{
    led_level = on;
    ++led_writes;
}

/* One main-loop iteration, through the board's glue when it is in use;
 * then the LED must show the state (board_app.h). */
static void loop_step(void)
{
    if (!use_board) {
        step();
        return;
    }
    assert_status(board_step(&board, &app), PMA_OK);
    drain();
    TEST_ASSERT_EQUAL_INT(board_led_on(app.state, pma_hal_time_us() / 1000u), led_level);
    TEST_ASSERT_EQUAL_INT(led_level, board.led);
}

/* A fresh node: the test harness's start, or the board's. */
static void start_node(uint8_t bridge, float x_cm)
{
    if (!use_board) {
        start_with(bridge, x_cm);
        return;
    }
    pma_fake_reset();
    pma_params_defaults(&app.params);
    pma_fake_adc_set(counts_at(x_cm));
    led_writes = 0;
    led_level = -1;
    static const uint8_t board_uid[PMA_DEVICE_UID_BYTES] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
    assert_status(board_start(&board, &app, NULL, board_uid), PMA_OK);
    plat = app.plat; /* the board's platform, for the harness's helpers */
    TEST_ASSERT_EQUAL_MEMORY(board_uid, plat.device_uid, PMA_DEVICE_UID_BYTES);
    TEST_ASSERT_EQUAL_INT(0, plat.plant_bridge); /* never forced on a board */
    TEST_ASSERT_EQUAL_INT(BOARD_STORE_BLOCKS_PER_SLOT, plat.store_blocks_per_slot);
    TEST_ASSERT_EQUAL_INT(BOARD_WATCHDOG_MS, plat.watchdog_ms);
    TEST_ASSERT_TRUE(pma_fake_watchdog_running());
    TEST_ASSERT_EQUAL_INT(PMA_HAL_CAN_DEFAULT_BITRATE_BPS, pma_fake_can_bitrate_bps());
    assert_state(app.state, PMA_STATE_IDLE);
    TEST_ASSERT_EQUAL_INT(1u, led_writes);
    cap_clear();
    drain();
    if (bridge) {
        set_u32(PMA_PARAM_SYS_PLANT_BRIDGE, 1u); /* allowed: disarmed */
        TEST_ASSERT_EQUAL_INT(1, pma_app_bridge_on(&app));
    }
}

/* One tick with the plant: the sample of x goes in (ADC or PLANT_SENSOR),
 * the node steps, its pressure command drives the plant for one period. */
static void tick_with_plant(void)
{
    const uint16_t raw = counts_at((float)pl.x);
    if (hb_count++ % 100u == 0) send_host_heartbeat((uint8_t)hb_count);
    uint16_t counts;
    if (pma_app_bridge_on(&app)) {
        send_sample(++seq, raw);
        cap_clear();
        loop_step();
        const struct pma_proto_plant_actuator_t m = last_actuator();
        TEST_ASSERT_EQUAL_INT(seq, m.seq);
        TEST_ASSERT_EQUAL_INT(PMA_SAMPLE_NEW, m.sample);
        counts = m.dac_counts;
    } else {
        pma_fake_adc_set(raw);
        cap_clear();
        loop_step();
        counts = dac_now();
    }
    plant_advance((double)counts / 4.55);
}

typedef struct result {
    double max_e_after_tu, final_abs_e, min_x, max_x;
    uint32_t barrier_ticks;
} result_t;

/* Starts the node on the plant (vented, at rest), sets the parameters,
 * arms it (1 s to settle at the preset pressure), starts it and runs
 * run_s of control time; xr_of() is the reference as the paper defines it. */
static result_t run(uint8_t bridge, uint32_t mode, uint32_t ref, float offset_cm, uint32_t run_s,
                    float t_u_s, double (*xr_of)(double t, float offset))
{
    pl.x = X_VENT;
    pl.v = 0.0;
    seq = 0;
    hb_count = 0;
    start_node(bridge, (float)pl.x);
    for (int i = 0; i < 5; ++i) tick_with_plant();
    set_f32(PMA_PARAM_ACT_P0_KPA, 150.0f);
    set_f32(PMA_PARAM_CTRL_U_MIN, -150.0f); /* p0 + u_min = act.p_min_kpa (rule 12) */
    command_ok(PMA_CMD_SELECT_CONTROLLER, (uint8_t)mode, PMA_OK);
    command_ok(PMA_CMD_SELECT_REFERENCE, (uint8_t)ref, PMA_OK);
    set_f32(PMA_PARAM_REF_OFFSET_CM, offset_cm);
    set_f32(PMA_PARAM_PPC_T_U_S, t_u_s);
    /* PPC: the steady-pressure feedforward (ppc.ff_gain_per_s) carries the
     * holding effort, so lambda2 stays clear of its barrier */
    set_f32(PMA_PARAM_PPC_FF_GAIN_PER_S, 2.0f);
    /* MFAC: the pseudo-gradient of this plant per 1 ms sample is small; lambda at least 1/1024
     * for the Q16.16 slot (docs/fixed-point.md), rho with it: the same step gain
     * rho phi / (lambda + phi^2) ~ 0.2 */
    set_f32(PMA_PARAM_MFAC_PHI1, 0.002f);
    set_f32(PMA_PARAM_MFAC_RHO, 0.1f);
    set_f32(PMA_PARAM_MFAC_LAMBDA, 1e-3f);
    /* PID: tuned for omega_n = 10 rad/s and K = 0.011 cm/kPa */
    set_f32(PMA_PARAM_PID_KP, 200.0f);
    set_f32(PMA_PARAM_PID_KI, 600.0f);
    set_f32(PMA_PARAM_PID_KD, 10.0f);
    tick_with_plant();
    command_ok(PMA_CMD_ARM, 0, PMA_OK);
    for (int i = 0; i < 1000; ++i) tick_with_plant();
    assert_state(app.state, PMA_STATE_ARMED);
    assert_near(pl.x, -1.5, 0.05); /* at the preset pressure */
    command_ok(PMA_CMD_START, 0, PMA_OK);
    plant_advance((double)app.output.dac_counts / 4.55); /* the START step's tick */

    result_t r = {0.0, 0.0, pl.x, pl.x, 0};
    const uint32_t n = run_s * 1000u;
    for (uint32_t k = 0; k < n; ++k) {
        const double x_sampled = pl.x;
        tick_with_plant();
        if (app.state != PMA_STATE_RUNNING) {
            pma_test_fail("left RUNNING at t = %.3f s: %s, fault %s", (double)pma_ctrl_out(&app.ctrl)->t_s,
                          pma_app_state_name(app.state), pma_fault_name(app.fault));
        }
        const double t = (double)pma_ctrl_out(&app.ctrl)->t_s;
        const double xr = xr_of(t, offset_cm);
        assert_near(pma_ctrl_out(&app.ctrl)->xr_cm, xr, 1e-4); /* the node's reference is the paper's */
        const double e = x_sampled - xr;
        if (t >= t_u_s && fabs(e) > r.max_e_after_tu) r.max_e_after_tu = fabs(e);
        if (pma_ctrl_out(&app.ctrl)->barrier) ++r.barrier_ticks;
        r.final_abs_e = fabs(e);
        if (pl.x < r.min_x) r.min_x = pl.x;
        if (pl.x > r.max_x) r.max_x = pl.x;
    }
    assert_fault(app.fault, PMA_FAULT_NONE);
    printf("%s %s mode %lu: max|e| after t_u %.4f cm, final |e| %.4f cm, x in [%.3f, %.3f] "
           "cm, barrier ticks %lu\n", bridge ? "bridge" : "adc",
           ref == PMA_REF_KIND_CASE1 ? "CASE1" : "HOLD", (unsigned long)mode,
           r.max_e_after_tu, r.final_abs_e, r.min_x, r.max_x,
           (unsigned long)r.barrier_ticks);
    return r;
}

static double xr_case1(double t, float offset)
{
    (void)offset;
    return -0.5 * sin(t) - 2.0;
}

static double xr_hold(double t, float offset)
{
    (void)t;
    return (double)offset;
}

static void test_ppc_case1_bridge(void)
{
    const result_t r = run(1, PMA_CTRL_MODE_PPC, PMA_REF_KIND_CASE1, -1.5f, 10, 2.0f, xr_case1);
    TEST_ASSERT_TRUE(r.max_e_after_tu < 0.2);
    TEST_ASSERT_TRUE(r.min_x > -3.0 && r.max_x < 0.0); /* the output constraint held */
}

static void test_ppc_hold_adc(void)
{
    const result_t r = run(0, PMA_CTRL_MODE_PPC, PMA_REF_KIND_HOLD, -2.0f, 6, 2.0f, xr_hold);
    TEST_ASSERT_TRUE(r.max_e_after_tu < 0.2);
    TEST_ASSERT_TRUE(r.final_abs_e < 0.05);
    TEST_ASSERT_TRUE(r.min_x > -3.0 && r.max_x < 0.0);
}

static void test_mfac_hold_adc(void)
{
    const result_t r = run(0, PMA_CTRL_MODE_MFAC, PMA_REF_KIND_HOLD, -2.0f, 6, 2.0f, xr_hold);
    TEST_ASSERT_TRUE(r.final_abs_e < 0.05);
    TEST_ASSERT_TRUE(r.min_x > -3.5 && r.max_x < 0.5);
}

static void test_pid_hold_adc(void)
{
    const result_t r = run(0, PMA_CTRL_MODE_PID, PMA_REF_KIND_HOLD, -2.0f, 6, 2.0f, xr_hold);
    TEST_ASSERT_TRUE(r.final_abs_e < 0.05);
    TEST_ASSERT_TRUE(r.min_x > -3.0 && r.max_x < 0.0);
}

/* The board glue, ADC and DAC: PID holding -2 cm; the LED blinks in IDLE
 * and ARMED and is steady on while RUNNING. */
static void test_board_glue_pid_hold_adc(void)
{
    use_board = 1;
    const result_t r = run(0, PMA_CTRL_MODE_PID, PMA_REF_KIND_HOLD, -2.0f, 6, 2.0f, xr_hold);
    use_board = 0;
    TEST_ASSERT_TRUE(r.final_abs_e < 0.05);
    TEST_ASSERT_TRUE(r.min_x > -3.0 && r.max_x < 0.0);
    TEST_ASSERT_GREATER_THAN(6000u, pma_fake_dac_write_count()); /* the DAC, every tick */
    TEST_ASSERT_EQUAL_INT(1, led_level);                         /* RUNNING */
    /* IDLE and ARMED before it blinked: the level changed several times */
    TEST_ASSERT_GREATER_OR_EQUAL(4u, board.led_changes);
}

/* The board glue over the plant bridge, switched on by sys.plant_bridge while
 * disarmed (true HIL): PPC on CASE1; the bridge cannot be switched off while
 * running and the DAC is not written while bridged. */
static void test_board_glue_ppc_case1_bridge_parameter(void)
{
    use_board = 1;
    const result_t r = run(1, PMA_CTRL_MODE_PPC, PMA_REF_KIND_CASE1, -1.5f, 4, 2.0f, xr_case1);
    TEST_ASSERT_TRUE(r.max_e_after_tu < 0.2);
    TEST_ASSERT_TRUE(r.min_x > -3.0 && r.max_x < 0.0);
    const uint32_t dac_writes = pma_fake_dac_write_count();
    assert_status(set_param(PMA_PARAM_SYS_PLANT_BRIDGE, vu(0)), PMA_ERR_STATE);
    for (int i = 0; i < 100; ++i) tick_with_plant(); /* still bridged, still tracking */
    assert_state(app.state, PMA_STATE_RUNNING);
    TEST_ASSERT_EQUAL_INT(dac_writes, pma_fake_dac_write_count());
    use_board = 0;
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_ppc_case1_bridge);
    RUN_TEST(test_ppc_hold_adc);
    RUN_TEST(test_mfac_hold_adc);
    RUN_TEST(test_pid_hold_adc);
    RUN_TEST(test_board_glue_pid_hold_adc);
    RUN_TEST(test_board_glue_ppc_case1_bridge_parameter);
    return UNITY_END();
}
