/* SPDX-License-Identifier: Apache-2.0 */
/* libpma_offline: see pma_offline.h. */
#include "pma_offline.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

#include "app.h"
#include "controller.h"
#include "generated/pma_proto.h"
#include "params.h"
#include "pma/status.h"
#include "pma_hal_fake.h"
#include "supervisor.h"

/* static: one node per process, as the fake port's devices (no heap) */
static pma_app_t app;
static struct {
    uint8_t ready;
    uint8_t seq;                 /* the last PLANT_SENSOR sequence number sent */
    uint8_t host_queue_on;
    uint32_t head, count, dropped;
    pma_can_frame_t host_queue[PMA_OFFLINE_HOST_QUEUE];
} node;

/* A frame the node sent, kept for the host (when the host queue is on). */
static void keep_for_host(const pma_can_frame_t *f)
{
    if (!node.host_queue_on) return;
    if (node.count == PMA_OFFLINE_HOST_QUEUE) {
        ++node.dropped;
        return;
    }
    node.host_queue[(node.head + node.count) % PMA_OFFLINE_HOST_QUEUE] = *f;
    ++node.count;
}

int pma_offline_api_version(void)
{
    return PMA_OFFLINE_API_VERSION;
}

const char *pma_offline_ctrl_arith(void)
{
#if PMA_CTRL_Q16
    return "q16";
#else
    return "f32";
#endif
}

/* ------------------------------------------------------------- frames -- */

static int inject(uint16_t base_id, uint8_t dlc, const uint8_t *data)
{
    pma_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = (uint16_t)(base_id | app.node_id);
    f.dlc = dlc;
    memcpy(f.data, data, dlc);
    return pma_fake_can_inject(&f);
}

static int is_ours(const pma_can_frame_t *f, uint16_t base_id)
{
    return f->id == (uint16_t)(base_id | app.node_id);
}

/* One loop iteration without a tick (the frames queued so far are handled),
 * then the reply of kind base_id popped from what the node sent; the other
 * frames (a heartbeat) are dropped. PMA_ERR_IO when no reply came. */
static int exchange(uint16_t base_id, pma_can_frame_t *reply)
{
    int rc = pma_app_step(&app);
    if (rc != PMA_OK) return rc;
    int found = 0;
    pma_can_frame_t f;
    while (pma_fake_can_tx_pop(&f) == PMA_OK) {
        if (!found && is_ours(&f, base_id)) {
            *reply = f;
            found = 1;
        } else {
            keep_for_host(&f);
        }
    }
    return found ? PMA_OK : PMA_ERR_IO;
}

/* ------------------------------------------------------------ start-up -- */

int pma_offline_init(uint8_t node_id)
{
    node.ready = 0;
    if (node_id > 15u) return PMA_ERR_RANGE;
    pma_fake_reset();
    int rc = pma_hal_init(NULL);
    if (rc != PMA_OK) return rc;
    pma_fake_tick_lockstep(true);
    const pma_app_platform_t plat = {
        .plant_bridge = 1, /* as pma-fw-host: the sample in PLANT_SENSOR, the command in PLANT_ACTUATOR */
        .lockstep = 1,
        .node_id = (int16_t)node_id,
        .store_first_block = 0,
        .store_blocks_per_slot = 0,
        .watchdog_ms = 0,
    };
    rc = pma_app_init(&app, &plat);
    pma_can_frame_t f;
    while (pma_fake_can_tx_pop(&f) == PMA_OK) {
    }
    node.seq = 0;
    node.host_queue_on = 0;
    node.head = node.count = node.dropped = 0;
    node.ready = (uint8_t)(rc == PMA_OK);
    return rc;
}

/* ---------------------------------------------------------- raw frames -- */

void pma_offline_host_queue(int on)
{
    node.host_queue_on = (uint8_t)(on != 0);
}

