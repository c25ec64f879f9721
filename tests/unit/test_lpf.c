/* SPDX-License-Identifier: Apache-2.0 */
/* First-order low-pass (pma/lpf.h): priming, the step response against its closed form, off as
 * pass-through, staying between the last output and the input, validation, Q16.16 against float. */
#include "test_util.h"
#include "pma/lpf.h"
#include "pma/status.h"

#define PI 3.14159265358979323846

static uint32_t seed = 57u;

/* uniform in [lo, hi) */
static double rand_in(double lo, double hi)
{
    return lo + 0.5 * (test_rand_uniform(&seed) + 1.0) * (hi - lo);
}

static pma_lpf_config_t lcfg(float fc_hz)
{
    return (pma_lpf_config_t){.fc_hz = fc_hz, .period_s = 1e-3f};
}

/* The first sample primes (no start transient); a step then follows
 * y(n) = x1 + (x0 - x1) exp(-2 pi fc T n), in both arithmetics. */
static void test_step_response(void)
{
    const pma_lpf_config_t c = lcfg(10.0f);
    pma_lpf_f32_t f;
    pma_lpf_q16_t q;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_lpf_init_f32(&f, &c));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_lpf_init_q16(&q, &c));
    TEST_ASSERT_TRUE(pma_lpf_step_f32(&f, -120.0f) == -120.0f);
    TEST_ASSERT_EQUAL_INT32(Q16(-120.0), pma_lpf_step_q16(&q, Q16(-120.0)));
    for (int n = 1; n <= 300; ++n) {
        const double want = 80.0 - 200.0 * exp(-2.0 * PI * 10.0 * 1e-3 * n);
        assert_near(pma_lpf_step_f32(&f, 80.0f), want, 2e-3);
        assert_near(F16(pma_lpf_step_q16(&q, Q16(80.0))), want, 2e-3);
    }
}

/* fc = 0 is off: every sample passes as it is, NaN included. */
static void test_off_passes_through(void)
{
    const pma_lpf_config_t c = lcfg(0.0f);
    pma_lpf_f32_t f;
    pma_lpf_q16_t q;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_lpf_init_f32(&f, &c));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_lpf_init_q16(&q, &c));
    for (int k = 0; k < 50; ++k) {
        const float x = (float)rand_in(-400.0, 400.0);
        TEST_ASSERT_TRUE(pma_lpf_step_f32(&f, x) == x);
        TEST_ASSERT_EQUAL_INT32(Q16(x), pma_lpf_step_q16(&q, Q16(x)));
    }
    TEST_ASSERT_TRUE(isnan(pma_lpf_step_f32(&f, NAN)));
}

/* Every output lies between the last output and the input (a filtered command stays inside its
 * inputs' range), in both arithmetics, at cut-offs from slow to beyond Nyquist; and a NaN input
 * passes through without touching the state. */
static void test_output_between_last_and_input(void)
{
    static const float fcs[] = {0.5f, 25.0f, 400.0f, 5000.0f};
    for (size_t i = 0; i < sizeof fcs / sizeof fcs[0]; ++i) {
        const pma_lpf_config_t c = lcfg(fcs[i]);
        pma_lpf_f32_t f;
        pma_lpf_q16_t q;
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_lpf_init_f32(&f, &c));
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_lpf_init_q16(&q, &c));
        float y = pma_lpf_step_f32(&f, 0.0f);
        pma_q16_t yq = pma_lpf_step_q16(&q, 0);
        for (int k = 0; k < 2000; ++k) {
            const float x = (float)rand_in(-32000.0, 32000.0);
            const float y1 = pma_lpf_step_f32(&f, x);
            TEST_ASSERT_TRUE(y1 >= fminf(y, x) && y1 <= fmaxf(y, x));
            const pma_q16_t xq = Q16(x), yq1 = pma_lpf_step_q16(&q, xq);
            TEST_ASSERT_TRUE(yq1 >= (yq < xq ? yq : xq) && yq1 <= (yq > xq ? yq : xq));
            y = y1;
            yq = yq1;
        }
        TEST_ASSERT_TRUE(isnan(pma_lpf_step_f32(&f, NAN)));
        TEST_ASSERT_TRUE(pma_lpf_step_f32(&f, y) == y);   /* the state was not touched */
    }
}

