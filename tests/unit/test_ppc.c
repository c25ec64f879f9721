/* SPDX-License-Identifier: Apache-2.0 */
/* Properties of the paper's controller (pma/ppc.h), float and fixed point. */
#include "test_util.h"
#include "pma/ppc.h"
#include "pma/status.h"

#define PI 3.14159265358979323846

static pma_ppc_config_t case3(void)
{
    pma_ppc_config_t c;
    pma_ppc_default_config(&c);
    return c;
}

/* u = 0 at t = 0 whatever the initial error and velocity (alpha(0) = 0). */
static void test_bumpless_start(void)
{
    pma_ppc_config_t c = case3();
    pma_ppc_f32_t f;
    pma_ppc_q16_t q;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_f32(&f, &c));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_q16(&q, &c));
    const float errs[] = {-2.9f, -1.0f, -0.19f, 0.0f, 0.5f, 2.0f};
    const float vels[] = {-50.0f, 0.0f, 3.0f};
    for (unsigned i = 0; i < 6; ++i) {
        for (unsigned j = 0; j < 3; ++j) {
            float u = 1.0f;
            pma_q16_t uq = 1;
            TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_f32(&f, 0.0f, -2.0f + errs[i], vels[j], -2.0f, &u));
            TEST_ASSERT_TRUE(u == 0.0f);
            TEST_ASSERT_TRUE(f.out.lambda1_cm == 0.0f && f.out.lambda2_cm_s == 0.0f);
            TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_q16(&q, 0, Q16(-2.0f + errs[i]), Q16(vels[j]), Q16(-2.0), &uq));
            TEST_ASSERT_EQUAL_INT(0, uq);
            TEST_ASSERT_EQUAL_HEX32(0, f.out.flags);
            TEST_ASSERT_EQUAL_HEX32(0, q.out.flags);
        }
    }
}

/* alpha(t) = 0.5 - 0.5 cos(pi t / t_u) before t_u, exactly 1 from t_u on,
 * monotone; e does not matter. */
static void test_alpha_profile(void)
{
    pma_ppc_config_t c = case3();
    c.t_u_s = 6.0f;
    pma_ppc_f32_t f;
    pma_ppc_q16_t q;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_f32(&f, &c));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_q16(&q, &c));
    float u, prev = -1.0f;
    pma_q16_t uq;
    for (int k = 0; k <= 800; ++k) {
        const double t = k * 0.01;
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_f32(&f, (float)t, -2.01f, 0.0f, -2.0f, &u));
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_q16(&q, Q16(t), Q16(-2.01), 0, Q16(-2.0), &uq));
        const double tq = F16(Q16(t));
        const double want = tq < 6.0 ? 0.5 - 0.5 * cos(PI * tq / 6.0) : 1.0;
        assert_near(f.out.alpha, t < 6.0 ? 0.5 - 0.5 * cos(PI * t / 6.0) : 1.0, 2e-7);
        assert_near(pma_q30_to_f32(q.out.alpha), want, 2e-7);
        TEST_ASSERT_TRUE(f.out.alpha >= prev);
        prev = f.out.alpha;
        if (t >= 6.0) {
            TEST_ASSERT_TRUE(f.out.alpha == 1.0f);
            TEST_ASSERT_EQUAL_INT(PMA_Q30_ONE, q.out.alpha);
        }
    }
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_f32(&f, 3.0f, -2.0f, 0.0f, -2.0f, &u));
    assert_near(f.out.alpha, 0.5, 1e-7);
}

/* The law's sign: x above the reference at rest, after t_u -> negative u
 * (the actuator's positive direction is +x; polarity is the application's). */
static void test_law_direction_and_equations(void)
{
    pma_ppc_config_t c = case3();
    pma_ppc_f32_t f;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_f32(&f, &c));
    float u;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_f32(&f, 5.0f, -1.99f, 0.1f, -2.0f, &u));
    TEST_ASSERT_EQUAL_HEX32(0, f.out.flags);
    /* the equations written out in double */
    const double e = 0.01, chi = tan(PI * e / (2 * 0.2)), theta = -2 * chi;
    const double l2 = 0.1 - theta, delta = tan(PI * l2 / (2 * 0.5));
    const double beta = 1.0 / (0.5 * pow(cos(PI * l2 / (2 * 0.5)), 2));
    assert_near(f.out.chi, chi, 1e-5);
    assert_near(f.out.lambda2_cm_s, l2, 1e-5);
    assert_near(f.out.delta, delta, 1e-5 * fabs(delta));
    assert_near(f.out.beta_s_cm, beta, 1e-5 * beta);
    assert_near(u, -2.0 * beta * delta, 1e-4 * fabs(u));
    TEST_ASSERT_LESS_THAN_DOUBLE(0.0, u);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_f32(&f, 5.0f, -2.01f, -0.1f, -2.0f, &u));
    TEST_ASSERT_EQUAL_HEX32(0, f.out.flags);
    TEST_ASSERT_GREATER_THAN_DOUBLE(0.0, u);
}

