/* SPDX-License-Identifier: Apache-2.0 */
/* Pressure command scaling: kPa -> counts, saturating (see scaling.h). */
#include "scaling.h"
#include "pma/status.h"
#include "pma/finite.h"

#include <math.h>
#include <stddef.h>

int pma_dac_validate_scaling(const pma_dac_scaling_t *s)
{
    if (s == NULL) return PMA_ERR_NULL;
    if (!pma_isfinite_f32(s->counts_at_zero_kpa) || !pma_isfinite_f32(s->counts_per_kpa)) {
        return PMA_ERR_NOT_FINITE;
    }
    if (s->counts_per_kpa == 0.0f) return PMA_ERR_RANGE;
    if (s->min_counts > s->max_counts) return PMA_ERR_RANGE;
    return PMA_OK;
}

int pma_dac_kpa_to_counts(const pma_dac_scaling_t *s, float p_kpa, uint16_t *counts)
{
    if (counts == NULL) return PMA_ERR_NULL;
    const int rc = pma_dac_validate_scaling(s);
    if (rc != PMA_OK) return rc;
    if (!pma_isfinite_f32(p_kpa)) return PMA_ERR_NOT_FINITE;
    const float v = s->counts_at_zero_kpa + s->counts_per_kpa * p_kpa;
    /* saturate before converting (also catches v = +-inf from a huge finite p) */
    if (!(v > (float)s->min_counts)) {
        *counts = s->min_counts;
    } else if (!(v < (float)s->max_counts)) {
        *counts = s->max_counts;
    } else {
        *counts = (uint16_t)(v + 0.5f);
    }
    return PMA_OK;
}
