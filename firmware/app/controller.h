/* SPDX-License-Identifier: Apache-2.0 */
/* The application's controller slot: the reference, the velocity estimator and
 * the selected controller (ctrl.mode), built from the parameters at START and
 * stepped once per tick while RUNNING, in the arithmetic the build chose (PMA_CTRL_Q16:
 * float on cores with an FPU, Q16.16 without one). controller.c builds and checks the
 * configurations, controller_f32.c / controller_q16.c step them. Pure: no HAL, no globals. */
#ifndef PMA_CONTROLLER_H
#define PMA_CONTROLLER_H

#include <stdint.h>

#include "params.h"
#include "pma/lpf.h"
#include "pma/mfac.h"
#include "pma/pid.h"
#include "pma/ppc.h"
#include "pma/ref.h"
#include "pma/velest.h"

/* Bits of pma_ctrl_out_t.flags above the control laws' own PMA_*_FLAG_* (bits 0-8); they
 * travel in TELEM_E CtrlFlags. */
#define PMA_CTRL_FLAG_GUARANTEE_LOST 0x4000u /* PPC: the guarantee was lost since START (latched) */
#define PMA_CTRL_FLAG_FALLBACK       0x8000u /* PPC: MFAC is in charge (ppc.fallback MFAC or WIDEN) */
/* the law's input-limit flags (pma/ppc.h), which the guarantee monitor follows */
#define PMA_CTRL_SAT_FLAGS (PMA_PPC_FLAG_SAT_HIGH | PMA_PPC_FLAG_SAT_LOW)

typedef struct pma_ctrl_out {
    float t_s;              /* control time since START */
    float xr_cm, e_cm;      /* reference and e = x - xr (x the raw sample) */
    float xr_dot_cm_s;      /* the reference's derivative [cm/s] (STREAM: this tick's rate-limited step / period) */
    float v_cm_s;           /* velocity estimate */
    float u;                /* output, within ctrl.u_min..u_max [input unit] */
    float internal1, internal2; /* TELEM_D: PPC lambda1 [cm], lambda2 [cm/s]; MFAC phi, u(k-1); PID I, D */
    uint32_t flags;         /* the controller's PMA_*_FLAG_* of this step, and PMA_CTRL_FLAG_* */
    uint8_t barrier;        /* PPC: a barrier clamp this step */
} pma_ctrl_out_t;

/* The controller slot's arithmetic, chosen at build time (CMake PMA_CTRL_ARITH, firmware/app):
 * 0 float (the _f32 variants), 1 Q16.16 (the _q16 variants; docs/fixed-point.md). The
 * parameters stay float in their physical units; START converts them once. */
#ifndef PMA_CTRL_Q16
#define PMA_CTRL_Q16 0
#endif

#if PMA_CTRL_Q16
/* Q16.16 copies of the step's signals (pma_ctrl_out_t in fixed point) */
typedef struct pma_ctrl_out_q16 {
    pma_q16_t t_s, xr_cm, e_cm, xr_dot_cm_s, v_cm_s, u, internal1, internal2;
} pma_ctrl_out_q16_t;
#endif