/* At and beyond the barrier: clamp just inside, flag, count, finite output
 * saturated in the direction the law demands; both variants agree. */
static void test_barrier_clamp(void)
{
    pma_ppc_config_t c = case3();
    pma_ppc_f32_t f;
    pma_ppc_q16_t q;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_f32(&f, &c));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_q16(&q, &c));
    float u;
    pma_q16_t uq;
    const float r_max = 1.0f - c.barrier_margin;
    const double tan_max = tan(PI / 2 * r_max);
    /* e = +0.3 > w1: lambda1 beyond the barrier, law pushes down */
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_f32(&f, 10.0f, -1.7f, 0.0f, -2.0f, &u));
    TEST_ASSERT_TRUE(f.out.flags & PMA_PPC_FLAG_BARRIER1);
    TEST_ASSERT_TRUE(f.out.flags & PMA_PPC_FLAG_BARRIER2);
    assert_near(f.out.chi, tan_max, 1e-3 * tan_max);
    TEST_ASSERT_TRUE(isfinite(f.out.u_law) && f.out.u_law < 0.0f);
    TEST_ASSERT_TRUE(u == c.u_min);
    TEST_ASSERT_TRUE(f.out.flags & PMA_PPC_FLAG_SAT_LOW);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_q16(&q, Q16(10.0), Q16(-1.7), 0, Q16(-2.0), &uq));
    TEST_ASSERT_EQUAL_HEX32(f.out.flags, q.out.flags);
    TEST_ASSERT_EQUAL_INT(Q16(c.u_min), uq);
    assert_near(F16(q.out.chi), tan_max, 1e-3 * tan_max);
    /* negative side */
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_f32(&f, 10.0f, -2.5f, 0.0f, -2.0f, &u));
    TEST_ASSERT_TRUE(u == c.u_max);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_q16(&q, Q16(10.0), Q16(-2.5), 0, Q16(-2.0), &uq));
    TEST_ASSERT_EQUAL_INT(Q16(c.u_max), uq);
    TEST_ASSERT_EQUAL_INT(2, f.breaches1);
    TEST_ASSERT_EQUAL_INT(2, f.breaches2);
    TEST_ASSERT_EQUAL_INT(2, q.breaches1);
    /* exactly at r = r_max counts as reaching the barrier */
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_f32(&f, 10.0f, -2.0f + 0.2f * r_max, 0.0f, -2.0f, &u));
    TEST_ASSERT_TRUE(f.out.flags & PMA_PPC_FLAG_BARRIER1);
    /* inside: no flag, and lambda2 alone can breach (large velocity) */
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_f32(&f, 10.0f, -2.0f, 0.6f, -2.0f, &u));
    TEST_ASSERT_EQUAL_HEX32(0, f.out.flags & PMA_PPC_FLAG_BARRIER1);
    TEST_ASSERT_TRUE(f.out.flags & PMA_PPC_FLAG_BARRIER2);
    TEST_ASSERT_TRUE(u == c.u_min);
    /* reset clears the counters */
    pma_ppc_reset_f32(&f);
    TEST_ASSERT_EQUAL_INT(0, f.breaches1);
}

/* Soft barrier: identical to the paper below soft_r, continuous at soft_r,
 * linear (bounded growth) beyond it. */
