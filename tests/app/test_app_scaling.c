/* SPDX-License-Identifier: Apache-2.0 */
/* ADC and DAC scaling (firmware/app/scaling.h): conversion, range and wire-break
 * checks, saturation, validation; the Q16.16 builds' fixed-point stages against the float
 * functions that define them (io_q16.h) and their control time (clock_q16.h). */
#include <math.h>
#include <stdint.h>

#include "pma/status.h"
#include "pma_test.h"
#include "clock_q16.h"
#include "io_q16.h"
#include "scaling.h"

/* The header's example: 4-20 mA over 165 ohm into a 12-bit 3.3 V ADC, 0-10 cm. */
static const pma_adc_scaling_t laser = {
    .offset_cm = -2.5f,
    .gain_cm_per_count = 10.0f / 3276.0f,
    .raw_min_counts = 778,
    .raw_max_counts = 4094,
    .wire_break_below_counts = 737,
};

/* 0-600 kPa regulator on a 12-bit DAC. */
static const pma_dac_scaling_t regulator = {
    .counts_at_zero_kpa = 0.0f,
    .counts_per_kpa = 4095.0f / 600.0f,
    .min_counts = 0,
    .max_counts = 4095,
};

static void test_adc_converts_valid_range(void)
{
    float x = -99.0f;
    assert_status(pma_adc_counts_to_cm(&laser, 819, &x), PMA_OK); /* 4 mA: the sensor's 0 */
    TEST_ASSERT_LESS_THAN_FLOAT(1e-5f, fabsf(x));
    assert_status(pma_adc_counts_to_cm(&laser, 4094, &x), PMA_OK);
    TEST_ASSERT_LESS_THAN_FLOAT(1e-5f, fabsf(x - (-2.5f + 4094.0f * 10.0f / 3276.0f)));
    assert_status(pma_adc_counts_to_cm(&laser, 778, &x), PMA_OK); /* 3.8 mA: still usable */
    TEST_ASSERT_LESS_THAN_FLOAT(0.0f, x);
}

static void test_adc_range_and_wire_break(void)
{
    float x = 42.0f;
    assert_status(pma_adc_counts_to_cm(&laser, 4095, &x), PMA_ERR_RANGE);    /* clipped */
    assert_status(pma_adc_counts_to_cm(&laser, 65535, &x), PMA_ERR_RANGE);
    assert_status(pma_adc_counts_to_cm(&laser, 777, &x), PMA_ERR_RANGE);     /* 3.6-3.8 mA */
    assert_status(pma_adc_counts_to_cm(&laser, 737, &x), PMA_ERR_RANGE);
    assert_status(pma_adc_counts_to_cm(&laser, 736, &x), PMA_ERR_WIRE_BREAK);
    assert_status(pma_adc_counts_to_cm(&laser, 0, &x), PMA_ERR_WIRE_BREAK);  /* 0 mA */
    TEST_ASSERT_FLOAT_WITHIN(0.0f, 42.0f, x); /* untouched on every error */

    /* 0-10 V sensor without a live zero: no wire-break check, 0 is valid */
    pma_adc_scaling_t volt = {.offset_cm = 0.0f, .gain_cm_per_count = 0.01f,
                              .raw_min_counts = 0, .raw_max_counts = 1000,
                              .wire_break_below_counts = 0};
    assert_status(pma_adc_counts_to_cm(&volt, 0, &x), PMA_OK);
    TEST_ASSERT_FLOAT_WITHIN(0.0f, 0.0f, x);
    assert_status(pma_adc_counts_to_cm(&volt, 1001, &x), PMA_ERR_RANGE);

    /* inverted mounting: negative gain */
    volt.offset_cm = 10.0f;
    volt.gain_cm_per_count = -0.01f;
    assert_status(pma_adc_counts_to_cm(&volt, 1000, &x), PMA_OK);
    TEST_ASSERT_LESS_THAN_FLOAT(1e-5f, fabsf(x));
}

