/* SPDX-License-Identifier: Apache-2.0 */
/* Golden-vector test of the PID baseline (pma_pid_*): every set of vectors/pid_vectors.h
 * through the float and the Q16.16 variant; u and the flags of every row.
 *
 * The rows are a recorded closed-loop sequence, run open loop here, so the integrator and
 * the derivative filter carry their rounding errors from row to row. The tolerance follows
 * them (pid_tol below, first order, on the expected values):
 *   P = kp e:      the product's rounding, and (Q16) kp's conversion (half an LSB x |e|);
 *   D (filtered):  error of D(k-1) x tf/(tf+T), plus the rounding of the new terms and
 *                  (Q16) the conversion of kd/(tf+T) (half an LSB x |y(k) - y(k-1)|);
 *   I:             unchanged by unsaturated rows except the rounding of T ki e (Q2.30
 *                  constant: 2^-31 |e|; the accumulator has 32 fractional bits); in a
 *                  saturated row the back-calculation I += T k_aw (u - v) feeds the error
 *                  of v back: (1 - T k_aw) tol(I) + T k_aw (tol(P) + tol(D));
 *   u:             the limit (exact) when saturated, else tol(P) + tol(I) + tol(D).
 *   tol = TOL_SAFETY * model + BASE_REL |u| + BASE_ABS + U_SPAN_FRAC (u_max - u_min).
 * Primitive errors: float 1e-6 relative per product and the rounding of the stored state
 * (6e-8 relative per row); Q16 half an LSB per rounding.
 * Floors: float 1e-5 relative + 1e-6; Q16 1e-5 relative + 4 LSB + 0.001 % of the input
 * range (2 mkPa for 200 kPa). No transcendental function and no run-time division: the
 * variant's error is a few LSB (the model above), so the PID gets a 100 times tighter
 * floor than the paper's controller, whose tan amplifies the Q16 quantisation.
 * Flags exact (the generator keeps the unclamped output more than 0.01 input units from
 * the limits). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>

#include "pma/status.h"
#include "pma_test.h"
#include "golden.h"
#include "golden_check.h"
#include "vectors/pid_vectors.h"

#define TOL_SAFETY 2.0

#define F32_REL 1e-6
#define F32_STATE_REL 6e-8
#define F32_BASE_REL 1e-5
#define F32_BASE_ABS 1e-6

#define Q16_HALF_LSB (0.5 / 65536.0)
#define Q30_HALF_LSB (0.5 / 1073741824.0)
#define Q16_REL 1e-6
#define Q16_BASE_REL 1e-5
#define Q16_BASE_ABS (4.0 / 65536.0)
#define U_SPAN_FRAC_Q16 1e-5

typedef struct pid_model {
    double rel, state_rel, h, hq30;
    double tol_i, tol_d;     /* running errors of I(k), D(k-1) */
    double i_abs, d_abs;     /* magnitude estimates of I and D (for relative terms) */
    double y1;
    int primed;
} pid_model_t;

