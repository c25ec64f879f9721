/* SPDX-License-Identifier: Apache-2.0 */
/* Velocity estimators: configuration, noise gain and float variant
 * (see pma/velest.h). */
#include "pma/velest.h"
#include "pma/status.h"

#include <stddef.h>
#include "check.h"
#include "pi.h"

#include <math.h>


void pma_velest_default_config(pma_velest_config_t *cfg)
{
    if (cfg == NULL) return;
    *cfg = (pma_velest_config_t){.kind = PMA_VELEST_FILTERED_DIFF, .fc_hz = 30.0f,
                                 .period_s = 1e-3f};
}

int pma_velest_validate_config(const pma_velest_config_t *cfg)
{
    if (cfg == NULL) return PMA_ERR_NULL;
    PMA_CHECK(pma_check_finite(cfg->fc_hz));
    PMA_CHECK(pma_check_finite(cfg->period_s));
    if (cfg->kind != PMA_VELEST_FILTERED_DIFF && cfg->kind != PMA_VELEST_TRACKING) {
        return PMA_ERR_RANGE;
    }
    if (!(cfg->period_s > 0.0f && cfg->fc_hz > 0.0f)) return PMA_ERR_RANGE;
    if (!(cfg->fc_hz < 0.5f / cfg->period_s)) return PMA_ERR_RANGE;   /* below Nyquist */
    return PMA_OK;
}

/* Steady-state std of v per unit std of white x noise, from the sum of the
 * squared impulse response of each recursion (closed forms, see docs). */
float pma_velest_noise_gain(const pma_velest_config_t *cfg)
{
    if (pma_velest_validate_config(cfg) != PMA_OK) return NAN;
    const double T = (double)cfg->period_s; /* this figure is computed in double */
    const double p = exp(-2.0 * PMA_PI * (double)cfg->fc_hz * T);
    if (cfg->kind == PMA_VELEST_FILTERED_DIFF) {
        return (float)((1.0 - p) / T * sqrt(2.0 / (1.0 + p)));
    }
    /* tracking observer (double pole at p): the steady-state variance is the
     * sum of the squared impulse response from x to v, summed until the
     * terms are negligible (they decay geometrically, like p^k). */
    const double ga = 1.0 - p * p, gb = (1.0 - p) * (1.0 - p);
    double xh = 0.0, vh = 0.0, sum = 0.0;
    for (int k = 0; k < 100000; ++k) {
        const double x = (k == 0) ? 1.0 : 0.0;
        const double xp = xh + T * vh;
        const double r = x - xp;
        xh = xp + ga * r;
        vh = vh + gb / T * r;
        sum += vh * vh;
        if (k > 10 && vh * vh < 1e-30 * sum) break;
    }
    return (float)sqrt(sum);
}

static void coefficients(const pma_velest_config_t *cfg, float *c1, float *c2)
{
    const float p = expf(-PMA_TWO_PI_F * cfg->fc_hz * cfg->period_s);
    if (cfg->kind == PMA_VELEST_FILTERED_DIFF) {
        *c1 = p;
        *c2 = (1.0f - p) / cfg->period_s;
    } else {
        *c1 = 1.0f - p * p;                              /* ga */
        *c2 = (1.0f - p) * (1.0f - p) / cfg->period_s;   /* gb / T */
    }
}

int pma_velest_init_f32(pma_velest_f32_t *s, const pma_velest_config_t *cfg)
{
    if (s == NULL) return PMA_ERR_NULL;
    s->ready = 0;
    PMA_CHECK(pma_velest_validate_config(cfg));
    s->cfg = *cfg;
    coefficients(cfg, &s->c1, &s->c2);
    pma_velest_reset_f32(s);
    s->ready = 1;
    return PMA_OK;
}

void pma_velest_reset_f32(pma_velest_f32_t *s)
{
    if (s == NULL) return;
    s->x1 = 0.0f;
    s->xh = 0.0f;
    s->v = 0.0f;
    s->primed = 0;
}

int pma_velest_step_f32(pma_velest_f32_t *s, float x_cm, float *v_cm_s)
{
    if (s == NULL || v_cm_s == NULL) return PMA_ERR_NULL;
    if (!s->ready) return PMA_ERR_NOT_READY;
    if (!isfinite(x_cm)) return PMA_ERR_NOT_FINITE;
    if (!s->primed) {
        s->x1 = x_cm;
        s->xh = x_cm;
        s->v = 0.0f;
        s->primed = 1;
    } else if (s->cfg.kind == PMA_VELEST_FILTERED_DIFF) {
        s->v = s->c1 * s->v + s->c2 * (x_cm - s->x1);
        s->x1 = x_cm;
    } else {
        const float xp = s->xh + s->cfg.period_s * s->v;
        const float r = x_cm - xp;
        s->xh = xp + s->c1 * r;
        s->v = s->v + s->c2 * r;
    }
    *v_cm_s = s->v;
    return PMA_OK;
}
