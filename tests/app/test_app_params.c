/* SPDX-License-Identifier: Apache-2.0 */
/* Parameters (params.h, generated table): defaults, typed access by id, every
 * rejection (unknown id, wrong type, NaN / infinity, below min, above max,
 * access class against the phase) leaving the set unchanged, enumeration by
 * NEXT_ID, and the storage format (round trip, unknown ids, out-of-range
 * stored values, bad lengths). Pure: no HAL. */
#include "app_test.h"

#include <float.h>

static pma_params_t p, before;

static const pma_param_phase_t phases[] = {PMA_PHASE_INACTIVE, PMA_PHASE_ARMED,
                                           PMA_PHASE_RUNNING};

/* Whether the access class allows a SET in the phase (params.toml, access). */
static bool allowed(uint8_t access, pma_param_phase_t phase)
{
    switch (access) {
    case PMA_PARAM_LIVE: return true;
    case PMA_PARAM_STOPPED: return phase != PMA_PHASE_RUNNING;
    case PMA_PARAM_IDLE: return phase == PMA_PHASE_INACTIVE;
    default: pma_test_fail("unknown access class %u", (unsigned)access); return false;
    }
}

/* A set that must fail with want and leave everything as it was. */
static void reject(uint16_t id, pma_param_type_t type, pma_param_value_t v, pma_param_phase_t ph,
                   int want)
{
    before = p;
    assert_status(pma_param_check(id, type, v, ph), want);
    assert_status(pma_param_set(&p, id, type, v, ph), want);
    TEST_ASSERT_EQUAL_MEMORY(&before, &p, sizeof p);
}

static void test_table_is_sorted_and_consistent(void)
{
    for (size_t i = 0; i < PMA_PARAM_COUNT; ++i) {
        const pma_param_desc_t *d = &pma_param_table[i];
        if (i > 0) TEST_ASSERT_GREATER_THAN(pma_param_table[i - 1].id, d->id);
        TEST_ASSERT_LESS_OR_EQUAL(PMA_PARAM_I32, d->type);
        TEST_ASSERT_LESS_OR_EQUAL(PMA_PARAM_IDLE, d->access);
        TEST_ASSERT_TRUE(d->offset % 4u == 0 && d->offset + 4u <= sizeof(pma_params_t));
        TEST_ASSERT_NOT_NULL(d->name);
        for (size_t j = 0; j < i; ++j) {
            TEST_ASSERT_TRUE(pma_param_table[j].offset != d->offset);
            TEST_ASSERT_TRUE(strcmp(pma_param_table[j].name, d->name) != 0);
        }
        /* the default is a value the parameter accepts */
        assert_status(pma_param_check(d->id, (pma_param_type_t)d->type, d->def,
                                      PMA_PHASE_INACTIVE), PMA_OK);
        TEST_ASSERT_EQUAL_PTR(d, pma_param_find(d->id));
    }
    /* every field of pma_params_t belongs to one parameter */
    TEST_ASSERT_EQUAL_INT(4u * PMA_PARAM_COUNT, sizeof(pma_params_t));
}

static void test_find_unknown_ids(void)
{
    static const uint16_t unknown[] = {0, 6, 15, 20, 31, 61, 104, 118, 133, 148, 169, 255,
                                       0x7FFF, 0xFFFF};
    for (size_t i = 0; i < sizeof unknown / sizeof unknown[0]; ++i) {
        TEST_ASSERT_NULL(pma_param_find(unknown[i]));
    }
}

