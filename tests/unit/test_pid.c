/* SPDX-License-Identifier: Apache-2.0 */
/* PID baseline (pma/pid.h): terms, derivative on measurement and its filter,
 * anti-windup, validation, float/fixed agreement. */
#include "test_util.h"
#include "pma/pid.h"
#include "pma/status.h"

static pma_pid_config_t cfg(float kp, float ki, float kd, float tf, float kaw)
{
    return (pma_pid_config_t){.kp = kp, .ki = ki, .kd = kd, .tf_s = tf, .k_aw_per_s = kaw,
                              .period_s = 1e-3f, .u_min = -100.0f, .u_max = 100.0f};
}

static void test_proportional_and_integral(void)
{
    pma_pid_config_t c = cfg(10.0f, 50.0f, 0.0f, 0.0f, 0.0f);
    pma_pid_f32_t p;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_pid_init_f32(&p, &c));
    float u;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_pid_step_f32(&p, -1.0f, -1.5f, &u));
    assert_near(u, 5.0, 1e-6);                       /* I starts at 0 */
    for (int k = 0; k < 999; ++k) TEST_ASSERT_EQUAL_INT(PMA_OK, pma_pid_step_f32(&p, -1.0f, -1.5f, &u));
    assert_near(u, 5.0 + 50.0 * 0.5 * 0.999, 1e-3);  /* 999 integrated steps of ki e T */
}

/* A reference step gives no derivative kick; a measurement step does, and
 * the filter spreads it (first value kd/(tf+T) times the step). */
static void test_derivative_on_measurement(void)
{
    pma_pid_config_t c = cfg(0.0f, 0.0f, 0.5f, 0.009f, 0.0f);
    pma_pid_f32_t p;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_pid_init_f32(&p, &c));
    float u;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_pid_step_f32(&p, 0.0f, -2.0f, &u));
    assert_near(u, 0.0, 0.0);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_pid_step_f32(&p, 1.0f, -2.0f, &u));  /* reference step */
    assert_near(u, 0.0, 0.0);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_pid_step_f32(&p, 1.0f, -1.9f, &u));  /* measurement +0.1 */
    assert_near(u, -0.5 / 0.01 * 0.1, 1e-4);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_pid_step_f32(&p, 1.0f, -1.9f, &u));  /* decays by tf/(tf+T) */
    assert_near(u, -0.5 / 0.01 * 0.1 * 0.9, 1e-4);
    /* tf = 0: plain backward difference */
    c.tf_s = 0.0f;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_pid_init_f32(&p, &c));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_pid_step_f32(&p, 0.0f, 0.0f, &u));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_pid_step_f32(&p, 0.0f, 0.001f, &u));
    assert_near(u, -0.5, 1e-4);
}

/* Anti-windup. While the output is saturated the integrator (a) never leaves
 * the output limits, and (b) with back-calculation settles where
 * ki e + k_aw (u_max - v) = 0, i.e. I = u_max - kp e + ki e / k_aw; both
 * variants agree. */
static void test_anti_windup(void)
{
    pma_pid_config_t c = cfg(20.0f, 200.0f, 0.0f, 0.0f, 0.0f);
    pma_pid_f32_t p;
    pma_pid_q16_t q;
    float u;
    pma_q16_t uq;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_pid_init_f32(&p, &c));
    for (int k = 0; k < 3000; ++k) TEST_ASSERT_EQUAL_INT(PMA_OK, pma_pid_step_f32(&p, 10.0f, 0.0f, &u));
    TEST_ASSERT_TRUE(u == 100.0f && (p.flags & PMA_PID_FLAG_SAT_HIGH));
    assert_near(p.i, 100.0, 0.0);                  /* clamped at the limit, not beyond */
    c.k_aw_per_s = 50.0f;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_pid_init_f32(&p, &c));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_pid_init_q16(&q, &c));
    for (int k = 0; k < 3000; ++k) {
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_pid_step_f32(&p, 10.0f, 0.0f, &u));
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_pid_step_q16(&q, Q16(10.0), 0, &uq));
    }
    TEST_ASSERT_TRUE(u == 100.0f);
    assert_near(p.i, 100.0 - 200.0 + 200.0 * 10.0 / 50.0, 1e-3);   /* -60 */
    assert_near(q.i_q32 / 4294967296.0, p.i, 1e-3);
}

