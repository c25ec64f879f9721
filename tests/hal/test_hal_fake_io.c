/* Fake port: sensor faults, DAC log, clock and tick, watchdog, reset causes,
 * initialisation rules. */
#include "hal_test.h"

#include "pma/hal.h"
#include "pma_hal_fake.h"

static int setup(void **state)
{
    (void)state;
    pma_fake_reset();
    return pma_hal_init(NULL) == PMA_OK ? 0 : -1;
}

static void test_not_ready_before_init(void **state)
{
    (void)state;
    pma_fake_reset();
    uint16_t raw;
    pma_can_frame_t f = {.id = 1, .dlc = 0};
    pma_can_status_t st;
    pma_nvm_geometry_t g;
    uint8_t b[8];
    assert_false(pma_fake_initialised());
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
    assert_true(pma_hal_time_us() == 0);
    assert_int_equal(pma_hal_reset_cause(), PMA_RESET_POWER_ON);
    assert_string_equal(pma_hal_port_name(), "fake");

    assert_status(pma_hal_init(NULL), PMA_OK);
    assert_true(pma_fake_initialised());
    assert_status(pma_hal_dac_write(1), PMA_OK);
    pma_hal_deinit();
    assert_status(pma_hal_dac_write(1), PMA_ERR_NOT_READY);
}

static void test_adc_faults(void **state)
{
    (void)state;
    uint16_t raw = 0;
    pma_fake_adc_set(2000);
    assert_status(pma_hal_adc_read(&raw), PMA_OK);
    assert_int_equal(raw, 2000);
    assert_status(pma_hal_adc_read(NULL), PMA_ERR_NULL);

    /* stuck: frozen at the current value, the plant's changes are not seen */
    pma_fake_adc_stuck();
    pma_fake_adc_set(2500);
    assert_status(pma_hal_adc_read(&raw), PMA_OK);
    assert_int_equal(raw, 2000);
    pma_fake_adc_clear_fault();
    assert_status(pma_hal_adc_read(&raw), PMA_OK);
    assert_int_equal(raw, 2500);

    /* out of range and wire break, seen through the scaling */
    const pma_adc_scaling_t s = {.offset_cm = -2.5f, .gain_cm_per_count = 10.0f / 3276.0f,
                                 .raw_min_counts = 778, .raw_max_counts = 4094,
                                 .wire_break_below_counts = 737};
    float x;
    pma_fake_adc_out_of_range(4095);
    assert_status(pma_hal_adc_read(&raw), PMA_OK);
    assert_int_equal(raw, 4095);
    assert_status(pma_adc_counts_to_cm(&s, raw, &x), PMA_ERR_RANGE);
    pma_fake_adc_wire_break();
    assert_status(pma_hal_adc_read(&raw), PMA_OK);
    assert_int_equal(raw, PMA_FAKE_ADC_WIRE_BREAK_COUNTS);
    assert_status(pma_adc_counts_to_cm(&s, raw, &x), PMA_ERR_WIRE_BREAK);
    /* a sensor that broke stays broken: stuck keeps reading the wire-break level */
    pma_fake_adc_stuck();
    pma_fake_adc_set(3000);
    assert_status(pma_hal_adc_read(&raw), PMA_OK);
    assert_int_equal(raw, PMA_FAKE_ADC_WIRE_BREAK_COUNTS);

    pma_fake_adc_read_error();
    raw = 77;
    assert_status(pma_hal_adc_read(&raw), PMA_ERR_IO);
    assert_int_equal(raw, 77);
    pma_fake_adc_clear_fault();
    assert_status(pma_hal_adc_read(&raw), PMA_OK);
    assert_int_equal(raw, 3000);
    assert_int_equal(pma_fake_adc_read_count(), 8); /* NULL is refused before reading */

    /* the sensor is outside the MCU: a reboot keeps its value and fault */
    pma_fake_adc_wire_break();
    pma_fake_reboot();
    assert_status(pma_hal_init(NULL), PMA_OK);
    assert_status(pma_hal_adc_read(&raw), PMA_OK);
    assert_int_equal(raw, PMA_FAKE_ADC_WIRE_BREAK_COUNTS);
}

static void test_dac_log(void **state)
{
    (void)state;
    pma_fake_dac_write_t w;
    assert_status(pma_fake_dac_log(0, &w), PMA_ERR_EMPTY);
    for (uint16_t i = 0; i < 12; ++i) {
        pma_fake_time_advance_us(100);
        assert_status(pma_hal_dac_write((uint16_t)(i * 300u)), PMA_OK);
    }
    assert_status(pma_hal_dac_write(PMA_FAKE_DAC_MAX_COUNTS + 1u), PMA_ERR_RANGE);
    assert_int_equal(pma_fake_dac_write_count(), 12);
    assert_status(pma_fake_dac_log(0, &w), PMA_OK);
    assert_int_equal(w.counts, 11 * 300);
    assert_true(w.time_us == 1200);
    assert_status(pma_fake_dac_log(PMA_FAKE_DAC_LOG_DEPTH - 1u, &w), PMA_OK);
    assert_int_equal(w.counts, (12 - PMA_FAKE_DAC_LOG_DEPTH) * 300);
    assert_true(w.time_us == (12 - PMA_FAKE_DAC_LOG_DEPTH + 1) * 100);
    assert_status(pma_fake_dac_log(PMA_FAKE_DAC_LOG_DEPTH, &w), PMA_ERR_RANGE); /* not kept */
    assert_status(pma_fake_dac_log(0, NULL), PMA_ERR_NULL);
}

