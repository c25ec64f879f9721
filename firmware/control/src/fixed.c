/* Saturating fixed-point arithmetic (see pma/fixed.h for formats).
 * Overflow checks are done in unsigned math; right shifts are only applied to
 * non-negative values, so every operation has defined behaviour in C11. */
#include "pma/fixed.h"
#include "fixed_internal.h"

#include <math.h>

#define SIGN32 0x80000000u

pma_q16_t pma_q16_sat64(int64_t a)
{
    if (a > INT32_MAX) return PMA_Q16_MAX;
    if (a < INT32_MIN) return PMA_Q16_MIN;
    return (pma_q16_t)a;
}

pma_q16_t pma_q16_sadd(pma_q16_t a, pma_q16_t b)
{
    uint32_t ua = (uint32_t)a, ub = (uint32_t)b, sum = ua + ub;
    /* overflow iff the operands share a sign and the sum does not */
    if (!((ua ^ ub) & SIGN32) && ((ua ^ sum) & SIGN32)) {
        return (ua & SIGN32) ? PMA_Q16_MIN : PMA_Q16_MAX;
    }
    return (pma_q16_t)sum;
}

pma_q16_t pma_q16_ssub(pma_q16_t a, pma_q16_t b)
{
    uint32_t ua = (uint32_t)a, ub = (uint32_t)b, diff = ua - ub;
    /* overflow iff the operands differ in sign and the result's sign is b's */
    if (((ua ^ ub) & SIGN32) && ((ua ^ diff) & SIGN32)) {
        return (ua & SIGN32) ? PMA_Q16_MIN : PMA_Q16_MAX;
    }
    return (pma_q16_t)diff;
}

pma_q16_t pma_q16_sneg(pma_q16_t a)
{
    return a == PMA_Q16_MIN ? PMA_Q16_MAX : -a;
}

pma_q16_t pma_q16_smul(pma_q16_t a, pma_q16_t b)
{
    return pma_q16_sat64(pma_rshift_round((int64_t)a * b, 16));
}

pma_q16_t pma_q16_smul_q30(pma_q16_t a, pma_q30_t b)
{
    return pma_q16_sat64(pma_rshift_round((int64_t)a * b, 30));
}

pma_q16_t pma_q16_sdiv(pma_q16_t a, pma_q16_t b)
{
    const int neg = (a < 0) != (b < 0);
    const uint64_t ua = (uint64_t)(a < 0 ? -(int64_t)a : a);
    const uint64_t ub = (uint64_t)(b < 0 ? -(int64_t)b : b);
    if (ub == 0u) {
        if (ua == 0u) return 0;
        return (a < 0) ? PMA_Q16_MIN : PMA_Q16_MAX;
    }
    const uint64_t q = ((ua << 16) + ub / 2u) / ub;
    if (neg) {
        return q > (uint64_t)INT32_MAX + 1u ? PMA_Q16_MIN : (pma_q16_t)(-(int64_t)q);
    }
    return q > (uint64_t)INT32_MAX ? PMA_Q16_MAX : (pma_q16_t)q;
}

pma_q16_t pma_q16_clamp(pma_q16_t a, pma_q16_t lo, pma_q16_t hi)
{
    return a < lo ? lo : (a > hi ? hi : a);
}

pma_q16_t pma_q16_from_f32(float x)
{
    if (isnan(x)) return 0;
    const float scaled = x * 65536.0f;
    if (scaled >= 2147483647.0f) return PMA_Q16_MAX;
    if (scaled <= -2147483648.0f) return PMA_Q16_MIN;
    return (pma_q16_t)lroundf(scaled);
}

float pma_q16_to_f32(pma_q16_t a)
{
    return (float)a * (1.0f / 65536.0f);
}

float pma_q30_to_f32(pma_q30_t a)
{
    return (float)a * (1.0f / 1073741824.0f);
}

/* tan(pi r / 2) = r g(r^2) / (1 - r^2); g(u) = sum G_k u^k, least-squares fit
 * weighted for relative error on [0, 1) (tools/fit_fixed_poly.py): max
 * relative error 1.4e-6. Coefficients in Q2.30. */
