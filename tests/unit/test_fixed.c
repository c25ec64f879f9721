/* SPDX-License-Identifier: Apache-2.0 */
/* Saturating fixed-point arithmetic and the tan / cos / sin approximations. */
#include <string.h>

#include "test_util.h"
#include "pma/fixed.h"

#define PI 3.14159265358979323846

static void test_sadd_ssub_saturate(void)
{
    TEST_ASSERT_EQUAL_INT(PMA_Q16_MAX, pma_q16_sadd(PMA_Q16_MAX, 1));
    TEST_ASSERT_EQUAL_INT(PMA_Q16_MIN, pma_q16_sadd(PMA_Q16_MIN, -1));
    TEST_ASSERT_EQUAL_INT(-1, pma_q16_sadd(PMA_Q16_MAX, PMA_Q16_MIN));
    TEST_ASSERT_EQUAL_INT(Q16(3.75), pma_q16_sadd(Q16(1.5), Q16(2.25)));
    TEST_ASSERT_EQUAL_INT(PMA_Q16_MIN, pma_q16_ssub(PMA_Q16_MIN, 1));
    TEST_ASSERT_EQUAL_INT(PMA_Q16_MAX, pma_q16_ssub(PMA_Q16_MAX, -1));
    TEST_ASSERT_EQUAL_INT(PMA_Q16_MAX, pma_q16_ssub(0, PMA_Q16_MIN));
    TEST_ASSERT_EQUAL_INT(PMA_Q16_MIN, pma_q16_ssub(-1, PMA_Q16_MAX));
    TEST_ASSERT_EQUAL_INT(Q16(-2.5), pma_q16_ssub(Q16(1.0), Q16(3.5)));
    TEST_ASSERT_EQUAL_INT(PMA_Q16_MAX, pma_q16_sneg(PMA_Q16_MIN));
    TEST_ASSERT_EQUAL_INT(Q16(-2.0), pma_q16_sneg(Q16(2.0)));
}

static void test_smul_rounds_and_saturates(void)
{
    TEST_ASSERT_EQUAL_INT(Q16(-3.0), pma_q16_smul(Q16(1.5), Q16(-2.0)));
    TEST_ASSERT_EQUAL_INT(PMA_Q16_MAX, pma_q16_smul(Q16(300.0), Q16(300.0)));
    TEST_ASSERT_EQUAL_INT(PMA_Q16_MIN, pma_q16_smul(Q16(-300.0), Q16(300.0)));
    /* 1 LSB x 0.5 = half an LSB: ties round away from zero, symmetric in sign */
    TEST_ASSERT_EQUAL_INT(1, pma_q16_smul(1, Q16(0.5)));
    TEST_ASSERT_EQUAL_INT(-1, pma_q16_smul(-1, Q16(0.5)));
    TEST_ASSERT_EQUAL_INT(0, pma_q16_smul(1, Q16(0.25)));
    TEST_ASSERT_EQUAL_INT(Q16(1.5), pma_q16_smul_q30(Q16(3.0), PMA_Q30_ONE / 2));
    TEST_ASSERT_EQUAL_INT(PMA_Q16_MIN, pma_q16_smul_q30(PMA_Q16_MAX, -2 * PMA_Q30_ONE));
}

static void test_sdiv(void)
{
    TEST_ASSERT_EQUAL_INT(Q16(1.5), pma_q16_sdiv(Q16(3.0), Q16(2.0)));
    TEST_ASSERT_EQUAL_INT(Q16(-1.5), pma_q16_sdiv(Q16(-3.0), Q16(2.0)));
    TEST_ASSERT_EQUAL_INT(21845, pma_q16_sdiv(Q16(1.0), Q16(3.0)));      /* 0.333328, rounded */
    TEST_ASSERT_EQUAL_INT(-21845, pma_q16_sdiv(Q16(-1.0), Q16(3.0)));
    TEST_ASSERT_EQUAL_INT(PMA_Q16_MAX, pma_q16_sdiv(Q16(1000.0), Q16(0.001)));
    TEST_ASSERT_EQUAL_INT(PMA_Q16_MIN, pma_q16_sdiv(Q16(-1000.0), Q16(0.001)));
    TEST_ASSERT_EQUAL_INT(PMA_Q16_MAX, pma_q16_sdiv(Q16(5.0), 0));
    TEST_ASSERT_EQUAL_INT(PMA_Q16_MIN, pma_q16_sdiv(Q16(-5.0), 0));
    TEST_ASSERT_EQUAL_INT(0, pma_q16_sdiv(0, 0));
    TEST_ASSERT_EQUAL_INT(PMA_Q16_MAX, pma_q16_sdiv(PMA_Q16_MIN, -PMA_Q16_ONE));
}

