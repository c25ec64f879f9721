/* SPDX-License-Identifier: Apache-2.0 */
/* Golden-vector test of the paper's controller (pma_ppc_*): every set of
 * vectors/ppc_vectors.h through the float and the Q16.16 variant, every output field.
 *
 * Tolerances. The law amplifies small errors of its arguments near the barrier (tan and
 * 1/cos^2 diverge), so one fixed relative tolerance would be either far too loose in the
 * linear regime or fail a correct implementation near the barrier. Each row's tolerance is
 * therefore a first-order propagation of the variant's primitive errors through the
 * equations (ppc_tol() below), evaluated at the expected values, times a safety factor,
 * plus a floor:
 *
 *   tol(field) = TOL_SAFETY * propagated(field) + BASE_REL * |expected| + BASE_ABS
 *
 * Primitive errors (per variant):
 *   float: alpha within 2e-6 (cosf of a rounded argument), 1e-6 relative per product /
 *          quotient (about 8 float ulps: different but legitimate orderings of the same
 *          formula), tan within 4e-6 relative (libm tanf, or a polynomial as accurate as the
 *          fixed-point one), a clamped r within 2.4e-7 (1 - margin rounded to float).
 *          Floor: 1e-5 relative (80 ulps) + 1e-6 absolute.
 *   Q16:   alpha within 1.5e-5 (pma_q30_cos_pi: abs error < 1e-5, halved, plus argument
 *          rounding; exactly 1 from t_u on), half an LSB (2^-17) per rounding to Q16.16,
 *          1e-6 relative for converted constants, tan within 4e-6 relative
 *          (pma_q16_tan_halfpi: g(r^2) within 1.6e-6), a clamped r within 2^-28.
 *          Floor: 1e-4 relative + 4 LSB (6.1e-5) absolute, and for u additionally
 *          U_SPAN_FRAC_Q16 = 0.1 % of (u_max - u_min) (0.8 kPa for [-400, 400]): the
 *          actuator resolution the Q16 variant must meet.
 * The feedforward accumulates the u_law error of every row in which it integrates
 * (ff_gain * period * tol(u_law)).
 * Funnel widening (the "widen" set): a widened channel's r_i = lambda_i g_i / w_i and
 * beta = sec^2 g2 / w2 add the scale's error. A widening sets k_i = widen_r / |lambda_i / w_i|
 * (relative error: raw's, the rounding of 1/w_i g_i to Q8.24 and of g to Q2.30); afterwards
 * g_i = 1 - (1 - k_i)(1 - alpha(t - t_i)) carries k_i's error times (1 - g_i) / (1 - k_i) and
 * alpha's times (1 - k_i). The test keeps each channel's k_i and its error from the rows that
 * widen (flags WIDEN1/2), as it keeps the feedforward's.
 * Values the Q16.16 format cannot hold (beta and u_law beyond the barrier) are expected
 * saturated at +-32768. Flags are compared exactly (the generator keeps every decision at
 * least 4 propagated Q16 errors and 1e-4 relative away from its threshold, except the
 * deliberate exact rows). Rows with t = 0 must give u = u_ff exactly (bumpless start:
 * alpha = 0 makes lambda1 = lambda2 = 0 whatever the initial error). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>

#include "pma/status.h"
#include "pma_test.h"
#include "golden.h"
#include "golden_check.h"
#include "vectors/ppc_vectors.h"

#define HALF_PI 1.57079632679489661923

#define TOL_SAFETY 2.0

/* float variant */
#define F32_ALPHA_ABS 2e-6
#define F32_REL 1e-6
#define F32_TAN_REL 4e-6
#define F32_R_CLAMPED 2.4e-7
#define F32_BASE_REL 1e-5
#define F32_BASE_ABS 1e-6
#define F32_G_ROUND 6e-8         /* a scale near 1 rounded to float */

