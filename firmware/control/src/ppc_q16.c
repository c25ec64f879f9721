/* SPDX-License-Identifier: Apache-2.0 */
/* The paper's controller, fixed-point variant (see pma/ppc.h).
 * Signals Q16.16 in the units of the float variant; alpha and the
 * normalised arguments r = lambda / w in Q2.30; reciprocals 1/w1, 1/w2, 1/t_u
 * in Q8.24 (so w1, w2, t_u >= 1/64). Every operation saturates. */
#include "pma/ppc.h"
#include "pma/status.h"

#include <stddef.h>
#include "check.h"
#include "pi.h"
#include "fixed_internal.h"

#define Q24_MIN_W (1.0f / 64.0f)

int pma_ppc_init_q16(pma_ppc_q16_t *s, const pma_ppc_config_t *cfg)
{
    if (s == NULL) return PMA_ERR_NULL;
    s->ready = 0;
    PMA_CHECK(pma_ppc_validate_config(cfg));
    if (cfg->w1_cm < Q24_MIN_W || cfg->w2_cm_s < Q24_MIN_W || cfg->t_u_s < Q24_MIN_W ||
        cfg->w1_cm > 100.0f || cfg->w2_cm_s > 100.0f) {
        return PMA_ERR_FIXED_RANGE;
    }
    const float q16_vals[] = {cfg->a_cm_s, cfg->c, cfg->t_u_s, cfg->u_min, cfg->u_max,
                              cfg->ff_init, cfg->ff_hold_speed_cm_s};
    for (unsigned i = 0; i < sizeof q16_vals / sizeof q16_vals[0]; ++i) {
        PMA_CHECK(pma_check_q16_range(q16_vals[i]));
    }
    const float ff_k = cfg->ff_gain_per_s * cfg->period_s;
    if (ff_k >= 1.0f) return PMA_ERR_FIXED_RANGE;   /* also a sane bound for a per-step gain */
    /* soft barrier point: tan and sec^2 from the same fixed-point tan (no libm) */
    const pma_q30_t soft_r = pma_to_q(cfg->soft_barrier_r, 30);
    int64_t soft_tan = 0, soft_sec2 = PMA_Q16_ONE;
    if (soft_r < PMA_Q30_ONE) {
        soft_tan = pma_q16_tan_halfpi(soft_r);
        soft_sec2 = PMA_Q16_ONE + pma_rshift_round(soft_tan * soft_tan, 16);
        if (soft_sec2 >= (int64_t)32767 * PMA_Q16_ONE) return PMA_ERR_FIXED_RANGE;
    }
    s->a = pma_to_q(cfg->a_cm_s, 16);
    s->c = pma_to_q(cfg->c, 16);
    s->t_u = pma_to_q(cfg->t_u_s, 16);
    s->u_min = pma_to_q(cfg->u_min, 16);
    s->u_max = pma_to_q(cfg->u_max, 16);
    s->ff_init = pma_to_q(cfg->ff_init, 16);
    s->inv_w1_q24 = pma_to_q(1.0f / cfg->w1_cm, 24);
    s->inv_w2_q24 = pma_to_q(1.0f / cfg->w2_cm_s, 24);
    s->inv_t_u_q24 = pma_to_q(1.0f / cfg->t_u_s, 24);
    s->ff_k = pma_to_q(ff_k, 30);
    s->ff_hold_v = pma_to_q(cfg->ff_hold_speed_cm_s, 16);
    s->r_max = pma_to_q(1.0f - cfg->barrier_margin, 30);
    s->widen_r = pma_to_q(cfg->widen_r, 30);
    s->widen2_steps = cfg->widen2_steps;
    s->soft_r = soft_r;
    s->soft_tan = (pma_q16_t)soft_tan;
    s->soft_sec2 = (pma_q16_t)soft_sec2;
    pma_ppc_reset_q16(s);
    s->ready = 1;
    return PMA_OK;
}

#define WIDEN_ON 4u   /* widen_bits: channel 0 widens (WIDEN_ON << 1: channel 1) */

void pma_ppc_reset_q16(pma_ppc_q16_t *s)
{
    if (s == NULL) return;
    s->u_ff_q32 = (int64_t)s->ff_init * 65536;
    s->breaches1 = 0;
    s->breaches2 = 0;
    s->widen_bits = 0u;
    if (s->widen_r > 0) s->widen_bits = WIDEN_ON | (s->widen2_steps ? WIDEN_ON << 1 : 0u);
    s->clamp_run2 = 0;
    s->out = (pma_ppc_out_q16_t){0};
    s->out.u_ff = s->ff_init;
    s->out.g1 = PMA_Q30_ONE;   /* the step's common case does not write them */
    s->out.g2 = PMA_Q30_ONE;
}

