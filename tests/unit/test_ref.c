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
static void test_values(void **state)
{
    (void)state;
    for (uint8_t kind = PMA_REF_HOLD; kind <= PMA_REF_CASE3; ++kind) {
        pma_ref_config_t c = rc(kind);
        pma_ref_f32_t f;
        pma_ref_q16_t q;
        assert_int_equal(pma_ref_init_f32(&f, &c), PMA_OK);
        assert_int_equal(pma_ref_init_q16(&q, &c), PMA_OK);
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
            assert_int_equal(pma_ref_eval_f32(&f, (float)t, &x, &d), PMA_OK);
            assert_int_equal(pma_ref_eval_q16(&q, Q16(t), &xq, &dq), PMA_OK);
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
        print_message("ref kind %u: max |x error| float %.2e, fixed %.2e cm; max |x' error| %.2e cm/s\n",
                      kind, worst_f, worst_q, worst_d);
        assert_true(worst_f < 2e-5);
        assert_true(worst_q < 5e-5);
        assert_true(worst_d < 2e-3);
    }
}

/* Streamed setpoint: starts at the offset, moves at most rate per second. */
static void test_stream(void **state)
{
    (void)state;
    pma_ref_config_t c = rc(PMA_REF_STREAM);
    pma_ref_f32_t f;
    pma_ref_q16_t q;
    assert_int_equal(pma_ref_init_f32(&f, &c), PMA_OK);
    assert_int_equal(pma_ref_init_q16(&q, &c), PMA_OK);
    float x, d;
    pma_q16_t xq, dq;
    assert_int_equal(pma_ref_eval_f32(&f, 0.0f, &x, &d), PMA_OK);
    assert_near(x, -2.0, 0.0);
    assert_int_equal(pma_ref_stream_f32(&f, -1.0f), PMA_OK);
    assert_int_equal(pma_ref_stream_q16(&q, Q16(-1.0)), PMA_OK);
    assert_int_equal(pma_ref_eval_f32(&f, 1.0f, &x, &d), PMA_OK);
    assert_int_equal(pma_ref_eval_q16(&q, Q16(1.0), &xq, &dq), PMA_OK);
    assert_near(x, -1.8, 1e-6);          /* 0.2 cm/s for 1 s */
    assert_near(d, 0.2, 1e-5);
    assert_near(F16(xq), -1.8, 1e-4);
    assert_int_equal(pma_ref_eval_f32(&f, 10.0f, &x, &d), PMA_OK);
    assert_near(x, -1.0, 0.0);           /* reached, holds */
    assert_int_equal(pma_ref_stream_f32(&f, NAN), PMA_ERR_NOT_FINITE);
    assert_int_equal(pma_ref_eval_f32(&f, 11.0f, &x, &d), PMA_OK);
    assert_near(x, -1.0, 0.0);
    /* a non-stream reference refuses streamed values */
    pma_ref_config_t s = rc(PMA_REF_SINE);
    assert_int_equal(pma_ref_init_f32(&f, &s), PMA_OK);
    assert_int_equal(pma_ref_stream_f32(&f, 1.0f), PMA_ERR_UNSUPPORTED);
    /* rate 0: jumps */
    c.rate_cm_s = 0.0f;
    assert_int_equal(pma_ref_init_f32(&f, &c), PMA_OK);
    assert_int_equal(pma_ref_stream_f32(&f, -2.5f), PMA_OK);
    assert_int_equal(pma_ref_eval_f32(&f, 0.001f, &x, NULL), PMA_OK);
    assert_near(x, -2.5, 0.0);
}

/* Bounds and the band check of eq. 14 (x_r +- w1 inside the band). */
static void test_band(void **state)
{
    (void)state;
    const pma_band_t band = pma_band_constant(-3.0f, 0.0f);
    pma_ref_config_t c3 = rc(PMA_REF_CASE3);
    float lo, hi;
    assert_int_equal(pma_ref_bounds(&c3, 180.0f, &lo, &hi), PMA_OK);
    assert_near(lo, -2.5, 1e-6);
    assert_near(hi, -1.5, 1e-6);
    assert_int_equal(pma_band_check_ref(&band, &c3, 180.0f, 0.2f), PMA_OK);   /* paper's Case 3 */
    assert_int_equal(pma_band_check_ref(&band, &c3, 180.0f, 0.6f), PMA_ERR_BAND);
    assert_int_equal(pma_band_check_ref(&band, &c3, 400.0f, 0.2f), PMA_ERR_BAND); /* envelope grows */
    pma_ref_config_t c1 = rc(PMA_REF_CASE1);
    /* the paper's Case 1 (w1 = 0.5) touches k_low exactly: -2.5 - 0.5 = -3, so
     * the strict inequality of eq. 14 fails; Case 2 (w1 = 0.3) fits */
    assert_int_equal(pma_band_check_ref(&band, &c1, 60.0f, 0.5f), PMA_ERR_BAND);
    assert_int_equal(pma_band_check_ref(&band, &c1, 60.0f, 0.3f), PMA_OK);
    pma_ref_config_t step = rc(PMA_REF_STEP);
    step.amplitude_cm = 2.0f;                                                    /* to 0 cm: at the edge */
    assert_int_equal(pma_band_check_ref(&band, &step, 10.0f, 0.1f), PMA_ERR_BAND);
    assert_int_equal(pma_band_check_ref(&band, &step, 0.5f, 0.1f), PMA_OK);      /* before the step */
    const pma_band_t bad = pma_band_constant(0.0f, -3.0f);                       /* the paper's typo */
    assert_int_equal(pma_band_validate(&bad, 10.0f), PMA_ERR_BAND);
    assert_int_equal(pma_band_check_ref(&bad, &c3, 10.0f, 0.2f), PMA_ERR_BAND);
    assert_int_equal(pma_band_contains(&band, 5.0f, -1.0f), 1);
    assert_int_equal(pma_band_contains(&band, 5.0f, 0.0f), 0);
    assert_int_equal(pma_band_contains(&band, 5.0f, NAN), 0);
    assert_int_equal(pma_band_contains(&band, -1.0f, -1.0f), 0);                 /* bad time */
    assert_int_equal(pma_ref_bounds(&c3, -1.0f, &lo, &hi), PMA_ERR_RANGE);
}

