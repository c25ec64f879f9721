/* SPDX-License-Identifier: Apache-2.0 */
/* Fake port: sensor faults, DAC log, clock and tick, watchdog, reset causes,
 * initialisation rules. */
#include "hal_test.h"

#include "pma/hal.h"
#include "pma_hal_fake.h"

/* Every test: fresh devices, HAL up. */
void setUp(void)
{
    pma_fake_reset();
    assert_status(pma_hal_init(NULL), PMA_OK);
}

static void test_not_ready_before_init(void)
{
    pma_fake_reset();
    uint16_t raw;
    pma_can_frame_t f = {.id = 1, .dlc = 0};
    pma_can_status_t st;
    pma_nvm_geometry_t g;
    uint8_t b[8];
    TEST_ASSERT_FALSE(pma_fake_initialised());
    assert_status(pma_hal_adc_read(&raw), PMA_ERR_NOT_READY);
    assert_status(pma_hal_dac_write(1), PMA_ERR_NOT_READY);
    assert_status(pma_hal_can_send(&f), PMA_ERR_NOT_READY);
    assert_status(pma_hal_can_recv(&f), PMA_ERR_NOT_READY);
    assert_status(pma_hal_can_status(&st), PMA_ERR_NOT_READY);
    assert_status(pma_hal_can_set_filters(NULL, 0), PMA_ERR_NOT_READY);
    assert_status(pma_hal_can_recover(), PMA_ERR_NOT_READY);
    assert_status(pma_hal_tick_start(1000), PMA_ERR_NOT_READY);
    assert_status(pma_hal_tick_wait(NULL), PMA_ERR_NOT_READY);
    assert_status(pma_hal_nvm_geometry(&g), PMA_ERR_NOT_READY);
    assert_status(pma_hal_nvm_read(0, 0, b, sizeof b), PMA_ERR_NOT_READY);
    TEST_ASSERT_EQUAL_UINT64(0, pma_hal_time_us());
    TEST_ASSERT_EQUAL_INT(PMA_RESET_POWER_ON, pma_hal_reset_cause());
    TEST_ASSERT_EQUAL_STRING("fake", pma_hal_port_name());

    assert_status(pma_hal_init(NULL), PMA_OK);
    TEST_ASSERT_TRUE(pma_fake_initialised());
    assert_status(pma_hal_dac_write(1), PMA_OK);
    pma_hal_deinit();
    assert_status(pma_hal_dac_write(1), PMA_ERR_NOT_READY);
}

static void test_adc_faults(void)
{
    uint16_t raw = 0;
    pma_fake_adc_set(2000);
    assert_status(pma_hal_adc_read(&raw), PMA_OK);
    TEST_ASSERT_EQUAL_INT(2000, raw);
    assert_status(pma_hal_adc_read(NULL), PMA_ERR_NULL);

    /* stuck: frozen at the current value, the plant's changes are not seen */
    pma_fake_adc_stuck();
    pma_fake_adc_set(2500);
    assert_status(pma_hal_adc_read(&raw), PMA_OK);
    TEST_ASSERT_EQUAL_INT(2000, raw);
    pma_fake_adc_clear_fault();
    assert_status(pma_hal_adc_read(&raw), PMA_OK);
    TEST_ASSERT_EQUAL_INT(2500, raw);

    /* out of range and wire break: the counts the application's scaling refuses
     * (its checks: tests/app/test_app_scaling.c) */
    pma_fake_adc_out_of_range(4095);
    assert_status(pma_hal_adc_read(&raw), PMA_OK);
    TEST_ASSERT_EQUAL_INT(4095, raw);
    pma_fake_adc_wire_break();
    assert_status(pma_hal_adc_read(&raw), PMA_OK);
    TEST_ASSERT_EQUAL_INT(PMA_FAKE_ADC_WIRE_BREAK_COUNTS, raw);
    /* a sensor that broke stays broken: stuck keeps reading the wire-break level */
    pma_fake_adc_stuck();
    pma_fake_adc_set(3000);
    assert_status(pma_hal_adc_read(&raw), PMA_OK);
    TEST_ASSERT_EQUAL_INT(PMA_FAKE_ADC_WIRE_BREAK_COUNTS, raw);

    pma_fake_adc_read_error();
    raw = 77;
    assert_status(pma_hal_adc_read(&raw), PMA_ERR_IO);
    TEST_ASSERT_EQUAL_INT(77, raw);
    pma_fake_adc_clear_fault();
    assert_status(pma_hal_adc_read(&raw), PMA_OK);
    TEST_ASSERT_EQUAL_INT(3000, raw);
    TEST_ASSERT_EQUAL_INT(8, pma_fake_adc_read_count()); /* NULL is refused before reading */

    /* the sensor is outside the MCU: a reboot keeps its value and fault */
    pma_fake_adc_wire_break();
    pma_fake_reboot();
    assert_status(pma_hal_init(NULL), PMA_OK);
    assert_status(pma_hal_adc_read(&raw), PMA_OK);
    TEST_ASSERT_EQUAL_INT(PMA_FAKE_ADC_WIRE_BREAK_COUNTS, raw);
}

