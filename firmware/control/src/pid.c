/* SPDX-License-Identifier: Apache-2.0 */
/* PID baseline: configuration and float variant (see pma/pid.h). */
#include "pma/pid.h"
#include "pma/status.h"

#include <stddef.h>
#include "check.h"

#include <math.h>

void pma_pid_default_config(pma_pid_config_t *cfg)
{
    if (cfg == NULL) return;
    /* a moderate starting point for a MAS-10 at 1 kHz, u in kPa; tune on the rig */
    *cfg = (pma_pid_config_t){
        .kp = 100.0f, .ki = 400.0f, .kd = 2.0f, .tf_s = 0.01f, .k_aw_per_s = 10.0f,
        .period_s = 1e-3f, .u_min = -400.0f, .u_max = 400.0f,
    };
}

int pma_pid_validate_config(const pma_pid_config_t *cfg)
{
    if (cfg == NULL) return PMA_ERR_NULL;
    const float all[] = {cfg->kp, cfg->ki, cfg->kd, cfg->tf_s, cfg->k_aw_per_s,
                         cfg->period_s, cfg->u_min, cfg->u_max};
    PMA_CHECK(pma_check_all_finite(all, sizeof all / sizeof all[0]));
    if (!(cfg->kp >= 0.0f && cfg->ki >= 0.0f && cfg->kd >= 0.0f)) return PMA_ERR_RANGE;
    if (!(cfg->tf_s >= 0.0f && cfg->k_aw_per_s >= 0.0f)) return PMA_ERR_RANGE;
    if (!(cfg->period_s > 0.0f)) return PMA_ERR_RANGE;
    if (!(cfg->u_min < cfg->u_max)) return PMA_ERR_RANGE;
    return PMA_OK;
}

int pma_pid_init_f32(pma_pid_f32_t *s, const pma_pid_config_t *cfg)
{
    if (s == NULL) return PMA_ERR_NULL;
    s->ready = 0;
    PMA_CHECK(pma_pid_validate_config(cfg));
    s->cfg = *cfg;
    s->d_a = cfg->tf_s / (cfg->tf_s + cfg->period_s);
    s->d_b = cfg->kd / (cfg->tf_s + cfg->period_s);
    pma_pid_reset_f32(s);
    s->ready = 1;
    return PMA_OK;
}

void pma_pid_reset_f32(pma_pid_f32_t *s)
{
    if (s == NULL) return;
    s->i = 0.0f;
    s->d = 0.0f;
    s->y1 = 0.0f;
    s->p = 0.0f;
    s->flags = 0;
    s->primed = 0;
}

int pma_pid_step_f32(pma_pid_f32_t *s, float r_cm, float y_cm, float *u)
{
    if (s == NULL || u == NULL) return PMA_ERR_NULL;
    if (!s->ready) return PMA_ERR_NOT_READY;
    if (!isfinite(r_cm) || !isfinite(y_cm)) return PMA_ERR_NOT_FINITE;
    const pma_pid_config_t *c = &s->cfg;
    const float e = r_cm - y_cm;
    const float y1 = s->primed ? s->y1 : y_cm;
    const float p = c->kp * e;
    const float d = s->d_a * s->d - s->d_b * (y_cm - y1);
    const float v = p + s->i + d;
    if (!isfinite(v)) return PMA_ERR_NOT_FINITE;
    uint32_t flags = 0;
    float out = v;
    if (v > c->u_max) {
        out = c->u_max;
        flags |= PMA_PID_FLAG_SAT_HIGH;
    } else if (v < c->u_min) {
        out = c->u_min;
        flags |= PMA_PID_FLAG_SAT_LOW;
    }
    const float i = s->i + c->period_s * (c->ki * e + c->k_aw_per_s * (out - v));
    s->i = fminf(fmaxf(i, c->u_min), c->u_max);
    s->d = d;
    s->p = p;
    s->y1 = y_cm;
    s->primed = 1;
    s->flags = flags;
    *u = out;
    return PMA_OK;
}
