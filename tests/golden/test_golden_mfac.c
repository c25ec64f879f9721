/* SPDX-License-Identifier: Apache-2.0 */
/* Golden-vector test of CFDL-MFAC (pma_mfac_*): every set of vectors/mfac_vectors.h through
 * the float and the Q16.16 variant; phi(k), u(k) and the flags of every row.
 *
 * The rows are a recorded sequence (the closed loop ran in Python), so the C code runs it
 * open loop: its own rounding errors are never corrected by feedback. phi is a contracting
 * recursion between resets and u is an integrator between saturations, so their errors
 * accumulate; the tolerance follows them row by row (mfac_tol below, first order, evaluated
 * on the expected values):
 *   phi: after a reset phi = phi(1) (exact up to its conversion); otherwise the error of
 *        phi(k-1), plus the sensitivity of the update to du (errors of u(k-1), u(k-2)),
 *        plus the relative error of the products, plus (Q16) the rounding of each
 *        intermediate: g = eta du / (mu + du^2), phi du, the residual dy - phi du, phi;
 *   u:   after a saturation u is the limit (exact); otherwise the error of u(k-1), plus
 *        |dG/dphi| tol(phi) |y* - y| with G = rho phi / (lambda + phi^2), plus the
 *        relative error of G (products, and in Q16.16 the conversion of lambda: half an
 *        LSB / (lambda + phi^2)), plus the rounding of G (times |y* - y|) and of u.
 *   tol = TOL_SAFETY * model + BASE_REL * |expected| + BASE_ABS (+ for the Q16 u:
 *         U_SPAN_FRAC_Q16 of the input range, the actuator resolution it must meet).
 * Primitive errors: float 1e-6 relative per product (8 ulps) and the rounding of the stored
 * state (half an ulp, 6e-8 relative); Q16.16 half an LSB (2^-17) per rounding, 1e-6
 * relative for the 64-bit products. Floors: float 1e-5 relative + 1e-6, Q16 1e-4 relative +
 * 4 LSB. Flags exact (the generator keeps |du| either 0 or > 1e-4, |phi| before the reset
 * rule > 5e-4 except in the designed rows, and the unclamped u more than 2 input units from
 * the limits). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>

#include "pma/status.h"
#include "pma_test.h"
#include "golden.h"
#include "golden_check.h"
#include "vectors/mfac_vectors.h"

#define TOL_SAFETY 2.0

#define F32_REL 1e-6
#define F32_STATE_REL 6e-8
#define F32_BASE_REL 1e-5
#define F32_BASE_ABS 1e-6

#define Q16_HALF_LSB (0.5 / 65536.0)
#define Q16_REL 1e-6
#define Q16_BASE_REL 1e-4
#define Q16_BASE_ABS (4.0 / 65536.0)
#define U_SPAN_FRAC_Q16 1e-3

typedef struct mfac_model {
    double rel, state_rel, half_lsb;
    double tol_phi, tol_u1, tol_u2;   /* running errors of phi(k-1), u(k-1), u(k-2) */
    double u1, u2, y1;                /* expected u(k-1), u(k-2), y(k-1) */
    double phi;                       /* expected phi(k-1) */
    uint32_t k;
} mfac_model_t;

static void model_init(mfac_model_t *m, const pma_mfac_config_t *cfg, int q16)
{
    m->rel = q16 ? Q16_REL : F32_REL;
    m->state_rel = q16 ? 0.0 : F32_STATE_REL;
    m->half_lsb = q16 ? Q16_HALF_LSB : 0.0;
    m->tol_phi = m->half_lsb;
    m->tol_u1 = m->tol_u2 = m->half_lsb;
    m->u1 = m->u2 = cfg->u_init;
    m->phi = cfg->phi1;
    m->y1 = 0.0;
    m->k = 0;
}

