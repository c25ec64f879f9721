/* SPDX-License-Identifier: Apache-2.0 */
/* The application's core: start-up, the state machine and its commands, one
 * control tick (acquire, law, supervisor, output) and the housekeeping of
 * poll. It sends no frame: what a tick or poll has to send it marks in
 * app->tx_due, and the orchestrating step (app_step.c) has the frames adapter
 * (app_frames.c) send it. See app.h. */
#include "app.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

#include "actuator.h"
#include "app_core.h"
#include "generated/pma_proto.h"

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

int pma_app_bridge_on(const pma_app_t *app)
{
    return app->plat.plant_bridge != 0 || app->params.sys_plant_bridge != 0;
}

/* The bridge was switched (sys.plant_bridge by SET, LOAD or RESTORE_DEFAULTS,
 * only possible with the output inactive): forget the other source's sample
 * state, so that a sample from before the switch never counts as fresh. */
void pma_app_sync_bridge(pma_app_t *app)
{
    const uint8_t on = (uint8_t)pma_app_bridge_on(app);
    if (on == app->bridge.active) return;
    app->bridge.active = on;
    app->bridge.have = app->bridge.fresh = app->bridge.gap = 0;
    app->sensor.ticks_since_sample = 0;
    app->sensor.sample_status = PMA_SAMPLE_NONE;
    app->sensor.status = PMA_ERR_NOT_READY;
}

static int output_active(const pma_app_t *app)
{
    return app->state == PMA_STATE_ARMED || app->state == PMA_STATE_RUNNING;
}

void pma_app_raise_fault(pma_app_t *app, pma_fault_t fault)
{
    if (app == NULL || fault == PMA_FAULT_NONE) return;
    if (app->state != PMA_STATE_FAULT) {
        app->state = PMA_STATE_FAULT;
        app->fault = (uint8_t)fault;
    }
}

/* --------------------------------------------------------- configuration -- */

void pma_app_adc_scaling(const pma_params_t *p, pma_adc_scaling_t *s)
{
    *s = (pma_adc_scaling_t){
        .offset_cm = p->adc_offset_cm, .gain_cm_per_count = p->adc_gain_cm_per_count,
        .raw_min_counts = (uint16_t)p->adc_raw_min_counts,
        .raw_max_counts = (uint16_t)p->adc_raw_max_counts,
        .wire_break_below_counts = (uint16_t)p->adc_wire_break_below_counts,
    };
}

static void dac_scaling(const pma_params_t *p, pma_dac_scaling_t *s)
{
    *s = (pma_dac_scaling_t){
        .counts_at_zero_kpa = p->dac_counts_at_zero_kpa, .counts_per_kpa = p->dac_counts_per_kpa,
        .min_counts = (uint16_t)p->dac_min_counts, .max_counts = (uint16_t)p->dac_max_counts,
    };
}

static void actuator_config(const pma_params_t *p, pma_actuator_config_t *c)
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
    dac_scaling(p, &ds);
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
static int check_cross_params(pma_app_t *app)
{
    const pma_params_t *p = &app->params;
    pma_adc_scaling_t as;
    pma_dac_scaling_t ds;
    pma_actuator_config_t ac;
    pma_app_adc_scaling(p, &as);
    dac_scaling(p, &ds);
    actuator_config(p, &ac);
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
    actuator_config(&app->params, &ac);
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

static int cmd_arm(pma_app_t *app)
{
    switch (app->state) {
    case PMA_STATE_ARMED: return PMA_OK;
    case PMA_STATE_IDLE: break;
    case PMA_STATE_FAULT: return PMA_ERR_FAULT;
    default: return PMA_ERR_STATE;
    }
    int rc = check_cross_params(app);
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
    const pma_params_t *p = &app->params;
    if (!(app->sensor.x_cm >= p->safety_x_min_cm - p->safety_x_margin_cm &&
          app->sensor.x_cm <= p->safety_x_max_cm + p->safety_x_margin_cm)) {
        return PMA_ERR_RANGE;
    }
    app->state = PMA_STATE_ARMED;
    app->output.u = 0.0f;
    return PMA_OK;
}

static int cmd_start(pma_app_t *app)
{
    if (app->state == PMA_STATE_FAULT) return PMA_ERR_FAULT;
    if (app->state != PMA_STATE_ARMED) return PMA_ERR_STATE;
    int rc = check_cross_params(app);
    if (rc == PMA_OK) rc = pma_ctrl_start(&app->ctrl, &app->params, app->timing.period_s);
    if (rc != PMA_OK) return rc;
    app->timing.run_ticks = 0;
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
            app->output.u = 0.0f;
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
        if (output_active(app)) return PMA_ERR_STATE;
        app->restart_pending = 1;
        return PMA_OK;
    default:
        return PMA_ERR_UNKNOWN_COMMAND;
    }
}

/* --------------------------------------------------------------------- tick -- */

/* The position of this tick: from the ADC, or the plant bridge's last sample. */
static void acquire(pma_app_t *app)
{
    int rc;
    if (pma_app_bridge_on(app)) {
        if (!app->bridge.have) {
            app->sensor.sample_status = PMA_SAMPLE_NONE;
            if (app->sensor.ticks_since_sample != UINT32_MAX) ++app->sensor.ticks_since_sample;
            app->sensor.status = PMA_ERR_NOT_READY;
            return;
        }
        if (app->bridge.fresh) {
            app->sensor.sample_status = app->bridge.gap ? PMA_SAMPLE_GAP : PMA_SAMPLE_NEW;
            app->sensor.ticks_since_sample = 0;
        } else {
            app->sensor.sample_status = PMA_SAMPLE_REPEATED;
            if (app->sensor.ticks_since_sample != UINT32_MAX) ++app->sensor.ticks_since_sample;
        }
        app->bridge.fresh = 0;
        app->bridge.gap = 0;
        app->sensor.raw_counts = app->bridge.raw_counts;
        rc = PMA_OK;
    } else {
        app->sensor.ticks_since_sample = 0;
        rc = pma_hal_adc_read(&app->sensor.raw_counts);
    }
    if (rc == PMA_OK) {
        pma_adc_scaling_t s;
        pma_app_adc_scaling(&app->params, &s);
        float x = 0.0f;
        rc = pma_adc_counts_to_cm(&s, app->sensor.raw_counts, &x);
        if (rc == PMA_OK) app->sensor.x_cm = x;
    }
    app->sensor.status = rc;
}