static void test_soft_barrier(void)
{
    pma_ppc_config_t c = case3();
    pma_ppc_config_t cs = c;
    cs.soft_barrier_r = 0.9f;
    pma_ppc_f32_t paper, soft;
    pma_ppc_q16_t softq;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_f32(&paper, &c));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_f32(&soft, &cs));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_q16(&softq, &cs));
    float u1, u2;
    pma_q16_t uq;
    /* r1 = 0.5 (e = 0.1, chi = 1, theta = -2), v = -1.9 so r2 = 0.2: identical */
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_f32(&paper, 10.0f, -1.9f, -1.9f, -2.0f, &u1));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_f32(&soft, 10.0f, -1.9f, -1.9f, -2.0f, &u2));
    TEST_ASSERT_TRUE(u1 == u2);
    TEST_ASSERT_EQUAL_HEX32(0, soft.out.flags & (PMA_PPC_FLAG_SOFT1 | PMA_PPC_FLAG_SOFT2));
    /* continuity of chi at soft_r = 0.9 (e = 0.18) */
    const float e_lo = 0.2f * 0.8999f, e_hi = 0.2f * 0.9001f;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_f32(&soft, 10.0f, -2.0f + e_lo, 0.0f, -2.0f, &u1));
    const float chi_lo = soft.out.chi;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_f32(&soft, 10.0f, -2.0f + e_hi, 0.0f, -2.0f, &u1));
    TEST_ASSERT_TRUE(soft.out.flags & PMA_PPC_FLAG_SOFT1);
    assert_near(soft.out.chi, chi_lo, 0.01 * chi_lo);
    /* beyond: linear growth, far below the paper's tan */
    const double t9 = tan(PI / 2 * 0.9), s9 = 1 + t9 * t9;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_f32(&soft, 10.0f, -2.0f + 0.2f * 0.98f, 0.0f, -2.0f, &u1));
    assert_near(soft.out.chi, t9 + PI / 2 * s9 * (0.98 - 0.9), 1e-3 * soft.out.chi);
    TEST_ASSERT_LESS_THAN_DOUBLE(tan(PI / 2 * 0.98), soft.out.chi);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_q16(&softq, Q16(10.0), Q16(-2.0f + 0.2f * 0.98f), 0, Q16(-2.0), &uq));
    assert_near(F16(softq.out.chi), soft.out.chi, 2e-3 * soft.out.chi);
    TEST_ASSERT_EQUAL_HEX32(soft.out.flags, softq.out.flags);
}

/* Funnel widening (widen_r; widen2_steps 1: lambda2 at once too): where the law would clamp,
 * the funnel widens so that |r| = widen_r (flags WIDEN1/2, WIDE; no barrier flag, bounded
 * gain), then shrinks back to w over t_u with the tuning function's shape; float and fixed
 * point agree. */
static void test_funnel_widening(void)
{
    pma_ppc_config_t c = case3();
    c.widen_r = 0.5f;
    c.widen2_steps = 1;
    pma_ppc_f32_t f;
    pma_ppc_q16_t q;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_f32(&f, &c));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_q16(&q, &c));
    float u;
    pma_q16_t uq;
    /* after t_u, e = +0.3 cm = 1.5 w1: g1 = 0.5 / 1.5, chi = tan(pi / 4) = 1, theta = -a = -2;
     * lambda2 = 2 = 4 w2: g2 = 0.125, delta = 1, beta = 2 g2 / w2 = 0.5, u_law = -c beta = -1 */
    const uint32_t widened = PMA_PPC_FLAG_WIDEN1 | PMA_PPC_FLAG_WIDEN2 | PMA_PPC_FLAG_WIDE;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_f32(&f, 10.0f, -1.7f, 0.0f, -2.0f, &u));
    TEST_ASSERT_EQUAL_HEX32(widened, f.out.flags);
    assert_near(f.out.g1, 1.0 / 3.0, 1e-6);
    assert_near(f.out.chi, 1.0, 1e-5);
    assert_near(f.out.g2, 0.125, 1e-6);
    assert_near(f.out.delta, 1.0, 1e-5);
    assert_near(f.out.beta_s_cm, 0.5, 1e-5);
    assert_near(f.out.u_law, -1.0, 1e-5);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_q16(&q, Q16(10.0), Q16(-1.7), 0, Q16(-2.0), &uq));
    TEST_ASSERT_EQUAL_HEX32(widened, q.out.flags);
    assert_near(F30(q.out.g1), 1.0 / 3.0, 2e-5);   /* e in Q16.16 */
    assert_near(F30(q.out.g2), 0.125, 2e-5);
    assert_near(F16(uq), u, 2e-4);
    TEST_ASSERT_EQUAL_INT(0, f.breaches1 + f.breaches2 + q.breaches1 + q.breaches2);
    /* half of t_u later, a small error: g = 1 - (1 - k)(0.5 + 0.5 cos(pi / 2)) = (1 + k) / 2,
     * still wide, no new widening */
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_f32(&f, 11.0f, -1.97f, 0.0f, -2.0f, &u));
    TEST_ASSERT_EQUAL_HEX32(PMA_PPC_FLAG_WIDE, f.out.flags);
    assert_near(f.out.g1, (1.0 + 1.0 / 3.0) / 2.0, 1e-5);
    assert_near(f.out.g2, (1.0 + 0.125) / 2.0, 1e-5);
    assert_near(f.out.chi, tan(PI / 2 * 0.15 * f.out.g1), 1e-4);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_q16(&q, Q16(11.0), Q16(-1.97), 0, Q16(-2.0), &uq));
    TEST_ASSERT_EQUAL_HEX32(PMA_PPC_FLAG_WIDE, q.out.flags);
    assert_near(F30(q.out.g1), f.out.g1, 1e-5);
    assert_near(F16(uq), u, 1e-3);    /* 0.02 % of it */
    /* t_u after the widening: the funnels are as assigned again, the paper's law exactly */
    pma_ppc_f32_t paper;
    pma_ppc_config_t cp = case3();
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_f32(&paper, &cp));
    float u_paper;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_f32(&f, 12.0f, -1.97f, -0.3f, -2.0f, &u));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_f32(&paper, 12.0f, -1.97f, -0.3f, -2.0f, &u_paper));
    TEST_ASSERT_EQUAL_HEX32(0, f.out.flags);
    TEST_ASSERT_TRUE(f.out.g1 == 1.0f && f.out.g2 == 1.0f && u == u_paper);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_q16(&q, Q16(12.0), Q16(-1.97), Q16(-0.3), Q16(-2.0), &uq));
    TEST_ASSERT_EQUAL_HEX32(0, q.out.flags);
    /* an error far beyond the funnel: the scale stops at its floor 2^-20, then the clamp */
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_f32(&f, 20.0f, 1.0e6f, 0.0f, -2.0f, &u));
    assert_near(f.out.g1, 1.0 / 1048576.0, 1e-12);
    TEST_ASSERT_TRUE(f.out.flags & PMA_PPC_FLAG_BARRIER1);
    TEST_ASSERT_TRUE(isfinite(u) && u < 0.0f && u >= c.u_min);   /* the right direction, bounded */
    /* reset: the funnels as assigned */
    pma_ppc_reset_f32(&f);
    pma_ppc_reset_q16(&q);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_f32(&f, 20.0f, -1.97f, 0.0f, -2.0f, &u));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_q16(&q, Q16(20.0), Q16(-1.97), 0, Q16(-2.0), &uq));
    TEST_ASSERT_TRUE(f.out.g1 == 1.0f && q.out.g1 == PMA_Q30_ONE);
}