static void test_adc_validation(void)
{
    float x;
    assert_status(pma_adc_validate_scaling(&laser), PMA_OK);
    assert_status(pma_adc_validate_scaling(NULL), PMA_ERR_NULL);
    assert_status(pma_adc_counts_to_cm(&laser, 1000, NULL), PMA_ERR_NULL);
    assert_status(pma_adc_counts_to_cm(NULL, 1000, &x), PMA_ERR_NULL);
    pma_adc_scaling_t s = laser;
    s.offset_cm = NAN;
    assert_status(pma_adc_validate_scaling(&s), PMA_ERR_NOT_FINITE);
    assert_status(pma_adc_counts_to_cm(&s, 1000, &x), PMA_ERR_NOT_FINITE);
    s = laser;
    s.gain_cm_per_count = INFINITY;
    assert_status(pma_adc_validate_scaling(&s), PMA_ERR_NOT_FINITE);
    s.gain_cm_per_count = 0.0f;
    assert_status(pma_adc_validate_scaling(&s), PMA_ERR_RANGE);
    s = laser;
    s.raw_min_counts = 4095;
    assert_status(pma_adc_validate_scaling(&s), PMA_ERR_RANGE); /* min > max */
    s = laser;
    s.wire_break_below_counts = 779;
    assert_status(pma_adc_validate_scaling(&s), PMA_ERR_RANGE); /* above raw_min */
}

static void test_adc_inverse(void)
{
    uint16_t raw = 1;
    for (uint16_t r = 778; r <= 4094; r = (uint16_t)(r + 97)) {
        float x;
        assert_status(pma_adc_counts_to_cm(&laser, r, &x), PMA_OK);
        assert_status(pma_adc_cm_to_counts(&laser, x, &raw), PMA_OK);
        TEST_ASSERT_EQUAL_INT(r, raw);
    }
    assert_status(pma_adc_cm_to_counts(&laser, -100.0f, &raw), PMA_OK);
    TEST_ASSERT_EQUAL_INT(778, raw); /* saturated to the valid range */
    assert_status(pma_adc_cm_to_counts(&laser, 1e30f, &raw), PMA_OK);
    TEST_ASSERT_EQUAL_INT(4094, raw);
    raw = 7;
    assert_status(pma_adc_cm_to_counts(&laser, NAN, &raw), PMA_ERR_NOT_FINITE);
    assert_status(pma_adc_cm_to_counts(&laser, -INFINITY, &raw), PMA_ERR_NOT_FINITE);
    TEST_ASSERT_EQUAL_INT(7, raw);
}

static void test_dac_scaling_and_saturation(void)
{
    uint16_t c = 1;
    assert_status(pma_dac_kpa_to_counts(&regulator, 0.0f, &c), PMA_OK);
    TEST_ASSERT_EQUAL_INT(0, c);
    assert_status(pma_dac_kpa_to_counts(&regulator, 200.0f, &c), PMA_OK);
    TEST_ASSERT_EQUAL_INT(1365, c);
    assert_status(pma_dac_kpa_to_counts(&regulator, 600.0f, &c), PMA_OK);
    TEST_ASSERT_EQUAL_INT(4095, c);
    assert_status(pma_dac_kpa_to_counts(&regulator, 100.1f, &c), PMA_OK);
    TEST_ASSERT_EQUAL_INT(683, c); /* 683.18: rounded to nearest */
    assert_status(pma_dac_kpa_to_counts(&regulator, 100.03f, &c), PMA_OK);
    TEST_ASSERT_EQUAL_INT(683, c); /* 682.70 */
    /* saturation at both ends, for any finite input */
    assert_status(pma_dac_kpa_to_counts(&regulator, -50.0f, &c), PMA_OK);
    TEST_ASSERT_EQUAL_INT(0, c);
    assert_status(pma_dac_kpa_to_counts(&regulator, 601.0f, &c), PMA_OK);
    TEST_ASSERT_EQUAL_INT(4095, c);
    assert_status(pma_dac_kpa_to_counts(&regulator, 3e38f, &c), PMA_OK); /* product overflows */
    TEST_ASSERT_EQUAL_INT(4095, c);
    assert_status(pma_dac_kpa_to_counts(&regulator, -3e38f, &c), PMA_OK);
    TEST_ASSERT_EQUAL_INT(0, c);
    /* a narrower output window (e.g. a 2-8 V regulator input) */
    pma_dac_scaling_t w = regulator;
    w.min_counts = 819;
    w.max_counts = 3276;
    assert_status(pma_dac_kpa_to_counts(&w, 0.0f, &c), PMA_OK);
    TEST_ASSERT_EQUAL_INT(819, c);
    assert_status(pma_dac_kpa_to_counts(&w, 590.0f, &c), PMA_OK);
    TEST_ASSERT_EQUAL_INT(3276, c);
    /* NaN and infinity: error, output untouched */
    c = 1234;
    assert_status(pma_dac_kpa_to_counts(&regulator, NAN, &c), PMA_ERR_NOT_FINITE);
    assert_status(pma_dac_kpa_to_counts(&regulator, INFINITY, &c), PMA_ERR_NOT_FINITE);
    TEST_ASSERT_EQUAL_INT(1234, c);
}