/* pma_udiv64_q32 against the 64 / 64 division of the C library (on ARMv6-M its own steps): random operands of every
 * bit length (both below and above 2^32 for the divisor), the quotients at 2^32 - 1 and 2^32,
 * and the edges of the operands' ranges. */
static uint32_t udiv_by_definition(uint64_t n, uint64_t d)
{
    const uint64_t q = n / d;
    return q > UINT32_MAX ? UINT32_MAX : (uint32_t)q;
}

static uint64_t next64(uint64_t *s)   /* xorshift64 */
{
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    return *s;
}

static void check_udiv(uint64_t n, uint64_t d)
{
    const uint64_t q = pma_udiv64_q32(n, d);
    const uint32_t got = q > UINT32_MAX ? UINT32_MAX : (uint32_t)q, want = udiv_by_definition(n, d);
    if (got != want) {
        pma_test_fail("pma_udiv64_q32(0x%08lx%08lx, 0x%08lx%08lx) = %lu, want %lu",
                      (unsigned long)(n >> 32), (unsigned long)(n & 0xFFFFFFFFu), (unsigned long)(d >> 32),
                      (unsigned long)(d & 0xFFFFFFFFu), (unsigned long)got, (unsigned long)want);
    }
}

static void test_udiv64_q32_is_exact(void)
{
    uint64_t s = 0x9E3779B97F4A7C15u;
    for (unsigned dbits = 1; dbits <= 64; ++dbits) {
        for (int i = 0; i < 48; ++i) {
            uint64_t d = next64(&s) >> (64u - dbits);
            if (d == 0u) d = 1u;
            /* a dividend whose quotient has 0..33 bits: most below the saturation */
            const unsigned qbits = (unsigned)(next64(&s) % 34u);
            const unsigned nbits = dbits + qbits > 64u ? 64u : dbits + qbits;
            check_udiv(next64(&s) >> (64u - nbits), d);
            /* quotient exactly 2^32 - 1 and 2^32 (plus a remainder), where d allows it */
            if (dbits <= 32u) {
                const uint64_t top = (uint64_t)UINT32_MAX * d;
                check_udiv(top, d);
                check_udiv(top + (d - 1u), d);
                check_udiv(top + d, d);
            }
        }
    }
    const uint64_t edges[] = {0u, 1u, 2u, 0x7FFFFFFFu, 0x80000000u, 0xFFFFFFFFu, 0x100000000u, 0x100000001u,
                              0x7FFFFFFFFFFFFFFFu, 0x8000000000000000u, 0xFFFFFFFFFFFFFFFEu, UINT64_MAX};
    for (size_t i = 0; i < sizeof edges / sizeof edges[0]; ++i) {
        for (size_t j = 0; j < sizeof edges / sizeof edges[0]; ++j) {
            if (edges[j] != 0u) check_udiv(edges[i], edges[j]);
        }
    }
}

static void check_round_sat(int64_t v, unsigned shift)
{
    const pma_q16_t got = pma_q16_round_sat64(v, shift), want = pma_q16_sat64(pma_rshift_round(v, shift));
    if (got != want) {
        pma_test_fail("pma_q16_round_sat64(0x%08lx%08lx, %u) = %ld, want %ld",
                      (unsigned long)((uint64_t)v >> 32), (unsigned long)((uint64_t)v & 0xFFFFFFFFu), shift,
                      (long)got, (long)want);
    }
}

/* The rounded, saturated shift (ARMv6-M: in two words) is its definition for every shift 1..31:
 * around the saturation limits, the ties and 0, at the ends of the 64-bit range, at random. */
