/* SPDX-License-Identifier: Apache-2.0 */
/* Blank template port: every function of pma/hal.h, doing nothing.
 *
 * Copy this directory to hal/portable/<vendor>/<mcu>/ to start a port and
 * fill in the functions one device at a time (docs/hal.md, "Writing a port").
 * Until a device is done its functions return PMA_ERR_NOT_IMPLEMENTED; the
 * functions that cannot fail do nothing or return a neutral value:
 *   pma_hal_deinit, pma_hal_watchdog_kick: nothing;
 *   pma_hal_time_us: 0 (a real port must count);
 *   pma_hal_reset_cause: PMA_RESET_UNKNOWN;
 *   pma_hal_system_reset: returns (a port must reset the MCU here).
 *
 * It is compiled on every preset (library `pma_hal_template`) so that the
 * interface and this file cannot drift apart, and tests/hal/test_hal_template.c
 * links it to check that every function exists.
 *
 * Device state of a real port lives here, in static storage (the hardware is
 * global): e.g. the CAN RX ring filled by the CAN interrupt, the tick counter
 * incremented by the timer interrupt. Share such state with an interrupt
 * through single-producer/single-consumer indices (volatile or C11 atomics),
 * never by disabling interrupts for long. */
#include "pma/hal.h"

#include <stddef.h>

int pma_hal_init(const pma_hal_config_t *cfg)
{
    (void)cfg; /* clocks, GPIO, CAN bit timing (cfg->can_bitrate_bps), ADC, DAC, timers */
    return PMA_ERR_NOT_IMPLEMENTED;
}

void pma_hal_deinit(void)
{
}

const char *pma_hal_port_name(void)
{
    return "template";
}

int pma_hal_adc_read(uint16_t *raw_counts)
{
    if (raw_counts == NULL) return PMA_ERR_NULL;
    return PMA_ERR_NOT_IMPLEMENTED;
}

int pma_hal_dac_write(uint16_t counts)
{
    (void)counts;
    return PMA_ERR_NOT_IMPLEMENTED;
}

int pma_hal_can_send(const pma_can_frame_t *frame)
{
    if (frame == NULL) return PMA_ERR_NULL;
    return PMA_ERR_NOT_IMPLEMENTED;
}

int pma_hal_can_recv(pma_can_frame_t *frame)
{
    if (frame == NULL) return PMA_ERR_NULL;
    return PMA_ERR_NOT_IMPLEMENTED;
}

int pma_hal_can_set_filters(const pma_can_filter_t *filters, size_t count)
{
    (void)filters;
    (void)count;
    return PMA_ERR_NOT_IMPLEMENTED;
}

int pma_hal_can_status(pma_can_status_t *status)
{
    if (status == NULL) return PMA_ERR_NULL;
    return PMA_ERR_NOT_IMPLEMENTED;
}

int pma_hal_can_recover(void)
{
    return PMA_ERR_NOT_IMPLEMENTED;
}

uint64_t pma_hal_time_us(void)
{
    return 0;
}

int pma_hal_tick_start(uint32_t period_us)
{
    (void)period_us;
    return PMA_ERR_NOT_IMPLEMENTED;
}

int pma_hal_tick_wait(uint32_t *late_ticks)
{
    (void)late_ticks; /* a real port sleeps (WFI) until the timer interrupt counts a tick */
    return PMA_ERR_NOT_IMPLEMENTED;
}

int pma_hal_nvm_geometry(pma_nvm_geometry_t *geometry)
{
    if (geometry == NULL) return PMA_ERR_NULL;
    return PMA_ERR_NOT_IMPLEMENTED;
}

int pma_hal_nvm_read(uint32_t block, uint32_t offset, void *buf, uint32_t len)
{
    (void)block;
    (void)offset;
    (void)len;
    if (buf == NULL) return PMA_ERR_NULL;
    return PMA_ERR_NOT_IMPLEMENTED;
}

int pma_hal_nvm_program(uint32_t block, uint32_t offset, const void *data, uint32_t len)
{
    (void)block;
    (void)offset;
    (void)len;
    if (data == NULL) return PMA_ERR_NULL;
    return PMA_ERR_NOT_IMPLEMENTED;
}

int pma_hal_nvm_erase(uint32_t block)
{
    (void)block;
    return PMA_ERR_NOT_IMPLEMENTED;
}

int pma_hal_watchdog_start(uint32_t timeout_ms)
{
    (void)timeout_ms;
    return PMA_ERR_NOT_IMPLEMENTED;
}

void pma_hal_watchdog_kick(void)
{
}

pma_reset_cause_t pma_hal_reset_cause(void)
{
    return PMA_RESET_UNKNOWN;
}

void pma_hal_system_reset(void)
{
}
