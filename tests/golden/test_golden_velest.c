/* SPDX-License-Identifier: Apache-2.0 */
/* Golden-vector test of the velocity estimators (pma_velest_*): every set of
 * vectors/velest_vectors.h through the float and the Q16.16 variant; v of every row.
 *
 * Both estimators are stable linear recursions, so a rounding error made in one step decays
 * but adds up with the others. The tolerance is the worst-case sum: the l1 norm of the error
 * system's impulse response (from an error injected into the position state or the
 * velocity state, to v), computed at the start of each set (velest_gains below), times the
 * largest error injected per step:
 *   filtered difference: v(k) = p v(k-1) + (1-p)/T dx; gain from a v error: 1/(1-p).
 *     Injected per step: the rounding of the two products and of v, (Q16) the conversion
 *     of (1-p)/T (half an LSB x |dx|), relative errors of the constants x |v|.
 *   tracking observer: error dynamics [ex; ev] -> [(1-ga)(ex + T ev); ev - (gb/T)(ex + T ev)]
 *     (two poles at p). Injected per step: into xh the rounding of xp and of xh (float:
 *     half an ulp of |x| each, which the observer differentiates: this dominates the float
 *     error at 1 kHz), into v the rounding of (gb/T) r and of v, (Q16) the conversion of
 *     gb/T (half an LSB x |r|), relative errors x |v|.
 *   tol = TOL_SAFETY * model + BASE_REL |v| + BASE_ABS
 * Floors: float 1e-5 relative + 1e-6 cm/s; Q16 1e-4 relative + 4 LSB (6.1e-5 cm/s).
 * The first sample primes the estimator and must give exactly 0. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>

#include "pma/status.h"
#include "pma_test.h"
#include "golden.h"
#include "golden_check.h"
#include "vectors/velest_vectors.h"

#define TOL_SAFETY 2.0
#define PI 3.14159265358979323846

#define F32_REL 1e-6
#define F32_HALF_ULP (1.0 / 16777216.0)      /* 2^-24: half an ulp, relative */
#define F32_BASE_REL 1e-5
#define F32_BASE_ABS 1e-6

#define Q16_HALF_LSB (0.5 / 65536.0)
#define Q16_REL 1e-6
#define Q16_BASE_REL 1e-4
#define Q16_BASE_ABS (4.0 / 65536.0)

#define GAIN_STEPS 4000u

typedef struct gains {
    double gx, gv;   /* l1 gains to v of a unit error injected into xh / v */
} gains_t;

static gains_t velest_gains(const pma_velest_config_t *cfg)
{
    const double T = cfg->period_s;
    const double p = exp(-2.0 * PI * (double)cfg->fc_hz * T);
    gains_t g = {0.0, 0.0};
    if (cfg->kind == PMA_VELEST_FILTERED_DIFF) {
        g.gv = 1.0 / (1.0 - p);
        return g;
    }
    const double ga = 1.0 - p * p, c2 = (1.0 - p) * (1.0 - p) / T;
    for (int inj = 0; inj < 2; inj++) {
        double ex = inj == 0 ? 1.0 : 0.0, ev = inj == 1 ? 1.0 : 0.0, sum = fabs(ev);
        for (uint32_t k = 0; k < GAIN_STEPS; k++) {
            const double ep = ex + T * ev;      /* error of xp; r gets -ep */
            ex = (1.0 - ga) * ep;
            ev = ev - c2 * ep;
            sum += fabs(ev);
        }
        if (inj == 0) g.gx = sum; else g.gv = sum;
    }
    return g;
}

static const char *set_name(uint32_t i) { return GOLDEN_VELEST_SETS[i].name; }

static void run(const golden_velest_set_t *set, golden_variant_t variant)
{
    const int q16 = variant == GOLDEN_Q16;
    golden_stats_t st;
    golden_stats_init(&st, "velest", set->name, variant, set->n);
    pma_velest_f32_t sf;
    pma_velest_q16_t sq;
    int rc = q16 ? pma_velest_init_q16(&sq, &set->cfg) : pma_velest_init_f32(&sf, &set->cfg);
    TEST_ASSERT_EQUAL_INT(PMA_OK, rc);

    /* largest magnitudes over the set, for the per-step injected errors */
    const double T = set->cfg.period_s;
    const double p = exp(-2.0 * PI * (double)set->cfg.fc_hz * T);
    const int diff = set->cfg.kind == PMA_VELEST_FILTERED_DIFF;
    const double c2 = diff ? (1.0 - p) / T : (1.0 - p) * (1.0 - p) / T;
    double xmax = 0.0, dxmax = 0.0, vmax = 0.0;
    for (uint32_t k = 0; k < set->n; k++) {
        xmax = fmax(xmax, fabs((double)set->rows[k].x_cm));
        vmax = fmax(vmax, fabs((double)set->rows[k].v_cm_s));
        if (k > 0) dxmax = fmax(dxmax, fabs((double)set->rows[k].x_cm - set->rows[k - 1].x_cm));
    }
    /* tracking residual r = x - xh - T v: bounded by the step of x plus the lag */
    const double rmax = dxmax + T * vmax + vmax / (c2 > 0.0 ? c2 : 1.0);
    const gains_t g = velest_gains(&set->cfg);
    double inj_x, inj_v;
    if (q16) {
        const double h = Q16_HALF_LSB;
        inj_x = diff ? 0.0 : 2.0 * h + Q16_REL * (xmax + T * vmax);
        inj_v = diff ? 2.0 * h + h * dxmax + Q16_REL * vmax
                     : 2.0 * h + h * rmax + Q16_REL * vmax;
    } else {
        inj_x = diff ? 0.0 : 2.0 * F32_HALF_ULP * (xmax + T * vmax) + F32_REL * rmax;
        inj_v = 2.0 * F32_HALF_ULP * vmax + F32_REL * (vmax + c2 * (diff ? dxmax : rmax));
    }
    const double model = g.gx * inj_x + g.gv * inj_v;
    const double base_rel = q16 ? Q16_BASE_REL : F32_BASE_REL;
    const double base_abs = q16 ? Q16_BASE_ABS : F32_BASE_ABS;

    for (uint32_t k = 0; k < set->n; k++) {
        const golden_velest_row_t *r = &set->rows[k];
        double v;
        if (q16) {
            pma_q16_t vq = 0x7fffffff;
            rc = pma_velest_step_q16(&sq, pma_q16_from_f32(r->x_cm), &vq);
            v = pma_q16_to_f32(vq);
        } else {
            float vf = NAN;
            rc = pma_velest_step_f32(&sf, r->x_cm, &vf);
            v = vf;
        }
        golden_check_status(&st, k, q16 ? "pma_velest_step_q16" : "pma_velest_step_f32", rc);
        if (k == 0) {
            golden_check(&st, k, "v_cm_s", 0.0, v, 0.0, 1);  /* priming sample: exactly 0 */
        } else {
            golden_check(&st, k, "v_cm_s", r->v_cm_s, v,
                         TOL_SAFETY * model + base_rel * fabs((double)r->v_cm_s) + base_abs, 1);
        }
    }
    golden_finish(&st);
}

static void test_set(void)
{
    const golden_case_t *c = &golden_current;
    run(&GOLDEN_VELEST_SETS[c->set], c->variant);
}

int main(void)
{
    UNITY_BEGIN();
    golden_run_all(GOLDEN_VELEST_NSETS, set_name, test_set, __LINE__);
    return UNITY_END();
}
