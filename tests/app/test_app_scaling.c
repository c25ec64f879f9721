/* SPDX-License-Identifier: Apache-2.0 */
/* ADC and DAC scaling (firmware/app/scaling.h): conversion, range and wire-break
 * checks, saturation, validation. */
#include <math.h>
#include <stdint.h>

#include "pma/status.h"
#include "pma_test.h"
#include "scaling.h"

/* The header's example: 4-20 mA over 165 ohm into a 12-bit 3.3 V ADC, 0-10 cm. */
static const pma_adc_scaling_t laser = {
    .offset_cm = -2.5f,
    .gain_cm_per_count = 10.0f / 3276.0f,
    .raw_min_counts = 778,
    .raw_max_counts = 4094,
    .wire_break_below_counts = 737,
};

/* 0-600 kPa regulator on a 12-bit DAC. */
static const pma_dac_scaling_t regulator = {
    .counts_at_zero_kpa = 0.0f,
    .counts_per_kpa = 4095.0f / 600.0f,
    .min_counts = 0,
    .max_counts = 4095,
};

static void test_adc_converts_valid_range(void)
{
    float x = -99.0f;
    assert_status(pma_adc_counts_to_cm(&laser, 819, &x), PMA_OK); /* 4 mA: the sensor's 0 */
    TEST_ASSERT_LESS_THAN_FLOAT(1e-5f, fabsf(x));
    assert_status(pma_adc_counts_to_cm(&laser, 4094, &x), PMA_OK);
    TEST_ASSERT_LESS_THAN_FLOAT(1e-5f, fabsf(x - (-2.5f + 4094.0f * 10.0f / 3276.0f)));
    assert_status(pma_adc_counts_to_cm(&laser, 778, &x), PMA_OK); /* 3.8 mA: still usable */
    TEST_ASSERT_LESS_THAN_FLOAT(0.0f, x);
}

static void test_adc_range_and_wire_break(void)
{
    float x = 42.0f;
    assert_status(pma_adc_counts_to_cm(&laser, 4095, &x), PMA_ERR_RANGE);    /* clipped */
    assert_status(pma_adc_counts_to_cm(&laser, 65535, &x), PMA_ERR_RANGE);
    assert_status(pma_adc_counts_to_cm(&laser, 777, &x), PMA_ERR_RANGE);     /* 3.6-3.8 mA */
    assert_status(pma_adc_counts_to_cm(&laser, 737, &x), PMA_ERR_RANGE);
    assert_status(pma_adc_counts_to_cm(&laser, 736, &x), PMA_ERR_WIRE_BREAK);
    assert_status(pma_adc_counts_to_cm(&laser, 0, &x), PMA_ERR_WIRE_BREAK);  /* 0 mA */
    TEST_ASSERT_FLOAT_WITHIN(0.0f, 42.0f, x); /* untouched on every error */

    /* 0-10 V sensor without a live zero: no wire-break check, 0 is valid */
    pma_adc_scaling_t volt = {.offset_cm = 0.0f, .gain_cm_per_count = 0.01f,
                              .raw_min_counts = 0, .raw_max_counts = 1000,
                              .wire_break_below_counts = 0};
    assert_status(pma_adc_counts_to_cm(&volt, 0, &x), PMA_OK);
    TEST_ASSERT_FLOAT_WITHIN(0.0f, 0.0f, x);
    assert_status(pma_adc_counts_to_cm(&volt, 1001, &x), PMA_ERR_RANGE);

    /* inverted mounting: negative gain */
    volt.offset_cm = 10.0f;
    volt.gain_cm_per_count = -0.01f;
    assert_status(pma_adc_counts_to_cm(&volt, 1000, &x), PMA_OK);
    TEST_ASSERT_LESS_THAN_FLOAT(1e-5f, fabsf(x));
}

static void test_adc_validation(void)
{
    float x;
    assert_status(pma_adc_validate_scaling(&laser), PMA_OK);
    assert_status(pma_adc_validate_scaling(NULL), PMA_ERR_NULL);
    assert_status(pma_adc_counts_to_cm(&laser, 1000, NULL), PMA_ERR_NULL);
    assert_status(pma_adc_counts_to_cm(NULL, 1000, &x), PMA_ERR_NULL);
    pma_adc_scaling_t s = laser;
    s.offset_cm = NAN;
    assert_status(pma_adc_validate_scaling(&s), PMA_ERR_NOT_FINITE);
    assert_status(pma_adc_counts_to_cm(&s, 1000, &x), PMA_ERR_NOT_FINITE);
    s = laser;
    s.gain_cm_per_count = INFINITY;
    assert_status(pma_adc_validate_scaling(&s), PMA_ERR_NOT_FINITE);
    s.gain_cm_per_count = 0.0f;
    assert_status(pma_adc_validate_scaling(&s), PMA_ERR_RANGE);
    s = laser;
    s.raw_min_counts = 4095;
    assert_status(pma_adc_validate_scaling(&s), PMA_ERR_RANGE); /* min > max */
    s = laser;
    s.wire_break_below_counts = 779;
    assert_status(pma_adc_validate_scaling(&s), PMA_ERR_RANGE); /* above raw_min */
}

