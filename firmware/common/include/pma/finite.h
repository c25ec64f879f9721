/* SPDX-License-Identifier: Apache-2.0 */
/* Float predicates from the float's bits. On cores without an FPU the C library's
 * isfinite() is two soft-float comparisons (an unordered test and |x| <= FLT_MAX,
 * about 60 instructions on a Cortex-M0), and each comparison of two floats a call of
 * about 30; these are masks and integer compares, with the same answer for every float
 * (IEEE 754 binary32). The application's tick checks every value it takes in and puts
 * out with them. */
#ifndef PMA_FINITE_H
#define PMA_FINITE_H

#include <stdint.h>
#include <string.h>

static inline int pma_isfinite_f32(float x)
{
    uint32_t bits;
    memcpy(&bits, &x, sizeof bits);
    return (bits & 0x7F800000u) != 0x7F800000u;
}

/* A signed integer in the order of the floats: for floats a, b that are not NaN,
 * a <= b exactly when key(a) <= key(b), and -0 and +0 both map to 0 (sign and
 * magnitude to two's complement). A NaN maps beyond the infinities of its sign. */
static inline int32_t pma_f32_order_key(float x)
{
    uint32_t bits;
    memcpy(&bits, &x, sizeof bits);
    const int32_t mag = (int32_t)(bits & 0x7FFFFFFFu);
    return (bits & 0x80000000u) ? -mag : mag;
}

/* lo <= x && x <= hi, false when any of them is NaN: the two float comparisons'
 * answer for every float. From the bits on cores without an FPU, where it is about
 * 15 instructions against two soft-float calls; the comparisons themselves elsewhere. */
static inline int pma_f32_within(float x, float lo, float hi)
{
#if defined(__arm__) && !defined(__ARM_FP)
    const uint32_t exp_all = 0x7F800000u;
    uint32_t bx, bl, bh;
    memcpy(&bx, &x, sizeof bx);
    memcpy(&bl, &lo, sizeof bl);
    memcpy(&bh, &hi, sizeof bh);
    /* a NaN (exponent all ones, mantissa not zero) answers false to every comparison */
    if ((bx & 0x7FFFFFFFu) > exp_all || (bl & 0x7FFFFFFFu) > exp_all || (bh & 0x7FFFFFFFu) > exp_all) return 0;
    const int32_t k = pma_f32_order_key(x);
    return pma_f32_order_key(lo) <= k && k <= pma_f32_order_key(hi);
#else
    return lo <= x && x <= hi;
#endif
}

#endif /* PMA_FINITE_H */
