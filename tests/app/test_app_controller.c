/* SPDX-License-Identifier: Apache-2.0 */
/* The controller slot (firmware/app/controller.c) on its own: what the PPC
 * options ppc.ref_vel and ppc.obs_pos feed the paper's law, and that both off
 * feed it the raw sample and the velocity estimate (the paper's law).
 *
 * The position is driven exactly along a SINE reference (x = x_r, no noise):
 * the paper's lambda2 = alpha x' - theta then rests at the reference's own
 * speed (theta = 0 at e = 0), ppc.ref_vel's lambda2 = alpha (x' - x_r') at
 * the observer's residual only. The reference feedforward and its hysteresis term add to
 * the law's output exactly what their formulas say. */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "controller.h"
#include "params.h"
#include "pma/status.h"
#include "pma_test.h"

#define PERIOD_S 1e-3f
#define OFFSET_CM (-1.5f)
#define AMPL_CM 0.5f
#define FREQ_HZ 0.5f
#define TWO_PI_F 6.28318530718f

static pma_params_t par;
static pma_ctrl_t ctl_off, ctl_on;

/* The law's signals of the last step in float, whichever arithmetic the slot was built in;
 * the tolerances between the slot's own signals: 0 and 1e-6 in float, in Q16.16 two LSB
 * (2^-16 = 1.5e-5) where the slot passes a value through, and 2e-4 where the law computes
 * it from rounded products. */
typedef struct law_view {
    float e_cm, alpha, theta_cm_s, lambda2_cm_s;
} law_view_t;

#if PMA_CTRL_Q16
#define TOL_PASS 3.1e-5f
#define TOL_LAW 2e-4f
static law_view_t law(const pma_ctrl_t *c)
{
    const pma_ppc_out_q16_t *o = &c->c.ppc.out;
    return (law_view_t){pma_q16_to_f32(o->e_cm), pma_q30_to_f32(o->alpha),
                        pma_q16_to_f32(o->theta_cm_s), pma_q16_to_f32(o->lambda2_cm_s)};
}
static float observer_x_cm(const pma_ctrl_t *c)
{
    return (float)((double)c->vel.xh_q32 / 4294967296.0);
}
static float law_u(const pma_ctrl_t *c)
{
    return pma_q16_to_f32(c->c.ppc.out.u_law);
}
#else
#define TOL_PASS 0.0f
#define TOL_LAW 1e-6f
static law_view_t law(const pma_ctrl_t *c)
{
    const pma_ppc_out_f32_t *o = &c->c.ppc.out;
    return (law_view_t){o->e_cm, o->alpha, o->theta_cm_s, o->lambda2_cm_s};
}
static float observer_x_cm(const pma_ctrl_t *c)
{
    return c->vel.xh;
}
static float law_u(const pma_ctrl_t *c)
{
    return c->c.ppc.out.u_law;
}
#endif

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
    p->ppc_fallback = 0; /* the law's inputs are under test: no hand-over on the open-loop sine */
}

static float sine_cm(float t_s)
{
    return OFFSET_CM + AMPL_CM * sinf(TWO_PI_F * FREQ_HZ * t_s);
}

static void test_options_are_off_by_default(void)
{
    pma_params_defaults(&par);
    TEST_ASSERT_EQUAL_INT(0, par.ppc_ref_vel);
    TEST_ASSERT_EQUAL_INT(0, par.ppc_obs_pos);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, par.ppc_ref_ff);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, par.ppc_u_lpf_hz);
}

static void test_obs_pos_needs_the_tracking_observer(void)
{
    sine_params(&par, 0, 1, 0);  /* filtered difference: no position estimate */
    TEST_ASSERT_EQUAL_INT(PMA_ERR_RANGE, pma_ctrl_start(&ctl_on, &par, PERIOD_S));
    sine_params(&par, 0, 1, 1);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_start(&ctl_on, &par, PERIOD_S));
    /* the option belongs to PPC: MFAC starts with the filtered difference */
    sine_params(&par, 0, 1, 0);
    par.ctrl_mode = PMA_CTRL_MODE_MFAC;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_start(&ctl_on, &par, PERIOD_S));
}

