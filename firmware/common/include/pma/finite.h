/* SPDX-License-Identifier: Apache-2.0 */
/* isfinite() of a float from its bits. On cores without an FPU the C library's
 * isfinite() is two soft-float comparisons (an unordered test and |x| <= FLT_MAX,
 * about 60 instructions on a Cortex-M0); this is a mask and a compare, with the
 * same answer for every float: finite exactly when the exponent field is not all
 * ones (IEEE 754 binary32). The application's tick checks every value it takes in
 * and puts out with it. */
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

#endif /* PMA_FINITE_H */
