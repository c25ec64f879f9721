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

/* Compile-time constant from a literal (rounded); only for in-range literals. */
#define PMA_Q16_C(x) ((pma_q16_t)((x) >= 0 ? (x) * 65536.0 + 0.5 : (x) * 65536.0 - 0.5))
#define PMA_Q30_C(x) ((pma_q30_t)((x) >= 0 ? (x) * 1073741824.0 + 0.5 : (x) * 1073741824.0 - 0.5))

pma_q16_t pma_q16_sadd(pma_q16_t a, pma_q16_t b);
pma_q16_t pma_q16_ssub(pma_q16_t a, pma_q16_t b);
pma_q16_t pma_q16_sneg(pma_q16_t a);
pma_q16_t pma_q16_smul(pma_q16_t a, pma_q16_t b);
pma_q16_t pma_q16_sdiv(pma_q16_t a, pma_q16_t b);
/* a (Q16.16) times b (Q2.30) -> Q16.16, saturating. */
pma_q16_t pma_q16_smul_q30(pma_q16_t a, pma_q30_t b);
/* Clamp a to [lo, hi] (requires lo <= hi). */
pma_q16_t pma_q16_clamp(pma_q16_t a, pma_q16_t lo, pma_q16_t hi);
/* Saturate a 64-bit Q16.16 intermediate to int32. */
pma_q16_t pma_q16_sat64(int64_t a);

/* Conversions for configuration and tests (not for the control tick).
 * from_f32 saturates; NaN converts to 0. */
pma_q16_t pma_q16_from_f32(float x);
float pma_q16_to_f32(pma_q16_t a);
float pma_q30_to_f32(pma_q30_t a);

/* tan(pi/2 * r) for r in Q2.30 with |r| < 1, result Q16.16 (saturated).
 * Uses tan(pi r/2) = r g(r^2) / (1 - r^2) with g a degree-3 polynomial
 * (relative error of g < 1.4e-6 over the whole open interval). Error bound:
 * 1 LSB + |tan| (2e-6 + 2^-31 / (1 - r^2)); the last term (rounding of
 * 1 - r^2) matters only above |tan| ~ 5000, far beyond the default barrier
 * (|r| <= 0.999, |tan| <= 637). |r| >= 1 saturates to +-PMA_Q16_MAX. */
pma_q16_t pma_q16_tan_halfpi(pma_q30_t r);

/* cos(pi * s) for s in Q2.30, any s in [-2, 2); result Q2.30.
 * Absolute error < 1e-7 (1 + x Q(x), x = s^2, Q of degree 3 on |s| <= 1/2,
 * folded by symmetry); cos(0) is exactly 1. */
pma_q30_t pma_q30_cos_pi(pma_q30_t s);

/* sin(2 pi * f) for a fraction of a turn f = frac / 2^32 (unsigned Q0.32, so
 * phase arithmetic wraps exactly modulo one turn); result Q2.30,
 * abs error < 1e-7. */
pma_q30_t pma_q30_sin_2pi_frac32(uint32_t frac);

#endif /* PMA_FIXED_H */