static void test_dac_validation(void)
{
    uint16_t c;
    assert_status(pma_dac_validate_scaling(&regulator), PMA_OK);
    assert_status(pma_dac_validate_scaling(NULL), PMA_ERR_NULL);
    assert_status(pma_dac_kpa_to_counts(&regulator, 1.0f, NULL), PMA_ERR_NULL);
    pma_dac_scaling_t s = regulator;
    s.counts_per_kpa = 0.0f;
    assert_status(pma_dac_kpa_to_counts(&s, 1.0f, &c), PMA_ERR_RANGE);
    s = regulator;
    s.counts_at_zero_kpa = NAN;
    assert_status(pma_dac_validate_scaling(&s), PMA_ERR_NOT_FINITE);
    s = regulator;
    s.min_counts = 5;
    s.max_counts = 4;
    assert_status(pma_dac_validate_scaling(&s), PMA_ERR_RANGE);
}

/* A small deterministic generator for the comparisons below (xorshift32). */
static uint32_t rng_state = 2463534242u;
static double uniform(double lo, double hi)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 17;
    rng_state ^= rng_state << 5;
    return lo + (hi - lo) * (double)rng_state / 4294967296.0;
}

/* The fixed-point output stage against the float functions that define it, on random
 * configurations within the parameters' ranges and random inputs (saturating, clamped,
 * slew-limited and free): the pressure within 6 LSB (1e-4 kPa: float's own rounding at
 * 1000 kPa is 6e-5) plus u's rounding to Q16.16 times act.kpa_per_u (the slot's u is a
 * Q16.16 value to begin with), and the DAC code equal, except by 1 where the float code's value lies
 * within 1e-3 counts of a rounding boundary. */
