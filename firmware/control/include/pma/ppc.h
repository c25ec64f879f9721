/* SPDX-License-Identifier: Apache-2.0 */
/* The paper's controller (Li & Gao, "Tracking control for pneumatic muscle
 * actuators with unknown dynamics and output constraints", eq. 15-22): a
 * prescribed-performance / error-transformation law with a tuning function.
 * Called "ppc" (prescribed performance control) here; the paper gives it no name.
 *
 * Per step, with t the time since the tracking task started:
 *   alpha   = 0.5 - 0.5 cos(pi t / t_u)  (t < t_u), 1 afterwards      (15)
 *   e       = x - x_r                                                 (8)
 *   lambda1 = alpha e                                                 (16)
 *   chi     = tan(pi lambda1 / (2 w1))                                (18)
 *   theta   = -a chi                                                  (17)
 *   lambda2 = alpha x' - theta                                        (19)
 *   delta   = tan(pi lambda2 / (2 w2))                                (22)
 *   beta    = 1 / (w2 cos^2(pi lambda2 / (2 w2)))  = (1 + delta^2)/w2 (21)
 *   u_law   = -c beta delta                                           (20)
 *
 * Units: x, x_r, e, lambda1, w1 in cm; x', lambda2, theta, w2 in cm/s; t, t_u
 * in s; a in cm/s (theta = -a chi is a velocity and chi is dimensionless);
 * chi, delta dimensionless; beta in s/cm; c in input-units*cm/s (so that u
 * has the input's unit); u in the actuator input unit (the firmware uses kPa
 * of pressure change from the preset p0, see docs/controllers.md).
 *
 * Barrier decision (|lambda_i| reaching w_i, where tan and 1/cos^2 diverge):
 * the normalised argument r_i = lambda_i / w_i is clamped to
 * +-(1 - barrier_margin) before the transformation; each step at or beyond
 * that limit sets PMA_PPC_FLAG_BARRIER1/2 and increments breach counters.
 * The output then saturates at the input limits in the direction the law
 * demands (it never flips sign or becomes NaN). Whether a breach faults the
 * drive is the safety supervisor's decision, fed by these flags.
 *
 * Switches beyond the paper (both OFF by default; OFF computes the paper's law
 * exactly, up to the barrier clamp above):
 *  - soft_barrier_r in (0, 1): for |r_i| > soft_barrier_r the transformation
 *    tan(pi r/2) is continued by its tangent line at soft_barrier_r (and beta
 *    by its value there), so the loop gain stays bounded in a sampled, lagged,
 *    saturated loop. 1 = off. (Fixed point: needs sec^2 at soft_barrier_r
 *    below 32768, i.e. soft_barrier_r <= 0.996.)
 *  - ff_gain_per_s >= 0 with ff_init: a steady-state input feedforward u_ff,
 *    starting at ff_init, that integrates the law's output
 *    (u_ff += ff_gain_per_s * period_s * u_law) while the output is not
 *    saturated in the same direction, clamped so that u_ff + u_ext stays in
 *    [u_min, u_max] (u_ext below; 0: u_ff itself in [u_min, u_max]). It supplies
 *    the steady pressure that the law (no integral action) can otherwise only
 *    produce by pushing lambda2 towards its barrier. 0 and 0 = off.
 *    (Fixed point: ff_gain_per_s * period_s < 1, else PMA_ERR_FIXED_RANGE.)
 *  - ff_hold_speed_cm_s >= 0 (with the feedforward on): the integrator also holds (flag
 *    FF_HOLD) while the muscle closes on the reference faster than this: the
 *    law's velocity input v and the error e have opposite signs and |v| is
 *    above it. A large error (the start, a disturbance) makes the law ask for
 *    a speed in proportion to it; a loop with lag cannot stop from that speed
 *    within the funnel, and an integrator that kept integrating the law's
 *    demand on the way would carry the muscle through the reference by
 *    (speed x lag). Where the muscle already closes that fast the integrator
 *    waits; the law's own output still acts. 0 = off.
 * Output: u = clamp(u_ff + u_law + u_ext, u_min, u_max), with u_ext an input
 * the caller adds (pma_ppc_step_ext_*: the application's reference
 * feedforward; 0 in pma_ppc_step_*). The clamp's flags and the feedforward's
 * anti-windup see the whole output: a reference beyond the plant's reach keeps
 * the input at its limit, not the law's share of it.
 *
 * Funnel widening (widen_r > 0; beyond the paper, off by default): where the
 * paper's law would reach its barrier, the guarantee cannot hold (the task asks
 * for more than the plant gives) and the law's gain is unbounded there. Instead
 * of the clamp, channel i's funnel is widened: lambda1's at the step it reaches
 * the clamp (the position error at its funnel: the guarantee is lost), lambda2's
 * only after widen2_steps consecutive steps at its clamp (a law with a tight w2
 * lives at its velocity barrier in short runs and keeps |e| < w1 there: only a
 * lasting clamp is a loss; widen2_steps 0 keeps lambda2's clamp always). The
 * funnel is widened so: w_i becomes w_i / g_i, with g_i
 * set on that step so that |r_i| = widen_r exactly (g_i is multiplied by
 * widen_r / |r_i|), and flag WIDEN1/2. The funnel then shrinks back to w_i
 * over t_u with the tuning function's shape:
 *   g_i(t) = 1 - (1 - k_i) (0.5 + 0.5 cos(pi (t - t_i) / t_u))  for t - t_i < t_u,
 * 1 afterwards, where k_i and t_i are the scale and time of the last widening.
 * So r_i never reaches the barrier, the loop gain stays that of |r| <= widen_r,
 * and the law keeps tracking as close as the plant allows; the guarantee is
 * back in force t_u after the last widening. r_i = lambda_i g_i / w_i, and
 * beta = sec^2 g2 / w2. Each widening is a lost guarantee for the caller to
 * report (the application's monitor). The clamp stays as a backstop (g_i is
 * kept at or above 2^-20).
 */