/* Reset forgets the history: the next sample primes again. */
static void test_reset_primes_again(void)
{
    const pma_lpf_config_t c = lcfg(5.0f);
    pma_lpf_f32_t f;
    pma_lpf_q16_t q;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_lpf_init_f32(&f, &c));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_lpf_init_q16(&q, &c));
    (void)pma_lpf_step_f32(&f, 10.0f);
    (void)pma_lpf_step_q16(&q, Q16(10.0));
    TEST_ASSERT_TRUE(pma_lpf_step_f32(&f, 50.0f) < 50.0f);
    pma_lpf_reset_f32(&f);
    pma_lpf_reset_q16(&q);
    TEST_ASSERT_TRUE(pma_lpf_step_f32(&f, -7.0f) == -7.0f);
    TEST_ASSERT_EQUAL_INT32(Q16(-7.0), pma_lpf_step_q16(&q, Q16(-7.0)));
}

static void test_invalid(void)
{
    pma_lpf_f32_t f;
    pma_lpf_q16_t q;
    const pma_lpf_config_t bad[] = {
        {.fc_hz = -1.0f, .period_s = 1e-3f}, {.fc_hz = 10.0f, .period_s = 0.0f},
        {.fc_hz = 10.0f, .period_s = -1e-3f}, {.fc_hz = NAN, .period_s = 1e-3f},
        {.fc_hz = 10.0f, .period_s = INFINITY},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        TEST_ASSERT_NOT_EQUAL_INT(PMA_OK, pma_lpf_init_f32(&f, &bad[i]));
        TEST_ASSERT_NOT_EQUAL_INT(PMA_OK, pma_lpf_init_q16(&q, &bad[i]));
        /* refused: off (k 0), the input passes as it is */
        TEST_ASSERT_TRUE(f.k == 0.0f && q.k == 0);
        TEST_ASSERT_TRUE(pma_lpf_step_f32(&f, 3.0f) == 3.0f);
        TEST_ASSERT_EQUAL_INT32(3 * PMA_Q16_ONE, pma_lpf_step_q16(&q, 3 * PMA_Q16_ONE));
    }
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NULL, pma_lpf_init_f32(NULL, &bad[0]));
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NULL, pma_lpf_init_f32(&f, NULL));
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NULL, pma_lpf_init_q16(&q, NULL));
}

/* A noisy command: Q16.16 follows float within a few LSB of rounding per step. */
static void test_fixed_matches_float(void)
{
    const pma_lpf_config_t c = lcfg(20.0f);
    pma_lpf_f32_t f;
    pma_lpf_q16_t q;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_lpf_init_f32(&f, &c));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_lpf_init_q16(&q, &c));
    double worst = 0.0;
    for (int k = 0; k < 20000; ++k) {
        const float x = (float)(150.0 * sin(2.0 * PI * 3.0 * k * 1e-3) + rand_in(-20.0, 20.0));
        const float y = pma_lpf_step_f32(&f, x);
        const pma_q16_t yq = pma_lpf_step_q16(&q, Q16(x));
        worst = fmax(worst, fabs(F16(yq) - y));
    }
    printf("lpf: fixed vs float max |dy| %.2e\n", worst);
    TEST_ASSERT_LESS_THAN_DOUBLE(1e-3, worst);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_step_response);
    RUN_TEST(test_off_passes_through);
    RUN_TEST(test_output_between_last_and_input);
    RUN_TEST(test_reset_primes_again);
    RUN_TEST(test_invalid);
    RUN_TEST(test_fixed_matches_float);
    return UNITY_END();
}