static void test_ref_vel_damps_the_velocity_error(void)
{
    sine_params(&par, 0, 0, 1);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_start(&ctl_off, &par, PERIOD_S));
    sine_params(&par, 1, 0, 1);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_start(&ctl_on, &par, PERIOD_S));

    const float peak_speed = TWO_PI_F * FREQ_HZ * AMPL_CM;  /* 1.57 cm/s */
    float max_on = 0.0f, max_off = 0.0f, max_err_off = 0.0f;
    float u;
    for (int k = 0; k < 4000; ++k) {
        const float t = (float)k * PERIOD_S;
        const float x = sine_cm(t);
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_step(&ctl_off, t, x, 0.0f, &u));
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_step(&ctl_on, t, x, 0.0f, &u));
        if (t < 2.5f) continue;  /* after t_u (2 s) and the observer's settling */
        const law_view_t off = law(&ctl_off), on = law(&ctl_on);
        const pma_ctrl_out_t *o_off = pma_ctrl_out(&ctl_off), *o_on = pma_ctrl_out(&ctl_on);
        /* both: the raw sample, e = x - x_r ~ 0, so theta ~ 0 */
        TEST_ASSERT_FLOAT_WITHIN(TOL_PASS, x - o_off->xr_cm, off.e_cm);
        TEST_ASSERT_FLOAT_WITHIN(TOL_PASS, x - o_on->xr_cm, on.e_cm);
        /* off: lambda2 = x' (the paper's law), the reference's speed */
        TEST_ASSERT_FLOAT_WITHIN(TOL_LAW, off.alpha * o_off->v_cm_s - off.theta_cm_s, off.lambda2_cm_s);
        const float err_off = fabsf(off.lambda2_cm_s - o_off->xr_dot_cm_s);
        if (err_off > max_err_off) max_err_off = err_off;
        if (fabsf(off.lambda2_cm_s) > max_off) max_off = fabsf(off.lambda2_cm_s);
        /* on: lambda2 = x' - x_r' */
        TEST_ASSERT_FLOAT_WITHIN(TOL_LAW, on.alpha * (o_on->v_cm_s - o_on->xr_dot_cm_s) - on.theta_cm_s,
                                 on.lambda2_cm_s);
        if (fabsf(on.lambda2_cm_s) > max_on) max_on = fabsf(on.lambda2_cm_s);
    }
    printf("lambda2 at x = x_r, max |.| [cm/s]: paper's %.4f (x_r' peak %.4f), ref_vel %.4f\n",
           (double)max_off, (double)peak_speed, (double)max_on);
    /* what is left is the observer's lag under acceleration: about
     * x_r'' / (pi fc) (pma/velest.h), 0.157 cm/s at this sine's 4.93 cm/s^2 */
    const float peak_accel = TWO_PI_F * FREQ_HZ * peak_speed;
    const float lag_cm_s = 1.2f * peak_accel / (0.5f * TWO_PI_F * par.vel_fc_hz);
    TEST_ASSERT_TRUE(max_err_off < lag_cm_s);   /* off: lambda2 follows x_r' */
    TEST_ASSERT_TRUE(max_off > 0.9f * peak_speed);
    TEST_ASSERT_TRUE(max_on < lag_cm_s);        /* on: lambda2 ~ 0 */
    TEST_ASSERT_TRUE(max_on < 0.15f * max_off);
}

static void test_obs_pos_takes_the_error_from_the_observer(void)
{
    sine_params(&par, 0, 0, 1);
    par.ref_kind = PMA_REF_HOLD;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_start(&ctl_off, &par, PERIOD_S));
    sine_params(&par, 0, 1, 1);
    par.ref_kind = PMA_REF_HOLD;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_start(&ctl_on, &par, PERIOD_S));

    float u;
    for (int k = 0; k < 3000; ++k) {  /* at the reference, past t_u */
        const float t = (float)k * PERIOD_S;
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_step(&ctl_off, t, OFFSET_CM, 0.0f, &u));
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_step(&ctl_on, t, OFFSET_CM, 0.0f, &u));
    }
    /* one sample 0.1 cm off (a noise spike): the paper's law sees all of it,
     * obs_pos only the observer's update ga r (ga = 1 - p^2 ~ 0.12 at 10 Hz) */
    const float t = 3000.0f * PERIOD_S, x = OFFSET_CM + 0.1f;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_step(&ctl_off, t, x, 0.0f, &u));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_step(&ctl_on, t, x, 0.0f, &u));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f + TOL_PASS, 0.1f, law(&ctl_off).e_cm);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f + TOL_PASS, observer_x_cm(&ctl_on) - OFFSET_CM, law(&ctl_on).e_cm);
    TEST_ASSERT_TRUE(law(&ctl_on).e_cm > 0.05f * 0.1f && law(&ctl_on).e_cm < 0.25f * 0.1f);
    /* telemetry's e stays the raw sample's */
    TEST_ASSERT_FLOAT_WITHIN(1e-6f + TOL_PASS, 0.1f, pma_ctrl_out(&ctl_on)->e_cm);
}