/* lambda2's funnel widens only after widen2_steps consecutive steps at its clamp (until then
 * the paper's clamp, BARRIER2); a step inside the clamp starts the count again; with
 * widen2_steps 0 lambda2 never widens. lambda1's widens at once. Both arithmetics. */
static void test_velocity_funnel_widens_after_a_run(void)
{
    for (uint32_t steps = 0; steps <= 3; steps += 3) {
        pma_ppc_config_t c = case3();
        c.widen_r = 0.5f;
        c.widen2_steps = steps;
        pma_ppc_f32_t f;
        pma_ppc_q16_t q;
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_f32(&f, &c));
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_q16(&q, &c));
        float u;
        pma_q16_t uq;
        /* after t_u, e = 0 (chi = 0, theta = 0), v = 2 cm/s = 4 w2: lambda2 beyond its clamp;
         * then v = 0.1 (inside); then the run again */
        const float v[] = {2.0f, 2.0f, 0.1f, 2.0f, 2.0f, 2.0f, 2.0f};
        for (int k = 0; k < 7; ++k) {
            const float t = 10.0f + 0.001f * (float)k;
            TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_f32(&f, t, -2.0f, v[k], -2.0f, &u));
            TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_q16(&q, Q16(t), Q16(-2.0), Q16(v[k]),
                                                           Q16(-2.0), &uq));
            /* the third step of the second run (k = 5) widens when widen2_steps is 3 */
            const int widens = steps == 3 && k == 5;
            const int wide = steps == 3 && k >= 5;
            const uint32_t want = (v[k] > 1.0f && !widens && !wide ? PMA_PPC_FLAG_BARRIER2 : 0u) |
                                  (widens ? PMA_PPC_FLAG_WIDEN2 : 0u) |
                                  (wide ? PMA_PPC_FLAG_WIDE : 0u);
            TEST_ASSERT_EQUAL_HEX32(want, f.out.flags & ~(PMA_PPC_FLAG_SAT_HIGH | PMA_PPC_FLAG_SAT_LOW));
            TEST_ASSERT_EQUAL_HEX32(f.out.flags, q.out.flags);
        }
        if (steps == 3) {
            /* widened to 0.5 / 4 = 0.125; 1 ms of t_u = 2 s later it has barely grown back */
            assert_near(f.out.g2, 0.125, 1e-3);
            assert_near(f.out.g2, F30(q.out.g2), 1e-5);
        } else {
            TEST_ASSERT_TRUE(f.out.g2 == 1.0f && q.out.g2 == PMA_Q30_ONE);
            TEST_ASSERT_EQUAL_INT(6, f.breaches2);
            TEST_ASSERT_EQUAL_INT(6, q.breaches2);
        }
    }
}

