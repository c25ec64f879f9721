/* SPDX-License-Identifier: Apache-2.0 */
/* CFDL-MFAC (pma/mfac.h): reset rule, first step, limits, validation, and
 * float/fixed agreement. */
#include "test_util.h"
#include "pma/mfac.h"
#include "pma/status.h"

static pma_mfac_config_t paper(void)
{
    pma_mfac_config_t c;
    pma_mfac_default_config(&c);
    return c;
}

/* Step 0: du = 0 -> reset to phi(1); u = u_init + rho phi1/(lambda + phi1^2) (y* - y). */
static void test_first_step(void)
{
    pma_mfac_config_t c = paper();
    c.u_init = 5.0f;
    pma_mfac_f32_t m;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_init_f32(&m, &c));
    float u;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_step_f32(&m, -2.0f, -1.99f, &u));
    TEST_ASSERT_TRUE(m.flags & PMA_MFAC_FLAG_RESET);
    assert_near(m.phi, 0.5, 0.0);
    assert_near(u, 5.0 + 31.7 * 0.5 / (0.03 + 0.25) * 0.01, 1e-4);
    TEST_ASSERT_EQUAL_INT(1, m.resets);
}

/* Drive the estimator to a chosen state, then check each reset condition
 * alone: |du| <= eps, |phi| <= eps, sign(phi) != sign(phi1). */
static void test_reset_conditions(void)
{
    pma_mfac_config_t c = paper();
    pma_mfac_f32_t m;
    float u;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_init_f32(&m, &c));

    /* no reset: du != 0, dy consistent with a positive gain */
    m.k = 1; m.phi = 0.4f; m.u1 = 2.0f; m.u2 = 1.0f; m.y1 = -2.0f;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_step_f32(&m, -1.6f, -1.6f, &u));
    TEST_ASSERT_EQUAL_HEX32(0, m.flags & PMA_MFAC_FLAG_RESET);
    /* phi = 0.4 + 0.5*1/(1.9+1)*(0.4 - 0.4) = 0.4 */
    assert_near(m.phi, 0.4, 1e-6);

    /* |du| <= eps: reset */
    m.k = 1; m.phi = 0.4f; m.u1 = 2.0f; m.u2 = 2.0f + 0.5e-5f; m.y1 = -2.0f;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_step_f32(&m, -1.9f, -1.9f, &u));
    TEST_ASSERT_TRUE(m.flags & PMA_MFAC_FLAG_RESET);
    assert_near(m.phi, c.phi1, 0.0);

    /* sign flip: output moved against the input -> phi would turn negative */
    m.k = 1; m.phi = 0.1f; m.u1 = 2.0f; m.u2 = 1.0f; m.y1 = -2.0f;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_step_f32(&m, -3.0f, -3.0f, &u));
    TEST_ASSERT_TRUE(m.flags & PMA_MFAC_FLAG_RESET);
    assert_near(m.phi, c.phi1, 0.0);

    /* |phi| <= eps without a sign flip: phi lands on ~0 (+) */
    c.eps = 1e-3f;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_init_f32(&m, &c));
    /* phi = 0.1 + 0.5/(2.9) (dy - 0.1) = 0.0005 when dy = 0.1 - 0.0995*2.9/0.5 */
    const float dy = 0.1f - (0.1f - 0.0005f) * 2.9f / 0.5f;
    m.k = 1; m.phi = 0.1f; m.u1 = 2.0f; m.u2 = 1.0f; m.y1 = -2.0f;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_step_f32(&m, -2.0f + dy, -2.0f, &u));
    TEST_ASSERT_TRUE(m.flags & PMA_MFAC_FLAG_RESET);
    assert_near(m.phi, c.phi1, 0.0);
}

static void test_limits(void)
{
    pma_mfac_config_t c = paper();
    pma_mfac_f32_t m;
    pma_mfac_q16_t q;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_init_f32(&m, &c));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_init_q16(&q, &c));
    float u;
    pma_q16_t uq;
    /* a large error saturates high, and the clamped value is the one remembered */
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_step_f32(&m, -2.0f, 10.0f, &u));
    TEST_ASSERT_TRUE(u == c.u_max && (m.flags & PMA_MFAC_FLAG_SAT_HIGH));
    TEST_ASSERT_TRUE(m.u1 == c.u_max);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_step_q16(&q, Q16(-2.0), Q16(10.0), &uq));
    TEST_ASSERT_EQUAL_INT(Q16(c.u_max), uq);
    TEST_ASSERT_TRUE(q.flags & PMA_MFAC_FLAG_SAT_HIGH);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_step_f32(&m, -2.0f, -20.0f, &u));
    TEST_ASSERT_TRUE(u == c.u_min && (m.flags & PMA_MFAC_FLAG_SAT_LOW));
    /* NaN: error, nothing changes */
    const pma_mfac_f32_t before = m;
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NOT_FINITE, pma_mfac_step_f32(&m, NAN, -2.0f, &u));
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NOT_FINITE, pma_mfac_step_f32(&m, -2.0f, INFINITY, &u));
    TEST_ASSERT_EQUAL_MEMORY(&before, &m, sizeof m);
}

