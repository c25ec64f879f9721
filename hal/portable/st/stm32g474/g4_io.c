/* SPDX-License-Identifier: Apache-2.0 */
/* The register blocks (g4_io.h) and the NVIC helpers. */
#include "g4_drivers.h" /* G4_NVM_BASE */

/* ST's base addresses (stm32g474xx.h; SRAMCAN_BASE: FDCAN1's message RAM comes first) */
#define G4_IO_HARDWARE                                                                         \
    {                                                                                          \
        .rcc = RCC, .pwr = PWR, .flash = FLASH, .gpioa = GPIOA, .gpiob = GPIOB, .tim2 = TIM2,  \
        .tim6 = TIM6, .adc1 = ADC1, .adc12_common = ADC12_COMMON, .dac1 = DAC1,                \
        .fdcan1 = FDCAN1, .fdcan_config = FDCAN_CONFIG,                                        \
        .mram = (volatile uint32_t *)SRAMCAN_BASE, .iwdg = IWDG, .nvic = NVIC,                 \
        .nvm = G4_NVM_BASE, .uid = (const volatile uint8_t *)UID_BASE,                         \
    }

g4_io_t g4_io = G4_IO_HARDWARE;

void g4_io_use_hardware(void)
{
    const g4_io_t hw = G4_IO_HARDWARE;
    g4_io = hw;
}

/* NVIC: what CMSIS-Core's NVIC_SetPriority / NVIC_EnableIRQ / NVIC_DisableIRQ /
 * NVIC_SetPendingIRQ do, but through g4_io.nvic instead of the fixed NVIC
 * address, so that the host test sees the writes. ISER/ICER/ISPR hold 32
 * interrupts per word; IPR one byte per interrupt, of which the G4
 * implements the upper __NVIC_PRIO_BITS (4). */
void g4_nvic_enable(IRQn_Type irq, uint8_t priority)
{
    const uint32_t n = (uint32_t)irq;
    g4_io.nvic->IPR[n] = (uint8_t)(priority << (8u - __NVIC_PRIO_BITS));
    g4_io.nvic->ISER[n / 32u] = 1u << (n % 32u);
}

void g4_nvic_disable(IRQn_Type irq)
{
    const uint32_t n = (uint32_t)irq;
    g4_io.nvic->ICER[n / 32u] = 1u << (n % 32u);
}

void g4_nvic_set_pending(IRQn_Type irq)
{
    const uint32_t n = (uint32_t)irq;
    g4_io.nvic->ISPR[n / 32u] = 1u << (n % 32u);
}