static void test_output_q16_matches_float(void)
{
    unsigned near_ties = 0, slewed = 0, clamped = 0, saturated = 0;
    for (int n = 0; n < 20000; ++n) {
        const float p_max = (float)uniform(50.0, 1000.0);
        const float p_min = (float)uniform(0.0, 0.5 * p_max);
        pma_actuator_config_t ac = {
            .p0_kpa = (float)uniform(p_min, p_max), .kpa_per_u = (float)exp(uniform(log(1e-3), log(1e3))),
            .polarity = (n & 1) ? 1 : -1, .p_min_kpa = p_min, .p_max_kpa = p_max,
            .slew_kpa_s = (n % 3 == 0) ? 0.0f : (float)exp(uniform(log(10.0), log(1e6))),
            .safe_mode = PMA_SAFE_VENT, .safe_kpa = 0.0f};
        const uint16_t lo = (uint16_t)uniform(0, 1000), hi = (uint16_t)(lo + uniform(1, 3095));
        pma_dac_scaling_t ds = {.counts_at_zero_kpa = (float)uniform(-2000.0, 2000.0),
                                .counts_per_kpa = (float)((n & 2 ? 1 : -1) * exp(uniform(log(0.05), log(100.0)))),
                                .min_counts = lo, .max_counts = hi};
        const float period_s = (n & 4) ? 1e-3f : 2.5e-4f;
        pma_output_q16_t q;
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_output_q16_build(&q, &ac, &ds, period_s));
        const float u = (float)uniform(-1.2 * p_max / ac.kpa_per_u, 1.2 * p_max / ac.kpa_per_u);
        if (!pma_output_q16_takes(u)) continue;
        const float p_prev = (float)uniform(p_min, p_max);
        const float pf = pma_actuator_active_kpa(&ac, u, p_prev, period_s);
        const pma_q16_t pq = pma_output_q16_kpa(&q, pma_q16_from_f32(u), pma_q16_from_f32(p_prev));
        /* and u's own rounding to Q16.16 (half an LSB), times the factor */
        TEST_ASSERT_FLOAT_WITHIN(1e-4f + ac.kpa_per_u * 7.7e-6f, pf, pma_q16_to_f32(pq));
        const float free = ac.p0_kpa + (float)ac.polarity * ac.kpa_per_u * u;
        if (pf != free) (free < p_min || free > p_max) ? ++clamped : ++slewed;
        uint16_t cf = 0;
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_dac_kpa_to_counts(&ds, pf, &cf));
        const uint16_t cq = pma_output_q16_counts(&q, pma_q16_from_f32(pf));
        const double v = (double)ds.counts_at_zero_kpa + (double)ds.counts_per_kpa * pf;
        if (v <= lo || v >= hi) ++saturated;
        if (fabs(v - floor(v) - 0.5) < 1e-3) {
            ++near_ties;
            TEST_ASSERT_UINT_WITHIN(1u, cf, cq);
        } else {
            TEST_ASSERT_EQUAL_UINT16(cf, cq);
        }
    }
    /* every branch ran many times */
    TEST_ASSERT_TRUE(slewed > 1000 && clamped > 1000 && saturated > 1000);
    (void)near_ties;
}

/* What the stage cannot represent is refused (the application then runs the float
 * functions), and an invalid configuration keeps its validation code. */
static void test_output_q16_refuses(void)
{
    pma_actuator_config_t ac = {.p0_kpa = 100.0f, .kpa_per_u = 1.0f, .polarity = 1, .p_min_kpa = 0.0f,
                                .p_max_kpa = 900.0f, .slew_kpa_s = 0.0f, .safe_mode = PMA_SAFE_VENT,
                                .safe_kpa = 0.0f};
    const pma_dac_scaling_t ds = {.counts_at_zero_kpa = 0.0f, .counts_per_kpa = 4.55f, .min_counts = 0,
                                  .max_counts = 4095};
    pma_output_q16_t q;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_output_q16_build(&q, &ac, &ds, 1e-3f));
    ac.slew_kpa_s = 0.005f;      /* 5e-6 kPa per tick: below half an LSB */
    TEST_ASSERT_EQUAL_INT(PMA_ERR_FIXED_RANGE, pma_output_q16_build(&q, &ac, &ds, 1e-3f));
    ac.slew_kpa_s = 0.0f;
    ac.kpa_per_u = 1e-12f;       /* beyond the shift's range */
    TEST_ASSERT_EQUAL_INT(PMA_ERR_FIXED_RANGE, pma_output_q16_build(&q, &ac, &ds, 1e-3f));
    ac.kpa_per_u = NAN;
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NOT_FINITE, pma_output_q16_build(&q, &ac, &ds, 1e-3f));
    ac.kpa_per_u = 1.0f;
    TEST_ASSERT_EQUAL_INT(PMA_ERR_RANGE, pma_output_q16_build(&q, &ac, &ds, 0.0f));
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NULL, pma_output_q16_build(NULL, &ac, &ds, 1e-3f));
    TEST_ASSERT_FALSE(pma_output_q16_takes(NAN));
    TEST_ASSERT_FALSE(pma_output_q16_takes(INFINITY));
    TEST_ASSERT_FALSE(pma_output_q16_takes(32768.0f));
    TEST_ASSERT_TRUE(pma_output_q16_takes(-32767.0f));
    TEST_ASSERT_TRUE(pma_output_q16_takes(0.0f));
}