/* Q16.16 variant */
#define Q16_ALPHA_ABS 1.5e-5
#define Q16_HALF_LSB (0.5 / 65536.0)
#define Q16_REL 1e-6
#define Q16_TAN_REL 4e-6
#define Q16_R_CLAMPED (1.0 / 268435456.0)
#define Q16_BASE_REL 1e-4
#define Q16_BASE_ABS (4.0 / 65536.0)
#define Q16_G_ROUND (1.0 / 2147483648.0)     /* a scale rounded to Q2.30 */
#define Q16_WINV_ROUND (1.0 / 33554432.0)    /* 1/w_i g_i of a widened funnel rounded to Q8.24 */
#define U_SPAN_FRAC_Q16 1e-3

typedef struct prim {
    double alpha_abs, rel, tan_rel, half_lsb, r_clamped, base_rel, base_abs, g_round, winv_round;
} prim_t;

static const prim_t PRIM_F32 = {F32_ALPHA_ABS, F32_REL, F32_TAN_REL, 0.0, F32_R_CLAMPED,
                                F32_BASE_REL, F32_BASE_ABS, F32_G_ROUND, 0.0};
static const prim_t PRIM_Q16 = {Q16_ALPHA_ABS, Q16_REL, Q16_TAN_REL, Q16_HALF_LSB,
                                Q16_R_CLAMPED, Q16_BASE_REL, Q16_BASE_ABS, Q16_G_ROUND,
                                Q16_WINV_ROUND};

/* Propagated (first-order) errors of one row, before the safety factor and the floor; and
 * the relative error of a scale k_i set in the row (a widening). */
typedef struct ppc_tol {
    double alpha, e, l1, chi, theta, l2, delta, beta, u_law, u_ff, u, g[2], rel_k[2];
} ppc_tol_t;

/* Each channel's scale at its last widening and the relative error of the variant's value. */
typedef struct funnels {
    double k[2], rel_k[2];
} funnels_t;

/* abs error of a scale g = 1 - (1 - k)(1 - alpha(t - t_i)) (1: the funnel as assigned) */
static double scale_tol(const prim_t *p, double g, double k, double rel_k)
{
    if (g >= 1.0) return 0.0;
    return (1.0 - g) / (1.0 - k) * k * rel_k + (1.0 - k) * p->alpha_abs + p->g_round;
}

/* Channel i: the error of r_i unclamped from raw = lambda_i / w_i's error; its scale's error
 * (*tol_g) and, where the row widens it, the new k_i's relative error (*rel_new). With the
 * funnel as assigned (g = 1) this is raw's error alone. */
static double channel_tol(const prim_t *p, double tol_raw, double raw, double lam, double g,
                          int widened, double w, const funnels_t *f, int i, double *tol_g,
                          double *rel_new)
{
    *rel_new = 0.0;
    if (widened) {
        *rel_new = tol_raw / fabs(raw) + p->winv_round * w / g + p->g_round / g + p->rel;
        *tol_g = g * *rel_new;
    } else {
        *tol_g = scale_tol(p, g, f->k[i], f->rel_k[i]);
    }
    double tol_r = g * tol_raw;
    if (g < 1.0) tol_r += fabs(raw) * *tol_g + fabs(lam) * p->winv_round + p->rel * fabs(raw * g);
    return tol_r;
}