static void test_defaults_equal_table(void)
{
    memset(&p, 0xA5, sizeof p);
    pma_params_defaults(&p);
    for (size_t i = 0; i < PMA_PARAM_COUNT; ++i) {
        const pma_param_desc_t *d = &pma_param_table[i];
        pma_param_type_t type = (pma_param_type_t)99;
        pma_param_value_t v;
        assert_status(pma_param_get(&p, d->id, &type, &v), PMA_OK);
        TEST_ASSERT_EQUAL_INT(d->type, type);
        TEST_ASSERT_EQUAL_INT(d->def.u32, v.u32); /* bit for bit */
    }
    /* a few by name, against params.toml */
    TEST_ASSERT_EQUAL_INT(1000u, p.sys_tick_hz);
    TEST_ASSERT_EQUAL_INT(100u, p.sys_heartbeat_ms);
    TEST_ASSERT_EQUAL_INT(PMA_CTRL_MODE_PPC, p.ctrl_mode);
    TEST_ASSERT_TRUE(p.ctrl_u_min == -300.0f && p.ctrl_u_max == 300.0f);
    TEST_ASSERT_TRUE(p.ref_offset_cm == -1.5f);
    TEST_ASSERT_EQUAL_INT(1, p.act_polarity);
    TEST_ASSERT_TRUE(p.act_p0_kpa == 300.0f);
    TEST_ASSERT_TRUE(p.safety_x_min_cm == -3.0f && p.safety_x_max_cm == 0.0f);
    TEST_ASSERT_EQUAL_INT(PMA_SAFETY_SAFE_MODE_VENT, p.safety_safe_mode);
}

static void test_get_set_each_type(void)
{
    pma_params_defaults(&p);
    pma_param_type_t t;
    pma_param_value_t v;

    assert_status(pma_param_set(&p, PMA_PARAM_PPC_C, PMA_PARAM_F32, vf(3.25f), PMA_PHASE_INACTIVE),
                  PMA_OK);
    TEST_ASSERT_TRUE(p.ppc_c == 3.25f);
    assert_status(pma_param_get(&p, PMA_PARAM_PPC_C, &t, &v), PMA_OK);
    TEST_ASSERT_EQUAL_INT(PMA_PARAM_F32, t);
    TEST_ASSERT_TRUE(v.f32 == 3.25f);

    assert_status(pma_param_set(&p, PMA_PARAM_TELEM_DECIMATION, PMA_PARAM_U32, vu(7),
                                PMA_PHASE_RUNNING), PMA_OK);
    TEST_ASSERT_EQUAL_INT(7u, p.telem_decimation);
    assert_status(pma_param_get(&p, PMA_PARAM_TELEM_DECIMATION, &t, &v), PMA_OK);
    TEST_ASSERT_EQUAL_INT(PMA_PARAM_U32, t);
    TEST_ASSERT_EQUAL_INT(7u, v.u32);

    assert_status(pma_param_set(&p, PMA_PARAM_ACT_POLARITY, PMA_PARAM_I32, vi(-1),
                                PMA_PHASE_INACTIVE), PMA_OK);
    TEST_ASSERT_EQUAL_INT(-1, p.act_polarity);
    assert_status(pma_param_get(&p, PMA_PARAM_ACT_POLARITY, &t, &v), PMA_OK);
    TEST_ASSERT_EQUAL_INT(PMA_PARAM_I32, t);
    TEST_ASSERT_EQUAL_INT(-1, v.i32);
    /* polarity's range is -1..1: 0 is settable (refused later, at ARM) */
    assert_status(pma_param_set(&p, PMA_PARAM_ACT_POLARITY, PMA_PARAM_I32, vi(0),
                                PMA_PHASE_INACTIVE), PMA_OK);
    TEST_ASSERT_EQUAL_INT(0, p.act_polarity);

    /* NULL arguments */
    assert_status(pma_param_get(NULL, PMA_PARAM_PPC_C, &t, &v), PMA_ERR_NULL);
    assert_status(pma_param_get(&p, PMA_PARAM_PPC_C, NULL, &v), PMA_ERR_NULL);
    assert_status(pma_param_get(&p, PMA_PARAM_PPC_C, &t, NULL), PMA_ERR_NULL);
    assert_status(pma_param_set(NULL, PMA_PARAM_PPC_C, PMA_PARAM_F32, vf(1.0f),
                                PMA_PHASE_INACTIVE), PMA_ERR_NULL);
    assert_status(pma_param_get(&p, 999, &t, &v), PMA_ERR_UNKNOWN_ID);
}

