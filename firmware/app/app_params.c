/* SPDX-License-Identifier: Apache-2.0 */
/* The parameter API (app.h): get, set, save, load, restore defaults and the
 * status values by id, with the application's policy. The CAN handler
 * (app_frames.c) only decodes PARAM_REQ into these calls and encodes their
 * result; another transport would call the same functions. */
#include <math.h>
#include <stddef.h>

#include "app_core.h"
#include "pstore.h"

int pma_app_param_get(const pma_app_t *app, uint16_t id, pma_param_type_t *type, pma_param_value_t *value)
{
    if (app == NULL) return PMA_ERR_NULL;
    return pma_param_get(&app->params, id, type, value);
}

int pma_app_param_set(pma_app_t *app, uint16_t id, pma_param_type_t type, pma_param_value_t value)
{
    if (app == NULL) return PMA_ERR_NULL;
    if (pma_param_find(id) == NULL) return PMA_ERR_UNKNOWN_ID; /* the id first, whatever the type */
    if (type > PMA_PARAM_I32) return PMA_ERR_TYPE;
    int rc = pma_param_check(id, type, value, pma_app_phase(app));
    if (rc != PMA_OK) return rc;
    /* the scalings must stay consistent as a group: on a trial copy first */
    pma_params_t trial = app->params;
    (void)pma_param_set(&trial, id, type, value, pma_app_phase(app));
    rc = pma_app_check_param_groups(&trial);
    if (rc == PMA_ERR_RANGE) app->last_rule = (uint8_t)pma_app_param_rule(&trial, 1);
    if (rc != PMA_OK) return rc;
    app->params = trial;
    app->storage.params_changed = 1;
    if (id == PMA_PARAM_SYS_TICK_HZ || id == PMA_PARAM_SYS_HEARTBEAT_MS) {
        return pma_app_apply_timing(app); /* the new periods from now on */
    }
    return PMA_OK;
}

int pma_app_params_save(pma_app_t *app)
{
    if (app == NULL) return PMA_ERR_NULL;
    if (pma_app_phase(app) != PMA_PHASE_INACTIVE) return PMA_ERR_STATE;
    if (!app->storage.ready) return PMA_ERR_NOT_IMPLEMENTED;
    uint8_t blob[PMA_PARAMS_BLOB_BYTES];
    const size_t n = pma_params_serialize(&app->params, blob, sizeof blob);
    const int rc = pma_pstore_save(&app->storage.pstore, blob, n, PMA_PARAMS_BLOB_VERSION);
    app->storage.save_failed = (uint8_t)(rc != PMA_OK);
    if (rc == PMA_OK) app->storage.params_changed = 0;
    return rc;
}

int pma_app_params_restore_defaults(pma_app_t *app)
{
    if (app == NULL) return PMA_ERR_NULL;
    if (pma_app_phase(app) != PMA_PHASE_INACTIVE) return PMA_ERR_STATE;
    pma_params_defaults(&app->params);
    app->storage.params_changed = 1;
    return pma_app_apply_timing(app);
}

int pma_app_params_load(pma_app_t *app)
{
    if (app == NULL) return PMA_ERR_NULL;
    if (pma_app_phase(app) != PMA_PHASE_INACTIVE) return PMA_ERR_STATE;
    const int rc = pma_app_load_params(app);
    if (rc != PMA_OK) return rc;
    return pma_app_apply_timing(app);
}

int pma_app_status_value(const pma_app_t *app, uint16_t id, uint32_t *value)
{
    if (app == NULL || value == NULL) return PMA_ERR_NULL;
    pma_can_status_t cs;
    switch (id) {
    case PMA_STATUS_LAST_RULE: *value = app->last_rule; return PMA_OK;
    case PMA_STATUS_RX_OVERRUNS:
        *value = pma_hal_can_status(&cs) == PMA_OK ? cs.rx_overruns : 0u;
        return PMA_OK;
    case PMA_STATUS_RX_DEFERRED: *value = app->counters.req_deferred; return PMA_OK;
    case PMA_STATUS_RX_DROPPED: *value = app->counters.req_dropped; return PMA_OK;
    case PMA_STATUS_FRAMES_BAD: *value = app->counters.frames_bad; return PMA_OK;
    case PMA_STATUS_TICKS: *value = (uint32_t)app->timing.ticks; return PMA_OK;
    case PMA_STATUS_FRAMES_RX: *value = app->counters.frames_rx; return PMA_OK;
    case PMA_STATUS_GUARANTEE_LOST_TICKS: *value = app->ctrl.lost_ticks; return PMA_OK;
    case PMA_STATUS_GUARANTEE_LOST_AT_MS:
        *value = app->ctrl.lost ? (uint32_t)lroundf(app->ctrl.lost_at_s * 1000.0f) : UINT32_MAX;
        return PMA_OK;
    case PMA_STATUS_BARRIER_BREACHES: *value = app->ctrl.breaches; return PMA_OK;
    default: *value = 0; return PMA_ERR_UNKNOWN_ID;
    }
}
