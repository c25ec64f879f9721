/* SPDX-License-Identifier: Apache-2.0 */
/* Shared between app.c and app_frames.c; not part of the application's API. */
#ifndef PMA_APP_INTERNAL_H
#define PMA_APP_INTERNAL_H

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

void pma_app_send_heartbeat(pma_app_t *app);
/* Sends DEVICE_INFO pages 0..4 (app_identity.c): the reply to DEVICE_INFO_REQ and
 * DEVICE_INFO_REQ_ALL. */
void pma_app_send_device_info(pma_app_t *app);
void pma_app_send_telemetry(pma_app_t *app);
int pma_app_send_actuator(pma_app_t *app);
/* Queues one of this node's frames (id = base_id + node id); counts one the HAL refuses. */
int pma_app_send_frame(pma_app_t *app, uint16_t base_id, uint8_t dlc, const uint8_t *data);

#endif /* PMA_APP_INTERNAL_H */