/* min and max themselves are accepted, for every parameter. */
static void test_bounds_inclusive(void)
{
    for (size_t i = 0; i < PMA_PARAM_COUNT; ++i) {
        const pma_param_desc_t *d = &pma_param_table[i];
        pma_params_defaults(&p);
        pma_param_type_t t;
        pma_param_value_t v;
        assert_status(pma_param_set(&p, d->id, (pma_param_type_t)d->type, d->min,
                                    PMA_PHASE_INACTIVE), PMA_OK);
        assert_status(pma_param_get(&p, d->id, &t, &v), PMA_OK);
        TEST_ASSERT_EQUAL_INT(d->min.u32, v.u32);
        assert_status(pma_param_set(&p, d->id, (pma_param_type_t)d->type, d->max,
                                    PMA_PHASE_INACTIVE), PMA_OK);
        assert_status(pma_param_get(&p, d->id, &t, &v), PMA_OK);
        TEST_ASSERT_EQUAL_INT(d->max.u32, v.u32);
    }
}

/* Just below min and just above max, NaN and infinities, wrong types: every
 * parameter, every phase; nothing changes. */
static void test_rejections_change_nothing(void)
{
    pma_params_defaults(&p);
    /* a non-default set, so "unchanged" is not "defaults" */
    p.ppc_c = 5.0f;
    p.telem_mask = 3u;
    p.act_polarity = -1;
    uint32_t checked = 0;
    for (size_t i = 0; i < PMA_PARAM_COUNT; ++i) {
        const pma_param_desc_t *d = &pma_param_table[i];
        const pma_param_type_t type = (pma_param_type_t)d->type;
        for (size_t k = 0; k < sizeof phases / sizeof phases[0]; ++k) {
            const pma_param_phase_t ph = phases[k];
            switch (type) {
            case PMA_PARAM_F32:
                reject(d->id, type, vf(nextafterf(d->min.f32, -INFINITY)), ph, PMA_ERR_RANGE);
                reject(d->id, type, vf(nextafterf(d->max.f32, INFINITY)), ph, PMA_ERR_RANGE);
                reject(d->id, type, vf(NAN), ph, PMA_ERR_NOT_FINITE);
                reject(d->id, type, vf(-NAN), ph, PMA_ERR_NOT_FINITE);
                reject(d->id, type, vf(INFINITY), ph, PMA_ERR_NOT_FINITE);
                reject(d->id, type, vf(-INFINITY), ph, PMA_ERR_NOT_FINITE);
                reject(d->id, PMA_PARAM_U32, d->def, ph, PMA_ERR_TYPE);
                reject(d->id, PMA_PARAM_I32, d->def, ph, PMA_ERR_TYPE);
                break;
            case PMA_PARAM_U32:
                if (d->min.u32 > 0) reject(d->id, type, vu(d->min.u32 - 1u), ph, PMA_ERR_RANGE);
                TEST_ASSERT_LESS_THAN(UINT32_MAX, d->max.u32);
                reject(d->id, type, vu(d->max.u32 + 1u), ph, PMA_ERR_RANGE);
                reject(d->id, type, vu(UINT32_MAX), ph, PMA_ERR_RANGE);
                reject(d->id, PMA_PARAM_F32, d->def, ph, PMA_ERR_TYPE);
                reject(d->id, PMA_PARAM_I32, d->def, ph, PMA_ERR_TYPE);
                break;
            default:
                reject(d->id, type, vi(d->min.i32 - 1), ph, PMA_ERR_RANGE);
                reject(d->id, type, vi(d->max.i32 + 1), ph, PMA_ERR_RANGE);
                reject(d->id, type, vi(INT32_MIN), ph, PMA_ERR_RANGE);
                reject(d->id, PMA_PARAM_F32, d->def, ph, PMA_ERR_TYPE);
                reject(d->id, PMA_PARAM_U32, d->def, ph, PMA_ERR_TYPE);
                break;
            }
            reject(d->id, (pma_param_type_t)3, d->def, ph, PMA_ERR_TYPE);
            ++checked;
        }
    }
    TEST_ASSERT_EQUAL_INT(3u * PMA_PARAM_COUNT, checked);
    static const uint16_t unknown[] = {0, 7, 170, 0xFFFF};
    for (size_t i = 0; i < sizeof unknown / sizeof unknown[0]; ++i) {
        reject(unknown[i], PMA_PARAM_F32, vf(1.0f), PMA_PHASE_INACTIVE, PMA_ERR_UNKNOWN_ID);
        reject(unknown[i], PMA_PARAM_U32, vu(1u), PMA_PHASE_INACTIVE, PMA_ERR_UNKNOWN_ID);
    }
}

