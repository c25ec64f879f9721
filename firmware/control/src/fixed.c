/* SPDX-License-Identifier: Apache-2.0 */
/* Saturating fixed-point arithmetic (see pma/fixed.h for formats).
 * Overflow checks are done in unsigned math; right shifts are only applied to
 * non-negative values, so every operation has defined behaviour in C11. */
#include "pma/fixed.h"
#include "fixed_internal.h"

#include <math.h>
#include <string.h>

#if defined(__ARM_ARCH_6M__)
/* floor((nhi 2^32 + nlo) / d) for nhi < d (the quotient fits 32 bits): 32 restoring steps,
 * unrolled. The dividend's low word shifts left through the remainder r (< d) and takes the
 * quotient bits in its freed low bit. 2r + 1 can pass 2^32 only when d > 2^31; then the carry
 * says r >= d and the wrapped subtraction is still exact. About six instructions a bit
 * (divided syntax, as in udiv_q16 below). Not inlined: the unrolled steps (450 bytes) would
 * put a caller's branches out of Thumb-1 range. */
__attribute__((noinline)) static uint32_t udiv64_32(uint32_t nhi, uint32_t nlo, uint32_t d)
{
    uint32_t r = nhi, q = nlo;
    __asm__(".rept 32\n\t"
            "lsl %[q], %[q], #1\n\t"
            "adc %[r], %[r]\n\t"
            "bcs 2f\n\t"
            "cmp %[r], %[d]\n\t"
            "bcc 1f\n"
            "2:\n\t"
            "sub %[r], %[r], %[d]\n\t"
            "add %[q], %[q], #1\n"
            "1:\n\t"
            ".endr"
            : [r] "+l"(r), [q] "+l"(q)
            : [d] "l"(d)
            : "cc");
    return q;
}

/* a b, exact, from the partial products (gcc would call the 64 x 64 multiply) */
static inline uint64_t umul64(uint32_t a, uint32_t b)
{
    uint32_t hi;
    const uint32_t lo = pma_umul32_v6m(a, b, &hi);
    return ((uint64_t)hi << 32) | lo;
}

/* Hacker's Delight's divdu: for d >= 2^32, the quotient of n / 2 by d's top 32 bits
 * (normalised) is within one of floor(n / d) after the shift back, from above; one product
 * and compare settle it. tests/unit/test_fixed.c checks it against the library's division
 * under QEMU. */
uint64_t pma_udiv64_q32(uint64_t n, uint64_t d)
{
    const uint32_t dhi = (uint32_t)(d >> 32), dlo = (uint32_t)d;
    const uint32_t nhi = (uint32_t)(n >> 32), nlo = (uint32_t)n;
    if (dhi == 0u) {
        if (nhi >= dlo) return UINT32_MAX;     /* quotient >= 2^32 (and d = 0) */
        return udiv64_32(nhi, nlo, dlo);
    }
    const unsigned z = (unsigned)__builtin_clz(dhi);                       /* 0..31 */
    const uint32_t v1 = (uint32_t)((d << z) >> 32);                        /* >= 2^31 */
    const uint64_t half = n >> 1;                                          /* < 2^63 */
    const uint32_t q1 = udiv64_32((uint32_t)(half >> 32), (uint32_t)half, v1);
    uint32_t q = q1 >> (31u - z);
    if (q != 0u) q--;                          /* now q <= floor(n / d): q d <= n */
    const uint64_t qd = umul64(q, dlo) + ((uint64_t)(q * dhi) << 32);
    if (n - qd >= d) q++;
    return q;
}
#endif

pma_q16_t pma_q16_sdiv(pma_q16_t a, pma_q16_t b)
{
    const int neg = (a < 0) != (b < 0);
    const uint64_t ua = (uint64_t)(a < 0 ? -(int64_t)a : a);
    const uint64_t ub = (uint64_t)(b < 0 ? -(int64_t)b : b);
    if (ub == 0u) {
        if (ua == 0u) return 0;
        return (a < 0) ? PMA_Q16_MIN : PMA_Q16_MAX;
    }
    const uint64_t q = pma_udiv64_q32((ua << 16) + ub / 2u, ub);
    if (neg) {
        return q > (uint64_t)INT32_MAX + 1u ? PMA_Q16_MIN : (pma_q16_t)(-(int64_t)q);
    }
    return q > (uint64_t)INT32_MAX ? PMA_Q16_MAX : (pma_q16_t)q;
}