static void ppc_tol(const prim_t *p, const pma_ppc_config_t *cfg, const golden_ppc_row_t *r,
                    double tol_uff, const funnels_t *f, ppc_tol_t *t)
{
    const double w1 = cfg->w1_cm, w2 = cfg->w2_cm_s;
    double soft_sec2 = 0.0;   /* sec^2 at the soft point: the slope factor beyond it */
    if (cfg->soft_barrier_r < 1.0f) {
        const double soft_tan = tan(HALF_PI * cfg->soft_barrier_r);
        soft_sec2 = 1.0 + soft_tan * soft_tan;
    }
    const double alpha = r->alpha, e = r->e_cm, l1 = r->lambda1_cm, chi = r->chi;
    const double theta = r->theta_cm_s, delta = r->delta, beta = r->beta_s_cm;
    const double v = r->v_cm_s;
    const double h = p->half_lsb;

    /* from t_u on alpha is exactly 1 (no cos evaluated) */
    t->alpha = r->t_s >= cfg->t_u_s ? 0.0 : p->alpha_abs;
    t->e = p->rel * (fabs((double)r->x_cm) + fabs((double)r->xr_cm)) + h;
    /* a result that is exactly 0 (e = 0, t = 0) carries no rounding */
    t->l1 = fabs(e) * t->alpha + alpha * t->e + p->rel * fabs(l1) + (l1 != 0.0 ? h : 0.0);
    const double raw1 = l1 / w1, raw2 = (double)r->lambda2_cm_s / w2;
    const double cr1 = channel_tol(p, t->l1 / w1 + p->rel * fabs(raw1), raw1, l1, r->g1,
                                   (r->flags & PMA_PPC_FLAG_WIDEN1) != 0, w1, f, 0, &t->g[0],
                                   &t->rel_k[0]);
    double tr1 = (r->flags & PMA_PPC_FLAG_BARRIER1) ? p->r_clamped : cr1;
    double sec1 = (r->flags & PMA_PPC_FLAG_SOFT1) ? soft_sec2 : 1.0 + chi * chi;
    t->chi = p->tan_rel * fabs(chi) + HALF_PI * sec1 * tr1 + (chi != 0.0 ? h : 0.0);
    t->theta = cfg->a_cm_s * t->chi + p->rel * fabs(theta) + (theta != 0.0 ? h : 0.0);
    t->l2 = fabs(v) * t->alpha + t->theta + p->rel * (fabs(alpha * v) + fabs(theta)) + h;
    const double cr2 = channel_tol(p, t->l2 / w2 + p->rel * fabs(raw2), raw2, r->lambda2_cm_s,
                                   r->g2, (r->flags & PMA_PPC_FLAG_WIDEN2) != 0, w2, f, 1,
                                   &t->g[1], &t->rel_k[1]);
    double tr2 = (r->flags & PMA_PPC_FLAG_BARRIER2) ? p->r_clamped : cr2;
    int soft2 = (r->flags & PMA_PPC_FLAG_SOFT2) != 0;
    double sec2 = soft2 ? soft_sec2 : 1.0 + delta * delta;
    t->delta = p->tan_rel * fabs(delta) + HALF_PI * sec2 * tr2 + h;
    /* beta = sec^2 g2 / w2: the widened funnel's 1/w2 g2 */
    const double tol_w = t->g[1] / w2 + (r->g2 < 1.0f ? p->winv_round : 0.0);
    if (soft2) {
        t->beta = p->rel * fabs(beta) + sec2 * tol_w + h;
    } else {
        t->beta = 2.0 * fabs(delta) * t->delta * r->g2 / w2 + sec2 * tol_w +
                  (p->rel + 2.0 * p->tan_rel) * fabs(beta) + h;
    }
    t->u_law = cfg->c * (fabs(beta) * t->delta + fabs(delta) * t->beta) +
               p->rel * fabs((double)r->u_law) + 2.0 * h;
    t->u_ff = tol_uff;
    if (r->flags & (PMA_PPC_FLAG_SAT_HIGH | PMA_PPC_FLAG_SAT_LOW)) {
        t->u = h;    /* at a limit: the limit itself */
    } else {
        t->u = tol_uff + t->u_law + p->rel * (fabs((double)r->u_ff) + fabs((double)r->u_law)) + h;
    }
}

/* Did the feedforward integrate in this row (expected flags and sign of u_law)? */
static int ff_integrates(const pma_ppc_config_t *cfg, const golden_ppc_row_t *r)
{
    if (!(cfg->ff_gain_per_s > 0.0f)) return 0;
    if (r->flags & PMA_PPC_FLAG_FF_HOLD) return 0;
    if ((r->flags & PMA_PPC_FLAG_SAT_HIGH) && r->u_law > 0.0f) return 0;
    if ((r->flags & PMA_PPC_FLAG_SAT_LOW) && r->u_law < 0.0f) return 0;
    return 1;
}

static const char *set_name(uint32_t i) { return GOLDEN_PPC_SETS[i].name; }

