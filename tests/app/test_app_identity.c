/* SPDX-License-Identifier: Apache-2.0 */
/* The node's identity on the wire (app_identity.c): DEVICE_INFO pages 0..4 in reply to
 * DEVICE_INFO_REQ and the broadcast DEVICE_INFO_REQ_ALL, their contents from the build, the DBC,
 * the parameter table and the platform's unique id; a request of the wrong length, or for
 * another node, is not answered; no state changes. */
#include "app_test.h"
#include "build_info.h"
#include "generated/pma_proto_version.h"

static const uint8_t uid[PMA_DEVICE_UID_BYTES] = {0x10, 0x21, 0x32, 0x43, 0x54, 0x65,
                                                  0x76, 0x87, 0x98, 0xA9, 0xBA, 0xCB};

static void start_node(void)
{
    pma_fake_reset();
    assert_status(pma_hal_init(NULL), PMA_OK);
    plat = platform(1);
    memcpy(plat.device_uid, uid, sizeof uid);
    assert_status(pma_app_init(&app, &plat), PMA_OK);
    pma_can_frame_t f;
    while (pma_fake_can_tx_pop(&f) == PMA_OK) {} /* the BOOT heartbeat */
}

/* One loop iteration; the DEVICE_INFO pages the node sent (other frames are skipped). */
static unsigned step_pages(struct pma_proto_device_info_t pages[8])
{
    assert_status(pma_app_step(&app), PMA_OK);
    unsigned n = 0;
    pma_can_frame_t f;
    while (pma_fake_can_tx_pop(&f) == PMA_OK) {
        if ((f.id & PMA_BASE_ID_MASK) != PMA_PROTO_DEVICE_INFO_FRAME_ID) continue;
        TEST_ASSERT_EQUAL_HEX16(PMA_PROTO_DEVICE_INFO_FRAME_ID | T_NODE, f.id);
        TEST_ASSERT_EQUAL_INT(PMA_PROTO_DEVICE_INFO_LENGTH, f.dlc);
        TEST_ASSERT_LESS_THAN_UINT(8u, n);
        TEST_ASSERT_EQUAL_INT(0, pma_proto_device_info_unpack(&pages[n], f.data, f.dlc));
        ++n;
    }
    return n;
}

/* DeviceTag of `uid`: CRC-8/SMBUS (polynomial 0x07, initial value 0) of its 12 bytes, 0x99,
 * from an independent implementation (pmactl.identity.device_tag; its check value of
 * "123456789" is 0xF4, host/tests/test_identity.py). */
#define UID_TAG 0x99u

static void check_pages(const struct pma_proto_device_info_t p[5])
{
    for (unsigned k = 0; k < 5u; ++k) TEST_ASSERT_EQUAL_INT(k, p[k].page); /* in page order */
    TEST_ASSERT_EQUAL_INT(PMA_PROTO_VERSION, p[0].protocol_version);
    TEST_ASSERT_EQUAL_INT(pma_build_info.fw_major, p[0].fw_major);
    TEST_ASSERT_EQUAL_INT(pma_build_info.fw_minor, p[0].fw_minor);
    TEST_ASSERT_EQUAL_INT(pma_build_info.fw_patch, p[0].fw_patch);
    TEST_ASSERT_EQUAL_INT(pma_build_info.build_target, p[0].build_target);
    TEST_ASSERT_NOT_EQUAL(PMA_PROTO_DEVICE_INFO_BUILD_TARGET_UNKNOWN_CHOICE, p[0].build_target);
    TEST_ASSERT_EQUAL_INT(pma_build_info.build_flags, p[0].build_flags);
    TEST_ASSERT_EQUAL_INT(PMA_PARAM_COUNT, p[1].param_count);
    TEST_ASSERT_EQUAL_HEX32(pma_build_info.fw_commit, p[1].fw_commit);
    TEST_ASSERT_EQUAL_HEX32(PMA_PARAM_TABLE_HASH, p[2].param_table_hash);
    /* the 12 bytes, byte 0 least significant in UidLow, byte 6 in UidHigh */
    TEST_ASSERT_EQUAL_HEX64(0x655443322110ull, p[3].uid_low);
    TEST_ASSERT_EQUAL_HEX64(0xCBBAA9988776ull, p[4].uid_high);
    for (unsigned k = 0; k < 5u; ++k) TEST_ASSERT_EQUAL_HEX8(UID_TAG, p[k].device_tag);
}

