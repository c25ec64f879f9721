/* SPDX-License-Identifier: Apache-2.0 */
/* The controller slot's START and STREAM checks, in either arithmetic: the
 * configurations from the parameters, the band check, the options (see
 * controller.h). The instances and the step: controller_f32.c, controller_q16.c. */
#include "controller.h"
#include "pma/finite.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

#define CHECK(expr)                     \
    do {                                \
        int rc_ = (expr);               \
        if (rc_ != PMA_OK) return rc_;  \
    } while (0)

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
    CHECK(pma_ref_validate_config(&s->ref_cfg));
    const pma_band_t band = pma_band_constant(p->safety_x_min_cm, p->safety_x_max_cm);
    const float margin = (s->mode == PMA_CTRL_MODE_PPC && p->ppc_band_check) ? p->ppc_w1_cm : 0.0f;
    s->stream_margin_cm = margin;
    CHECK(pma_band_check_ref(&band, &s->ref_cfg, p->ref_horizon_s, margin));

    pma_ctrl_setup_t su;
    memset(&su, 0, sizeof su);
    su.vel = (pma_velest_config_t){.kind = (uint8_t)p->vel_kind, .fc_hz = p->vel_fc_hz,
                                   .period_s = period_s};
    switch (s->mode) {
    case PMA_CTRL_MODE_PPC: {
        s->ppc_ref_vel = (uint8_t)(p->ppc_ref_vel != 0);
        s->ppc_obs_pos = (uint8_t)(p->ppc_obs_pos != 0);
        s->ref_ff_u_per_cm = p->ppc_ref_ff;
        s->ref_ff_lead_s = p->ppc_ref_ff_lead_s;
        if (!pma_isfinite_f32(s->ref_ff_u_per_cm) || !(s->ref_ff_lead_s >= 0.0f)) return PMA_ERR_RANGE;
        if (!(p->ppc_ref_ff_hyst >= 0.0f && p->ppc_ref_ff_hyst_cm > 0.0f)) return PMA_ERR_RANGE;
        s->hyst_cm = p->ppc_ref_ff_hyst_cm;
        s->hyst_u = p->ppc_ref_ff_hyst;
        s->hyst_k = p->ppc_ref_ff_hyst_gain_per_s * period_s;
        s->hyst_max_u = p->ppc_ref_ff_hyst_max;
        /* the adaptation starts inside its bound, at a per-step gain below 1 */
        if (!(s->hyst_k >= 0.0f && s->hyst_k < 1.0f)) return PMA_ERR_RANGE;
        if (s->hyst_k > 0.0f && (!(s->hyst_u <= s->hyst_max_u) || !(p->ppc_ff_gain_per_s > 0.0f))) {
            return PMA_ERR_RANGE;   /* it learns from, and hands over to, the feedforward integrator */
        }
        s->hyst_on = (uint8_t)(s->hyst_u > 0.0f || s->hyst_k > 0.0f);
        if (s->ppc_obs_pos && su.vel.kind != PMA_VELEST_TRACKING) return PMA_ERR_RANGE;
        pma_ppc_config_t *c = &su.ppc;
        pma_ppc_default_config(c);
        c->a_cm_s = p->ppc_a_cm_s;
        c->c = p->ppc_c;
        c->w1_cm = p->ppc_w1_cm;
        c->w2_cm_s = p->ppc_w2_cm_s;
        c->t_u_s = p->ppc_t_u_s;
        c->u_min = p->ctrl_u_min;
        c->u_max = p->ctrl_u_max;
        c->barrier_margin = p->ppc_barrier_margin;
        c->soft_barrier_r = p->ppc_soft_barrier_r;
        c->ff_gain_per_s = p->ppc_ff_gain_per_s;
        c->ff_init = p->ppc_ff_init;
        c->ff_hold_speed_cm_s = p->ppc_ff_hold_speed_cm_s;
        c->period_s = period_s;
        su.u_lpf = (pma_lpf_config_t){.fc_hz = p->ppc_u_lpf_hz, .period_s = period_s};
        s->fallback_mode = (uint8_t)p->ppc_fallback;
        c->widen_r = s->fallback_mode == PMA_PPC_FALLBACK_WIDEN ? p->ppc_widen_r : 0.0f;
        /* a clamp run as long as the one the monitor calls lost (and ppc.fallback 0 faults) */
        c->widen2_steps = p->safety_barrier_ticks;
        c->band_enabled = (uint8_t)(p->ppc_band_check != 0);
        c->k_low_cm = p->safety_x_min_cm;
        c->k_high_cm = p->safety_x_max_cm;
        s->w1_cm = c->w1_cm;
        s->t_u_s = c->t_u_s;
        s->barrier_ticks = p->safety_barrier_ticks;
        /* the fallback's MFAC: the mfac.* gains; its start is set at the hand-over (controller_*.c) */
        su.mfac = (pma_mfac_config_t){
            .eta = p->mfac_eta, .mu = p->mfac_mu, .rho = p->mfac_rho, .lambda = p->mfac_lambda,
            .eps = p->mfac_eps, .phi1 = p->mfac_phi1, .u_min = p->ctrl_u_min,
            .u_max = p->ctrl_u_max, .u_init = c->ff_init,
        };
        break;
    }
    case PMA_CTRL_MODE_MFAC:
        su.mfac = (pma_mfac_config_t){
            .eta = p->mfac_eta, .mu = p->mfac_mu, .rho = p->mfac_rho, .lambda = p->mfac_lambda,
            .eps = p->mfac_eps, .phi1 = p->mfac_phi1, .u_min = p->ctrl_u_min,
            .u_max = p->ctrl_u_max, .u_init = p->mfac_u_init,
        };
        break;
    case PMA_CTRL_MODE_PID:
        su.pid = (pma_pid_config_t){
            .kp = p->pid_kp, .ki = p->pid_ki, .kd = p->pid_kd, .tf_s = p->pid_tf_s,
            .k_aw_per_s = p->pid_k_aw_per_s, .period_s = period_s, .u_min = p->ctrl_u_min,
            .u_max = p->ctrl_u_max,
        };
        break;
    case PMA_CTRL_MODE_OFF:
    case PMA_CTRL_MODE_OPEN_LOOP:
        break;
    default:
        return PMA_ERR_RANGE;
    }
    return pma_ctrl_init_arith(s, &su);
}

