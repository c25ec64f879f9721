/* SPDX-License-Identifier: Apache-2.0 */
/* Cost of one control step of every controller, float and fixed point, on
 * the build's core. Under `cmake --build --preset <arm> --target bench` QEMU
 * runs with -icount shift=0, so figures are exact instruction counts; on the
 * host they are wall-clock ns. Prints figures, never asserts.
 *
 * Each figure is (time of N steps - time of the same loop with an empty body)
 * / N, with inputs cycling through a 64-entry table of realistic values
 * (error within +-0.1 cm, velocity within +-0.3 cm/s: the linear region,
 * no saturation), so the input generation is not measured. */
#include <stdint.h>
#include <stdio.h>

#include "pma_board.h"
#include "pma/fixed.h"
#include "pma/mfac.h"
#include "pma/pid.h"
#include "pma/ppc.h"
#include "pma/ref.h"
#include "pma/velest.h"

#define N 4096u
#define TABLE 64u

static float tx[TABLE], tv[TABLE], tr[TABLE];
static pma_q16_t qx[TABLE], qv[TABLE], qr[TABLE];
static volatile float sink_f;
static volatile pma_q16_t sink_q;

static void fill_inputs(void)
{
    uint32_t s = 1u;
    for (unsigned i = 0; i < TABLE; ++i) {
        s = s * 1664525u + 1013904223u;
        const float a = (float)(s >> 8) / 16777216.0f - 0.5f;   /* [-0.5, 0.5) */
        s = s * 1664525u + 1013904223u;
        const float b = (float)(s >> 8) / 16777216.0f - 0.5f;
        tr[i] = -2.0f + 0.5f * a;
        tx[i] = tr[i] + 0.2f * b;
        tv[i] = 0.6f * b;
        qx[i] = pma_q16_from_f32(tx[i]);
        qv[i] = pma_q16_from_f32(tv[i]);
        qr[i] = pma_q16_from_f32(tr[i]);
    }
}

static double per_step(uint32_t total, uint32_t empty)
{
    return ((double)total - (double)empty) / (double)N;
}

static void report(const char *what, double cost)
{
    printf("BENCH %s %s %.1f %s/step\n", pma_board_name(), what, cost, pma_board_time_unit());
}

static uint32_t empty_loop(void)
{
    pma_board_timer_start();
    for (uint32_t k = 0; k < N; ++k) {
        sink_f = tx[k % TABLE] + tv[k % TABLE] + tr[k % TABLE];
    }
    return pma_board_timer_elapsed_ns();
}

static uint32_t empty_loop_q(void)
{
    pma_board_timer_start();
    for (uint32_t k = 0; k < N; ++k) {
        sink_q = qx[k % TABLE] + qv[k % TABLE] + qr[k % TABLE];
    }
    return pma_board_timer_elapsed_ns();
}

static void bench_ppc(uint32_t e_f, uint32_t e_q)
{
    pma_ppc_config_t c;
    pma_ppc_default_config(&c);
    c.t_u_s = 1000.0f;   /* t = 500 < t_u: the tuning function's cos is evaluated every step */
    pma_ppc_f32_t f;
    pma_ppc_q16_t q;
    pma_velest_config_t vc;
    pma_velest_default_config(&vc);
    pma_velest_f32_t vf;
    pma_velest_q16_t vq;
    float u, v;
    pma_q16_t uq, vqv;
    for (int during = 1; during >= 0; --during) {
        if (!during) c.t_u_s = 2.0f;   /* after t_u: alpha = 1, no cos */
        const float t = during ? 500.0f : 10.0f;
        const pma_q16_t tq = pma_q16_from_f32(t);
        if (pma_ppc_init_f32(&f, &c) != 0 || pma_ppc_init_q16(&q, &c) != 0) {
            printf("BENCH setup failed: ppc init\n");
            return;
        }
        pma_board_timer_start();
        for (uint32_t k = 0; k < N; ++k) {
            pma_ppc_step_f32(&f, t, tx[k % TABLE], tv[k % TABLE], tr[k % TABLE], &u);
        }
        report(during ? "ppc_f32(t<t_u)" : "ppc_f32(t>=t_u)", per_step(pma_board_timer_elapsed_ns(), e_f));
        pma_board_timer_start();
        for (uint32_t k = 0; k < N; ++k) {
            pma_ppc_step_q16(&q, tq, qx[k % TABLE], qv[k % TABLE], qr[k % TABLE], &uq);
        }
        report(during ? "ppc_q16(t<t_u)" : "ppc_q16(t>=t_u)", per_step(pma_board_timer_elapsed_ns(), e_q));
        /* with the velocity estimator, as the firmware runs it */
        pma_velest_init_f32(&vf, &vc);
        pma_velest_init_q16(&vq, &vc);
        pma_board_timer_start();
        for (uint32_t k = 0; k < N; ++k) {
            pma_velest_step_f32(&vf, tx[k % TABLE], &v);
            pma_ppc_step_f32(&f, t, tx[k % TABLE], v, tr[k % TABLE], &u);
        }
        report(during ? "ppc_f32+velest(t<t_u)" : "ppc_f32+velest(t>=t_u)",
               per_step(pma_board_timer_elapsed_ns(), e_f));
        pma_board_timer_start();
        for (uint32_t k = 0; k < N; ++k) {
            pma_velest_step_q16(&vq, qx[k % TABLE], &vqv);
            pma_ppc_step_q16(&q, tq, qx[k % TABLE], vqv, qr[k % TABLE], &uq);
        }
        report(during ? "ppc_q16+velest(t<t_u)" : "ppc_q16+velest(t>=t_u)",
               per_step(pma_board_timer_elapsed_ns(), e_q));
    }
    sink_f = u;
    sink_q = uq;
}