/* Both slots one step on the sine's sample at t: u_on - u_off */
static float step_both(float t_s)
{
    float u_off, u_on;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_step(&ctl_off, t_s, sine_cm(t_s), 0.0f, &u_off));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_step(&ctl_on, t_s, sine_cm(t_s), 0.0f, &u_on));
    return u_on - u_off;
}

/* ppc.ref_ff with its lead: two slots on the same samples, one with the reference feedforward,
 * differ in u by exactly ref_ff ((x_r - x_r(0)) + lead x_r') while neither output saturates. */
static void test_ref_ff_adds_the_maps_input_for_the_reference_ahead(void)
{
    sine_params(&par, 1, 0, 1);
    par.ctrl_u_min = -5000.0f;
    par.ctrl_u_max = 5000.0f;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_start(&ctl_off, &par, PERIOD_S));
    par.ppc_ref_ff = 300.0f;
    par.ppc_ref_ff_lead_s = 0.08f;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_start(&ctl_on, &par, PERIOD_S));
    float max_dev = 0.0f;
    for (int k = 0; k < 2000; ++k) {
        const float du = step_both((float)k * PERIOD_S);
        const pma_ctrl_out_t *o = pma_ctrl_out(&ctl_on);
        const float expect = 300.0f * ((o->xr_cm - sine_cm(0.0f)) + 0.08f * o->xr_dot_cm_s);
        const float dev = fabsf(du - expect);
        if (dev > max_dev) max_dev = dev;
    }
    TEST_ASSERT_TRUE(max_dev < 1e-2f);
    /* a negative lead is refused at START */
    par.ppc_ref_ff_lead_s = -0.1f;
    TEST_ASSERT_EQUAL_INT(PMA_ERR_RANGE, pma_ctrl_start(&ctl_on, &par, PERIOD_S));
}

/* ppc.ref_ff_hyst with ppc.ref_ff_hyst_cm: the hysteresis term is H (x_a - z) / b, z a play
 * (backlash) operator of half-width b on x_a = x_r + lead x_r' from z(0) = x_a(0), computed here
 * on the slot's own reference: +H while the sine rises (past b), -H while it falls, and across
 * in between. Refused at START: a negative H, a half-width of 0 and, in Q16.16, a height
 * beyond the format's range. */
static void test_ref_ff_hyst_adds_a_play_operator_on_the_reference(void)
{
    const float h = 20.0f, b = 0.1f, lead = 0.08f;
    sine_params(&par, 1, 0, 1);
    par.ctrl_u_min = -5000.0f;
    par.ctrl_u_max = 5000.0f;
    par.ppc_ref_ff_lead_s = lead;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_start(&ctl_off, &par, PERIOD_S));
    par.ppc_ref_ff_hyst = h;
    par.ppc_ref_ff_hyst_cm = b;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_start(&ctl_on, &par, PERIOD_S));
    double z = 0.0;
    float max_dev = 0.0f, lo = 0.0f, hi = 0.0f;
    for (int k = 0; k < 4000; ++k) {
        const float du = step_both((float)k * PERIOD_S);
        const pma_ctrl_out_t *o = pma_ctrl_out(&ctl_on);
        const double xa = (double)o->xr_cm + (double)lead * (double)o->xr_dot_cm_s;
        z = (k == 0) ? xa : fmin(fmax(z, xa - b), xa + b);
        const float dev = fabsf(du - (float)(h * (xa - z) / b));
        if (dev > max_dev) max_dev = dev;
        if (du < lo) lo = du;
        if (du > hi) hi = du;
    }
    TEST_ASSERT_TRUE(max_dev < 1e-2f);
    TEST_ASSERT_FLOAT_WITHIN(1e-2f, -h, lo);   /* both branches reached over two periods */
    TEST_ASSERT_FLOAT_WITHIN(1e-2f, h, hi);
    par.ppc_ref_ff_hyst = -1.0f;
    TEST_ASSERT_EQUAL_INT(PMA_ERR_RANGE, pma_ctrl_start(&ctl_on, &par, PERIOD_S));
    par.ppc_ref_ff_hyst = h;
    par.ppc_ref_ff_hyst_cm = 0.0f;
    TEST_ASSERT_EQUAL_INT(PMA_ERR_RANGE, pma_ctrl_start(&ctl_on, &par, PERIOD_S));
    par.ppc_ref_ff_hyst = 40000.0f;   /* beyond Q16.16 */
    par.ppc_ref_ff_hyst_cm = 0.01f;
