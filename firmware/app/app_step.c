/* SPDX-License-Identifier: Apache-2.0 */
/* The orchestrating step: the application's public entry points (app.h) as
 * the core (app.c) and the frames adapter (app_frames.c) make them together.
 * Start-up sends the BOOT heartbeat between the core's two parts; a tick and
 * a poll run the core, then send what it marked due; one main-loop iteration
 * takes the received frames (control frames at once, requests queued and
 * answered in order, a bounded number per iteration), runs the tick and the
 * poll, kicks the watchdog and, after an accepted RESTART, resets. */
#include <stddef.h>

#include "app_core.h"
#include "app_frames.h"
#include "generated/pma_proto.h"

int pma_app_init(pma_app_t *app, const pma_app_platform_t *plat)
{
    if (app == NULL || plat == NULL) return PMA_ERR_NULL;
    const int rc = pma_app_core_init(app, plat);
    pma_app_send_heartbeat(app); /* the BOOT heartbeat: "I have (re)started" */
    return pma_app_core_init_finish(app, rc);
}

void pma_app_tick(pma_app_t *app, uint32_t late_ticks)
{
    if (app == NULL || app->state == PMA_STATE_BOOT) return;
    pma_app_core_tick(app, late_ticks);
    pma_app_send_due(app);
}

void pma_app_poll(pma_app_t *app)
{
    if (app == NULL) return;
    pma_app_core_poll(app);
    pma_app_send_due(app);
}

/* A request to this node: a frame that is answered (COMMAND, PARAM_REQ). */
static int is_request(const pma_app_t *app, const pma_can_frame_t *f)
{
    const uint16_t base = (uint16_t)(f->id & PMA_BASE_ID_MASK);
    return f->id <= PMA_CAN_ID_MAX && (f->id & PMA_NODE_ID_MASK) == app->node_id &&
           (base == PMA_PROTO_COMMAND_FRAME_ID || base == PMA_PROTO_PARAM_REQ_FRAME_ID) &&
           f->id != PMA_PROTO_ESTOP_ALL_FRAME_ID;
}

/* The request queue is full and f arrives: a COMMAND (START, STOP, DISARM ...)
 * takes the place of the newest queued PARAM_REQ, which is dropped; the order of
 * the others is kept. Returns 0 when f is to be dropped instead. */
static int evict_param_req(pma_app_t *app, const pma_can_frame_t *f)
{
    if ((f->id & PMA_BASE_ID_MASK) != PMA_PROTO_COMMAND_FRAME_ID) return 0;
    for (unsigned k = app->requests.count; k-- > 0;) {
        const unsigned at = (app->requests.head + k) % PMA_APP_PARAM_REQ_QUEUE;
        if ((app->requests.q[at].id & PMA_BASE_ID_MASK) != PMA_PROTO_PARAM_REQ_FRAME_ID) continue;
        for (unsigned j = k; j + 1u < app->requests.count; ++j) {
            app->requests.q[(app->requests.head + j) % PMA_APP_PARAM_REQ_QUEUE] =
                app->requests.q[(app->requests.head + j + 1u) % PMA_APP_PARAM_REQ_QUEUE];
        }
        --app->requests.count;
        ++app->counters.frames_rx;
        ++app->counters.req_dropped;
        return 1;
    }
    return 0;
}

int pma_app_step(pma_app_t *app)
{
    if (app == NULL) return PMA_ERR_NULL;
    uint32_t late = 0;
    const int rc = pma_hal_tick_wait(&late);
    pma_can_frame_t f;
    const uint16_t sample_id = (uint16_t)(PMA_PROTO_PLANT_SENSOR_FRAME_ID | app->node_id);
    unsigned fresh = 0; /* requests queued in this iteration */
    /* lockstep: the port reported a tick, i.e. the sample is in its RX queue: read up to
     * it whatever the bound (the queue is finite), so that the tick has its sample */
    const int need_sample = app->plat.lockstep && rc == PMA_OK;
    for (unsigned i = 0; (i < PMA_APP_RX_PER_STEP || need_sample) && pma_hal_can_recv(&f) == PMA_OK; ++i) {
        if (is_request(app, &f)) {
            /* answered later in this iteration, in order, at most
             * PMA_APP_PARAM_REQ_PER_STEP of them: a flood of requests never
             * delays the tick or the frames that feed it */
            if (app->requests.count == PMA_APP_PARAM_REQ_QUEUE && !evict_param_req(app, &f)) {
                ++app->counters.frames_rx;
                ++app->counters.req_dropped; /* dropped unanswered */
                continue;
            }
            app->requests.q[(app->requests.head + app->requests.count) % PMA_APP_PARAM_REQ_QUEUE] = f;
            ++app->requests.count;
            ++fresh;
            continue;
        }
        pma_app_handle_frame(app, &f);
        /* lockstep: each sample is its own tick; later frames (perhaps the
         * next sample) wait for the next iteration, which the port grants */
        if (app->plat.lockstep && f.id == sample_id && f.dlc == PMA_PROTO_PLANT_SENSOR_LENGTH) break;
    }
    for (unsigned n = 0; n < PMA_APP_PARAM_REQ_PER_STEP && app->requests.count > 0; ++n) {
        const pma_can_frame_t req = app->requests.q[app->requests.head];
        app->requests.head = (uint8_t)((app->requests.head + 1u) % PMA_APP_PARAM_REQ_QUEUE);
        --app->requests.count;
        pma_app_handle_frame(app, &req);
    }
    app->counters.req_deferred += fresh < app->requests.count ? fresh : app->requests.count;
    if (rc == PMA_OK) pma_app_tick(app, late);
    pma_app_poll(app);
    pma_hal_watchdog_kick();
    if (app->restart_pending) {
        /* RESTART: its COMMAND_ACK is queued; the port sends it, then resets */
        app->restart_pending = 0;
        pma_hal_system_reset();
    }
    return rc == PMA_ERR_EMPTY ? PMA_OK : rc;
}