void pma_ctrl_monitor_lost(pma_ctrl_t *s, float t_s, uint32_t law_flags)
{
    const uint8_t sat = (uint8_t)(law_flags & PMA_CTRL_SAT_FLAGS);
    if (!s->lost) s->lost_at_s = t_s;
    s->lost = 1;
    pma_ctrl_count_lost(s);
    int hand_over = s->fallback_mode == PMA_PPC_FALLBACK_MFAC;
    if (s->fallback_mode == PMA_PPC_FALLBACK_WIDEN) {
        /* WIDEN: one widening of the position funnel is a transient the law recovers from; a
         * second within t_u of the last (or a lasting clamp) is a task the law cannot hold
         * here, and MFAC takes over (docs/controllers.md, "When the guarantee is lost").
         * Unless the law's input stays at its limit through both widenings (at the limit it
         * was at the last one, even with the widened funnel's lower gain, or held there on
         * every tick since): the reference lies beyond what that limit gives (out of the
         * stroke, a load the pressure cannot hold), MFAC would be held there too, and the law
         * tracks the rest better */
        const int within_t_u = s->widen1_count != 0 && t_s - s->widen1_at_s < s->t_u_s;
        if (law_flags & PMA_PPC_FLAG_WIDEN1) {
            const int held = s->widen1_held != 0 || (sat != 0 && sat == s->widen1_sat);
            if (within_t_u && !held) hand_over = 1;
            s->widen1_at_s = t_s;
            s->widen1_sat = s->widen1_held = s->widen1_swing = sat;
            if (s->widen1_count != UINT32_MAX) ++s->widen1_count;
        } else if (within_t_u) {
            /* the input at both of its limits within t_u of a widening: the law swings from one
             * limit to the other, which the widened funnel's lower gain did not calm (a loop
             * unstable in the large); MFAC takes over now, not at the second widening */
            s->widen1_swing |= sat;
            if (s->widen1_swing == PMA_CTRL_SAT_FLAGS) hand_over = 1;
        }
        if (pma_ctrl_clamp_run(s)) hand_over = 1;
    }
    if (hand_over) s->fallback_active = 1;
}

int pma_ctrl_stream(pma_ctrl_t *s, float target_cm, float x_min_cm, float x_max_cm)
{
    if (s == NULL) return PMA_ERR_NULL;
    if (s->ref_cfg.kind != PMA_REF_STREAM) return PMA_ERR_UNSUPPORTED;
    if (!pma_isfinite_f32(target_cm)) return PMA_ERR_NOT_FINITE;
    if (!(target_cm > x_min_cm + s->stream_margin_cm && target_cm < x_max_cm - s->stream_margin_cm)) {
        return PMA_ERR_RANGE;
    }
    return pma_ctrl_stream_arith(s, target_cm);
}
