/* SPDX-License-Identifier: Apache-2.0 */
/* The controller slot in float (PMA_CTRL_Q16 0): the _f32 instances and the
 * step. See controller.h. */
#include "controller.h"
#include "pma/finite.h"

#if !PMA_CTRL_Q16

#include <math.h>
#include <stddef.h>

#define CHECK(expr)                     \
    do {                                \
        int rc_ = (expr);               \
        if (rc_ != PMA_OK) return rc_;  \
    } while (0)

/* MFAC's reference of the next sample, y*(k+1); STREAM's next value is not known yet: this
 * sample's. */
static float next_reference(const pma_ctrl_t *s, float t_s)
{
    float xr_next;
    if (pma_ref_value_f32(&s->ref_cfg, t_s + s->period_s, &xr_next, NULL) != PMA_OK) {
        xr_next = s->out.xr_cm;
    }
    return xr_next;
}

static float clampf(float v, float lo, float hi)
{
    return v < lo ? lo : (v > hi ? hi : v);
}

/* ppc.ref_ff_hyst_gain_per_s: the hysteresis term's height learns the part of the law's output
 * that follows the branch, where the feedforward integrator would (not while the reference
 * stands still, nor where the integrator's anti-windup holds it, nor once the guarantee was
 * lost: a task beyond the rig says nothing about the muscle's hysteresis), and the integrator gives up
 * what the term takes: u_ff + H s stays on the integrator's path, so between reversals the loop
 * is the one without adaptation, and at a reversal H s moves by the step that the law needed. */
static void adapt_hysteresis(pma_ctrl_t *s, float branch, float xr_dot_cm_s)
{
    const pma_ppc_out_f32_t *po = &s->c.ppc.out;
    if (s->lost || xr_dot_cm_s == 0.0f || pma_ppc_ff_held(po->flags, po->u_law > 0.0f, po->u_law < 0.0f)) {
        return;
    }
    const float h = clampf(s->hyst_u + s->hyst_k * po->u_law * branch, 0.0f, s->hyst_max_u);
    pma_ppc_ff_move_f32(&s->c.ppc, -(h - s->hyst_u) * branch);
    s->hyst_u = h;
}

int pma_ctrl_init_arith(pma_ctrl_t *s, const pma_ctrl_setup_t *su)
{
    CHECK(pma_ref_init_f32(&s->ref, &s->ref_cfg));
    CHECK(pma_velest_init_f32(&s->vel, &su->vel));
    switch (s->mode) {
    case PMA_CTRL_MODE_PPC:
        CHECK(pma_ppc_init_f32(&s->c.ppc, &su->ppc));
        CHECK(pma_lpf_init_f32(&s->u_lpf, &su->u_lpf));
        return s->fallback_mode != PMA_PPC_FALLBACK_NONE ? pma_mfac_init_f32(&s->shadow, &su->mfac)
                                                          : PMA_OK;
    case PMA_CTRL_MODE_MFAC: return pma_mfac_init_f32(&s->c.mfac, &su->mfac);
    case PMA_CTRL_MODE_PID: return pma_pid_init_f32(&s->c.pid, &su->pid);
    default: return PMA_OK;
    }
}

int pma_ctrl_stream_arith(pma_ctrl_t *s, float target_cm)
{
    return pma_ref_stream_f32(&s->ref, target_cm);
}

const pma_ctrl_out_t *pma_ctrl_out(pma_ctrl_t *s)
{
    return &s->out;
}