/* Access classes: live in every phase, stopped not while RUNNING, idle only
 * while inactive; a refused set (PMA_ERR_STATE) changes nothing. */
static void test_access_by_phase(void)
{
    uint32_t refused = 0, accepted = 0;
    uint32_t per_class[3] = {0, 0, 0};
    for (size_t i = 0; i < PMA_PARAM_COUNT; ++i) {
        const pma_param_desc_t *d = &pma_param_table[i];
        per_class[d->access]++;
        for (size_t k = 0; k < sizeof phases / sizeof phases[0]; ++k) {
            pma_params_defaults(&p);
            /* a valid value other than the default when there is one */
            pma_param_value_t v = d->def.u32 == d->max.u32 ? d->min : d->max;
            if (allowed(d->access, phases[k])) {
                assert_status(pma_param_set(&p, d->id, (pma_param_type_t)d->type, v, phases[k]),
                              PMA_OK);
                pma_param_type_t t;
                pma_param_value_t got;
                assert_status(pma_param_get(&p, d->id, &t, &got), PMA_OK);
                TEST_ASSERT_EQUAL_INT(v.u32, got.u32);
                ++accepted;
            } else {
                reject(d->id, (pma_param_type_t)d->type, v, phases[k], PMA_ERR_STATE);
                ++refused;
            }
        }
    }
    /* each class is populated, so each rule was exercised */
    TEST_ASSERT_TRUE(per_class[PMA_PARAM_LIVE] > 0 && per_class[PMA_PARAM_STOPPED] > 0 &&
                per_class[PMA_PARAM_IDLE] > 0);
    TEST_ASSERT_EQUAL_INT(per_class[PMA_PARAM_STOPPED] + 2u * per_class[PMA_PARAM_IDLE], refused);
    TEST_ASSERT_EQUAL_INT(3u * PMA_PARAM_COUNT, accepted + refused);
    /* spot checks against params.toml */
    TEST_ASSERT_EQUAL_INT(PMA_PARAM_IDLE, pma_param_find(PMA_PARAM_SAFETY_X_MAX_CM)->access);
    TEST_ASSERT_EQUAL_INT(PMA_PARAM_STOPPED, pma_param_find(PMA_PARAM_CTRL_MODE)->access);
    TEST_ASSERT_EQUAL_INT(PMA_PARAM_LIVE, pma_param_find(PMA_PARAM_CTRL_OPENLOOP_U)->access);
}

/* The parameter API (app.h) as a second transport would call it: the same
 * policy as PARAM_REQ, and not one frame sent. */