static void test_round_sat64_is_its_definition(void)
{
    uint64_t s = 0xD1B54A32D192ED03u;
    for (unsigned shift = 1; shift <= 31; ++shift) {
        const int64_t one = (int64_t)1 << shift, half = one / 2;
        const int64_t centres[] = {0, half, -half, (int64_t)INT32_MAX * one, (int64_t)INT32_MIN * one,
                                   (int64_t)INT32_MAX * one + half, (int64_t)INT32_MIN * one - half,
                                   (int64_t)UINT32_MAX * one, -(int64_t)UINT32_MAX * one,
                                   INT64_MAX - 4, INT64_MIN + 5};
        for (size_t c = 0; c < sizeof centres / sizeof centres[0]; ++c) {
            for (int64_t d = -4; d <= 4; ++d) check_round_sat(centres[c] + d, shift);
        }
        for (int i = 0; i < 400; ++i) {
            const uint64_t r = next64(&s);
            const int64_t v = (int64_t)(r >> (r & 63u));   /* every magnitude: 1 to 63 bits */
            check_round_sat(v == INT64_MIN ? v + 1 : v, shift);
            check_round_sat(v == INT64_MIN ? -(v + 1) : -v, shift);
        }
    }
}

static void test_conversions(void)
{
    TEST_ASSERT_EQUAL_INT(0, pma_q16_from_f32(NAN));
    TEST_ASSERT_EQUAL_INT(PMA_Q16_MAX, pma_q16_from_f32(INFINITY));
    TEST_ASSERT_EQUAL_INT(PMA_Q16_MIN, pma_q16_from_f32(-INFINITY));
    TEST_ASSERT_EQUAL_INT(PMA_Q16_MAX, pma_q16_from_f32(1e9f));
    TEST_ASSERT_EQUAL_INT(-163840, pma_q16_from_f32(-2.5f));
    assert_near(pma_q16_to_f32(Q16(-2.0)), -2.0, 0.0);
    TEST_ASSERT_EQUAL_INT(Q16(1.0), pma_q16_clamp(Q16(5.0), Q16(-1.0), Q16(1.0)));
    TEST_ASSERT_EQUAL_INT(PMA_Q16_MAX, pma_q16_sat64((int64_t)1 << 40));
}

/* The conversions work on the float's bits: the same results as the arithmetic definitions
 * (lroundf(x 2^16) saturated, NaN 0; (float)a 2^-16), over every exponent with random
 * significands and signs, and at the rounding ties and the saturation edges. */
static pma_q16_t from_f32_by_definition(float x)
{
    if (isnan(x)) return 0;
    const float scaled = x * 65536.0f;
    if (scaled >= 2147483647.0f) return PMA_Q16_MAX;
    if (scaled <= -2147483648.0f) return PMA_Q16_MIN;
    return (pma_q16_t)lroundf(scaled);
}

static float bits_to_f32(uint32_t b)
{
    float f;
    memcpy(&f, &b, sizeof f);
    return f;
}

static void test_conversions_match_their_definitions(void)
{
    uint32_t s = 12345u;
    for (uint32_t e = 0; e < 256u; ++e) {
        for (int i = 0; i < 64; ++i) {
            s = s * 1664525u + 1013904223u;
            const uint32_t b = (s & 0x807FFFFFu) | (e << 23);
            const float x = bits_to_f32(b);
            if (pma_q16_from_f32(x) != from_f32_by_definition(x)) {
                pma_test_fail("from_f32(bits 0x%08lx) = %ld, by definition %ld", (unsigned long)b,
                              (long)pma_q16_from_f32(x), (long)from_f32_by_definition(x));
            }
        }
    }
    static const float edges[] = {0.5f / 65536.0f, 1.5f / 65536.0f, -2.5f / 65536.0f, 0.49999997f / 65536.0f,
                                  32767.99998f, 32768.0f, -32768.0f, -32768.004f, 1e-30f, -0.0f};
    for (size_t i = 0; i < sizeof edges / sizeof edges[0]; ++i) {
        TEST_ASSERT_EQUAL_INT(from_f32_by_definition(edges[i]), pma_q16_from_f32(edges[i]));
    }
    const pma_q16_t as[] = {0, 1, -1, 12345, -98765, PMA_Q16_MAX, PMA_Q16_MIN, PMA_Q16_ONE,
                            16777217, 16777219, -16777219, 0x7FFFFFBF, 0x7FFFFF80, 0x7FFFFFC0};   /* ties, carries */
    for (size_t i = 0; i < sizeof as / sizeof as[0]; ++i) {
        const float want = (float)as[i] * (1.0f / 65536.0f), got = pma_q16_to_f32(as[i]);
        TEST_ASSERT_EQUAL_MEMORY(&want, &got, sizeof want);   /* to the bit */
    }
    for (int i = 0; i < 4096; ++i) {
        s = s * 1664525u + 1013904223u;
        const pma_q16_t a = (pma_q16_t)s;
        const float want = (float)a * (1.0f / 65536.0f), got = pma_q16_to_f32(a);
        TEST_ASSERT_EQUAL_MEMORY(&want, &got, sizeof want);
    }
    /* every magnitude of 1 to 31 bits, both signs; and from 25 bits on (where the significand
     * rounds) the ties exactly, on odd and even significands, the carry into the exponent */
    for (unsigned bits = 1; bits <= 31; ++bits) {
        for (int i = 0; i < 64; ++i) {
            s = s * 1664525u + 1013904223u;
            uint32_t m = (s >> (32u - bits)) | (1u << (bits - 1u));
            if (bits >= 25u && i < 16) {
                const unsigned low = bits - 24u;   /* the bits below the significand */
                m = ((m >> low) << low) | (1u << (low - 1u));
                if (i < 2) m = (0xFFFFFFu << low) | (1u << (low - 1u)) | (uint32_t)(i & 1);
            }
            const pma_q16_t as2[] = {(pma_q16_t)m, -(pma_q16_t)m};
            for (int k = 0; k < 2; ++k) {
                const float want = (float)as2[k] * (1.0f / 65536.0f), got = pma_q16_to_f32(as2[k]);
                if (memcmp(&want, &got, sizeof want) != 0) {
                    pma_test_fail("q16_to_f32(%ld) = %.9g, want %.9g", (long)as2[k], (double)got, (double)want);
                }
            }
        }
    }
}

