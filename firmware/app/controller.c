/* SPDX-License-Identifier: Apache-2.0 */
/* The controller slot: see controller.h. */
#include "controller.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

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

int pma_ctrl_start(pma_ctrl_t *s, const pma_params_t *p, float period_s)
{
    if (s == NULL || p == NULL) return PMA_ERR_NULL;
    memset(s, 0, sizeof *s);
    if (!(period_s > 0.0f) || !(p->ctrl_u_min < p->ctrl_u_max)) return PMA_ERR_RANGE;
    s->mode = (uint8_t)p->ctrl_mode;
    s->period_s = period_s;
    s->u_min = p->ctrl_u_min;
    s->u_max = p->ctrl_u_max;

    s->ref_cfg = (pma_ref_config_t){
        .kind = (uint8_t)p->ref_kind, .offset_cm = p->ref_offset_cm,
        .amplitude_cm = p->ref_amplitude_cm, .freq_hz = p->ref_freq_hz,
        .phase_rad = p->ref_phase_rad, .t0_s = p->ref_t0_s, .rate_cm_s = p->ref_rate_cm_s,
    };
    CHECK(pma_ref_init_f32(&s->ref, &s->ref_cfg));
    const pma_band_t band = pma_band_constant(p->safety_x_min_cm, p->safety_x_max_cm);
    const float margin = (s->mode == PMA_CTRL_MODE_PPC && p->ppc_band_check) ? p->ppc_w1_cm : 0.0f;
    s->stream_margin_cm = margin;
    CHECK(pma_band_check_ref(&band, &s->ref_cfg, p->ref_horizon_s, margin));

    pma_velest_config_t vc = {.kind = (uint8_t)p->vel_kind, .fc_hz = p->vel_fc_hz,
                              .period_s = period_s};
    CHECK(pma_velest_init_f32(&s->vel, &vc));

    switch (s->mode) {
    case PMA_CTRL_MODE_PPC: {
        s->ppc_ref_vel = (uint8_t)(p->ppc_ref_vel != 0);
        s->ppc_obs_pos = (uint8_t)(p->ppc_obs_pos != 0);
        s->ref_ff_u_per_cm = p->ppc_ref_ff;
        s->ref_ff_lead_s = p->ppc_ref_ff_lead_s;
        if (!isfinite(s->ref_ff_u_per_cm) || !(s->ref_ff_lead_s >= 0.0f)) return PMA_ERR_RANGE;
        if (s->ppc_obs_pos && vc.kind != PMA_VELEST_TRACKING) return PMA_ERR_RANGE;
        pma_ppc_config_t c;
        pma_ppc_default_config(&c);
        c.a_cm_s = p->ppc_a_cm_s;
        c.c = p->ppc_c;
        c.w1_cm = p->ppc_w1_cm;
        c.w2_cm_s = p->ppc_w2_cm_s;
        c.t_u_s = p->ppc_t_u_s;
        c.u_min = p->ctrl_u_min;
        c.u_max = p->ctrl_u_max;
        c.barrier_margin = p->ppc_barrier_margin;
        c.soft_barrier_r = p->ppc_soft_barrier_r;
        c.ff_gain_per_s = p->ppc_ff_gain_per_s;
        c.ff_init = p->ppc_ff_init;
        c.period_s = period_s;
        c.band_enabled = (uint8_t)(p->ppc_band_check != 0);
        c.k_low_cm = p->safety_x_min_cm;
        c.k_high_cm = p->safety_x_max_cm;
        CHECK(pma_ppc_init_f32(&s->c.ppc, &c));
        s->w1_cm = c.w1_cm;
        s->t_u_s = c.t_u_s;
        s->barrier_ticks = p->safety_barrier_ticks;
        s->fallback_mode = (uint8_t)(p->ppc_fallback != 0);
        if (!s->fallback_mode) return PMA_OK;
        pma_mfac_config_t m = {
            .eta = p->mfac_eta, .mu = p->mfac_mu, .rho = p->mfac_rho, .lambda = p->mfac_lambda,
            .eps = p->mfac_eps, .phi1 = p->mfac_phi1, .u_min = p->ctrl_u_min,
            .u_max = p->ctrl_u_max, .u_init = c.ff_init,
        };
        return pma_mfac_init_f32(&s->shadow, &m);
    }
    case PMA_CTRL_MODE_MFAC: {
        pma_mfac_config_t c = {
            .eta = p->mfac_eta, .mu = p->mfac_mu, .rho = p->mfac_rho, .lambda = p->mfac_lambda,
            .eps = p->mfac_eps, .phi1 = p->mfac_phi1, .u_min = p->ctrl_u_min,
            .u_max = p->ctrl_u_max, .u_init = p->mfac_u_init,
        };
        return pma_mfac_init_f32(&s->c.mfac, &c);
    }
    case PMA_CTRL_MODE_PID: {
        pma_pid_config_t c = {
            .kp = p->pid_kp, .ki = p->pid_ki, .kd = p->pid_kd, .tf_s = p->pid_tf_s,
            .k_aw_per_s = p->pid_k_aw_per_s, .period_s = period_s, .u_min = p->ctrl_u_min,
            .u_max = p->ctrl_u_max,
        };
        return pma_pid_init_f32(&s->c.pid, &c);
    }
    case PMA_CTRL_MODE_OFF:
    case PMA_CTRL_MODE_OPEN_LOOP:
        return PMA_OK;
    default:
        return PMA_ERR_RANGE;
    }
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
        float u_mfac = 0.0f;
        if (s->fallback_mode) {
            CHECK(pma_mfac_step_f32(&s->shadow, x_cm, next_reference(s, t_s), &u_mfac));
        }
        if (!s->fallback_active) {
            /* the options (controller.h) choose the law's inputs */
            const float x_law_cm = s->ppc_obs_pos ? s->vel.xh : x_cm;
            const float v_law_cm_s = s->ppc_ref_vel ? o->v_cm_s - o->xr_dot_cm_s : o->v_cm_s;
            CHECK(pma_ppc_step_f32(&s->c.ppc, t_s, x_law_cm, v_law_cm_s, o->xr_cm, &out));
            if (s->ref_ff_u_per_cm != 0.0f) {
                if (!s->xr0_set) {
                    s->xr0_cm = o->xr_cm;
                    s->xr0_set = 1;
                }
                const float ahead_cm = (o->xr_cm - s->xr0_cm) + s->ref_ff_lead_s * o->xr_dot_cm_s;
                out = clampf(out + s->ref_ff_u_per_cm * ahead_cm, s->u_min, s->u_max);
            }
            o->flags = s->c.ppc.out.flags;
            o->internal1 = s->c.ppc.out.lambda1_cm;
            o->internal2 = s->c.ppc.out.lambda2_cm_s;
            o->barrier = (uint8_t)((o->flags & (PMA_PPC_FLAG_BARRIER1 | PMA_PPC_FLAG_BARRIER2)) != 0);
        }
        s->barrier_run = o->barrier ? s->barrier_run + 1u : 0u;
        const int clamp_run = s->barrier_ticks != 0 && s->barrier_run >= s->barrier_ticks;
        if ((t_s >= s->t_u_s && fabsf(o->e_cm) >= s->w1_cm) || clamp_run) {
            if (!s->lost) s->lost_at_s = t_s;
            s->lost = 1;
            if (s->lost_ticks != UINT32_MAX) ++s->lost_ticks;
            if (s->fallback_mode) s->fallback_active = 1;
        }
        if (s->fallback_active) {
            out = u_mfac;
            o->flags = s->shadow.flags | PMA_CTRL_FLAG_FALLBACK;
            o->internal1 = s->shadow.phi;   /* TELEM_D as in mode MFAC */
            o->internal2 = s->shadow.u1;
        }
        if (s->lost) o->flags |= PMA_CTRL_FLAG_GUARANTEE_LOST;
        if (s->fallback_mode) s->shadow.u1 = out; /* MFAC learns from the input applied */
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
        out = isfinite(openloop_u) ? clampf(openloop_u, s->u_min, s->u_max) : openloop_u;
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

int pma_ctrl_stream(pma_ctrl_t *s, float target_cm, float x_min_cm, float x_max_cm)
{
    if (s == NULL) return PMA_ERR_NULL;
    if (s->ref_cfg.kind != PMA_REF_STREAM) return PMA_ERR_UNSUPPORTED;
    if (!isfinite(target_cm)) return PMA_ERR_NOT_FINITE;
    if (!(target_cm > x_min_cm + s->stream_margin_cm && target_cm < x_max_cm - s->stream_margin_cm)) {
        return PMA_ERR_RANGE;
    }
    return pma_ref_stream_f32(&s->ref, target_cm);
}
