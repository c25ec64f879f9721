/* SPDX-License-Identifier: Apache-2.0 */
/* Fake port, CAN: queues, filters, dropped and duplicated frames, the fault
 * confinement state machine (error-active, error-passive, bus-off) and
 * bus-off recovery. */
#include "hal_test.h"

#include <string.h>

#include "pma/hal.h"
#include "pma_hal_fake.h"

/* Every test: fresh devices, HAL up. */
void setUp(void)
{
    pma_fake_reset();
    assert_status(pma_hal_init(NULL), PMA_OK);
}

static pma_can_frame_t frame(uint16_t id, uint8_t tag)
{
    pma_can_frame_t f = {.id = id, .dlc = 8, .data = {tag, 1, 2, 3, 4, 5, 6, 7}};
    return f;
}

static void assert_can_state(pma_can_state_t want, uint16_t tec, uint16_t rec)
{
    pma_can_status_t st;
    assert_status(pma_hal_can_status(&st), PMA_OK);
    TEST_ASSERT_EQUAL_INT(want, st.state);
    TEST_ASSERT_EQUAL_INT(tec, st.tec);
    TEST_ASSERT_EQUAL_INT(rec, st.rec);
}

static void test_send_and_tx_log(void)
{
    pma_can_frame_t got;
    assert_status(pma_fake_can_tx_pop(&got), PMA_ERR_EMPTY);
    for (uint8_t i = 0; i < 3; ++i) {
        const pma_can_frame_t f = frame((uint16_t)(0x700u + i), i);
        assert_status(pma_hal_can_send(&f), PMA_OK);
    }
    TEST_ASSERT_EQUAL_INT(3, pma_fake_can_tx_pending());
    for (uint8_t i = 0; i < 3; ++i) {
        assert_status(pma_fake_can_tx_pop(&got), PMA_OK);
        const pma_can_frame_t want = frame((uint16_t)(0x700u + i), i);
        TEST_ASSERT_EQUAL_INT(want.id, got.id); /* field by field: the struct has padding */
        TEST_ASSERT_EQUAL_INT(want.dlc, got.dlc);
        TEST_ASSERT_EQUAL_MEMORY(want.data, got.data, sizeof got.data);
    }
    /* invalid frames are refused */
    pma_can_frame_t bad = frame(0x800, 0);
    assert_status(pma_hal_can_send(&bad), PMA_ERR_RANGE);
    bad = frame(0x7FF, 0);
    bad.dlc = 9;
    assert_status(pma_hal_can_send(&bad), PMA_ERR_RANGE);
    assert_status(pma_hal_can_send(NULL), PMA_ERR_NULL);
    TEST_ASSERT_EQUAL_INT(0, pma_fake_can_tx_pending());
    /* the log keeps the newest PMA_FAKE_CAN_TX_LOG_DEPTH frames */
    for (uint8_t i = 0; i < PMA_FAKE_CAN_TX_LOG_DEPTH + 2u; ++i) {
        const pma_can_frame_t f = frame(0x10, i);
        assert_status(pma_hal_can_send(&f), PMA_OK);
    }
    TEST_ASSERT_EQUAL_INT(2, pma_fake_can_tx_overwritten());
    assert_status(pma_fake_can_tx_pop(&got), PMA_OK);
    TEST_ASSERT_EQUAL_INT(2, got.data[0]);
}

static void test_tx_queue_full(void)
{
    pma_fake_can_block_tx(true); /* nobody acknowledges */
    for (uint8_t i = 0; i < PMA_FAKE_CAN_TX_QUEUE_DEPTH; ++i) {
        const pma_can_frame_t f = frame(0x20, i);
        assert_status(pma_hal_can_send(&f), PMA_OK);
    }
    const pma_can_frame_t extra = frame(0x20, 99);
    assert_status(pma_hal_can_send(&extra), PMA_ERR_FULL);
    TEST_ASSERT_EQUAL_INT(0, pma_fake_can_tx_pending());
    pma_fake_can_block_tx(false);
    TEST_ASSERT_EQUAL_INT(PMA_FAKE_CAN_TX_QUEUE_DEPTH, pma_fake_can_tx_pending());
    pma_can_frame_t got;
    for (uint8_t i = 0; i < PMA_FAKE_CAN_TX_QUEUE_DEPTH; ++i) {
        assert_status(pma_fake_can_tx_pop(&got), PMA_OK);
        TEST_ASSERT_EQUAL_INT(i, got.data[0]);
    }
    assert_status(pma_hal_can_send(&extra), PMA_OK);
}