static void test_adc_inverse(void)
{
    uint16_t raw = 1;
    for (uint16_t r = 778; r <= 4094; r = (uint16_t)(r + 97)) {
        float x;
        assert_status(pma_adc_counts_to_cm(&laser, r, &x), PMA_OK);
        assert_status(pma_adc_cm_to_counts(&laser, x, &raw), PMA_OK);
        TEST_ASSERT_EQUAL_INT(r, raw);
    }
    assert_status(pma_adc_cm_to_counts(&laser, -100.0f, &raw), PMA_OK);
    TEST_ASSERT_EQUAL_INT(778, raw); /* saturated to the valid range */
    assert_status(pma_adc_cm_to_counts(&laser, 1e30f, &raw), PMA_OK);
    TEST_ASSERT_EQUAL_INT(4094, raw);
    raw = 7;
    assert_status(pma_adc_cm_to_counts(&laser, NAN, &raw), PMA_ERR_NOT_FINITE);
    assert_status(pma_adc_cm_to_counts(&laser, -INFINITY, &raw), PMA_ERR_NOT_FINITE);
    TEST_ASSERT_EQUAL_INT(7, raw);
}

static void test_dac_scaling_and_saturation(void)
{
    uint16_t c = 1;
    assert_status(pma_dac_kpa_to_counts(&regulator, 0.0f, &c), PMA_OK);
    TEST_ASSERT_EQUAL_INT(0, c);
    assert_status(pma_dac_kpa_to_counts(&regulator, 200.0f, &c), PMA_OK);
    TEST_ASSERT_EQUAL_INT(1365, c);
    assert_status(pma_dac_kpa_to_counts(&regulator, 600.0f, &c), PMA_OK);
    TEST_ASSERT_EQUAL_INT(4095, c);
    assert_status(pma_dac_kpa_to_counts(&regulator, 100.1f, &c), PMA_OK);
    TEST_ASSERT_EQUAL_INT(683, c); /* 683.18: rounded to nearest */
    assert_status(pma_dac_kpa_to_counts(&regulator, 100.03f, &c), PMA_OK);
    TEST_ASSERT_EQUAL_INT(683, c); /* 682.70 */
    /* saturation at both ends, for any finite input */
    assert_status(pma_dac_kpa_to_counts(&regulator, -50.0f, &c), PMA_OK);
    TEST_ASSERT_EQUAL_INT(0, c);
    assert_status(pma_dac_kpa_to_counts(&regulator, 601.0f, &c), PMA_OK);
    TEST_ASSERT_EQUAL_INT(4095, c);
    assert_status(pma_dac_kpa_to_counts(&regulator, 3e38f, &c), PMA_OK); /* product overflows */
    TEST_ASSERT_EQUAL_INT(4095, c);
    assert_status(pma_dac_kpa_to_counts(&regulator, -3e38f, &c), PMA_OK);
    TEST_ASSERT_EQUAL_INT(0, c);
    /* a narrower output window (e.g. a 2-8 V regulator input) */
    pma_dac_scaling_t w = regulator;
    w.min_counts = 819;
    w.max_counts = 3276;
    assert_status(pma_dac_kpa_to_counts(&w, 0.0f, &c), PMA_OK);
    TEST_ASSERT_EQUAL_INT(819, c);
    assert_status(pma_dac_kpa_to_counts(&w, 590.0f, &c), PMA_OK);
    TEST_ASSERT_EQUAL_INT(3276, c);
    /* NaN and infinity: error, output untouched */
    c = 1234;
    assert_status(pma_dac_kpa_to_counts(&regulator, NAN, &c), PMA_ERR_NOT_FINITE);
    assert_status(pma_dac_kpa_to_counts(&regulator, INFINITY, &c), PMA_ERR_NOT_FINITE);
    TEST_ASSERT_EQUAL_INT(1234, c);
}

static void test_dac_validation(void)
{
    uint16_t c;
    assert_status(pma_dac_validate_scaling(&regulator), PMA_OK);
    assert_status(pma_dac_validate_scaling(NULL), PMA_ERR_NULL);
    assert_status(pma_dac_kpa_to_counts(&regulator, 1.0f, NULL), PMA_ERR_NULL);
    pma_dac_scaling_t s = regulator;
    s.counts_per_kpa = 0.0f;
    assert_status(pma_dac_kpa_to_counts(&s, 1.0f, &c), PMA_ERR_RANGE);
    s = regulator;
    s.counts_at_zero_kpa = NAN;
    assert_status(pma_dac_validate_scaling(&s), PMA_ERR_NOT_FINITE);
    s = regulator;
    s.min_counts = 5;
    s.max_counts = 4;
    assert_status(pma_dac_validate_scaling(&s), PMA_ERR_RANGE);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_adc_converts_valid_range);
    RUN_TEST(test_adc_range_and_wire_break);
    RUN_TEST(test_adc_validation);
    RUN_TEST(test_adc_inverse);
    RUN_TEST(test_dac_scaling_and_saturation);
    RUN_TEST(test_dac_validation);
    return UNITY_END();
}
