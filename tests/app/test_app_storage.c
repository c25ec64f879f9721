/* SPDX-License-Identifier: Apache-2.0 */
/* Parameter storage through the protocol: SET then SAVE then a restart
 * (watchdog/software reboot or power-on, on the same fake NVM) loads the saved
 * set; a power cut at every single NVM operation of a SAVE (applied 0 %, 50 %
 * or 100 %, plain and ECC flash, with 0, 1 or 2 records stored before)
 * followed by power-on gives exactly the old or exactly the new set, never a
 * mix, never the defaults once a set was saved; SAVE refused while ARMED and
 * RUNNING; LOAD restores the saved set; the heartbeat flags PARAMS_CHANGED,
 * PARAMS_DEFAULT, SAVE_FAILED; stored records that are corrupt, of another
 * blob version or holding a value out of range. */
/* the smallest slot of 16-byte blocks that holds this firmware's blob and the record's 20 bytes */
#define T_NVM_BPS ((PMA_PARAMS_BLOB_BYTES + 20u + 15u) / 16u)
#include "app_test.h"

#include "pstore.h"

/* The parameter sets, by CRC-32 (no room on the Cortex-M0 for copies). */
static uint32_t set_a0, set_a, set_b, defaults;
static pma_pstore_t ps;

static uint32_t default_crc(void)
{
    pma_params_t d;
    pma_params_defaults(&d);
    return params_crc(&d);
}

/* Three parameter sets, set through PARAM_REQ (one of each type, live,
 * stopped and idle parameters); each ends with the set in *out. */
static void apply_a0(uint32_t *out)
{
    set_f32(PMA_PARAM_PPC_C, 1.5f);
    set_u32(PMA_PARAM_TELEM_DECIMATION, 5);
    *out = params_crc(&app.params);
}

static void apply_a(uint32_t *out)
{
    set_f32(PMA_PARAM_PPC_C, 3.0f);
    set_u32(PMA_PARAM_TELEM_DECIMATION, 20);
    set_i32(PMA_PARAM_ACT_POLARITY, -1);
    set_f32(PMA_PARAM_SAFETY_SAFE_KPA, 50.0f);
    set_f32(PMA_PARAM_REF_OFFSET_CM, -1.25f);
    set_u32(PMA_PARAM_CTRL_MODE, PMA_CTRL_MODE_PID);
    set_u32(PMA_PARAM_SYS_HEARTBEAT_MS, 200);
    *out = params_crc(&app.params);
}

static void apply_b(uint32_t *out)
{
    set_f32(PMA_PARAM_PPC_C, 4.0f);
    set_u32(PMA_PARAM_TELEM_DECIMATION, 30);
    set_i32(PMA_PARAM_ACT_POLARITY, 1);
    set_f32(PMA_PARAM_SAFETY_SAFE_KPA, 60.0f);
    set_f32(PMA_PARAM_REF_OFFSET_CM, -1.75f);
    set_u32(PMA_PARAM_CTRL_MODE, PMA_CTRL_MODE_MFAC);
    set_u32(PMA_PARAM_SYS_HEARTBEAT_MS, 300);
    set_f32(PMA_PARAM_MFAC_RHO, 20.0f);
    set_f32(PMA_PARAM_SAFETY_X_MIN_CM, -2.5f);
    *out = params_crc(&app.params);
}

static bool params_are(const uint32_t *want)
{
    return params_crc(&app.params) == *want;
}

static void save_ok(void)
{
    assert_status(whole_op(PMA_PARAM_OP_SAVE), PMA_OK);
    TEST_ASSERT_EQUAL_INT(0, app.storage.save_failed);
}

/* -------------------------------------------------------------------------- */

