/* SPDX-License-Identifier: Apache-2.0 */
/* The application's core: start-up, the state machine and its commands, one
 * control tick (acquire, law, supervisor, output: the acquisition and the
 * output are app_io.c's, the configuration builders and the rules between
 * parameters app_config.c's) and the housekeeping of poll. It sends no frame: what a tick or poll has to send it marks in
 * app->tx_due, and the orchestrating step (app_step.c) has the frames adapter
 * (app_frames.c) send it. See app.h. */
#include "app.h"

#include <stddef.h>
#include <string.h>

#include "actuator.h"
#include "app_core.h"
#include "generated/pma_proto.h"
#include "pma/finite.h"

_Static_assert(PMA_PARAMS_BLOB_BYTES <= PMA_PSTORE_MAX_BLOB_BYTES,
               "the parameter blob must fit a storage record");

const char *pma_app_state_name(int state)
{
    static const char *const names[] = {"BOOT", "IDLE", "ARMED", "RUNNING", "FAULT"};
    if (state < 0 || (size_t)state >= sizeof names / sizeof names[0]) return "UNKNOWN";
    return names[state];
}

pma_param_phase_t pma_app_phase(const pma_app_t *app)
{
    switch (app->state) {
    case PMA_STATE_ARMED: return PMA_PHASE_ARMED;
    case PMA_STATE_RUNNING: return PMA_PHASE_RUNNING;
    default: return PMA_PHASE_INACTIVE;
    }
}

void pma_app_raise_fault(pma_app_t *app, pma_fault_t fault)
{
    if (app == NULL || fault == PMA_FAULT_NONE) return;
    if (app->state != PMA_STATE_FAULT) {
        app->state = PMA_STATE_FAULT;
        app->fault = (uint8_t)fault;
    }
}

/* ---------------------------------------------------------------- start-up -- */

static void load_params(pma_app_t *app)
{
    pma_params_defaults(&app->params);
    app->storage.params_default = 1;
    app->storage.ready = 0;
    if (app->plat.store_blocks_per_slot == 0) return;
    if (pma_pstore_init(&app->storage.pstore, app->plat.store_first_block,
                        app->plat.store_blocks_per_slot) != PMA_OK) {
        return;
    }
    app->storage.ready = 1;
    (void)pma_app_load_params(app);
}

int pma_app_load_params(pma_app_t *app)
{
    if (!app->storage.ready) return PMA_ERR_NOT_IMPLEMENTED;
    /* the record's own limit, not this firmware's blob size: a set saved by a
     * firmware with more parameters loads too (unknown ids are skipped) */
    uint8_t blob[PMA_PSTORE_MAX_BLOB_BYTES];
    pma_pstore_info_t info;
    int rc = pma_pstore_load(&app->storage.pstore, blob, sizeof blob, &info);
    if (rc != PMA_OK) return rc;
    if (info.blob_version != PMA_PARAMS_BLOB_VERSION) return PMA_ERR_NO_RECORD;
    pma_params_t loaded;
    rc = pma_params_deserialize(&loaded, blob, info.len);
    if (rc < 0) return rc;
    rc = pma_app_check_param_groups(&loaded);
    if (rc != PMA_OK) return rc; /* an inconsistent stored set: keep what is in RAM */
    app->params = loaded;
    app->storage.params_default = 0;
    app->storage.params_changed = 0;
    return PMA_OK;
}

int pma_app_core_init(pma_app_t *app, const pma_app_platform_t *plat)
{
    memset(app, 0, sizeof *app);
    app->plat = *plat;
    app->state = PMA_STATE_BOOT;
    app->sensor.status = PMA_ERR_NOT_READY;
    app->sensor.sample_status = PMA_SAMPLE_NONE;
    app->reset_cause = (uint8_t)pma_hal_reset_cause();
    if (plat->watchdog_ms != 0) (void)pma_hal_watchdog_start(plat->watchdog_ms);

    load_params(app);
    app->bridge.active = (uint8_t)pma_app_bridge_on(app);
    app->node_id = (uint8_t)(plat->node_id >= 0 && plat->node_id <= 15 ? plat->node_id
                                                                        : (int)app->params.sys_node_id);
    pma_actuator_config_t ac;
    pma_app_actuator_config(&app->params, &ac);
    app->output.p_kpa = pma_actuator_safe_kpa(&ac, 0.0f);

    /* this node's ids, and the broadcasts: emergency stop and device-info request */
    const pma_can_filter_t filters[3] = {
        {.id = app->node_id, .mask = PMA_NODE_ID_MASK},
        {.id = PMA_PROTO_ESTOP_ALL_FRAME_ID, .mask = PMA_CAN_ID_MAX},
        {.id = PMA_PROTO_DEVICE_INFO_REQ_ALL_FRAME_ID, .mask = PMA_CAN_ID_MAX},
    };
    return pma_hal_can_set_filters(filters, 3u);
}

