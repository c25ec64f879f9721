/* SPDX-License-Identifier: Apache-2.0 */
/* The controller slot in Q16.16 (PMA_CTRL_Q16 1): the _q16 instances and the
 * step, for cores without an FPU. The parameters arrive in float at START and
 * are converted once (a value outside the Q16.16 range: PMA_ERR_FIXED_RANGE;
 * docs/fixed-point.md lists each module's limits); each step converts its
 * inputs (t, x) and its output u, and nothing else: the telemetry's signals are
 * converted only when read (pma_ctrl_out). Same logic as controller_f32.c, in
 * saturating Q16.16 arithmetic (pma/fixed.h). See controller.h. */
#include "controller.h"
#include "pma/finite.h"

#if PMA_CTRL_Q16

#include <math.h>
#include <stddef.h>

#define CHECK(expr)                     \
    do {                                \
        int rc_ = (expr);               \
        if (rc_ != PMA_OK) return rc_;  \
    } while (0)

/* v in Q16.16, PMA_ERR_FIXED_RANGE when it does not fit (strictly inside +-32767) */
static int to_q16(float v, pma_q16_t *q)
{
    if (!pma_isfinite_f32(v)) return PMA_ERR_NOT_FINITE;
    if (!(fabsf(v) < 32767.0f)) return PMA_ERR_FIXED_RANGE;
    *q = pma_q16_from_f32(v);
    return PMA_OK;
}

/* a Q32.32 accumulator (the estimators' and the PID's) rounded to Q16.16, saturated */
static pma_q16_t q32_to_q16(int64_t a)
{
    return pma_q16_round_sat64(a, 16);
}

/* MFAC's phi (Q8.24) as the telemetry's Q16.16 signal */
static pma_q16_t phi_q16(int32_t phi_q24)
{
    return (pma_q16_t)pma_rshift_round(phi_q24, 8);
}

static pma_q16_t q16_abs(pma_q16_t a)
{
    return a < 0 ? pma_q16_sneg(a) : a;
}

/* As controller_f32.c's: H in Q32 (its increments are far below Q16.16's resolution), the
 * integrator moved by the change of the rounded H s that u_ref carries. */
static void adapt_hysteresis(pma_ctrl_t *s, pma_q16_t branch, pma_q16_t xr_dot_cm_s)
{
    const pma_ppc_out_q16_t *po = &s->c.ppc.out;
    if (s->lost || xr_dot_cm_s == 0 || pma_ppc_ff_held(po->flags, po->u_law > 0, po->u_law < 0)) return;
    const int64_t hi = (int64_t)s->q_hyst_max_u * 65536;
    int64_t h = s->q_hyst_u_q32 + pma_rshift_round(pma_mul32(pma_q16_smul(po->u_law, branch), s->q_hyst_k), 14);
    h = h < 0 ? 0 : (h > hi ? hi : h);
    s->q_hyst_u_q32 = h;
    const pma_q16_t h16 = pma_q16_round_sat64(h, 16);
    const pma_q16_t moved = pma_q16_smul(pma_q16_ssub(h16, s->q_hyst_u), branch);
    pma_ppc_ff_move_q16(&s->c.ppc, -(int64_t)moved * 65536);
    s->q_hyst_u = h16;
}

