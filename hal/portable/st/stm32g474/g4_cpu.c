/* SPDX-License-Identifier: Apache-2.0 */
/* Board-only primitives: the CPU instructions the drivers need (CMSIS-Core,
 * core_cm4.h via g4_cmsis.h), and the two register behaviours a host test's
 * RAM register file fakes (g4_io.h). */
#include "g4_io.h"

void g4_cpu_wait_for_interrupt(void)
{
    __DSB();
    __WFI();
}

void g4_cpu_irq_disable(void)
{
    __disable_irq();
}

void g4_cpu_irq_enable(void)
{
    __enable_irq();
    __ISB();
}

void g4_cpu_delay_cycles(uint32_t cycles)
{
    /* about 3 cycles per iteration (subs + bne); only for short start-up
     * delays that need "at least", never for timing (CMSIS has no delay) */
    uint32_t n = cycles / 3u + 1u;
    __ASM volatile("1: subs %0, %0, #1\n\tbne 1b" : "+r"(n) : : "cc");
}

int g4_wait(const volatile uint32_t *reg, uint32_t mask, uint32_t want, uint32_t max_polls)
{
    for (uint32_t i = 0; i < max_polls; ++i) {
        if ((*reg & mask) == want) return 0;
    }
    return -1;
}

void g4_w1c(volatile uint32_t *reg, uint32_t bits)
{
    *reg = bits;
}

void g4_cpu_system_reset(void)
{
    NVIC_SystemReset(); /* CMSIS-Core: DSB, AIRCR.SYSRESETREQ, wait; never returns */
}
