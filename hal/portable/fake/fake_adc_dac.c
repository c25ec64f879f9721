/* SPDX-License-Identifier: Apache-2.0 */
/* Fake port: position sensor (ADC) with injectable faults, and the pressure
 * command output (DAC) with a log of recent writes. */
#include "fake_internal.h"

#include <stddef.h>

typedef enum adc_fault {
    ADC_OK = 0,
    ADC_STUCK,
    ADC_OUT_OF_RANGE,
    ADC_WIRE_BREAK,
    ADC_READ_ERROR,
} adc_fault_t;

static struct {
    uint16_t value;              /* the sensor's true output */
    uint16_t fault_value;        /* what a stuck / out-of-range sensor reads */
    adc_fault_t fault;
    uint32_t reads;
} adc;

static struct {
    pma_fake_dac_write_t log[PMA_FAKE_DAC_LOG_DEPTH]; /* ring, newest at (count - 1) % depth */
    uint32_t count;
    bool fail;                   /* injected: every write fails with PMA_ERR_IO */
} dac;

void pma_fake_adc_dac_reset_(pma_fake_reset_depth_t depth)
{
    /* the sensor and the DAC log are outside the MCU: only a full reset clears them */
    if (depth < PMA_FAKE_RESET_ALL) return;
    adc.value = 0;
    adc.fault_value = 0;
    adc.fault = ADC_OK;
    adc.reads = 0;
    dac.count = 0;
    dac.fail = false;
}

void pma_fake_dac_fail(bool fail)
{
    dac.fail = fail;
}

int pma_hal_adc_read(uint16_t *raw_counts)
{
    if (raw_counts == NULL) return PMA_ERR_NULL;
    if (!pma_fake_initialised()) return PMA_ERR_NOT_READY;
    adc.reads++;
    switch (adc.fault) {
    case ADC_OK: *raw_counts = adc.value; break;
    case ADC_STUCK:
    case ADC_OUT_OF_RANGE: *raw_counts = adc.fault_value; break;
    case ADC_WIRE_BREAK: *raw_counts = PMA_FAKE_ADC_WIRE_BREAK_COUNTS; break;
    case ADC_READ_ERROR:
    default: return PMA_ERR_IO;
    }
    return PMA_OK;
}

void pma_fake_adc_set(uint16_t raw_counts)
{
    adc.value = raw_counts;
}

void pma_fake_adc_stuck(void)
{
    uint16_t now = adc.value;
    if (adc.fault == ADC_STUCK || adc.fault == ADC_OUT_OF_RANGE) now = adc.fault_value;
    if (adc.fault == ADC_WIRE_BREAK) now = PMA_FAKE_ADC_WIRE_BREAK_COUNTS;
    adc.fault_value = now;
    adc.fault = ADC_STUCK;
}

void pma_fake_adc_out_of_range(uint16_t raw_counts)
{
    adc.fault_value = raw_counts;
    adc.fault = ADC_OUT_OF_RANGE;
}

void pma_fake_adc_wire_break(void)
{
    adc.fault = ADC_WIRE_BREAK;
}

void pma_fake_adc_read_error(void)
{
    adc.fault = ADC_READ_ERROR;
}

void pma_fake_adc_clear_fault(void)
{
    adc.fault = ADC_OK;
}

uint32_t pma_fake_adc_read_count(void)
{
    return adc.reads;
}

int pma_hal_dac_write(uint16_t counts)
{
    if (!pma_fake_initialised()) return PMA_ERR_NOT_READY;
    if (dac.fail) return PMA_ERR_IO;
    if (counts > PMA_FAKE_DAC_MAX_COUNTS) return PMA_ERR_RANGE;
    dac.log[dac.count % PMA_FAKE_DAC_LOG_DEPTH] =
        (pma_fake_dac_write_t){.time_us = pma_hal_time_us(), .counts = counts};
    dac.count++;
    return PMA_OK;
}

uint32_t pma_fake_dac_write_count(void)
{
    return dac.count;
}

int pma_fake_dac_log(uint32_t age, pma_fake_dac_write_t *w)
{
    if (w == NULL) return PMA_ERR_NULL;
    if (dac.count == 0) return PMA_ERR_EMPTY;
    if (age >= dac.count || age >= PMA_FAKE_DAC_LOG_DEPTH) return PMA_ERR_RANGE;
    *w = dac.log[(dac.count - 1u - age) % PMA_FAKE_DAC_LOG_DEPTH];
    return PMA_OK;
}
