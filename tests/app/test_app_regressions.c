/* SPDX-License-Identifier: Apache-2.0 */
/* Regression tests: bugs found in firmware/app by the test review, one test
 * each, with what was wrong (the line numbers refer to the code before the
 * fix) and how it was fixed. They failed before the fixes. */
/* 16-byte blocks: room for a blob 5 entries longer than this firmware's and the record's 20 bytes (BUG 3) */
#define T_NVM_BPS ((PMA_PARAMS_BLOB_BYTES + 5u * PMA_PARAMS_ENTRY_BYTES + 20u + 15u) / 16u)
#include "app_test.h"

#include "pstore.h"

/* WAS BUG 1: the safe output while the output is inactive can exceed the
 * actuator's pressure limit.
 * safety.safe_kpa (0..1000) is only checked against act.p_max_kpa at ARM
 * (pma_actuator_validate), but IDLE and FAULT put the FIXED safe pressure out
 * unchecked (actuator.c:33-34, used by app.c:309): with act.p_max_kpa = 600
 * and safety.safe_kpa = 1000 an idle node commands 1000 kPa (DAC clipped at
 * 4095 counts = 900 kPa) the moment the parameter is set.
 * Fix: clamp the FIXED pressure to [0, p_max] in pma_actuator_safe_kpa (or
 * vent when the configuration is invalid), or refuse the SET. */
static void test_was_bug_fixed_safe_pressure_above_p_max(void)
{
    to_idle(0);
    set_u32(PMA_PARAM_SAFETY_SAFE_MODE, PMA_SAFETY_SAFE_MODE_FIXED);
    set_f32(PMA_PARAM_SAFETY_SAFE_KPA, 1000.0f); /* accepted: within its own range */
    step();
    const uint16_t limit = dac_counts_of(app.params.act_p_max_kpa); /* 2730 */
    const uint16_t out = dac_now();
    printf("idle output %u counts, act.p_max_kpa is %u counts\n", out, limit);
    TEST_ASSERT_LESS_OR_EQUAL(limit, out);
}

/* WAS BUG 2: an invalid DAC scaling set in the same step as DISARM (or ESTOP)
 * freezes the last ACTIVE pressure on the output instead of the safe one.
 * app.c:314 keeps the previous counts when pma_dac_kpa_to_counts() fails
 * (dac.counts_per_kpa = 0 or dac.min_counts > dac.max_counts are settable
 * while inactive), and app.c:319 writes them: the node reports IDLE / FAULT
 * (OutputActive 0) while the regulator stays at 300 kPa.
 * Fix: when the conversion fails while the output is inactive, write a fixed
 * safe code (e.g. 0 counts, or the counts of the last valid safe value), or
 * validate the dac.* parameters as a set at SET time. */
static void test_was_bug_invalid_dac_scaling_keeps_active_output_after_disarm(void)
{
    to_armed(0);
    TEST_ASSERT_EQUAL_INT(T_P0_COUNTS, dac_now());
    inject(PMA_PROTO_COMMAND_FRAME_ID, 2, (const uint8_t[]){PMA_CMD_DISARM, 0});
    struct pma_proto_param_req_t m;
    memset(&m, 0, sizeof m);
    m.op = PMA_PARAM_OP_SET;
    m.type = PMA_PARAM_F32;
    m.id = PMA_PARAM_DAC_COUNTS_PER_KPA;
    m.value_f32 = 0.0f;
    uint8_t d[8];
    TEST_ASSERT_EQUAL_INT(8, pma_proto_param_req_pack(d, &m, sizeof d));
    inject(PMA_PROTO_PARAM_REQ_FRAME_ID, 8, d);
    cap_clear();
    step();
    assert_state(app.state, PMA_STATE_IDLE);
    /* fixed: the scalings are kept valid at every SET */
    assert_status(decode_param_resp(last_frame(PMA_PROTO_PARAM_RESP_FRAME_ID)).result, PMA_ERR_RANGE);
    steps(5);
    const uint16_t out = dac_now();
    printf("IDLE (VENT) output: %u counts\n", out);
    TEST_ASSERT_EQUAL_INT(0, out);
}

static void test_was_bug_invalid_dac_scaling_keeps_active_output_after_estop(void)
{
    to_running(0);
    const pma_can_frame_t e = frame_of(PMA_PROTO_ESTOP_FRAME_ID, T_NODE, 0, NULL);
    assert_status(pma_fake_can_inject(&e), PMA_OK);
    struct pma_proto_param_req_t m;
    memset(&m, 0, sizeof m);
    m.op = PMA_PARAM_OP_SET;
    m.type = PMA_PARAM_U32;
    m.id = PMA_PARAM_DAC_MIN_COUNTS;
    m.value_u32 = 5000; /* above dac.max_counts */
    uint8_t d[8];
    TEST_ASSERT_EQUAL_INT(8, pma_proto_param_req_pack(d, &m, sizeof d));
    inject(PMA_PROTO_PARAM_REQ_FRAME_ID, 8, d);
    cap_clear();
    step();
    assert_state(app.state, PMA_STATE_FAULT);
    const uint16_t out = dac_now();
    printf("FAULT (VENT) output: %u counts\n", out);
    TEST_ASSERT_EQUAL_INT(0, out);
}