static void test_parameter_api_without_frames(void)
{
    start_with(0, -1.5f);
    cap_clear();
    pma_param_value_t v = {.u32 = 500};
    assert_status(pma_app_param_set(&app, PMA_PARAM_SYS_TICK_HZ, PMA_PARAM_U32, v), PMA_OK);
    TEST_ASSERT_EQUAL_UINT32(2000u, app.timing.period_us);            /* the new tick period at once */
    TEST_ASSERT_EQUAL_INT(1, app.storage.params_changed);
    pma_param_type_t t = PMA_PARAM_F32;
    pma_param_value_t got = {.u32 = 0};
    assert_status(pma_app_param_get(&app, PMA_PARAM_SYS_TICK_HZ, &t, &got), PMA_OK);
    TEST_ASSERT_EQUAL_INT(PMA_PARAM_U32, t);
    TEST_ASSERT_EQUAL_UINT32(500u, got.u32);
    /* refusals change nothing: an unknown id, a wrong type, a rule between parameters */
    const pma_params_t before = app.params;
    assert_status(pma_app_param_set(&app, 999u, PMA_PARAM_U32, v), PMA_ERR_UNKNOWN_ID);
    assert_status(pma_app_param_set(&app, PMA_PARAM_SYS_TICK_HZ, (pma_param_type_t)7, v), PMA_ERR_TYPE);
    pma_param_value_t zero = {.f32 = 0.0f};
    assert_status(pma_app_param_set(&app, PMA_PARAM_ADC_GAIN_CM_PER_COUNT, PMA_PARAM_F32, zero),
                  PMA_ERR_RANGE);
    TEST_ASSERT_EQUAL_INT(PMA_RULE_ADC_GAIN, app.last_rule);
    TEST_ASSERT_EQUAL_MEMORY(&before, &app.params, sizeof before);
    uint32_t rule = 0;
    assert_status(pma_app_status_value(&app, PMA_STATUS_LAST_RULE, &rule), PMA_OK);
    TEST_ASSERT_EQUAL_UINT32(PMA_RULE_ADC_GAIN, rule);
    assert_status(pma_app_status_value(&app, 0xFFFFu, &rule), PMA_ERR_UNKNOWN_ID);
    /* the whole set: no storage attached here; the defaults back, the timing with them */
    assert_status(pma_app_params_save(&app), PMA_ERR_NOT_IMPLEMENTED);
    assert_status(pma_app_params_restore_defaults(&app), PMA_OK);
    TEST_ASSERT_EQUAL_UINT32(T_PERIOD_US, app.timing.period_us);
    drain();
    TEST_ASSERT_EQUAL_INT(0, cap.total);                        /* nothing on the bus */
    /* not while the output is active */
    to_armed(0);
    assert_status(pma_app_params_restore_defaults(&app), PMA_ERR_STATE);
    assert_status(pma_app_params_load(&app), PMA_ERR_STATE);
}

static void test_next_id_enumerates_in_order(void)
{
    uint16_t id = 0, next = 0;
    size_t n = 0;
    while (pma_param_next_id(id, &next) == PMA_OK) {
        TEST_ASSERT_LESS_THAN(PMA_PARAM_COUNT, n);
        TEST_ASSERT_GREATER_THAN(id, next);
        TEST_ASSERT_EQUAL_INT(pma_param_table[n].id, next); /* every id once, in order */
        id = next;
        ++n;
    }
    TEST_ASSERT_EQUAL_INT(PMA_PARAM_COUNT, n);
    assert_status(pma_param_next_id(id, &next), PMA_ERR_EMPTY);
    assert_status(pma_param_next_id(0xFFFF, &next), PMA_ERR_EMPTY);
    /* from inside a gap and from an existing id */
    assert_status(pma_param_next_id(9, &next), PMA_OK); /* the gap after sys.plant_bridge (8) */
    TEST_ASSERT_EQUAL_INT(PMA_PARAM_CTRL_MODE, next);
    assert_status(pma_param_next_id(PMA_PARAM_CTRL_MODE, &next), PMA_OK);
    TEST_ASSERT_EQUAL_INT(PMA_PARAM_CTRL_U_MIN, next);
    assert_status(pma_param_next_id(0, NULL), PMA_ERR_NULL);
}

/* A set with every parameter away from its default where possible. */
static void non_default_set(pma_params_t *q)
{
    pma_params_defaults(q);
    for (size_t i = 0; i < PMA_PARAM_COUNT; ++i) {
        const pma_param_desc_t *d = &pma_param_table[i];
        const pma_param_value_t v = d->def.u32 == d->max.u32 ? d->min : d->max;
        assert_status(pma_param_set(q, d->id, (pma_param_type_t)d->type, v, PMA_PHASE_INACTIVE),
                      PMA_OK);
    }
}