int pma_app_core_init_finish(pma_app_t *app, int rc)
{
    if (rc == PMA_OK) rc = pma_app_apply_timing(app);
    app->timing.next_heartbeat_us = pma_hal_time_us() + 1000u * (uint64_t)app->params.sys_heartbeat_ms;
    if (rc != PMA_OK) {
        pma_app_raise_fault(app, PMA_FAULT_INIT);
        return rc;
    }
    app->state = PMA_STATE_IDLE;
    if (app->reset_cause == PMA_RESET_WATCHDOG) pma_app_raise_fault(app, PMA_FAULT_WATCHDOG_RESET);
    return PMA_OK;
}

/* ----------------------------------------------------------------- commands -- */

/* u = 0 (and its Q16.16 copy) */
static void zero_output_u(pma_app_t *app)
{
    app->output.u = 0.0f;
#if PMA_CTRL_Q16
    app->output.u_q16 = 0;
    app->output.u_in_q16 = 0;
#endif
}

static uint32_t ms_to_ticks(uint32_t ms, uint32_t tick_hz)
{
    if (ms == 0) return 0;
    uint64_t t = ((uint64_t)ms * tick_hz + 999u) / 1000u;
    return t == 0 ? 1u : (t > UINT32_MAX ? UINT32_MAX : (uint32_t)t);
}

/* The supervisor's limits from the safety.* parameters. Built at ARM and kept while the output
 * is active, the only time the supervisor reads them: the parameters they come from (and
 * sys.tick_hz) are idle-only, so they cannot change meanwhile, and a tick neither recomputes
 * the envelope in software float nor divides in 64 bits on a core without an FPU or divider. */
static void supervisor_limits(const pma_app_t *app, pma_supervisor_limits_t *lim)
{
    const pma_params_t *p = &app->params;
    *lim = (pma_supervisor_limits_t){
        .x_lo_cm = p->safety_x_min_cm - p->safety_x_margin_cm,
        .x_hi_cm = p->safety_x_max_cm + p->safety_x_margin_cm,
        .sensor_timeout_ticks = p->safety_sensor_timeout_ticks,
        .max_late_ticks = p->safety_max_late_ticks,
        .host_timeout_ticks = ms_to_ticks(p->safety_host_timeout_ms, p->sys_tick_hz),
        .barrier_ticks = p->safety_barrier_ticks,
    };
#if PMA_CTRL_Q16
    pma_supervisor_limits_q16(lim);
#endif
}

static int cmd_arm(pma_app_t *app)
{
    switch (app->state) {
    case PMA_STATE_ARMED: return PMA_OK;
    case PMA_STATE_IDLE: break;
    case PMA_STATE_FAULT: return PMA_ERR_FAULT;
    default: return PMA_ERR_STATE;
    }
    int rc = pma_app_check_cross_params(app);
    if (rc != PMA_OK) return rc;
    if (pma_app_bridge_on(app) &&
        app->sensor.ticks_since_sample >= app->params.safety_sensor_timeout_ticks) {
        return PMA_ERR_NOT_READY; /* the last sample is too old: the rig is not sending */
    }
    if (app->sensor.status != PMA_OK) {
        /* never activate the output without a position: no sample yet, or a
         * sensor fault (its code) */
        return app->sensor.status == PMA_ERR_NOT_READY ? PMA_ERR_NOT_READY : app->sensor.status;
    }
    pma_supervisor_limits_t lim;
    supervisor_limits(app, &lim);
    if (!pma_f32_within(pma_app_position_cm(app), lim.x_lo_cm, lim.x_hi_cm)) return PMA_ERR_RANGE;
    app->limits = lim;
#if PMA_CTRL_Q16
    pma_app_io_q16_arm(app);
#endif
    app->state = PMA_STATE_ARMED;
    zero_output_u(app);
    return PMA_OK;
}

