/* SPDX-License-Identifier: Apache-2.0 */
/* The simulated rig's dynamics: see pma_rig_core.h. The model and its figures are documented
 * in docs/rig.md; every expression keeps the order of operations it has there and had in
 * Python, so that runs are reproducible to the last digit across versions. */
#include "pma_rig_core.h"

#include <math.h>

int pma_rig_core_api_version(void) { return PMA_RIG_CORE_API_VERSION; }

int pma_rig_model_size(void) { return (int)sizeof(pma_rig_model); }

int pma_rig_max_state(void) { return PMA_RIG_MAX_STATE; }

int pma_rig_state_len(const pma_rig_model *m) { return 4 + m->n_hyst + (m->ext ? 2 : 0); }

double pma_rig_disturbance_n(const pma_rig_model *m, double t_s)
{
    double value = 0.0;
    for (int32_t i = 0; i < m->n_dist; i++) {
        double t_on = (double)m->dist_t_ns[i] * 1e-9;
        if (t_s < t_on) {
            break;
        }
        double target = m->dist_target_n[i];
        value = m->dist_tau_s <= 0.0 ? target
                                     : target + (m->dist_start_n[i] - target) * exp(-(t_s - t_on) / m->dist_tau_s);
    }
    return value;
}

/* Relative flow of an orifice at a downstream/upstream pressure ratio (1: choked). */
static double iso6358(double ratio, double b)
{
    if (ratio <= b) {
        return 1.0;
    }
    if (ratio >= 1.0) {
        return 0.0;
    }
    double r = (ratio - b) / (1.0 - b);
    return sqrt(1.0 - r * r);
}

/* The temperature rise [K] at t_s. */
static double temp_rise_k(const pma_rig_model *m, double t_s)
{
    double rate = m->drift_rate_k_per_s;
    return rate > 0.0 ? (rate * t_s < m->drift_max_rise_k ? rate * t_s : m->drift_max_rise_k) : 0.0;
}

/* Spring K(P) [N/mm] with the temperature drift. */
static double stiffness(const pma_rig_model *m, double pr, double d_t)
{
    double u = (pr - m->k_break_kpa) / m->k_blend_kpa;
    double k_lo = m->k0_low_n_per_mm - m->k1_low_n_per_mm_kpa * pr;
    double k_hi = m->k0_high_n_per_mm - m->k1_high_n_per_mm_kpa * pr;
    return (k_lo + (k_hi - k_lo) * 0.5 * (1.0 + u / sqrt(u * u + 1.0))) * (1.0 + m->drift_k_per_k * d_t);
}

/* Damper B(v) [N s/mm] with the temperature drift. */
static double damping(const pma_rig_model *m, double v, double d_t)
{
    return (m->b_mid_ns_per_mm + m->b_half_ns_per_mm * tanh(v / m->b_blend_mm_s)) * (1.0 + m->drift_b_per_k * d_t);
}

/* The hysteresis elements' derivatives into out[4..] and their force [N]. */
static double hysteresis(const pma_rig_model *m, const double *z, double v, double force, double *out)
{
    int32_t nh = m->n_hyst;
    if (!(m->hyst_force_n > 0.0)) {
        for (int32_t i = 0; i < nh; i++) {
            out[4 + i] = 0.0;
        }
        return 0.0;
    }
    double av = fabs(v);
    double acc = 0.0;
    for (int32_t i = 0; i < nh; i++) {
        acc += m->hyst_w_per_delta_per_mm[i] * z[i];
        out[4 + i] = v - av * z[i] / m->hyst_delta_mm[i];
    }
    return m->hyst_force_n * (1.0 - exp(-force / m->hyst_ramp_n)) * acc;
}

static double load_n(const pma_rig_model *m, double t)
{
    double w_load = m->w_static_n;
    if (m->n_dist > 0) {
        w_load += pma_rig_disturbance_n(m, t);
    }
    return w_load;
}

/* The mechanics with the muscle's force [N]: out[0], out[1] (the load's motion), out[3] (the
 * sensor) and the hysteresis elements' out[4..]. */
static void mechanics(const pma_rig_model *m, double t, const double *s, double force, double d_t, double *out)
{
    double xs = s[0], v = s[1], pr = s[2];
    double k = stiffness(m, pr, d_t);
    double b = damping(m, v, d_t);
    double w_load = load_n(m, t);
    out[0] = v;
    double fh = hysteresis(m, s + 4, v, force, out);
    out[1] = m->acc_mm_s2_per_n * (force - k * xs - b * v - fh - w_load);
    out[3] = m->tau_y_s > 0.0 ? (xs - s[3]) / m->tau_y_s : v;
}

/* The three-element model (docs/rig.md). */
static void rhs(const pma_rig_model *m, double t, const double *s, double p_set, double *out)
{
    double pr = s[2];
    double d_t = temp_rise_k(m, t);
    double f = m->f0_n + m->f1_n_per_kpa * pr;
    double force = 0.5 * (f + sqrt(f * f + m->f_clip_width_sq_n2)) * (1.0 + m->drift_f_per_k * d_t);
    mechanics(m, t, s, force, d_t, out);
    out[2] = (p_set - pr) / m->tau_p_s;
}

/* The extended model: the three-element one with creep and the valve (docs/rig.md, "Against a
 * real muscle"). */