static uint8_t blob[PMA_PARAMS_BLOB_BYTES + 2u * PMA_PARAMS_ENTRY_BYTES];

static void put_entry(uint8_t *e, uint16_t id, uint32_t raw)
{
    e[0] = (uint8_t)id;
    e[1] = (uint8_t)(id >> 8);
    for (unsigned b = 0; b < 4u; ++b) e[2u + b] = (uint8_t)(raw >> (8u * b));
}

static void test_serialize_round_trip(void)
{
    non_default_set(&before);
    TEST_ASSERT_EQUAL_INT(PMA_PARAMS_BLOB_BYTES, pma_params_serialize(&before, blob, sizeof blob));
    TEST_ASSERT_EQUAL_INT(6u * PMA_PARAM_COUNT, PMA_PARAMS_BLOB_BYTES);
    /* layout: little-endian id, then the raw value */
    for (size_t i = 0; i < PMA_PARAM_COUNT; ++i) {
        const uint8_t *e = blob + i * PMA_PARAMS_ENTRY_BYTES;
        TEST_ASSERT_EQUAL_INT(pma_param_table[i].id, e[0] | (e[1] << 8));
    }
    const uint8_t *e = blob; /* sys.node_id = max 15 */
    TEST_ASSERT_TRUE(e[2] == 15u && e[3] == 0 && e[4] == 0 && e[5] == 0);
    memset(&p, 0, sizeof p);
    TEST_ASSERT_EQUAL_INT(0, pma_params_deserialize(&p, blob, PMA_PARAMS_BLOB_BYTES));
    TEST_ASSERT_EQUAL_MEMORY(&before, &p, sizeof p);
    /* capacity too small: nothing written */
    TEST_ASSERT_EQUAL_INT(0, pma_params_serialize(&before, blob, PMA_PARAMS_BLOB_BYTES - 1u));
    TEST_ASSERT_EQUAL_INT(0, pma_params_serialize(NULL, blob, sizeof blob));
    TEST_ASSERT_EQUAL_INT(0, pma_params_serialize(&before, NULL, sizeof blob));
}

static void test_deserialize_skips_unknown_ids(void)
{
    non_default_set(&before);
    TEST_ASSERT_EQUAL_INT(PMA_PARAMS_BLOB_BYTES, pma_params_serialize(&before, blob, sizeof blob));
    /* a newer firmware's parameters, one at the front and one at the end */
    memmove(blob + PMA_PARAMS_ENTRY_BYTES, blob, PMA_PARAMS_BLOB_BYTES);
    put_entry(blob, 6, 0xDEADBEEFu);
    put_entry(blob + PMA_PARAMS_BLOB_BYTES + PMA_PARAMS_ENTRY_BYTES, 999, 1u);
    TEST_ASSERT_EQUAL_INT(0, pma_params_deserialize(&p, blob, sizeof blob));
    TEST_ASSERT_EQUAL_MEMORY(&before, &p, sizeof p);
}