/* r = lambda / w in Q2.30 (int64, not yet clamped) from lambda with 24 fractional bits (int64,
 * so the product alpha e is not rounded to Q16.16 before 1/w amplifies it) and 1/w in Q8.24.
 * |lambda| is limited to 128 first (then |r| > 1 anyway, since w <= 100), which keeps the
 * product below 2^63. */
#define LAMBDA_Q24_LIMIT ((int64_t)INT32_MAX)
static int64_t raw_r(int64_t lambda_q24, int32_t inv_w_q24)
{
    if (lambda_q24 > LAMBDA_Q24_LIMIT) lambda_q24 = LAMBDA_Q24_LIMIT;
    if (lambda_q24 < -LAMBDA_Q24_LIMIT) lambda_q24 = -LAMBDA_Q24_LIMIT;
    return pma_rshift_round(pma_mul32((int32_t)lambda_q24, inv_w_q24), 18);
}

/* r clamped to +-r_max (flagging the barrier) */
static pma_q30_t clamp_r(const pma_ppc_q16_t *s, int64_t r, uint32_t *flags, uint32_t barrier_flag)
{
    if (r >= s->r_max) {
        *flags |= barrier_flag;
        return s->r_max;
    }
    if (r <= -(int64_t)s->r_max) {
        *flags |= barrier_flag;
        return -s->r_max;
    }
    return (pma_q30_t)r;
}

/* 1/w_i of the widened funnel, w_i / g: (1/w_i) g in Q8.24 */
static int32_t widened_inv_w(int32_t inv_w_q24, pma_q30_t g)
{
    return g >= PMA_Q30_ONE ? inv_w_q24 : (int32_t)pma_rshift_round(pma_mul32(inv_w_q24, g), 30);
}

#define WIDEN_K_MIN ((pma_q30_t)1 << 10)   /* 2^-20: the widening's floor */

/* The tuning function alpha(t) (eq. 15) in Q2.30: 0 at t <= 0, 1 from t_u on. */
static pma_q30_t tuning_alpha(const pma_ppc_q16_t *s, pma_q16_t t)
{
    if (t <= 0) return 0;                      /* exact bumpless start */
    if (t >= s->t_u) return PMA_Q30_ONE;
    /* t/t_u, Q30 (0 < t < t_u: unsigned, and below 2^31 with 1/t_u's rounding) */
    return pma_q30_sin2_halfpi(pma_umul_shift((uint32_t)t, (uint32_t)s->inv_t_u_q24, 10));   /* 15 */
}

/* alpha a with 24 fractional bits (int64) for a in Q16.16 and alpha in Q2.30; from t_u on
 * alpha is 1 and the product is a shifted, the same bits without the multiply */
static inline int64_t times_alpha_q24(pma_q16_t a, pma_q30_t alpha)
{
    return alpha == PMA_Q30_ONE ? (int64_t)a * 256 : pma_rshift_round(pma_mul32(a, alpha), 22);
}

/* Funnel scale g_i at t, Q2.30 (ppc.h, "Funnel widening") of a channel wider than assigned:
 * g = 1 - (1 - k)(1 - alpha(t - t_i)), the tuning function from the widening on; t_u after it
 * the funnel is as assigned again (the step's common case again). */
static pma_q30_t widen_scale(pma_ppc_q16_t *s, int i, pma_q16_t t)
{
    const pma_q16_t dt = pma_q16_ssub(t, s->widen_t_s[i]);
    if (dt >= s->t_u) {
        s->widen_bits &= ~(1u << i);
        return PMA_Q30_ONE;
    }
    const int64_t rest = PMA_Q30_ONE - tuning_alpha(s, dt);                     /* Q30 */
    return (pma_q30_t)(PMA_Q30_ONE -
                       pma_rshift_round((int64_t)(PMA_Q30_ONE - s->widen_k[i]) * rest, 30));
}