static void test_receive_queue(void)
{
    pma_can_frame_t got;
    assert_status(pma_hal_can_recv(&got), PMA_ERR_EMPTY);
    assert_status(pma_hal_can_recv(NULL), PMA_ERR_NULL);
    for (uint8_t i = 0; i < PMA_FAKE_CAN_RX_DEPTH; ++i) {
        const pma_can_frame_t f = frame(0x100, i);
        assert_status(pma_fake_can_inject(&f), PMA_OK);
    }
    const pma_can_frame_t lost = frame(0x100, 99);
    assert_status(pma_fake_can_inject(&lost), PMA_ERR_FULL);
    pma_can_status_t st;
    assert_status(pma_hal_can_status(&st), PMA_OK);
    TEST_ASSERT_EQUAL_INT(1, st.rx_overruns);
    for (uint8_t i = 0; i < PMA_FAKE_CAN_RX_DEPTH; ++i) {
        assert_status(pma_hal_can_recv(&got), PMA_OK);
        TEST_ASSERT_EQUAL_INT(i, got.data[0]);
    }
    assert_status(pma_hal_can_recv(&got), PMA_ERR_EMPTY);
    pma_can_frame_t bad = frame(0x800, 0);
    assert_status(pma_fake_can_inject(&bad), PMA_ERR_RANGE);
}

static void test_filters(void)
{
    /* node 5: its own range 0x280..0x28F (id/mask), plus broadcast 0x000 */
    const pma_can_filter_t f[2] = {{.id = 0x285, .mask = 0x7F0}, {.id = 0x000, .mask = 0x7FF}};
    assert_status(pma_hal_can_set_filters(f, 2), PMA_OK);
    const uint16_t pass[] = {0x280, 0x285, 0x28F, 0x000};
    const uint16_t reject[] = {0x290, 0x27F, 0x001, 0x685};
    for (size_t i = 0; i < sizeof pass / sizeof pass[0]; ++i) {
        const pma_can_frame_t fr = frame(pass[i], 0);
        assert_status(pma_fake_can_inject(&fr), PMA_OK);
    }
    for (size_t i = 0; i < sizeof reject / sizeof reject[0]; ++i) {
        const pma_can_frame_t fr = frame(reject[i], 0);
        TEST_ASSERT_EQUAL_INT(PMA_FAKE_CAN_FILTERED, pma_fake_can_inject(&fr));
    }
    TEST_ASSERT_EQUAL_INT(4, pma_fake_can_rx_pending());

    /* bad filter sets change nothing */
    pma_can_filter_t many[PMA_CAN_FILTERS_MAX + 1u];
    memset(many, 0, sizeof many);
    assert_status(pma_hal_can_set_filters(many, PMA_CAN_FILTERS_MAX + 1u), PMA_ERR_RANGE);
    const pma_can_filter_t wide = {.id = 0x800, .mask = 0x7FF};
    assert_status(pma_hal_can_set_filters(&wide, 1), PMA_ERR_RANGE);
    assert_status(pma_hal_can_set_filters(NULL, 1), PMA_ERR_NULL);
    const pma_can_frame_t fr = frame(0x290, 0);
    TEST_ASSERT_EQUAL_INT(PMA_FAKE_CAN_FILTERED, pma_fake_can_inject(&fr));
    assert_status(pma_hal_can_set_filters(many, PMA_CAN_FILTERS_MAX), PMA_OK); /* mask 0 */
    assert_status(pma_fake_can_inject(&fr), PMA_OK);
    /* count 0: accept all again */
    assert_status(pma_hal_can_set_filters(f, 1), PMA_OK);
    TEST_ASSERT_EQUAL_INT(PMA_FAKE_CAN_FILTERED, pma_fake_can_inject(&fr));
    assert_status(pma_hal_can_set_filters(NULL, 0), PMA_OK);
    assert_status(pma_fake_can_inject(&fr), PMA_OK);
}

