/* SPDX-License-Identifier: Apache-2.0 */
/* Reference generators and the constraint band: configuration, bounds and
 * float variant (see pma/ref.h). Sines are evaluated from the fractional part
 * of the phase in turns, so long runs keep their precision. */
#include "pma/ref.h"
#include "pma/status.h"

#include <stddef.h>
#include "check.h"
#include "pi.h"

#include <math.h>


int pma_ref_validate_config(const pma_ref_config_t *cfg)
{
    if (cfg == NULL) return PMA_ERR_NULL;
    const float all[] = {cfg->offset_cm, cfg->amplitude_cm, cfg->freq_hz, cfg->phase_rad,
                         cfg->t0_s, cfg->rate_cm_s};
    PMA_CHECK(pma_check_all_finite(all, sizeof all / sizeof all[0]));
    switch (cfg->kind) {
    case PMA_REF_HOLD:
    case PMA_REF_CASE1:
    case PMA_REF_CASE3:
        return PMA_OK;
    case PMA_REF_STEP:
    case PMA_REF_RAMP:
        return cfg->t0_s >= 0.0f ? PMA_OK : PMA_ERR_RANGE;
    case PMA_REF_SINE:
        return cfg->freq_hz >= 0.0f ? PMA_OK : PMA_ERR_RANGE;
    case PMA_REF_STREAM:
        return cfg->rate_cm_s >= 0.0f ? PMA_OK : PMA_ERR_RANGE;
    default:
        return PMA_ERR_RANGE;
    }
}

int pma_ref_bounds(const pma_ref_config_t *cfg, float t_end_s, float *min_cm, float *max_cm)
{
    if (min_cm == NULL || max_cm == NULL) return PMA_ERR_NULL;
    PMA_CHECK(pma_ref_validate_config(cfg));
    PMA_CHECK(pma_check_finite(t_end_s));
    if (t_end_s < 0.0f) return PMA_ERR_RANGE;
    const float off = cfg->offset_cm, amp = fabsf(cfg->amplitude_cm);
    float lo = off, hi = off;
    switch (cfg->kind) {
    case PMA_REF_STEP:
        if (t_end_s >= cfg->t0_s) {
            lo = fminf(off, off + cfg->amplitude_cm);
            hi = fmaxf(off, off + cfg->amplitude_cm);
        }
        break;
    case PMA_REF_RAMP:
        if (t_end_s > cfg->t0_s) {
            float end = off + cfg->rate_cm_s * (t_end_s - cfg->t0_s);
            end = fminf(fmaxf(end, off - amp), off + amp);
            lo = fminf(off, end);
            hi = fmaxf(off, end);
        }
        break;
    case PMA_REF_SINE:
        lo = off - amp;
        hi = off + amp;
        break;
    case PMA_REF_CASE1:
        lo = -2.5f;
        hi = -1.5f;
        break;
    case PMA_REF_CASE3:   /* envelope -2 +- t/360 */
        lo = -2.0f - t_end_s / 360.0f;
        hi = -2.0f + t_end_s / 360.0f;
        break;
    default:              /* HOLD, STREAM: the offset */
        break;
    }
    *min_cm = lo;
    *max_cm = hi;
    return PMA_OK;
}

pma_band_t pma_band_constant(float k_low_cm, float k_high_cm)
{
    return (pma_band_t){.low = {.kind = PMA_REF_HOLD, .offset_cm = k_low_cm},
                        .high = {.kind = PMA_REF_HOLD, .offset_cm = k_high_cm}};
}

int pma_band_validate(const pma_band_t *band, float t_end_s)
{
    if (band == NULL) return PMA_ERR_NULL;
    if (band->low.kind == PMA_REF_STREAM || band->high.kind == PMA_REF_STREAM) {
        return PMA_ERR_UNSUPPORTED;
    }
    float lo_min, lo_max, hi_min, hi_max;
    PMA_CHECK(pma_ref_bounds(&band->low, t_end_s, &lo_min, &lo_max));
    PMA_CHECK(pma_ref_bounds(&band->high, t_end_s, &hi_min, &hi_max));
    return lo_max < hi_min ? PMA_OK : PMA_ERR_BAND;
}

int pma_band_contains(const pma_band_t *band, float t_s, float x_cm)
{
    float lo, hi;
    if (band == NULL || pma_ref_value_f32(&band->low, t_s, &lo, NULL) != PMA_OK ||
        pma_ref_value_f32(&band->high, t_s, &hi, NULL) != PMA_OK) {
        return 0;
    }
    return (x_cm > lo && x_cm < hi) ? 1 : 0;
}

int pma_band_check_ref(const pma_band_t *band, const pma_ref_config_t *cfg, float t_end_s,
                       float margin_cm)
{
    PMA_CHECK(pma_band_validate(band, t_end_s));
    PMA_CHECK(pma_check_finite(margin_cm));
    if (margin_cm < 0.0f) return PMA_ERR_RANGE;
    float lo_min, lo_max, hi_min, hi_max, r_min, r_max;
    PMA_CHECK(pma_ref_bounds(&band->low, t_end_s, &lo_min, &lo_max));
    PMA_CHECK(pma_ref_bounds(&band->high, t_end_s, &hi_min, &hi_max));
    PMA_CHECK(pma_ref_bounds(cfg, t_end_s, &r_min, &r_max));
    if (!(lo_max < r_min - margin_cm && r_max + margin_cm < hi_min)) return PMA_ERR_BAND;
    return PMA_OK;
}