/* tan(pi r / 2): error <= 1 LSB + |tan| (2e-6 + 2^-31 / (1 - r^2)) over the
 * whole open interval (grid dense near the pole), odd, saturating. */
static void test_tan_halfpi_accuracy(void)
{
    double worst = 0.0;
    for (int i = -4000; i <= 4000; ++i) {
        /* r = sign * (1 - 10^(-k)) spacing near the pole, linear elsewhere */
        double r = i / 4000.0 * 0.99;
        if (i > 3990) r = 1.0 - pow(10.0, -2.0 - (i - 3990) * 0.35);
        if (i < -3990) r = -(1.0 - pow(10.0, -2.0 - (-i - 3990) * 0.35));
        const pma_q30_t rq = (pma_q30_t)llround(r * 1073741824.0);
        const double exact = tan(PI / 2.0 * (rq / 1073741824.0));
        if (fabs(exact) > 32000.0) continue;
        const double got = pma_q16_tan_halfpi(rq) / 65536.0;
        const double rr = rq / 1073741824.0;
        const double bound = 1.0 / 65536.0 + fabs(exact) * (2e-6 + 0x1p-31 / (1.0 - rr * rr));
        const double err = fabs(got - exact) / bound;
        if (err > worst) worst = err;
        TEST_ASSERT_EQUAL_INT(-pma_q16_tan_halfpi(rq), pma_q16_tan_halfpi(-rq));
    }
    printf("tan_halfpi: worst error / stated bound = %.3f\n", worst);
    TEST_ASSERT_TRUE(worst <= 1.0);
    TEST_ASSERT_EQUAL_INT(0, pma_q16_tan_halfpi(0));
    TEST_ASSERT_EQUAL_INT(PMA_Q16_ONE, pma_q16_tan_halfpi(PMA_Q30_ONE / 2));  /* tan(pi/4) = 1 */
    TEST_ASSERT_EQUAL_INT(PMA_Q16_MAX, pma_q16_tan_halfpi(PMA_Q30_ONE));
    TEST_ASSERT_EQUAL_INT(-PMA_Q16_MAX, pma_q16_tan_halfpi(-PMA_Q30_ONE));  /* symmetric */
    TEST_ASSERT_EQUAL_INT(PMA_Q16_MAX, pma_q16_tan_halfpi(PMA_Q30_ONE + 5));
    TEST_ASSERT_EQUAL_INT(PMA_Q16_MAX, pma_q16_tan_halfpi(PMA_Q30_ONE - 1));  /* 6.8e8 > range */
}

/* Monotone over a dense grid of the whole interval, exact at integers: a
 * dropped carry in the fraction division once returned 1.0 instead of 2.0
 * at r = 756808056 / 2^30 (tan = 1.99999...); every core must also give the
 * same, exactly rounded result, checked here against a 64-bit division. */
static void test_tan_halfpi_monotone_exact(void)
{
    TEST_ASSERT_EQUAL_INT(2 * PMA_Q16_ONE, pma_q16_tan_halfpi(756808056));
    pma_q16_t prev = 0;
    for (int32_t r = 1; r < PMA_Q30_ONE; r += 4099) {            /* 262,000 points */
        const pma_q16_t t = pma_q16_tan_halfpi(r);
        if (t < prev) {
            pma_test_fail("tan not monotone at r = %ld: %ld < %ld", (long)r, (long)t, (long)prev);
        }
        prev = t;
    }
}