static void test_save_then_restart_loads(void)
{
    defaults = default_crc();
    to_idle(0);
    TEST_ASSERT_EQUAL_INT(1, app.storage.params_default);
    apply_a(&set_a);
    set_u32(PMA_PARAM_SYS_TICK_HZ, 500);
    set_a = params_crc(&app.params);
    save_ok();
    /* a software reboot */
    pma_fake_reboot();
    assert_status(restart_app(), PMA_OK);
    TEST_ASSERT_TRUE(params_are(&set_a));
    struct pma_proto_heartbeat_t h = last_heartbeat(); /* the BOOT one */
    TEST_ASSERT_EQUAL_INT(PMA_RESET_SOFTWARE, h.reset_cause);
    TEST_ASSERT_EQUAL_INT(PMA_CTRL_MODE_PID, h.controller);
    TEST_ASSERT_FALSE(h.flags &
                      (PMA_HB_PARAMS_DEFAULT | PMA_HB_PARAMS_CHANGED | PMA_HB_SAVE_FAILED));
    /* the loaded timing is in force: 500 Hz ticks, heartbeat every 200 ms */
    uint64_t t0 = pma_hal_time_us();
    step();
    TEST_ASSERT_EQUAL_INT(2000u, pma_hal_time_us() - t0);
    (void)next_heartbeat();
    t0 = pma_hal_time_us();
    (void)next_heartbeat();
    TEST_ASSERT_EQUAL_INT(200000u, pma_hal_time_us() - t0);
    /* read back through GET as a host would */
    presp_t r = param_req(PMA_PARAM_OP_GET, 0, PMA_PARAM_ACT_POLARITY, vu(0));
    TEST_ASSERT_EQUAL_INT(-1, r.v.i32);
    r = param_req(PMA_PARAM_OP_GET, 0, PMA_PARAM_PPC_C, vu(0));
    TEST_ASSERT_TRUE(r.v.f32 == 3.0f);
    /* a power cycle */
    pma_fake_power_on();
    assert_status(restart_app(), PMA_OK);
    TEST_ASSERT_TRUE(params_are(&set_a));
    TEST_ASSERT_EQUAL_INT(PMA_RESET_POWER_ON, last_heartbeat().reset_cause);
    /* RESTORE_DEFAULTS is RAM only: the stored set comes back at the next start */
    assert_status(whole_op(PMA_PARAM_OP_RESTORE_DEFAULTS), PMA_OK);
    TEST_ASSERT_TRUE(params_are(&defaults));
    pma_fake_reboot();
    assert_status(restart_app(), PMA_OK);
    TEST_ASSERT_TRUE(params_are(&set_a));
    /* an unsaved SET is lost at a restart */
    set_f32(PMA_PARAM_PPC_C, 9.0f);
    pma_fake_reboot();
    assert_status(restart_app(), PMA_OK);
    TEST_ASSERT_TRUE(params_are(&set_a));
}

/* RESTART over CAN: refused with the output active; accepted with it safe, the
 * COMMAND_ACK sent first and the system reset requested at the end of that
 * step, every later command of the step but ESTOP refused; the node starts
 * again (reset cause SOFTWARE) with the saved set, the unsaved SET lost. */
static void test_restart_command(void)
{
    to_armed(1);
    command_ok(PMA_CMD_RESTART, 0, PMA_ERR_STATE);
    assert_state(app.state, PMA_STATE_ARMED);
    TEST_ASSERT_EQUAL_UINT32(0u, pma_fake_system_reset_requests());
    command_ok(PMA_CMD_DISARM, 0, PMA_OK);
    set_f32(PMA_PARAM_PPC_C, 6.0f);
    save_ok();
    set_f32(PMA_PARAM_PPC_C, 9.0f);                /* not saved */
    /* RESTART, then ARM and ESTOP before the step ends (handled as the step does) */
    static const uint8_t cmds[3][2] = {{PMA_CMD_RESTART, 0}, {PMA_CMD_ARM, 0}, {PMA_CMD_ESTOP, 0}};
    static const int want[3] = {PMA_OK, PMA_ERR_STATE, PMA_OK};
    for (int i = 0; i < 3; ++i) {
        const pma_can_frame_t f = frame_of(PMA_PROTO_COMMAND_FRAME_ID, T_NODE, 2, cmds[i]);
        cap_clear();
        pma_app_handle_frame(&app, &f);
        drain();
        TEST_ASSERT_EQUAL_INT(1, sent(PMA_PROTO_COMMAND_ACK_FRAME_ID));
        const pma_can_frame_t *r = last_frame(PMA_PROTO_COMMAND_ACK_FRAME_ID);
        struct pma_proto_command_ack_t ack;
        TEST_ASSERT_EQUAL_INT(0, pma_proto_command_ack_unpack(&ack, r->data, r->dlc));
        TEST_ASSERT_EQUAL_INT(cmds[i][0], ack.command);
        assert_status(ack.result, want[i]);
        TEST_ASSERT_EQUAL_UINT32(0u, pma_fake_system_reset_requests()); /* not before the step ends */
    }
    send_sample((uint8_t)(app.bridge.seq + 1u), counts_at(-1.5f));
    step();
    TEST_ASSERT_EQUAL_UINT32(1u, pma_fake_system_reset_requests());
    assert_state(app.state, PMA_STATE_FAULT);       /* the ESTOP; the output stayed safe */
    TEST_ASSERT_EQUAL_INT(0, app.restart_pending);
    /* the reset, as the board does it */
    pma_fake_reboot();
    assert_status(restart_app(), PMA_OK);
    TEST_ASSERT_EQUAL_UINT32(0u, pma_fake_system_reset_requests());
    const struct pma_proto_heartbeat_t h = last_heartbeat();
    TEST_ASSERT_EQUAL_INT(PMA_STATE_BOOT, h.state);
    TEST_ASSERT_EQUAL_INT(PMA_RESET_SOFTWARE, h.reset_cause);
    assert_state(app.state, PMA_STATE_IDLE);         /* a software reset is no fault */
    TEST_ASSERT_TRUE(app.params.ppc_c == 6.0f);
    /* from FAULT, too */
    command_ok(PMA_CMD_ESTOP, 0, PMA_OK);
    command_ok(PMA_CMD_RESTART, 0, PMA_OK);
    TEST_ASSERT_EQUAL_UINT32(1u, pma_fake_system_reset_requests());
}

