/* SPDX-License-Identifier: Apache-2.0 */
/* Reference generators and constraint band (pma/ref.h). */
#include "test_util.h"
#include "pma/ref.h"
#include "pma/status.h"

#define PI 3.14159265358979323846

static pma_ref_config_t rc(uint8_t kind)
{
    return (pma_ref_config_t){.kind = kind, .offset_cm = -2.0f, .amplitude_cm = 0.5f,
                              .freq_hz = 0.25f, .phase_rad = 0.3f, .t0_s = 1.0f,
                              .rate_cm_s = 0.2f};
}

static double case1(double t) { return -0.5 * sin(t) - 2.0; }
static double case3(double t)
{
    return t * sin(2 * PI * t * (1 + t / 55) / 55 - PI / 2) / 360 - 2;
}

/* Values and derivatives of every kind, float and fixed point, against the
 * formulas in double (derivative also against a central difference). */
static void test_values(void)
{
    for (uint8_t kind = PMA_REF_HOLD; kind <= PMA_REF_CASE3; ++kind) {
        pma_ref_config_t c = rc(kind);
        pma_ref_f32_t f;
        pma_ref_q16_t q;
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ref_init_f32(&f, &c));
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ref_init_q16(&q, &c));
        double worst_f = 0.0, worst_q = 0.0, worst_d = 0.0;
        for (int k = 0; k <= 1800; ++k) {
            const double t = F16(Q16(k * 0.1 + 0.0371));
            double want;
            switch (kind) {
            case PMA_REF_HOLD: want = -2.0; break;
            case PMA_REF_STEP: want = t >= 1.0 ? -1.5 : -2.0; break;
            case PMA_REF_RAMP: want = t < 1.0 ? -2.0 : fmin(-2.0 + 0.2 * (t - 1.0), -1.5); break;
            case PMA_REF_SINE: want = -2.0 + 0.5 * sin(2 * PI * 0.25 * t + 0.3); break;
            case PMA_REF_CASE1: want = case1(t); break;
            default: want = case3(t); break;
            }
            float x, d;
            pma_q16_t xq, dq;
            TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ref_eval_f32(&f, (float)t, &x, &d));
            TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ref_eval_q16(&q, Q16(t), &xq, &dq));
            worst_f = fmax(worst_f, fabs(x - want));
            worst_q = fmax(worst_q, fabs(F16(xq) - want));
            if (kind >= PMA_REF_SINE) {
                const double h = 1e-4;
                double num;
                if (kind == PMA_REF_SINE) num = (sin(2 * PI * 0.25 * (t + h) + 0.3) - sin(2 * PI * 0.25 * (t - h) + 0.3)) * 0.25 / h;
                else if (kind == PMA_REF_CASE1) num = (case1(t + h) - case1(t - h)) / (2 * h);
                else num = (case3(t + h) - case3(t - h)) / (2 * h);
                worst_d = fmax(worst_d, fmax(fabs(d - num), fabs(F16(dq) - num)));
            }
        }
        printf("ref kind %u: max |x error| float %.2e, fixed %.2e cm; max |x' error| %.2e cm/s\n",
               kind, worst_f, worst_q, worst_d);
        TEST_ASSERT_LESS_THAN_DOUBLE(2e-5, worst_f);
        TEST_ASSERT_LESS_THAN_DOUBLE(5e-5, worst_q);
        TEST_ASSERT_LESS_THAN_DOUBLE(2e-3, worst_d);
    }
}