/* The fixed-point input stage against pma_adc_counts_to_cm on random scalings (12- and
 * 16-bit converters, both mountings, positions up to a few metres): the same status for
 * every class of counts, and x within one LSB (2^-16 cm) plus the float function's own
 * rounding. */
static void test_input_q16_matches_float(void)
{
    unsigned wire = 0, range = 0, valid = 0;
    for (int n = 0; n < 2000; ++n) {
        const double full = (n & 1) ? 4095.0 : 65535.0;
        const uint16_t lo = (uint16_t)uniform(0.0, 0.3 * full), hi = (uint16_t)uniform(0.7 * full, full);
        const pma_adc_scaling_t s = {
            .offset_cm = (float)uniform(-300.0, 300.0),
            .gain_cm_per_count = (float)((n & 2 ? 1 : -1) * exp(uniform(log(1e-5), log(0.1)))),
            .raw_min_counts = lo, .raw_max_counts = hi,
            .wire_break_below_counts = (n % 3 == 0) ? 0u : (uint16_t)uniform(0.0, lo)};
        pma_input_q16_t q;
        TEST_ASSERT_EQUAL_INT(PMA_OK, pma_input_q16_build(&q, &s));
        for (int k = 0; k < 50; ++k) {
            const uint16_t c = (uint16_t)uniform(0.0, (k & 1) ? full + 1.0 : (double)lo + 2.0);
            float xf = 123.0f;
            pma_q16_t xq = 77;
            const int rf = pma_adc_counts_to_cm(&s, c, &xf), rq = pma_input_q16_cm(&q, c, &xq);
            TEST_ASSERT_EQUAL_INT(rf, rq);
            if (rf != PMA_OK) {
                TEST_ASSERT_EQUAL_INT(77, xq);   /* untouched on an error */
                rf == PMA_ERR_WIRE_BREAK ? ++wire : ++range;
                continue;
            }
            ++valid;
            TEST_ASSERT_FLOAT_WITHIN(1.0f / 65536.0f + fabsf(xf) * 1.2e-7f, xf, pma_q16_to_f32(xq));
        }
    }
    TEST_ASSERT_TRUE(wire > 1000 && range > 1000 && valid > 20000);
}

/* A scaling whose valid counts reach beyond Q16.16 is refused (the float function then
 * runs); an invalid one keeps its validation code. */
static void test_input_q16_refuses(void)
{
    pma_input_q16_t q;
    TEST_ASSERT_EQUAL_INT(PMA_OK, pma_input_q16_build(&q, &laser));
    pma_adc_scaling_t s = laser;
    s.gain_cm_per_count = 10.0f;              /* 40,940 cm at raw_max */
    TEST_ASSERT_EQUAL_INT(PMA_ERR_FIXED_RANGE, pma_input_q16_build(&q, &s));
    s = laser;
    s.offset_cm = -40000.0f;
    TEST_ASSERT_EQUAL_INT(PMA_ERR_FIXED_RANGE, pma_input_q16_build(&q, &s));
    s.offset_cm = NAN;
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NOT_FINITE, pma_input_q16_build(&q, &s));
    s = laser;
    s.gain_cm_per_count = 0.0f;
    TEST_ASSERT_EQUAL_INT(PMA_ERR_RANGE, pma_input_q16_build(&q, &s));
    TEST_ASSERT_EQUAL_INT(PMA_ERR_NULL, pma_input_q16_build(NULL, &laser));
}

/* The Q16.16 control time is k / hz rounded half up, exactly, at every tick rate the
 * parameters allow and some beyond, and saturates instead of wrapping. */