static void test_cos_sin_accuracy(void)
{
    double worst_cos = 0.0, worst_sin = 0.0;
    for (int i = -20000; i < 20000; ++i) {
        const pma_q30_t sq = (pma_q30_t)((int64_t)i * 107374 + 12345);   /* s in [-2, 2) */
        const double exact = cos(PI * (sq / 1073741824.0));
        const double err = fabs(pma_q30_cos_pi(sq) / 1073741824.0 - exact);
        if (err > worst_cos) worst_cos = err;
    }
    for (uint32_t k = 0; k < 40000; ++k) {
        const uint32_t f = k * 107371u + 7u;
        const double exact = sin(2.0 * PI * (f / 4294967296.0));
        const double err = fabs(pma_q30_sin_2pi_frac32(f) / 1073741824.0 - exact);
        if (err > worst_sin) worst_sin = err;
    }
    printf("cos_pi max error %.3g, sin_2pi max error %.3g\n", worst_cos, worst_sin);
    TEST_ASSERT_LESS_THAN_DOUBLE(1e-7, worst_cos);
    TEST_ASSERT_LESS_THAN_DOUBLE(1e-7, worst_sin);
    TEST_ASSERT_EQUAL_INT(PMA_Q30_ONE, pma_q30_cos_pi(0));      /* alpha(0) = 0 exactly */
    TEST_ASSERT_EQUAL_INT(-PMA_Q30_ONE, pma_q30_cos_pi(PMA_Q30_ONE));
    assert_near(pma_q30_sin_2pi_frac32(0) / 1073741824.0, 0.0, 1e-7);
    assert_near(pma_q30_sin_2pi_frac32(0x40000000u) / 1073741824.0, 1.0, 1e-7);
    assert_near(pma_q30_sin_2pi_frac32(0xC0000000u) / 1073741824.0, -1.0, 1e-7);
}

/* the tuning function's sin^2(pi x / 2): the bits of (1 - cos(pi x)) / 2 on [0, 1], 1 above */
static void test_sin2_halfpi_is_cos_to_the_bit(void)
{
    for (uint32_t x = 0; x <= (uint32_t)PMA_Q30_ONE; x += 65521u) {
        TEST_ASSERT_EQUAL_INT(((int64_t)PMA_Q30_ONE - pma_q30_cos_pi((pma_q30_t)x)) / 2, pma_q30_sin2_halfpi(x));
    }
    const uint32_t edges[] = {0u, 1u, (uint32_t)PMA_Q30_ONE / 2u - 1u, (uint32_t)PMA_Q30_ONE / 2u,
                              (uint32_t)PMA_Q30_ONE / 2u + 1u, (uint32_t)PMA_Q30_ONE - 1u, (uint32_t)PMA_Q30_ONE};
    for (size_t i = 0; i < sizeof edges / sizeof edges[0]; ++i) {
        TEST_ASSERT_EQUAL_INT(((int64_t)PMA_Q30_ONE - pma_q30_cos_pi((pma_q30_t)edges[i])) / 2,
                              pma_q30_sin2_halfpi(edges[i]));
    }
    TEST_ASSERT_EQUAL_INT(0, pma_q30_sin2_halfpi(0u));
    TEST_ASSERT_EQUAL_INT(PMA_Q30_ONE, pma_q30_sin2_halfpi((uint32_t)PMA_Q30_ONE));
    TEST_ASSERT_EQUAL_INT(PMA_Q30_ONE, pma_q30_sin2_halfpi(0xFFFFFFFFu));   /* above 1: 1 */
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_sadd_ssub_saturate);
    RUN_TEST(test_smul_rounds_and_saturates);
    RUN_TEST(test_sdiv);
    RUN_TEST(test_udiv64_q32_is_exact);
    RUN_TEST(test_round_sat64_is_its_definition);
    RUN_TEST(test_conversions);
    RUN_TEST(test_conversions_match_their_definitions);
    RUN_TEST(test_tan_halfpi_accuracy);
    RUN_TEST(test_tan_halfpi_monotone_exact);
    RUN_TEST(test_sin2_halfpi_is_cos_to_the_bit);
    RUN_TEST(test_cos_sin_accuracy);
    return UNITY_END();
}