int pma_ctrl_init_arith(pma_ctrl_t *s, const pma_ctrl_setup_t *su)
{
    CHECK(to_q16(s->period_s, &s->q_period_s));
    pma_q16_t q_limit;   /* the input range must fit Q16.16 whatever the mode (else START refuses) */
    CHECK(to_q16(s->u_min, &q_limit));
    CHECK(to_q16(s->u_max, &q_limit));
    CHECK(pma_ref_init_q16(&s->ref, &s->ref_cfg));
    CHECK(pma_velest_init_q16(&s->vel, &su->vel));
    switch (s->mode) {
    case PMA_CTRL_MODE_PPC:
        CHECK(to_q16(s->w1_cm, &s->q_w1_cm));
        CHECK(to_q16(s->t_u_s, &s->q_t_u_s));
        CHECK(to_q16(s->ref_ff_u_per_cm, &s->q_ref_ff_u_per_cm));
        CHECK(to_q16(s->ref_ff_lead_s, &s->q_ref_ff_lead_s));
        /* the hysteresis term's height, its bound, the play's half-width and its inverse must fit
         * Q16.16, and a term that would round to nothing is refused, not dropped */
        CHECK(to_q16(s->hyst_u, &s->q_hyst_u));
        CHECK(to_q16(s->hyst_max_u, &s->q_hyst_max_u));
        CHECK(to_q16(s->hyst_cm, &s->q_hyst_cm));
        CHECK(to_q16(1.0f / s->hyst_cm, &s->q_hyst_inv_cm));
        if (s->hyst_on && (s->q_hyst_cm == 0 || (s->hyst_u > 0.0f && s->q_hyst_u == 0))) {
            return PMA_ERR_FIXED_RANGE;
        }
        if (!s->hyst_on) s->q_hyst_cm = 0;   /* the step's one test for the term (a word near the others) */
        s->q_hyst_u_q32 = (int64_t)s->q_hyst_u * 65536;
        s->q_hyst_k = (pma_q30_t)(s->hyst_k * 1073741824.0f + 0.5f);   /* Q2.30: 0 <= k < 1 (controller.c) */
        if (s->hyst_k > 0.0f && s->q_hyst_k == 0) return PMA_ERR_FIXED_RANGE;
        CHECK(pma_ppc_init_q16(&s->c.ppc, &su->ppc));
        CHECK(pma_lpf_init_q16(&s->u_lpf, &su->u_lpf));
        return s->fallback_mode != PMA_PPC_FALLBACK_NONE ? pma_mfac_init_q16(&s->shadow, &su->mfac)
                                                          : PMA_OK;
    case PMA_CTRL_MODE_MFAC: return pma_mfac_init_q16(&s->c.mfac, &su->mfac);
    case PMA_CTRL_MODE_PID: return pma_pid_init_q16(&s->c.pid, &su->pid);
    default: return PMA_OK;
    }
}

int pma_ctrl_stream_arith(pma_ctrl_t *s, float target_cm)
{
    pma_q16_t q;
    CHECK(to_q16(target_cm, &q));
    return pma_ref_stream_q16(&s->ref, q);
}

const pma_ctrl_out_t *pma_ctrl_out(pma_ctrl_t *s)
{
    const pma_ctrl_out_q16_t *q = &s->q_out;
    pma_ctrl_out_t *o = &s->out;
    o->t_s = pma_q16_to_f32(q->t_s);
    o->xr_cm = pma_q16_to_f32(q->xr_cm);
    o->e_cm = pma_q16_to_f32(q->e_cm);
    o->xr_dot_cm_s = pma_q16_to_f32(q->xr_dot_cm_s);
    o->v_cm_s = pma_q16_to_f32(q->v_cm_s);
    o->u = pma_q16_to_f32(q->u);
    o->internal1 = pma_q16_to_f32(q->internal1);
    o->internal2 = pma_q16_to_f32(q->internal2);
    return o;
}

/* MFAC's reference of the next sample, y*(k+1); STREAM's next value is not known yet: this
 * sample's. The other kinds' evaluation only reads the instance. */
static pma_q16_t next_reference(pma_ctrl_t *s, pma_q16_t t)
{
    pma_q16_t xr_next;
    if (s->ref_cfg.kind == PMA_REF_STREAM ||
        pma_ref_eval_q16(&s->ref, pma_q16_sadd(t, s->q_period_s), &xr_next, NULL) != PMA_OK) {
        xr_next = s->q_out.xr_cm;
    }
    return xr_next;
}

int pma_ctrl_step(pma_ctrl_t *s, float t_s, float x_cm, float openloop_u, float *u)
{
    if (s == NULL || u == NULL) return PMA_ERR_NULL;
    *u = 0.0f;
    if (!pma_isfinite_f32(t_s) || !pma_isfinite_f32(x_cm)) return PMA_ERR_NOT_FINITE;
    if (!(t_s < 32767.0f)) return PMA_ERR_FIXED_RANGE;
    pma_q16_t uq;
    return pma_ctrl_step_q16(s, pma_q16_from_f32(t_s), pma_q16_from_f32(x_cm), openloop_u, &uq, u);
}

