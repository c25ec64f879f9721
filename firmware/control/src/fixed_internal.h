/* SPDX-License-Identifier: Apache-2.0 */
/* Internal fixed-point helpers shared by the *_q16 modules. */
#ifndef PMA_FIXED_INTERNAL_H
#define PMA_FIXED_INTERNAL_H

#include <stdint.h>
#include "pma/fixed.h"

/* Float configuration value to a Q format with `frac` fractional bits,
 * rounded, saturated to int32 (init-time only; single precision so that no
 * soft-double code is linked on the targets). */
static inline int32_t pma_to_q(float x, unsigned frac)
{
    const float scaled = x * (float)((uint32_t)1 << frac);   /* exact: power of 2 */
    if (!(scaled < 2147483520.0f)) return scaled > 0.0f ? INT32_MAX : 0;  /* NaN: 0 */
    if (!(scaled > -2147483520.0f)) return INT32_MIN;
    return (int32_t)(scaled >= 0.0f ? scaled + 0.5f : scaled - 0.5f);
}

#endif /* PMA_FIXED_INTERNAL_H */