/* Streamed setpoint: starts at the offset, moves at most rate per second. */
static void test_stream(void)
{
    pma_ref_config_t c = rc(PMA_REF_STREAM);
    pma_ref_f32_t f;
    pma_ref_q16_t q;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ref_init_f32(&f, &c));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ref_init_q16(&q, &c));
    float x, d;
    pma_q16_t xq, dq;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ref_eval_f32(&f, 0.0f, &x, &d));
    assert_near(x, -2.0, 0.0);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ref_stream_f32(&f, -1.0f));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ref_stream_q16(&q, Q16(-1.0)));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ref_eval_f32(&f, 1.0f, &x, &d));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ref_eval_q16(&q, Q16(1.0), &xq, &dq));
    assert_near(x, -1.8, 1e-6);          /* 0.2 cm/s for 1 s */
    assert_near(d, 0.2, 1e-5);
    assert_near(F16(xq), -1.8, 1e-4);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ref_eval_f32(&f, 10.0f, &x, &d));
    assert_near(x, -1.0, 0.0);           /* reached, holds */
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NOT_FINITE, pma_ref_stream_f32(&f, NAN));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ref_eval_f32(&f, 11.0f, &x, &d));
    assert_near(x, -1.0, 0.0);
    /* a non-stream reference refuses streamed values */
    pma_ref_config_t s = rc(PMA_REF_SINE);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ref_init_f32(&f, &s));
    TEST_ASSERT_EQUAL_INT(PMA_ERR_UNSUPPORTED, pma_ref_stream_f32(&f, 1.0f));
    /* rate 0: jumps */
    c.rate_cm_s = 0.0f;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ref_init_f32(&f, &c));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ref_stream_f32(&f, -2.5f));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ref_eval_f32(&f, 0.001f, &x, NULL));
    assert_near(x, -2.5, 0.0);
}

/* Bounds and the band check of eq. 14 (x_r +- w1 inside the band). */
static void test_band(void)
{
    const pma_band_t band = pma_band_constant(-3.0f, 0.0f);
    pma_ref_config_t c3 = rc(PMA_REF_CASE3);
    float lo, hi;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ref_bounds(&c3, 180.0f, &lo, &hi));
    assert_near(lo, -2.5, 1e-6);
    assert_near(hi, -1.5, 1e-6);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_band_check_ref(&band, &c3, 180.0f, 0.2f));  /* paper's Case 3 */
    TEST_ASSERT_EQUAL_INT(PMA_ERR_BAND, pma_band_check_ref(&band, &c3, 180.0f, 0.6f));
    TEST_ASSERT_EQUAL_INT(PMA_ERR_BAND, pma_band_check_ref(&band, &c3, 400.0f, 0.2f)); /* envelope grows */
    pma_ref_config_t c1 = rc(PMA_REF_CASE1);
    /* the paper's Case 1 (w1 = 0.5) touches k_low exactly: -2.5 - 0.5 = -3, so
     * the strict inequality of eq. 14 fails; Case 2 (w1 = 0.3) fits */
    TEST_ASSERT_EQUAL_INT(PMA_ERR_BAND, pma_band_check_ref(&band, &c1, 60.0f, 0.5f));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_band_check_ref(&band, &c1, 60.0f, 0.3f));
    pma_ref_config_t step = rc(PMA_REF_STEP);
    step.amplitude_cm = 2.0f;                                                    /* to 0 cm: at the edge */
    TEST_ASSERT_EQUAL_INT(PMA_ERR_BAND, pma_band_check_ref(&band, &step, 10.0f, 0.1f));
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_band_check_ref(&band, &step, 0.5f, 0.1f));  /* before the step */
    const pma_band_t bad = pma_band_constant(0.0f, -3.0f);                       /* the paper's typo */
    TEST_ASSERT_EQUAL_INT(PMA_ERR_BAND, pma_band_validate(&bad, 10.0f));
    TEST_ASSERT_EQUAL_INT(PMA_ERR_BAND, pma_band_check_ref(&bad, &c3, 10.0f, 0.2f));
    TEST_ASSERT_EQUAL_INT(1, pma_band_contains(&band, 5.0f, -1.0f));
    TEST_ASSERT_EQUAL_INT(0, pma_band_contains(&band, 5.0f, 0.0f));
    TEST_ASSERT_EQUAL_INT(0, pma_band_contains(&band, 5.0f, NAN));
    TEST_ASSERT_EQUAL_INT(0, pma_band_contains(&band, -1.0f, -1.0f));            /* bad time */
    TEST_ASSERT_EQUAL_INT(PMA_ERR_RANGE, pma_ref_bounds(&c3, -1.0f, &lo, &hi));
}