/* A row that widens a channel sets its k_i (the expected scale) and k_i's error. */
static void note_widenings(const golden_ppc_row_t *r, const ppc_tol_t *t, funnels_t *f)
{
    if (r->flags & PMA_PPC_FLAG_WIDEN1) {
        f->k[0] = r->g1;
        f->rel_k[0] = t->rel_k[0];
    }
    if (r->flags & PMA_PPC_FLAG_WIDEN2) {
        f->k[1] = r->g2;
        f->rel_k[1] = t->rel_k[1];
    }
}

static void compare_row(golden_stats_t *st, const prim_t *p, uint32_t k,
                        const golden_ppc_row_t *r, const ppc_tol_t *t, const double got[14],
                        double u_extra, int q16)
{
    /* expected in field order: alpha e l1 chi theta l2 delta beta u_law u_ff u */
    static const char *const names[11] = {"alpha", "e_cm", "lambda1_cm", "chi", "theta_cm_s",
                                          "lambda2_cm_s", "delta", "beta_s_cm", "u_law", "u_ff",
                                          "u"};
    const double exp_[11] = {r->alpha, r->e_cm, r->lambda1_cm, r->chi, r->theta_cm_s,
                             r->lambda2_cm_s, r->delta, r->beta_s_cm, r->u_law, r->u_ff, r->u};
    const double prop[11] = {t->alpha, t->e, t->l1, t->chi, t->theta, t->l2,
                             t->delta, t->beta, t->u_law, t->u_ff, t->u};
    for (int i = 0; i < 11; i++) {
        double e = q16 ? golden_q16_sat(exp_[i]) : exp_[i];
        double tol = TOL_SAFETY * prop[i] + p->base_rel * fabs(e) + p->base_abs;
        if (i == 10) tol += u_extra;
        golden_check(st, k, names[i], e, got[i], tol, i == 10);
    }
    /* the funnels' scales: got[12], got[13] */
    const double g_exp[2] = {r->g1, r->g2};
    static const char *const g_names[2] = {"g1", "g2"};
    for (int i = 0; i < 2; i++) {
        const double tol = TOL_SAFETY * t->g[i] + p->base_rel * g_exp[i] + p->base_abs;
        golden_check(st, k, g_names[i], g_exp[i], got[12 + i], tol, 0);
    }
    /* bumpless start: exactly u = u_ff at t = 0 (no u_ext there) */
    if (r->t_s == 0.0f && r->u_ext == 0.0f && got[10] != got[9]) {
        char buf[96];
        snprintf(buf, sizeof buf, "t = 0: u %.9g must equal u_ff %.9g exactly", got[10], got[9]);
        golden_fail_msg(st, k, "u", buf);
    }
    /* the value written to *u is the one reported in out.u */
    if (got[11] != got[10]) golden_fail_msg(st, k, "u", "*u differs from out.u");
}

static void run_f32(const golden_ppc_set_t *set)
{
    golden_stats_t st;
    golden_stats_init(&st, "ppc", set->name, GOLDEN_F32, set->n);
    pma_ppc_f32_t s;
    int rc = pma_ppc_init_f32(&s, &set->cfg);
    TEST_ASSERT_EQUAL_INT(PMA_OK, rc);
    const double ff_k = (double)set->cfg.ff_gain_per_s * set->cfg.period_s;
    double tol_uff = F32_REL * fabs((double)set->cfg.ff_init);
    funnels_t fun = {{1.0, 1.0}, {0.0, 0.0}};
    for (uint32_t k = 0; k < set->n; k++) {
        const golden_ppc_row_t *r = &set->rows[k];
        float u = NAN;
        rc = pma_ppc_step_ext_f32(&s, r->t_s, r->x_cm, r->v_cm_s, r->xr_cm, r->u_ext, &u);
        golden_check_status(&st, k, "pma_ppc_step_ext_f32", rc);
        ppc_tol_t t;
        ppc_tol(&PRIM_F32, &set->cfg, r, tol_uff, &fun, &t);
        const pma_ppc_out_f32_t *o = &s.out;
        const double got[14] = {o->alpha, o->e_cm, o->lambda1_cm, o->chi, o->theta_cm_s,
                                o->lambda2_cm_s, o->delta, o->beta_s_cm, o->u_law, o->u_ff,
                                o->u, u, o->g1, o->g2};
        compare_row(&st, &PRIM_F32, k, r, &t, got, 0.0, 0);
        golden_check_flags(&st, k, "flags", r->flags, o->flags);
        if (ff_integrates(&set->cfg, r)) tol_uff += ff_k * t.u_law + F32_REL * fabs((double)r->u_ff);
        note_widenings(r, &t, &fun);
    }
    golden_finish(&st);
}

