/* SPDX-License-Identifier: Apache-2.0 */
/* Velocity estimators (pma/velest.h): ramp tracking, noise gain against the
 * documented formula, priming, validation, float/fixed agreement. */
#include "test_util.h"
#include "pma/velest.h"
#include "pma/status.h"

#define PI 3.14159265358979323846

static pma_velest_config_t vcfg(uint8_t kind, float fc)
{
    return (pma_velest_config_t){.kind = kind, .fc_hz = fc, .period_s = 1e-3f};
}

/* Ramp of 2 cm/s: the tracking observer converges to the slope exactly,
 * the filtered difference too (after its lag), both variants. */
static void test_ramp(void)
{
    for (uint8_t kind = 0; kind < 2; ++kind) {
        pma_velest_config_t c = vcfg(kind, 20.0f);
        pma_velest_f32_t f;
        pma_velest_q16_t q;
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_velest_init_f32(&f, &c));
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_velest_init_q16(&q, &c));
        float v = 1.0f;
        pma_q16_t vq;
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_velest_step_f32(&f, -2.0f, &v));
        TEST_ASSERT_TRUE(v == 0.0f);                 /* first sample primes: no kick */
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_velest_step_q16(&q, Q16(-2.0), &vq));
        for (int k = 1; k <= 1000; ++k) {
            const double x = -2.0 + 2.0 * k * 1e-3;
            TEST_ASSERT_EQUAL_INT(PMA_OK, pma_velest_step_f32(&f, (float)x, &v));
            TEST_ASSERT_EQUAL_INT(PMA_OK, pma_velest_step_q16(&q, Q16(x), &vq));
        }
        assert_near(v, 2.0, 2e-3);
        assert_near(F16(vq), 2.0, 5e-3);
    }
}

/* White position noise: the measured std of v matches the documented noise
 * gain (exact closed form for the filtered difference) within 5 %. */
static void test_noise_gain(void)
{
    const double sigma = 0.001;   /* cm, Baumer-class sensor noise */
    for (uint8_t kind = 0; kind < 2; ++kind) {
        pma_velest_config_t c = vcfg(kind, 30.0f);
        pma_velest_f32_t f;
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_velest_init_f32(&f, &c));
        uint32_t seed = 2024u + kind;
        double sum = 0.0, sum2 = 0.0;
        int n = 0;
        for (int k = 0; k < 60000; ++k) {
            float v;
            TEST_ASSERT_EQUAL_INT(PMA_OK, pma_velest_step_f32(&f, (float)(-2.0 + sigma * test_rand_gauss(&seed)), &v));
            if (k >= 1000) {
                sum += v;
                sum2 += (double)v * v;
                ++n;
            }
        }
        const double std = sqrt(sum2 / n - (sum / n) * (sum / n));
        const double predicted = sigma * pma_velest_noise_gain(&c);
        printf("%s, fc 30 Hz: velocity noise %.4f cm/s, predicted %.4f cm/s\n",
               kind ? "tracking" : "filtered difference", std, predicted);
        assert_near(std, predicted, 0.05 * predicted);
    }
    /* the closed form of the filtered difference */
    pma_velest_config_t c = vcfg(PMA_VELEST_FILTERED_DIFF, 30.0f);
    const double p = exp(-2 * PI * 30.0 * 1e-3);
    assert_near(pma_velest_noise_gain(&c), (1 - p) / 1e-3 * sqrt(2 / (1 + p)), 1e-2);
    /* noise gain rises with bandwidth */
    pma_velest_config_t c2 = vcfg(PMA_VELEST_FILTERED_DIFF, 60.0f);
    TEST_ASSERT_GREATER_THAN_DOUBLE(pma_velest_noise_gain(&c), pma_velest_noise_gain(&c2));
}

/* Sine of 1 Hz, 0.5 cm: amplitude and phase lag as the first-order filter
 * predicts for the filtered difference (|H| = 1/sqrt(1 + (f/fc)^2)). */
