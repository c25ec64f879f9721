/* SPDX-License-Identifier: Apache-2.0 */
/* Accuracy of the float and fixed-point controllers against the independent
 * double-precision reference: the golden vectors (tests/golden/vectors) run
 * through each variant; max and RMS |u - u_ref| in % of the input range
 * (u_max - u_min) per controller, over all sets. Printed, never asserted
 * (the pass criteria live in tests/golden/test_golden_*.c). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>

#include "golden.h"
#include "pma_board.h"
#include "vectors/mfac_vectors.h"
#include "vectors/pid_vectors.h"
#include "vectors/ppc_vectors.h"

typedef struct acc {
    double max_pct, sum_sq_pct;
    uint32_t n;
} acc_t;

static void add(acc_t *a, double u, double u_ref, double range)
{
    const double pct = 100.0 * fabs(u - u_ref) / range;
    if (pct > a->max_pct) a->max_pct = pct;
    a->sum_sq_pct += pct * pct;
    a->n++;
}

static void print(const char *what, const acc_t *a)
{
    printf("ACCURACY %s %s rows=%lu max=%.5f%% rms=%.5f%% of the input range\n", pma_board_name(),
           what, (unsigned long)a->n, a->max_pct, a->n ? sqrt(a->sum_sq_pct / a->n) : 0.0);
}

static void ppc(void)
{
    acc_t f = {0}, q = {0};
    for (uint32_t s = 0; s < GOLDEN_PPC_NSETS; ++s) {
        const golden_ppc_set_t *set = &GOLDEN_PPC_SETS[s];
        const double range = (double)set->cfg.u_max - (double)set->cfg.u_min;
        static pma_ppc_f32_t pf;
        static pma_ppc_q16_t pq;
        if (pma_ppc_init_f32(&pf, &set->cfg) != 0 || pma_ppc_init_q16(&pq, &set->cfg) != 0) continue;
        for (uint32_t k = 0; k < set->n; ++k) {
            const golden_ppc_row_t *r = &set->rows[k];
            float u;
            pma_q16_t uq;
            pma_ppc_step_ext_f32(&pf, r->t_s, r->x_cm, r->v_cm_s, r->xr_cm, r->u_ext, &u);
            pma_ppc_step_ext_q16(&pq, pma_q16_from_f32(r->t_s), pma_q16_from_f32(r->x_cm),
                                 pma_q16_from_f32(r->v_cm_s), pma_q16_from_f32(r->xr_cm),
                                 pma_q16_from_f32(r->u_ext), &uq);
            add(&f, u, r->u, range);
            add(&q, pma_q16_to_f32(uq), r->u, range);
        }
    }
    print("ppc_f32", &f);
    print("ppc_q16", &q);
}

static void mfac(void)
{
    acc_t f = {0}, q = {0};
    for (uint32_t s = 0; s < GOLDEN_MFAC_NSETS; ++s) {
        const golden_mfac_set_t *set = &GOLDEN_MFAC_SETS[s];
        const double range = (double)set->cfg.u_max - (double)set->cfg.u_min;
        pma_mfac_f32_t mf;
        pma_mfac_q16_t mq;
        if (pma_mfac_init_f32(&mf, &set->cfg) != 0 || pma_mfac_init_q16(&mq, &set->cfg) != 0) continue;
        for (uint32_t k = 0; k < set->n; ++k) {
            const golden_mfac_row_t *r = &set->rows[k];
            float u;
            pma_q16_t uq;
            pma_mfac_step_f32(&mf, r->y_cm, r->yref_next_cm, &u);
            pma_mfac_step_q16(&mq, pma_q16_from_f32(r->y_cm), pma_q16_from_f32(r->yref_next_cm), &uq);
            add(&f, u, r->u, range);
            add(&q, pma_q16_to_f32(uq), r->u, range);
        }
    }
    print("mfac_f32", &f);
    print("mfac_q16", &q);
}

static void pid(void)
{
    acc_t f = {0}, q = {0};
    for (uint32_t s = 0; s < GOLDEN_PID_NSETS; ++s) {
        const golden_pid_set_t *set = &GOLDEN_PID_SETS[s];
        const double range = (double)set->cfg.u_max - (double)set->cfg.u_min;
        pma_pid_f32_t pf;
        pma_pid_q16_t pq;
        if (pma_pid_init_f32(&pf, &set->cfg) != 0 || pma_pid_init_q16(&pq, &set->cfg) != 0) continue;
        for (uint32_t k = 0; k < set->n; ++k) {
            const golden_pid_row_t *r = &set->rows[k];
            float u;
            pma_q16_t uq;
            pma_pid_step_f32(&pf, r->r_cm, r->y_cm, &u);
            pma_pid_step_q16(&pq, pma_q16_from_f32(r->r_cm), pma_q16_from_f32(r->y_cm), &uq);
            add(&f, u, r->u, range);
            add(&q, pma_q16_to_f32(uq), r->u, range);
        }
    }
    print("pid_f32", &f);
    print("pid_q16", &q);
}

int main(void)
{
    ppc();
    mfac();
    pid();
    return 0;
}
