/* SPDX-License-Identifier: Apache-2.0 */
/* The CAN side of the application: decoding received frames with the codec
 * generated from firmware/protocol/pma_proto.dbc, the replies, heartbeat,
 * telemetry and plant-bridge frames. Rules for bad frames (docs/protocol.md):
 *
 *   - another node's id, or an id this node does not receive: ignored;
 *   - ESTOP / ESTOP_ALL: obeyed whatever the data length (fail safe);
 *   - COMMAND, PARAM_REQ with the wrong length: answered with PMA_ERR_LENGTH,
 *     nothing changes;
 *   - PLANT_SENSOR, SETPOINT, HOST_HEARTBEAT, DEVICE_INFO_REQ(_ALL) with the wrong
 *     length: dropped (counted), as if never received;
 *   - out-of-range or malformed values: answered with the error (COMMAND,
 *     PARAM_REQ) or dropped (SETPOINT), nothing changes. */
#include <string.h>

#include "actuator.h" /* pma_safe_mode_t, tied to safety.safe_mode below */
#include "app_core.h"
#include "app_frames.h"
#include "generated/pma_proto.h"
#include "generated/pma_proto_ties.h"

/* One of this node's frames: the message's id and length, its data bytes zero, for the codec to
 * pack in place. Stored member by member: on cores without unaligned word access a struct
 * initialiser or assignment here is a library memset and memcpy on every telemetry frame. */
static void frame_init(pma_can_frame_t *f, const pma_app_t *app, uint16_t base_id, uint8_t dlc)
{
    f->id = (uint16_t)(base_id | app->node_id);
    f->dlc = dlc;
    f->data[0] = f->data[1] = f->data[2] = f->data[3] = 0;
    f->data[4] = f->data[5] = f->data[6] = f->data[7] = 0;
    _Static_assert(sizeof f->data == 8u, "every data byte above");
}

/* Queues f; a frame the HAL does not take is counted. */
static int send(pma_app_t *app, const pma_can_frame_t *f)
{
    const int rc = pma_hal_can_send(f);
    if (rc != PMA_OK) ++app->counters.tx_failed;
    return rc;
}

static int8_t result_code(int rc)
{
    return (int8_t)(rc < -128 ? -128 : (rc > 0 ? 0 : rc));
}

int pma_app_send_frame(pma_app_t *app, uint16_t base_id, uint8_t dlc, const uint8_t *data)
{
    if (dlc > PMA_CAN_DLC_MAX) return PMA_ERR_RANGE;
    if (dlc > 0 && data == NULL) return PMA_ERR_NULL;
    pma_can_frame_t f;
    frame_init(&f, app, base_id, dlc);
    if (dlc > 0) memcpy(f.data, data, dlc);
    return send(app, &f);
}

/* ------------------------------------------------------------------ replies -- */

static void send_ack(pma_app_t *app, uint8_t command, uint8_t arg, int rc)
{
    struct pma_proto_command_ack_t m = {
        .command = command, .arg = arg, .result = result_code(rc), .state = app->state,
    };
    pma_can_frame_t f;
    frame_init(&f, app, PMA_PROTO_COMMAND_ACK_FRAME_ID, PMA_PROTO_COMMAND_ACK_LENGTH);
    (void)pma_proto_command_ack_pack(f.data, &m, sizeof f.data);
    (void)send(app, &f);
}

static void send_param_resp(pma_app_t *app, uint8_t op, uint16_t id, int rc, uint8_t type,
                            pma_param_value_t v)
{
    if (type > PMA_PARAM_I32) v.u32 = 0; /* an undefined Type, echoed from the request: no value */
    struct pma_proto_param_resp_t m;
    memset(&m, 0, sizeof m);
    m.op = (uint8_t)(op & 0x0Fu);
    m.type = (uint8_t)(type & 0x0Fu);
    m.id = id;
    m.result = result_code(rc);
    m.value_f32 = v.f32;
    m.value_u32 = v.u32;
    m.value_i32 = v.i32;
    pma_can_frame_t f;
    frame_init(&f, app, PMA_PROTO_PARAM_RESP_FRAME_ID, PMA_PROTO_PARAM_RESP_LENGTH);
    (void)pma_proto_param_resp_pack(f.data, &m, sizeof f.data);
    (void)send(app, &f);
}

