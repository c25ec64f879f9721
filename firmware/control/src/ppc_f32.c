/* SPDX-License-Identifier: Apache-2.0 */
/* The paper's controller, float variant (eq. 15-22; see pma/ppc.h). */
#include "pma/ppc.h"
#include "pma/status.h"
#include "pma/trig.h"
#include "pi.h"

#include <stddef.h>

#include <math.h>


int pma_ppc_init_f32(pma_ppc_f32_t *s, const pma_ppc_config_t *cfg)
{
    if (s == NULL) return PMA_ERR_NULL;
    s->ready = 0;
    const int rc = pma_ppc_validate_config(cfg);
    if (rc != PMA_OK) return rc;
    s->cfg = *cfg;
    s->inv_w1 = 1.0f / cfg->w1_cm;
    s->inv_w2 = 1.0f / cfg->w2_cm_s;
    s->r_max = 1.0f - cfg->barrier_margin;
    s->soft_tan = (cfg->soft_barrier_r < 1.0f) ? pma_tan_halfpi_f32(cfg->soft_barrier_r) : 0.0f;
    s->soft_sec2 = 1.0f + s->soft_tan * s->soft_tan;
    pma_ppc_reset_f32(s);
    s->ready = 1;
    return PMA_OK;
}

#define WIDEN_ON 4u   /* widen_bits: channel 0 widens (WIDEN_ON << 1: channel 1) */

void pma_ppc_reset_f32(pma_ppc_f32_t *s)
{
    if (s == NULL) return;
    s->u_ff = s->cfg.ff_init;
    s->widen_bits = 0u;
    if (s->cfg.widen_r > 0.0f) s->widen_bits = WIDEN_ON | (s->cfg.widen2_steps ? WIDEN_ON << 1 : 0u);
    s->clamp_run2 = 0;
    s->breaches1 = 0;
    s->breaches2 = 0;
    s->out = (pma_ppc_out_f32_t){0};
    s->out.u_ff = s->u_ff;
}

/* Error transformation tan(pi r / 2) with the barrier clamp and the optional
 * soft barrier; writes sec^2 of the same argument. */
static float transform(const pma_ppc_f32_t *s, float r, float *sec2, uint32_t *flags,
                       uint32_t barrier_flag, uint32_t soft_flag)
{
    float ar = fabsf(r);
    if (ar >= s->r_max) {
        *flags |= barrier_flag;
        ar = s->r_max;
    }
    float t;
    if (ar > s->cfg.soft_barrier_r) {
        *flags |= soft_flag;
        *sec2 = s->soft_sec2;
        t = s->soft_tan + PMA_HALF_PI_F * s->soft_sec2 * (ar - s->cfg.soft_barrier_r);
    } else {
        t = pma_tan_halfpi_f32(ar);
        *sec2 = 1.0f + t * t;
    }
    return r < 0.0f ? -t : t;
}

#define WIDEN_K_MIN (1.0f / 1048576.0f)   /* 2^-20: the widening's floor */

/* The tuning function alpha(t) (eq. 15): 0.5 - 0.5 cos(pi t / t_u) before t_u, 1 from t_u on. */
static float tuning_alpha(const pma_ppc_f32_t *s, float t_s)
{
    return (t_s < s->cfg.t_u_s) ? 0.5f - 0.5f * pma_cos_pi_f32(t_s / s->cfg.t_u_s) : 1.0f;
}

/* Funnel scale g_i at t (ppc.h, "Funnel widening") of a channel wider than assigned:
 * g = 1 - (1 - k)(1 - alpha(t - t_i)), the tuning function from the widening on; t_u after it
 * the funnel is as assigned again (the step's common case again). */
static float widen_scale(pma_ppc_f32_t *s, int i, float t_s)
{
    const float dt = t_s - s->widen_t_s[i];
    if (!(dt < s->cfg.t_u_s)) {
        s->widen_bits &= ~(1u << i);
        return 1.0f;
    }
    return 1.0f - (1.0f - s->widen_k[i]) * (1.0f - tuning_alpha(s, fmaxf(dt, 0.0f)));
}

/* r_i = raw g_i of channel i (0: lambda1, 1: lambda2; raw = lambda_i / w_i) where its funnel
 * is wider than assigned or the channel widens and raw is at the clamp: where |r_i| reaches
 * the clamp (lambda2: for widen2_steps steps in a row), its funnel widens so that
 * |r_i| = widen_r (flag WIDEN1/2). Writes g_i (and flag
 * WIDE while g_i < 1); the clamp itself is transform's. */
static float channel_r_wide(pma_ppc_f32_t *s, int i, float t_s, float raw, float *g,
                            uint32_t *flags)
{
    float k = (s->widen_bits & (1u << i)) ? widen_scale(s, i, t_s) : 1.0f;
    const float ar = fabsf(raw * k);
    const int at_clamp = (s->widen_bits & (WIDEN_ON << i)) && ar >= s->r_max;
    if (i == 1) s->clamp_run2 = at_clamp ? s->clamp_run2 + (s->clamp_run2 != UINT32_MAX) : 0u;
    if (at_clamp && (i == 0 || s->clamp_run2 >= s->cfg.widen2_steps)) {
        if (i == 1) s->clamp_run2 = 0;
        k = fmaxf(k * (s->cfg.widen_r / ar), WIDEN_K_MIN);
        s->widen_k[i] = k;
        s->widen_t_s[i] = t_s;
        s->widen_bits |= 1u << i;
        *flags |= PMA_PPC_FLAG_WIDEN1 << i;
    }
    if (k < 1.0f) *flags |= PMA_PPC_FLAG_WIDE;
    *g = k;
    return raw * k;
}