int pma_ctrl_step(pma_ctrl_t *s, float t_s, float x_cm, float openloop_u, float *u)
{
    if (s == NULL || u == NULL) return PMA_ERR_NULL;
    *u = 0.0f;
    pma_ctrl_out_t *o = &s->out;
    o->t_s = t_s;
    o->flags = 0;
    o->barrier = 0;
    o->internal1 = o->internal2 = 0.0f;
    CHECK(pma_ref_eval_f32(&s->ref, t_s, &o->xr_cm, &o->xr_dot_cm_s));
    CHECK(pma_velest_step_f32(&s->vel, x_cm, &o->v_cm_s));
    o->e_cm = x_cm - o->xr_cm;

    float out = 0.0f;
    switch (s->mode) {
    case PMA_CTRL_MODE_PPC: {
        float u_ref = 0.0f;   /* the reference feedforward, inside the law's clamp */
        if (!s->fallback_active) {
            /* the options (controller.h) choose the law's inputs */
            const float x_law_cm = s->ppc_obs_pos ? s->vel.xh : x_cm;
            const float v_law_cm_s = s->ppc_ref_vel ? o->v_cm_s - o->xr_dot_cm_s : o->v_cm_s;
            float branch = 0.0f;   /* the hysteresis term's branch s = (x_a - z) / b, -1..1 */
            if (s->ref_ff_u_per_cm != 0.0f || s->hyst_on) {
                const float lead_cm = s->ref_ff_lead_s * o->xr_dot_cm_s;
                const float xa_cm = o->xr_cm + lead_cm;   /* x_a: the reference taken lead ahead */
                if (!s->xr0_set) {
                    s->xr0_cm = o->xr_cm;
                    s->play_z_cm = xa_cm;
                    s->xr0_set = 1;
                }
                const float ahead_cm = (o->xr_cm - s->xr0_cm) + lead_cm;
                u_ref = s->ref_ff_u_per_cm * ahead_cm;
                if (s->hyst_on) {
                    /* the play operator: z follows x_a at hyst_cm */
                    s->play_z_cm = clampf(s->play_z_cm, xa_cm - s->hyst_cm, xa_cm + s->hyst_cm);
                    branch = (xa_cm - s->play_z_cm) / s->hyst_cm;
                    u_ref += s->hyst_u * branch;
                }
            }
            CHECK(pma_ppc_step_ext_f32(&s->c.ppc, t_s, x_law_cm, v_law_cm_s, o->xr_cm, u_ref, &out));
            if (s->hyst_k > 0.0f) adapt_hysteresis(s, branch, o->xr_dot_cm_s);
            out = pma_lpf_step_f32(&s->u_lpf, out);   /* option ppc.u_lpf_hz (off: out itself) */
            o->flags = s->c.ppc.out.flags;
            o->internal1 = s->c.ppc.out.lambda1_cm;
            o->internal2 = s->c.ppc.out.lambda2_cm_s;
            o->barrier = (uint8_t)((o->flags & (PMA_PPC_FLAG_BARRIER1 | PMA_PPC_FLAG_BARRIER2)) != 0);
        }
        const uint8_t was_fallback = s->fallback_active;
        const int after_tu = t_s >= s->t_u_s;
        if (pma_ctrl_monitor(s, after_tu, after_tu && fabsf(o->e_cm) >= s->w1_cm, o->flags)) {
            pma_ctrl_monitor_lost(s, t_s, o->flags);
        }
        /* MFAC takes over as it would start on its own at this point of the reference: from
         * the holding input there by the static map (ppc.ff_init at the reference's start plus
         * the reference feedforward) and phi(1). Not from the law's last output (the
         * near-barrier input that lost the guarantee) nor its feedforward integrator (wound up
         * by that input): docs/controllers.md, "When the guarantee is lost" */
        if (s->fallback_active && !was_fallback) {
            CHECK(pma_mfac_take_over_f32(&s->shadow, s->c.ppc.cfg.ff_init + u_ref));
        }
        /* the fallback's MFAC runs from the tick of the hand-over */
        if (s->fallback_active) {
            CHECK(pma_mfac_step_f32(&s->shadow, x_cm, next_reference(s, t_s), &out));
            o->flags = s->shadow.flags | PMA_CTRL_FLAG_FALLBACK;
            o->internal1 = s->shadow.phi;   /* TELEM_D as in mode MFAC */
            o->internal2 = s->shadow.u1;
        }
        if (s->lost) o->flags |= PMA_CTRL_FLAG_GUARANTEE_LOST;
        break;
    }
    case PMA_CTRL_MODE_MFAC: {
        /* MFAC's law uses the reference of the next sample, y*(k+1) */
        CHECK(pma_mfac_step_f32(&s->c.mfac, x_cm, next_reference(s, t_s), &out));
        o->flags = s->c.mfac.flags;
        o->internal1 = s->c.mfac.phi;
        o->internal2 = s->c.mfac.u1;
        break;
    }
    case PMA_CTRL_MODE_PID:
        CHECK(pma_pid_step_f32(&s->c.pid, o->xr_cm, x_cm, &out));
        o->flags = s->c.pid.flags;
        o->internal1 = s->c.pid.i;
        o->internal2 = s->c.pid.d;
        break;
    case PMA_CTRL_MODE_OPEN_LOOP:
        out = pma_isfinite_f32(openloop_u) ? clampf(openloop_u, s->u_min, s->u_max) : openloop_u;
        break;
    default:
        out = 0.0f;
        break;
    }
    if (o->barrier && s->breaches != UINT32_MAX) ++s->breaches;
    o->u = out;
    *u = out;
    return PMA_OK;
}

#endif /* !PMA_CTRL_Q16 */