static int cmd_start(pma_app_t *app)
{
    if (app->state == PMA_STATE_FAULT) return PMA_ERR_FAULT;
    if (app->state != PMA_STATE_ARMED) return PMA_ERR_STATE;
    int rc = pma_app_check_cross_params(app);
    if (rc == PMA_OK) rc = pma_ctrl_start(&app->ctrl, &app->params, app->timing.period_s);
    if (rc != PMA_OK) return rc;
    app->timing.run_ticks = 0;
#if PMA_CTRL_Q16
    pma_clock_q16_start(&app->timing.clock, app->params.sys_tick_hz);   /* idle-only: fixed while RUNNING */
#endif
    app->timing.ticks_since_host_heartbeat = 0;
    app->telem_count = 0;
    app->state = PMA_STATE_RUNNING;
    return PMA_OK;
}

static int select_param(pma_app_t *app, uint16_t id, uint8_t arg)
{
    pma_param_value_t v;
    v.u32 = arg;
    int rc = pma_param_set(&app->params, id, PMA_PARAM_U32, v, pma_app_phase(app));
    if (rc == PMA_OK) app->storage.params_changed = 1;
    return rc;
}

int pma_app_command(pma_app_t *app, uint8_t command, uint8_t arg)
{
    if (app == NULL) return PMA_ERR_NULL;
    /* a reset is due at the end of this step: nothing may start meanwhile */
    if (app->restart_pending && command != PMA_CMD_ESTOP) return PMA_ERR_STATE;
    switch (command) {
    case PMA_CMD_ARM:
        return cmd_arm(app);
    case PMA_CMD_DISARM:
        if (app->state == PMA_STATE_FAULT) return PMA_ERR_FAULT;
        if (app->state == PMA_STATE_BOOT) return PMA_ERR_STATE;
        app->state = PMA_STATE_IDLE;
        return PMA_OK;
    case PMA_CMD_START:
        return cmd_start(app);
    case PMA_CMD_STOP:
        if (app->state == PMA_STATE_RUNNING) {
            app->state = PMA_STATE_ARMED;
            zero_output_u(app);
            return PMA_OK;
        }
        return app->state == PMA_STATE_ARMED ? PMA_OK
               : app->state == PMA_STATE_FAULT ? PMA_ERR_FAULT : PMA_ERR_STATE;
    case PMA_CMD_ESTOP:
        pma_app_raise_fault(app, PMA_FAULT_ESTOP);
        return PMA_OK;
    case PMA_CMD_CLEAR_FAULTS: {
        if (app->state != PMA_STATE_FAULT) return PMA_OK;
        pma_can_status_t cs;
        if (pma_hal_can_status(&cs) == PMA_OK && cs.state == PMA_CAN_BUS_OFF) return PMA_ERR_BUS_OFF;
        app->state = PMA_STATE_IDLE;
        app->fault = PMA_FAULT_NONE;
        return PMA_OK;
    }
    case PMA_CMD_SELECT_CONTROLLER:
        return select_param(app, PMA_PARAM_CTRL_MODE, arg);
    case PMA_CMD_SELECT_REFERENCE:
        return select_param(app, PMA_PARAM_REF_KIND, arg);
    case PMA_CMD_RESTART:
        /* only with the output safe: a reset must not drop an active output */
        if (pma_app_output_active(app)) return PMA_ERR_STATE;
        app->restart_pending = 1;
        return PMA_OK;
    default:
        return PMA_ERR_UNKNOWN_COMMAND;
    }
}

/* --------------------------------------------------------------------- tick -- */