static void test_dac_log(void)
{
    pma_fake_dac_write_t w;
    assert_status(pma_fake_dac_log(0, &w), PMA_ERR_EMPTY);
    for (uint16_t i = 0; i < 12; ++i) {
        pma_fake_time_advance_us(100);
        assert_status(pma_hal_dac_write((uint16_t)(i * 300u)), PMA_OK);
    }
    assert_status(pma_hal_dac_write(PMA_FAKE_DAC_MAX_COUNTS + 1u), PMA_ERR_RANGE);
    TEST_ASSERT_EQUAL_INT(12, pma_fake_dac_write_count());
    assert_status(pma_fake_dac_log(0, &w), PMA_OK);
    TEST_ASSERT_EQUAL_INT(11 * 300, w.counts);
    TEST_ASSERT_EQUAL_UINT64(1200, w.time_us);
    assert_status(pma_fake_dac_log(PMA_FAKE_DAC_LOG_DEPTH - 1u, &w), PMA_OK);
    TEST_ASSERT_EQUAL_INT((12 - PMA_FAKE_DAC_LOG_DEPTH) * 300, w.counts);
    TEST_ASSERT_EQUAL_UINT64((12 - PMA_FAKE_DAC_LOG_DEPTH + 1) * 100, w.time_us);
    assert_status(pma_fake_dac_log(PMA_FAKE_DAC_LOG_DEPTH, &w), PMA_ERR_RANGE); /* not kept */
    assert_status(pma_fake_dac_log(0, NULL), PMA_ERR_NULL);
}

static void test_clock_and_tick(void)
{
    uint32_t late = 99;
    TEST_ASSERT_EQUAL_UINT64(0, pma_hal_time_us());
    pma_fake_time_advance_us(5);
    TEST_ASSERT_EQUAL_UINT64(5, pma_hal_time_us());
    assert_status(pma_hal_tick_wait(&late), PMA_ERR_NOT_READY); /* not started */
    assert_status(pma_hal_tick_start(0), PMA_ERR_RANGE);
    assert_status(pma_hal_tick_start(1000), PMA_OK);            /* ticks at 1005, 2005, ... */

    assert_status(pma_hal_tick_wait(&late), PMA_OK);            /* sleeps */
    TEST_ASSERT_EQUAL_UINT64(1005, pma_hal_time_us());
    TEST_ASSERT_EQUAL_INT(0, late);
    pma_fake_time_advance_us(300);                              /* the control work */
    assert_status(pma_hal_tick_wait(&late), PMA_OK);
    TEST_ASSERT_EQUAL_UINT64(2005, pma_hal_time_us());
    TEST_ASSERT_EQUAL_INT(0, late);

    pma_fake_time_advance_us(1200);                             /* overrun into the next period */
    assert_status(pma_hal_tick_wait(&late), PMA_OK);
    TEST_ASSERT_EQUAL_UINT64(3205, pma_hal_time_us());          /* returns at once, late */
    TEST_ASSERT_EQUAL_INT(1, late);
    assert_status(pma_hal_tick_wait(&late), PMA_OK);            /* back on the grid */
    TEST_ASSERT_EQUAL_UINT64(4005, pma_hal_time_us());
    TEST_ASSERT_EQUAL_INT(0, late);

    pma_fake_time_advance_us(3500);                             /* 5005, 6005, 7005 passed */
    assert_status(pma_hal_tick_wait(&late), PMA_OK);
    TEST_ASSERT_EQUAL_INT(3, late);                             /* two skipped, one late */
    assert_status(pma_hal_tick_wait(NULL), PMA_OK);
    TEST_ASSERT_EQUAL_UINT64(8005, pma_hal_time_us());

    /* restart with another period: the first tick one period after the call */
    assert_status(pma_hal_tick_start(250), PMA_OK);
    assert_status(pma_hal_tick_wait(&late), PMA_OK);
    TEST_ASSERT_EQUAL_UINT64(8255, pma_hal_time_us());
    /* pma_hal_init stops the tick */
    assert_status(pma_hal_init(NULL), PMA_OK);
    assert_status(pma_hal_tick_wait(&late), PMA_ERR_NOT_READY);
}