/* From the float's bits, without float operations (on a core without an FPU, lroundf and the
 * compares cost about 400 instructions, this about 40); the same result as
 * lroundf(x * 2^16) saturated to the Q16.16 range, NaN 0 (tests/unit/test_fixed.c compares the
 * two): x = m 2^(e - 150) with the 24-bit significand m, so x 2^16 = m 2^(e - 134). */
pma_q16_t pma_q16_from_f32(float x)
{
    uint32_t b;
    memcpy(&b, &x, sizeof b);
    const int neg = (b >> 31) != 0u;
    const int e = (int)((b >> 23) & 0xFFu);
    if (e == 0xFF && (b & 0x7FFFFFu) != 0u) return 0;        /* NaN */
    if (e == 0) return 0;                                     /* zero, subnormal: below 2^-126 */
    const uint32_t m = (b & 0x7FFFFFu) | 0x800000u;
    const int shift = e - 134;
    if (shift >= 8) return neg ? PMA_Q16_MIN : PMA_Q16_MAX;  /* |x 2^16| >= 2^31, infinity */
    uint32_t r;
    if (shift >= 0) {
        r = m << shift;                                       /* < 2^31 */
    } else if (shift < -25) {
        r = 0u;                                               /* below a quarter of an LSB */
    } else {
        r = (m + (1u << (-shift - 1))) >> (-shift);           /* ties away from zero */
    }
    return neg ? -(pma_q16_t)r : (pma_q16_t)r;
}

/* (float)a 2^-16 (exact scaling: every nonzero result is a normal float, at least 2^-16).
 * Where the core has no FPU, from the integer's bits without a float operation or a
 * count-leading-zeros call (the library conversion costs about 60 instructions on a Cortex-M0,
 * this 25 to 40 by the magnitude): a = m 2^-n with m normalised to bit 31, the float's 24-bit
 * significand the top of m rounded to nearest even as the conversion (float)a rounds, its
 * exponent 15 - n.
 * Elsewhere the conversion, with the scaling done on the exponent. Both give the same bits
 * (tests/unit/test_fixed.c compares them with (float)a / 65536 on every core). */
float pma_q16_to_f32(pma_q16_t a)
{
    if (a == 0) return 0.0f;
#if defined(__arm__) && !defined(__ARM_FP)
    const uint32_t sign = a < 0 ? 0x80000000u : 0u;
    uint32_t m = a < 0 ? 0u - (uint32_t)a : (uint32_t)a;      /* 1 .. 2^31 */
    uint32_t e = 127u + 15u;                                  /* the exponent of m at bit 31 */
    if ((m >> 16) == 0u) { m <<= 16; e -= 16u; }              /* shift tests: no constant loads */
    if ((m >> 24) == 0u) { m <<= 8; e -= 8u; }
    if ((m >> 28) == 0u) { m <<= 4; e -= 4u; }
    if ((m >> 30) == 0u) { m <<= 2; e -= 2u; }
    if ((m >> 31) == 0u) { m <<= 1; e -= 1u; }
    const uint32_t mant = m >> 8;                             /* 24 bits, the top one set */
    const uint32_t rest = m & 0xFFu;
    /* the top bit adds one to the exponent field ((e - 1) << 23 + mant), so that rounding up to
     * 2^24 carries into it; to nearest, ties even: up where rest + (mant & 1) > 1/2 */
    const uint32_t b = sign | (((e - 1u) << 23) + mant + (uint32_t)(rest + (mant & 1u) > 0x80u));
#else
    const float f0 = (float)a;
    uint32_t b;
    memcpy(&b, &f0, sizeof b);
    b -= 16u << 23;
#endif
    float f;
    memcpy(&f, &b, sizeof f);
    return f;
}

float pma_q30_to_f32(pma_q30_t a)
{
    return (float)a * (1.0f / 1073741824.0f);
}

/* round(a b / 2^16) for b < 2^16 (any a): two 16 x 16 products, exact on every core. Where an
 * operand needs only 16 bits (the small high-order terms of Horner's rule, whose error the
 * later steps shrink), this costs about a quarter of pma_umul_shift on ARMv6-M. */
static inline uint32_t umul16_shift16(uint32_t a, uint32_t b)
{
    return (a >> 16) * b + (((a & 0xFFFFu) * b + 0x8000u) >> 16);
}