/* WAS BUG 3: a stored parameter set longer than this firmware's blob (written by
 * a firmware with more parameters, e.g. after a downgrade) is not loaded at
 * all, although params.h promises "unknown ids are skipped".
 * app.c:122 loads into uint8_t blob[PMA_PARAMS_BLOB_BYTES] (390 bytes), so
 * pma_pstore_load() returns PMA_ERR_RANGE for a 420-byte record (70 entries)
 * and the node starts on the defaults.
 * Fix: load into a PMA_PSTORE_MAX_BLOB_BYTES buffer (the record's own limit)
 * and let pma_params_deserialize() skip the unknown ids. */
static pma_pstore_t ps;

/* Stores the defaults with ppc.c = 5, telem.mask = 7 and five entries of
 * ids this firmware does not know (200..204), as a newer firmware would. Its
 * own frame holds the blob (the Cortex-M0 has no room for it in
 * .bss), released before the restart. */
static void store_longer_blob(void)
{
    uint8_t big[PMA_PARAMS_BLOB_BYTES + 5u * PMA_PARAMS_ENTRY_BYTES];
    pma_params_t p;
    pma_params_defaults(&p);
    p.ppc_c = 5.0f;
    p.telem_mask = 7u;
    TEST_ASSERT_EQUAL_INT(PMA_PARAMS_BLOB_BYTES, pma_params_serialize(&p, big, sizeof big));
    for (unsigned i = 0; i < 5u; ++i) {
        uint8_t *e = big + PMA_PARAMS_BLOB_BYTES + i * PMA_PARAMS_ENTRY_BYTES;
        e[0] = (uint8_t)(200u + i);
        e[1] = 0;
        e[2] = 1;
        e[3] = e[4] = e[5] = 0;
    }
    /* the parser itself accepts it */
    TEST_ASSERT_EQUAL_INT(0, pma_params_deserialize(&p, big, sizeof big));
    TEST_ASSERT_TRUE(p.ppc_c == 5.0f);
    assert_status(pma_pstore_init(&ps, T_FIRST, T_BPS), PMA_OK);
    assert_status(pma_pstore_save(&ps, big, sizeof big, PMA_PARAMS_BLOB_VERSION), PMA_OK);
}

static void test_was_bug_longer_stored_blob_not_loaded(void)
{
    start_with(0, -1.5f);
    store_longer_blob();
    pma_fake_reboot();
    assert_status(restart_app(), PMA_OK);
    printf("after restart: ppc.c %g, telem.mask %lu, params_default %u\n",
           (double)app.params.ppc_c, (unsigned long)app.params.telem_mask,
           app.storage.params_default);
    TEST_ASSERT_TRUE(app.params.ppc_c == 5.0f);
    TEST_ASSERT_EQUAL_INT(7u, app.params.telem_mask);
    TEST_ASSERT_EQUAL_INT(0, app.storage.params_default);
}

/* WAS BUG 4: plant bridge: ARM is accepted with a sample far older than
 * safety.sensor_timeout_ticks, and the node faults SENSOR_TIMEOUT at the very
 * next tick. cmd_arm (app.c:184) only looks at sensor_status, which stays
 * PMA_OK for a repeated (stale) sample; the age is checked only once the
 * output is active.
 * Fix: in cmd_arm, refuse (PMA_ERR_NOT_READY) when plant_bridge and
 * ticks_since_sample >= safety.sensor_timeout_ticks. */
static void test_was_bug_arm_accepted_with_stale_bridge_sample(void)
{
    to_idle(1);
    steps(50); /* the rig stopped sending 50 ticks ago (timeout: 10) */
    const struct pma_proto_command_ack_t a = command(PMA_CMD_ARM, 0);
    printf("ARM with a 51-tick-old sample: %s, then %s fault %s\n",
           pma_status_name(a.result), pma_app_state_name(app.state),
           pma_fault_name(app.fault));
    assert_status(a.result, PMA_ERR_NOT_READY);
    assert_state(app.state, PMA_STATE_IDLE);
}

/* WAS BUG 5: HOLD safe mode with a non-finite u vents instead of holding.
 * actuator.h: "A non-finite u or previous pressure gives the safe pressure";
 * for HOLD that is the previous command, but actuator.c:43 passes 0.0f as
 * the previous pressure to pma_actuator_safe_kpa(), so HOLD returns 0 kPa.
 * (In the application the supervisor faults on the NaN first, so this shows
 * in the pure function only.)
 * Fix: return pma_actuator_safe_kpa(c, p_prev_kpa) (it already maps a
 * non-finite p_prev to 0). */
static void test_was_bug_hold_with_nan_u_vents(void)
{
    const pma_actuator_config_t ac = {
        .p0_kpa = 300.0f, .kpa_per_u = 1.0f, .polarity = 1, .p_min_kpa = 0.0f,
        .p_max_kpa = 600.0f, .slew_kpa_s = 20000.0f, .safe_mode = PMA_SAFE_HOLD,
        .safe_kpa = 0.0f,
    };
    assert_near(pma_actuator_active_kpa(&ac, NAN, 450.0f, 1e-3f), 450.0f, 0.0);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_was_bug_fixed_safe_pressure_above_p_max);
    RUN_TEST(test_was_bug_invalid_dac_scaling_keeps_active_output_after_disarm);
    RUN_TEST(test_was_bug_invalid_dac_scaling_keeps_active_output_after_estop);
    RUN_TEST(test_was_bug_longer_stored_blob_not_loaded);
    RUN_TEST(test_was_bug_arm_accepted_with_stale_bridge_sample);
    RUN_TEST(test_was_bug_hold_with_nan_u_vents);
    return UNITY_END();
}
