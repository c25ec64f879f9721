/* SPDX-License-Identifier: Apache-2.0 */
/*
 * pma_board.h on QEMU's microbit (nRF51822, Cortex-M0). The nRF51 has no SysTick.
 *
 * Timer: TIMER0 at 0x40008000 in timer mode, 32-bit, prescaler 0: 16 MHz, 62.5 ns per tick.
 * The counter is read by triggering TASKS_CAPTURE[0] and reading CC[0]. QEMU's model
 * (hw/timer/nrf51_timer.c) derives the count from QEMU_CLOCK_VIRTUAL, so under -icount shift=0 a
 * tick is exactly 62.5 instructions.
 */
#include "pma_board.h"

#ifndef PMA_BOARD_NAME
#define PMA_BOARD_NAME "microbit"
#endif

#define NRF_TIMER0_BASE 0x40008000u
#define NRF_TIMER_REG(off) (*(volatile uint32_t *)(NRF_TIMER0_BASE + (off)))
#define NRF_TIMER_TASKS_START NRF_TIMER_REG(0x000u)
#define NRF_TIMER_TASKS_STOP NRF_TIMER_REG(0x004u)
#define NRF_TIMER_TASKS_CLEAR NRF_TIMER_REG(0x00Cu)
#define NRF_TIMER_TASKS_CAPTURE0 NRF_TIMER_REG(0x040u)
#define NRF_TIMER_MODE NRF_TIMER_REG(0x504u)
#define NRF_TIMER_BITMODE NRF_TIMER_REG(0x508u)
#define NRF_TIMER_PRESCALER NRF_TIMER_REG(0x510u)
#define NRF_TIMER_CC0 NRF_TIMER_REG(0x540u)

#define NRF_TIMER_MODE_TIMER 0u
#define NRF_TIMER_BITMODE_32 3u

void pma_board_timer_start(void)
{
    NRF_TIMER_TASKS_STOP = 1u;
    NRF_TIMER_MODE = NRF_TIMER_MODE_TIMER;
    NRF_TIMER_BITMODE = NRF_TIMER_BITMODE_32;
    NRF_TIMER_PRESCALER = 0u;
    NRF_TIMER_TASKS_CLEAR = 1u;
    NRF_TIMER_TASKS_START = 1u;
}

uint32_t pma_board_timer_elapsed_ns(void)
{
    NRF_TIMER_TASKS_CAPTURE0 = 1u;
    uint32_t ticks = NRF_TIMER_CC0;
    /* 62.5 ns per tick; wraps mod 2^32 as documented */
    return (uint32_t)(((uint64_t)ticks * 125u) / 2u);
}

uint32_t pma_board_timer_resolution_ns(void)
{
    return 63u; /* 62.5 rounded up */
}

const char *pma_board_name(void)
{
    return PMA_BOARD_NAME;
}

const char *pma_board_time_unit(void)
{
    return "instructions";
}