/* sys.node_id takes effect at the next start-up (platform node id -1). */
static void test_saved_node_id(void)
{
    start_with(0, -1.5f);
    plat.node_id = -1;
    assert_status(pma_app_init(&app, &plat), PMA_OK);
    cap_clear();
    drain();
    TEST_ASSERT_EQUAL_INT(0, app.node_id);
    step();
    set_u32(PMA_PARAM_SYS_NODE_ID, 7);
    TEST_ASSERT_EQUAL_INT(0, app.node_id); /* not yet */
    save_ok();
    pma_fake_reboot();
    assert_status(restart_app(), PMA_OK);
    TEST_ASSERT_EQUAL_INT(7, app.node_id);
    TEST_ASSERT_EQUAL_HEX16(PMA_PROTO_HEARTBEAT_FRAME_ID | 7u,
                            last_frame(PMA_PROTO_HEARTBEAT_FRAME_ID)->id);
    /* node 0's frames no longer reach it; node 7's do */
    pma_can_frame_t f = frame_of(PMA_PROTO_COMMAND_FRAME_ID, 0, 2,
                                 (const uint8_t[]){PMA_CMD_ESTOP, 0});
    TEST_ASSERT_EQUAL_INT(PMA_FAKE_CAN_FILTERED, pma_fake_can_inject(&f));
    step();
    command_ok(PMA_CMD_ARM, 0, PMA_OK);
    assert_state(app.state, PMA_STATE_ARMED);
}

/* The power-cut sweep. scenario: 0 nothing stored before, 1 one record (A),
 * 2 two records (A0 then A). */
typedef struct tally {
    uint32_t cuts, old_sets, new_sets, defaults;
} tally_t;

static tally_t tally;

static void prepare(int scenario, bool ecc)
{
    start_with(0, -1.5f);
    pma_fake_nvm_ecc(ecc);
    step();
    if (scenario >= 2) {
        apply_a0(&set_a0);
        save_ok();
    }
    if (scenario >= 1) {
        apply_a(&set_a);
        save_ok();
    }
    apply_b(&set_b);
}