/* v (< 2^32) to 16 bits: round(v / 2^shift), at most 0xFFFF */
static inline uint32_t round_to16(uint32_t v, unsigned shift)
{
    const uint32_t r = (v >> shift) + ((v >> (shift - 1u)) & 1u);
    return r > 0xFFFFu ? 0xFFFFu : r;
}

/* tan(pi r / 2) = r g(r^2) / (1 - r^2); g(u) = G0 - u (G1 + u (G2 + u G3))
 * with G0..G3 > 0 (signs folded in, so Horner runs in unsigned arithmetic):
 * least-squares fit weighted for relative error on [0, 1)
 * (tools/fit_fixed_poly.py), max relative error 1.4e-6 (with u to 16 bits in the first two
 * Horner steps, below 1.6e-6). Q2.30. */
#define TAN_G0 1686631833u   /* 1.5707983011850581 */
#define TAN_G1 299496310u    /* 0.2789276745391055 */
#define TAN_G2 17785356u     /* 0.0165639033588072 */
#define TAN_G3_Q24 34653u    /* 0.0020654821500586, Q8.24: G3 u and (G2 + G3 u) u take u to 16
                              * bits (error below 2e-7 of g, whose lowest value is 1.27) */

/* round(num 2^16 / den) for num < 2^31, 0 < den <= 2^30, with 32-bit
 * divisions only (64-bit division is a long library routine on every core).
 * Exact: the 16 fraction bits come from long division of the remainder
 * r < den, then round half up. Integer parts of 2^15 and more saturate to
 * INT32_MAX. The integer part needs a division only when num >= den (|tan| >= 1).
 *  - ARMv6-M (no divide instruction; the library division costs ~80
 *    instructions): restoring division, one bit per step (in assembly: the
 *    quotient bit is the compare's carry);
 *  - elsewhere (hardware UDIV): two bits per division, since r < den <= 2^30
 *    keeps r << 2 below 2^32.
 * Both give the same, exactly rounded result on every core. */
static uint32_t udiv_q16(uint32_t num, uint32_t den)
{
    uint32_t q = 0, r = num;
    if (num >= den) {
        q = num / den;
        if (q >= 32768u) return (uint32_t)INT32_MAX;
        r = num - q * den;
    }                                          /* r < den <= 2^30 */
    uint32_t out = q;
#if defined(__ARM_ARCH_6M__)
    /* 16 restoring steps, unrolled, each quotient bit taken from the carry of the compare (or
     * of the subtraction, which leaves it set): out = 2 out + C. Four or five instructions a
     * bit, where the C loop took about seven (r < den <= 2^30: r << 1 never overflows) */
    __asm__(/* gcc hands Thumb-1 inline assembly over in divided syntax: lsl, sub and adc
             * are the flag-setting 16-bit forms */
            ".rept 16\n\t"
            "lsl %[r], %[r], #1\n\t"
            "cmp %[r], %[d]\n\t"
            "bcc 1f\n\t"
            "sub %[r], %[r], %[d]\n"
            "1:\n\t"
            "adc %[q], %[q]\n\t"
            ".endr"
            : [r] "+l"(r), [q] "+l"(out)
            : [d] "l"(den)
            : "cc");
#else
    for (int i = 0; i < 8; ++i) {
        r <<= 2;
        const uint32_t f = r / den;            /* 0..3 */
        r -= f * den;
        out = (out << 2) | f;
    }
#endif
    if (r >= den - r) out++;                   /* round half up (2r >= den) */
    return out > (uint32_t)INT32_MAX ? (uint32_t)INT32_MAX : out;
}

pma_q16_t pma_q16_tan_halfpi(pma_q30_t r)
{
    if (r == 0) return 0;
    const int neg = r < 0;
    const uint32_t ar = neg ? (uint32_t)0 - (uint32_t)r : (uint32_t)r;
    if (ar >= (uint32_t)PMA_Q30_ONE) return neg ? -PMA_Q16_MAX : PMA_Q16_MAX;
    const uint32_t u = pma_umul_shift(ar, ar, 30);              /* r^2, Q30, < 1 */
    const uint32_t u16 = round_to16(u, 14);                     /* r^2, Q16 */
    uint32_t h = TAN_G2 + ((TAN_G3_Q24 * u16 + 512u) >> 10);    /* Q24 Q16 = Q40 to Q30 */
    h = TAN_G1 + umul16_shift16(h, u16);
    const uint32_t g = TAN_G0 - pma_umul_shift(h, u, 30);       /* Q30, in [1.27, 1.571] */
    const uint32_t num = pma_umul_shift(ar, g, 30);             /* r g, Q30 */
    const uint32_t den = (uint32_t)PMA_Q30_ONE - u;             /* 1 - r^2 > 0 */
    const pma_q16_t q = (pma_q16_t)udiv_q16(num, den);
    return neg ? -q : q;
}