/* Propagated errors of row k's phi and u (before the safety factor and the floor). */
static void mfac_tol(mfac_model_t *m, const pma_mfac_config_t *cfg, const golden_mfac_row_t *r,
                     double *tol_phi, double *tol_u)
{
    const double eta = cfg->eta, mu = cfg->mu, rho = cfg->rho, lam = cfg->lambda;
    const double h = m->half_lsb;
    if (m->k == 0) m->y1 = r->y_cm;
    const double du = m->u1 - m->u2, dy = r->y_cm - m->y1;
    const double tol_du = m->tol_u1 + m->tol_u2;
    double tp;
    if (r->flags & PMA_MFAC_FLAG_RESET) {
        tp = h;
    } else {
        /* phi_c = phi + g (dy - phi du), g = eta du / (mu + du^2) */
        const double den = mu + du * du;
        const double g = eta * du / den;
        const double dg_ddu = eta * (mu - du * du) / (den * den);
        const double resid = dy - m->phi * du;
        tp = fabs(1.0 - g * du) * m->tol_phi                     /* phi(k-1) */
             + (fabs(dg_ddu * resid) + fabs(g * m->phi)) * tol_du /* du */
             + m->rel * (fabs(m->phi) + fabs(g * resid) + fabs(g * m->phi * du))
             + h * (1.0 + fabs(resid) + 2.0 * fabs(g));   /* rounded g, phi du, resid */
    }
    const double phi = r->phi, e = (double)r->yref_next_cm - r->y_cm;
    const double den = lam + phi * phi;
    const double G = rho * phi / den;
    const double dG = rho * (lam - phi * phi) / (den * den);
    double tu;
    if (r->flags & (PMA_MFAC_FLAG_SAT_HIGH | PMA_MFAC_FLAG_SAT_LOW)) {
        tu = h;
    } else {
        tu = m->tol_u1 + fabs(dG * e) * tp + fabs(G * e) * (m->rel + h / den) +
             m->state_rel * fabs((double)r->u) + h * (1.0 + fabs(e));   /* rounded G */
    }
    /* advance */
    m->tol_u2 = m->tol_u1;
    m->tol_u1 = tu;
    m->tol_phi = tp;
    m->u2 = m->u1;
    m->u1 = r->u;
    m->phi = r->phi;
    m->y1 = r->y_cm;
    m->k++;
    *tol_phi = tp;
    *tol_u = tu;
}

static const char *set_name(uint32_t i) { return GOLDEN_MFAC_SETS[i].name; }

static void run(const golden_mfac_set_t *set, golden_variant_t variant)
{
    const int q16 = variant == GOLDEN_Q16;
    golden_stats_t st;
    golden_stats_init(&st, "mfac", set->name, variant, set->n);
    pma_mfac_f32_t sf;
    pma_mfac_q16_t sq;
    int rc = q16 ? pma_mfac_init_q16(&sq, &set->cfg) : pma_mfac_init_f32(&sf, &set->cfg);
    TEST_ASSERT_EQUAL_INT(PMA_OK, rc);
    mfac_model_t m;
    model_init(&m, &set->cfg, q16);
    const double base_rel = q16 ? Q16_BASE_REL : F32_BASE_REL;
    const double base_abs = q16 ? Q16_BASE_ABS : F32_BASE_ABS;
    const double u_extra = q16 ? U_SPAN_FRAC_Q16 * ((double)set->cfg.u_max - set->cfg.u_min)
                               : 0.0;
    for (uint32_t k = 0; k < set->n; k++) {
        const golden_mfac_row_t *r = &set->rows[k];
        double phi, u;
        uint32_t flags;
        if (q16) {
            pma_q16_t uq = 0;
            rc = pma_mfac_step_q16(&sq, pma_q16_from_f32(r->y_cm),
                                   pma_q16_from_f32(r->yref_next_cm), &uq);
            phi = (float)sq.phi_q24 / 16777216.0f;   /* Q8.24 */
            u = pma_q16_to_f32(uq);
            flags = sq.flags;
        } else {
            float uf = NAN;
            rc = pma_mfac_step_f32(&sf, r->y_cm, r->yref_next_cm, &uf);
            phi = sf.phi;
            u = uf;
            flags = sf.flags;
        }
        golden_check_status(&st, k, q16 ? "pma_mfac_step_q16" : "pma_mfac_step_f32", rc);
        double tp, tu;
        mfac_tol(&m, &set->cfg, r, &tp, &tu);
        golden_check(&st, k, "phi", r->phi, phi,
                     TOL_SAFETY * tp + base_rel * fabs((double)r->phi) + base_abs, 0);
        golden_check(&st, k, "u", r->u, u,
                     TOL_SAFETY * tu + base_rel * fabs((double)r->u) + base_abs + u_extra, 1);
        golden_check_flags(&st, k, "flags", r->flags, flags);
    }
    golden_finish(&st);
}

static void test_set(void)
{
    const golden_case_t *c = &golden_current;
    run(&GOLDEN_MFAC_SETS[c->set], c->variant);
}

int main(void)
{
    UNITY_BEGIN();
    golden_run_all(GOLDEN_MFAC_NSETS, set_name, test_set, __LINE__);
    return UNITY_END();
}