#if PMA_CTRL_Q16
    TEST_ASSERT_EQUAL_INT(PMA_ERR_FIXED_RANGE, pma_ctrl_start(&ctl_on, &par, PERIOD_S));
#else
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_start(&ctl_on, &par, PERIOD_S));
#endif
}

/* ppc.ref_ff_hyst_gain_per_s on a muscle with hysteresis: a slot closes the loop around a
 * first-order lag (TAU_S) whose input passes a backlash of half-width BACKLASH_U, the static
 * map x = X_VENT_CM + u / MAP_U_PER_CM between the branches. Started with no hysteresis term
 * (H = 0), the adapted height learns the backlash (H tends to it: the step of 2 H at a reversal
 * is the one the muscle needs) and the tracking error drops below the fixed slot's; its bound
 * holds. */
#define TAU_S 0.03f
#define BACKLASH_U 30.0f
#define MAP_U_PER_CM 100.0f
#define X_VENT_CM (-3.0f)

typedef struct lagged_backlash {
    float y_u, x_cm;   /* the backlash's output, the position */
} lagged_backlash_t;

static float lagged_backlash_step(lagged_backlash_t *m, float u)
{
    if (m->y_u < u - BACKLASH_U) m->y_u = u - BACKLASH_U;
    if (m->y_u > u + BACKLASH_U) m->y_u = u + BACKLASH_U;
    const float x_eq = X_VENT_CM + m->y_u / MAP_U_PER_CM;
    m->x_cm += (x_eq - m->x_cm) * (PERIOD_S / TAU_S);
    return m->x_cm;
}

static float adapted_height(const pma_ctrl_t *c)
{
#if PMA_CTRL_Q16
    return pma_q16_to_f32(c->q_hyst_u);
#else
    return c->hyst_u;
#endif
}

/* the RMS error [cm] of the last 4 s of a 20 s sine, the height adapted at the end in *h_u */
static float track_backlash(pma_ctrl_t *c, float gain_per_s, float h_max_u, float *h_u)
{
    sine_params(&par, 1, 1, 1);
    par.vel_fc_hz = 20.0f;
    par.ctrl_u_min = -500.0f;
    par.ctrl_u_max = 800.0f;
    par.ppc_a_cm_s = 3.0f;
    par.ppc_w1_cm = 0.2f;
    par.ppc_w2_cm_s = 15.0f;
    par.ppc_c = 13.0f;
    par.ppc_t_u_s = 1.0f;
    par.ppc_ff_gain_per_s = 700.0f;
    par.ppc_ff_init = (OFFSET_CM - X_VENT_CM) * MAP_U_PER_CM;
    par.ppc_ref_ff = MAP_U_PER_CM;
    par.ppc_ref_ff_lead_s = TAU_S;
    par.ppc_ref_ff_hyst = 0.0f;
    par.ppc_ref_ff_hyst_cm = 0.01f;
    par.ppc_ref_ff_hyst_gain_per_s = gain_per_s;
    par.ppc_ref_ff_hyst_max = h_max_u;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_start(c, &par, PERIOD_S));
    lagged_backlash_t m = {par.ppc_ff_init, OFFSET_CM};
    double sq = 0.0;
    int n = 0;
    float x = m.x_cm, u = 0.0f;
    for (int k = 0; k < 20000; ++k) {
        const float t = (float)k * PERIOD_S;
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_step(c, t, x, 0.0f, &u));
        if (t >= 16.0f) {
            const float e = x - sine_cm(t);
            sq += (double)e * e;
            ++n;
        }
        x = lagged_backlash_step(&m, u);
    }
    TEST_ASSERT_FALSE(c->lost);
    *h_u = adapted_height(c);
    return (float)sqrt(sq / n);
}