typedef struct pma_ctrl {
    uint8_t mode;           /* PMA_CTRL_MODE_* */
    float period_s, u_min, u_max;
    pma_ref_config_t ref_cfg;
#if PMA_CTRL_Q16
    /* option ppc.u_lpf_hz: the law's command low-pass, as below (near the start: the M0 reaches
     * it without an offset computation on every tick) */
    pma_lpf_q16_t u_lpf;
    pma_ref_q16_t ref;
    pma_velest_q16_t vel;
    union {
        pma_ppc_q16_t ppc;
        pma_mfac_q16_t mfac;
        pma_pid_q16_t pid;
    } c;
    pma_mfac_q16_t shadow;  /* MFAC, in charge from the hand-over (ppc.fallback), as below */
    pma_q16_t q_period_s, q_w1_cm, q_t_u_s;
    pma_q16_t q_ref_ff_u_per_cm, q_ref_ff_lead_s, q_xr0_cm;
    pma_q16_t q_hyst_cm, q_hyst_inv_cm, q_play_z_cm;     /* ref_ff_hyst_cm (0: the term is off), its inverse, the play */
    pma_q16_t q_hyst_u, q_hyst_max_u;                    /* the height H and its bound [input unit] */
    int64_t q_hyst_u_q32;                                /* H with 32 fractional bits (adapted) */
    pma_q30_t q_hyst_k;                                  /* gain * period (Q2.30) */
    pma_ctrl_out_q16_t q_out;
#else
    pma_ref_f32_t ref;
    pma_velest_f32_t vel;
    union {
        pma_ppc_f32_t ppc;
        pma_mfac_f32_t mfac;
        pma_pid_f32_t pid;
    } c;
    /* PPC's guarantee monitor and fallback (docs/controllers.md, "When the guarantee is lost") */
    pma_mfac_f32_t shadow;  /* MFAC, in charge from the hand-over (ppc.fallback) */
    pma_lpf_f32_t u_lpf;    /* option ppc.u_lpf_hz: the law's command low-pass (not MFAC's) */
    float play_z_cm;        /* ppc.ref_ff_hyst's play operator: its output z on x_r + lead x_r' [cm] */
#endif
    uint8_t ppc_ref_vel;    /* option ppc.ref_vel: the law damps x' - x_r' */
    uint8_t ppc_obs_pos;    /* option ppc.obs_pos: the law's x is the observer's x_hat */
    uint8_t xr0_set;        /* xr0_cm holds the reference at START */
    uint8_t hyst_on;        /* the hysteresis term is on (ppc.ref_ff_hyst or its adaptation) */
    float ref_ff_u_per_cm;  /* option ppc.ref_ff: the static map's slope [input unit/cm] (0: off) */
    float ref_ff_lead_s;    /* ppc.ref_ff_lead_s: how far ahead the feedforward takes x_r [s] */
    float hyst_u;           /* its height H [input unit]: ppc.ref_ff_hyst at START; float: adapted */
    float hyst_cm;          /* ppc.ref_ff_hyst_cm: the play operator's half-width [cm] */
    float hyst_k;           /* ppc.ref_ff_hyst_gain_per_s * period: H's adaptation per step (0: fixed) */
    float hyst_max_u;       /* ppc.ref_ff_hyst_max: H's bound while it adapts [input unit] */
    float xr0_cm;           /* the reference at START [cm] */
    uint32_t breaches;      /* steps with a barrier clamp since START */
    uint8_t fallback_mode;  /* ppc.fallback: PMA_PPC_FALLBACK_NONE, _MFAC, _WIDEN */
    uint8_t lost;           /* the guarantee was lost since START (latched) */
    uint8_t fallback_active;/* MFAC is in charge (from the first lost tick until STOP) */
    uint8_t widen1_sat;     /* WIDEN: the law's SAT_HIGH / SAT_LOW flag at the last widening */
    uint8_t widen1_held;    /* WIDEN: that flag while every tick since has had it, else 0 */
    uint8_t widen1_swing;   /* WIDEN: the SAT flags of the lost ticks since the last widening */
    float w1_cm, t_u_s;     /* the monitor's bound and the time it starts [cm, s] */
    uint32_t barrier_ticks; /* safety.barrier_ticks: a clamp run this long is lost (0: never) */
    uint32_t barrier_run;   /* consecutive ticks with a barrier clamp */
    uint32_t lost_ticks;    /* lost ticks since START (saturates at 2^32-1) */
    float lost_at_s;        /* control time of the first of them [s] */
    uint32_t widen1_count;  /* WIDEN: widenings of the position funnel since START */
    float widen1_at_s;      /* WIDEN: control time of the last of them [s] */
    float stream_margin_cm; /* STREAM targets keep this far inside the band (PPC: w1) */
    /* the last step's signals in float: read them with pma_ctrl_out() (Q16.16: converted
     * there, not in every step) */
    pma_ctrl_out_t out;
} pma_ctrl_t;

/* The configurations START builds from the parameters, for the arithmetic's init
 * (controller_f32.c or controller_q16.c). */
typedef struct pma_ctrl_setup {
    pma_velest_config_t vel;
    pma_ppc_config_t ppc;   /* mode PPC */
    pma_lpf_config_t u_lpf; /* mode PPC: ppc.u_lpf_hz */
    pma_mfac_config_t mfac; /* mode MFAC, or PPC's fallback (fallback_mode) */
    pma_pid_config_t pid;   /* mode PID */
} pma_ctrl_setup_t;

/* The arithmetic's part of START: the instances from su (s's fields from the parameters
 * are set); PMA_ERR_FIXED_RANGE when a value does not fit Q16.16. */
int pma_ctrl_init_arith(pma_ctrl_t *s, const pma_ctrl_setup_t *su);
/* The PPC's guarantee monitor for one step, in either arithmetic (see below): after_tu is
 * t >= t_u, outside_w1 after_tu and |e| >= w1, law_flags the law's PMA_PPC_FLAG_* of this step
 * (a barrier clamp, a widening, the output at a limit). pma_ctrl_monitor counts the clamp run
 * and returns nonzero where this step lost the guarantee; then pma_ctrl_monitor_lost, with the
 * step's time t_s [s] (taken only then: the Q16.16 slot converts it to float only for it),
 * counts the lost ticks, latches `lost` with `lost_at_s` and, with the MFAC fallback, hands
 * over. The monitor is inline (every step),
 * pma_ctrl_monitor_lost (controller.c) runs only on a lost tick. */