static void run_q16(const golden_ppc_set_t *set)
{
    golden_stats_t st;
    golden_stats_init(&st, "ppc", set->name, GOLDEN_Q16, set->n);
    pma_ppc_q16_t s;
    int rc = pma_ppc_init_q16(&s, &set->cfg);
    const double ff_k = (double)set->cfg.ff_gain_per_s * set->cfg.period_s;
    if (rc == PMA_ERR_FIXED_RANGE && ff_k >= 1.0) {
        /* "converted and range-checked at init": a per-step feedforward gain >= 1 may be
         * refused by the fixed-point variant (the u_ff clamp is unreachable below 1). */
        printf("GOLDEN-SKIP ppc %s q16: init refused ff_gain_per_s * period_s = %g "
               "(PMA_ERR_FIXED_RANGE)\n", set->name, ff_k);
        return;
    }
    TEST_ASSERT_EQUAL_INT(PMA_OK, rc);
    const double u_extra = U_SPAN_FRAC_Q16 * ((double)set->cfg.u_max - set->cfg.u_min);
    double tol_uff = Q16_HALF_LSB;
    funnels_t fun = {{1.0, 1.0}, {0.0, 0.0}};
    for (uint32_t k = 0; k < set->n; k++) {
        const golden_ppc_row_t *r = &set->rows[k];
        pma_q16_t u = 0x7fffffff;
        rc = pma_ppc_step_ext_q16(&s, pma_q16_from_f32(r->t_s), pma_q16_from_f32(r->x_cm),
                                  pma_q16_from_f32(r->v_cm_s), pma_q16_from_f32(r->xr_cm),
                                  pma_q16_from_f32(r->u_ext), &u);
        golden_check_status(&st, k, "pma_ppc_step_ext_q16", rc);
        ppc_tol_t t;
        ppc_tol(&PRIM_Q16, &set->cfg, r, tol_uff, &fun, &t);
        const pma_ppc_out_q16_t *o = &s.out;
        const double got[14] = {pma_q30_to_f32(o->alpha), pma_q16_to_f32(o->e_cm),
                                pma_q16_to_f32(o->lambda1_cm), pma_q16_to_f32(o->chi),
                                pma_q16_to_f32(o->theta_cm_s), pma_q16_to_f32(o->lambda2_cm_s),
                                pma_q16_to_f32(o->delta), pma_q16_to_f32(o->beta_s_cm),
                                pma_q16_to_f32(o->u_law), pma_q16_to_f32(o->u_ff),
                                pma_q16_to_f32(o->u), pma_q16_to_f32(u),
                                pma_q30_to_f32(o->g1), pma_q30_to_f32(o->g2)};
        compare_row(&st, &PRIM_Q16, k, r, &t, got, u_extra, 1);
        golden_check_flags(&st, k, "flags", r->flags, o->flags);
        if (ff_integrates(&set->cfg, r)) tol_uff += ff_k * t.u_law + Q16_HALF_LSB;
        note_widenings(r, &t, &fun);
    }
    golden_finish(&st);
}

static void test_set(void)
{
    const golden_case_t *c = &golden_current;
    const golden_ppc_set_t *set = &GOLDEN_PPC_SETS[c->set];
    if (c->variant == GOLDEN_F32) {
        run_f32(set);
    } else {
        run_q16(set);
    }
}

int main(void)
{
    UNITY_BEGIN();
    golden_run_all(GOLDEN_PPC_NSETS, set_name, test_set, __LINE__);
    return UNITY_END();
}