static void cut_once(int scenario, bool ecc, uint32_t op, uint32_t ops, uint32_t permille)
{
    prepare(scenario, ecc);
    pma_fake_nvm_cut_power(op, permille);
    const presp_t r = param_req(PMA_PARAM_OP_SAVE, 0, 0, vu(0));
    if (op < ops) {
        assert_status(r.result, PMA_ERR_IO);
        TEST_ASSERT_EQUAL_INT(1, app.storage.save_failed);
        TEST_ASSERT_EQUAL_INT(1, app.storage.params_changed);
        TEST_ASSERT_TRUE(pma_fake_nvm_power_lost());
    } else {
        assert_status(r.result, PMA_OK);
    }
    /* power fails and comes back */
    pma_fake_power_on();
    assert_status(restart_app(), PMA_OK);
    ++tally.cuts;
    const struct pma_proto_heartbeat_t h = last_heartbeat();
    if (params_are(&set_b)) {
        ++tally.new_sets;
        TEST_ASSERT_FALSE(h.flags & PMA_HB_PARAMS_DEFAULT);
    } else if (scenario >= 1 && params_are(&set_a)) {
        ++tally.old_sets;
        TEST_ASSERT_FALSE(h.flags & PMA_HB_PARAMS_DEFAULT);
    } else if (scenario == 0 && params_are(&defaults)) {
        ++tally.defaults;
        TEST_ASSERT_TRUE(h.flags & PMA_HB_PARAMS_DEFAULT);
    } else {
        pma_test_fail("scenario %d%s: cut at op %lu of %lu, %lu permille: loaded neither the "
                      "old nor the new set (ppc.c %g, telem.decimation %lu)", scenario,
                      ecc ? " (ECC)" : "", (unsigned long)op, (unsigned long)ops,
                      (unsigned long)permille, (double)app.params.ppc_c,
                      (unsigned long)app.params.telem_decimation);
    }
    TEST_ASSERT_FALSE(h.flags & (PMA_HB_SAVE_FAILED | PMA_HB_PARAMS_CHANGED));
    /* storage works again: B saved and loaded */
    step();
    if (!params_are(&set_b)) apply_b(&set_b);
    save_ok();
    pma_fake_reboot();
    assert_status(restart_app(), PMA_OK);
    TEST_ASSERT_TRUE(params_are(&set_b));
}

static void sweep(int scenario)
{
    defaults = default_crc();
    memset(&tally, 0, sizeof tally);
    for (int e = 0; e < 2; ++e) {
        const bool ecc = e != 0;
        /* the operations of an uninterrupted SAVE from this state */
        prepare(scenario, ecc);
        const uint32_t before = pma_fake_nvm_op_count();
        save_ok();
        const uint32_t ops = pma_fake_nvm_op_count() - before;
        /* erases, programs */
        TEST_ASSERT_GREATER_OR_EQUAL(2u * ((PMA_PARAMS_BLOB_BYTES + 20u) / T_BLOCK), ops);
        static const uint32_t permilles[] = {0, 500, 1000};
        for (uint32_t op = 0; op <= ops; ++op) {
            for (size_t k = 0; k < sizeof permilles / sizeof permilles[0]; ++k) {
                cut_once(scenario, ecc, op, ops, permilles[k]);
            }
        }
    }
    printf("scenario %d: %lu power cuts: old set %lu, new set %lu, defaults %lu\n",
           scenario, (unsigned long)tally.cuts, (unsigned long)tally.old_sets,
           (unsigned long)tally.new_sets, (unsigned long)tally.defaults);
    TEST_ASSERT_GREATER_THAN(0, tally.new_sets);
    if (scenario == 0) {
        TEST_ASSERT_GREATER_THAN(0, tally.defaults);
        TEST_ASSERT_EQUAL_INT(0, tally.old_sets);
    } else {
        TEST_ASSERT_GREATER_THAN(0, tally.old_sets);
        TEST_ASSERT_EQUAL_INT(0, tally.defaults);
    }
}

static void test_power_cut_nothing_saved_before(void)
{
    sweep(0);
}

static void test_power_cut_one_record(void)
{
    sweep(1);
}

static void test_power_cut_two_records(void)
{
    sweep(2);
}

/* SAVE refused while the output is active: no NVM operation at all. */
static void test_save_refused_active(void)
{
    to_armed(0);
    set_f32(PMA_PARAM_PPC_C, 3.0f);
    const uint32_t ops = pma_fake_nvm_op_count();
    assert_status(whole_op(PMA_PARAM_OP_SAVE), PMA_ERR_STATE);
    command_ok(PMA_CMD_START, 0, PMA_OK);
    assert_status(whole_op(PMA_PARAM_OP_SAVE), PMA_ERR_STATE);
    TEST_ASSERT_EQUAL_INT(ops, pma_fake_nvm_op_count());
    TEST_ASSERT_EQUAL_INT(1, app.storage.params_changed);
    TEST_ASSERT_EQUAL_INT(0, app.storage.save_failed);
    command_ok(PMA_CMD_DISARM, 0, PMA_OK);
    save_ok();
    TEST_ASSERT_GREATER_THAN(ops, pma_fake_nvm_op_count());
}