static void test_clock_q16_exact(void)
{
    static const uint32_t rates[] = {50u, 333u, 999u, 1000u, 1024u, 4999u, 5000u, 7u, 65536u};
    for (unsigned i = 0; i < sizeof rates / sizeof rates[0]; ++i) {
        const uint32_t hz = rates[i];
        pma_clock_q16_t c;
        pma_clock_q16_start(&c, hz);
        for (uint64_t k = 0; k < 100000u; ++k) {
            const uint64_t want = (k * 65536u + hz / 2u) / hz;
            if ((uint64_t)c.t_s != want) {
                TEST_FAIL_MESSAGE("control time differs from k / hz rounded");
            }
            pma_clock_q16_advance(&c);
        }
    }
    pma_clock_q16_t c;
    pma_clock_q16_start(&c, 1u);              /* one second a tick: 32,767 ticks to the end */
    for (int k = 0; k < 32767; ++k) pma_clock_q16_advance(&c);
    TEST_ASSERT_EQUAL_INT32((int32_t)32767 * 65536, c.t_s);
    pma_clock_q16_advance(&c);
    TEST_ASSERT_EQUAL_INT32(PMA_Q16_MAX, c.t_s);
    pma_clock_q16_advance(&c);
    TEST_ASSERT_EQUAL_INT32(PMA_Q16_MAX, c.t_s);
}

/* pma_scale_q_apply's word-by-word path (ARMv6-M, shifts 1..31) against the general form
 * it stands for, the rounded shift of the exact product: the same value for every sign, the
 * edges of both operands and the rounding ties, and 20,000 random operands per shift. On the
 * other cores both sides are the general form (this then checks nothing new). */
static void test_scale_q_apply_is_the_general_form(void)
{
    const int32_t ms[] = {0, 1, -1, (1 << 29), -(1 << 29), (1 << 30) - 1, -((1 << 30) - 1), 3, 0x2AAAAAAA};
    const int32_t xs[] = {0, 1, -1, 2, -2, INT32_MAX, INT32_MIN + 1, INT32_MIN, 0x8000, -0x8000, 12345};
    for (unsigned s = 1; s <= 62; ++s) {
        for (unsigned i = 0; i < sizeof ms / sizeof ms[0]; ++i) {
            for (unsigned j = 0; j < sizeof xs / sizeof xs[0]; ++j) {
                const pma_scale_q_t sc = {.m = ms[i], .s = (uint8_t)s};
                const int64_t want = pma_rshift_round(pma_mul32(ms[i], xs[j]), s);
                if (pma_scale_q_apply(sc, xs[j]) != want) TEST_FAIL_MESSAGE("an edge operand differs");
            }
        }
        for (int n = 0; n < (s < 32u ? 20000 : 200); ++n) {
            uniform(0.0, 1.0);
            const int32_t m = (int32_t)(rng_state >> 1) >> (rng_state & 7u);   /* |m| < 2^30 mostly */
            uniform(0.0, 1.0);
            const int32_t x = (int32_t)rng_state >> (rng_state & 15u);
            const pma_scale_q_t sc = {.m = m % (1 << 30), .s = (uint8_t)s};
            /* a tie: a product whose dropped bits are exactly one half */
            const int32_t xt = (n & 1) ? x : (int32_t)((uint32_t)1 << (s < 31u ? s - 1u : 30u));
            const int64_t want = pma_rshift_round(pma_mul32(sc.m, xt), s);
            if (pma_scale_q_apply(sc, xt) != want) TEST_FAIL_MESSAGE("a random operand differs");
        }
    }
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_adc_converts_valid_range);
    RUN_TEST(test_adc_range_and_wire_break);
    RUN_TEST(test_adc_validation);
    RUN_TEST(test_adc_inverse);
    RUN_TEST(test_dac_scaling_and_saturation);
    RUN_TEST(test_dac_validation);
    RUN_TEST(test_output_q16_matches_float);
    RUN_TEST(test_output_q16_refuses);
    RUN_TEST(test_input_q16_matches_float);
    RUN_TEST(test_input_q16_refuses);
    RUN_TEST(test_clock_q16_exact);
    RUN_TEST(test_scale_q_apply_is_the_general_form);
    return UNITY_END();
}