static inline int pma_ctrl_clamp_run(const pma_ctrl_t *s)
{
    /* the law's clamp has lasted ctrl.barrier_ticks steps (0: never counts) */
    return s->barrier_ticks != 0 && s->barrier_run >= s->barrier_ticks;
}
static inline int pma_ctrl_monitor(pma_ctrl_t *s, int after_tu, int outside_w1, uint32_t law_flags)
{
    const int widened = (law_flags & (PMA_PPC_FLAG_WIDEN1 | PMA_PPC_FLAG_WIDEN2)) != 0;
    s->widen1_held &= (uint8_t)(law_flags & PMA_CTRL_SAT_FLAGS);
    if (!(law_flags & (PMA_PPC_FLAG_BARRIER1 | PMA_PPC_FLAG_BARRIER2))) {
        s->barrier_run = 0u;
        return outside_w1 || widened;
    }
    ++s->barrier_run;
    /* after t_u a clamp with the output at its limit, however short: the law has no input left
     * to hold its funnel with (the task asks more than the input range gives there) */
    if (after_tu && (law_flags & PMA_CTRL_SAT_FLAGS)) return 1;
    return outside_w1 || pma_ctrl_clamp_run(s) || widened;
}
void pma_ctrl_monitor_lost(pma_ctrl_t *s, float t_s, uint32_t law_flags);
/* Every lost tick counts (saturating at 2^32-1). */
static inline void pma_ctrl_count_lost(pma_ctrl_t *s)
{
    if (s->lost_ticks != UINT32_MAX) ++s->lost_ticks;
}
/* A lost tick on which pma_ctrl_monitor_lost would only count: the guarantee already lost, no
 * widening of the position funnel since START nor on this tick, no clamp run, MFAC not to take
 * over. Then the caller counts it (pma_ctrl_count_lost) and the Q16.16 slot need not convert
 * the time to float for pma_ctrl_monitor_lost (a law living at its barrier with its output at a
 * limit loses every tick after t_u). */
static inline int pma_ctrl_lost_again(const pma_ctrl_t *s, uint32_t law_flags)
{
    return s->lost && s->widen1_count == 0u && !(law_flags & PMA_PPC_FLAG_WIDEN1) &&
           !pma_ctrl_clamp_run(s) && (s->fallback_mode != PMA_PPC_FALLBACK_MFAC || s->fallback_active);
}
/* The arithmetic's part of pma_ctrl_stream, after the band check. */
int pma_ctrl_stream_arith(pma_ctrl_t *s, float target_cm);

/* Builds and validates everything from p for control period period_s; checks
 * the reference against the constraint band (safety.x_min/x_max_cm; with
 * margin ppc.w1_cm for PPC when ppc.band_check) over ref.horizon_s.
 * PMA_OK or the first validation error (PMA_ERR_RANGE, PMA_ERR_BAND, ...;
 * PMA_ERR_RANGE also for ppc.obs_pos without the tracking observer).
 *
 * The PPC options beyond the paper (all off by default) choose what the
 * unchanged law (pma/ppc.h) is fed, so that eq. 15-22 stay as written:
 *  - ppc.ref_vel: the velocity input is x' - x_r' instead of x', i.e.
 *    lambda2 = alpha (x' - x_r') - theta. The paper's lambda2 damps the
 *    absolute velocity, which on a moving reference acts against the
 *    motion; with the feedforward integrator (which then integrates x' and
 *    so becomes a stiffness on x rather than on e) that is a lag.
 *  - ppc.obs_pos: the position input is the tracking observer's estimate
 *    x_hat (vel.kind 1, bandwidth vel.fc_hz) instead of the raw sample: the
 *    law's error e = x_hat - x_r passes the sensor's noise and quantisation
 *    to u only through the observer's low-pass.
 *  - ppc.ref_ff (input unit per cm) with ppc.ref_ff_lead_s: a reference
 *    feedforward added to the law's output inside its clamp to
 *    ctrl.u_min..u_max (pma_ppc_step_ext_*: the flags and the feedforward
 *    integrator's anti-windup see the sum), u_rff = ref_ff ((x_r - x_r(0)) +
 *    lead x_r'), x_r(0) the reference at START: the input the static map
 *    predicts for the reference taken `lead` ahead, so that the law and its
 *    feedforward integrator correct only what the map does not predict. Off
 *    (0) in the paper's law.
 *  - ppc.ref_ff_hyst (input unit) with ppc.ref_ff_hyst_cm: added to u_rff, the
 *    branch of the muscle's hysteresis the reference is on, H (x_a - z) / b
 *    with x_a = x_r + lead x_r' and z a play operator of half-width b on x_a
 *    (z(0) = x_a(0)): +H while x_a rises, -H while it falls. It depends on
 *    the reference alone. Off (0) in the paper's law; PMA_ERR_RANGE for a
 *    negative H or b <= 0, and in Q16.16 PMA_ERR_FIXED_RANGE where H / b does
 *    not fit or the term would round to nothing.
 *  - ppc.u_lpf_hz: the law's output (with the feedforwards, after its clamp)
 *    through a first-order low-pass at that cut-off (pma/lpf.h), primed by
 *    the first step; the law, its flags and its feedforward integrator are
 *    the unfiltered law's. MFAC's output after a hand-over is not filtered.
 *    Off (0) in the paper's law. */