static void test_ref_ff_hyst_adapts_to_the_muscles_hysteresis(void)
{
    float h_fixed = -1.0f, h_adapted = -1.0f, h_bounded = -1.0f;
    const float e_fixed = track_backlash(&ctl_off, 0.0f, 0.0f, &h_fixed);
    const float e_adapted = track_backlash(&ctl_on, 70.0f, 4.0f * BACKLASH_U, &h_adapted);
    printf("backlash %.1f: RMS error %.5f cm fixed (H %.2f), %.5f cm adapted (H %.2f)\n",
           (double)BACKLASH_U, (double)e_fixed, (double)h_fixed, (double)e_adapted, (double)h_adapted);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, h_fixed);
    TEST_ASSERT_FLOAT_WITHIN(0.3f * BACKLASH_U, BACKLASH_U, h_adapted);
    TEST_ASSERT_TRUE(e_adapted < 0.7f * e_fixed);
    (void)track_backlash(&ctl_on, 70.0f, 0.5f * BACKLASH_U, &h_bounded);
    TEST_ASSERT_FLOAT_WITHIN(1e-3f, 0.5f * BACKLASH_U, h_bounded);
    /* refused at START: a start above the bound, a per-step gain of 1 or more, no integrator */
    par.ppc_ref_ff_hyst = 0.6f * BACKLASH_U;
    TEST_ASSERT_EQUAL_INT(PMA_ERR_RANGE, pma_ctrl_start(&ctl_on, &par, PERIOD_S));
    par.ppc_ref_ff_hyst = 0.0f;
    par.ppc_ref_ff_hyst_gain_per_s = 1.0f / PERIOD_S;
    TEST_ASSERT_EQUAL_INT(PMA_ERR_RANGE, pma_ctrl_start(&ctl_on, &par, PERIOD_S));
    par.ppc_ref_ff_hyst_gain_per_s = 70.0f;
    par.ppc_ff_gain_per_s = 0.0f;
    TEST_ASSERT_EQUAL_INT(PMA_ERR_RANGE, pma_ctrl_start(&ctl_on, &par, PERIOD_S));
}

/* ppc.u_lpf_hz: two slots on the same noisy samples, one with the command's low-pass. The law
 * does not see the filter (its feedforward integrator integrates the unfiltered law), so the
 * filtered slot's output is exactly the low-pass of the other's, primed by its first step
 * (pma/lpf.h), and moves the valve far less. A negative cut-off is refused at START. */
static void test_u_lpf_filters_the_laws_command(void)
{
    const float fu = 10.0f;
    sine_params(&par, 1, 1, 1);
    par.vel_fc_hz = 30.0f;
    par.ctrl_u_min = -5000.0f;
    par.ctrl_u_max = 5000.0f;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_start(&ctl_off, &par, PERIOD_S));
    par.ppc_u_lpf_hz = fu;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_start(&ctl_on, &par, PERIOD_S));
    const double k_u = 1.0 - exp(-2.0 * 3.14159265358979 * fu * PERIOD_S);
    uint32_t seed = 11u;
    double y = 0.0, tv_off = 0.0, tv_on = 0.0, max_dev = 0.0;
    float last_off = 0.0f, last_on = 0.0f;
    for (int k = 0; k < 3000; ++k) {
        const float t_s = (float)k * PERIOD_S;
        const float x = sine_cm(t_s) + 0.002f * (float)test_rand_uniform(&seed);
        float u_off, u_on;
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_step(&ctl_off, t_s, x, 0.0f, &u_off));
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_step(&ctl_on, t_s, x, 0.0f, &u_on));
        y = (k == 0) ? u_off : y + k_u * (u_off - y);
        max_dev = fmax(max_dev, fabs(u_on - y));
        if (k > 0) {
            tv_off += fabsf(u_off - last_off);
            tv_on += fabsf(u_on - last_on);
        }
        last_off = u_off;
        last_on = u_on;
    }
    printf("u_lpf: max |u - lpf(u_law)| %.2e, total variation %.1f filtered against %.1f\n", max_dev,
           tv_on, tv_off);
    TEST_ASSERT_TRUE(max_dev < 2e-3);
    TEST_ASSERT_TRUE(tv_on < 0.5 * tv_off);
    par.ppc_u_lpf_hz = -1.0f;
    TEST_ASSERT_EQUAL_INT(PMA_ERR_RANGE, pma_ctrl_start(&ctl_on, &par, PERIOD_S));
}

/* ppc.ff_hold_speed_cm_s reaches the law: two slots with the feedforward integrator on, one with
 * the hold at 0.5 cm/s, on a muscle driven from 1 cm above a held reference down onto it at
 * 1 cm/s. Both laws see the same samples, so their outputs differ by their integrators only: the
 * slot that holds has FF_HOLD set while the observer reads the muscle closing faster than 0.5
 * cm/s and its integrator has not moved when the muscle arrives; the other's has. Standing on the
 * reference, neither holds. A negative hold speed is refused at START. */
