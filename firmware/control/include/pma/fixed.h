/* SPDX-License-Identifier: Apache-2.0 */
/* Saturating fixed-point arithmetic used by the *_q16 control variants.
 *
 * Formats (all signed two's complement in int32_t):
 *   Q16.16 (pma_q16_t): value = raw / 2^16, range [-32768, 32768 - 2^-16],
 *                       resolution 2^-16 = 1.53e-5.
 *   Q2.30  (pma_q30_t): value = raw / 2^30, range [-2, 2 - 2^-30]; used for
 *                       dimensionless quantities in [-1, 1] (alpha, r = lambda/w)
 *                       because 1.0 is exactly representable.
 * Saturation: every operation clamps its exact result to the format's range
 * (PMA_Q16_MIN / PMA_Q16_MAX); nothing wraps. Rounding: multiplications and
 * divisions round to nearest (ties away from zero). Division by zero returns
 * the saturation limit with the sign of the dividend (0 for 0/0).
 * All functions are pure: no static state, no tables, safe from interrupts. */
#ifndef PMA_FIXED_H
#define PMA_FIXED_H

#include <stdint.h>

typedef int32_t pma_q16_t;
typedef int32_t pma_q30_t;

#define PMA_Q16_ONE ((pma_q16_t)0x00010000)
#define PMA_Q16_MAX ((pma_q16_t)INT32_MAX)
#define PMA_Q16_MIN ((pma_q16_t)INT32_MIN)
#define PMA_Q30_ONE ((pma_q30_t)0x40000000)

/* ---- building blocks (inline: they are the inner loop of every *_q16 step) ---- */

#if defined(__ARM_ARCH_6M__)
/* Unsigned 32 x 32 -> 64-bit product from four 16 x 16 partial products
 * (ARMv6-M has only a 32-bit MULS; gcc would call the generic 64 x 64
 * __aeabi_lmul). Returns the low word, stores the high word; the halves are
 * kept apart because 64-bit shifts and adds are several instructions on
 * Thumb-1. No intermediate exceeds 2^32. */
static inline uint32_t pma_umul32_v6m(uint32_t a, uint32_t b, uint32_t *hi)
{
    const uint32_t al = a & 0xFFFFu, ah = a >> 16, bl = b & 0xFFFFu, bh = b >> 16;
    const uint32_t lo = al * bl;
    const uint32_t m1 = ah * bl + (lo >> 16);
    const uint32_t m2 = al * bh + (m1 & 0xFFFFu);
    *hi = ah * bh + (m1 >> 16) + (m2 >> 16);
    return (m2 << 16) | (lo & 0xFFFFu);
}
#endif

/* Exact signed 32 x 32 -> 64-bit product: one SMULL on ARMv7-M, partial
 * products of the magnitudes on ARMv6-M. */
static inline int64_t pma_mul32(int32_t a, int32_t b)
{
#if defined(__ARM_ARCH_6M__)
    const uint32_t ua = a < 0 ? 0u - (uint32_t)a : (uint32_t)a;
    const uint32_t ub = b < 0 ? 0u - (uint32_t)b : (uint32_t)b;
    uint32_t hi;
    const uint32_t lo = pma_umul32_v6m(ua, ub, &hi);
    const int64_t p = (int64_t)(((uint64_t)hi << 32) | lo);   /* <= 2^62 */
    return ((a < 0) != (b < 0)) ? -p : p;
#else
    return (int64_t)a * b;
#endif
}

/* round(a b / 2^shift) for unsigned operands, 1 <= shift <= 31, result < 2^32 (one UMULL on
 * ARMv7-M, partial products on ARMv6-M, with no 64-bit shift or add on either). */
static inline uint32_t pma_umul_shift(uint32_t a, uint32_t b, unsigned shift)
{
#if defined(__ARM_ARCH_6M__)
    uint32_t hi;
    const uint32_t low = pma_umul32_v6m(a, b, &hi);
    const uint32_t low_r = low + ((uint32_t)1 << (shift - 1u));
    hi += low_r < low;                     /* carry of the rounding add */
    return (hi << (32u - shift)) | (low_r >> shift);
#else
    return (uint32_t)(((uint64_t)a * b + ((uint64_t)1 << (shift - 1u))) >> shift);
#endif
}

/* Round-to-nearest (ties away from zero) right shift of a signed 64-bit
 * value with |p| < 2^63, 1 <= shift <= 62; defined for negative values. */
