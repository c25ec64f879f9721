/* SPDX-License-Identifier: Apache-2.0 */
/* Golden-vector test of the reference generators (pma_ref_*): every set of
 * vectors/ref_vectors.h through the float and the Q16.16 variant; x_r and x_r' of every row
 * (STREAM rows first give the row's target, when not NAN, with pma_ref_stream_*).
 *
 * Tolerances (tol = TOL_SAFETY * model + floor):
 *   phase error: the sine-like kinds (SINE, CASE1, CASE3) evaluate sin/cos of a phase that
 *     grows with t. Float: a few ulps of the phase in radians (PHASE_REL_F32 = 4 x 2^-24
 *     relative, + 1e-7 rad) plus sinf/cosf (1e-7). Q16 (phase kept in turns, per ref.h):
 *     PHASE_TURNS_Q16 = 4 LSB of turns (rounding of the products and of the constants'
 *     conversion), + t x 2^-24 turns/s (a Q8.24-or-better turns-per-second rate), plus
 *     pma_q30_sin_2pi_turns (abs error < 1e-5). The phase error moves x_r by
 *     |dx/dphase| (A for SINE, 0.5 for CASE1, t/360 for CASE3) and x_r' by |d x_r'/dphase|.
 *   STREAM: the rate-limited value accumulates one rounding per eval (Q16: half an LSB of
 *     rate x dt), and x_r' = (new - old)/dt divides the value's error by dt.
 *   Floors: float 1e-5 relative + 1e-6; Q16 1e-4 relative + 4 LSB (6.1e-5 cm, cm/s).
 * HOLD and STEP are exact in both variants (tolerance = the floor). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>

#include "pma/status.h"
#include "pma_test.h"
#include "golden.h"
#include "golden_check.h"
#include "vectors/ref_vectors.h"

#define TOL_SAFETY 2.0
#define TWO_PI 6.28318530717958647692

#define PHASE_REL_F32 (4.0 / 16777216.0)
#define PHASE_ABS_F32 1e-7
#define TRIG_ABS_F32 1e-7
#define F32_BASE_REL 1e-5
#define F32_BASE_ABS 1e-6

#define PHASE_TURNS_Q16 (4.0 / 65536.0)
#define PHASE_RATE_Q16 (1.0 / 16777216.0)
#define TRIG_ABS_Q16 1e-5
#define Q16_HALF_LSB (0.5 / 65536.0)
#define Q16_BASE_REL 1e-4
#define Q16_BASE_ABS (4.0 / 65536.0)

/* |phase| [rad], |d x/d phase| and |d x'/d phase| for the sine-like kinds at t */
static void phase_sens(const pma_ref_config_t *c, double t, double *phase, double *sx,
                       double *sxd)
{
    *phase = 0.0;
    *sx = 0.0;
    *sxd = 0.0;
    switch (c->kind) {
    case PMA_REF_SINE:
        *phase = fabs(TWO_PI * c->freq_hz * t) + fabs((double)c->phase_rad);
        *sx = fabs((double)c->amplitude_cm);
        *sxd = fabs((double)c->amplitude_cm) * TWO_PI * c->freq_hz;
        break;
    case PMA_REF_CASE1:
        *phase = t;
        *sx = 0.5;
        *sxd = 0.5;
        break;
    case PMA_REF_CASE3: {
        const double dphi = TWO_PI * (1.0 + 2.0 * t / 55.0) / 55.0;
        *phase = TWO_PI * t * (1.0 + t / 55.0) / 55.0 + TWO_PI / 4.0;
        *sx = t / 360.0;
        *sxd = 1.0 / 360.0 + t * dphi / 360.0;
        break;
    }
    default:
        break;
    }
}

static const char *set_name(uint32_t i) { return GOLDEN_REF_SETS[i].name; }

