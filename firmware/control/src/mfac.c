/* SPDX-License-Identifier: Apache-2.0 */
/* CFDL-MFAC: configuration and float variant (see pma/mfac.h). */
#include "pma/mfac.h"
#include "pma/status.h"

#include <stddef.h>
#include "check.h"

#include <math.h>

void pma_mfac_default_config(pma_mfac_config_t *cfg)
{
    if (cfg == NULL) return;
    *cfg = (pma_mfac_config_t){
        .eta = 0.5f, .mu = 1.9f, .rho = 31.7f, .lambda = 0.03f, .eps = 1e-5f,
        .phi1 = 0.5f, .u_min = -400.0f, .u_max = 400.0f, .u_init = 0.0f,
    };
}

int pma_mfac_validate_config(const pma_mfac_config_t *cfg)
{
    if (cfg == NULL) return PMA_ERR_NULL;
    const float all[] = {cfg->eta, cfg->mu, cfg->rho, cfg->lambda, cfg->eps,
                         cfg->phi1, cfg->u_min, cfg->u_max, cfg->u_init};
    PMA_CHECK(pma_check_all_finite(all, sizeof all / sizeof all[0]));
    if (!(cfg->eta > 0.0f && cfg->eta <= 2.0f)) return PMA_ERR_RANGE;
    if (!(cfg->mu > 0.0f && cfg->rho > 0.0f && cfg->lambda > 0.0f)) return PMA_ERR_RANGE;
    if (!(cfg->eps >= 0.0f)) return PMA_ERR_RANGE;
    if (!(fabsf(cfg->phi1) > cfg->eps)) return PMA_ERR_RANGE;
    if (!(cfg->u_min < cfg->u_max)) return PMA_ERR_RANGE;
    if (!(cfg->u_init >= cfg->u_min && cfg->u_init <= cfg->u_max)) return PMA_ERR_RANGE;
    return PMA_OK;
}

int pma_mfac_init_f32(pma_mfac_f32_t *s, const pma_mfac_config_t *cfg)
{
    if (s == NULL) return PMA_ERR_NULL;
    s->ready = 0;
    PMA_CHECK(pma_mfac_validate_config(cfg));
    s->cfg = *cfg;
    pma_mfac_reset_f32(s);
    s->ready = 1;
    return PMA_OK;
}

void pma_mfac_reset_f32(pma_mfac_f32_t *s)
{
    if (s == NULL) return;
    s->phi = s->cfg.phi1;
    s->u1 = s->cfg.u_init;
    s->u2 = s->cfg.u_init;
    s->y1 = 0.0f;
    s->k = 0;
    s->resets = 0;
    s->flags = 0;
}

/* phi(k) from y(k) and the inputs applied at k-1 and k-2 (eq. of pma/mfac.h, with its reset
 * rule); *flags gets PMA_MFAC_FLAG_RESET when the rule put phi back to phi(1). */
static inline float estimate(const pma_mfac_f32_t *s, float y_cm, uint32_t *flags)
{
    const pma_mfac_config_t *c = &s->cfg;
    const float y1 = (s->k == 0) ? y_cm : s->y1;   /* y(-1) = y(0) */
    const float du = s->u1 - s->u2;
    const float dy = y_cm - y1;
    float phi = s->phi + c->eta * du / (c->mu + du * du) * (dy - s->phi * du);
    const int sign_flip = (c->phi1 > 0.0f) ? !(phi > 0.0f) : !(phi < 0.0f);
    if (fabsf(phi) <= c->eps || fabsf(du) <= c->eps || sign_flip) {
        phi = c->phi1;
        *flags |= PMA_MFAC_FLAG_RESET;
    }
    return phi;
}

/* the state after step k: phi(k), the input u applied at k, y(k) */
static inline void commit(pma_mfac_f32_t *s, float phi, float u, float y_cm, uint32_t flags)
{
    s->phi = phi;
    s->u2 = s->u1;
    s->u1 = u;
    s->y1 = y_cm;
    s->k++;
    if (flags & PMA_MFAC_FLAG_RESET) s->resets++;
    s->flags = flags;
}

int pma_mfac_step_f32(pma_mfac_f32_t *s, float y_cm, float yref_next_cm, float *u)
{
    if (s == NULL || u == NULL) return PMA_ERR_NULL;
    if (!s->ready) return PMA_ERR_NOT_READY;
    if (!isfinite(y_cm) || !isfinite(yref_next_cm)) return PMA_ERR_NOT_FINITE;
    const pma_mfac_config_t *c = &s->cfg;
    uint32_t flags = 0;
    const float phi = estimate(s, y_cm, &flags);
    float v = s->u1 + c->rho * phi / (c->lambda + phi * phi) * (yref_next_cm - y_cm);
    if (!isfinite(v)) return PMA_ERR_NOT_FINITE;   /* inputs far outside any sane range */
    if (v > c->u_max) {
        v = c->u_max;
        flags |= PMA_MFAC_FLAG_SAT_HIGH;
    } else if (v < c->u_min) {
        v = c->u_min;
        flags |= PMA_MFAC_FLAG_SAT_LOW;
    }
    commit(s, phi, v, y_cm, flags);
    *u = v;
    return PMA_OK;
}

int pma_mfac_take_over_f32(pma_mfac_f32_t *s, float u_start)
{
    if (s == NULL) return PMA_ERR_NULL;
    if (!s->ready) return PMA_ERR_NOT_READY;
    if (!isfinite(u_start)) return PMA_ERR_NOT_FINITE;
    const pma_mfac_config_t *c = &s->cfg;
    s->u1 = s->u2 = u_start > c->u_max ? c->u_max : (u_start < c->u_min ? c->u_min : u_start);
    return PMA_OK;
}