static void test_invalid_and_bad_input(void)
{
    pma_pid_f32_t p;
    pma_pid_q16_t q;
    pma_pid_config_t c = cfg(1.0f, 1.0f, 1.0f, 0.01f, 1.0f);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_pid_init_f32(&p, &c));
    c.kp = -1.0f;
    TEST_ASSERT_EQUAL_INT(PMA_ERR_RANGE, pma_pid_init_f32(&p, &c));
    float u = 3.0f;
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NOT_READY, pma_pid_step_f32(&p, 0.0f, 0.0f, &u));
    c = cfg(1.0f, NAN, 1.0f, 0.01f, 1.0f);
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NOT_FINITE, pma_pid_init_f32(&p, &c));
    c = cfg(1.0f, 1.0f, 1.0f, -0.01f, 1.0f);
    TEST_ASSERT_EQUAL_INT(PMA_ERR_RANGE, pma_pid_init_q16(&q, &c));
    c = cfg(1.0f, 1.0f, 1.0f, 0.01f, 1.0f);
    c.period_s = 0.0f;
    TEST_ASSERT_EQUAL_INT(PMA_ERR_RANGE, pma_pid_init_f32(&p, &c));
    c = cfg(1.0f, 1.0f, 1.0f, 0.01f, 1.0f);
    c.u_min = c.u_max;
    TEST_ASSERT_EQUAL_INT(PMA_ERR_RANGE, pma_pid_init_f32(&p, &c));
    c = cfg(1.0f, 5000.0f, 1.0f, 0.01f, 1.0f);    /* ki T = 5 fits Q8.24 */
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_pid_init_f32(&p, &c));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_pid_init_q16(&q, &c));
    c = cfg(1.0f, 130000.0f, 1.0f, 0.01f, 1.0f);  /* ki T = 130 does not */
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_pid_init_f32(&p, &c));
    TEST_ASSERT_EQUAL_INT(PMA_ERR_FIXED_RANGE, pma_pid_init_q16(&q, &c));
    c = cfg(1.0f, 1.0f, 1.0f, 0.01f, 1.0f);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_pid_init_f32(&p, &c));
    const pma_pid_f32_t before = p;
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NOT_FINITE, pma_pid_step_f32(&p, NAN, 0.0f, &u));
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NOT_FINITE, pma_pid_step_f32(&p, 0.0f, -INFINITY, &u));
    TEST_ASSERT_EQUAL_MEMORY(&before, &p, sizeof p);
    TEST_ASSERT_TRUE(u == 3.0f);
}

/* Closed loop on a second-order plant: fixed point follows float, and the
 * integrator's late increments (ki T e ~ 1e-6, below one Q16.16 LSB) are not
 * lost: zero steady-state error in both. */
static void test_closed_loop_fixed_matches_float(void)
{
    pma_pid_config_t c = cfg(30.0f, 20.0f, 0.5f, 0.005f, 10.0f);
    pma_pid_f32_t p;
    pma_pid_q16_t q;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_pid_init_f32(&p, &c));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_pid_init_q16(&q, &c));
    double xf = -2.0, vf = 0.0, xq = -2.0, vq = 0.0, worst = 0.0;
    const double T = 1e-3;
    for (int k = 0; k < 20000; ++k) {
        float u;
        pma_q16_t uq;
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_pid_step_f32(&p, -1.5f, (float)xf, &u));
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_pid_step_q16(&q, Q16(-1.5), Q16(xq), &uq));
        /* x'' = 5 u - 20 x' - 50 (x + 2): needs u = 5 at x = -1.5 */
        const double af = 5.0 * u - 20.0 * vf - 50.0 * (xf + 2.0);
        const double aq = 5.0 * F16(uq) - 20.0 * vq - 50.0 * (xq + 2.0);
        vf += T * af; xf += T * vf;
        vq += T * aq; xq += T * vq;
        worst = fmax(worst, fabs(F16(uq) - u) / (c.u_max - c.u_min));
    }
    printf("pid closed loop: fixed vs float max |du| %.4f %% of range; final e %.2e / %.2e cm\n",
           worst * 100, xf + 1.5, xq + 1.5);
    TEST_ASSERT_LESS_THAN_DOUBLE(0.001, worst);
    assert_near(xf, -1.5, 1e-3);
    assert_near(xq, -1.5, 1e-3);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_proportional_and_integral);
    RUN_TEST(test_derivative_on_measurement);
    RUN_TEST(test_anti_windup);
    RUN_TEST(test_invalid_and_bad_input);
    RUN_TEST(test_closed_loop_fixed_matches_float);
    return UNITY_END();
}