static void run(const golden_ref_set_t *set, golden_variant_t variant)
{
    const int q16 = variant == GOLDEN_Q16;
    golden_stats_t st;
    golden_stats_init(&st, "ref", set->name, variant, set->n);
    pma_ref_f32_t sf;
    pma_ref_q16_t sq;
    int rc = q16 ? pma_ref_init_q16(&sq, &set->cfg) : pma_ref_init_f32(&sf, &set->cfg);
    TEST_ASSERT_EQUAL_INT(PMA_OK, rc);
    const double base_rel = q16 ? Q16_BASE_REL : F32_BASE_REL;
    const double base_abs = q16 ? Q16_BASE_ABS : F32_BASE_ABS;
    double tol_stream = 0.0;   /* running error of the STREAM value */
    double last_t = 0.0;
    for (uint32_t k = 0; k < set->n; k++) {
        const golden_ref_row_t *r = &set->rows[k];
        if (!isnan(r->stream_cm)) {
            rc = q16 ? pma_ref_stream_q16(&sq, pma_q16_from_f32(r->stream_cm))
                     : pma_ref_stream_f32(&sf, r->stream_cm);
            golden_check_status(&st, k, q16 ? "pma_ref_stream_q16" : "pma_ref_stream_f32", rc);
        }
        double x, xd;
        if (q16) {
            pma_q16_t xq = 0x7fffffff, xdq = 0x7fffffff;
            rc = pma_ref_eval_q16(&sq, pma_q16_from_f32(r->t_s), &xq, &xdq);
            x = pma_q16_to_f32(xq);
            xd = pma_q16_to_f32(xdq);
        } else {
            float xf = NAN, xdf = NAN;
            rc = pma_ref_eval_f32(&sf, r->t_s, &xf, &xdf);
            x = xf;
            xd = xdf;
        }
        golden_check_status(&st, k, q16 ? "pma_ref_eval_q16" : "pma_ref_eval_f32", rc);

        double tx = 0.0, txd = 0.0;
        const double t = r->t_s;
        double phase, sx, sxd;
        phase_sens(&set->cfg, t, &phase, &sx, &sxd);
        if (sx > 0.0) {
            double ph_err, trig;   /* phase error [rad], sin/cos error */
            if (q16) {
                ph_err = TWO_PI * (PHASE_TURNS_Q16 + PHASE_RATE_Q16 * t);
                trig = TRIG_ABS_Q16;
            } else {
                ph_err = PHASE_REL_F32 * phase + PHASE_ABS_F32;
                trig = TRIG_ABS_F32;
            }
            tx = sx * (ph_err + trig);
            txd = sxd * (ph_err + trig);
        }
        if (set->cfg.kind == PMA_REF_STREAM) {
            const double dt = t - last_t > 0.0 ? t - last_t : 0.0;
            const double old_tol = tol_stream;
            if (set->cfg.rate_cm_s > 0.0f && dt > 0.0) {
                /* one rounding of rate dt and of the sum (Q16), or of the float value */
                tol_stream += q16 ? 2.0 * Q16_HALF_LSB
                                  : 1e-7 * (fabs((double)r->xr_cm) + set->cfg.rate_cm_s * dt);
            }
            if (r->xr_dot_cm_s == 0.0f && dt > 0.0) tol_stream = 0.0;  /* at the target */
            tx = tol_stream;
            txd = dt > 0.0 ? (tol_stream + old_tol + (q16 ? Q16_HALF_LSB : 0.0)) / dt : 0.0;
            last_t = t > last_t ? t : last_t;
        }
        golden_check(&st, k, "xr_cm", r->xr_cm, x,
                     TOL_SAFETY * tx + base_rel * fabs((double)r->xr_cm) + base_abs, 1);
        golden_check(&st, k, "xr_dot_cm_s", r->xr_dot_cm_s, xd,
                     TOL_SAFETY * txd + base_rel * fabs((double)r->xr_dot_cm_s) + base_abs, 0);
    }
    golden_finish(&st);
}

static void test_set(void)
{
    const golden_case_t *c = &golden_current;
    run(&GOLDEN_REF_SETS[c->set], c->variant);
}

int main(void)
{
    UNITY_BEGIN();
    golden_run_all(GOLDEN_REF_NSETS, set_name, test_set, __LINE__);
    return UNITY_END();
}
