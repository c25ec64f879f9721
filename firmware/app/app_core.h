/* SPDX-License-Identifier: Apache-2.0 */
/* The application's core as its parts use each other (the state machine
 * app.c, the configuration app_config.c, the input and output app_io.c, the
 * parameter API app_params.c, the frames adapter app_frames.c, the
 * orchestrating step app_step.c); not part of the application's API (app.h).
 * The core (app.c, app_config.c, app_io.c) includes only this header of them: it
 * never calls the frames adapter. */
#ifndef PMA_APP_CORE_H
#define PMA_APP_CORE_H

#include "app.h"
#include "scaling.h"

#include "actuator.h"

/* app.c: the state machine */
pma_param_phase_t pma_app_phase(const pma_app_t *app);
/* ARMED or RUNNING (inline: several times a tick) */
static inline int pma_app_output_active(const pma_app_t *app)
{
    return app->state == PMA_STATE_ARMED || app->state == PMA_STATE_RUNNING;
}
int pma_app_load_params(pma_app_t *app);

/* app_config.c: the configurations the parameters make, and their rules */
void pma_app_adc_scaling(const pma_params_t *p, pma_adc_scaling_t *s);
void pma_app_dac_scaling(const pma_params_t *p, pma_dac_scaling_t *s);
void pma_app_actuator_config(const pma_params_t *p, pma_actuator_config_t *c);
int pma_app_check_param_groups(const pma_params_t *p);
/* The first rule between parameters that p breaks (PMA_RULE_*, app.h), 0 when all
 * hold; set_only: only the rules every SET enforces (the sensor and DAC scalings). */
int pma_app_param_rule(const pma_params_t *p, int set_only);
/* Everything ARM and START check (scalings, actuator, the rules); a rule's refusal
 * is kept in app->last_rule. */
int pma_app_check_cross_params(pma_app_t *app);
int pma_app_apply_timing(pma_app_t *app);

/* app_io.c: the sample in, the command out */
/* The bridge was switched (sys.plant_bridge by SET, LOAD or RESTORE_DEFAULTS,
 * only possible with the output inactive): forget the other source's sample
 * state, so that a sample from before the switch never counts as fresh. The check
 * inline (every tick), the switch out of line. */
void pma_app_bridge_switched(pma_app_t *app, uint8_t on);
static inline void pma_app_sync_bridge(pma_app_t *app)
{
    const uint8_t on = (uint8_t)pma_app_bridge_on(app);
    if (on != app->bridge.active) pma_app_bridge_switched(app, on);
}
void pma_app_acquire(pma_app_t *app);       /* this tick's position into app->sensor */
void pma_app_write_output(pma_app_t *app);  /* app->output.u to the DAC or the bridge */
#if PMA_CTRL_Q16
void pma_app_io_q16_arm(pma_app_t *app);    /* ARM: the fixed-point stages built anew */
#endif

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