int pma_offline_frame_in(uint16_t id, uint8_t dlc, const uint8_t *data)
{
    if (!node.ready) return PMA_ERR_NOT_READY;
    if (id > PMA_CAN_ID_MAX || dlc > PMA_CAN_DLC_MAX || (dlc > 0 && data == NULL)) return PMA_ERR_RANGE;
    pma_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.dlc = dlc;
    if (dlc > 0) memcpy(f.data, data, dlc);
    return pma_fake_can_inject(&f);
}

int pma_offline_loop(void)
{
    if (!node.ready) return PMA_ERR_NOT_READY;
    const int rc = pma_app_step(&app);
    pma_can_frame_t f;
    while (pma_fake_can_tx_pop(&f) == PMA_OK) keep_for_host(&f);
    return rc;
}

int pma_offline_frame_out(uint16_t *id, uint8_t *dlc, uint8_t *data)
{
    if (id == NULL || dlc == NULL || data == NULL) return PMA_ERR_NULL;
    if (node.count == 0) return PMA_ERR_EMPTY;
    const pma_can_frame_t *f = &node.host_queue[node.head];
    *id = f->id;
    *dlc = f->dlc;
    memcpy(data, f->data, 8u);
    node.head = (node.head + 1u) % PMA_OFFLINE_HOST_QUEUE;
    --node.count;
    return PMA_OK;
}

uint32_t pma_offline_host_dropped(void)
{
    return node.dropped;
}

/* ---------------------------------------------------------- parameters -- */

int pma_offline_param_count(void)
{
    return (int)PMA_PARAM_COUNT;
}

int pma_offline_param_id(const char *name)
{
    if (name == NULL) return PMA_ERR_NULL;
    for (size_t i = 0; i < PMA_PARAM_COUNT; ++i) {
        if (strcmp(pma_param_table[i].name, name) == 0) return (int)pma_param_table[i].id;
    }
    return PMA_ERR_UNKNOWN_ID;
}

const char *pma_offline_param_at(int index, uint16_t *id)
{
    if (index < 0 || (size_t)index >= PMA_PARAM_COUNT) return NULL;
    if (id != NULL) *id = pma_param_table[index].id;
    return pma_param_table[index].name;
}

int pma_offline_param_type(uint16_t id)
{
    const pma_param_desc_t *d = pma_param_find(id);
    return d == NULL ? PMA_ERR_UNKNOWN_ID : (int)d->type;
}

static double value_of(uint8_t type, const struct pma_proto_param_resp_t *m)
{
    switch (type) {
    case PMA_PARAM_F32: return (double)m->value_f32;
    case PMA_PARAM_U32: return (double)m->value_u32;
    default: return (double)m->value_i32;
    }
}

static int param_request(uint8_t op, uint16_t id, uint8_t type, pma_param_value_t v, double *value)
{
    if (!node.ready) return PMA_ERR_NOT_READY;
    struct pma_proto_param_req_t m;
    memset(&m, 0, sizeof m);
    m.op = op;
    m.type = type;
    m.id = id;
    m.value_f32 = v.f32;
    m.value_u32 = v.u32;
    m.value_i32 = v.i32;
    uint8_t d[8] = {0};
    if (pma_proto_param_req_pack(d, &m, sizeof d) != PMA_PROTO_PARAM_REQ_LENGTH) return PMA_ERR_RANGE;
    int rc = inject(PMA_PROTO_PARAM_REQ_FRAME_ID, PMA_PROTO_PARAM_REQ_LENGTH, d);
    if (rc != PMA_OK) return rc;
    pma_can_frame_t f;
    rc = exchange(PMA_PROTO_PARAM_RESP_FRAME_ID, &f);
    if (rc != PMA_OK) return rc;
    struct pma_proto_param_resp_t r;
    memset(&r, 0, sizeof r);
    if (pma_proto_param_resp_unpack(&r, f.data, f.dlc) != 0 || r.op != op || r.id != id) {
        return PMA_ERR_IO;
    }
    if (value != NULL) *value = value_of(r.type, &r);
    return r.result;
}