/* Feedforward switch: off keeps u_ff = 0; on integrates the law's output,
 * holds it while saturated in the same direction, stays within limits. */
static void test_feedforward(void)
{
    pma_ppc_config_t c = case3();
    pma_ppc_f32_t off;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_f32(&off, &c));
    float u;
    for (int k = 0; k < 100; ++k) {
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_f32(&off, 5.0f, -1.99f, 0.0f, -2.0f, &u));
    }
    TEST_ASSERT_TRUE(off.u_ff == 0.0f && off.out.u_ff == 0.0f);
    TEST_ASSERT_TRUE(u == off.out.u_law);

    c.ff_gain_per_s = 2.0f;
    c.ff_init = 10.0f;
    pma_ppc_f32_t on;
    pma_ppc_q16_t onq;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_f32(&on, &c));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_q16(&onq, &c));
    pma_q16_t uq;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_f32(&on, 5.0f, -1.99f, 0.0f, -2.0f, &u));
    const float law = on.out.u_law;
    assert_near(on.out.u_ff, 10.0, 0.0);
    assert_near(u, 10.0 + law, 1e-4);
    assert_near(on.u_ff, 10.0 + 2.0 * 1e-3 * law, 1e-5);
    for (int k = 0; k < 999; ++k) {
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_f32(&on, 5.0f, -1.99f, 0.0f, -2.0f, &u));
    }
    for (int k = 0; k < 1000; ++k) {
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_q16(&onq, Q16(5.0), Q16(-1.99), 0, Q16(-2.0), &uq));
    }
    assert_near(on.u_ff, 10.0 + 2.0 * law, 1e-3);   /* 1 s of integration */
    assert_near(F16(onq.out.u_ff), on.out.u_ff, 0.01);
    /* saturated in the law's direction: the feedforward holds (anti-windup) */
    const float held = on.u_ff;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_f32(&on, 5.0f, -1.7f, 0.0f, -2.0f, &u));
    TEST_ASSERT_TRUE(on.out.flags & PMA_PPC_FLAG_SAT_LOW);
    TEST_ASSERT_TRUE(on.u_ff == held);
    pma_ppc_reset_f32(&on);
    TEST_ASSERT_TRUE(on.u_ff == 10.0f);
}

/* ff_hold_speed_cm_s: the feedforward integrator holds (flag FF_HOLD) while the error and the
 * velocity input have opposite signs and the speed is above the hold speed: the muscle closes
 * on the reference faster than that. Slower, standing, moving away, or the option off: it
 * integrates as before. Float and fixed point decide alike, and the law's output is the same. */
static void test_feedforward_holds_while_closing(void)
{
    pma_ppc_config_t c = case3();
    c.ff_gain_per_s = 2.0f;
    c.ff_init = 10.0f;
    c.ff_hold_speed_cm_s = 0.1f;   /* speeds below w2 = 0.5 cm/s: the law inside its funnels */
    const struct { float x_cm, v_cm_s; int held; } steps[] = {
        {-1.99f, -0.2f, 1},   /* e > 0, closing at 0.2 cm/s: held */
        {-1.99f, -0.05f, 0},  /* closing slower than the hold speed */
        {-1.99f, 0.0f, 0},    /* standing */
        {-1.99f, 0.2f, 0},    /* moving away */
        {-2.01f, 0.2f, 1},    /* e < 0, closing from below */
        {-2.01f, 0.15f, 1},
        {-2.01f, -0.2f, 0},
        {-2.0f, -0.2f, 0},    /* on the reference */
    };
    for (unsigned i = 0; i < sizeof steps / sizeof steps[0]; ++i) {
        pma_ppc_f32_t f;
        pma_ppc_q16_t q;
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_f32(&f, &c));
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_q16(&q, &c));
        float u;
        pma_q16_t uq;
        TEST_ASSERT_EQUAL_INT(PMA_OK,
                              pma_ppc_step_f32(&f, 5.0f, steps[i].x_cm, steps[i].v_cm_s, -2.0f, &u));
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_q16(&q, Q16(5.0), Q16(steps[i].x_cm),
                                                       Q16(steps[i].v_cm_s), Q16(-2.0), &uq));
        const uint32_t want = steps[i].held ? PMA_PPC_FLAG_FF_HOLD : 0u;
        TEST_ASSERT_EQUAL_HEX32(want, f.out.flags & PMA_PPC_FLAG_FF_HOLD);
        TEST_ASSERT_EQUAL_HEX32(want, q.out.flags & PMA_PPC_FLAG_FF_HOLD);
        if (steps[i].held) {
            TEST_ASSERT_TRUE(f.u_ff == 10.0f);
            TEST_ASSERT_TRUE(q.u_ff_q32 == (int64_t)Q16(10.0) * 65536);
        } else {
            assert_near(f.u_ff, 10.0 + 2.0 * 1e-3 * f.out.u_law, 1e-5);
            TEST_ASSERT_TRUE(f.out.u_law == 0.0f || f.u_ff != 10.0f);
        }
        assert_near(u, 10.0 + f.out.u_law, 1e-4);   /* the law's own output acts either way */
    }
    /* off (0): closing fast integrates as before */
    c.ff_hold_speed_cm_s = 0.0f;
    pma_ppc_f32_t off;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_f32(&off, &c));
    float u;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_f32(&off, 5.0f, -1.99f, -0.2f, -2.0f, &u));
    TEST_ASSERT_EQUAL_HEX32(0u, off.out.flags & PMA_PPC_FLAG_FF_HOLD);
    TEST_ASSERT_TRUE(off.u_ff != 10.0f);
}

