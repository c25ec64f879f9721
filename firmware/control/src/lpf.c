/* SPDX-License-Identifier: Apache-2.0 */
/* First-order low-pass, float and Q16.16 (see pma/lpf.h). */
#include "pma/lpf.h"
#include "pma/status.h"

#include <stddef.h>
#include "check.h"
#include "fixed_internal.h"
#include "pi.h"

#include <math.h>


int pma_lpf_validate_config(const pma_lpf_config_t *cfg)
{
    if (cfg == NULL) return PMA_ERR_NULL;
    if (!isfinite(cfg->fc_hz) || !isfinite(cfg->period_s)) return PMA_ERR_NOT_FINITE;
    if (!(cfg->fc_hz >= 0.0f) || !(cfg->period_s > 0.0f)) return PMA_ERR_RANGE;
    return PMA_OK;
}

/* k_f = 1 - exp(-2 pi fc T) in (0, 1], 0 when off (fc 0); a k_f of 1 (a cut-off far beyond
 * the sampling rate) passes every sample: 0 as well. expf as the velocity estimators use it (no
 * other libm function linked): at 2 Hz and 1 kHz k_f is exact to 5e-6, far below its Q16.16
 * rounding. */
static float gain(const pma_lpf_config_t *cfg)
{
    const float k = cfg->fc_hz > 0.0f ? 1.0f - expf(-PMA_TWO_PI_F * cfg->fc_hz * cfg->period_s) : 0.0f;
    return k < 1.0f ? k : 0.0f;
}

int pma_lpf_init_f32(pma_lpf_f32_t *s, const pma_lpf_config_t *cfg)
{
    if (s == NULL) return PMA_ERR_NULL;
    s->k = 0.0f;   /* off until configured: a refused configuration passes samples through */
    PMA_CHECK(pma_lpf_validate_config(cfg));
    s->k = gain(cfg);
    pma_lpf_reset_f32(s);
    return PMA_OK;
}

void pma_lpf_reset_f32(pma_lpf_f32_t *s)
{
    if (s == NULL) return;
    s->y = 0.0f;
    s->primed = 0;
}

int pma_lpf_init_q16(pma_lpf_q16_t *s, const pma_lpf_config_t *cfg)
{
    if (s == NULL) return PMA_ERR_NULL;
    s->k = 0;   /* as the float init */
    PMA_CHECK(pma_lpf_validate_config(cfg));
    const float k = gain(cfg);
    if (k > 0.0f) {
        /* 1 LSB at least (a cut-off that rounds to nothing still filters); below 1.0 */
        s->k = pma_to_q(k, 16);
        if (s->k < 1) s->k = 1;
        if (s->k >= PMA_Q16_ONE) s->k = 0;
    }
    pma_lpf_reset_q16(s);
    return PMA_OK;
}

void pma_lpf_reset_q16(pma_lpf_q16_t *s)
{
    if (s == NULL) return;
    s->y = 0;
    s->primed = 0;
}

pma_q16_t pma_lpf_filter_q16(pma_lpf_q16_t *s, pma_q16_t x)
{
    if (!s->primed) {
        s->primed = 1;
        s->y = x;
        return x;
    }
    /* |k_f (x - y)| <= |x - y| (k_f < 1, rounded to nearest): y stays between y and x */
    s->y = pma_q16_sadd(s->y, pma_q16_smul(pma_q16_ssub(x, s->y), s->k));
    return s->y;
}