void pma_app_send_heartbeat(pma_app_t *app)
{
    uint16_t flags = 0;
    if (app->state == PMA_STATE_ARMED || app->state == PMA_STATE_RUNNING) flags |= PMA_HB_OUTPUT_ACTIVE;
    if (pma_app_bridge_on(app)) flags |= PMA_HB_PLANT_BRIDGE;
    if (app->plat.lockstep) flags |= PMA_HB_LOCKSTEP;
    if (app->storage.params_changed) flags |= PMA_HB_PARAMS_CHANGED;
    if (app->storage.params_default) flags |= PMA_HB_PARAMS_DEFAULT;
    if (app->storage.save_failed) flags |= PMA_HB_SAVE_FAILED;
    if (app->ctrl.lost) flags |= PMA_HB_GUARANTEE_LOST;
    if (app->ctrl.fallback_active) flags |= PMA_HB_FALLBACK;
    if (app->sensor.status == PMA_OK &&
        !(pma_app_bridge_on(app) &&
          app->sensor.ticks_since_sample >= app->params.safety_sensor_timeout_ticks)) {
        flags |= PMA_HB_SENSOR_VALID;
    }
    if (app->state == PMA_STATE_RUNNING) flags |= PMA_HB_REF_ACTIVE;
    pma_can_status_t cs;
    if (pma_hal_can_status(&cs) == PMA_OK && cs.state != PMA_CAN_ERROR_ACTIVE) {
        flags |= PMA_HB_CAN_PASSIVE;
    }
    struct pma_proto_heartbeat_t m = {
        .state = app->state, .fault_code = app->fault, .flags = flags,
        .controller = (uint8_t)app->params.ctrl_mode, .reference = (uint8_t)app->params.ref_kind,
        .reset_cause = app->reset_cause, .counter = app->timing.heartbeat_counter++,
    };
    pma_can_frame_t f;
    frame_init(&f, app, PMA_PROTO_HEARTBEAT_FRAME_ID, PMA_PROTO_HEARTBEAT_LENGTH);
    (void)pma_proto_heartbeat_pack(f.data, &m, sizeof f.data);
    (void)send(app, &f);
}

int pma_app_send_actuator(pma_app_t *app)
{
    struct pma_proto_plant_actuator_t m = {
        .seq = app->bridge.seq, .dac_counts = app->output.dac_counts, .sample = app->sensor.sample_status,
        .output_active = (uint8_t)(app->state == PMA_STATE_ARMED || app->state == PMA_STATE_RUNNING),
    };
    pma_can_frame_t f;
    frame_init(&f, app, PMA_PROTO_PLANT_ACTUATOR_FRAME_ID, PMA_PROTO_PLANT_ACTUATOR_LENGTH);
    (void)pma_proto_plant_actuator_pack(f.data, &m, sizeof f.data);
    return send(app, &f);
}

void pma_app_send_telemetry(pma_app_t *app)
{
    const pma_ctrl_out_t *o = pma_ctrl_out(&app->ctrl); /* Q16.16: converted here */
    const uint32_t mask = app->params.telem_mask;
    if (mask & PMA_TELEM_MASK_A) {
        /* the control time of this step: run_ticks was counted up after it */
        const uint64_t steps = app->timing.run_ticks > 0 ? app->timing.run_ticks - 1u : 0u;
        const uint64_t us = steps * app->timing.period_us;
        /* the 32-bit division while the time fits (71 min): the same value, without the 64-bit
         * one (a long library call on cores without a divide instruction) */
        const uint64_t ms = (us >> 32) == 0u ? (uint32_t)us / 1000u : us / 1000u;
        struct pma_proto_telem_a_t m = {.time_ms = (uint32_t)ms, .x_cm = pma_app_position_cm(app)};
        pma_can_frame_t f;
        frame_init(&f, app, PMA_PROTO_TELEM_A_FRAME_ID, PMA_PROTO_TELEM_A_LENGTH);
        (void)pma_proto_telem_a_pack(f.data, &m, sizeof f.data);
        (void)send(app, &f);
    }
    if (mask & PMA_TELEM_MASK_B) {
        struct pma_proto_telem_b_t m = {.xr_cm = o->xr_cm, .e_cm = o->e_cm};
        pma_can_frame_t f;
        frame_init(&f, app, PMA_PROTO_TELEM_B_FRAME_ID, PMA_PROTO_TELEM_B_LENGTH);
        (void)pma_proto_telem_b_pack(f.data, &m, sizeof f.data);
        (void)send(app, &f);
    }
    if (mask & PMA_TELEM_MASK_C) {
        struct pma_proto_telem_c_t m = {.u = pma_app_output_u(app), .v_cm_s = o->v_cm_s};
        pma_can_frame_t f;
        frame_init(&f, app, PMA_PROTO_TELEM_C_FRAME_ID, PMA_PROTO_TELEM_C_LENGTH);
        (void)pma_proto_telem_c_pack(f.data, &m, sizeof f.data);
        (void)send(app, &f);
    }
    if (mask & PMA_TELEM_MASK_D) {
        struct pma_proto_telem_d_t m = {.internal1 = o->internal1, .internal2 = o->internal2};
        pma_can_frame_t f;
        frame_init(&f, app, PMA_PROTO_TELEM_D_FRAME_ID, PMA_PROTO_TELEM_D_LENGTH);
        (void)pma_proto_telem_d_pack(f.data, &m, sizeof f.data);
        (void)send(app, &f);
    }
    if (mask & PMA_TELEM_MASK_E) {
        struct pma_proto_telem_e_t m = {
            .pressure_kpa = pma_app_pressure_kpa(app), .ctrl_flags = (uint16_t)o->flags,
            .breaches = (uint16_t)(app->ctrl.breaches & 0xFFFFu), /* mod 2^16 (DBC) */
        };
        pma_can_frame_t f;
        frame_init(&f, app, PMA_PROTO_TELEM_E_FRAME_ID, PMA_PROTO_TELEM_E_LENGTH);
        (void)pma_proto_telem_e_pack(f.data, &m, sizeof f.data);
        (void)send(app, &f);
    }
}

