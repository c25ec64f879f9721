/* Board-only primitives: the CPU instructions the drivers need, and the two
 * register behaviours a host test's RAM register file fakes (g4_io.h). */
#include "g4_io.h"

void g4_cpu_wait_for_interrupt(void)
{
    __asm volatile("dsb\n\twfi" ::: "memory");
}

void g4_cpu_irq_disable(void)
{
    __asm volatile("cpsid i" ::: "memory");
}

void g4_cpu_irq_enable(void)
{
    __asm volatile("cpsie i\n\tisb" ::: "memory");
}

void g4_cpu_delay_cycles(uint32_t cycles)
{
    /* about 3 cycles per iteration (subs + bne); only for short start-up
     * delays that need "at least", never for timing */
    uint32_t n = cycles / 3u + 1u;
    __asm volatile("1: subs %0, %0, #1\n\tbne 1b" : "+r"(n) : : "cc");
}

int g4_wait(uintptr_t base, uint32_t offset, uint32_t mask, uint32_t want, uint32_t max_polls)
{
    for (uint32_t i = 0; i < max_polls; ++i) {
        if ((g4_rd(base, offset) & mask) == want) return 0;
    }
    return -1;
}

void g4_w1c(uintptr_t base, uint32_t offset, uint32_t bits)
{
    g4_wr(base, offset, bits);
}