/* The step's error return: its outputs and TELEM_D's signals 0, written only on this cold path
 * (every path that returns PMA_OK writes them) */
static int step_failed(int rc, pma_ctrl_t *s, pma_q16_t *u_q16, float *u)
{
    s->q_out.internal1 = s->q_out.internal2 = 0;
    *u_q16 = 0;
    if (u != NULL) *u = 0.0f;
    return rc;
}

#define STEP_CHECK(expr)                                          \
    do {                                                          \
        int rc_ = (expr);                                         \
        if (rc_ != PMA_OK) return step_failed(rc_, s, u_q16, u); \
    } while (0)

int pma_ctrl_step_q16(pma_ctrl_t *s, pma_q16_t t, pma_q16_t x, float openloop_u, pma_q16_t *u_q16,
                      float *u)
{
    if (s == NULL || u_q16 == NULL) {
        if (u != NULL) *u = 0.0f;
        return PMA_ERR_NULL;
    }
    /* Q16.16 time ends at 32767 s (9.1 h): past it the step refuses, and the supervisor
     * faults CONTROLLER (the output goes safe), rather than the reference freezing */
    if (t >= PMA_CTRL_Q16_T_END) return step_failed(PMA_ERR_FIXED_RANGE, s, u_q16, u);
    pma_ctrl_out_q16_t *o = &s->q_out;
    o->t_s = t;
    s->out.flags = 0;
    s->out.barrier = 0;
    STEP_CHECK(pma_ref_eval_q16(&s->ref, t, &o->xr_cm, &o->xr_dot_cm_s));
    STEP_CHECK(pma_velest_step_q16(&s->vel, x, &o->v_cm_s));
    o->e_cm = pma_q16_ssub(x, o->xr_cm);

    pma_q16_t out = 0;
    uint32_t flags = 0;
    uint8_t barrier = 0;
    switch (s->mode) {
    case PMA_CTRL_MODE_PPC: {
        pma_q16_t u_ref = 0;   /* the reference feedforward, inside the law's clamp */
        if (!s->fallback_active) {
            /* the options (controller.h) choose the law's inputs */
            const pma_q16_t x_law = s->ppc_obs_pos ? q32_to_q16(s->vel.xh_q32) : x;
            const pma_q16_t v_law = s->ppc_ref_vel ? pma_q16_ssub(o->v_cm_s, o->xr_dot_cm_s) : o->v_cm_s;
            pma_q16_t branch = 0;   /* as controller_f32.c: (x_a - z) / b, -1..1 */
            int adapt = 0;
            if (s->q_ref_ff_u_per_cm != 0 || s->q_hyst_cm != 0) {
                const pma_q16_t lead = pma_q16_smul(s->q_ref_ff_lead_s, o->xr_dot_cm_s);
                const pma_q16_t xa = pma_q16_sadd(o->xr_cm, lead);
                if (!s->xr0_set) {
                    s->q_xr0_cm = o->xr_cm;
                    s->q_play_z_cm = xa;
                    s->xr0_set = 1;
                }
                const pma_q16_t ahead = pma_q16_sadd(pma_q16_ssub(o->xr_cm, s->q_xr0_cm), lead);
                u_ref = pma_q16_smul(s->q_ref_ff_u_per_cm, ahead);
                if (s->q_hyst_cm != 0) {   /* the play operator, as controller_f32.c */
                    const pma_q16_t lo = pma_q16_ssub(xa, s->q_hyst_cm), hi = pma_q16_sadd(xa, s->q_hyst_cm);
                    s->q_play_z_cm = pma_q16_clamp(s->q_play_z_cm, lo, hi);
                    branch = pma_q16_clamp(pma_q16_smul(pma_q16_ssub(xa, s->q_play_z_cm), s->q_hyst_inv_cm),
                                           -PMA_Q16_ONE, PMA_Q16_ONE);
                    u_ref = pma_q16_sadd(u_ref, pma_q16_smul(s->q_hyst_u, branch));
                    adapt = s->q_hyst_k != 0;
                }
            }
            STEP_CHECK(pma_ppc_step_ext_q16(&s->c.ppc, t, x_law, v_law, o->xr_cm, u_ref, &out));
            if (adapt) adapt_hysteresis(s, branch, o->xr_dot_cm_s);
            out = pma_lpf_step_q16(&s->u_lpf, out);   /* as controller_f32.c */
            flags = s->c.ppc.out.flags;
            o->internal1 = s->c.ppc.out.lambda1_cm;
            o->internal2 = s->c.ppc.out.lambda2_cm_s;
            barrier = (uint8_t)((flags & (PMA_PPC_FLAG_BARRIER1 | PMA_PPC_FLAG_BARRIER2)) != 0);
        }
        const uint8_t was_fallback = s->fallback_active;
        const int after_tu = t >= s->q_t_u_s;
        if (pma_ctrl_monitor(s, after_tu, after_tu && q16_abs(o->e_cm) >= s->q_w1_cm, flags)) {
            if (pma_ctrl_lost_again(s, flags)) {
                pma_ctrl_count_lost(s);   /* all it would do: no float time needed */
            } else {
                pma_ctrl_monitor_lost(s, pma_q16_to_f32(t), flags);
            }
        }
        if (s->fallback_active && !was_fallback) {   /* as controller_f32.c */
            STEP_CHECK(pma_mfac_take_over_q16(&s->shadow, pma_q16_sadd(s->c.ppc.ff_init, u_ref)));
        }
        /* as controller_f32.c: the fallback's MFAC from the tick of the hand-over */
        if (s->fallback_active) {
            STEP_CHECK(pma_mfac_step_q16(&s->shadow, x, next_reference(s, t), &out));
            flags = s->shadow.flags | PMA_CTRL_FLAG_FALLBACK;
            o->internal1 = phi_q16(s->shadow.phi_q24);   /* TELEM_D as in mode MFAC */
            o->internal2 = s->shadow.u1;
        }
        if (s->lost) flags |= PMA_CTRL_FLAG_GUARANTEE_LOST;
        break;
    }
    case PMA_CTRL_MODE_MFAC:
        /* MFAC's law uses the reference of the next sample, y*(k+1) */
        STEP_CHECK(pma_mfac_step_q16(&s->c.mfac, x, next_reference(s, t), &out));
        flags = s->c.mfac.flags;
        o->internal1 = phi_q16(s->c.mfac.phi_q24);
        o->internal2 = s->c.mfac.u1;
        break;
    case PMA_CTRL_MODE_PID:
        STEP_CHECK(pma_pid_step_q16(&s->c.pid, o->xr_cm, x, &out));
        flags = s->c.pid.flags;
        o->internal1 = q32_to_q16(s->c.pid.i_q32);
        o->internal2 = s->c.pid.d;
        break;
    case PMA_CTRL_MODE_OPEN_LOOP: {
        o->internal1 = o->internal2 = 0;   /* (every other mode writes both) */
        /* ctrl.openloop_u is live and float: clamped in float, as the float build does */
        const float ol = pma_isfinite_f32(openloop_u)
                             ? (openloop_u < s->u_min ? s->u_min : (openloop_u > s->u_max ? s->u_max : openloop_u))
                             : openloop_u;
        o->u = pma_q16_from_f32(ol);
        *u_q16 = o->u;
        if (u != NULL) *u = ol;
        return PMA_OK;
    }
    default:
        o->internal1 = o->internal2 = 0;
        break;
    }
    s->out.flags = flags;
    s->out.barrier = barrier;
    if (barrier && s->breaches != UINT32_MAX) ++s->breaches;
    o->u = out;
    *u_q16 = out;
    if (u != NULL) *u = pma_q16_to_f32(out);
    return PMA_OK;
}

#endif /* PMA_CTRL_Q16 */