static void test_sine_response(void)
{
    pma_velest_config_t c = vcfg(PMA_VELEST_FILTERED_DIFF, 10.0f);
    pma_velest_f32_t f;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_velest_init_f32(&f, &c));
    double peak = 0.0;
    for (int k = 0; k < 3000; ++k) {
        float v;
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_velest_step_f32(&f, (float)(0.5 * sin(2 * PI * k * 1e-3)), &v));
        if (k > 1000) peak = fmax(peak, v);
    }
    const double want = 0.5 * 2 * PI / sqrt(1.0 + 0.01);
    assert_near(peak, want, 0.01 * want);
}

static void test_invalid(void)
{
    pma_velest_f32_t f;
    pma_velest_q16_t q;
    pma_velest_config_t c = vcfg(PMA_VELEST_FILTERED_DIFF, 500.0f);   /* Nyquist */
    TEST_ASSERT_EQUAL_INT(PMA_ERR_RANGE, pma_velest_init_f32(&f, &c));
    float v = 9.0f;
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NOT_READY, pma_velest_step_f32(&f, 0.0f, &v));
    c = vcfg(PMA_VELEST_FILTERED_DIFF, 0.0f);
    TEST_ASSERT_EQUAL_INT(PMA_ERR_RANGE, pma_velest_init_q16(&q, &c));
    c = vcfg(7, 30.0f);
    TEST_ASSERT_EQUAL_INT(PMA_ERR_RANGE, pma_velest_init_f32(&f, &c));
    c = vcfg(PMA_VELEST_TRACKING, NAN);
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NOT_FINITE, pma_velest_init_f32(&f, &c));
    c = vcfg(PMA_VELEST_TRACKING, 30.0f);
    c.period_s = -1e-3f;
    TEST_ASSERT_EQUAL_INT(PMA_ERR_RANGE, pma_velest_init_f32(&f, &c));
    TEST_ASSERT_TRUE(isnan(pma_velest_noise_gain(&c)));
    c = vcfg(PMA_VELEST_TRACKING, 30.0f);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_velest_init_f32(&f, &c));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_velest_step_f32(&f, -2.0f, &v));
    const pma_velest_f32_t before = f;
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NOT_FINITE, pma_velest_step_f32(&f, NAN, &v));
    TEST_ASSERT_EQUAL_MEMORY(&before, &f, sizeof f);
    /* reset: the next sample primes again (no velocity kick from a jump) */
    pma_velest_reset_f32(&f);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_velest_step_f32(&f, 5.0f, &v));
    TEST_ASSERT_TRUE(v == 0.0f);
}

/* Fixed point follows float on noisy sine data. */
static void test_fixed_matches_float(void)
{
    for (uint8_t kind = 0; kind < 2; ++kind) {
        pma_velest_config_t c = vcfg(kind, 30.0f);
        pma_velest_f32_t f;
        pma_velest_q16_t q;
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_velest_init_f32(&f, &c));
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_velest_init_q16(&q, &c));
        uint32_t seed = 99u;
        double worst = 0.0;
        for (int k = 0; k < 5000; ++k) {
            const float x = (float)F16(Q16(-2.0 + 0.5 * sin(2 * PI * 0.5 * k * 1e-3) +
                                            0.001 * test_rand_gauss(&seed)));
            float v;
            pma_q16_t vq;
            TEST_ASSERT_EQUAL_INT(PMA_OK, pma_velest_step_f32(&f, x, &v));
            TEST_ASSERT_EQUAL_INT(PMA_OK, pma_velest_step_q16(&q, Q16(x), &vq));
            worst = fmax(worst, fabs(F16(vq) - v));
        }
        printf("velest kind %u: fixed vs float max |dv| %.2e cm/s\n", (unsigned)kind, worst);
        TEST_ASSERT_LESS_THAN_DOUBLE(0.01, worst);
    }
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_ramp);
    RUN_TEST(test_noise_gain);
    RUN_TEST(test_sine_response);
    RUN_TEST(test_invalid);
    RUN_TEST(test_fixed_matches_float);
    return UNITY_END();
}