/* ---------------------------------------------------------------- handlers -- */

static void on_plant_sensor(pma_app_t *app, const pma_can_frame_t *f)
{
    struct pma_proto_plant_sensor_t m;
    if (!pma_app_bridge_on(app) || f->dlc != PMA_PROTO_PLANT_SENSOR_LENGTH ||
        pma_proto_plant_sensor_unpack(&m, f->data, f->dlc) != 0) {
        ++app->counters.frames_bad;
        return;
    }
    if (app->bridge.have && m.seq == app->bridge.seq) {
        ++app->counters.bridge_repeats; /* a duplicated frame: not a new sample */
        return;
    }
    if (app->bridge.have && m.seq != (uint8_t)(app->bridge.seq + 1u)) {
        ++app->counters.bridge_gaps;
        app->bridge.gap = 1;
    }
    app->bridge.have = 1;
    app->bridge.fresh = 1;
    app->bridge.seq = m.seq;
    app->bridge.raw_counts = m.raw_counts;
}

/* DEVICE_INFO_REQ(_ALL): no data; another length is dropped (counted), as for the other
 * messages that are not answered with a result code. */
static void on_device_info_req(pma_app_t *app, const pma_can_frame_t *f)
{
    if (f->dlc != PMA_PROTO_DEVICE_INFO_REQ_LENGTH) {
        ++app->counters.frames_bad;
        return;
    }
    pma_app_send_device_info(app);
}

static void on_command(pma_app_t *app, const pma_can_frame_t *f)
{
    const uint8_t cmd = f->dlc > 0 ? f->data[0] : 0u;
    const uint8_t arg = f->dlc > 1 ? f->data[1] : 0u;
    if (f->dlc != PMA_PROTO_COMMAND_LENGTH) {
        ++app->counters.frames_bad;
        send_ack(app, cmd, arg, PMA_ERR_LENGTH);
        return;
    }
    send_ack(app, cmd, arg, pma_app_command(app, cmd, arg));
}

static void on_setpoint(pma_app_t *app, const pma_can_frame_t *f)
{
    struct pma_proto_setpoint_t m;
    if (f->dlc != PMA_PROTO_SETPOINT_LENGTH || pma_proto_setpoint_unpack(&m, f->data, f->dlc) != 0) {
        ++app->counters.frames_bad;
        return;
    }
    if (app->state != PMA_STATE_RUNNING ||
        pma_ctrl_stream(&app->ctrl, m.xr_cm, app->params.safety_x_min_cm,
                        app->params.safety_x_max_cm) != PMA_OK) {
        ++app->counters.setpoints_rejected;
    }
}