void pma_app_core_tick(pma_app_t *app, uint32_t late_ticks)
{
    pma_app_sync_bridge(app);
    ++app->timing.ticks;
    app->timing.late_ticks = late_ticks;
    pma_app_acquire(app);

    uint8_t ctrl_error = 0;
    if (app->state == PMA_STATE_RUNNING) {
        if (app->timing.ticks_since_host_heartbeat != UINT32_MAX) ++app->timing.ticks_since_host_heartbeat;
        if (app->sensor.status == PMA_OK) {
            float u = 0.0f;
#if PMA_CTRL_Q16
            /* the output's float only where it is one (OPEN_LOOP), else when read */
            const uint8_t in_q16 = (uint8_t)pma_ctrl_output_in_q16(&app->ctrl);
            ctrl_error = (uint8_t)(pma_ctrl_step_q16(&app->ctrl, app->timing.clock.t_s, app->sensor.x_q16,
                                                     app->params.ctrl_openloop_u, &app->output.u_q16,
                                                     in_q16 ? NULL : &u) != PMA_OK);
            app->output.u_in_q16 = in_q16;
            pma_clock_q16_advance(&app->timing.clock);
#else
            /* the same float either way; the 32-bit conversion is one instruction with an FPU
             * and a short call without, the 64-bit one a long call (49.7 days at 1 kHz) */
            const uint64_t k = app->timing.run_ticks;
            const float ticks = k <= UINT32_MAX ? (float)(uint32_t)k : (float)k;
            const float t_s = ticks * app->timing.period_s;
            ctrl_error = (uint8_t)(pma_ctrl_step(&app->ctrl, t_s, app->sensor.x_cm,
                                                 app->params.ctrl_openloop_u, &u) != PMA_OK);
#endif
            app->output.u = u;
            ++app->timing.run_ticks;
        }
    } else {
        zero_output_u(app);
    }

    pma_can_status_t cs;
    const uint8_t bus_off = (uint8_t)(pma_hal_can_status(&cs) == PMA_OK && cs.state == PMA_CAN_BUS_OFF);
    const pma_params_t *p = &app->params;
    const pma_supervisor_input_t in = {
        .output_active = (uint8_t)pma_app_output_active(app),
        .running = (uint8_t)(app->state == PMA_STATE_RUNNING),
        .bus_off = bus_off,
        .sensor_status = app->sensor.status,
        .x_cm = app->sensor.x_cm,
#if PMA_CTRL_Q16
        .x_in_q16 = app->sensor.x_in_q16,   /* then x_q16 is checked, and x_cm is not read */
        .x_q16 = app->sensor.x_q16,
#endif
        .ticks_since_sample = pma_app_bridge_on(app) ? app->sensor.ticks_since_sample : 0u,
        .late_ticks = late_ticks,
        .ticks_since_host_heartbeat = app->timing.ticks_since_host_heartbeat,
        .controller_error = ctrl_error,
#if PMA_CTRL_Q16
        .u = app->output.u_in_q16 ? 0.0f : app->output.u,   /* a Q16.16 output is finite */
#else
        .u = app->output.u,
#endif
        /* the law's clamp run faults only without a fallback: with MFAC the run hands over in
         * the same tick, and WIDEN keeps the law in charge (docs/controllers.md) */
        .barrier_run = app->ctrl.fallback_mode == PMA_PPC_FALLBACK_NONE ? app->ctrl.barrier_run : 0u,
    };
    const pma_fault_t f = pma_supervisor_check(&app->limits, &in);
    if (f != PMA_FAULT_NONE) pma_app_raise_fault(app, f); /* safe output below, this tick */

    pma_app_write_output(app);

    if (app->state == PMA_STATE_RUNNING && p->telem_decimation != 0) {
        if (++app->telem_count >= p->telem_decimation) {
            app->telem_count = 0;
            app->tx_due |= PMA_APP_TX_TELEMETRY;
        }
    }
}

/* ------------------------------------------------------------------ poll -- */

void pma_app_core_poll(pma_app_t *app)
{
    pma_can_status_t cs;
    if (pma_hal_can_status(&cs) == PMA_OK && cs.state == PMA_CAN_BUS_OFF) {
        /* explicit bus-off handling: latch the fault (the output goes safe at
         * the next tick) and ask the controller to rejoin; CLEAR_FAULTS is
         * refused until it has */
        pma_app_raise_fault(app, PMA_FAULT_CAN_BUS_OFF);
        const uint64_t t = pma_hal_time_us();
        if (t >= app->timing.next_recover_us) { /* at most every PMA_APP_RECOVER_INTERVAL_US */
            (void)pma_hal_can_recover();
            app->timing.next_recover_us = t + PMA_APP_RECOVER_INTERVAL_US;
        }
    }
    const uint64_t now = pma_hal_time_us();
    if (now >= app->timing.next_heartbeat_us) {
        app->tx_due |= PMA_APP_TX_HEARTBEAT;
        const uint64_t period = 1000u * (uint64_t)app->params.sys_heartbeat_ms;
        app->timing.next_heartbeat_us += period;
        if (app->timing.next_heartbeat_us <= now) app->timing.next_heartbeat_us = now + period;
    }
}
