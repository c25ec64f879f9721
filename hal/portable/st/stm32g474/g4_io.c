/* Base addresses of the registers (g4_io.h) and the NVIC helpers. */
#include "g4_drivers.h" /* G4_NVM_BASE */

g4_io_t g4_io = {
    .rcc = G4_RCC_BASE, .pwr = G4_PWR_BASE, .flash = G4_FLASH_BASE, .gpioa = G4_GPIOA_BASE,
    .gpiob = G4_GPIOB_BASE, .tim2 = G4_TIM2_BASE, .tim6 = G4_TIM6_BASE, .adc1 = G4_ADC1_BASE,
    .adc12_common = G4_ADC12_COMMON_BASE, .dac1 = G4_DAC1_BASE, .fdcan1 = G4_FDCAN1_BASE,
    .mram = G4_MRAM_BASE, .iwdg = G4_IWDG_BASE, .dbgmcu = G4_DBGMCU_BASE, .nvic = G4_NVIC_BASE,
    .nvm = G4_NVM_BASE,
};

void g4_io_use_hardware(void)
{
    const g4_io_t hw = {
        .rcc = G4_RCC_BASE, .pwr = G4_PWR_BASE, .flash = G4_FLASH_BASE, .gpioa = G4_GPIOA_BASE,
        .gpiob = G4_GPIOB_BASE, .tim2 = G4_TIM2_BASE, .tim6 = G4_TIM6_BASE, .adc1 = G4_ADC1_BASE,
        .adc12_common = G4_ADC12_COMMON_BASE, .dac1 = G4_DAC1_BASE, .fdcan1 = G4_FDCAN1_BASE,
        .mram = G4_MRAM_BASE, .iwdg = G4_IWDG_BASE, .dbgmcu = G4_DBGMCU_BASE,
        .nvic = G4_NVIC_BASE, .nvm = G4_NVM_BASE,
    };
    g4_io = hw;
}

/* NVIC: ISERn/ICERn/ISPRn hold 32 interrupts each; IPRn one byte per
 * interrupt, of which the G4 implements the upper 4 bits. */
void g4_nvic_enable(uint32_t irq, uint8_t priority)
{
    const uint32_t ipr = G4_NVIC_IPR0_OFFSET + (irq & ~3u);
    const uint32_t shift = 8u * (irq & 3u);
    g4_rmw(g4_io.nvic, ipr, 0xFFu << shift, (uint32_t)(uint8_t)(priority << 4) << shift);
    g4_wr(g4_io.nvic, G4_NVIC_ISER0_OFFSET + 4u * (irq / 32u), 1u << (irq % 32u));
}

void g4_nvic_disable(uint32_t irq)
{
    g4_wr(g4_io.nvic, G4_NVIC_ICER0_OFFSET + 4u * (irq / 32u), 1u << (irq % 32u));
}

void g4_nvic_set_pending(uint32_t irq)
{
    g4_wr(g4_io.nvic, G4_NVIC_ISPR0_OFFSET + 4u * (irq / 32u), 1u << (irq % 32u));
}