/* Whole-set ops with storage: LOAD with nothing saved, SAVE, LOAD,
 * RESTORE_DEFAULTS (RAM only); SAVE allowed in FAULT. */
static void test_whole_set_ops(void)
{
    defaults = default_crc();
    to_idle(0);
    assert_status(whole_op(PMA_PARAM_OP_LOAD), PMA_ERR_NO_RECORD); /* nothing saved yet */
    TEST_ASSERT_TRUE(params_are(&defaults));
    set_f32(PMA_PARAM_PPC_C, 7.0f);
    set_u32(PMA_PARAM_TELEM_MASK, 1);
    save_ok();
    set_f32(PMA_PARAM_PPC_C, 9.0f);
    set_i32(PMA_PARAM_ACT_POLARITY, -1);
    assert_status(whole_op(PMA_PARAM_OP_LOAD), PMA_OK);
    TEST_ASSERT_TRUE(app.params.ppc_c == 7.0f);
    TEST_ASSERT_EQUAL_INT(1, app.params.telem_mask);
    TEST_ASSERT_EQUAL_INT(1, app.params.act_polarity);
    assert_status(whole_op(PMA_PARAM_OP_RESTORE_DEFAULTS), PMA_OK);
    TEST_ASSERT_TRUE(params_are(&defaults));
    assert_status(whole_op(PMA_PARAM_OP_LOAD), PMA_OK);
    TEST_ASSERT_TRUE(app.params.ppc_c == 7.0f);
    /* in FAULT (output safe) SAVE works */
    command_ok(PMA_CMD_ESTOP, 0, PMA_OK);
    set_f32(PMA_PARAM_PPC_C, 8.0f);
    save_ok();
    pma_fake_reboot();
    assert_status(restart_app(), PMA_OK);
    TEST_ASSERT_TRUE(app.params.ppc_c == 8.0f);
}

/* LOAD brings back the stored set, clears PARAMS_CHANGED; refused while ARMED. */
static void test_load_restores_saved_set(void)
{
    to_idle(0);
    apply_a(&set_a);
    save_ok();
    apply_b(&set_b);
    TEST_ASSERT_EQUAL_INT(1, app.storage.params_changed);
    assert_status(whole_op(PMA_PARAM_OP_LOAD), PMA_OK);
    TEST_ASSERT_TRUE(params_are(&set_a));
    TEST_ASSERT_EQUAL_INT(0, app.storage.params_changed);
    TEST_ASSERT_EQUAL_INT(0, app.storage.params_default);
    /* the loaded timing: heartbeat every 200 ms */
    (void)next_heartbeat();
    const uint64_t t0 = pma_hal_time_us();
    (void)next_heartbeat();
    TEST_ASSERT_EQUAL_INT(200000u, pma_hal_time_us() - t0);
    /* refused while ARMED: nothing changes */
    apply_b(&set_b);
    command_ok(PMA_CMD_ARM, 0, PMA_OK);
    assert_status(whole_op(PMA_PARAM_OP_LOAD), PMA_ERR_STATE);
    TEST_ASSERT_TRUE(params_are(&set_b));
    /* a storage read failure: the set in RAM stays */
    command_ok(PMA_CMD_DISARM, 0, PMA_OK);
    pma_fake_nvm_cut_power(0, 0);
    set_f32(PMA_PARAM_PPC_C, 1.0f); /* no NVM op */
    const uint32_t now = params_crc(&app.params);
    assert_status(pma_hal_nvm_erase(0), PMA_ERR_IO); /* the cut: the NVM is gone */
    TEST_ASSERT_LESS_THAN(0, whole_op(PMA_PARAM_OP_LOAD));
    TEST_ASSERT_TRUE(params_are(&now));
}

