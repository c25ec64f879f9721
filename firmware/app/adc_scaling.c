/* SPDX-License-Identifier: Apache-2.0 */
/* Position sensor scaling: counts <-> cm with range and wire-break checks
 * (see scaling.h). */
#include "scaling.h"
#include "pma/status.h"
#include "pma/finite.h"

#include <math.h>
#include <stddef.h>

int pma_adc_validate_scaling(const pma_adc_scaling_t *s)
{
    if (s == NULL) return PMA_ERR_NULL;
    if (!pma_isfinite_f32(s->offset_cm) || !pma_isfinite_f32(s->gain_cm_per_count)) return PMA_ERR_NOT_FINITE;
    if (s->gain_cm_per_count == 0.0f) return PMA_ERR_RANGE;
    if (s->raw_min_counts > s->raw_max_counts) return PMA_ERR_RANGE;
    if (s->wire_break_below_counts > s->raw_min_counts) return PMA_ERR_RANGE;
    return PMA_OK;
}

int pma_adc_counts_to_cm(const pma_adc_scaling_t *s, uint16_t raw_counts, float *x_cm)
{
    if (x_cm == NULL) return PMA_ERR_NULL;
    const int rc = pma_adc_validate_scaling(s);
    if (rc != PMA_OK) return rc;
    /* wire break first: it lies below raw_min and is the more specific finding */
    if (raw_counts < s->wire_break_below_counts) return PMA_ERR_WIRE_BREAK;
    if (raw_counts < s->raw_min_counts || raw_counts > s->raw_max_counts) return PMA_ERR_RANGE;
    *x_cm = s->offset_cm + s->gain_cm_per_count * (float)raw_counts;
    return PMA_OK;
}

int pma_adc_cm_to_counts(const pma_adc_scaling_t *s, float x_cm, uint16_t *raw_counts)
{
    if (raw_counts == NULL) return PMA_ERR_NULL;
    const int rc = pma_adc_validate_scaling(s);
    if (rc != PMA_OK) return rc;
    if (!pma_isfinite_f32(x_cm)) return PMA_ERR_NOT_FINITE;
    const float v = (x_cm - s->offset_cm) / s->gain_cm_per_count;
    /* compare before converting: a float outside uint16_t's range is UB to convert */
    if (!(v > (float)s->raw_min_counts)) {
        *raw_counts = s->raw_min_counts;
    } else if (!(v < (float)s->raw_max_counts)) {
        *raw_counts = s->raw_max_counts;
    } else {
        *raw_counts = (uint16_t)(v + 0.5f);
    }
    return PMA_OK;
}
