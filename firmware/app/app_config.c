/* SPDX-License-Identifier: Apache-2.0 */
/* The application's configuration: the parameters turned into the scalings' and
 * the actuator's configurations, the rules within and between parameters
 * (docs/parameters.md, "Rules between parameters"), and the timing they set.
 * Pure functions of the parameters, except pma_app_apply_timing (the tick). */
#include <math.h>

#include "actuator.h"
#include "app_core.h"

void pma_app_adc_scaling(const pma_params_t *p, pma_adc_scaling_t *s)
{
    *s = (pma_adc_scaling_t){
        .offset_cm = p->adc_offset_cm, .gain_cm_per_count = p->adc_gain_cm_per_count,
        .raw_min_counts = (uint16_t)p->adc_raw_min_counts,
        .raw_max_counts = (uint16_t)p->adc_raw_max_counts,
        .wire_break_below_counts = (uint16_t)p->adc_wire_break_below_counts,
    };
}

void pma_app_dac_scaling(const pma_params_t *p, pma_dac_scaling_t *s)
{
    *s = (pma_dac_scaling_t){
        .counts_at_zero_kpa = p->dac_counts_at_zero_kpa, .counts_per_kpa = p->dac_counts_per_kpa,
        .min_counts = (uint16_t)p->dac_min_counts, .max_counts = (uint16_t)p->dac_max_counts,
    };
}

void pma_app_actuator_config(const pma_params_t *p, pma_actuator_config_t *c)
{
    *c = (pma_actuator_config_t){
        .p0_kpa = p->act_p0_kpa, .kpa_per_u = p->act_kpa_per_u, .polarity = p->act_polarity,
        .p_min_kpa = p->act_p_min_kpa, .p_max_kpa = p->act_p_max_kpa,
        .slew_kpa_s = p->act_slew_kpa_s, .safe_mode = p->safety_safe_mode,
        .safe_kpa = p->safety_safe_kpa,
    };
}

/* Rules within the groups of parameters that act even while the output is
 * inactive (the sensor and DAC scalings): enforced at every SET, so the
 * safe-state output can always be converted. */
int pma_app_check_param_groups(const pma_params_t *p)
{
    pma_adc_scaling_t as;
    pma_dac_scaling_t ds;
    pma_app_adc_scaling(p, &as);
    pma_app_dac_scaling(p, &ds);
    int rc = pma_adc_validate_scaling(&as);
    return rc != PMA_OK ? rc : pma_dac_validate_scaling(&ds);
}

/* The pressure p(u) = p0 + polarity * kpa_per_u * u at u, and whether it lies in
 * [p_min, p_max] (within float rounding: a set derived as u = p - p0 holds). */
static int pressure_in_range(const pma_params_t *p, float u)
{
    const float k = (float)p->act_polarity * p->act_kpa_per_u;
    const float pu = p->act_p0_kpa + k * u;
    const float tol = 1e-3f + 1e-6f * fabsf(p->act_p_max_kpa);
    return pu >= p->act_p_min_kpa - tol && pu <= p->act_p_max_kpa + tol;
}

int pma_app_param_rule(const pma_params_t *p, int set_only)
{
    /* checked at every SET (the scalings act while the output is inactive too) */
    if (p->adc_gain_cm_per_count == 0.0f) return PMA_RULE_ADC_GAIN;
    if (p->adc_raw_min_counts > p->adc_raw_max_counts) return PMA_RULE_ADC_RAW_ORDER;
    if (p->adc_wire_break_below_counts > p->adc_raw_min_counts) return PMA_RULE_ADC_WIRE_BREAK;
    if (p->dac_counts_per_kpa == 0.0f) return PMA_RULE_DAC_GAIN;
    if (p->dac_min_counts > p->dac_max_counts) return PMA_RULE_DAC_ORDER;
    if (set_only) return PMA_RULE_NONE;
    /* checked at ARM and START */
    if (p->act_polarity != 1 && p->act_polarity != -1) return PMA_RULE_ACT_POLARITY;
    if (!(p->act_p_min_kpa >= 0.0f && p->act_p_min_kpa < p->act_p_max_kpa)) return PMA_RULE_ACT_P_ORDER;
    if (!(p->act_p0_kpa >= p->act_p_min_kpa && p->act_p0_kpa <= p->act_p_max_kpa)) return PMA_RULE_ACT_P0;
    if (p->safety_safe_mode == PMA_SAFE_FIXED && !(p->safety_safe_kpa <= p->act_p_max_kpa)) {
        return PMA_RULE_SAFE_KPA;
    }
    if (!(p->safety_x_min_cm < p->safety_x_max_cm)) return PMA_RULE_X_ORDER;
    if (!(p->ctrl_u_min < p->ctrl_u_max)) return PMA_RULE_U_ORDER;
    if (!pressure_in_range(p, p->ctrl_u_min) || !pressure_in_range(p, p->ctrl_u_max)) {
        return PMA_RULE_U_PRESSURE;
    }
    return PMA_RULE_NONE;
}

/* Rules between parameters, checked at ARM and START (docs/parameters.md). */
int pma_app_check_cross_params(pma_app_t *app)
{
    const pma_params_t *p = &app->params;
    pma_adc_scaling_t as;
    pma_dac_scaling_t ds;
    pma_actuator_config_t ac;
    pma_app_adc_scaling(p, &as);
    pma_app_dac_scaling(p, &ds);
    pma_app_actuator_config(p, &ac);
    int rc = pma_adc_validate_scaling(&as);
    if (rc == PMA_OK) rc = pma_dac_validate_scaling(&ds);
    if (rc == PMA_OK) rc = pma_actuator_validate(&ac);
    if (rc == PMA_OK && !(p->safety_x_min_cm < p->safety_x_max_cm)) rc = PMA_ERR_RANGE;
    if (rc == PMA_OK && !(p->ctrl_u_min < p->ctrl_u_max)) rc = PMA_ERR_RANGE;
    const int rule = pma_app_param_rule(p, 0);
    if (rc == PMA_OK && rule != PMA_RULE_NONE) rc = PMA_ERR_RANGE;
    if (rc == PMA_ERR_RANGE) app->last_rule = (uint8_t)rule;
    return rc;
}

/* Applies the timing parameters: tick period and, if running, the tick. */
int pma_app_apply_timing(pma_app_t *app)
{
    const uint32_t hz = app->params.sys_tick_hz;
    const uint32_t period_us = (1000000u + hz / 2u) / hz;
    app->timing.period_s = 1.0f / (float)hz;
    /* the heartbeat period may have changed too (RESTORE_DEFAULTS, LOAD):
     * the next one no later than one new period from now */
    const uint64_t next_hb = pma_hal_time_us() + 1000u * (uint64_t)app->params.sys_heartbeat_ms;
    if (next_hb < app->timing.next_heartbeat_us) app->timing.next_heartbeat_us = next_hb;
    if (app->timing.tick_started && period_us == app->timing.period_us) return PMA_OK; /* unchanged: keep it */
    app->timing.period_us = period_us;
    int rc = pma_hal_tick_start(app->timing.period_us);
    app->timing.tick_started = (uint8_t)(rc == PMA_OK);
    return rc;
}