static void rhs_ext(const pma_rig_model *m, double t, const double *s, double p_set, double *out)
{
    int32_t nh = m->n_hyst;
    double xs = s[0], v = s[1], pr = s[2];
    double q = s[4 + nh], fc = s[5 + nh];
    double d_t = temp_rise_k(m, t);
    double f = m->f0_n + m->f1_n_per_kpa * pr;
    double f_pos = 0.5 * (f + sqrt(f * f + m->f_clip_width_sq_n2));
    /* creep: part of the contractile force arrives through a first-order lag */
    double d = f_pos - fc;
    double sw = 0.5 * (1.0 + d / sqrt(d * d + m->creep_blend_sq_n2)); /* 1 contracting, 0 relaxing */
    double d_fc = d * (m->creep_inv_tau_relax_per_s +
                       (m->creep_inv_tau_contract_per_s - m->creep_inv_tau_relax_per_s) * sw);
    double force = (f_pos - (m->creep_frac_relax + (m->creep_frac_contract - m->creep_frac_relax) * sw) * d) *
                   (1.0 + m->drift_f_per_k * d_t);
    mechanics(m, t, s, force, d_t, out);
    /* the valve's set point: part of a step at once, the rest through the slow pilot */
    double dq = p_set - q;
    double swq = 0.5 * (1.0 + dq / sqrt(dq * dq + 1.0)); /* 1 rising, 0 falling (1 kPa blend) */
    double target = p_set - (m->slow_weight_fall + (m->slow_weight_rise - m->slow_weight_fall) * swq) * dq;
    double d_q = dq * (m->slow_inv_tau_fall_per_s + (m->slow_inv_tau_rise_per_s - m->slow_inv_tau_fall_per_s) * swq);
    if (m->flow) {
        double e = (target - pr) / m->valve_band_kpa;
        double opening = e / sqrt(1.0 + e * e);
        double p_abs = pr + m->valve_atm_kpa;
        double dp;
        if (opening >= 0.0) {
            dp = m->valve_fill_rate_kpa_s * opening * iso6358(p_abs / m->valve_supply_abs_kpa, m->valve_b_critical);
        } else {
            dp = m->valve_exhaust_rate_kpa_s * opening * (p_abs / m->valve_supply_abs_kpa) *
                 iso6358(p_abs > 0.0 ? m->valve_atm_kpa / p_abs : 1.0, m->valve_b_critical);
        }
        double vol = 1.0 + m->valve_volume_gain_per_mm * xs;
        vol = vol > 0.2 ? vol : 0.2;
        out[2] = (dp - m->valve_polytropic_n * p_abs * m->valve_volume_gain_per_mm * v) / vol;
    } else {
        out[2] = (target - pr) / m->tau_p_s;
    }
    out[4 + nh] = d_q;
    out[5 + nh] = d_fc;
}

static void eval(const pma_rig_model *m, double t, const double *s, double p_set, double *out)
{
    if (m->ext) {
        rhs_ext(m, t, s, p_set, out);
    } else {
        rhs(m, t, s, p_set, out);
    }
}

static void rk4(const pma_rig_model *m, double *s, int n, double t, double h, double p_set)
{
    double k1[PMA_RIG_MAX_STATE], k2[PMA_RIG_MAX_STATE], k3[PMA_RIG_MAX_STATE], k4[PMA_RIG_MAX_STATE];
    double tmp[PMA_RIG_MAX_STATE] = {0};
    double hh = 0.5 * h;
    eval(m, t, s, p_set, k1);
    for (int i = 0; i < n; i++) {
        tmp[i] = s[i] + hh * k1[i];
    }
    eval(m, t + hh, tmp, p_set, k2);
    for (int i = 0; i < n; i++) {
        tmp[i] = s[i] + hh * k2[i];
    }
    eval(m, t + hh, tmp, p_set, k3);
    for (int i = 0; i < n; i++) {
        tmp[i] = s[i] + h * k3[i];
    }
    eval(m, t + h, tmp, p_set, k4);
    double h6 = h / 6.0;
    for (int i = 0; i < n; i++) {
        s[i] = s[i] + h6 * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]);
    }
}

int pma_rig_advance(const pma_rig_model *m, double *s, int64_t t_ns, int64_t stop_ns, int64_t h_ns,
                    double p_set_kpa)
{
    if (m->n_hyst < 0 || m->n_hyst > PMA_RIG_MAX_HYST || h_ns <= 0) {
        return -1;
    }
    int n = pma_rig_state_len(m);
    while (t_ns < stop_ns) {
        int64_t nxt = t_ns + h_ns < stop_ns ? t_ns + h_ns : stop_ns;
        for (int32_t i = 0; i < m->n_dist; i++) {
            if (t_ns < m->dist_t_ns[i] && m->dist_t_ns[i] < nxt) {
                nxt = m->dist_t_ns[i];
                break;
            }
        }
        if (m->drift_knee_ns >= 0 && t_ns < m->drift_knee_ns && m->drift_knee_ns < nxt) {
            nxt = m->drift_knee_ns;
        }
        rk4(m, s, n, (double)t_ns * 1e-9, (double)(nxt - t_ns) * 1e-9, p_set_kpa);
        t_ns = nxt;
    }
    return 0;
}