static void test_clock_and_tick(void **state)
{
    (void)state;
    uint32_t late = 99;
    assert_true(pma_hal_time_us() == 0);
    pma_fake_time_advance_us(5);
    assert_true(pma_hal_time_us() == 5);
    assert_status(pma_hal_tick_wait(&late), PMA_ERR_NOT_READY); /* not started */
    assert_status(pma_hal_tick_start(0), PMA_ERR_RANGE);
    assert_status(pma_hal_tick_start(1000), PMA_OK);            /* ticks at 1005, 2005, ... */

    assert_status(pma_hal_tick_wait(&late), PMA_OK);            /* sleeps */
    assert_true(pma_hal_time_us() == 1005);
    assert_int_equal(late, 0);
    pma_fake_time_advance_us(300);                              /* the control work */
    assert_status(pma_hal_tick_wait(&late), PMA_OK);
    assert_true(pma_hal_time_us() == 2005);
    assert_int_equal(late, 0);

    pma_fake_time_advance_us(1200);                             /* overrun into the next period */
    assert_status(pma_hal_tick_wait(&late), PMA_OK);
    assert_true(pma_hal_time_us() == 3205);                     /* returns at once, late */
    assert_int_equal(late, 1);
    assert_status(pma_hal_tick_wait(&late), PMA_OK);            /* back on the grid */
    assert_true(pma_hal_time_us() == 4005);
    assert_int_equal(late, 0);

    pma_fake_time_advance_us(3500);                             /* 5005, 6005, 7005 passed */
    assert_status(pma_hal_tick_wait(&late), PMA_OK);
    assert_int_equal(late, 3);                                  /* two skipped, one late */
    assert_status(pma_hal_tick_wait(NULL), PMA_OK);
    assert_true(pma_hal_time_us() == 8005);

    /* restart with another period: the first tick one period after the call */
    assert_status(pma_hal_tick_start(250), PMA_OK);
    assert_status(pma_hal_tick_wait(&late), PMA_OK);
    assert_true(pma_hal_time_us() == 8255);
    /* pma_hal_init stops the tick */
    assert_status(pma_hal_init(NULL), PMA_OK);
    assert_status(pma_hal_tick_wait(&late), PMA_ERR_NOT_READY);
}

static void test_watchdog_expiry(void **state)
{
    (void)state;
    assert_status(pma_hal_watchdog_start(0), PMA_ERR_RANGE);
    assert_status(pma_hal_watchdog_start(PMA_FAKE_WATCHDOG_MAX_MS + 1u), PMA_ERR_RANGE);
    assert_false(pma_fake_watchdog_running());
    pma_hal_watchdog_kick(); /* not started: nothing */

    assert_status(pma_hal_watchdog_start(10), PMA_OK);
    assert_true(pma_fake_watchdog_running());
    for (int i = 0; i < 100; ++i) {      /* kicked in time: never expires */
        pma_fake_time_advance_us(9999);
        pma_hal_watchdog_kick();
    }
    assert_false(pma_fake_watchdog_expired());
    pma_fake_time_advance_us(10000);     /* exactly the timeout: not yet past it */
    assert_false(pma_fake_watchdog_expired());
    pma_fake_time_advance_us(1);
    assert_true(pma_fake_watchdog_expired());
    pma_hal_watchdog_kick();             /* too late */
    assert_true(pma_fake_watchdog_expired());
    pma_hal_deinit();                    /* cannot stop it either */
    assert_true(pma_fake_watchdog_running());

    pma_fake_reboot();
    assert_int_equal(pma_hal_reset_cause(), PMA_RESET_WATCHDOG);
    assert_false(pma_fake_watchdog_expired());
    assert_false(pma_fake_watchdog_running());
    assert_false(pma_fake_initialised());
}

/* A control loop that stalls inside its tick: the watchdog bites while the
 * tick wait sleeps, too. */
static void test_watchdog_via_tick(void **state)
{
    (void)state;
    assert_status(pma_hal_watchdog_start(5), PMA_OK);
    assert_status(pma_hal_tick_start(1000), PMA_OK);
    for (int i = 0; i < 20; ++i) {
        assert_status(pma_hal_tick_wait(NULL), PMA_OK);
        pma_hal_watchdog_kick();
    }
    assert_false(pma_fake_watchdog_expired());
    for (int i = 0; i < 5; ++i) assert_status(pma_hal_tick_wait(NULL), PMA_OK); /* no kicks */
    assert_false(pma_fake_watchdog_expired());   /* 5 ms: not past */
    assert_status(pma_hal_tick_wait(NULL), PMA_OK);
    assert_true(pma_fake_watchdog_expired());
    /* changing the timeout kicks; a restart is SOFTWARE when the watchdog did not bite */
    pma_fake_reboot();
    assert_status(pma_hal_watchdog_start(5), PMA_OK);
    pma_fake_time_advance_us(4000);
    assert_status(pma_hal_watchdog_start(20), PMA_OK);
    pma_fake_time_advance_us(19000);
    assert_false(pma_fake_watchdog_expired());
    pma_fake_reboot();
    assert_int_equal(pma_hal_reset_cause(), PMA_RESET_SOFTWARE);
    pma_fake_power_on();
    assert_int_equal(pma_hal_reset_cause(), PMA_RESET_POWER_ON);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_not_ready_before_init, setup),
        cmocka_unit_test_setup(test_adc_faults, setup),
        cmocka_unit_test_setup(test_dac_log, setup),
        cmocka_unit_test_setup(test_clock_and_tick, setup),
        cmocka_unit_test_setup(test_watchdog_expiry, setup),
        cmocka_unit_test_setup(test_watchdog_via_tick, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