/* An input added by the caller (pma_ppc_step_ext_*, the application's reference feedforward)
 * is inside the clamp: the flags and the feedforward's anti-windup see the whole output, so a
 * reference beyond the plant's reach keeps the input at its limit while the law pushes there
 * (the feedforward winds past u_min by u_ext, no further), in both arithmetics. */
static void test_external_input(void)
{
    pma_ppc_config_t c = case3();
    c.u_min = -400.0f;
    c.u_max = 400.0f;
    c.ff_gain_per_s = 400.0f;          /* 0.4 per step: the run below winds up in 10^4 steps */
    c.ff_init = 0.0f;
    pma_ppc_f32_t a, b;
    pma_ppc_q16_t aq, bq;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_f32(&a, &c));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_f32(&b, &c));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_q16(&aq, &c));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_q16(&bq, &c));
    float u, ub;
    pma_q16_t uq, ubq;
    /* u_ext = 0 is the plain step, bit for bit */
    for (int k = 0; k < 200; ++k) {
        const float t = 1e-3f * (float)k, x = -1.9f + 1e-4f * (float)k;
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_f32(&a, t, x, 0.1f, -2.0f, &u));
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_ext_f32(&b, t, x, 0.1f, -2.0f, 0.0f, &ub));
        TEST_ASSERT_TRUE(u == ub && a.u_ff == b.u_ff);
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_q16(&aq, Q16(t), Q16(x), Q16(0.1), Q16(-2.0), &uq));
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_ext_q16(&bq, Q16(t), Q16(x), Q16(0.1), Q16(-2.0), 0, &ubq));
        TEST_ASSERT_EQUAL_INT(uq, ubq);
    }
    /* the sum is clamped and flagged */
    pma_ppc_reset_f32(&b);
    pma_ppc_reset_q16(&bq);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_ext_f32(&b, 5.0f, -2.0f, 0.0f, -2.0f, 1000.0f, &u));
    TEST_ASSERT_TRUE(u == 400.0f && (b.out.flags & PMA_PPC_FLAG_SAT_HIGH));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_ext_q16(&bq, Q16(5.0), Q16(-2.0), 0, Q16(-2.0), Q16(1000.0), &uq));
    TEST_ASSERT_TRUE(uq == Q16(400.0) && (bq.out.flags & PMA_PPC_FLAG_SAT_HIGH));
    /* out of reach: e = +0.1 cm for good (v such that lambda2 = 0.1 cm/s: u_law = -1.4), the law
     * pushes u down; u_ext = +50 */
    pma_ppc_reset_f32(&b);
    pma_ppc_reset_q16(&bq);
    for (int k = 0; k < 10000; ++k) {
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_ext_f32(&b, 5.0f, -1.9f, -1.9f, -2.0f, 50.0f, &u));
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_ext_q16(&bq, Q16(5.0), Q16(-1.9), Q16(-1.9), Q16(-2.0), Q16(50.0), &uq));
    }
    TEST_ASSERT_TRUE(u == -400.0f && (b.out.flags & PMA_PPC_FLAG_SAT_LOW));
    TEST_ASSERT_TRUE(uq == Q16(-400.0) && (bq.out.flags & PMA_PPC_FLAG_SAT_LOW));
    TEST_ASSERT_TRUE(b.u_ff < -400.0f && b.u_ff >= -450.0f);     /* past u_min, by u_ext at most */
    assert_near(F16(bq.out.u_ff), b.u_ff, 0.5);
    /* the reference moves on (u_ext 80): the input goes back to its limit, not 30 above it */
    for (int k = 0; k < 100; ++k) {
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_ext_f32(&b, 5.0f, -1.9f, -1.9f, -2.0f, 80.0f, &u));
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_ext_q16(&bq, Q16(5.0), Q16(-1.9), Q16(-1.9), Q16(-2.0), Q16(80.0), &uq));
    }
    TEST_ASSERT_TRUE(u == -400.0f && uq == Q16(-400.0));
    TEST_ASSERT_TRUE(b.u_ff >= -480.0f);
    /* a non-finite u_ext is refused, state unchanged */
    const float held = b.u_ff;
    u = 7.0f;
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NOT_FINITE, pma_ppc_step_ext_f32(&b, 5.0f, -1.9f, -1.9f, -2.0f, NAN, &u));
    TEST_ASSERT_TRUE(u == 7.0f && b.u_ff == held);
}

