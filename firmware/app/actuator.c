/* SPDX-License-Identifier: Apache-2.0 */
/* Actuator limits and the safe state: see actuator.h. */
#include "actuator.h"

#include <math.h>
#include <stddef.h>

#include "pma/status.h"
#include "pma/finite.h"

int pma_actuator_validate(const pma_actuator_config_t *c)
{
    if (c == NULL) return PMA_ERR_NULL;
    const float all[] = {c->p0_kpa, c->kpa_per_u, c->p_min_kpa, c->p_max_kpa, c->slew_kpa_s,
                         c->safe_kpa};
    for (size_t i = 0; i < sizeof all / sizeof all[0]; ++i) {
        if (!pma_isfinite_f32(all[i])) return PMA_ERR_NOT_FINITE;
    }
    if (c->polarity != 1 && c->polarity != -1) return PMA_ERR_RANGE;
    if (!(c->p_min_kpa >= 0.0f && c->p_min_kpa < c->p_max_kpa)) return PMA_ERR_RANGE;
    if (!(c->p0_kpa >= c->p_min_kpa && c->p0_kpa <= c->p_max_kpa)) return PMA_ERR_RANGE;
    if (!(c->kpa_per_u > 0.0f && c->slew_kpa_s >= 0.0f)) return PMA_ERR_RANGE;
    if (c->safe_mode > PMA_SAFE_FIXED) return PMA_ERR_RANGE;
    if (c->safe_mode == PMA_SAFE_FIXED && !(c->safe_kpa >= 0.0f && c->safe_kpa <= c->p_max_kpa)) {
        return PMA_ERR_RANGE;
    }
    return PMA_OK;
}

float pma_actuator_safe_kpa(const pma_actuator_config_t *c, float p_prev_kpa)
{
    switch (c->safe_mode) {
    case PMA_SAFE_HOLD:
        return (pma_isfinite_f32(p_prev_kpa) && p_prev_kpa >= 0.0f) ? p_prev_kpa : 0.0f;
    case PMA_SAFE_FIXED:
        /* never above the actuator's limit, whatever the order the parameters were set in */
        return c->safe_kpa < c->p_max_kpa ? c->safe_kpa : c->p_max_kpa;
    default:
        return 0.0f;
    }
}

float pma_actuator_active_kpa(const pma_actuator_config_t *c, float u, float p_prev_kpa,
                              float period_s)
{
    if (!pma_isfinite_f32(u) || !pma_isfinite_f32(p_prev_kpa)) return pma_actuator_safe_kpa(c, p_prev_kpa);
    float p = c->p0_kpa + (float)c->polarity * c->kpa_per_u * u;
    if (p < c->p_min_kpa) p = c->p_min_kpa;
    if (p > c->p_max_kpa) p = c->p_max_kpa;
    if (c->slew_kpa_s > 0.0f) {
        const float step = c->slew_kpa_s * period_s;
        if (p > p_prev_kpa + step) p = p_prev_kpa + step;
        if (p < p_prev_kpa - step) p = p_prev_kpa - step;
    }
    return p;
}