/* A time-varying band: the upper edge ramps down from 0 to -1 cm over 10 s. */
static void test_time_varying_band(void)
{
    pma_band_t band = pma_band_constant(-3.0f, 0.0f);
    band.high = (pma_ref_config_t){.kind = PMA_REF_RAMP, .offset_cm = 0.0f, .amplitude_cm = 1.0f,
                                   .t0_s = 0.0f, .rate_cm_s = -0.1f};
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_band_validate(&band, 20.0f));
    TEST_ASSERT_EQUAL_INT(1, pma_band_contains(&band, 0.0f, -0.5f));
    TEST_ASSERT_EQUAL_INT(0, pma_band_contains(&band, 6.0f, -0.5f));  /* k_high(6) = -0.6 */
    TEST_ASSERT_EQUAL_INT(1, pma_band_contains(&band, 6.0f, -0.7f));
    pma_ref_config_t hold = {.kind = PMA_REF_HOLD, .offset_cm = -1.5f};
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_band_check_ref(&band, &hold, 20.0f, 0.4f));  /* -1.1 < -1 */
    TEST_ASSERT_EQUAL_INT(PMA_ERR_BAND, pma_band_check_ref(&band, &hold, 20.0f, 0.6f));
    /* edges that may cross, and a STREAM edge, are refused */
    band.low = (pma_ref_config_t){.kind = PMA_REF_SINE, .offset_cm = -1.5f, .amplitude_cm = 1.0f,
                                  .freq_hz = 0.1f};
    TEST_ASSERT_EQUAL_INT(PMA_ERR_BAND, pma_band_validate(&band, 20.0f));
    band.low = (pma_ref_config_t){.kind = PMA_REF_STREAM, .offset_cm = -3.0f};
    TEST_ASSERT_EQUAL_INT(PMA_ERR_UNSUPPORTED, pma_band_validate(&band, 20.0f));
    TEST_ASSERT_EQUAL_INT(0, pma_band_contains(&band, 1.0f, -2.0f));
}

static void test_invalid(void)
{
    pma_ref_f32_t f;
    pma_ref_config_t c = rc(PMA_REF_SINE);
    c.freq_hz = -1.0f;
    TEST_ASSERT_EQUAL_INT(PMA_ERR_RANGE, pma_ref_init_f32(&f, &c));
    float x = 4.0f;
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NOT_READY, pma_ref_eval_f32(&f, 0.0f, &x, NULL));
    TEST_ASSERT_TRUE(x == 4.0f);
    c = rc(PMA_REF_SINE);
    c.phase_rad = NAN;
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NOT_FINITE, pma_ref_init_f32(&f, &c));
    c = rc(9);
    TEST_ASSERT_EQUAL_INT(PMA_ERR_RANGE, pma_ref_init_f32(&f, &c));
    c = rc(PMA_REF_STEP);
    c.t0_s = -1.0f;
    TEST_ASSERT_EQUAL_INT(PMA_ERR_RANGE, pma_ref_init_f32(&f, &c));
    c = rc(PMA_REF_STEP);
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_ref_init_f32(&f, &c));
    TEST_ASSERT_EQUAL_INT(PMA_ERR_RANGE, pma_ref_eval_f32(&f, -0.5f, &x, NULL));
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NOT_FINITE, pma_ref_eval_f32(&f, NAN, &x, NULL));
    pma_ref_q16_t q;
    c = rc(PMA_REF_SINE);
    c.freq_hz = 200.0f;
    TEST_ASSERT_EQUAL_INT(PMA_ERR_FIXED_RANGE, pma_ref_init_q16(&q, &c));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_values);
    RUN_TEST(test_stream);
    RUN_TEST(test_band);
    RUN_TEST(test_time_varying_band);
    RUN_TEST(test_invalid);
    return UNITY_END();
}