static void test_invalid_config(void)
{
    pma_mfac_config_t c;
    pma_mfac_f32_t m;
    pma_mfac_q16_t q;
#define BAD(field, value, code)                                                   \
    do {                                                                          \
        c = paper();                                                              \
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_init_f32(&m, &c));                 \
        c.field = (value);                                                        \
        TEST_ASSERT_EQUAL_INT(code, pma_mfac_init_f32(&m, &c));                   \
        TEST_ASSERT_EQUAL_INT(code, pma_mfac_init_q16(&q, &c));                   \
        float u_;                                                                 \
        TEST_ASSERT_EQUAL_INT(PMA_ERR_NOT_READY, pma_mfac_step_f32(&m, 0.0f, 0.0f, &u_)); \
    } while (0)
    BAD(eta, 0.0f, PMA_ERR_RANGE);
    BAD(eta, 2.5f, PMA_ERR_RANGE);
    BAD(eta, NAN, PMA_ERR_NOT_FINITE);
    BAD(mu, 0.0f, PMA_ERR_RANGE);
    BAD(mu, -1.0f, PMA_ERR_RANGE);
    BAD(rho, 0.0f, PMA_ERR_RANGE);
    BAD(rho, INFINITY, PMA_ERR_NOT_FINITE);
    BAD(lambda, 0.0f, PMA_ERR_RANGE);
    BAD(eps, -1e-5f, PMA_ERR_RANGE);
    BAD(phi1, 0.0f, PMA_ERR_RANGE);
    BAD(u_max, -500.0f, PMA_ERR_RANGE);
    BAD(u_init, 1000.0f, PMA_ERR_RANGE);
#undef BAD
    c = paper();
    c.u_max = 1e6f;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_init_f32(&m, &c));
    TEST_ASSERT_EQUAL_INT(PMA_ERR_FIXED_RANGE, pma_mfac_init_q16(&q, &c));
    /* phi1 in Q8.24: |phi1| < 127 */
    c = paper();
    c.phi1 = -126.0f;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_init_q16(&q, &c));
    c.phi1 = 200.0f;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_init_f32(&m, &c));
    TEST_ASSERT_EQUAL_INT(PMA_ERR_FIXED_RANGE, pma_mfac_init_q16(&q, &c));
}

/* Closed loop on a first-order plant: float and fixed point stay together
 * and both track a slow sine. */
static void test_closed_loop_fixed_matches_float(void)
{
    pma_mfac_config_t c = paper();
    pma_mfac_f32_t m;
    pma_mfac_q16_t q;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_init_f32(&m, &c));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_init_q16(&q, &c));
    double yf = -2.0, yq = -2.0, worst_u = 0.0, worst_e = 0.0;
    for (int k = 0; k < 3000; ++k) {
        const double t = k * 0.01;
        const double ref_next = -2.0 + 0.3 * sin(0.5 * (t + 0.01));
        float u;
        pma_q16_t uq;
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_step_f32(&m, (float)yf, (float)ref_next, &u));
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_step_q16(&q, Q16(yq), Q16(ref_next), &uq));
        /* plant: y(k+1) = 0.9 y(k) + 0.004 u(k) - 0.2 (equilibrium at u = 0: y = -2) */
        yf = 0.9 * yf + 0.004 * u - 0.2;
        yq = 0.9 * yq + 0.004 * F16(uq) - 0.2;
        if (k > 500) {
            worst_u = fmax(worst_u, fabs(F16(uq) - u) / (c.u_max - c.u_min));
            worst_e = fmax(worst_e, fabs(yf - ref_next));
        }
    }
    printf("mfac closed loop: fixed vs float max |du| %.4f %% of range, float max |e| %.4f cm\n",
           worst_u * 100, worst_e);
    TEST_ASSERT_LESS_THAN_DOUBLE(0.005, worst_u);
    TEST_ASSERT_LESS_THAN_DOUBLE(0.05, worst_e);
}

/* The same closed loop with a small pseudo partial derivative, as commissioning derives on a
 * muscle (phi1 0.015 cm/kPa, a plant of 0.01 cm/kPa that answers late): the estimator drives
 * phi towards 1e-4 and back, where Q16.16 would hold it to a few LSB and lose the small term
 * of the innovation (phi stuck, MFAC five times worse than float); in Q8.24 the fixed-point
 * loop stays with the float one. */
