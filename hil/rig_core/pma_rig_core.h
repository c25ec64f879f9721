/* SPDX-License-Identifier: Apache-2.0 */
/* The simulated rig's dynamics (hil/rig.py, docs/rig.md): the right-hand side of the PMA's
 * three-element model with its load, hysteresis, temperature drift, disturbance cylinder,
 * and the extended model's flow-limited valve and creep, integrated by classic RK4. Compiled
 * for the HIL harness (libpma_rig.so, preset host-offline) so that a control tick's rig step
 * costs no Python interpreter time; hil/rig.py keeps the parameters, the regulator's dead time
 * and events, the sensor and the static model, and fills pma_rig_model (ctypes).
 * Units: positions mm (contraction), velocities mm/s, pressures kPa (gauge), forces N,
 * times s (ns where an int64_t), temperatures K. Not firmware: doubles, no target. */
#ifndef PMA_RIG_CORE_H
#define PMA_RIG_CORE_H

#include <stdint.h>

#define PMA_RIG_CORE_API_VERSION 3
#define PMA_RIG_MAX_HYST 8                          /* Dahl elements of the hysteresis */
#define PMA_RIG_MAX_STATE (4 + PMA_RIG_MAX_HYST + 2) /* xs, v, P, y, z_i..., q, Fc */

/* The constants of the right-hand side (hil/rig.py Rig._cache fills them). hil/rig_lib.py reads
 * this struct's fields from here (its ctypes layout): declare them as double, int32_t, int64_t,
 * const double * or const int64_t *, arrays sized by a number or an integer #define. */
typedef struct {
    double f0_n, f1_n_per_kpa, f_clip_width_sq_n2; /* contractile element F(P), smooth clip */
    double k_break_kpa, k_blend_kpa;                /* spring K(P): branch blend */
    double k0_low_n_per_mm, k1_low_n_per_mm_kpa;    /* low branch, stiffness scale applied */
    double k0_high_n_per_mm, k1_high_n_per_mm_kpa;  /* high branch, stiffness scale applied */
    double b_mid_ns_per_mm, b_half_ns_per_mm, b_blend_mm_s; /* damper B(v) */
    double hyst_force_n, hyst_ramp_n;               /* hysteresis force scale and its ramp in F */
    double hyst_delta_mm[PMA_RIG_MAX_HYST];         /* each element's width */
    double hyst_w_per_delta_per_mm[PMA_RIG_MAX_HYST]; /* its weight / width */
    double drift_rate_k_per_s, drift_max_rise_k;    /* temperature rise: ramp, then flat */
    double drift_f_per_k, drift_k_per_k, drift_b_per_k; /* relative change of F, K, B per K */
    double tau_p_s, tau_y_s;                        /* regulator lag; sensor lag (0: none) */
    double w_static_n;                              /* gravity along the axis + bias force */
    double acc_mm_s2_per_n;                         /* 1000 / load mass [kg] */
    double dist_tau_s;                              /* the disturbance cylinder's lag */
    const int64_t *dist_t_ns;                       /* its switch times, ascending */
    const double *dist_target_n;                    /* the force it moves to at each switch */
    const double *dist_start_n;                     /* its force at each switch */
    int64_t drift_knee_ns;                          /* end of the temperature ramp; <0: none */
    int32_t n_hyst;                                 /* 0..PMA_RIG_MAX_HYST */
    int32_t n_dist;                                 /* switch events (0: no disturbance) */
    int32_t ext;                                    /* 1: extended model (valve and creep) */
    int32_t flow;                                   /* 1: flow-limited valve (ext only) */
    /* extended model: creep (part of F through a lag) */
    double creep_frac_contract, creep_frac_relax, creep_inv_tau_contract_per_s, creep_inv_tau_relax_per_s;
    double creep_blend_sq_n2;
    /* extended model: the valve's pilot (part of a step at once, the rest with a lag) */
    double slow_weight_rise, slow_weight_fall, slow_inv_tau_rise_per_s, slow_inv_tau_fall_per_s;
    /* extended model: the flow-limited valve (ISO 6358 orifice, polytropic volume change) */
    double valve_band_kpa, valve_fill_rate_kpa_s, valve_exhaust_rate_kpa_s;
    double valve_supply_abs_kpa, valve_atm_kpa, valve_b_critical, valve_volume_gain_per_mm, valve_polytropic_n;
} pma_rig_model;

int pma_rig_core_api_version(void);
/* sizeof(pma_rig_model): the ctypes layout is checked against it at load */
int pma_rig_model_size(void);
/* PMA_RIG_MAX_STATE: the state buffer's length the caller provides (checked at load) */
int pma_rig_max_state(void);
/* The number of state variables of a model: 4 + n_hyst (+ 2 with ext). */
int pma_rig_state_len(const pma_rig_model *m);
/* Advance the state s from t_ns to stop_ns with the regulator set point p_set_kpa held: RK4
 * sub-steps of h_ns from t_ns, each ended early at a disturbance switch or at the temperature
 * ramp's end. 0, or -1 (s untouched) for a model this build cannot hold (n_hyst outside
 * 0..PMA_RIG_MAX_HYST) or a sub-step h_ns <= 0. */
int pma_rig_advance(const pma_rig_model *m, double *s, int64_t t_ns, int64_t stop_ns, int64_t h_ns,
                    double p_set_kpa);
/* The disturbance cylinder's force [N] at t_s. */
double pma_rig_disturbance_n(const pma_rig_model *m, double t_s);

#endif
