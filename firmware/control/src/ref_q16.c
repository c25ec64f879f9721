/* SPDX-License-Identifier: Apache-2.0 */
/* Reference generators, fixed-point variant (see pma/ref.h). Positions in
 * Q16.16 cm, time in Q16.16 s (t >= 0). Phases are unsigned Q0.32 fractions
 * of a turn: their arithmetic wraps modulo one turn exactly (unsigned
 * overflow is defined), so precision does not degrade with time. */
#include "pma/ref.h"
#include "pma/status.h"

#include <stddef.h>
#include "check.h"
#include "pi.h"
#include "fixed_internal.h"

#include <math.h>

#define INV_2PI_Q32 ((uint64_t)683565276u)    /* 2^32 / (2 pi) */
#define INV_55_Q32 ((uint64_t)78090314u)      /* 2^32 / 55 */
#define INV_360_Q32 ((uint64_t)11930465u)     /* 2^32 / 360 */
#define INV_360_Q30 ((int64_t)2982616)        /* 2^30 / 360 */
#define QUARTER_TURN 0x40000000u
#define Q24_ONE ((uint64_t)1 << 24)

int pma_ref_init_q16(pma_ref_q16_t *s, const pma_ref_config_t *cfg)
{
    if (s == NULL) return PMA_ERR_NULL;
    s->ready = 0;
    PMA_CHECK(pma_ref_validate_config(cfg));
    const float vals[] = {cfg->offset_cm, cfg->amplitude_cm, cfg->t0_s, cfg->rate_cm_s,
                          PMA_TWO_PI_F * cfg->freq_hz};
    for (unsigned i = 0; i < sizeof vals / sizeof vals[0]; ++i) {
        PMA_CHECK(pma_check_q16_range(vals[i]));
    }
    if (cfg->freq_hz >= 127.0f) return PMA_ERR_FIXED_RANGE;   /* Q8.24 */
    s->kind = cfg->kind;
    s->offset = pma_to_q(cfg->offset_cm, 16);
    s->amplitude = pma_to_q(cfg->amplitude_cm, 16);
    s->t0 = pma_to_q(cfg->t0_s, 16);
    s->rate = pma_to_q(cfg->rate_cm_s, 16);
    s->freq_q24 = pma_to_q(cfg->freq_hz, 24);
    s->omega = pma_to_q(PMA_TWO_PI_F * cfg->freq_hz, 16);
    /* phase as a fraction of a turn, reduced to [0, 1) */
    const float turns = cfg->phase_rad / PMA_TWO_PI_F;
    const float frac = turns - floorf(turns);
    s->phase_frac32 = (uint32_t)pma_to_q(frac, 30) << 2;   /* frac 2^32; 1.0 wraps to 0 */
    pma_ref_reset_q16(s);
    s->ready = 1;
    return PMA_OK;
}

void pma_ref_reset_q16(pma_ref_q16_t *s)
{
    if (s == NULL) return;
    s->stream_target = s->offset;
    s->stream_value = s->offset;
    s->last_t = 0;
}

/* t (Q16.16, >= 0) times k (Q0.32 scale of a turn per unit) -> fraction of a turn. */
static uint32_t turns_frac(pma_q16_t t, uint64_t k_q32)
{
    return (uint32_t)(((uint64_t)t * k_q32) >> 16);
}