static void test_closed_loop_small_phi_fixed_matches_float(void)
{
    pma_mfac_config_t c = paper();
    c.phi1 = 0.015f;
    c.u_min = -500.0f;
    c.u_max = 500.0f;
    pma_mfac_f32_t m;
    pma_mfac_q16_t q;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_init_f32(&m, &c));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_init_q16(&q, &c));
    /* plant: a 5-tick dead time, then y(k+1) = 0.995 y(k) + 5e-5 u (0.01 cm/kPa) */
    double yf = 0.0, yq = 0.0, uf_hist[5] = {0}, uq_hist[5] = {0}, ef2 = 0.0, eq2 = 0.0;
    double phi_min = 1.0;
    for (int k = 0; k < 6000; ++k) {
        const double ref_next = 0.5 + 0.3 * sin(2.0 * 3.14159265358979 * 0.05 * (k + 1) * 0.001);
        float u;
        pma_q16_t uq;
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_step_f32(&m, (float)yf, (float)ref_next, &u));
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_step_q16(&q, Q16(yq), Q16(ref_next), &uq));
        phi_min = fmin(phi_min, (double)q.phi_q24 / 16777216.0);
        const double uf_late = uf_hist[k % 5], uq_late = uq_hist[k % 5];
        uf_hist[k % 5] = u;
        uq_hist[k % 5] = F16(uq);
        yf = 0.995 * yf + 5e-5 * uf_late;
        yq = 0.995 * yq + 5e-5 * uq_late;
        if (k >= 3000) {
            ef2 += (yf - ref_next) * (yf - ref_next);
            eq2 += (yq - ref_next) * (yq - ref_next);
        }
    }
    const double rf = sqrt(ef2 / 3000.0), rq = sqrt(eq2 / 3000.0);
    printf("mfac small phi: RMS error float %.5f cm, fixed %.5f cm, fixed phi down to %.2e\n", rf, rq, phi_min);
    TEST_ASSERT_TRUE(phi_min < 2e-3);            /* the estimator went where Q16.16 is coarse */
    TEST_ASSERT_LESS_THAN_DOUBLE(1.2 * rf + 1e-4, rq);
}

/* take over: after MFAC's own steps on a plant whose gain is not phi(1) (phi moved off it), the
 * next step starts from u_start (clamped to the limits) and from phi(1), in both arithmetics */
static void test_take_over_starts_from_u_start_and_phi1(void)
{
    pma_mfac_config_t c = paper();
    pma_mfac_f32_t m;
    pma_mfac_q16_t q;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_init_f32(&m, &c));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_init_q16(&q, &c));
    double y = -2.0, yq = -2.0;
    for (int k = 0; k < 300; ++k) {   /* y = -2 + 0.02 u, a ramp reference */
        float u;
        pma_q16_t uq;
        const double ref = -2.0 + 0.002 * (k + 1);
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_step_f32(&m, (float)y, (float)ref, &u));
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_step_q16(&q, Q16(yq), Q16(ref), &uq));
        y = -2.0 + 0.02 * u;
        yq = -2.0 + 0.02 * (uq / 65536.0);
    }
    const double y_end = y;
    TEST_ASSERT_TRUE(fabsf(m.phi - c.phi1) > 0.1f);   /* learned: off phi(1) */
    TEST_ASSERT_TRUE(fabs((q.phi_q24 - q.phi1_q24) / 16777216.0) > 0.1);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_take_over_f32(&m, 12.5f));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_take_over_q16(&q, Q16(12.5)));
    float u;
    pma_q16_t uq;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_step_f32(&m, (float)y_end, (float)(y_end + 0.01), &u));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_step_q16(&q, Q16(y_end), Q16(y_end + 0.01), &uq));
    const double expect = 12.5 + 31.7 * 0.5 / (0.03 + 0.25) * 0.01;   /* phi(1) = 0.5 */
    TEST_ASSERT_TRUE(m.flags & PMA_MFAC_FLAG_RESET);
    TEST_ASSERT_TRUE(q.flags & PMA_MFAC_FLAG_RESET);
    assert_near(m.phi, 0.5, 0.0);
    assert_near(u, expect, 1e-4);
    assert_near(uq / 65536.0, expect, 2e-3);
    /* beyond the limits: clamped; non-finite: refused, state unchanged */
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_take_over_f32(&m, 1e6f));
    assert_near(m.u1, c.u_max, 0.0);
    assert_near(m.u2, c.u_max, 0.0);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_mfac_take_over_q16(&q, Q16(-1e4)));
    TEST_ASSERT_EQUAL_INT32(Q16(c.u_min), q.u1);
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NOT_FINITE, pma_mfac_take_over_f32(&m, NAN));
    assert_near(m.u1, c.u_max, 0.0);
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NULL, pma_mfac_take_over_q16(NULL, 0));
    pma_mfac_f32_t idle = {0};
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NOT_READY, pma_mfac_take_over_f32(&idle, 0.0f));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_first_step);
    RUN_TEST(test_reset_conditions);
    RUN_TEST(test_limits);
    RUN_TEST(test_invalid_config);
    RUN_TEST(test_closed_loop_fixed_matches_float);
    RUN_TEST(test_closed_loop_small_phi_fixed_matches_float);
    RUN_TEST(test_take_over_starts_from_u_start_and_phi1);
    return UNITY_END();
}
