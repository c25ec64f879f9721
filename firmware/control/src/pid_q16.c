/* SPDX-License-Identifier: Apache-2.0 */
/* PID baseline, fixed-point variant (see pma/pid.h). Signals and kp, kd/(tf+T)
 * in Q16.16; the filter pole tf/(tf+T) in Q2.30; ki T and k_aw T in Q8.24 (so
 * ki T and k_aw T < 128: a stiff integrator on a fast tick, e.g. ki 10,000 per s
 * at 1 kHz, fits); the integrator keeps 32 fractional bits so that the small
 * per-step increments of a slow integrator are not rounded away. */
#include "pma/pid.h"
#include "pma/status.h"

#include <stddef.h>
#include "check.h"
#include "fixed_internal.h"

int pma_pid_init_q16(pma_pid_q16_t *s, const pma_pid_config_t *cfg)
{
    if (s == NULL) return PMA_ERR_NULL;
    s->ready = 0;
    PMA_CHECK(pma_pid_validate_config(cfg));
    const float d_b = cfg->kd / (cfg->tf_s + cfg->period_s);
    const float vals[] = {cfg->kp, d_b, cfg->u_min, cfg->u_max};
    for (unsigned i = 0; i < sizeof vals / sizeof vals[0]; ++i) {
        PMA_CHECK(pma_check_q16_range(vals[i]));
    }
    if (cfg->ki * cfg->period_s >= 128.0f || cfg->k_aw_per_s * cfg->period_s >= 128.0f) {
        return PMA_ERR_FIXED_RANGE;
    }
    s->kp = pma_to_q(cfg->kp, 16);
    s->d_a = pma_to_q(cfg->tf_s / (cfg->tf_s + cfg->period_s), 30);
    s->d_b = pma_to_q(d_b, 16);
    s->ki_t = pma_to_q(cfg->ki * cfg->period_s, 24);
    s->kaw_t = pma_to_q(cfg->k_aw_per_s * cfg->period_s, 24);
    s->u_min = pma_to_q(cfg->u_min, 16);
    s->u_max = pma_to_q(cfg->u_max, 16);
    pma_pid_reset_q16(s);
    s->ready = 1;
    return PMA_OK;
}

void pma_pid_reset_q16(pma_pid_q16_t *s)
{
    if (s == NULL) return;
    s->i_q32 = 0;
    s->d = 0;
    s->y1 = 0;
    s->p = 0;
    s->flags = 0;
    s->primed = 0;
}

int pma_pid_step_q16(pma_pid_q16_t *s, pma_q16_t r_cm, pma_q16_t y_cm, pma_q16_t *u)
{
    if (s == NULL || u == NULL) return PMA_ERR_NULL;
    if (!s->ready) return PMA_ERR_NOT_READY;
    const pma_q16_t e = pma_q16_ssub(r_cm, y_cm);
    const pma_q16_t y1 = s->primed ? s->y1 : y_cm;
    const pma_q16_t p = pma_q16_smul(s->kp, e);
    const pma_q16_t d = pma_q16_ssub(pma_q16_smul_q30(s->d, s->d_a),
                                     pma_q16_smul(s->d_b, pma_q16_ssub(y_cm, y1)));
    const pma_q16_t i = pma_q16_round_sat64(s->i_q32, 16);
    const pma_q16_t v = pma_q16_sadd(pma_q16_sadd(p, i), d);
    uint32_t flags = 0;
    pma_q16_t out = v;
    if (v > s->u_max) {
        out = s->u_max;
        flags |= PMA_PID_FLAG_SAT_HIGH;
    } else if (v < s->u_min) {
        out = s->u_min;
        flags |= PMA_PID_FLAG_SAT_LOW;
    }
    /* I += T (ki e + k_aw (u - v)), Q16 x Q24 = Q40 -> Q32 */
    int64_t iq = s->i_q32 + pma_rshift_round((int64_t)e * s->ki_t, 8) +
                 pma_rshift_round((int64_t)pma_q16_ssub(out, v) * s->kaw_t, 8);
    const int64_t lo = (int64_t)s->u_min * 65536, hi = (int64_t)s->u_max * 65536;
    s->i_q32 = iq < lo ? lo : (iq > hi ? hi : iq);
    s->d = d;
    s->p = p;
    s->y1 = y_cm;
    s->primed = 1;
    s->flags = flags;
    *u = out;
    return PMA_OK;
}
