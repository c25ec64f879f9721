/* SPDX-License-Identifier: Apache-2.0 */
/* Velocity estimators, fixed-point variant (see pma/velest.h). x and v in
 * Q16.16; p or ga and T in Q2.30; (1-p)/T or gb/T in Q16.16. The tracking
 * observer keeps its position estimate with 32 fractional bits so that the
 * per-step prediction v T (often below 2^-16 cm) is not rounded away. */
#include "pma/velest.h"
#include "pma/status.h"

#include <stddef.h>
#include "check.h"
#include "fixed_internal.h"
#include "pi.h"

#include <math.h>

#define RES_LIMIT ((int64_t)1 << 46)   /* residual clamp: 16384 cm in Q32 */

/* round(r c / 2^shift) for |r| <= 2^46, 0 <= c < 2^31, 16 < shift < 48,
 * computed in two halves so no intermediate exceeds 2^62. */
static int64_t mul_shift(int64_t r, int32_t c, unsigned shift)
{
    const uint64_t ar = (uint64_t)(r < 0 ? -r : r);
    const uint64_t uc = (uint64_t)c;
    const uint64_t acc = (ar >> 16) * uc + (((ar & 0xFFFFu) * uc) >> 16);   /* r c / 2^16 */
    const uint64_t q = (acc + ((uint64_t)1 << (shift - 17u))) >> (shift - 16u);
    return r < 0 ? -(int64_t)q : (int64_t)q;
}

int pma_velest_init_q16(pma_velest_q16_t *s, const pma_velest_config_t *cfg)
{
    if (s == NULL) return PMA_ERR_NULL;
    s->ready = 0;
    PMA_CHECK(pma_velest_validate_config(cfg));
    if (cfg->period_s >= 2.0f) return PMA_ERR_FIXED_RANGE;
    const float p = expf(-PMA_TWO_PI_F * cfg->fc_hz * cfg->period_s);
    float c1, c2;
    if (cfg->kind == PMA_VELEST_FILTERED_DIFF) {
        c1 = p;
        c2 = (1.0f - p) / cfg->period_s;
    } else {
        c1 = 1.0f - p * p;
        c2 = (1.0f - p) * (1.0f - p) / cfg->period_s;
    }
    PMA_CHECK(pma_check_q16_range(c2));
    s->kind = cfg->kind;
    s->c1 = pma_to_q(c1, 30);
    s->c2 = pma_to_q(c2, 16);
    s->ct = pma_to_q(cfg->period_s, 30);
    pma_velest_reset_q16(s);
    s->ready = 1;
    return PMA_OK;
}

void pma_velest_reset_q16(pma_velest_q16_t *s)
{
    if (s == NULL) return;
    s->x1 = 0;
    s->v = 0;
    s->xh_q32 = 0;
    s->primed = 0;
}

int pma_velest_step_q16(pma_velest_q16_t *s, pma_q16_t x_cm, pma_q16_t *v_cm_s)
{
    if (s == NULL || v_cm_s == NULL) return PMA_ERR_NULL;
    if (!s->ready) return PMA_ERR_NOT_READY;
    if (!s->primed) {
        s->x1 = x_cm;
        s->xh_q32 = (int64_t)x_cm * 65536;
        s->v = 0;
        s->primed = 1;
    } else if (s->kind == PMA_VELEST_FILTERED_DIFF) {
        s->v = pma_q16_sadd(pma_q16_smul_q30(s->v, s->c1),
                            pma_q16_smul(s->c2, pma_q16_ssub(x_cm, s->x1)));
        s->x1 = x_cm;
    } else {
        const int64_t xp = s->xh_q32 + pma_rshift_round((int64_t)s->v * s->ct, 14);
        int64_t r = (int64_t)x_cm * 65536 - xp;
        r = r > RES_LIMIT ? RES_LIMIT : (r < -RES_LIMIT ? -RES_LIMIT : r);
        s->xh_q32 = xp + mul_shift(r, s->c1, 30);
        const pma_q16_t dv = pma_q16_sat64(mul_shift(r, s->c2, 32));
        s->v = pma_q16_sadd(s->v, dv);
    }
    *v_cm_s = s->v;
    return PMA_OK;
}