int pma_offline_param_set(uint16_t id, double value, double *now)
{
    const pma_param_desc_t *d = pma_param_find(id);
    if (d == NULL) return PMA_ERR_UNKNOWN_ID;
    pma_param_value_t v;
    v.u32 = 0;
    switch (d->type) {
    case PMA_PARAM_F32:
        v.f32 = (float)value; /* NaN stays NaN: the node's check refuses it */
        break;
    case PMA_PARAM_U32:
        if (!(value >= 0.0 && value <= 4294967295.0) || value != floor(value)) return PMA_ERR_TYPE;
        v.u32 = (uint32_t)value;
        break;
    default:
        if (!(value >= -2147483648.0 && value <= 2147483647.0) || value != floor(value)) {
            return PMA_ERR_TYPE;
        }
        v.i32 = (int32_t)value;
        break;
    }
    return param_request(PMA_PARAM_OP_SET, id, d->type, v, now);
}

int pma_offline_param_get(uint16_t id, double *value)
{
    const pma_param_desc_t *d = pma_param_find(id);
    pma_param_value_t v;
    v.u32 = 0;
    return param_request(PMA_PARAM_OP_GET, id, d != NULL ? d->type : (uint8_t)PMA_PARAM_U32, v, value);
}

/* ------------------------------------------------------------ commands -- */

int pma_offline_command(uint8_t command, uint8_t arg, uint8_t *state)
{
    if (!node.ready) return PMA_ERR_NOT_READY;
    struct pma_proto_command_t m = {.command = command, .arg = arg};
    uint8_t d[8] = {0};
    if (pma_proto_command_pack(d, &m, sizeof d) != PMA_PROTO_COMMAND_LENGTH) return PMA_ERR_RANGE;
    int rc = inject(PMA_PROTO_COMMAND_FRAME_ID, PMA_PROTO_COMMAND_LENGTH, d);
    if (rc != PMA_OK) return rc;
    pma_can_frame_t f;
    rc = exchange(PMA_PROTO_COMMAND_ACK_FRAME_ID, &f);
    if (rc != PMA_OK) return rc;
    struct pma_proto_command_ack_t a;
    memset(&a, 0, sizeof a);
    if (pma_proto_command_ack_unpack(&a, f.data, f.dlc) != 0 || a.command != command) return PMA_ERR_IO;
    if (state != NULL) *state = a.state;
    return a.result;
}

int pma_offline_host_heartbeat(uint8_t counter)
{
    if (!node.ready) return PMA_ERR_NOT_READY;
    struct pma_proto_host_heartbeat_t m = {.counter = counter};
    uint8_t d[8] = {0};
    if (pma_proto_host_heartbeat_pack(d, &m, sizeof d) != PMA_PROTO_HOST_HEARTBEAT_LENGTH) {
        return PMA_ERR_RANGE;
    }
    return inject(PMA_PROTO_HOST_HEARTBEAT_FRAME_ID, PMA_PROTO_HOST_HEARTBEAT_LENGTH, d);
}

/* ---------------------------------------------------------------- tick -- */