static void bench_mfac_pid(uint32_t e_f, uint32_t e_q)
{
    pma_mfac_config_t mc;
    pma_mfac_default_config(&mc);
    pma_mfac_f32_t mf;
    pma_mfac_q16_t mq;
    pma_mfac_init_f32(&mf, &mc);
    pma_mfac_init_q16(&mq, &mc);
    float u;
    pma_q16_t uq;
    pma_board_timer_start();
    for (uint32_t k = 0; k < N; ++k) pma_mfac_step_f32(&mf, tx[k % TABLE], tr[k % TABLE], &u);
    report("mfac_f32", per_step(pma_board_timer_elapsed_ns(), e_f));
    pma_board_timer_start();
    for (uint32_t k = 0; k < N; ++k) pma_mfac_step_q16(&mq, qx[k % TABLE], qr[k % TABLE], &uq);
    report("mfac_q16", per_step(pma_board_timer_elapsed_ns(), e_q));

    pma_pid_config_t pc;
    pma_pid_default_config(&pc);
    pma_pid_f32_t pf;
    pma_pid_q16_t pq;
    pma_pid_init_f32(&pf, &pc);
    pma_pid_init_q16(&pq, &pc);
    pma_board_timer_start();
    for (uint32_t k = 0; k < N; ++k) pma_pid_step_f32(&pf, tr[k % TABLE], tx[k % TABLE], &u);
    report("pid_f32", per_step(pma_board_timer_elapsed_ns(), e_f));
    pma_board_timer_start();
    for (uint32_t k = 0; k < N; ++k) pma_pid_step_q16(&pq, qr[k % TABLE], qx[k % TABLE], &uq);
    report("pid_q16", per_step(pma_board_timer_elapsed_ns(), e_q));
    sink_f = u;
    sink_q = uq;
}

static void bench_velest_ref(uint32_t e_f, uint32_t e_q)
{
    static const char *const names_f[2] = {"velest_f32(diff)", "velest_f32(tracking)"};
    static const char *const names_q[2] = {"velest_q16(diff)", "velest_q16(tracking)"};
    float v = 0.0f;
    pma_q16_t vq = 0;
    for (uint8_t kind = 0; kind < 2; ++kind) {
        pma_velest_config_t vc;
        pma_velest_default_config(&vc);
        vc.kind = kind;
        pma_velest_f32_t f;
        pma_velest_q16_t q;
        pma_velest_init_f32(&f, &vc);
        pma_velest_init_q16(&q, &vc);
        pma_board_timer_start();
        for (uint32_t k = 0; k < N; ++k) pma_velest_step_f32(&f, tx[k % TABLE], &v);
        report(names_f[kind], per_step(pma_board_timer_elapsed_ns(), e_f));
        pma_board_timer_start();
        for (uint32_t k = 0; k < N; ++k) pma_velest_step_q16(&q, qx[k % TABLE], &vq);
        report(names_q[kind], per_step(pma_board_timer_elapsed_ns(), e_q));
    }
    pma_ref_config_t rc = {.kind = PMA_REF_CASE3};
    pma_ref_f32_t rf;
    pma_ref_q16_t rq;
    pma_ref_init_f32(&rf, &rc);
    pma_ref_init_q16(&rq, &rc);
    float x, d;
    pma_q16_t xq, dq;
    pma_board_timer_start();
    for (uint32_t k = 0; k < N; ++k) pma_ref_eval_f32(&rf, 100.0f + tv[k % TABLE], &x, &d);
    report("ref_f32(case3)", per_step(pma_board_timer_elapsed_ns(), e_f));
    pma_board_timer_start();
    for (uint32_t k = 0; k < N; ++k) {
        pma_ref_eval_q16(&rq, 100 * PMA_Q16_ONE + qv[k % TABLE], &xq, &dq);
    }
    report("ref_q16(case3)", per_step(pma_board_timer_elapsed_ns(), e_q));
    sink_f = v + x + d;
    sink_q = (pma_q16_t)(((uint32_t)vq + (uint32_t)xq + (uint32_t)dq) & 0x7FFFFFFFu);
}

static void bench_fixed(uint32_t e_q)
{
    uint32_t acc = 0;   /* checksum keeps the calls alive; unsigned: wraps by definition */
    pma_board_timer_start();
    for (uint32_t k = 0; k < N; ++k) acc += (uint32_t)pma_q16_tan_halfpi(qv[k % TABLE] * 16384);
    report("q16_tan_halfpi", per_step(pma_board_timer_elapsed_ns(), e_q));
    pma_board_timer_start();
    for (uint32_t k = 0; k < N; ++k) acc += (uint32_t)pma_q30_cos_pi(qv[k % TABLE] * 16384);
    report("q30_cos_pi", per_step(pma_board_timer_elapsed_ns(), e_q));
    pma_board_timer_start();
    for (uint32_t k = 0; k < N; ++k) acc += (uint32_t)pma_q16_smul(qx[k % TABLE], qv[k % TABLE]);
    report("q16_smul", per_step(pma_board_timer_elapsed_ns(), e_q));
    pma_board_timer_start();
    for (uint32_t k = 0; k < N; ++k) acc += (uint32_t)pma_q16_sdiv(qv[k % TABLE], qx[k % TABLE]);
    report("q16_sdiv", per_step(pma_board_timer_elapsed_ns(), e_q));
    sink_q = (pma_q16_t)(acc & 0x7FFFFFFFu);
}

int main(void)
{
    fill_inputs();
    const uint32_t e_f = empty_loop(), e_q = empty_loop_q();
    bench_ppc(e_f, e_q);
    bench_mfac_pid(e_f, e_q);
    bench_velest_ref(e_f, e_q);
    bench_fixed(e_q);
    return 0;
}