static void test_request_is_answered_with_five_pages(void)
{
    start_node();
    inject(PMA_PROTO_DEVICE_INFO_REQ_FRAME_ID, 0, NULL);
    struct pma_proto_device_info_t p[8];
    TEST_ASSERT_EQUAL_INT(5, step_pages(p));
    check_pages(p);
    assert_state(app.state, PMA_STATE_IDLE);
}

static void test_broadcast_request_is_answered_by_every_node(void)
{
    start_node();
    const pma_can_frame_t all = frame_of(PMA_PROTO_DEVICE_INFO_REQ_ALL_FRAME_ID, 0, 0, NULL);
    assert_status(pma_fake_can_inject(&all), PMA_OK); /* through the node's receive filters */
    struct pma_proto_device_info_t p[8];
    TEST_ASSERT_EQUAL_INT(5, step_pages(p));
    check_pages(p);
}

static void test_wrong_length_and_other_nodes_requests_are_not_answered(void)
{
    start_node();
    const uint32_t bad = app.counters.frames_bad;
    const uint8_t d[2] = {0, 1};
    inject(PMA_PROTO_DEVICE_INFO_REQ_FRAME_ID, 1, d);
    const pma_can_frame_t all = frame_of(PMA_PROTO_DEVICE_INFO_REQ_ALL_FRAME_ID, 0, 2, d);
    assert_status(pma_fake_can_inject(&all), PMA_OK);
    struct pma_proto_device_info_t p[8];
    TEST_ASSERT_EQUAL_INT(0, step_pages(p));
    TEST_ASSERT_EQUAL_UINT32(bad + 2u, app.counters.frames_bad);
    /* another node's request: not received (filters) or ignored, never answered */
    const pma_can_frame_t other = frame_of(PMA_PROTO_DEVICE_INFO_REQ_FRAME_ID, 5, 0, NULL);
    (void)pma_fake_can_inject(&other);
    TEST_ASSERT_EQUAL_INT(0, step_pages(p));
}

static void test_answered_in_every_state_without_changing_it(void)
{
    start_node();
    struct pma_proto_device_info_t p[8];
    inject(PMA_PROTO_ESTOP_FRAME_ID, 0, NULL);
    (void)step_pages(p);
    assert_state(app.state, PMA_STATE_FAULT);
    inject(PMA_PROTO_DEVICE_INFO_REQ_FRAME_ID, 0, NULL);
    TEST_ASSERT_EQUAL_INT(5, step_pages(p));
    assert_state(app.state, PMA_STATE_FAULT);
    assert_fault(app.fault, PMA_FAULT_ESTOP);
}

static void test_unknown_uid_reads_zero(void)
{
    pma_fake_reset();
    assert_status(pma_hal_init(NULL), PMA_OK);
    plat = platform(1); /* no unique id given */
    assert_status(pma_app_init(&app, &plat), PMA_OK);
    inject(PMA_PROTO_DEVICE_INFO_REQ_FRAME_ID, 0, NULL);
    struct pma_proto_device_info_t p[8];
    TEST_ASSERT_EQUAL_INT(5, step_pages(p));
    TEST_ASSERT_EQUAL_HEX64(0, p[3].uid_low);
    TEST_ASSERT_EQUAL_HEX64(0, p[4].uid_high);
    TEST_ASSERT_EQUAL_HEX8(0, p[0].device_tag); /* CRC-8 of zeros, initial value 0 */
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_request_is_answered_with_five_pages);
    RUN_TEST(test_broadcast_request_is_answered_by_every_node);
    RUN_TEST(test_wrong_length_and_other_nodes_requests_are_not_answered);
    RUN_TEST(test_answered_in_every_state_without_changing_it);
    RUN_TEST(test_unknown_uid_reads_zero);
    return UNITY_END();
}
