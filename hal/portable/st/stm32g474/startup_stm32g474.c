/* SPDX-License-Identifier: Apache-2.0 */
/* Start-up of the STM32G474: vector table, reset handler (.data copy, .bss
 * clear, FPU on), the interrupt handlers of the port, and the default
 * handler. Symbols from stm32g474re.ld: _estack, _sidata, _sdata, _edata,
 * _sbss, _ebss. */
#include <stdint.h>

#include "g4_drivers.h"
#include "pma_hal_stm32g474.h"

extern uint32_t _estack, _sidata, _sdata, _edata, _sbss, _ebss;
int main(void);

void Reset_Handler(void);
void NMI_Handler(void);
void HardFault_Handler(void);
void Default_Handler(void);

void Reset_Handler(void)
{
    /* FPU first (CP10/CP11 full access, PM0214 4.6.1): the compiler may use
     * FP registers anywhere in hard-float code. CMSIS-Core's SCB, a constant
     * address: g4_io is in .data, which is not copied yet. */
    SCB->CPACR |= (3u << 20) | (3u << 22);
    __DSB();
    __ISB();
    uint32_t *src = &_sidata;
    for (uint32_t *dst = &_sdata; dst < &_edata;) *dst++ = *src++;
    for (uint32_t *dst = &_sbss; dst < &_ebss;) *dst++ = 0u;
    pma_hal_stm32g474_system_init();
    (void)main();
    for (;;) {
        /* main never returns; if it did, the watchdog restarts the MCU */
    }
}

void NMI_Handler(void)
{
    /* a flash double ECC error is the one NMI the port expects (a torn
     * parameter record): flagged for the read in progress, which fails
     * with PMA_ERR_CORRUPT. Anything else: stop, the watchdog resets. */
    if (!g4_flash_nmi()) Default_Handler();
}

void HardFault_Handler(void)
{
    Default_Handler();
}

void Default_Handler(void)
{
    for (;;) {
        /* no kick: the watchdog (if started) resets the MCU */
    }
}

static void TIM2_IRQHandler(void)
{
    g4_time_isr();
}

static void TIM6_DAC_IRQHandler(void)
{
    g4_tick_isr();
}

static void FDCAN1_IT0_IRQHandler(void)
{
    g4_can_isr();
}

typedef void (*vector_t)(void);

/* 16 system exceptions, then the G474's 102 interrupt lines (every one
 * listed: an interrupt the port never enables lands in Default_Handler). */
#define D Default_Handler
_Static_assert(G4_IRQ_COUNT == 102u, "the table below lists 102 interrupt lines");
_Static_assert(FDCAN1_IT0_IRQn == 21 && TIM2_IRQn == 28 && TIM6_DAC_IRQn == 54,
               "the handlers below sit at these lines");
__attribute__((section(".isr_vector"), used)) static const vector_t vectors[16 + G4_IRQ_COUNT] = {
    (vector_t)(uintptr_t)&_estack, Reset_Handler, NMI_Handler, HardFault_Handler,
    D /* MemManage */, D /* BusFault */, D /* UsageFault */, 0, 0, 0, 0,
    D /* SVCall */, D /* DebugMon */, 0, D /* PendSV */, D /* SysTick */,
    D, D, D, D, D, D, /* IRQ 0..5 */
    D, D, D, D, D, D, /* IRQ 6..11 */
    D, D, D, D, D, D, /* IRQ 12..17 */
    D, D, D, FDCAN1_IT0_IRQHandler, D, D, /* IRQ 18..23 */
    D, D, D, D, TIM2_IRQHandler, D, /* IRQ 24..29 */
    D, D, D, D, D, D, /* IRQ 30..35 */
    D, D, D, D, D, D, /* IRQ 36..41 */
    D, D, D, D, D, D, /* IRQ 42..47 */
    D, D, D, D, D, D, /* IRQ 48..53 */
    TIM6_DAC_IRQHandler, D, D, D, D, D, /* IRQ 54..59 */
    D, D, D, D, D, D, /* IRQ 60..65 */
    D, D, D, D, D, D, /* IRQ 66..71 */
    D, D, D, D, D, D, /* IRQ 72..77 */
    D, D, D, D, D, D, /* IRQ 78..83 */
    D, D, D, D, D, D, /* IRQ 84..89 */
    D, D, D, D, D, D, /* IRQ 90..95 */
    D, D, D, D, D, D, /* IRQ 96..101 */
};
#undef D