int pma_ctrl_start(pma_ctrl_t *s, const pma_params_t *p, float period_s);

/* One step at control time t_s with position x_cm; openloop_u is the live
 * ctrl.openloop_u. *u receives the output (0 on error). */
int pma_ctrl_step(pma_ctrl_t *s, float t_s, float x_cm, float openloop_u, float *u);

#if PMA_CTRL_Q16
/* The end of the Q16.16 slot's control time: 32767 s [Q16.16] (a step at or after it is refused) */
#define PMA_CTRL_Q16_T_END ((pma_q16_t)32767 * PMA_Q16_ONE)
/* The same step in the Q16.16 slot's numbers, as the application's tick calls it (no float
 * conversion of its inputs): t [s] and x [cm] in Q16.16; the output in Q16.16 (*u_q16) and, where
 * u is not NULL, in float (*u). pma_ctrl_step converts its float inputs (range checked) and
 * calls it. */
int pma_ctrl_step_q16(pma_ctrl_t *s, pma_q16_t t_s, pma_q16_t x_cm, float openloop_u, pma_q16_t *u_q16,
                      float *u);
/* 1 where the step's output is its Q16.16 value (*u == pma_q16_to_f32(*u_q16)): every mode but
 * OPEN_LOOP, whose output is ctrl.openloop_u clamped in float, the float build's value */
static inline int pma_ctrl_output_in_q16(const pma_ctrl_t *s)
{
    return s->mode != PMA_CTRL_MODE_OPEN_LOOP;
}
#endif

/* The PPC's guarantee monitor (mode PPC; t the control time since START, e = x - x_r with
 * the raw sample): a tick with t >= t_u and |e| >= w1, a tick on which the law widened a
 * funnel (ppc.fallback WIDEN: flags WIDEN1/2), a tick with t >= t_u on which the law's
 * barrier clamp came with its output at ctrl.u_min or u_max (SAT_LOW / SAT_HIGH), or (at any
 * t) the last of safety.barrier_ticks consecutive ticks with a barrier clamp of the law (the
 * run that faults BARRIER with ppc.fallback NONE) and every clamped tick after it, is a lost
 * tick. The first one latches `lost` and records `lost_at_s`; every one counts in
 * `lost_ticks`.
 * The hand-over to MFAC (`shadow`, the mfac.* gains; the law is not stepped again until
 * STOP) starts MFAC as it would start on its own at that point of the reference: from the
 * holding input there by the static map (ppc.ff_init plus the reference feedforward) and
 * from phi(1), not from the law's last input (pma_mfac_take_over_*). It comes
 *  - with ppc.fallback MFAC at the first lost tick;
 *  - with ppc.fallback WIDEN at the second widening of the position funnel within t_u of
 *    the one before (the law could not bring the error back inside its widened funnel: the
 *    task keeps asking more than the rig gives), or at a clamp run (the widening's floor);
 *  - with ppc.fallback NONE never: the clamp run faults BARRIER instead. */

/* The last step's signals in float (for telemetry and tests): Q16.16 converts them here. */
const pma_ctrl_out_t *pma_ctrl_out(pma_ctrl_t *s);

/* STREAM reference: a new target, accepted when finite and strictly inside
 * the constraint band (x_min + m, x_max - m), m = w1 for PPC with the band
 * check (eq. 14 as START checks it), else 0; PMA_ERR_UNSUPPORTED for other
 * kinds. */
int pma_ctrl_stream(pma_ctrl_t *s, float target_cm, float x_min_cm, float x_max_cm);

#endif /* PMA_CONTROLLER_H */
