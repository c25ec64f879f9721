/* SPDX-License-Identifier: Apache-2.0 */
/* The STM32G474 port (NUCLEO-G474RE): what it adds to pma/hal.h.
 *
 * Devices (docs/hardware.md has the wiring):
 *   position sensor  ADC1_IN1 on PA0 (NUCLEO A0), 12 bits: 0..4095 counts for 0..3.3 V
 *   pressure output  DAC1_OUT1 on PA4 (NUCLEO A2), 12 bits: 0..4095 counts for 0..3.3 V;
 *                    counts above 4095: PMA_ERR_RANGE
 *   CAN              FDCAN1, classic CAN, PA11 RX / PA12 TX (or PB8/PB9), 1 Mbit/s default;
 *                    any rate that divides 170 MHz into 8..25 time quanta
 *   control tick     TIM6, 1 us resolution: period_us 1..65536
 *   clock            TIM2, 1 us, 64 bits
 *   NVM              2 blocks (the last two flash pages), 2 KB each (4 KB single-bank), 8-byte program
 *   watchdog         IWDG, 1..32768 ms
 *   status LED       LD2 on PA5
 *
 * cfg->port is unused (NULL). */
#ifndef PMA_HAL_STM32G474_H
#define PMA_HAL_STM32G474_H

#include <stdint.h>

#include "pma/hal.h"

/* Status LED LD2 (PA5): 1 on, 0 off. Works before pma_hal_init(). */
void pma_hal_stm32g474_led_set(int on);

/* The clock source start-up ended with: 1 HSE crystal, 2 HSI16 (the HSE did
 * not start: CAN timing then has the HSI's +-1 % tolerance), 0 the PLL
 * failed (running at 16 MHz, nothing else is started). */
int pma_hal_stm32g474_clock_source(void);

/* Bytes of the factory-programmed unique device id (RM0440 48.1). */
#define PMA_HAL_STM32G474_UID_BYTES 12u

/* Copies the 96-bit unique device id, byte 0 (UID[7:0]) first: what DEVICE_INFO reports.
 * Works before pma_hal_init(). */
void pma_hal_stm32g474_device_uid(uint8_t uid[PMA_HAL_STM32G474_UID_BYTES]);

/* Start-up (called by the reset handler before main): FPU already on,
 * reset cause latched, clock tree to 170 MHz, time base. */
void pma_hal_stm32g474_system_init(void);

#endif /* PMA_HAL_STM32G474_H */