static void test_dropped_and_duplicated(void)
{
    pma_can_frame_t got;
    pma_fake_can_drop(PMA_FAKE_CAN_RX, 2);
    pma_fake_can_duplicate(PMA_FAKE_CAN_RX, 1);
    for (uint8_t i = 0; i < 4; ++i) {
        const pma_can_frame_t f = frame(0x300, i);
        TEST_ASSERT_EQUAL_INT(i < 2 ? PMA_FAKE_CAN_DROPPED : PMA_OK, pma_fake_can_inject(&f));
    }
    const uint8_t rx_seen[] = {2, 2, 3}; /* frames 0 and 1 lost, frame 2 twice */
    for (size_t i = 0; i < sizeof rx_seen; ++i) {
        assert_status(pma_hal_can_recv(&got), PMA_OK);
        TEST_ASSERT_EQUAL_INT(rx_seen[i], got.data[0]);
    }
    assert_status(pma_hal_can_recv(&got), PMA_ERR_EMPTY);

    pma_fake_can_duplicate(PMA_FAKE_CAN_TX, 2);
    pma_fake_can_drop(PMA_FAKE_CAN_TX, 1);
    for (uint8_t i = 0; i < 4; ++i) {
        const pma_can_frame_t f = frame(0x400, i);
        assert_status(pma_hal_can_send(&f), PMA_OK); /* the sender cannot tell */
    }
    const uint8_t tx_seen[] = {1, 1, 2, 2, 3}; /* frame 0 lost, 1 and 2 twice */
    for (size_t i = 0; i < sizeof tx_seen; ++i) {
        assert_status(pma_fake_can_tx_pop(&got), PMA_OK);
        TEST_ASSERT_EQUAL_INT(tx_seen[i], got.data[0]);
    }
    assert_status(pma_fake_can_tx_pop(&got), PMA_ERR_EMPTY);
}

static void test_error_states_forced(void)
{
    assert_can_state(PMA_CAN_ERROR_ACTIVE, 0, 0);
    pma_fake_can_set_error_counters(127, 127);
    assert_can_state(PMA_CAN_ERROR_ACTIVE, 127, 127);
    pma_fake_can_set_error_counters(128, 0);
    assert_can_state(PMA_CAN_ERROR_PASSIVE, 128, 0);
    pma_fake_can_set_error_counters(0, 128);
    assert_can_state(PMA_CAN_ERROR_PASSIVE, 0, 128);
    /* error-passive still sends and receives */
    const pma_can_frame_t f = frame(0x123, 0);
    assert_status(pma_hal_can_send(&f), PMA_OK);
    /* a correct reception brings REC back below 128 (ISO 11898-1: to 119..127) */
    assert_status(pma_fake_can_inject(&f), PMA_OK);
    assert_can_state(PMA_CAN_ERROR_ACTIVE, 0, 119);
    assert_status(pma_fake_can_inject(&f), PMA_OK);
    assert_can_state(PMA_CAN_ERROR_ACTIVE, 0, 118);

    pma_fake_can_set_error_counters(300, 5);
    assert_can_state(PMA_CAN_BUS_OFF, 256, 5);
    assert_status(pma_hal_can_send(&f), PMA_ERR_BUS_OFF);
    assert_status(pma_fake_can_inject(&f), PMA_ERR_BUS_OFF);
    pma_can_frame_t got;
    assert_status(pma_hal_can_recv(&got), PMA_OK);    /* frames received before stay */
    /* recovery (default: immediate) */
    assert_status(pma_hal_can_recover(), PMA_OK);
    assert_can_state(PMA_CAN_ERROR_ACTIVE, 0, 0);
    assert_status(pma_hal_can_send(&f), PMA_OK);
    assert_status(pma_hal_can_recover(), PMA_OK);     /* not bus-off: nothing to do */
    assert_can_state(PMA_CAN_ERROR_ACTIVE, 0, 0);
}

/* A broken bus: each send is a failed attempt, TEC += 8: error-passive after
 * 16, bus-off after 32; afterwards successful sends lower TEC again. */
static void test_bus_errors_lead_to_bus_off(void)
{
    const pma_can_frame_t f = frame(0x181, 0);
    pma_fake_can_bus_errors(true);
    for (int i = 1; i <= 32; ++i) {
        assert_status(pma_hal_can_send(&f), PMA_OK);
        if (i == 15) assert_can_state(PMA_CAN_ERROR_ACTIVE, 120, 0);
        if (i == 16) assert_can_state(PMA_CAN_ERROR_PASSIVE, 128, 0);
        if (i == 31) assert_can_state(PMA_CAN_ERROR_PASSIVE, 248, 0);
    }
    assert_can_state(PMA_CAN_BUS_OFF, 256, 0);
    TEST_ASSERT_EQUAL_INT(0, pma_fake_can_tx_pending()); /* nothing got through */
    assert_status(pma_hal_can_send(&f), PMA_ERR_BUS_OFF);

    /* recovery takes 128 x 11 bit times (1.4 ms at 1 Mbit/s) */
    pma_fake_can_bus_errors(false);
    pma_fake_can_set_recovery(1408, false);
    assert_status(pma_hal_can_recover(), PMA_OK);
    pma_fake_time_advance_us(1407);
    assert_can_state(PMA_CAN_BUS_OFF, 256, 0);
    assert_status(pma_hal_can_send(&f), PMA_ERR_BUS_OFF);
    pma_fake_time_advance_us(1);
    assert_can_state(PMA_CAN_ERROR_ACTIVE, 0, 0);
    assert_status(pma_hal_can_send(&f), PMA_OK);
    TEST_ASSERT_EQUAL_INT(1, pma_fake_can_tx_pending());

    /* successful transmissions count TEC down */
    pma_fake_can_set_error_counters(130, 0);
    for (int i = 0; i < 3; ++i) assert_status(pma_hal_can_send(&f), PMA_OK);
    assert_can_state(PMA_CAN_ERROR_ACTIVE, 127, 0);
}