static inline int64_t pma_rshift_round(int64_t p, unsigned shift)
{
    const uint64_t half = (uint64_t)1 << (shift - 1u);
    if (p >= 0) return (int64_t)(((uint64_t)p + half) >> shift);
    return -(int64_t)(((uint64_t)(-p) + half) >> shift);
}

/* Saturate a 64-bit intermediate to int32. */
static inline pma_q16_t pma_q16_sat64(int64_t a)
{
    if (a > INT32_MAX) return PMA_Q16_MAX;
    if (a < INT32_MIN) return PMA_Q16_MIN;
    return (pma_q16_t)a;
}

/* pma_q16_sat64(pma_rshift_round(p, shift)) for 1 <= shift <= 31, the same value for every p
 * (|p| < 2^63). On ARMv6-M the magnitude is rounded and shifted in its two words and compared
 * with the limit there (a 64-bit rounding, shift and saturation are each several instructions
 * on Thumb-1); elsewhere the composition itself. */
static inline pma_q16_t pma_q16_round_sat64(int64_t p, unsigned shift)
{
#if defined(__ARM_ARCH_6M__)
    const int neg = p < 0;
    const uint64_t m = neg ? 0u - (uint64_t)p : (uint64_t)p;
    const uint32_t lo = (uint32_t)m, lo_r = lo + ((uint32_t)1 << (shift - 1u));
    const uint32_t hi = (uint32_t)(m >> 32) + (lo_r < lo);   /* with the rounding's carry */
    if (hi >> shift) return neg ? PMA_Q16_MIN : PMA_Q16_MAX;  /* |result| >= 2^32 */
    const uint32_t r = (hi << (32u - shift)) | (lo_r >> shift);
    if (neg) return r >= 0x80000000u ? PMA_Q16_MIN : (pma_q16_t)(0u - r);
    return r > 0x7FFFFFFFu ? PMA_Q16_MAX : (pma_q16_t)r;
#else
    return pma_q16_sat64(pma_rshift_round(p, shift));
#endif
}

/* a + b, saturating; overflow is detected in unsigned math (the operands
 * share a sign and the sum does not). */
static inline pma_q16_t pma_q16_sadd(pma_q16_t a, pma_q16_t b)
{
    const uint32_t ua = (uint32_t)a, ub = (uint32_t)b, sum = ua + ub;
    if (!((ua ^ ub) & 0x80000000u) && ((ua ^ sum) & 0x80000000u)) {
        return (ua & 0x80000000u) ? PMA_Q16_MIN : PMA_Q16_MAX;
    }
    return (pma_q16_t)sum;
}

/* a - b, saturating (overflow iff the operands differ in sign and the
 * result's sign differs from a's). */
static inline pma_q16_t pma_q16_ssub(pma_q16_t a, pma_q16_t b)
{
    const uint32_t ua = (uint32_t)a, ub = (uint32_t)b, diff = ua - ub;
    if (((ua ^ ub) & 0x80000000u) && ((ua ^ diff) & 0x80000000u)) {
        return (ua & 0x80000000u) ? PMA_Q16_MIN : PMA_Q16_MAX;
    }
    return (pma_q16_t)diff;
}

static inline pma_q16_t pma_q16_sneg(pma_q16_t a)
{
    return a == PMA_Q16_MIN ? PMA_Q16_MAX : -a;
}

/* a b (both Q16.16) -> Q16.16, rounded, saturating. On ARMv6-M the rounded
 * magnitude (|a| |b| + 2^15) >> 16 is assembled from 16 x 16 partial products
 * with overflow checks, skipping the 64-bit intermediate; same results. */
static inline pma_q16_t pma_q16_smul(pma_q16_t a, pma_q16_t b)
{
#if defined(__ARM_ARCH_6M__)
    const int neg = (a < 0) != (b < 0);
    const uint32_t ua = a < 0 ? 0u - (uint32_t)a : (uint32_t)a;
    const uint32_t ub = b < 0 ? 0u - (uint32_t)b : (uint32_t)b;
    const uint32_t al = ua & 0xFFFFu, ah = ua >> 16, bl = ub & 0xFFFFu, bh = ub >> 16;
    const uint32_t limit = neg ? 0x80000000u : 0x7FFFFFFFu;
    const uint32_t hi = ah * bh, m1 = ah * bl, m2 = al * bh;
    if (hi >= 0x8000u || m1 >= 0x80000000u || m2 >= 0x80000000u) {
        return neg ? PMA_Q16_MIN : PMA_Q16_MAX;
    }
    /* each term < 2^31: the partial sums below never wrap before the checks */
    uint32_t m = (hi << 16) + m1;
    if (m > limit) return neg ? PMA_Q16_MIN : PMA_Q16_MAX;
    m += m2;
    if (m > limit) return neg ? PMA_Q16_MIN : PMA_Q16_MAX;
    m += (al * bl + 0x8000u) >> 16;
    if (m > limit) return neg ? PMA_Q16_MIN : PMA_Q16_MAX;
    return neg ? (pma_q16_t)(0u - m) : (pma_q16_t)m;
#else
    return pma_q16_round_sat64(pma_mul32(a, b), 16);
#endif
}

