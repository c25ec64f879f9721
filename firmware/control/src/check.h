/* SPDX-License-Identifier: Apache-2.0 */
/* Internal helpers for configuration validation (not part of the API). */
#ifndef PMA_CHECK_H
#define PMA_CHECK_H

#include <math.h>
#include <stddef.h>
#include "pma/status.h"

#define PMA_CHECK(expr)               \
    do {                              \
        const int pma_rc_ = (expr);   \
        if (pma_rc_ != PMA_OK) {      \
            return pma_rc_;           \
        }                             \
    } while (0)

static inline int pma_check_finite(float x)
{
    return isfinite(x) ? PMA_OK : PMA_ERR_NOT_FINITE;
}

static inline int pma_check_all_finite(const float *v, size_t n)
{
    for (size_t i = 0; i < n; ++i) {
        if (!isfinite(v[i])) return PMA_ERR_NOT_FINITE;
    }
    return PMA_OK;
}

/* |x| fits the Q16.16 range with room for the arithmetic around it. */
static inline int pma_check_q16_range(float x)
{
    return (x > -32767.0f && x < 32767.0f) ? PMA_OK : PMA_ERR_FIXED_RANGE;
}

#endif /* PMA_CHECK_H */