#ifndef PMA_PPC_H
#define PMA_PPC_H

#include <stdint.h>
#include "pma/fixed.h"

typedef struct pma_ppc_config {
    float a_cm_s;           /* a > 0 [cm/s] */
    float c;                /* c > 0 [input unit * cm/s] */
    float w1_cm;            /* assigned tracking accuracy w1 > 0 [cm] */
    float w2_cm_s;          /* w2 > 0 [cm/s] */
    float t_u_s;            /* tuning time t_u > 0 [s] */
    float u_min;            /* input limits, u_min < u_max [input unit] */
    float u_max;
    float barrier_margin;   /* clamp |lambda_i/w_i| to 1 - margin; margin in [1e-6, 0.5], default 1e-3 */
    float soft_barrier_r;   /* (0, 1]; 1 = off (paper's law) */
    float ff_gain_per_s;    /* >= 0 [1/s]; 0 = off */
    float ff_init;          /* initial feedforward [input unit], within [u_min, u_max] */
    float ff_hold_speed_cm_s; /* >= 0 [cm/s]: the feedforward holds while the muscle closes on the
                               * reference faster than this (see above); 0 = off */
    float widen_r;          /* funnel widening instead of the clamp: 0 = off (paper's law), else
                             * in [0.05, 1 - barrier_margin) (see "Funnel widening" above) */
    uint32_t widen2_steps;  /* with widen_r: lambda2's funnel widens after this many consecutive
                             * steps at its clamp (0: never, 1: at once); lambda1's at once */
    float period_s;         /* control period > 0 [s] (used by the feedforward only) */
    uint8_t band_enabled;   /* 1: check the constraint band below at init */
    float k_low_cm;         /* constraint band k_low < x < k_high [cm] */
    float k_high_cm;
} pma_ppc_config_t;

/* Defaults: the paper's Case 3 (a = c = 2, w1 = 0.2, w2 = 0.5, t_u = 2),
 * band -3 < x < 0 cm, u in [-400, 400], 1 kHz, switches off. */
void pma_ppc_default_config(pma_ppc_config_t *cfg);

/* Checks every field; also, when band_enabled, that the band is wider than
 * 2 w1 (necessary for eq. 14). Returns PMA_OK or a negative pma_status_t. */
int pma_ppc_validate_config(const pma_ppc_config_t *cfg);