/* a (Q16.16) times b (Q2.30) -> Q16.16, rounded, saturating. */
static inline pma_q16_t pma_q16_smul_q30(pma_q16_t a, pma_q30_t b)
{
    return pma_q16_round_sat64(pma_mul32(a, b), 30);
}

/* Clamp a to [lo, hi] (requires lo <= hi). */
static inline pma_q16_t pma_q16_clamp(pma_q16_t a, pma_q16_t lo, pma_q16_t hi)
{
    return a < lo ? lo : (a > hi ? hi : a);
}

/* a / b, rounded, saturating; b = 0 gives the limit with a's sign (0/0 = 0). */
pma_q16_t pma_q16_sdiv(pma_q16_t a, pma_q16_t b);

/* floor(n / d) for d > 0, exact where it is below 2^32; a quotient of 2^32 or more comes back
 * as some value >= 2^32 - 1 (the callers saturate): the 64-bit quotients of the *_q16 modules
 * (MFAC's gains, pma_q16_sdiv). On ARMv6-M without the generic 64 / 64 library division
 * (about 350 instructions there): one 64 / 32 division by a normalised divisor, and a
 * correction step when d >= 2^32 (fixed.c; it returns 2^32 - 1 for the large quotients).
 * Elsewhere the library's division, which a divide instruction makes the faster. */
#if defined(__ARM_ARCH_6M__)
uint64_t pma_udiv64_q32(uint64_t n, uint64_t d);
#else
static inline uint64_t pma_udiv64_q32(uint64_t n, uint64_t d)
{
    return n / d;
}
#endif

/* Conversions for configuration and tests (not for the control tick).
 * from_f32 saturates; NaN converts to 0. */
pma_q16_t pma_q16_from_f32(float x);
float pma_q16_to_f32(pma_q16_t a);
float pma_q30_to_f32(pma_q30_t a);

/* tan(pi/2 * r) for r in Q2.30 with |r| < 1, result Q16.16 (saturated).
 * Uses tan(pi r/2) = r g(r^2) / (1 - r^2) with g a degree-3 polynomial
 * (relative error of g < 1.6e-6 over the whole open interval, the fit 1.4e-6 and its first
 * two Horner steps on 16-bit operands). Error bound:
 * 1 LSB + |tan| (2e-6 + 2^-31 / (1 - r^2)); the last term (rounding of
 * 1 - r^2) matters only above |tan| ~ 5000, far beyond the default barrier
 * (|r| <= 0.999, |tan| <= 637). |r| >= 1 saturates to +-PMA_Q16_MAX. */
pma_q16_t pma_q16_tan_halfpi(pma_q30_t r);

/* cos(pi * s) for s in Q2.30, any s in [-2, 2); result Q2.30.
 * Absolute error < 1e-7 (1 + x Q(x), x = s^2, Q of degree 3 on |s| <= 1/2,
 * folded by symmetry); cos(0) is exactly 1. */
pma_q30_t pma_q30_cos_pi(pma_q30_t s);

/* sin^2(pi x / 2) = (1 - cos(pi x)) / 2 for x in Q2.30, x in [0, 1] (above 1: 1); result
 * Q2.30, the same bits as (PMA_Q30_ONE - pma_q30_cos_pi(x)) / 2 (the paper's tuning function). */
pma_q30_t pma_q30_sin2_halfpi(uint32_t x);

/* sin(2 pi * f) for a fraction of a turn f = frac / 2^32 (unsigned Q0.32, so
 * phase arithmetic wraps exactly modulo one turn); result Q2.30,
 * abs error < 1e-7. */
pma_q30_t pma_q30_sin_2pi_frac32(uint32_t frac);

#endif /* PMA_FIXED_H */