static void test_ff_hold_waits_while_the_muscle_closes(void)
{
    pma_params_defaults(&par);
    par.ctrl_mode = PMA_CTRL_MODE_PPC;
    par.ref_kind = PMA_REF_KIND_HOLD;
    par.ref_offset_cm = OFFSET_CM;
    par.vel_kind = PMA_VELEST_TRACKING;
    par.vel_fc_hz = 20.0f;
    par.ppc_ref_vel = 1;
    par.ppc_fallback = 0;
    par.ppc_t_u_s = 0.5f;
    par.ppc_w1_cm = 1.2f;          /* the funnels wide enough for the whole approach */
    par.ppc_w2_cm_s = 5.0f;
    par.ppc_c = 200.0f;
    par.ppc_ff_gain_per_s = 20.0f;
    par.ppc_ff_init = 0.0f;
    par.ctrl_u_min = -5000.0f;
    par.ctrl_u_max = 5000.0f;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_start(&ctl_off, &par, PERIOD_S));
    par.ppc_ff_hold_speed_cm_s = 0.5f;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_start(&ctl_on, &par, PERIOD_S));
    int held = 0, held_off = 0, held_standing = 0;
    float u_off = 0.0f, u_on = 0.0f;
    for (int k = 0; k < 1500; ++k) {
        const float t_s = (float)k * PERIOD_S;
        const float x = OFFSET_CM + (t_s < 1.0f ? 1.0f - t_s : 0.0f);
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_step(&ctl_off, t_s, x, 0.0f, &u_off));
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_step(&ctl_on, t_s, x, 0.0f, &u_on));
        const int hold = (pma_ctrl_out(&ctl_on)->flags & PMA_PPC_FLAG_FF_HOLD) != 0;
        held += hold;
        held_off += (pma_ctrl_out(&ctl_off)->flags & PMA_PPC_FLAG_FF_HOLD) != 0;
        if (t_s > 1.2f) held_standing += hold;
        if (k == 900) {
            /* arriving: the held integrator is about where it started (ff_init 0; it integrated
             * only the observer's first ticks), the other has wound up */
            const float ff_on = u_on - law_u(&ctl_on), ff_off = u_off - law_u(&ctl_off);
            printf("ff_hold: held %d of 900 ticks; the integrators at arrival %.3f held, %.3f not\n",
                   held, (double)ff_on, (double)ff_off);
            TEST_ASSERT_TRUE(held > 800);
            TEST_ASSERT_TRUE(fabsf(ff_off) > 10.0f);
            TEST_ASSERT_TRUE(fabsf(ff_on) < 0.02f * fabsf(ff_off));
        }
    }
    TEST_ASSERT_EQUAL_INT(0, held_off);
    TEST_ASSERT_EQUAL_INT(0, held_standing);
    par.ppc_ff_hold_speed_cm_s = -1.0f;
    TEST_ASSERT_EQUAL_INT(PMA_ERR_RANGE, pma_ctrl_start(&ctl_on, &par, PERIOD_S));
}

/* Q16.16 time ends at 32767 s: the Q16.16 slot refuses a step past it (the application then
 * faults CONTROLLER); float goes on. */
static void test_time_beyond_the_fixed_point_range(void)
{
    pma_params_defaults(&par);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_start(&ctl_on, &par, PERIOD_S));
    float u;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_step(&ctl_on, 32766.0f, OFFSET_CM, 0.0f, &u));
#if PMA_CTRL_Q16
    TEST_ASSERT_EQUAL_INT(PMA_ERR_FIXED_RANGE, pma_ctrl_step(&ctl_on, 32767.0f, OFFSET_CM, 0.0f, &u));
#else
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_step(&ctl_on, 32767.0f, OFFSET_CM, 0.0f, &u));
#endif
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NOT_FINITE, pma_ctrl_step(&ctl_on, 1.0f, NAN, 0.0f, &u));
}

/* The guarantee monitor's hand-over rules with ppc.fallback WIDEN (the default), driven
 * directly with the law's flags of lost ticks: after a widening of the position funnel, the
 * input at both of its limits within t_u (the law swinging limit to limit) hands over at once;
 * one limit only, both limits but the second after t_u, or both without a widening, do not. */