int pma_ref_eval_q16(pma_ref_q16_t *s, pma_q16_t t_s, pma_q16_t *xr_cm, pma_q16_t *xr_dot_cm_s)
{
    if (s == NULL || xr_cm == NULL) return PMA_ERR_NULL;
    if (!s->ready) return PMA_ERR_NOT_READY;
    if (t_s < 0) return PMA_ERR_RANGE;
    pma_q16_t x = s->offset, d = 0;
    switch (s->kind) {
    case PMA_REF_STEP:
        if (t_s >= s->t0) x = pma_q16_sadd(x, s->amplitude);
        break;
    case PMA_REF_RAMP:
        if (t_s >= s->t0) {
            const pma_q16_t lim = s->amplitude < 0 ? pma_q16_sneg(s->amplitude) : s->amplitude;
            const pma_q16_t hi = pma_q16_sadd(s->offset, lim), lo = pma_q16_ssub(s->offset, lim);
            x = pma_q16_sadd(s->offset, pma_q16_smul(s->rate, pma_q16_ssub(t_s, s->t0)));
            d = s->rate;
            if (x > hi) {
                x = hi;
                d = 0;
            } else if (x < lo) {
                x = lo;
                d = 0;
            }
        }
        break;
    case PMA_REF_SINE: {
        /* t (Q16) x f (Q8.24) = turns in Q40: bits 8..39 are the fraction */
        const uint32_t ph = (uint32_t)(((uint64_t)t_s * (uint64_t)s->freq_q24) >> 8) +
                            s->phase_frac32;
        x = pma_q16_sadd(x, pma_q16_smul_q30(s->amplitude, pma_q30_sin_2pi_frac32(ph)));
        d = pma_q16_smul_q30(pma_q16_smul(s->amplitude, s->omega),
                             pma_q30_sin_2pi_frac32(ph + QUARTER_TURN));
        break;
    }
    case PMA_REF_CASE1: {  /* -0.5 sin(t) - 2 */
        const uint32_t ph = turns_frac(t_s, INV_2PI_Q32);
        x = pma_q16_ssub(pma_q16_smul_q30(-PMA_Q16_ONE / 2, pma_q30_sin_2pi_frac32(ph)),
                         2 * PMA_Q16_ONE);
        d = pma_q16_smul_q30(-PMA_Q16_ONE / 2, pma_q30_sin_2pi_frac32(ph + QUARTER_TURN));
        break;
    }
    case PMA_REF_CASE3: {  /* t sin(2 pi t (1 + t/55)/55 - pi/2)/360 - 2 */
        const uint64_t a_q24 = ((uint64_t)t_s * INV_55_Q32) >> 24;         /* t/55 */
        /* turns = a (1 + a) in Q48; the wrapping product keeps the fraction exact */
        const uint64_t turns_q48 = a_q24 * (Q24_ONE + a_q24);
        const uint32_t ph = (uint32_t)(turns_q48 >> 16) - QUARTER_TURN;
        const pma_q30_t sn = pma_q30_sin_2pi_frac32(ph);
        const pma_q30_t cs = pma_q30_sin_2pi_frac32(ph + QUARTER_TURN);
        const pma_q16_t amp = (pma_q16_t)(((uint64_t)t_s * INV_360_Q32) >> 32);  /* t/360 */
        x = pma_q16_ssub(pma_q16_smul_q30(amp, sn), 2 * PMA_Q16_ONE);
        /* phi' = 2 pi (1 + 2 t/55) / 55 [rad/s], Q16.16 */
        const pma_q16_t dphi = pma_q16_sat64(
            PMA_TWO_PI_55_Q16 + pma_rshift_round(PMA_TWO_PI_55_Q16 * 2 * (int64_t)a_q24, 24));
        const pma_q16_t d1 = pma_q16_sat64(pma_rshift_round((int64_t)sn * INV_360_Q30, 44));
        d = pma_q16_sadd(d1, pma_q16_smul(pma_q16_smul_q30(amp, cs), dphi));
        break;
    }
    case PMA_REF_STREAM: {
        const pma_q16_t dt = t_s > s->last_t ? pma_q16_ssub(t_s, s->last_t) : 0;
        const pma_q16_t old = s->stream_value;
        pma_q16_t v = s->stream_target;
        if (s->rate > 0) {
            const pma_q16_t step = pma_q16_smul(s->rate, dt);
            const pma_q16_t lo = pma_q16_ssub(old, step), hi = pma_q16_sadd(old, step);
            v = pma_q16_clamp(v, lo, hi);
        }
        s->stream_value = v;
        s->last_t = t_s;
        x = v;
        d = dt > 0 ? pma_q16_sdiv(pma_q16_ssub(v, old), dt) : 0;
        break;
    }
    default:               /* HOLD */
        break;
    }
    *xr_cm = x;
    if (xr_dot_cm_s != NULL) *xr_dot_cm_s = d;
    return PMA_OK;
}

int pma_ref_stream_q16(pma_ref_q16_t *s, pma_q16_t target_cm)
{
    if (s == NULL) return PMA_ERR_NULL;
    if (!s->ready) return PMA_ERR_NOT_READY;
    if (s->kind != PMA_REF_STREAM) return PMA_ERR_UNSUPPORTED;
    s->stream_target = target_cm;
    return PMA_OK;
}