/* cos(pi s) = 1 - x (C1 - x (C2 - x (C3 - x C4))), x = s^2, |s| <= 1/2,
 * C1..C4 > 0 (signs folded in; every bracket stays positive for x <= 1/4,
 * so Horner runs unsigned); least-squares fit with cos(0) = 1 exactly: max
 * abs error 5.5e-8 (with x to 16 bits in the first Horner step, below 7e-8). Q4.28 (C1 and
 * C2 exceed 2). */
#define COS_C1 1324674033u   /* 4.9347953240805404 */
#define COS_C2 1089431141u   /* 4.0584472586995    */
#define COS_C3 357574299u    /* 1.3320680658776491 */
#define COS_C4_Q18 57680u    /* 0.2200300516253903, Q14.18: C4 x takes x to 16 bits (Q18) */

/* 1 - cos(pi a) for a in [0, 1/2] (Q30), Q30, at most 1 */
static uint32_t one_minus_cos_pi(uint32_t a)
{
    const uint32_t x = pma_umul_shift(a, a, 30);                /* Q30, <= 1/4 */
    uint32_t h = COS_C3 - ((COS_C4_Q18 * round_to16(x, 12) + 128u) >> 8);   /* Q36 to Q28 */
    h = COS_C2 - pma_umul_shift(h, x, 30);
    h = COS_C1 - pma_umul_shift(h, x, 30);                      /* Q28, in [3.9, 4.94] */
    const uint32_t d = pma_umul_shift(h, x, 28);
    return d > (uint32_t)PMA_Q30_ONE ? (uint32_t)PMA_Q30_ONE : d;
}

pma_q30_t pma_q30_cos_pi(pma_q30_t s)
{
    /* fold to s in [0, 1]: cos is even and cos(pi s) = cos(pi (2 - s)) */
    uint32_t a = s < 0 ? (uint32_t)0 - (uint32_t)s : (uint32_t)s;
    if (a > (uint32_t)PMA_Q30_ONE) a = 2u * (uint32_t)PMA_Q30_ONE - a;
    if (a > (uint32_t)PMA_Q30_ONE / 2u) {       /* cos(pi s) = -cos(pi (1 - s)) */
        return -(pma_q30_t)((uint32_t)PMA_Q30_ONE - one_minus_cos_pi((uint32_t)PMA_Q30_ONE - a));
    }
    return (pma_q30_t)((uint32_t)PMA_Q30_ONE - one_minus_cos_pi(a));
}

/* (1 - cos(pi x)) / 2 = (PMA_Q30_ONE - pma_q30_cos_pi(x)) / 2 to the bit, without the fold of
 * negative arguments and the sign: 1 - (1 - cos(pi (1 - x))) / 2 from x = 1/2 on */
pma_q30_t pma_q30_sin2_halfpi(uint32_t x)
{
    if (x > (uint32_t)PMA_Q30_ONE) x = (uint32_t)PMA_Q30_ONE;
    if (x > (uint32_t)PMA_Q30_ONE / 2u) {
        const uint32_t d = one_minus_cos_pi((uint32_t)PMA_Q30_ONE - x);
        return (pma_q30_t)((2u * (uint32_t)PMA_Q30_ONE - d) >> 1);
    }
    return (pma_q30_t)(one_minus_cos_pi(x) >> 1);
}

pma_q30_t pma_q30_sin_2pi_frac32(uint32_t frac)
{
    /* sin(2 pi f) = cos(pi (2 f - 1/2)); 2 f - 1/2 in [-1/2, 3/2) as Q30 */
    const int64_t s = (int64_t)(frac >> 1) - (int64_t)(PMA_Q30_ONE / 2);
    return pma_q30_cos_pi((pma_q30_t)s);
}
