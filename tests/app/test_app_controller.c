/* The controller slot (firmware/app/controller.c) on its own: what the PPC
 * options ppc.ref_vel and ppc.obs_pos feed the paper's law, and that both off
 * feed it the raw sample and the velocity estimate (the paper's law).
 *
 * The position is driven exactly along a SINE reference (x = x_r, no noise):
 * the paper's lambda2 = alpha x' - theta then rests at the reference's own
 * speed (theta = 0 at e = 0), ppc.ref_vel's lambda2 = alpha (x' - x_r') at
 * the observer's residual only. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>

#include "controller.h"
#include "params.h"
#include "pma/status.h"

#define PERIOD_S 1e-3f
#define OFFSET_CM (-1.5f)
#define AMPL_CM 0.5f
#define FREQ_HZ 0.5f
#define TWO_PI_F 6.28318530718f

static pma_params_t par;
static pma_ctrl_t ctl_off, ctl_on;

static void sine_params(pma_params_t *p, uint32_t ref_vel, uint32_t obs_pos, uint32_t vel_kind)
{
    pma_params_defaults(p);
    p->ctrl_mode = PMA_CTRL_MODE_PPC;
    p->ref_kind = PMA_REF_SINE;
    p->ref_offset_cm = OFFSET_CM;
    p->ref_amplitude_cm = AMPL_CM;
    p->ref_freq_hz = FREQ_HZ;
    p->ref_phase_rad = 0.0f;
    p->vel_kind = vel_kind;
    p->vel_fc_hz = 10.0f;
    p->ppc_ref_vel = ref_vel;
    p->ppc_obs_pos = obs_pos;
}

static float sine_cm(float t_s)
{
    return OFFSET_CM + AMPL_CM * sinf(TWO_PI_F * FREQ_HZ * t_s);
}

static void test_options_are_off_by_default(void **state)
{
    (void)state;
    pma_params_defaults(&par);
    assert_int_equal(par.ppc_ref_vel, 0);
    assert_int_equal(par.ppc_obs_pos, 0);
}

static void test_obs_pos_needs_the_tracking_observer(void **state)
{
    (void)state;
    sine_params(&par, 0, 1, 0);  /* filtered difference: no position estimate */
    assert_int_equal(pma_ctrl_start(&ctl_on, &par, PERIOD_S), PMA_ERR_RANGE);
    sine_params(&par, 0, 1, 1);
    assert_int_equal(pma_ctrl_start(&ctl_on, &par, PERIOD_S), PMA_OK);
    /* the option belongs to PPC: MFAC starts with the filtered difference */
    sine_params(&par, 0, 1, 0);
    par.ctrl_mode = PMA_CTRL_MODE_MFAC;
    assert_int_equal(pma_ctrl_start(&ctl_on, &par, PERIOD_S), PMA_OK);
}