#define TAN_G0 ((int64_t)1686631833)   /*  1.5707983011850581 */
#define TAN_G1 ((int64_t)-299496310)   /* -0.2789276745391055 */
#define TAN_G2 ((int64_t)-17785356)    /* -0.0165639033588072 */
#define TAN_G3 ((int64_t)-2217795)     /* -0.0020654821500586 */

pma_q16_t pma_q16_tan_halfpi(pma_q30_t r)
{
    if (r == 0) return 0;
    const int neg = r < 0;
    const uint32_t ar = neg ? (uint32_t)0 - (uint32_t)r : (uint32_t)r;
    if (ar >= (uint32_t)PMA_Q30_ONE) return neg ? PMA_Q16_MIN : PMA_Q16_MAX;
    const int64_t u = (int64_t)(((uint64_t)ar * ar + (1u << 29)) >> 30);   /* r^2, Q30 */
    int64_t g = TAN_G3;
    g = TAN_G2 + pma_rshift_round(g * u, 30);
    g = TAN_G1 + pma_rshift_round(g * u, 30);
    g = TAN_G0 + pma_rshift_round(g * u, 30);                                     /* Q30, > 1.27 */
    const uint64_t num = ((uint64_t)ar * (uint64_t)g + (1u << 29)) >> 30;   /* r g, Q30 */
    const uint64_t den = (uint64_t)PMA_Q30_ONE - (uint64_t)u;               /* 1 - r^2 > 0 */
    const uint64_t q = ((num << 16) + den / 2u) / den;                       /* Q16 */
    if (q > (uint64_t)INT32_MAX) return neg ? PMA_Q16_MIN : PMA_Q16_MAX;
    return neg ? -(pma_q16_t)q : (pma_q16_t)q;
}

/* cos(pi s) = 1 + x (C1 + x (C2 + x (C3 + x C4))), x = s^2, |s| <= 1/2;
 * least-squares fit with cos(0) = 1 exactly: max abs error 5.5e-8.
 * Coefficients in Q4.28 (they exceed 2). */
#define COS_C1 ((int64_t)-1324674033)  /* -4.9347953240805404 */
#define COS_C2 ((int64_t)1089431141)   /*  4.0584472586995    */
#define COS_C3 ((int64_t)-357574299)   /* -1.3320680658776491 */
#define COS_C4 ((int64_t)59063867)     /*  0.2200300516253903 */

pma_q30_t pma_q30_cos_pi(pma_q30_t s)
{
    /* fold to s in [0, 1]: cos is even and cos(pi s) = cos(pi (2 - s)) */
    int64_t a = s < 0 ? -(int64_t)s : (int64_t)s;
    if (a > PMA_Q30_ONE) a = 2 * (int64_t)PMA_Q30_ONE - a;
    int negate = 0;
    if (a > PMA_Q30_ONE / 2) {                 /* cos(pi s) = -cos(pi (1 - s)) */
        a = PMA_Q30_ONE - a;
        negate = 1;
    }
    const int64_t x = pma_rshift_round(a * a, 30);                 /* Q30, <= 0.25 */
    int64_t p = COS_C4;
    p = COS_C3 + pma_rshift_round(p * x, 30);
    p = COS_C2 + pma_rshift_round(p * x, 30);
    p = COS_C1 + pma_rshift_round(p * x, 30);                       /* Q28 */
    int64_t c = PMA_Q30_ONE + pma_rshift_round(p * x, 28);          /* Q30 */
    if (c > PMA_Q30_ONE) c = PMA_Q30_ONE;
    return (pma_q30_t)(negate ? -c : c);
}

pma_q30_t pma_q30_sin_2pi_frac32(uint32_t frac)
{
    /* sin(2 pi f) = cos(pi (2 f - 1/2)); 2 f - 1/2 in [-1/2, 3/2) as Q30 */
    const int64_t s = (int64_t)(frac >> 1) - (int64_t)(PMA_Q30_ONE / 2);
    return pma_q30_cos_pi((pma_q30_t)s);
}