/* r_i of channel i in the step. The common case costs what the paper's law alone does: the
 * funnel as assigned and raw inside the clamp, or widening off. */
static inline float channel_r(pma_ppc_f32_t *s, int i, float t_s, float raw, float *g,
                              uint32_t *flags)
{
    const uint32_t bits = s->widen_bits;
    if (!(bits & (1u << i)) && (!(bits & (WIDEN_ON << i)) || fabsf(raw) < s->r_max)) {
        if (i == 1) s->clamp_run2 = 0;
        *g = 1.0f;
        return raw;
    }
    return channel_r_wide(s, i, t_s, raw, g, flags);
}

int pma_ppc_step_ext_f32(pma_ppc_f32_t *s, float t_s, float x_cm, float v_cm_s, float xr_cm,
                         float u_ext, float *u)
{
    if (s == NULL || u == NULL) return PMA_ERR_NULL;
    if (!s->ready) return PMA_ERR_NOT_READY;
    if (!isfinite(t_s) || !isfinite(x_cm) || !isfinite(v_cm_s) || !isfinite(xr_cm) ||
        !isfinite(u_ext)) {
        return PMA_ERR_NOT_FINITE;
    }
    if (t_s < 0.0f) return PMA_ERR_RANGE;

    pma_ppc_out_f32_t o;   /* every field is set below (not zeroed: a memset call per step) */
    o.flags = 0;
    o.alpha = tuning_alpha(s, t_s);                                           /* 15 */
    o.e_cm = x_cm - xr_cm;                                                    /* 8 */
    o.lambda1_cm = o.alpha * o.e_cm;                                          /* 16 */
    if (!isfinite(o.lambda1_cm)) return PMA_ERR_NOT_FINITE;   /* inputs too far apart */
    float sec2;
    const float r1 = channel_r(s, 0, t_s, o.lambda1_cm * s->inv_w1, &o.g1, &o.flags);
    o.chi = transform(s, r1, &sec2, &o.flags,
                      PMA_PPC_FLAG_BARRIER1, PMA_PPC_FLAG_SOFT1);             /* 18 */
    o.theta_cm_s = -s->cfg.a_cm_s * o.chi;                                   /* 17 */
    o.lambda2_cm_s = o.alpha * v_cm_s - o.theta_cm_s;                         /* 19 */
    if (!isfinite(o.lambda2_cm_s)) return PMA_ERR_NOT_FINITE;
    const float r2 = channel_r(s, 1, t_s, o.lambda2_cm_s * s->inv_w2, &o.g2, &o.flags);
    o.delta = transform(s, r2, &sec2, &o.flags,
                        PMA_PPC_FLAG_BARRIER2, PMA_PPC_FLAG_SOFT2);           /* 22 */
    o.beta_s_cm = sec2 * s->inv_w2;                                           /* 21 */
    if (o.g2 < 1.0f) o.beta_s_cm *= o.g2;   /* the widened funnel's 1/w2 */
    o.u_law = -s->cfg.c * o.beta_s_cm * o.delta;                              /* 20 */

    o.u_ff = s->u_ff;
    const float v = o.u_ff + o.u_law + u_ext;   /* the clamp and anti-windup see the whole output */
    if (v > s->cfg.u_max) {
        o.flags |= PMA_PPC_FLAG_SAT_HIGH;
        o.u = s->cfg.u_max;
    } else if (v < s->cfg.u_min) {
        o.flags |= PMA_PPC_FLAG_SAT_LOW;
        o.u = s->cfg.u_min;
    } else {
        o.u = v;
    }

    /* optional steady-state feedforward: integrate the law's output unless the
     * output is saturated in the direction the law pushes (anti-windup) or the muscle closes on
     * the reference faster than ff_hold_speed_cm_s (FF_HOLD, an option) */
    if (s->cfg.ff_gain_per_s > 0.0f) {
        const float hold_v = s->cfg.ff_hold_speed_cm_s;
        if (hold_v > 0.0f &&
            ((o.e_cm > 0.0f && v_cm_s < -hold_v) || (o.e_cm < 0.0f && v_cm_s > hold_v))) {
            o.flags |= PMA_PPC_FLAG_FF_HOLD;
        }
        if (!pma_ppc_ff_held(o.flags, o.u_law > 0.0f, o.u_law < 0.0f)) {
            float ff = s->u_ff + s->cfg.ff_gain_per_s * s->cfg.period_s * o.u_law;
            /* bounded so that u_ff + u_ext stays within the input range (its wind-up bound) */
            s->u_ff = fminf(fmaxf(ff, s->cfg.u_min - u_ext), s->cfg.u_max - u_ext);
        }
    }
    if (o.flags & PMA_PPC_FLAG_BARRIER1) s->breaches1++;
    if (o.flags & PMA_PPC_FLAG_BARRIER2) s->breaches2++;
    s->out = o;
    *u = o.u;
    return PMA_OK;
}
