/* SPDX-License-Identifier: Apache-2.0 */
/* Register access of the STM32G474 port. Every driver reaches its registers
 * through the register-block pointers in g4_io (never through ST's fixed
 * RCC, FDCAN1 ... macros), so that a host test can point a peripheral at a
 * RAM register file (tests/board/test_g4_drivers.c). The blocks are ST's
 * structs (g4_cmsis.h); on the board g4_io holds ST's base addresses.
 * Polling waits are bounded by an iteration count, not a clock: a
 * peripheral that never answers gives an error instead of a hang (and a
 * RAM register file without the ready bit fails the same way). */
#ifndef G4_IO_H
#define G4_IO_H

#include <stdint.h>

#include "g4_cmsis.h"
#include "g4_port_defs.h"

typedef struct g4_io {
    RCC_TypeDef *rcc;
    PWR_TypeDef *pwr;
    FLASH_TypeDef *flash;
    GPIO_TypeDef *gpioa, *gpiob;
    TIM_TypeDef *tim2, *tim6;
    ADC_TypeDef *adc1;
    ADC_Common_TypeDef *adc12_common;
    DAC_TypeDef *dac1;
    FDCAN_GlobalTypeDef *fdcan1;
    FDCAN_Config_TypeDef *fdcan_config; /* CKDIV, shared by the FDCAN instances */
    volatile uint32_t *mram;            /* FDCAN1's message RAM: G4_MRAM_SIZE bytes */
    IWDG_TypeDef *iwdg;
    NVIC_Type *nvic;
    uintptr_t nvm;        /* the first byte of the two parameter pages (flash memory itself) */
    const volatile uint8_t *uid; /* the 96-bit unique device id (RM0440 48.1: UID_BASE) */
} g4_io_t;

extern g4_io_t g4_io;

/* Sets g4_io to the board's addresses (the state at start-up). */
void g4_io_use_hardware(void);

/* The two register behaviours a RAM register file cannot have; on the board
 * (g4_cpu.c) plain register accesses, in a host test the fake's versions:
 *   g4_wait  polls until (*reg & mask) == want; 0 when it did within
 *            max_polls reads, -1 otherwise (the fake completes what the
 *            hardware would: ready bits, self-clearing bits, BSY);
 *   g4_w1c   clears status bits that are cleared by writing 1 to them. */
int g4_wait(const volatile uint32_t *reg, uint32_t mask, uint32_t want, uint32_t max_polls);
void g4_w1c(volatile uint32_t *reg, uint32_t bits);

/* Polls for the bounded waits: about 1 ms at 170 MHz (a read is a few
 * cycles); the slowest (HSE start-up, 2 ms typ.) loops longer. */
#define G4_POLLS_SHORT 100000u
#define G4_POLLS_LONG 4000000u  /* flash page erase: 22 ms max (DS12288) */

/* CPU (g4_cpu.c on the board, with CMSIS-Core's __WFI, __disable_irq ...; a
 * host test defines its own) and NVIC (g4_io.c, through g4_io.nvic). */
void g4_cpu_wait_for_interrupt(void);
void g4_cpu_irq_disable(void);  /* PRIMASK, for the few instructions that need it */
void g4_cpu_irq_enable(void);
void g4_nvic_enable(IRQn_Type irq, uint8_t priority);
void g4_nvic_disable(IRQn_Type irq);
void g4_nvic_set_pending(IRQn_Type irq);
void g4_cpu_delay_cycles(uint32_t cycles);
void g4_cpu_system_reset(void); /* the Cortex-M system reset (SCB AIRCR SYSRESETREQ) */

#endif /* G4_IO_H */