static void expect_invalid(pma_ppc_config_t c, int want)
{
    pma_ppc_f32_t f;
    pma_ppc_q16_t q;
    pma_ppc_config_t good = case3();
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_f32(&f, &good));  /* was ready ... */
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_q16(&q, &good));
    TEST_ASSERT_EQUAL_INT(want, pma_ppc_validate_config(&c));
    TEST_ASSERT_EQUAL_INT(want, pma_ppc_init_f32(&f, &c));   /* ... now unusable */
    TEST_ASSERT_EQUAL_INT(want, pma_ppc_init_q16(&q, &c));
    float u = 123.0f;
    pma_q16_t uq = 123;
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NOT_READY, pma_ppc_step_f32(&f, 1.0f, 0.0f, 0.0f, 0.0f, &u));
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NOT_READY, pma_ppc_step_q16(&q, 0, 0, 0, 0, &uq));
    TEST_ASSERT_TRUE(u == 123.0f);
    TEST_ASSERT_EQUAL_INT(123, uq);
}

static void test_invalid_config(void)
{
    pma_ppc_config_t c;
#define BAD(field, value, code) do { c = case3(); c.field = (value); expect_invalid(c, code); } while (0)
    BAD(a_cm_s, 0.0f, PMA_ERR_RANGE);
    BAD(a_cm_s, -1.0f, PMA_ERR_RANGE);
    BAD(a_cm_s, NAN, PMA_ERR_NOT_FINITE);
    BAD(c, 0.0f, PMA_ERR_RANGE);
    BAD(c, INFINITY, PMA_ERR_NOT_FINITE);
    BAD(w1_cm, 0.0f, PMA_ERR_RANGE);
    BAD(w1_cm, -0.2f, PMA_ERR_RANGE);
    BAD(w2_cm_s, 0.0f, PMA_ERR_RANGE);
    BAD(w2_cm_s, NAN, PMA_ERR_NOT_FINITE);
    BAD(t_u_s, 0.0f, PMA_ERR_RANGE);
    BAD(t_u_s, -2.0f, PMA_ERR_RANGE);
    BAD(t_u_s, INFINITY, PMA_ERR_NOT_FINITE);
    BAD(u_min, 500.0f, PMA_ERR_RANGE);
    BAD(barrier_margin, 0.0f, PMA_ERR_RANGE);
    BAD(barrier_margin, 0.6f, PMA_ERR_RANGE);
    BAD(soft_barrier_r, 0.0f, PMA_ERR_RANGE);
    BAD(soft_barrier_r, 1.5f, PMA_ERR_RANGE);
    BAD(ff_gain_per_s, -1.0f, PMA_ERR_RANGE);
    BAD(ff_hold_speed_cm_s, -0.1f, PMA_ERR_RANGE);
    BAD(ff_hold_speed_cm_s, NAN, PMA_ERR_NOT_FINITE);
    BAD(ff_init, 1000.0f, PMA_ERR_RANGE);
    BAD(widen_r, 0.01f, PMA_ERR_RANGE);
    BAD(widen_r, -0.5f, PMA_ERR_RANGE);
    BAD(widen_r, 1.0f - 1e-3f, PMA_ERR_RANGE);   /* not below 1 - barrier_margin */
    BAD(widen_r, NAN, PMA_ERR_NOT_FINITE);
    BAD(period_s, 0.0f, PMA_ERR_RANGE);
    BAD(k_low_cm, NAN, PMA_ERR_NOT_FINITE);
    BAD(k_high_cm, -4.0f, PMA_ERR_RANGE);
    /* w1 does not fit the band: 2 w1 >= k_high - k_low */
    BAD(w1_cm, 1.5f, PMA_ERR_BAND);
    c = case3();
    c.k_low_cm = -0.3f;
    expect_invalid(c, PMA_ERR_BAND);
#undef BAD
    /* band disabled: its fields are not looked at */
    c = case3();
    c.band_enabled = 0;
    c.k_low_cm = NAN;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_validate_config(&c));
    /* fixed point only: reciprocals out of Q8.24 */
    c = case3();
    c.w1_cm = 0.01f;
    pma_ppc_q16_t q;
    pma_ppc_f32_t f;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_f32(&f, &c));
    TEST_ASSERT_EQUAL_INT(PMA_ERR_FIXED_RANGE, pma_ppc_init_q16(&q, &c));
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NULL, pma_ppc_init_f32(NULL, &c));
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NULL, pma_ppc_init_f32(&f, NULL));
}