#define PMA_PPC_FLAG_BARRIER1 0x01u   /* |lambda1| reached (1 - margin) w1 this step */
#define PMA_PPC_FLAG_BARRIER2 0x02u   /* |lambda2| reached (1 - margin) w2 this step */
#define PMA_PPC_FLAG_SAT_HIGH 0x04u   /* output clamped at u_max */
#define PMA_PPC_FLAG_SAT_LOW  0x08u   /* output clamped at u_min */
#define PMA_PPC_FLAG_SOFT1    0x10u   /* lambda1 beyond the soft-barrier point */
#define PMA_PPC_FLAG_SOFT2    0x20u   /* lambda2 beyond the soft-barrier point */
#define PMA_PPC_FLAG_WIDEN1   0x40u   /* widen_r: w1's funnel widened this step (instead of a clamp) */
#define PMA_PPC_FLAG_WIDEN2   0x80u   /* widen_r: w2's funnel widened this step (instead of a clamp) */
#define PMA_PPC_FLAG_WIDE     0x100u  /* widen_r: a funnel is still wider than assigned (g < 1) */
#define PMA_PPC_FLAG_FF_HOLD  0x200u  /* ff_hold_speed_cm_s: the muscle closes on the reference
                                       * faster than that; the feedforward held this step */

/* The feedforward integrator's anti-windup: it holds while the output is clamped in the
 * direction the law pushes, and while the muscle closes on the reference faster than
 * ff_hold_speed_cm_s (FF_HOLD) (flags: the step's PMA_PPC_FLAG_*; law_up / law_down:
 * u_law > 0 / u_law < 0). One rule for the integrator and for whatever integrates beside it. */
static inline int pma_ppc_ff_held(uint32_t flags, int law_up, int law_down)
{
    return (flags & PMA_PPC_FLAG_FF_HOLD) || ((flags & PMA_PPC_FLAG_SAT_HIGH) && law_up) ||
           ((flags & PMA_PPC_FLAG_SAT_LOW) && law_down);
}

/* Internals of the last step, for telemetry (float variant). */
typedef struct pma_ppc_out_f32 {
    float alpha, e_cm, lambda1_cm, chi, theta_cm_s, lambda2_cm_s, delta, beta_s_cm;
    float g1, g2;           /* funnel scales: the funnels are w1 / g1, w2 / g2 (1 = as assigned) */
    float u_law;            /* -c beta delta, before feedforward and clamp */
    float u_ff;             /* feedforward term (0 when off) */
    float u;                /* output applied */
    uint32_t flags;         /* PMA_PPC_FLAG_* of this step */
} pma_ppc_out_f32_t;

typedef struct pma_ppc_f32 {
    /* configuration, derived once at init */
    pma_ppc_config_t cfg;
    float inv_w1, inv_w2, r_max;
    float soft_tan, soft_sec2;  /* tan and sec^2 of (pi/2) soft_r */
    /* state */
    float u_ff;
    float widen_k[2], widen_t_s[2]; /* g_i and the time [s] of channel i's last widening
                                     * (meaningful while channel i is wide, widen_bits) */
    uint32_t widen_bits;            /* bits 2 + i: channel i widens; bit i (0, 1): channel i
                                     * wider than assigned. One word for the step's common case */
    uint32_t clamp_run2;            /* consecutive steps of lambda2 at its clamp (widen2_steps) */
    uint32_t breaches1, breaches2;  /* steps with a barrier clamp, since reset */
    pma_ppc_out_f32_t out;
    uint8_t ready;
} pma_ppc_f32_t;

/* init validates cfg; on error the instance is left not ready (step refuses). */
int pma_ppc_init_f32(pma_ppc_f32_t *s, const pma_ppc_config_t *cfg);
/* Clears state (feedforward back to ff_init, counters, outputs). */
void pma_ppc_reset_f32(pma_ppc_f32_t *s);
/* One step. t_s: time since task start [s] (>= 0); x_cm: measured position;
 * v_cm_s: estimated velocity; xr_cm: reference. Writes the input to *u.
 * (The application's options ppc.ref_vel and ppc.obs_pos feed x' - x_r' as
 * v_cm_s and the velocity observer's position estimate as x_cm; the law
 * itself is unchanged: firmware/app/controller.h.)
 * u_ext [input unit]: added to the law's output before the clamp (see "Output"
 * above); pma_ppc_step_f32 is the step with u_ext = 0.
 * Non-finite inputs: returns PMA_ERR_NOT_FINITE, *u and state unchanged.
 * Returns PMA_OK, or a negative code. */