static void on_param_req(pma_app_t *app, const pma_can_frame_t *f)
{
    const pma_param_value_t zero = {.u32 = 0};
    const uint8_t op = f->dlc > 0 ? (uint8_t)(f->data[0] & 0x0Fu) : 0u;
    const uint8_t req_type = f->dlc > 0 ? (uint8_t)(f->data[0] >> 4) : 0u;
    const uint16_t id = (uint16_t)(f->dlc > 2 ? (unsigned)f->data[1] | ((unsigned)f->data[2] << 8) : 0u);
    struct pma_proto_param_req_t m;
    memset(&m, 0, sizeof m);
    if (f->dlc != PMA_PROTO_PARAM_REQ_LENGTH || pma_proto_param_req_unpack(&m, f->data, f->dlc) != 0) {
        ++app->counters.frames_bad;
        send_param_resp(app, op, id, PMA_ERR_LENGTH, req_type, zero);
        return;
    }
    if (m.reserved != 0) {
        send_param_resp(app, op, id, PMA_ERR_UNKNOWN_COMMAND, req_type, zero);
        return;
    }
    const pma_param_desc_t *d = pma_param_find(id);
    pma_param_type_t type = d ? (pma_param_type_t)d->type : (pma_param_type_t)req_type;
    pma_param_value_t v = zero;
    int rc = PMA_OK;
    switch (op) {
    case PMA_PARAM_OP_GET:
        rc = pma_app_param_get(app, id, &type, &v);
        break;
    case PMA_PARAM_OP_SET: {
        pma_param_value_t nv;
        nv.u32 = m.value_u32; /* the raw bits: the codec unpacks only the Type's signal */
        if (req_type == PMA_PARAM_F32) nv.f32 = m.value_f32;
        if (req_type == PMA_PARAM_I32) nv.i32 = m.value_i32;
        rc = pma_app_param_set(app, id, (pma_param_type_t)req_type, nv);
        if (d != NULL) (void)pma_app_param_get(app, id, &type, &v); /* the value now */
        break;
    }
    case PMA_PARAM_OP_SAVE:
    case PMA_PARAM_OP_RESTORE_DEFAULTS:
    case PMA_PARAM_OP_LOAD: /* the whole set; the reply echoes the request's Type */
        rc = op == PMA_PARAM_OP_SAVE ? pma_app_params_save(app)
             : op == PMA_PARAM_OP_LOAD ? pma_app_params_load(app)
                                       : pma_app_params_restore_defaults(app);
        type = (pma_param_type_t)req_type;
        break;
    case PMA_PARAM_OP_GET_MIN:
    case PMA_PARAM_OP_GET_MAX:
    case PMA_PARAM_OP_GET_DEFAULT:
        if (d == NULL) {
            rc = PMA_ERR_UNKNOWN_ID;
        } else {
            v = op == PMA_PARAM_OP_GET_MIN ? d->min : (op == PMA_PARAM_OP_GET_MAX ? d->max : d->def);
        }
        break;
    case PMA_PARAM_OP_NEXT_ID: {
        uint16_t next = 0;
        rc = pma_param_next_id(id, &next);
        type = PMA_PARAM_U32;
        v.u32 = next;
        break;
    }
    case PMA_PARAM_OP_GET_STATUS:
        type = PMA_PARAM_U32;
        rc = pma_app_status_value(app, id, &v.u32);
        break;
    default:
        rc = PMA_ERR_UNKNOWN_COMMAND;
        break;
    }
    send_param_resp(app, op, id, rc, (uint8_t)type, v);
}

void pma_app_handle_frame(pma_app_t *app, const pma_can_frame_t *f)
{
    if (app == NULL || f == NULL) return;
    pma_app_sync_bridge(app); /* a SET in an earlier frame may have switched the bridge */
    ++app->counters.frames_rx;
    /* emergency stops first: obeyed whatever the length, even an invalid one */
    if (f->id == PMA_PROTO_ESTOP_ALL_FRAME_ID ||
        f->id == (uint16_t)(PMA_PROTO_ESTOP_FRAME_ID | app->node_id)) {
        pma_app_raise_fault(app, PMA_FAULT_ESTOP);
        return;
    }
    if (f->dlc > PMA_CAN_DLC_MAX || f->id > PMA_CAN_ID_MAX) {
        ++app->counters.frames_bad;
        return;
    }
    if (f->id == PMA_PROTO_DEVICE_INFO_REQ_ALL_FRAME_ID) { /* the one broadcast request */
        on_device_info_req(app, f);
        return;
    }
    if ((f->id & PMA_NODE_ID_MASK) != app->node_id) {
        ++app->counters.frames_ignored;
        return;
    }
    switch (f->id & PMA_BASE_ID_MASK) {
    case PMA_PROTO_PLANT_SENSOR_FRAME_ID:
        on_plant_sensor(app, f);
        break;
    case PMA_PROTO_COMMAND_FRAME_ID:
        on_command(app, f);
        break;
    case PMA_PROTO_SETPOINT_FRAME_ID:
        on_setpoint(app, f);
        break;
    case PMA_PROTO_PARAM_REQ_FRAME_ID:
        on_param_req(app, f);
        break;
    case PMA_PROTO_DEVICE_INFO_REQ_FRAME_ID:
        on_device_info_req(app, f);
        break;
    case PMA_PROTO_HOST_HEARTBEAT_FRAME_ID:
        if (f->dlc == PMA_PROTO_HOST_HEARTBEAT_LENGTH) {
            app->timing.ticks_since_host_heartbeat = 0;
        } else {
            ++app->counters.frames_bad;
        }
        break;
    default: /* what this node sends, or not defined */
        ++app->counters.frames_ignored;
        break;
    }
}

void pma_app_send_marked(pma_app_t *app)
{
    const uint8_t due = app->tx_due;
    app->tx_due = 0;
    if (due & PMA_APP_TX_ACTUATOR) (void)pma_app_send_actuator(app);
    if (due & PMA_APP_TX_TELEMETRY) pma_app_send_telemetry(app);
    if (due & PMA_APP_TX_HEARTBEAT) pma_app_send_heartbeat(app);
}