#define T0_S 10.0f   /* the first lost tick's control time [s] */
typedef struct lost_tick {
    float at_t_u;    /* the tick's time after T0_S, in units of t_u */
    uint32_t flags;  /* the law's PMA_PPC_FLAG_* of that tick */
} lost_tick_t;

/* START with the defaults (ppc.fallback as given), then the lost ticks; MFAC in charge after? */
static int hands_over(uint32_t fallback, const lost_tick_t *ticks, size_t n)
{
    pma_params_defaults(&par);
    par.ppc_fallback = fallback;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_start(&ctl_on, &par, PERIOD_S));
    TEST_ASSERT_TRUE(ctl_on.t_u_s > 0.0f);
    for (size_t i = 0; i < n; ++i) {
        TEST_ASSERT_FALSE(ctl_on.fallback_active);   /* not before the last tick */
        pma_ctrl_monitor_lost(&ctl_on, T0_S + ticks[i].at_t_u * ctl_on.t_u_s, ticks[i].flags);
    }
    TEST_ASSERT_TRUE(ctl_on.lost);
    return ctl_on.fallback_active;
}

#define W1 PMA_PPC_FLAG_WIDEN1
#define HI PMA_PPC_FLAG_SAT_HIGH
#define LO PMA_PPC_FLAG_SAT_LOW
#define HANDS_OVER(fallback, ...)                                                    \
    hands_over((fallback), (const lost_tick_t[]){__VA_ARGS__},                       \
               sizeof((const lost_tick_t[]){__VA_ARGS__}) / sizeof(lost_tick_t))

static void test_swing_limit_to_limit_after_a_widening_hands_over(void)
{
    pma_params_defaults(&par);
    TEST_ASSERT_EQUAL_INT(PMA_PPC_FALLBACK_WIDEN, par.ppc_fallback);   /* the default */
    /* widening at the high limit, then the low limit within t_u */
    TEST_ASSERT_TRUE(HANDS_OVER(PMA_PPC_FALLBACK_WIDEN, {0.0f, W1 | HI}, {0.1f, HI}, {0.5f, LO}));
    /* a widening off the limits, then low, neither, high within t_u */
    TEST_ASSERT_TRUE(HANDS_OVER(PMA_PPC_FALLBACK_WIDEN, {0.0f, W1}, {0.2f, LO}, {0.3f, 0u}, {0.9f, HI}));
}

static void test_one_limit_or_a_late_swing_keeps_the_law(void)
{
    /* held at one limit after the widening (a reference beyond it), then the other limit only
     * after t_u has passed since the widening */
    TEST_ASSERT_FALSE(HANDS_OVER(PMA_PPC_FALLBACK_WIDEN, {0.0f, W1 | LO}, {0.1f, LO}, {0.5f, LO},
                                 {0.9f, LO}, {1.5f, HI}));
    /* both limits on lost ticks with no widening (|e| >= w1 after t_u alone) */
    TEST_ASSERT_FALSE(HANDS_OVER(PMA_PPC_FALLBACK_WIDEN, {0.0f, HI}, {0.1f, LO}, {0.2f, HI}));
    /* the paper's law without widening (ppc.fallback 0) never hands over */
    TEST_ASSERT_FALSE(HANDS_OVER(0u, {0.0f, W1 | HI}, {0.1f, LO}));
}

/* The monitor's lost ticks from a barrier clamp (pma_ctrl_monitor, driven with the law's flags):
 * after t_u a clamp with the output at either limit is lost at once, however short; a clamp off
 * the limits, a clamp at a limit before t_u (the start's transient) and a limit without a clamp
 * are not (a clamp run of safety.barrier_ticks is: test_app_faults.c). */
