/* SPDX-License-Identifier: Apache-2.0 */
/* pma/hal.h on the STM32G474 (the port's functions over its drivers, g4_*.c). */
#include "pma_hal_stm32g474.h"

#include <stddef.h>

#include "g4_drivers.h"

static uint8_t hal_up;
static uint8_t reset_cause_latched;
static pma_reset_cause_t reset_cause = PMA_RESET_UNKNOWN;
static g4_clock_source_t clock_source;

void pma_hal_stm32g474_system_init(void)
{
    reset_cause = g4_reset_latch();
    reset_cause_latched = 1;
    clock_source = g4_clock_init(G4_HSE_HZ != 0u); /* HSE 0: HSI16 only */
    g4_time_init(g4_clock_sysclk_hz());
    /* the LED pin, so that the board can signal even when init fails */
    SET_BIT(g4_io.rcc->AHB2ENR, RCC_AHB2ENR_GPIOAEN);
    (void)READ_REG(g4_io.rcc->AHB2ENR);
    g4_gpio_write(g4_io.gpioa, G4_LED_PIN, 0);
    g4_gpio_mode(g4_io.gpioa, G4_LED_PIN, G4_GPIO_MODE_OUTPUT);
}

int pma_hal_stm32g474_clock_source(void)
{
    return (int)clock_source;
}

void pma_hal_stm32g474_led_set(int on)
{
    g4_gpio_write(g4_io.gpioa, G4_LED_PIN, on);
}

int pma_hal_init(const pma_hal_config_t *cfg)
{
    hal_up = 0;
    if (clock_source == 0) return PMA_ERR_IO; /* no 170 MHz: every timing below would be wrong */
    g4_tick_stop();
    const uint32_t bps = (cfg != NULL && cfg->can_bitrate_bps != 0u) ? cfg->can_bitrate_bps
                                                                     : PMA_HAL_CAN_DEFAULT_BITRATE_BPS;
    int rc = g4_dac_init(); /* first: the output at 0 V as early as possible */
    if (rc == PMA_OK) rc = g4_adc_init();
    if (rc == PMA_OK) rc = g4_can_init(g4_clock_sysclk_hz(), bps);
    if (rc != PMA_OK) return rc;
    hal_up = 1;
    return PMA_OK;
}

void pma_hal_deinit(void)
{
    hal_up = 0;
    g4_tick_stop();
    g4_can_stop();
    g4_adc_stop();
}

const char *pma_hal_port_name(void)
{
    return "stm32g474";
}

int pma_hal_adc_read(uint16_t *raw_counts)
{
    if (raw_counts == NULL) return PMA_ERR_NULL;
    if (!hal_up) return PMA_ERR_NOT_READY;
    return g4_adc_read(raw_counts);
}

int pma_hal_dac_write(uint16_t counts)
{
    if (!hal_up) return PMA_ERR_NOT_READY;
    return g4_dac_write(counts);
}

int pma_hal_can_send(const pma_can_frame_t *frame)
{
    if (frame == NULL) return PMA_ERR_NULL;
    if (!hal_up) return PMA_ERR_NOT_READY;
    return g4_can_send(frame);
}

int pma_hal_can_recv(pma_can_frame_t *frame)
{
    if (frame == NULL) return PMA_ERR_NULL;
    if (!hal_up) return PMA_ERR_NOT_READY;
    return g4_can_recv(frame);
}

int pma_hal_can_set_filters(const pma_can_filter_t *filters, size_t count)
{
    if (!hal_up) return PMA_ERR_NOT_READY;
    return g4_can_set_filters(filters, count);
}

int pma_hal_can_status(pma_can_status_t *status)
{
    if (status == NULL) return PMA_ERR_NULL;
    if (!hal_up) return PMA_ERR_NOT_READY;
    return g4_can_status(status);
}

int pma_hal_can_recover(void)
{
    if (!hal_up) return PMA_ERR_NOT_READY;
    return g4_can_recover();
}

uint64_t pma_hal_time_us(void)
{
    return g4_time_us();
}

int pma_hal_tick_start(uint32_t period_us)
{
    if (period_us == 0u) return PMA_ERR_RANGE;
    if (!hal_up) return PMA_ERR_NOT_READY;
    return g4_tick_start(g4_clock_sysclk_hz(), period_us);
}

int pma_hal_tick_wait(uint32_t *late_ticks)
{
    if (!hal_up) return PMA_ERR_NOT_READY;
    return g4_tick_wait(late_ticks);
}

int pma_hal_nvm_geometry(pma_nvm_geometry_t *geometry)
{
    if (geometry == NULL) return PMA_ERR_NULL;
    if (!hal_up) return PMA_ERR_NOT_READY;
    return g4_flash_geometry(geometry);
}

int pma_hal_nvm_read(uint32_t block, uint32_t offset, void *buf, uint32_t len)
{
    if (buf == NULL) return PMA_ERR_NULL;
    if (!hal_up) return PMA_ERR_NOT_READY;
    return g4_flash_read(block, offset, buf, len);
}

int pma_hal_nvm_program(uint32_t block, uint32_t offset, const void *data, uint32_t len)
{
    if (data == NULL) return PMA_ERR_NULL;
    if (!hal_up) return PMA_ERR_NOT_READY;
    return g4_flash_program(block, offset, data, len);
}

int pma_hal_nvm_erase(uint32_t block)
{
    if (!hal_up) return PMA_ERR_NOT_READY;
    return g4_flash_erase(block);
}

int pma_hal_watchdog_start(uint32_t timeout_ms)
{
    return g4_iwdg_start(timeout_ms);
}

void pma_hal_watchdog_kick(void)
{
    g4_iwdg_kick();
}

pma_reset_cause_t pma_hal_reset_cause(void)
{
    if (!reset_cause_latched) {
        reset_cause = g4_reset_latch();
        reset_cause_latched = 1;
    }
    return reset_cause;
}

void pma_hal_system_reset(void)
{
    const uint64_t deadline_us = g4_time_us() + PMA_HAL_RESET_TX_FLUSH_US;
    while (!g4_can_tx_idle() && g4_time_us() < deadline_us) {
        g4_iwdg_kick(); /* the wait is bounded: the watchdog must not cut it short */
    }
    g4_cpu_system_reset(); /* RCC_CSR SFTRSTF: the next start reads PMA_RESET_SOFTWARE */
}

void pma_hal_stm32g474_device_uid(uint8_t uid[PMA_HAL_STM32G474_UID_BYTES])
{
    for (unsigned k = 0; k < PMA_HAL_STM32G474_UID_BYTES; ++k) uid[k] = g4_io.uid[k];
}