static void test_watchdog_expiry(void)
{
    assert_status(pma_hal_watchdog_start(0), PMA_ERR_RANGE);
    assert_status(pma_hal_watchdog_start(PMA_FAKE_WATCHDOG_MAX_MS + 1u), PMA_ERR_RANGE);
    TEST_ASSERT_FALSE(pma_fake_watchdog_running());
    pma_hal_watchdog_kick(); /* not started: nothing */

    assert_status(pma_hal_watchdog_start(10), PMA_OK);
    TEST_ASSERT_TRUE(pma_fake_watchdog_running());
    for (int i = 0; i < 100; ++i) {      /* kicked in time: never expires */
        pma_fake_time_advance_us(9999);
        pma_hal_watchdog_kick();
    }
    TEST_ASSERT_FALSE(pma_fake_watchdog_expired());
    pma_fake_time_advance_us(10000);     /* exactly the timeout: not yet past it */
    TEST_ASSERT_FALSE(pma_fake_watchdog_expired());
    pma_fake_time_advance_us(1);
    TEST_ASSERT_TRUE(pma_fake_watchdog_expired());
    pma_hal_watchdog_kick();             /* too late */
    TEST_ASSERT_TRUE(pma_fake_watchdog_expired());
    pma_hal_deinit();                    /* cannot stop it either */
    TEST_ASSERT_TRUE(pma_fake_watchdog_running());

    pma_fake_reboot();
    TEST_ASSERT_EQUAL_INT(PMA_RESET_WATCHDOG, pma_hal_reset_cause());
    TEST_ASSERT_FALSE(pma_fake_watchdog_expired());
    TEST_ASSERT_FALSE(pma_fake_watchdog_running());
    TEST_ASSERT_FALSE(pma_fake_initialised());
}

/* A control loop that stalls inside its tick: the watchdog bites while the
 * tick wait sleeps, too. */
static void test_watchdog_via_tick(void)
{
    assert_status(pma_hal_watchdog_start(5), PMA_OK);
    assert_status(pma_hal_tick_start(1000), PMA_OK);
    for (int i = 0; i < 20; ++i) {
        assert_status(pma_hal_tick_wait(NULL), PMA_OK);
        pma_hal_watchdog_kick();
    }
    TEST_ASSERT_FALSE(pma_fake_watchdog_expired());
    for (int i = 0; i < 5; ++i) assert_status(pma_hal_tick_wait(NULL), PMA_OK); /* no kicks */
    TEST_ASSERT_FALSE(pma_fake_watchdog_expired()); /* 5 ms: not past */
    assert_status(pma_hal_tick_wait(NULL), PMA_OK);
    TEST_ASSERT_TRUE(pma_fake_watchdog_expired());
    /* changing the timeout kicks; a restart is SOFTWARE when the watchdog did not bite */
    pma_fake_reboot();
    assert_status(pma_hal_watchdog_start(5), PMA_OK);
    pma_fake_time_advance_us(4000);
    assert_status(pma_hal_watchdog_start(20), PMA_OK);
    pma_fake_time_advance_us(19000);
    TEST_ASSERT_FALSE(pma_fake_watchdog_expired());
    pma_fake_reboot();
    TEST_ASSERT_EQUAL_INT(PMA_RESET_SOFTWARE, pma_hal_reset_cause());
    pma_fake_power_on();
    TEST_ASSERT_EQUAL_INT(PMA_RESET_POWER_ON, pma_hal_reset_cause());
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_not_ready_before_init);
    RUN_TEST(test_adc_faults);
    RUN_TEST(test_dac_log);
    RUN_TEST(test_clock_and_tick);
    RUN_TEST(test_watchdog_expiry);
    RUN_TEST(test_watchdog_via_tick);
    return UNITY_END();
}