/* r_i = lambda_i g_i / w_i of channel i (0: lambda1, 1: lambda2) in Q2.30 where its funnel is
 * wider than assigned or r_i is at the clamp (the common case is inline in the step): where
 * the channel widens and |r_i| reaches the clamp (lambda2: for widen2_steps steps in a row),
 * its funnel widens so that |r_i| = widen_r (flag WIDEN1/2); then clamped to +-r_max (flag
 * BARRIER1/2). Writes the scale g_i (and flag WIDE while g_i < 1). */
static pma_q30_t channel_r_wide(pma_ppc_q16_t *s, int i, pma_q16_t t, int64_t lambda_q24,
                                int32_t inv_w_q24, int64_t r_plain, pma_q30_t *g,
                                uint32_t *flags)
{
    int64_t r = r_plain;   /* r with the funnel as assigned */
    *g = PMA_Q30_ONE;
    if (s->widen_bits & (1u << i)) {
        *g = widen_scale(s, i, t);
        r = raw_r(lambda_q24, widened_inv_w(inv_w_q24, *g));
    }
    const int64_t ar = r < 0 ? -r : r;
    const int at_clamp = (s->widen_bits & (WIDEN_ON << i)) && ar >= s->r_max;
    if (i == 1) s->clamp_run2 = at_clamp ? s->clamp_run2 + (s->clamp_run2 != UINT32_MAX) : 0u;
    if (at_clamp && (i == 0 || s->clamp_run2 >= s->widen2_steps)) {
        if (i == 1) s->clamp_run2 = 0;
        int64_t k = ((int64_t)*g * s->widen_r) / ar;      /* Q60 / Q30: Q30 */
        if (k < WIDEN_K_MIN) k = WIDEN_K_MIN;
        *g = (pma_q30_t)k;
        s->widen_k[i] = *g;
        s->widen_t_s[i] = t;
        s->widen_bits |= 1u << i;
        *flags |= PMA_PPC_FLAG_WIDEN1 << i;
        r = raw_r(lambda_q24, widened_inv_w(inv_w_q24, *g));
    }
    if (*g < PMA_Q30_ONE) *flags |= PMA_PPC_FLAG_WIDE;
    return clamp_r(s, r, flags, PMA_PPC_FLAG_BARRIER1 << i);
}

/* r_i of channel i in the step, from r with the funnel as assigned. The common case costs what
 * the paper's law alone does: the funnel as assigned and r inside the clamp, or widening off. */
static inline pma_q30_t channel_r(pma_ppc_q16_t *s, uint32_t widen_bits, int i, pma_q16_t t,
                                  int64_t lambda_q24, int32_t inv_w_q24, int64_t r,
                                  pma_q30_t *g, uint32_t *flags)
{
    if (!(widen_bits & (1u << i))) {
        if (r < s->r_max && r > -(int64_t)s->r_max) {
            if (i == 1) s->clamp_run2 = 0;
            return (pma_q30_t)r;
        }
        if (!(widen_bits & (WIDEN_ON << i))) {
            return clamp_r(s, r, flags, PMA_PPC_FLAG_BARRIER1 << i);
        }
    }
    return channel_r_wide(s, i, t, lambda_q24, inv_w_q24, r, g, flags);
}

/* tan(pi r / 2) with the optional soft barrier; writes sec^2 (Q16.16). */
static pma_q16_t transform(const pma_ppc_q16_t *s, pma_q30_t r, pma_q16_t *sec2,
                           uint32_t *flags, uint32_t soft_flag)
{
    const pma_q30_t ar = r < 0 ? -r : r;
    pma_q16_t t;
    if (ar > s->soft_r) {
        *flags |= soft_flag;
        *sec2 = s->soft_sec2;
        const pma_q16_t slope = pma_q16_smul_q30(s->soft_sec2, PMA_HALF_PI_Q30);
        t = pma_q16_sadd(s->soft_tan, pma_q16_smul_q30(slope, ar - s->soft_r));
    } else {
        t = pma_q16_tan_halfpi(ar);
        *sec2 = pma_q16_sadd(PMA_Q16_ONE, pma_q16_smul(t, t));
    }
    return r < 0 ? pma_q16_sneg(t) : t;
}