/* The heartbeat's storage flags. */
static void test_heartbeat_storage_flags(void)
{
    to_idle(0);
    struct pma_proto_heartbeat_t h = next_heartbeat();
    TEST_ASSERT_EQUAL_HEX16(PMA_HB_PARAMS_DEFAULT,
                            h.flags & (PMA_HB_PARAMS_DEFAULT | PMA_HB_PARAMS_CHANGED |
                                       PMA_HB_SAVE_FAILED));
    set_f32(PMA_PARAM_PPC_C, 3.0f);
    h = next_heartbeat();
    TEST_ASSERT_TRUE(h.flags & PMA_HB_PARAMS_CHANGED);
    save_ok();
    h = next_heartbeat();
    TEST_ASSERT_FALSE(h.flags & PMA_HB_PARAMS_CHANGED);
    TEST_ASSERT_TRUE(h.flags & PMA_HB_PARAMS_DEFAULT); /* storage held no record at start-up */
    /* a SELECT_* command changes a parameter too */
    command_ok(PMA_CMD_SELECT_REFERENCE, PMA_REF_KIND_SINE, PMA_OK);
    h = next_heartbeat();
    TEST_ASSERT_TRUE(h.flags & PMA_HB_PARAMS_CHANGED);
    /* a worn flash byte in slot B, where this SAVE goes (A holds the newest):
     * the read-back fails, SAVE_FAILED */
    pma_fake_nvm_stuck_byte(T_FIRST + T_BPS + 1u, 4, true); /* record byte 20 */
    assert_status(whole_op(PMA_PARAM_OP_SAVE), PMA_ERR_VERIFY);
    h = next_heartbeat();
    TEST_ASSERT_TRUE(h.flags & PMA_HB_SAVE_FAILED);
    TEST_ASSERT_TRUE(h.flags & PMA_HB_PARAMS_CHANGED);
    /* the previous record is still the one that loads */
    assert_status(whole_op(PMA_PARAM_OP_LOAD), PMA_OK);
    TEST_ASSERT_EQUAL_INT(PMA_REF_KIND_HOLD, app.params.ref_kind);
    /* repaired: the next SAVE clears it */
    pma_fake_nvm_stuck_byte(T_FIRST + T_BPS + 1u, 4, false);
    command_ok(PMA_CMD_SELECT_REFERENCE, PMA_REF_KIND_SINE, PMA_OK);
    save_ok();
    h = next_heartbeat();
    TEST_ASSERT_FALSE(h.flags & (PMA_HB_SAVE_FAILED | PMA_HB_PARAMS_CHANGED));
    /* restarted on the stored set: PARAMS_DEFAULT is gone */
    pma_fake_reboot();
    assert_status(restart_app(), PMA_OK);
    h = last_heartbeat();
    TEST_ASSERT_FALSE(h.flags &
                      (PMA_HB_PARAMS_DEFAULT | PMA_HB_PARAMS_CHANGED | PMA_HB_SAVE_FAILED));
    TEST_ASSERT_EQUAL_INT(PMA_REF_KIND_SINE, app.params.ref_kind);
    /* RESTORE_DEFAULTS: changed (the RAM set differs from the stored one) */
    assert_status(whole_op(PMA_PARAM_OP_RESTORE_DEFAULTS), PMA_OK);
    h = next_heartbeat();
    TEST_ASSERT_TRUE(h.flags & PMA_HB_PARAMS_CHANGED);
}

/* Records written with pstore directly, as another firmware or a damaged
 * flash would leave them: the blob of p, its first `len` bytes, with the
 * value of entry `patch_entry` (if below PMA_PARAM_COUNT) replaced by
 * patch_raw. Its own frame holds the blob, released before the restart. */
static void store_blob(const pma_params_t *p, size_t len, uint16_t version, size_t patch_entry,
                       uint32_t patch_raw)
{
    uint8_t blob[PMA_PARAMS_BLOB_BYTES];
    TEST_ASSERT_EQUAL_INT(PMA_PARAMS_BLOB_BYTES, pma_params_serialize(p, blob, sizeof blob));
    if (patch_entry < PMA_PARAM_COUNT) {
        uint8_t *e = blob + patch_entry * PMA_PARAMS_ENTRY_BYTES;
        for (unsigned b = 0; b < 4u; ++b) e[2u + b] = (uint8_t)(patch_raw >> (8u * b));
    }
    assert_status(pma_pstore_init(&ps, T_FIRST, T_BPS), PMA_OK);
    assert_status(pma_pstore_save(&ps, blob, len, version), PMA_OK);
}

