/* SPDX-License-Identifier: Apache-2.0 */
/* The frames adapter (app_frames.c): the application's CAN codec side. It
 * decodes a received frame into a call of the application's API (commands,
 * the parameter API, the plant bridge, set-points) and encodes what the
 * application reports; it depends on the application, never the other way
 * round (pma_app_handle_frame() is in app.h). */
#ifndef PMA_APP_FRAMES_H
#define PMA_APP_FRAMES_H

#include <stdint.h>

#include "app.h"

void pma_app_send_heartbeat(pma_app_t *app);
/* Sends DEVICE_INFO pages 0..4 (app_identity.c): the reply to DEVICE_INFO_REQ and
 * DEVICE_INFO_REQ_ALL. */
void pma_app_send_device_info(pma_app_t *app);
void pma_app_send_telemetry(pma_app_t *app);
int pma_app_send_actuator(pma_app_t *app);
/* Queues one of this node's frames (id = base_id + node id); counts one the HAL refuses. */
int pma_app_send_frame(pma_app_t *app, uint16_t base_id, uint8_t dlc, const uint8_t *data);
/* Sends what the core marked in app->tx_due (actuator, telemetry, heartbeat, in
 * that order) and clears it; inline where nothing is due (most of a tick's calls). */
void pma_app_send_marked(pma_app_t *app);
static inline void pma_app_send_due(pma_app_t *app)
{
    if (app->tx_due != 0u) pma_app_send_marked(app);
}

#endif /* PMA_APP_FRAMES_H */