int pma_ppc_step_ext_q16(pma_ppc_q16_t *s, pma_q16_t t_s, pma_q16_t x_cm, pma_q16_t v_cm_s,
                         pma_q16_t xr_cm, pma_q16_t u_ext, pma_q16_t *u)
{
    if (s == NULL || u == NULL) return PMA_ERR_NULL;
    if (!s->ready) return PMA_ERR_NOT_READY;
    if (t_s < 0) return PMA_ERR_RANGE;

    pma_ppc_out_q16_t *const o = &s->out;   /* telemetry written in place: no copy */
    o->flags = 0;
    pma_q16_t sec2;
    o->alpha = tuning_alpha(s, t_s);
    o->e_cm = pma_q16_ssub(x_cm, xr_cm);                                        /* 8 */
    const int64_t lambda1_q24 = times_alpha_q24(o->e_cm, o->alpha);               /* 16 */
    o->lambda1_cm = pma_q16_round_sat64(lambda1_q24, 8);
    /* channel 0's step changes only bit 0 of widen_bits: the copy serves both channels */
    const uint32_t widen_bits = s->widen_bits;
    const pma_q30_t r1 = channel_r(s, widen_bits, 0, t_s, lambda1_q24, s->inv_w1_q24,
                                   raw_r(lambda1_q24, s->inv_w1_q24), &o->g1, &o->flags);
    o->chi = transform(s, r1, &sec2, &o->flags, PMA_PPC_FLAG_SOFT1);              /* 18 */
    const int64_t theta_q24 = -pma_rshift_round(pma_mul32(s->a, o->chi), 8);      /* 17 */
    o->theta_cm_s = pma_q16_round_sat64(theta_q24, 8);
    const int64_t lambda2_q24 = times_alpha_q24(v_cm_s, o->alpha) - theta_q24;     /* 19 */
    o->lambda2_cm_s = pma_q16_round_sat64(lambda2_q24, 8);
    const pma_q30_t r2 = channel_r(s, widen_bits, 1, t_s, lambda2_q24, s->inv_w2_q24,
                                   raw_r(lambda2_q24, s->inv_w2_q24), &o->g2, &o->flags);
    const int32_t inv_w2 = widened_inv_w(s->inv_w2_q24, o->g2);   /* of the funnel, Q8.24 */
    o->delta = transform(s, r2, &sec2, &o->flags, PMA_PPC_FLAG_SOFT2);            /* 22 */
    o->beta_s_cm = pma_q16_round_sat64(pma_mul32(sec2, inv_w2), 24);  /* 21 */
    o->u_law = pma_q16_sneg(pma_q16_smul(pma_q16_smul(s->c, o->beta_s_cm), o->delta)); /* 20 */

    /* without the feedforward out.u_ff keeps ff_init from reset: no 64-bit rounding per step */
    if (s->ff_k > 0) o->u_ff = pma_q16_round_sat64(s->u_ff_q32, 16);
    /* the clamp and anti-windup see the whole output (saturating sums) */
    pma_q16_t v = pma_q16_sadd(o->u_ff, o->u_law);
    if (u_ext != 0) v = pma_q16_sadd(v, u_ext);
    if (v > s->u_max) {
        o->flags |= PMA_PPC_FLAG_SAT_HIGH;
        o->u = s->u_max;
    } else if (v < s->u_min) {
        o->flags |= PMA_PPC_FLAG_SAT_LOW;
        o->u = s->u_min;
    } else {
        o->u = v;
    }

    if (s->ff_k > 0) {
        /* option: the muscle closes on the reference faster than ff_hold_speed_cm_s */
        const pma_q16_t hold_v = s->ff_hold_v;
        if (hold_v > 0 &&
            ((o->e_cm > 0 && v_cm_s < -hold_v) || (o->e_cm < 0 && v_cm_s > hold_v))) {
            o->flags |= PMA_PPC_FLAG_FF_HOLD;
        }
        if (!pma_ppc_ff_held(o->flags, o->u_law > 0, o->u_law < 0)) {
            int64_t ff = s->u_ff_q32 + pma_rshift_round(pma_mul32(o->u_law, s->ff_k), 14); /* Q32 */
            /* bounded so that u_ff + u_ext stays within the input range (its wind-up bound) */
            const int64_t lo = ((int64_t)s->u_min - u_ext) * 65536;
            const int64_t hi = ((int64_t)s->u_max - u_ext) * 65536;
            s->u_ff_q32 = ff < lo ? lo : (ff > hi ? hi : ff);
        }
    }
    if (o->flags & PMA_PPC_FLAG_BARRIER1) s->breaches1++;
    if (o->flags & PMA_PPC_FLAG_BARRIER2) s->breaches2++;
    *u = o->u;
    return PMA_OK;
}
