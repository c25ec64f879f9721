/* SPDX-License-Identifier: Apache-2.0 */
/* From the controller output u to the pressure command: pure functions.
 *
 *   active: p = clamp(p0 + polarity * kpa_per_u * u, p_min, p_max), then
 *           limited to slew_kpa_s * period from the previous command
 *   safe:   VENT 0 kPa | HOLD the previous command | FIXED min(safe_kpa, p_max), at once
 *           (no slew limit: a fault must reach the safe state within one tick)
 * Pressures are gauge, in kPa. A non-finite u or previous pressure gives the
 * safe pressure (the supervisor faults on it in the same tick). */
#ifndef PMA_ACTUATOR_H
#define PMA_ACTUATOR_H

#include <stdint.h>

typedef enum pma_safe_mode {
    PMA_SAFE_VENT = 0,
    PMA_SAFE_HOLD = 1,
    PMA_SAFE_FIXED = 2,
} pma_safe_mode_t;

typedef struct pma_actuator_config {
    float p0_kpa, kpa_per_u;
    int32_t polarity;          /* +1 or -1 */
    float p_min_kpa, p_max_kpa;
    float slew_kpa_s;          /* 0: no limit */
    uint32_t safe_mode;        /* pma_safe_mode_t */
    float safe_kpa;
} pma_actuator_config_t;

/* PMA_OK or PMA_ERR_RANGE (polarity not +-1, p_min >= p_max, p0 outside
 * [p_min, p_max], kpa_per_u <= 0, safe_kpa outside [0, p_max] for FIXED);
 * PMA_ERR_NOT_FINITE for NaN or infinity. */
int pma_actuator_validate(const pma_actuator_config_t *cfg);

float pma_actuator_safe_kpa(const pma_actuator_config_t *cfg, float p_prev_kpa);

float pma_actuator_active_kpa(const pma_actuator_config_t *cfg, float u, float p_prev_kpa,
                              float period_s);

#endif /* PMA_ACTUATOR_H */
