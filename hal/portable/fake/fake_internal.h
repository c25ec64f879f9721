/* SPDX-License-Identifier: Apache-2.0 */
/* Internal to the fake port: how its device modules reset one another.
 * Each module (fake_*.c) keeps its own device state in static storage. */
#ifndef PMA_FAKE_INTERNAL_H
#define PMA_FAKE_INTERNAL_H

#include "pma_hal_fake.h"

typedef enum pma_fake_reset_depth {
    PMA_FAKE_RESET_INIT = 0,    /* pma_hal_init(): device controllers */
    PMA_FAKE_RESET_RESTART = 1, /* the MCU restarts: + watchdog, NVM power */
    PMA_FAKE_RESET_ALL = 2,     /* pma_fake_reset(): everything, time 0 */
} pma_fake_reset_depth_t;

void pma_fake_adc_dac_reset_(pma_fake_reset_depth_t depth);
void pma_fake_can_reset_(pma_fake_reset_depth_t depth, uint32_t bitrate_bps);
void pma_fake_time_reset_(pma_fake_reset_depth_t depth);
void pma_fake_nvm_reset_(pma_fake_reset_depth_t depth);
/* Reset cause reported after the next restart; the time module latches it. */
void pma_fake_set_reset_cause_(pma_reset_cause_t cause);

#endif /* PMA_FAKE_INTERNAL_H */