static void test_recovery_blocked_and_bus_off_flush(void)
{
    const pma_can_frame_t f = frame(0x181, 0);
    /* frames waiting for transmission are abandoned at bus-off */
    pma_fake_can_block_tx(true);
    assert_status(pma_hal_can_send(&f), PMA_OK);
    assert_status(pma_hal_can_send(&f), PMA_OK);
    pma_fake_can_set_error_counters(256, 0);
    pma_fake_can_block_tx(false);
    TEST_ASSERT_EQUAL_INT(0, pma_fake_can_tx_pending());

    /* the bus is still broken: recovery never completes */
    pma_fake_can_set_recovery(0, true);
    assert_status(pma_hal_can_recover(), PMA_OK);
    pma_fake_time_advance_us(1000000);
    assert_can_state(PMA_CAN_BUS_OFF, 256, 0);
    assert_status(pma_hal_can_recover(), PMA_OK);   /* asking again changes nothing */
    assert_can_state(PMA_CAN_BUS_OFF, 256, 0);
    /* the bus is repaired: the pending request completes */
    pma_fake_can_set_recovery(0, false);
    assert_can_state(PMA_CAN_ERROR_ACTIVE, 0, 0);

    /* without a request a port never leaves bus-off on its own */
    pma_fake_can_set_error_counters(256, 0);
    pma_fake_time_advance_us(1000000);
    assert_can_state(PMA_CAN_BUS_OFF, 256, 0);
}

static void test_init_and_reboot_reset_the_controller(void)
{
    TEST_ASSERT_EQUAL_INT(PMA_HAL_CAN_DEFAULT_BITRATE_BPS, pma_fake_can_bitrate_bps());
    const pma_can_filter_t filt = {.id = 0x100, .mask = 0x7FF};
    assert_status(pma_hal_can_set_filters(&filt, 1), PMA_OK);
    const pma_can_frame_t f = frame(0x100, 0);
    assert_status(pma_fake_can_inject(&f), PMA_OK);
    assert_status(pma_hal_can_send(&f), PMA_OK);
    pma_fake_can_set_error_counters(256, 0);

    const pma_hal_config_t cfg = {.can_bitrate_bps = 500000u};
    assert_status(pma_hal_init(&cfg), PMA_OK);
    TEST_ASSERT_EQUAL_INT(500000u, pma_fake_can_bitrate_bps());
    assert_can_state(PMA_CAN_ERROR_ACTIVE, 0, 0);
    TEST_ASSERT_EQUAL_INT(0, pma_fake_can_rx_pending());
    const pma_can_frame_t other = frame(0x200, 0);
    assert_status(pma_fake_can_inject(&other), PMA_OK);   /* accept-all again */
    TEST_ASSERT_EQUAL_INT(1, pma_fake_can_tx_pending());  /* the bus saw it: still logged */

    pma_fake_reboot();
    assert_status(pma_fake_can_inject(&other), PMA_ERR_NOT_READY);
    assert_status(pma_hal_init(NULL), PMA_OK);
    TEST_ASSERT_EQUAL_INT(0, pma_fake_can_rx_pending());
    TEST_ASSERT_EQUAL_INT(1, pma_fake_can_tx_pending());
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_send_and_tx_log);
    RUN_TEST(test_tx_queue_full);
    RUN_TEST(test_receive_queue);
    RUN_TEST(test_filters);
    RUN_TEST(test_dropped_and_duplicated);
    RUN_TEST(test_error_states_forced);
    RUN_TEST(test_bus_errors_lead_to_bus_off);
    RUN_TEST(test_recovery_blocked_and_bus_off_flush);
    RUN_TEST(test_init_and_reboot_reset_the_controller);
    return UNITY_END();
}