static void test_ref_vel_damps_the_velocity_error(void **state)
{
    (void)state;
    sine_params(&par, 0, 0, 1);
    assert_int_equal(pma_ctrl_start(&ctl_off, &par, PERIOD_S), PMA_OK);
    sine_params(&par, 1, 0, 1);
    assert_int_equal(pma_ctrl_start(&ctl_on, &par, PERIOD_S), PMA_OK);

    const float peak_speed = TWO_PI_F * FREQ_HZ * AMPL_CM;  /* 1.57 cm/s */
    float max_on = 0.0f, max_off = 0.0f, max_err_off = 0.0f;
    float u;
    for (int k = 0; k < 4000; ++k) {
        const float t = (float)k * PERIOD_S;
        const float x = sine_cm(t);
        assert_int_equal(pma_ctrl_step(&ctl_off, t, x, 0.0f, &u), PMA_OK);
        assert_int_equal(pma_ctrl_step(&ctl_on, t, x, 0.0f, &u), PMA_OK);
        if (t < 2.5f) continue;  /* after t_u (2 s) and the observer's settling */
        const pma_ppc_out_f32_t *off = &ctl_off.c.ppc.out, *on = &ctl_on.c.ppc.out;
        /* both: the raw sample, e = x - x_r ~ 0, so theta ~ 0 */
        assert_float_equal(off->e_cm, x - ctl_off.out.xr_cm, 0.0f);
        assert_float_equal(on->e_cm, x - ctl_on.out.xr_cm, 0.0f);
        /* off: lambda2 = x' (the paper's law), the reference's speed */
        assert_float_equal(off->lambda2_cm_s, off->alpha * ctl_off.out.v_cm_s - off->theta_cm_s, 1e-6f);
        const float err_off = fabsf(off->lambda2_cm_s - ctl_off.out.xr_dot_cm_s);
        if (err_off > max_err_off) max_err_off = err_off;
        if (fabsf(off->lambda2_cm_s) > max_off) max_off = fabsf(off->lambda2_cm_s);
        /* on: lambda2 = x' - x_r' */
        assert_float_equal(on->lambda2_cm_s,
                           on->alpha * (ctl_on.out.v_cm_s - ctl_on.out.xr_dot_cm_s) - on->theta_cm_s,
                           1e-6f);
        if (fabsf(on->lambda2_cm_s) > max_on) max_on = fabsf(on->lambda2_cm_s);
    }
    print_message("lambda2 at x = x_r, max |.| [cm/s]: paper's %.4f (x_r' peak %.4f), ref_vel %.4f\n",
                  (double)max_off, (double)peak_speed, (double)max_on);
    /* what is left is the observer's lag under acceleration: about
     * x_r'' / (pi fc) (pma/velest.h), 0.157 cm/s at this sine's 4.93 cm/s^2 */
    const float peak_accel = TWO_PI_F * FREQ_HZ * peak_speed;
    const float lag_cm_s = 1.2f * peak_accel / (0.5f * TWO_PI_F * par.vel_fc_hz);
    assert_true(max_err_off < lag_cm_s);   /* off: lambda2 follows x_r' */
    assert_true(max_off > 0.9f * peak_speed);
    assert_true(max_on < lag_cm_s);        /* on: lambda2 ~ 0 */
    assert_true(max_on < 0.15f * max_off);
}

static void test_obs_pos_takes_the_error_from_the_observer(void **state)
{
    (void)state;
    sine_params(&par, 0, 0, 1);
    par.ref_kind = PMA_REF_HOLD;
    assert_int_equal(pma_ctrl_start(&ctl_off, &par, PERIOD_S), PMA_OK);
    sine_params(&par, 0, 1, 1);
    par.ref_kind = PMA_REF_HOLD;
    assert_int_equal(pma_ctrl_start(&ctl_on, &par, PERIOD_S), PMA_OK);

    float u;
    for (int k = 0; k < 3000; ++k) {  /* at the reference, past t_u */
        const float t = (float)k * PERIOD_S;
        assert_int_equal(pma_ctrl_step(&ctl_off, t, OFFSET_CM, 0.0f, &u), PMA_OK);
        assert_int_equal(pma_ctrl_step(&ctl_on, t, OFFSET_CM, 0.0f, &u), PMA_OK);
    }
    /* one sample 0.1 cm off (a noise spike): the paper's law sees all of it,
     * obs_pos only the observer's update ga r (ga = 1 - p^2 ~ 0.12 at 10 Hz) */
    const float t = 3000.0f * PERIOD_S, x = OFFSET_CM + 0.1f;
    assert_int_equal(pma_ctrl_step(&ctl_off, t, x, 0.0f, &u), PMA_OK);
    assert_int_equal(pma_ctrl_step(&ctl_on, t, x, 0.0f, &u), PMA_OK);
    assert_float_equal(ctl_off.c.ppc.out.e_cm, 0.1f, 1e-6f);
    assert_float_equal(ctl_on.c.ppc.out.e_cm, ctl_on.vel.xh - OFFSET_CM, 1e-6f);
    assert_true(ctl_on.c.ppc.out.e_cm > 0.05f * 0.1f && ctl_on.c.ppc.out.e_cm < 0.25f * 0.1f);
    /* telemetry's e stays the raw sample's */
    assert_float_equal(ctl_on.out.e_cm, 0.1f, 1e-6f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_options_are_off_by_default),
        cmocka_unit_test(test_obs_pos_needs_the_tracking_observer),
        cmocka_unit_test(test_ref_vel_damps_the_velocity_error),
        cmocka_unit_test(test_obs_pos_takes_the_error_from_the_observer),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