static void test_deserialize_rejects_to_default(void)
{
    non_default_set(&before);
    TEST_ASSERT_EQUAL_INT(PMA_PARAMS_BLOB_BYTES, pma_params_serialize(&before, blob, sizeof blob));
    /* entry 1: sys.tick_hz = 10 (below 50); ppc.c NaN; act.polarity 2; u32 far above */
    size_t i_tick = 1, i_c = 0, i_pol = 0, i_mask = 4;
    for (size_t i = 0; i < PMA_PARAM_COUNT; ++i) {
        if (pma_param_table[i].id == PMA_PARAM_PPC_C) i_c = i;
        if (pma_param_table[i].id == PMA_PARAM_ACT_POLARITY) i_pol = i;
    }
    TEST_ASSERT_EQUAL_INT(PMA_PARAM_SYS_TICK_HZ, pma_param_table[i_tick].id);
    TEST_ASSERT_EQUAL_INT(PMA_PARAM_TELEM_MASK, pma_param_table[i_mask].id);
    pma_param_value_t nan;
    nan.f32 = NAN;
    put_entry(blob + i_tick * 6u, PMA_PARAM_SYS_TICK_HZ, 10u);
    put_entry(blob + i_c * 6u, PMA_PARAM_PPC_C, nan.u32);
    put_entry(blob + i_pol * 6u, PMA_PARAM_ACT_POLARITY, 2u);
    put_entry(blob + i_mask * 6u, PMA_PARAM_TELEM_MASK, 32u);
    TEST_ASSERT_EQUAL_INT(4, pma_params_deserialize(&p, blob, PMA_PARAMS_BLOB_BYTES));
    TEST_ASSERT_EQUAL_INT(1000u, p.sys_tick_hz);       /* defaults */
    TEST_ASSERT_TRUE(p.ppc_c == 2.0f);
    TEST_ASSERT_EQUAL_INT(1, p.act_polarity);
    TEST_ASSERT_EQUAL_INT(31u, p.telem_mask);
    /* the rest as stored */
    before.sys_tick_hz = 1000u;
    before.ppc_c = 2.0f;
    before.act_polarity = 1;
    before.telem_mask = 31u;
    TEST_ASSERT_EQUAL_MEMORY(&before, &p, sizeof p);
}

static void test_deserialize_partial_and_bad_length(void)
{
    non_default_set(&before);
    TEST_ASSERT_EQUAL_INT(PMA_PARAMS_BLOB_BYTES, pma_params_serialize(&before, blob, sizeof blob));
    /* only the first three entries: the rest keep their defaults */
    TEST_ASSERT_EQUAL_INT(0, pma_params_deserialize(&p, blob, 3u * PMA_PARAMS_ENTRY_BYTES));
    TEST_ASSERT_EQUAL_INT(before.sys_node_id, p.sys_node_id);
    TEST_ASSERT_EQUAL_INT(before.sys_tick_hz, p.sys_tick_hz);
    TEST_ASSERT_EQUAL_INT(before.sys_heartbeat_ms, p.sys_heartbeat_ms);
    TEST_ASSERT_EQUAL_INT(10u, p.telem_decimation);
    TEST_ASSERT_TRUE(p.safety_safe_kpa == 0.0f);
    /* empty: defaults */
    pma_params_t def;
    pma_params_defaults(&def);
    TEST_ASSERT_EQUAL_INT(0, pma_params_deserialize(&p, blob, 0));
    TEST_ASSERT_EQUAL_MEMORY(&def, &p, sizeof p);
    /* not a whole number of entries: PMA_ERR_RANGE and the defaults */
    static const size_t bad[] = {1, 5, 7, PMA_PARAMS_BLOB_BYTES - 1u, PMA_PARAMS_BLOB_BYTES + 1u};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        memset(&p, 0x5A, sizeof p);
        assert_status(pma_params_deserialize(&p, blob, bad[i]), PMA_ERR_RANGE);
        TEST_ASSERT_EQUAL_MEMORY(&def, &p, sizeof p);
    }
    assert_status(pma_params_deserialize(NULL, blob, 6), PMA_ERR_NULL);
    assert_status(pma_params_deserialize(&p, NULL, 6), PMA_ERR_NULL);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_table_is_sorted_and_consistent);
    RUN_TEST(test_find_unknown_ids);
    RUN_TEST(test_defaults_equal_table);
    RUN_TEST(test_get_set_each_type);
    RUN_TEST(test_bounds_inclusive);
    RUN_TEST(test_rejections_change_nothing);
    RUN_TEST(test_access_by_phase);
    RUN_TEST(test_next_id_enumerates_in_order);
    RUN_TEST(test_serialize_round_trip);
    RUN_TEST(test_deserialize_skips_unknown_ids);
    RUN_TEST(test_deserialize_rejects_to_default);
    RUN_TEST(test_deserialize_partial_and_bad_length);
    RUN_TEST(test_parameter_api_without_frames);
    return UNITY_END();
}