int pma_ppc_step_ext_f32(pma_ppc_f32_t *s, float t_s, float x_cm, float v_cm_s,
                         float xr_cm, float u_ext, float *u);
static inline int pma_ppc_step_f32(pma_ppc_f32_t *s, float t_s, float x_cm, float v_cm_s,
                                   float xr_cm, float *u)
{
    return pma_ppc_step_ext_f32(s, t_s, x_cm, v_cm_s, xr_cm, 0.0f, u);
}
/* Moves the feedforward integrator u_ff by du_u [input unit], without a step: a caller that
 * takes a part of the steady input into u_ext (the application's adapted hysteresis term)
 * hands it over so that u_ff + u_ext stays where the integrator had it. */
static inline void pma_ppc_ff_move_f32(pma_ppc_f32_t *s, float du_u)
{
    s->u_ff += du_u;
}

/* Fixed-point variant: same config (converted and range-checked at init),
 * signals in Q16.16 with the same units, dimensionless r and alpha in Q2.30. */
typedef struct pma_ppc_out_q16 {
    pma_q30_t alpha;
    pma_q16_t e_cm, lambda1_cm, chi, theta_cm_s, lambda2_cm_s, delta, beta_s_cm;
    pma_q16_t u_law, u_ff, u;
    uint32_t flags;
    pma_q30_t g1, g2;               /* funnel scales, Q2.30 (as the float variant) */
} pma_ppc_out_q16_t;

typedef struct pma_ppc_q16 {
    /* configuration, converted once at init. Q8.24 (int32, value = raw/2^24,
     * range +-128) keeps the reciprocals precise: w1, w2, t_u >= 1/64; w1, w2 <= 100. */
    pma_q16_t a, c, t_u, u_min, u_max, ff_init;
    int32_t inv_w1_q24, inv_w2_q24, inv_t_u_q24;
    pma_q30_t ff_k;                 /* ff_gain_per_s * period_s, Q2.30 */
    pma_q30_t r_max, soft_r;
    pma_q16_t soft_tan, soft_sec2;
    /* state */
    int64_t u_ff_q32;               /* feedforward accumulator, 32 fractional bits */
    uint32_t breaches1, breaches2;
    uint32_t widen_bits;            /* bits 2 + i: channel i widens; bit i (0, 1): channel i
                                     * wider than assigned. One word for the step's common case */
    pma_ppc_out_q16_t out;
    /* the feedforward's hold and funnel widening, read only when on: after the step's hot
     * fields, which the Cortex-M0 reaches with one load only within 124 bytes of the instance */
    pma_q16_t ff_hold_v;            /* ff_hold_speed_cm_s, Q16.16 (0: off) */
    pma_q30_t widen_r;              /* 0: widening off */
    uint32_t widen2_steps, clamp_run2;  /* as the float variant's */
    pma_q30_t widen_k[2];           /* g_i at channel i's last widening, Q2.30 (while wide) */
    pma_q16_t widen_t_s[2];         /* its time [s] */
    uint8_t ready;
} pma_ppc_q16_t;

int pma_ppc_init_q16(pma_ppc_q16_t *s, const pma_ppc_config_t *cfg);
void pma_ppc_reset_q16(pma_ppc_q16_t *s);
/* t_s in Q16.16 seconds (>= 0; up to 9.1 h), others Q16.16 as in the float variant. */
int pma_ppc_step_ext_q16(pma_ppc_q16_t *s, pma_q16_t t_s, pma_q16_t x_cm, pma_q16_t v_cm_s,
                         pma_q16_t xr_cm, pma_q16_t u_ext, pma_q16_t *u);
static inline int pma_ppc_step_q16(pma_ppc_q16_t *s, pma_q16_t t_s, pma_q16_t x_cm,
                                   pma_q16_t v_cm_s, pma_q16_t xr_cm, pma_q16_t *u)
{
    return pma_ppc_step_ext_q16(s, t_s, x_cm, v_cm_s, xr_cm, 0, u);
}
/* As pma_ppc_ff_move_f32, du in input units with 32 fractional bits (the accumulator's);
 * meaningful with the feedforward on (ff_gain_per_s > 0: the step reads u_ff from it only then). */
static inline void pma_ppc_ff_move_q16(pma_ppc_q16_t *s, int64_t du_q32)
{
    s->u_ff_q32 += du_q32;
}

#endif /* PMA_PPC_H */