static void test_a_clamp_at_the_input_limit_after_t_u_is_lost(void)
{
    pma_params_defaults(&par);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_start(&ctl_on, &par, PERIOD_S));
    const uint32_t b1 = PMA_PPC_FLAG_BARRIER1, b2 = PMA_PPC_FLAG_BARRIER2;
    TEST_ASSERT_TRUE(pma_ctrl_monitor(&ctl_on, 1, 0, b2 | PMA_PPC_FLAG_SAT_LOW));
    TEST_ASSERT_TRUE(pma_ctrl_monitor(&ctl_on, 1, 0, b1 | PMA_PPC_FLAG_SAT_HIGH));
    TEST_ASSERT_FALSE(pma_ctrl_monitor(&ctl_on, 1, 0, b2));
    TEST_ASSERT_FALSE(pma_ctrl_monitor(&ctl_on, 0, 0, b2 | PMA_PPC_FLAG_SAT_LOW));
    TEST_ASSERT_FALSE(pma_ctrl_monitor(&ctl_on, 1, 0, PMA_PPC_FLAG_SAT_HIGH));
    TEST_ASSERT_TRUE(pma_ctrl_monitor(&ctl_on, 1, 1, 0u));   /* |e| >= w1 after t_u, as before */
    TEST_ASSERT_EQUAL_UINT32(0u, ctl_on.barrier_run);        /* the last tick had no clamp */
    /* the clamp at the limit counts in the clamp run like any other */
    TEST_ASSERT_TRUE(pma_ctrl_monitor(&ctl_on, 1, 0, b2 | PMA_PPC_FLAG_SAT_LOW));
    TEST_ASSERT_EQUAL_UINT32(1u, ctl_on.barrier_run);
}

/* pma_ctrl_lost_again: the lost ticks on which pma_ctrl_monitor_lost would only count (the
 * Q16.16 slot then skips it and its float time): after the first loss, with no widening of the
 * position funnel since START, none on the tick, no clamp run, and MFAC already in charge where
 * ppc.fallback is MFAC. */
static void test_a_lost_tick_that_only_counts(void)
{
    pma_params_defaults(&par);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_start(&ctl_on, &par, PERIOD_S));
    TEST_ASSERT_FALSE(pma_ctrl_lost_again(&ctl_on, 0u));                  /* not lost yet */
    pma_ctrl_monitor_lost(&ctl_on, T0_S, PMA_PPC_FLAG_SAT_LOW);
    TEST_ASSERT_TRUE(pma_ctrl_lost_again(&ctl_on, PMA_PPC_FLAG_SAT_LOW));
    TEST_ASSERT_FALSE(pma_ctrl_lost_again(&ctl_on, W1));                  /* a widening: its rules */
    const uint32_t ticks = ctl_on.lost_ticks;
    pma_ctrl_count_lost(&ctl_on);
    TEST_ASSERT_EQUAL_UINT32(ticks + 1u, ctl_on.lost_ticks);
    ctl_on.barrier_run = ctl_on.barrier_ticks;                            /* a clamp run: hands over */
    TEST_ASSERT_FALSE(pma_ctrl_lost_again(&ctl_on, 0u));
    ctl_on.barrier_run = 0u;
    pma_ctrl_monitor_lost(&ctl_on, T0_S + 0.1f, W1 | PMA_PPC_FLAG_SAT_LOW);
    TEST_ASSERT_FALSE(pma_ctrl_lost_again(&ctl_on, 0u));                  /* after a widening: its rules */
    par.ppc_fallback = PMA_PPC_FALLBACK_MFAC;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ctrl_start(&ctl_on, &par, PERIOD_S));
    pma_ctrl_monitor_lost(&ctl_on, T0_S, 0u);                             /* MFAC takes over */
    TEST_ASSERT_TRUE(ctl_on.fallback_active && pma_ctrl_lost_again(&ctl_on, 0u));
    ctl_on.lost_ticks = UINT32_MAX;                                       /* saturates, never wraps */
    pma_ctrl_count_lost(&ctl_on);
    TEST_ASSERT_EQUAL_UINT32(UINT32_MAX, ctl_on.lost_ticks);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_options_are_off_by_default);
    RUN_TEST(test_obs_pos_needs_the_tracking_observer);
    RUN_TEST(test_ref_vel_damps_the_velocity_error);
    RUN_TEST(test_obs_pos_takes_the_error_from_the_observer);
    RUN_TEST(test_ref_ff_adds_the_maps_input_for_the_reference_ahead);
    RUN_TEST(test_ref_ff_hyst_adds_a_play_operator_on_the_reference);
    RUN_TEST(test_ref_ff_hyst_adapts_to_the_muscles_hysteresis);
    RUN_TEST(test_u_lpf_filters_the_laws_command);
    RUN_TEST(test_ff_hold_waits_while_the_muscle_closes);
    RUN_TEST(test_time_beyond_the_fixed_point_range);
    RUN_TEST(test_swing_limit_to_limit_after_a_widening_hands_over);
    RUN_TEST(test_one_limit_or_a_late_swing_keeps_the_law);
    RUN_TEST(test_a_clamp_at_the_input_limit_after_t_u_is_lost);
    RUN_TEST(test_a_lost_tick_that_only_counts);
    return UNITY_END();
}
