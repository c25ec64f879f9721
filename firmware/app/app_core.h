/* SPDX-License-Identifier: Apache-2.0 */
/* The application's core as its other parts use it (the parameter API
 * app_params.c, the frames adapter app_frames.c, the orchestrating step
 * app_step.c); not part of the application's API (app.h). The core (app.c)
 * includes only this header of them: it never calls the frames adapter. */
#ifndef PMA_APP_CORE_H
#define PMA_APP_CORE_H

#include "app.h"
#include "scaling.h"

pma_param_phase_t pma_app_phase(const pma_app_t *app);
void pma_app_adc_scaling(const pma_params_t *p, pma_adc_scaling_t *s);
int pma_app_apply_timing(pma_app_t *app);
int pma_app_load_params(pma_app_t *app);
int pma_app_check_param_groups(const pma_params_t *p);
/* The first rule between parameters that p breaks (PMA_RULE_*, app.h), 0 when all
 * hold; set_only: only the rules every SET enforces (the sensor and DAC scalings). */
int pma_app_param_rule(const pma_params_t *p, int set_only);
void pma_app_sync_bridge(pma_app_t *app);

/* pma_app_init() in two parts around the BOOT heartbeat, which the step sends
 * between them: core_init clears *app, loads the parameters and sets the CAN
 * filters (returns their result; the state is BOOT); core_init_finish starts
 * the timing, enters IDLE (FAULT WATCHDOG_RESET after a watchdog reset, FAULT
 * INIT when rc or the timing failed) and returns the first error. */
int pma_app_core_init(pma_app_t *app, const pma_app_platform_t *plat);
int pma_app_core_init_finish(pma_app_t *app, int rc);
/* One control tick and the housekeeping, without sending: what is due is
 * marked in app->tx_due (PMA_APP_TX_*). core_tick needs a state past BOOT. */
void pma_app_core_tick(pma_app_t *app, uint32_t late_ticks);
void pma_app_core_poll(pma_app_t *app);

#endif /* PMA_APP_CORE_H */