static void write_output(pma_app_t *app)
{
    pma_actuator_config_t ac;
    actuator_config(&app->params, &ac);
    if (output_active(app)) {
        app->output.p_kpa = pma_actuator_active_kpa(&ac, app->output.u, app->output.p_kpa, app->timing.period_s);
    } else {
        app->output.p_kpa = pma_actuator_safe_kpa(&ac, app->output.p_kpa);
    }
    pma_dac_scaling_t ds;
    dac_scaling(&app->params, &ds);
    uint16_t counts = app->output.dac_counts;
    if (pma_dac_kpa_to_counts(&ds, app->output.p_kpa, &counts) == PMA_OK) {
        app->output.dac_counts = counts;
    } else {
        /* unreachable while the scaling is enforced at SET (and p is finite):
         * never keep an active pressure on the output */
        pma_app_raise_fault(app, PMA_FAULT_OUTPUT);
        app->output.dac_counts = 0;
    }
    if (pma_app_bridge_on(app)) {
        app->tx_due |= PMA_APP_TX_ACTUATOR; /* the plant bridge's output: a frame */
        return;
    }
    const int rc = pma_hal_dac_write(app->output.dac_counts);
    if (rc != PMA_OK) {
        /* the DAC refused the value (or failed): never leave an earlier,
         * perhaps active, command on the output. Try the safe value, and if
         * the DAC refuses that too, 0 counts (0 V / 0 mA: a regulator's
         * minimum pressure). */
        pma_app_raise_fault(app, PMA_FAULT_OUTPUT);
        app->output.p_kpa = pma_actuator_safe_kpa(&ac, app->output.p_kpa);
        if (pma_dac_kpa_to_counts(&ds, app->output.p_kpa, &counts) != PMA_OK ||
            pma_hal_dac_write(counts) != PMA_OK) {
            counts = 0;
            (void)pma_hal_dac_write(counts);
        }
        app->output.dac_counts = counts;
    }
}

static uint32_t ms_to_ticks(uint32_t ms, uint32_t tick_hz)
{
    if (ms == 0) return 0;
    uint64_t t = ((uint64_t)ms * tick_hz + 999u) / 1000u;
    return t == 0 ? 1u : (t > UINT32_MAX ? UINT32_MAX : (uint32_t)t);
}

void pma_app_core_tick(pma_app_t *app, uint32_t late_ticks)
{
    pma_app_sync_bridge(app);
    ++app->timing.ticks;
    app->timing.late_ticks = late_ticks;
    acquire(app);

    uint8_t ctrl_error = 0;
    if (app->state == PMA_STATE_RUNNING) {
        if (app->timing.ticks_since_host_heartbeat != UINT32_MAX) ++app->timing.ticks_since_host_heartbeat;
        if (app->sensor.status == PMA_OK) {
            const float t_s = (float)app->timing.run_ticks * app->timing.period_s;
            float u = 0.0f;
            ctrl_error = (uint8_t)(pma_ctrl_step(&app->ctrl, t_s, app->sensor.x_cm,
                                                 app->params.ctrl_openloop_u, &u) != PMA_OK);
            app->output.u = u;
            ++app->timing.run_ticks;
        }
    } else {
        app->output.u = 0.0f;
    }

    pma_can_status_t cs;
    const uint8_t bus_off = (uint8_t)(pma_hal_can_status(&cs) == PMA_OK && cs.state == PMA_CAN_BUS_OFF);
    const pma_params_t *p = &app->params;
    const pma_supervisor_limits_t lim = {
        .x_min_cm = p->safety_x_min_cm, .x_max_cm = p->safety_x_max_cm,
        .x_margin_cm = p->safety_x_margin_cm,
        .sensor_timeout_ticks = p->safety_sensor_timeout_ticks,
        .max_late_ticks = p->safety_max_late_ticks,
        .host_timeout_ticks = ms_to_ticks(p->safety_host_timeout_ms, p->sys_tick_hz),
        .barrier_ticks = p->safety_barrier_ticks,
    };
    const pma_supervisor_input_t in = {
        .output_active = (uint8_t)output_active(app),
        .running = (uint8_t)(app->state == PMA_STATE_RUNNING),
        .bus_off = bus_off,
        .sensor_status = app->sensor.status,
        .x_cm = app->sensor.x_cm,
        .ticks_since_sample = pma_app_bridge_on(app) ? app->sensor.ticks_since_sample : 0u,
        .late_ticks = late_ticks,
        .ticks_since_host_heartbeat = app->timing.ticks_since_host_heartbeat,
        .controller_error = ctrl_error,
        .u = app->output.u,
        /* the law's clamp run; none once MFAC is in charge (the run that hands over) */
        .barrier_run = app->ctrl.fallback_active ? 0u : app->ctrl.barrier_run,
    };
    const pma_fault_t f = pma_supervisor_check(&lim, &in);
    if (f != PMA_FAULT_NONE) pma_app_raise_fault(app, f); /* safe output below, this tick */

    write_output(app);

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