static void take_telemetry(const pma_can_frame_t *f, pma_offline_tick_t *out)
{
    switch (f->id & PMA_BASE_ID_MASK) {
    case PMA_PROTO_TELEM_A_FRAME_ID: {
        struct pma_proto_telem_a_t m;
        if (pma_proto_telem_a_unpack(&m, f->data, f->dlc) != 0) return;
        out->telem_time_ms = m.time_ms;
        out->telem_x_cm = m.x_cm;
        out->telem_frames |= 0x01u;
        break;
    }
    case PMA_PROTO_TELEM_B_FRAME_ID: {
        struct pma_proto_telem_b_t m;
        if (pma_proto_telem_b_unpack(&m, f->data, f->dlc) != 0) return;
        out->telem_xr_cm = m.xr_cm;
        out->telem_e_cm = m.e_cm;
        out->telem_frames |= 0x02u;
        break;
    }
    case PMA_PROTO_TELEM_C_FRAME_ID: {
        struct pma_proto_telem_c_t m;
        if (pma_proto_telem_c_unpack(&m, f->data, f->dlc) != 0) return;
        out->telem_u = m.u;
        out->telem_v_cm_s = m.v_cm_s;
        out->telem_frames |= 0x04u;
        break;
    }
    case PMA_PROTO_TELEM_D_FRAME_ID: {
        struct pma_proto_telem_d_t m;
        if (pma_proto_telem_d_unpack(&m, f->data, f->dlc) != 0) return;
        out->telem_internal1 = m.internal1;
        out->telem_internal2 = m.internal2;
        out->telem_frames |= 0x08u;
        break;
    }
    case PMA_PROTO_TELEM_E_FRAME_ID: {
        struct pma_proto_telem_e_t m;
        if (pma_proto_telem_e_unpack(&m, f->data, f->dlc) != 0) return;
        out->telem_pressure_kpa = m.pressure_kpa;
        out->telem_ctrl_flags = m.ctrl_flags;
        out->telem_breaches = m.breaches;
        out->telem_frames |= 0x10u;
        break;
    }
    default:
        ++out->other_frames;
        break;
    }
}

int pma_offline_tick(uint16_t raw_counts, pma_offline_tick_t *out)
{
    if (out == NULL) return PMA_ERR_NULL;
    memset(out, 0, sizeof *out);
    if (!node.ready) return PMA_ERR_NOT_READY;
    node.seq = (uint8_t)(node.seq + 1u);
    struct pma_proto_plant_sensor_t m = {.seq = node.seq, .raw_counts = raw_counts};
    uint8_t d[8] = {0};
    if (pma_proto_plant_sensor_pack(d, &m, sizeof d) != PMA_PROTO_PLANT_SENSOR_LENGTH) return PMA_ERR_RANGE;
    int rc = inject(PMA_PROTO_PLANT_SENSOR_FRAME_ID, PMA_PROTO_PLANT_SENSOR_LENGTH, d);
    if (rc != PMA_OK) return rc;
    pma_fake_tick_grant(); /* the sample is the tick, as in the host port's lockstep */
    rc = pma_app_step(&app);
    if (rc != PMA_OK) return rc;
    int actuator = 0;
    pma_can_frame_t f;
    while (pma_fake_can_tx_pop(&f) == PMA_OK) {
        if ((f.id & PMA_NODE_ID_MASK) != app.node_id) continue;
        if ((f.id & PMA_BASE_ID_MASK) == PMA_PROTO_PLANT_ACTUATOR_FRAME_ID) {
            struct pma_proto_plant_actuator_t a;
            if (pma_proto_plant_actuator_unpack(&a, f.data, f.dlc) != 0) continue;
            out->dac_counts = a.dac_counts;
            out->seq = a.seq;
            out->sample_status = a.sample;
            out->output_active = a.output_active;
            actuator = 1;
        } else {
            take_telemetry(&f, out);
            keep_for_host(&f);
        }
    }
    out->state = app.state;
    out->fault = app.fault;
    out->sensor_status = app.sensor.status;
    out->x_cm = pma_app_position_cm(&app);
    out->u = pma_app_output_u(&app);
    out->p_kpa = pma_app_pressure_kpa(&app);
    out->barrier_run = app.ctrl.barrier_run;
    return actuator ? PMA_OK : PMA_ERR_IO;
}

/* --------------------------------------------------------------- state -- */

int pma_offline_state(void)
{
    return app.state;
}

int pma_offline_fault(void)
{
    return app.fault;
}

uint64_t pma_offline_ticks(void)
{
    return app.timing.ticks;
}

uint64_t pma_offline_time_us(void)
{
    return pma_hal_time_us();
}

const char *pma_offline_status_name(int rc)
{
    return pma_status_name(rc);
}

const char *pma_offline_state_name(int state)
{
    return pma_app_state_name(state);
}

const char *pma_offline_fault_name(int fault)
{
    return pma_fault_name(fault);
}
