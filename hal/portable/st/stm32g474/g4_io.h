/* Register access of the STM32G474 port. Every driver reaches its registers
 * through the base addresses in g4_io (never through a constant address), so
 * that a host test can point a peripheral at a RAM register file
 * (tests/board/test_g4_drivers.c). On the board g4_io holds the addresses of
 * g4_regs.h. Polling waits are bounded by an iteration count, not a clock:
 * a peripheral that never answers gives an error instead of a hang (and a
 * RAM register file without the ready bit fails the same way). */
#ifndef G4_IO_H
#define G4_IO_H

#include <stdint.h>

#include "g4_regs.h"

typedef struct g4_io {
    uintptr_t rcc, pwr, flash, gpioa, gpiob, tim2, tim6, adc1, adc12_common, dac1, fdcan1, mram,
        iwdg, dbgmcu, nvic;
    uintptr_t nvm;        /* the first byte of the two parameter pages (flash memory itself) */
} g4_io_t;

extern g4_io_t g4_io;

/* Sets g4_io to the board's addresses (the state at start-up). */
void g4_io_use_hardware(void);

static inline uint32_t g4_rd(uintptr_t base, uint32_t offset)
{
    return *(volatile const uint32_t *)(base + offset);
}

static inline void g4_wr(uintptr_t base, uint32_t offset, uint32_t value)
{
    *(volatile uint32_t *)(base + offset) = value;
}

/* Read-modify-write: clears `clear` and sets `set` (never on registers with
 * write-1-to-clear bits). */
static inline void g4_rmw(uintptr_t base, uint32_t offset, uint32_t clear, uint32_t set)
{
    g4_wr(base, offset, (g4_rd(base, offset) & ~clear) | set);
}

/* Field value helpers: FIELD(v, X) puts v into field X (X_Pos / X_Msk). */
#define G4_FIELD(value, name) (((uint32_t)(value) << name##_Pos) & name##_Msk)
#define G4_GET(reg, name) (((uint32_t)(reg) & name##_Msk) >> name##_Pos)

/* The two register behaviours a RAM register file cannot have; on the board
 * (g4_cpu.c) plain register accesses, in a host test the fake's versions:
 *   g4_wait  polls until (register & mask) == want; 0 when it did within
 *            max_polls reads, -1 otherwise (the fake completes what the
 *            hardware would: ready bits, self-clearing bits, BSY);
 *   g4_w1c   clears status bits that are cleared by writing 1 to them. */
int g4_wait(uintptr_t base, uint32_t offset, uint32_t mask, uint32_t want, uint32_t max_polls);
void g4_w1c(uintptr_t base, uint32_t offset, uint32_t bits);

/* Polls for the bounded waits: about 1 ms at 170 MHz (a read is a few
 * cycles); the slowest (HSE start-up, 2 ms typ.) loops longer. */
#define G4_POLLS_SHORT 100000u
#define G4_POLLS_LONG 4000000u  /* flash page erase: 22 ms max (DS12288) */

/* CPU (g4_cpu.c on the board; a host test defines its own) and NVIC (g4_io.c). */
void g4_cpu_wait_for_interrupt(void);
void g4_cpu_irq_disable(void);  /* PRIMASK, for the few instructions that need it */
void g4_cpu_irq_enable(void);
void g4_nvic_enable(uint32_t irq, uint8_t priority);
void g4_nvic_disable(uint32_t irq);
void g4_nvic_set_pending(uint32_t irq);
void g4_cpu_delay_cycles(uint32_t cycles);

#endif /* G4_IO_H */