static void test_stored_records_checked(void)
{
    defaults = default_crc();
    start_with(0, -1.5f);
    pma_params_t p;
    pma_params_defaults(&p);
    p.ppc_c = 5.0f;
    p.telem_mask = 7u;
    /* a stored value outside its (new) range: that one is the default */
    store_blob(&p, PMA_PARAMS_BLOB_BYTES, PMA_PARAMS_BLOB_VERSION, 1 /* sys.tick_hz */, 10u);
    pma_fake_reboot();
    assert_status(restart_app(), PMA_OK);
    TEST_ASSERT_TRUE(app.params.ppc_c == 5.0f);
    TEST_ASSERT_EQUAL_INT(7u, app.params.telem_mask);
    TEST_ASSERT_EQUAL_INT(1000u, app.params.sys_tick_hz);
    TEST_ASSERT_EQUAL_INT(0, app.storage.params_default);
    /* fewer entries (an older firmware's set): the rest are defaults */
    store_blob(&p, 10u * PMA_PARAMS_ENTRY_BYTES, PMA_PARAMS_BLOB_VERSION, PMA_PARAM_COUNT, 0);
    pma_fake_reboot();
    assert_status(restart_app(), PMA_OK);
    TEST_ASSERT_TRUE(app.params.ppc_c == 2.0f);      /* entry 10 and later: defaults */
    TEST_ASSERT_EQUAL_INT(7u, app.params.telem_mask); /* entry 4 */
    /* another blob version: not loaded */
    store_blob(&p, PMA_PARAMS_BLOB_BYTES, PMA_PARAMS_BLOB_VERSION + 1u, PMA_PARAM_COUNT, 0);
    pma_fake_reboot();
    assert_status(restart_app(), PMA_OK);
    TEST_ASSERT_TRUE(params_are(&defaults));
    TEST_ASSERT_TRUE(last_heartbeat().flags & PMA_HB_PARAMS_DEFAULT);
    /* a length that is no whole number of entries: defaults */
    store_blob(&p, PMA_PARAMS_BLOB_BYTES - 1u, PMA_PARAMS_BLOB_VERSION, PMA_PARAM_COUNT, 0);
    pma_fake_reboot();
    assert_status(restart_app(), PMA_OK);
    TEST_ASSERT_TRUE(params_are(&defaults));
    TEST_ASSERT_TRUE(last_heartbeat().flags & PMA_HB_PARAMS_DEFAULT);
}

/* A damaged newest record: the older one loads; both damaged: defaults. */
static void test_corrupt_record_falls_back(void)
{
    defaults = default_crc();
    to_idle(0);
    apply_a(&set_a);
    save_ok(); /* slot A */
    apply_b(&set_b);
    save_ok(); /* slot B, newest */
    pma_fake_reboot();
    assert_status(restart_app(), PMA_OK);
    TEST_ASSERT_TRUE(params_are(&set_b));
    nvm_mem[(T_FIRST + T_BPS) * T_BLOCK + 40u] ^= 0x01u; /* a bit of B's blob */
    pma_fake_reboot();
    assert_status(restart_app(), PMA_OK);
    TEST_ASSERT_TRUE(params_are(&set_a));
    TEST_ASSERT_FALSE(last_heartbeat().flags & PMA_HB_PARAMS_DEFAULT);
    nvm_mem[T_FIRST * T_BLOCK + 100u] ^= 0x80u;
    pma_fake_reboot();
    assert_status(restart_app(), PMA_OK);
    TEST_ASSERT_TRUE(params_are(&defaults));
    TEST_ASSERT_TRUE(last_heartbeat().flags & PMA_HB_PARAMS_DEFAULT);
    /* and a SAVE repairs it */
    step();
    apply_a(&set_a);
    save_ok();
    pma_fake_reboot();
    assert_status(restart_app(), PMA_OK);
    TEST_ASSERT_TRUE(params_are(&set_a));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_save_then_restart_loads);
    RUN_TEST(test_restart_command);
    RUN_TEST(test_saved_node_id);
    RUN_TEST(test_power_cut_nothing_saved_before);
    RUN_TEST(test_power_cut_one_record);
    RUN_TEST(test_power_cut_two_records);
    RUN_TEST(test_save_refused_active);
    RUN_TEST(test_whole_set_ops);
    RUN_TEST(test_load_restores_saved_set);
    RUN_TEST(test_heartbeat_storage_flags);
    RUN_TEST(test_stored_records_checked);
    RUN_TEST(test_corrupt_record_falls_back);
    return UNITY_END();
}