static double pid_tol(pid_model_t *m, const pma_pid_config_t *cfg, const golden_pid_row_t *r)
{
    const double T = cfg->period_s, tf = cfg->tf_s;
    const double d_a = tf / (tf + T), d_b = cfg->kd / (tf + T);
    if (!m->primed) {
        m->y1 = r->y_cm;
        m->primed = 1;
    }
    const double e = (double)r->r_cm - r->y_cm, dy = (double)r->y_cm - m->y1;
    const double p = cfg->kp * e;
    const double tol_p = m->rel * fabs(p) + m->h * (1.0 + fabs(e));
    m->d_abs = d_a * m->d_abs + fabs(d_b * dy);
    const double tol_d = d_a * m->tol_d + m->hq30 * m->d_abs + m->rel * m->d_abs +
                         m->h * (2.0 + fabs(dy)) + m->state_rel * m->d_abs;
    const int sat = (r->flags & (PMA_PID_FLAG_SAT_HIGH | PMA_PID_FLAG_SAT_LOW)) != 0;
    const double tol_v = tol_p + m->tol_i + tol_d + m->h;
    const double tol_u = sat ? m->h : tol_v;
    /* integrator update */
    const double kaw_t = cfg->k_aw_per_s * T, ki_t = cfg->ki * T;
    double ti = m->tol_i;
    if (sat) ti = fabs(1.0 - kaw_t) * ti + kaw_t * (tol_p + tol_d);
    /* Q2.30 constants ki T, k_aw T: 2^-31 x |e| and x |u - v| (|u - v| < 2 (u_max - u_min)
     * is a generous bound); the 32-fraction-bit accumulator itself is exact enough */
    ti += m->hq30 * (fabs(e) + 2.0 * fabs((double)cfg->u_max - cfg->u_min)) +
          m->rel * fabs(ki_t * e) + m->state_rel * m->i_abs;
    m->i_abs = fmax(m->i_abs, fabs((double)r->u));
    m->tol_i = ti;
    m->tol_d = tol_d;
    m->y1 = r->y_cm;
    return tol_u;
}

static const char *set_name(uint32_t i) { return GOLDEN_PID_SETS[i].name; }

static void run(const golden_pid_set_t *set, golden_variant_t variant)
{
    const int q16 = variant == GOLDEN_Q16;
    golden_stats_t st;
    golden_stats_init(&st, "pid", set->name, variant, set->n);
    pma_pid_f32_t sf;
    pma_pid_q16_t sq;
    int rc = q16 ? pma_pid_init_q16(&sq, &set->cfg) : pma_pid_init_f32(&sf, &set->cfg);
    TEST_ASSERT_EQUAL_INT(PMA_OK, rc);
    pid_model_t m = {0};
    m.rel = q16 ? Q16_REL : F32_REL;
    m.state_rel = q16 ? 0.0 : F32_STATE_REL;
    m.h = q16 ? Q16_HALF_LSB : 0.0;
    m.hq30 = q16 ? Q30_HALF_LSB : 0.0;
    const double base_rel = q16 ? Q16_BASE_REL : F32_BASE_REL;
    const double base_abs = q16 ? Q16_BASE_ABS : F32_BASE_ABS;
    const double u_extra = q16 ? U_SPAN_FRAC_Q16 * ((double)set->cfg.u_max - set->cfg.u_min)
                               : 0.0;
    for (uint32_t k = 0; k < set->n; k++) {
        const golden_pid_row_t *r = &set->rows[k];
        double u;
        uint32_t flags;
        if (q16) {
            pma_q16_t uq = 0;
            rc = pma_pid_step_q16(&sq, pma_q16_from_f32(r->r_cm), pma_q16_from_f32(r->y_cm),
                                  &uq);
            u = pma_q16_to_f32(uq);
            flags = sq.flags;
        } else {
            float uf = NAN;
            rc = pma_pid_step_f32(&sf, r->r_cm, r->y_cm, &uf);
            u = uf;
            flags = sf.flags;
        }
        golden_check_status(&st, k, q16 ? "pma_pid_step_q16" : "pma_pid_step_f32", rc);
        const double tu = pid_tol(&m, &set->cfg, r);
        golden_check(&st, k, "u", r->u, u,
                     TOL_SAFETY * tu + base_rel * fabs((double)r->u) + base_abs + u_extra, 1);
        golden_check_flags(&st, k, "flags", r->flags, flags);
    }
    golden_finish(&st);
}

static void test_set(void)
{
    const golden_case_t *c = &golden_current;
    run(&GOLDEN_PID_SETS[c->set], c->variant);
}

int main(void)
{
    UNITY_BEGIN();
    golden_run_all(GOLDEN_PID_NSETS, set_name, test_set, __LINE__);
    return UNITY_END();
}
