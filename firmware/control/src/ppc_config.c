/* SPDX-License-Identifier: Apache-2.0 */
/* Configuration of the paper's controller: defaults and validation shared by
 * the float and fixed-point variants. */
#include "pma/ppc.h"
#include "pma/status.h"

#include <stddef.h>
#include "check.h"

void pma_ppc_default_config(pma_ppc_config_t *cfg)
{
    if (cfg == NULL) return;
    *cfg = (pma_ppc_config_t){
        .a_cm_s = 2.0f, .c = 2.0f, .w1_cm = 0.2f, .w2_cm_s = 0.5f, .t_u_s = 2.0f,
        .u_min = -400.0f, .u_max = 400.0f,
        .barrier_margin = 1e-3f, .soft_barrier_r = 1.0f,
        .ff_gain_per_s = 0.0f, .ff_init = 0.0f, .ff_hold_speed_cm_s = 0.0f,
        .widen_r = 0.0f, .widen2_steps = 0, .period_s = 1e-3f,
        .band_enabled = 1, .k_low_cm = -3.0f, .k_high_cm = 0.0f,
    };
}

int pma_ppc_validate_config(const pma_ppc_config_t *cfg)
{
    if (cfg == NULL) return PMA_ERR_NULL;
    const float all[] = {cfg->a_cm_s, cfg->c, cfg->w1_cm, cfg->w2_cm_s, cfg->t_u_s,
                         cfg->u_min, cfg->u_max, cfg->barrier_margin, cfg->soft_barrier_r,
                         cfg->ff_gain_per_s, cfg->ff_init, cfg->ff_hold_speed_cm_s, cfg->widen_r,
                         cfg->period_s};
    PMA_CHECK(pma_check_all_finite(all, sizeof all / sizeof all[0]));
    if (cfg->band_enabled) {
        PMA_CHECK(pma_check_finite(cfg->k_low_cm));
        PMA_CHECK(pma_check_finite(cfg->k_high_cm));
    }
    if (!(cfg->a_cm_s > 0.0f && cfg->c > 0.0f && cfg->w1_cm > 0.0f && cfg->w2_cm_s > 0.0f &&
          cfg->t_u_s > 0.0f && cfg->period_s > 0.0f)) {
        return PMA_ERR_RANGE;
    }
    if (!(cfg->u_min < cfg->u_max)) return PMA_ERR_RANGE;
    if (!(cfg->barrier_margin >= 1e-6f && cfg->barrier_margin <= 0.5f)) return PMA_ERR_RANGE;
    if (!(cfg->soft_barrier_r > 0.0f && cfg->soft_barrier_r <= 1.0f)) return PMA_ERR_RANGE;
    if (!(cfg->ff_gain_per_s >= 0.0f && cfg->ff_hold_speed_cm_s >= 0.0f)) return PMA_ERR_RANGE;
    if (!(cfg->widen_r == 0.0f ||
          (cfg->widen_r >= 0.05f && cfg->widen_r < 1.0f - cfg->barrier_margin))) {
        return PMA_ERR_RANGE;
    }
    if (!(cfg->ff_init >= cfg->u_min && cfg->ff_init <= cfg->u_max)) return PMA_ERR_RANGE;
    if (cfg->band_enabled) {
        if (!(cfg->k_low_cm < cfg->k_high_cm)) return PMA_ERR_RANGE;
        /* eq. 14: k_low - x_r < -w1 < w1 < k_high - x_r needs a band wider than 2 w1 */
        if (!(cfg->k_high_cm - cfg->k_low_cm > 2.0f * cfg->w1_cm)) return PMA_ERR_BAND;
    }
    return PMA_OK;
}