int pma_ref_init_f32(pma_ref_f32_t *s, const pma_ref_config_t *cfg)
{
    if (s == NULL) return PMA_ERR_NULL;
    s->ready = 0;
    PMA_CHECK(pma_ref_validate_config(cfg));
    s->cfg = *cfg;
    pma_ref_reset_f32(s);
    s->ready = 1;
    return PMA_OK;
}

void pma_ref_reset_f32(pma_ref_f32_t *s)
{
    if (s == NULL) return;
    s->stream_target = s->cfg.offset_cm;
    s->stream_value = s->cfg.offset_cm;
    s->last_t = 0.0f;
}

/* sin and cos of 2 pi (turns) + phase, reducing turns to its fraction first. */
static void sincos_turns(float turns, float phase_rad, float *sn, float *cs)
{
    const float ph = PMA_TWO_PI_F * (turns - floorf(turns)) + phase_rad;
    *sn = sinf(ph);
    *cs = cosf(ph);
}

int pma_ref_value_f32(const pma_ref_config_t *c, float t_s, float *xr_cm, float *xr_dot_cm_s)
{
    if (c == NULL || xr_cm == NULL) return PMA_ERR_NULL;
    if (c->kind == PMA_REF_STREAM) return PMA_ERR_UNSUPPORTED;
    if (!isfinite(t_s)) return PMA_ERR_NOT_FINITE;
    if (t_s < 0.0f) return PMA_ERR_RANGE;
    float x = c->offset_cm, d = 0.0f, sn, cs;
    switch (c->kind) {
    case PMA_REF_STEP:
        if (t_s >= c->t0_s) x += c->amplitude_cm;
        break;
    case PMA_REF_RAMP:
        if (t_s >= c->t0_s) {
            const float lim = fabsf(c->amplitude_cm);
            x = c->offset_cm + c->rate_cm_s * (t_s - c->t0_s);
            d = c->rate_cm_s;
            if (x > c->offset_cm + lim) {
                x = c->offset_cm + lim;
                d = 0.0f;
            } else if (x < c->offset_cm - lim) {
                x = c->offset_cm - lim;
                d = 0.0f;
            }
        }
        break;
    case PMA_REF_SINE:
        sincos_turns(c->freq_hz * t_s, c->phase_rad, &sn, &cs);
        x += c->amplitude_cm * sn;
        d = c->amplitude_cm * PMA_TWO_PI_F * c->freq_hz * cs;
        break;
    case PMA_REF_CASE1:   /* -0.5 sin(t) - 2 */
        sincos_turns(t_s / PMA_TWO_PI_F, 0.0f, &sn, &cs);
        x = -0.5f * sn - 2.0f;
        d = -0.5f * cs;
        break;
    case PMA_REF_CASE3: { /* t sin(2 pi t (1 + t/55)/55 - pi/2)/360 - 2 */
        const float a = t_s / 55.0f;
        sincos_turns(a * (1.0f + a), -0.25f * PMA_TWO_PI_F, &sn, &cs);
        const float dphi = PMA_TWO_PI_F * (1.0f + 2.0f * a) / 55.0f;
        x = t_s * sn / 360.0f - 2.0f;
        d = sn / 360.0f + t_s * cs * dphi / 360.0f;
        break;
    }
    case PMA_REF_HOLD:
        break;
    default:
        return PMA_ERR_RANGE;
    }
    *xr_cm = x;
    if (xr_dot_cm_s != NULL) *xr_dot_cm_s = d;
    return PMA_OK;
}

int pma_ref_eval_f32(pma_ref_f32_t *s, float t_s, float *xr_cm, float *xr_dot_cm_s)
{
    if (s == NULL || xr_cm == NULL) return PMA_ERR_NULL;
    if (!s->ready) return PMA_ERR_NOT_READY;
    if (s->cfg.kind != PMA_REF_STREAM) return pma_ref_value_f32(&s->cfg, t_s, xr_cm, xr_dot_cm_s);
    if (!isfinite(t_s)) return PMA_ERR_NOT_FINITE;
    if (t_s < 0.0f) return PMA_ERR_RANGE;
    /* STREAM: move towards the last target at most rate per second */
    const float dt = fmaxf(t_s - s->last_t, 0.0f);
    const float old = s->stream_value;
    float v = s->stream_target;
    if (s->cfg.rate_cm_s > 0.0f) {
        const float step = s->cfg.rate_cm_s * dt;
        v = fminf(fmaxf(v, old - step), old + step);
    }
    s->stream_value = v;
    s->last_t = t_s;
    *xr_cm = v;
    if (xr_dot_cm_s != NULL) *xr_dot_cm_s = dt > 0.0f ? (v - old) / dt : 0.0f;
    return PMA_OK;
}

int pma_ref_stream_f32(pma_ref_f32_t *s, float target_cm)
{
    if (s == NULL) return PMA_ERR_NULL;
    if (!s->ready) return PMA_ERR_NOT_READY;
    if (s->cfg.kind != PMA_REF_STREAM) return PMA_ERR_UNSUPPORTED;
    if (!isfinite(target_cm)) return PMA_ERR_NOT_FINITE;
    s->stream_target = target_cm;
    return PMA_OK;
}