/* A time-varying band: the upper edge ramps down from 0 to -1 cm over 10 s. */
static void test_time_varying_band(void **state)
{
    (void)state;
    pma_band_t band = pma_band_constant(-3.0f, 0.0f);
    band.high = (pma_ref_config_t){.kind = PMA_REF_RAMP, .offset_cm = 0.0f, .amplitude_cm = 1.0f,
                                   .t0_s = 0.0f, .rate_cm_s = -0.1f};
    assert_int_equal(pma_band_validate(&band, 20.0f), PMA_OK);
    assert_int_equal(pma_band_contains(&band, 0.0f, -0.5f), 1);
    assert_int_equal(pma_band_contains(&band, 6.0f, -0.5f), 0);     /* k_high(6) = -0.6 */
    assert_int_equal(pma_band_contains(&band, 6.0f, -0.7f), 1);
    pma_ref_config_t hold = {.kind = PMA_REF_HOLD, .offset_cm = -1.5f};
    assert_int_equal(pma_band_check_ref(&band, &hold, 20.0f, 0.4f), PMA_OK);     /* -1.1 < -1 */
    assert_int_equal(pma_band_check_ref(&band, &hold, 20.0f, 0.6f), PMA_ERR_BAND);
    /* edges that may cross, and a STREAM edge, are refused */
    band.low = (pma_ref_config_t){.kind = PMA_REF_SINE, .offset_cm = -1.5f, .amplitude_cm = 1.0f,
                                  .freq_hz = 0.1f};
    assert_int_equal(pma_band_validate(&band, 20.0f), PMA_ERR_BAND);
    band.low = (pma_ref_config_t){.kind = PMA_REF_STREAM, .offset_cm = -3.0f};
    assert_int_equal(pma_band_validate(&band, 20.0f), PMA_ERR_UNSUPPORTED);
    assert_int_equal(pma_band_contains(&band, 1.0f, -2.0f), 0);
}

static void test_invalid(void **state)
{
    (void)state;
    pma_ref_f32_t f;
    pma_ref_config_t c = rc(PMA_REF_SINE);
    c.freq_hz = -1.0f;
    assert_int_equal(pma_ref_init_f32(&f, &c), PMA_ERR_RANGE);
    float x = 4.0f;
    assert_int_equal(pma_ref_eval_f32(&f, 0.0f, &x, NULL), PMA_ERR_NOT_READY);
    assert_true(x == 4.0f);
    c = rc(PMA_REF_SINE);
    c.phase_rad = NAN;
    assert_int_equal(pma_ref_init_f32(&f, &c), PMA_ERR_NOT_FINITE);
    c = rc(9);
    assert_int_equal(pma_ref_init_f32(&f, &c), PMA_ERR_RANGE);
    c = rc(PMA_REF_STEP);
    c.t0_s = -1.0f;
    assert_int_equal(pma_ref_init_f32(&f, &c), PMA_ERR_RANGE);
    c = rc(PMA_REF_STEP);
    assert_int_equal(pma_ref_init_f32(&f, &c), PMA_OK);
    assert_int_equal(pma_ref_eval_f32(&f, -0.5f, &x, NULL), PMA_ERR_RANGE);
    assert_int_equal(pma_ref_eval_f32(&f, NAN, &x, NULL), PMA_ERR_NOT_FINITE);
    pma_ref_q16_t q;
    c = rc(PMA_REF_SINE);
    c.freq_hz = 200.0f;
    assert_int_equal(pma_ref_init_q16(&q, &c), PMA_ERR_FIXED_RANGE);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_values),
        cmocka_unit_test(test_stream),
        cmocka_unit_test(test_band),
        cmocka_unit_test(test_time_varying_band),
        cmocka_unit_test(test_invalid),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