/* Non-finite or negative-time inputs: an error, no output, no state change. */
static void test_bad_step_inputs(void)
{
    pma_ppc_config_t c = case3();
    c.ff_gain_per_s = 1.0f;
    pma_ppc_f32_t f;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_f32(&f, &c));
    float u = 0.0f;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_f32(&f, 3.0f, -1.9f, 0.5f, -2.0f, &u));
    const pma_ppc_f32_t before = f;
    float u2 = 77.0f;
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NOT_FINITE, pma_ppc_step_f32(&f, NAN, -1.9f, 0.5f, -2.0f, &u2));
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NOT_FINITE, pma_ppc_step_f32(&f, 3.0f, INFINITY, 0.5f, -2.0f, &u2));
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NOT_FINITE, pma_ppc_step_f32(&f, 3.0f, -1.9f, NAN, -2.0f, &u2));
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NOT_FINITE, pma_ppc_step_f32(&f, 3.0f, -1.9f, 0.5f, -INFINITY, &u2));
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NOT_FINITE, pma_ppc_step_f32(&f, 3.0f, 3e38f, 0.5f, -3e38f, &u2));
    TEST_ASSERT_EQUAL_INT(PMA_ERR_RANGE, pma_ppc_step_f32(&f, -0.001f, -1.9f, 0.5f, -2.0f, &u2));
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NULL, pma_ppc_step_f32(&f, 3.0f, -1.9f, 0.5f, -2.0f, NULL));
    TEST_ASSERT_TRUE(u2 == 77.0f);
    TEST_ASSERT_EQUAL_MEMORY(&before, &f, sizeof f);
    pma_ppc_q16_t q;
    pma_q16_t uq = 5;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_q16(&q, &c));
    TEST_ASSERT_EQUAL_INT(PMA_ERR_RANGE, pma_ppc_step_q16(&q, -1, 0, 0, 0, &uq));
    TEST_ASSERT_EQUAL_INT(5, uq);
    /* extreme but finite fixed-point inputs saturate instead of wrapping */
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_q16(&q, Q16(9.0), PMA_Q16_MAX, PMA_Q16_MAX, PMA_Q16_MIN, &uq));
    TEST_ASSERT_EQUAL_INT(Q16(c.u_min), uq);
}

/* Float and fixed point agree over a sweep of the operating region. */
static void test_fixed_matches_float(void)
{
    pma_ppc_config_t c = case3();
    pma_ppc_f32_t f;
    pma_ppc_q16_t q;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_f32(&f, &c));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_init_q16(&q, &c));
    uint32_t seed = 12345u;
    double worst = 0.0;
    for (int k = 0; k < 4000; ++k) {
        const float t = (float)F16(Q16(k * 0.001));
        const float e = (float)F16(Q16(0.15 * test_rand_uniform(&seed)));
        const float v = (float)F16(Q16(0.8 * test_rand_uniform(&seed)));
        float u;
        pma_q16_t uq;
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_f32(&f, t, -2.0f + e, v, -2.0f, &u));
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ppc_step_q16(&q, Q16(t), Q16(-2.0f + e), Q16(v), Q16(-2.0), &uq));
        const double d = fabs(F16(uq) - u) / (c.u_max - c.u_min);
        if (d > worst) worst = d;
    }
    printf("ppc fixed vs float: max |du| = %.4f %% of the input range\n", worst * 100);
    TEST_ASSERT_LESS_THAN_DOUBLE(0.0005, worst);  /* 0.05 % of the range; measured 0.026 % */
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_bumpless_start);
    RUN_TEST(test_alpha_profile);
    RUN_TEST(test_law_direction_and_equations);
    RUN_TEST(test_barrier_clamp);
    RUN_TEST(test_velocity_funnel_widens_after_a_run);
    RUN_TEST(test_soft_barrier);
    RUN_TEST(test_funnel_widening);
    RUN_TEST(test_feedforward);
    RUN_TEST(test_feedforward_holds_while_closing);
    RUN_TEST(test_external_input);
    RUN_TEST(test_invalid_config);
    RUN_TEST(test_bad_step_inputs);
    RUN_TEST(test_fixed_matches_float);
    return UNITY_END();
}
