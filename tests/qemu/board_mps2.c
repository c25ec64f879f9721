/* SPDX-License-Identifier: Apache-2.0 */
/*
 * pma_board.h on QEMU's mps2-an385 (Cortex-M3) and mps2-an386 (Cortex-M4F).
 *
 * Timer: CMSDK APB TIMER0 at 0x40000000, clocked by the 25 MHz system clock on these FPGA
 * images: a 32-bit down-counter, 40 ns per tick, no interrupt needed (it wraps after 171 s).
 * Under -icount shift=0 one tick is exactly 40 instructions.
 */
#include "pma_board.h"

#ifndef PMA_BOARD_NAME
#define PMA_BOARD_NAME "mps2"
#endif

#define CMSDK_TIMER0_BASE 0x40000000u
#define CMSDK_TIMER_CTRL (*(volatile uint32_t *)(CMSDK_TIMER0_BASE + 0x00u))
#define CMSDK_TIMER_VALUE (*(volatile uint32_t *)(CMSDK_TIMER0_BASE + 0x04u))
#define CMSDK_TIMER_RELOAD (*(volatile uint32_t *)(CMSDK_TIMER0_BASE + 0x08u))
#define CMSDK_TIMER_INTCLEAR (*(volatile uint32_t *)(CMSDK_TIMER0_BASE + 0x0Cu))
#define CMSDK_TIMER_CTRL_ENABLE 0x1u

#define MPS2_TIMER_NS_PER_TICK 40u /* 25 MHz */

void pma_board_timer_start(void)
{
    CMSDK_TIMER_CTRL = 0u;
    CMSDK_TIMER_INTCLEAR = 1u;
    CMSDK_TIMER_RELOAD = 0xFFFFFFFFu;
    CMSDK_TIMER_VALUE = 0xFFFFFFFFu;
    CMSDK_TIMER_CTRL = CMSDK_TIMER_CTRL_ENABLE;
}

uint32_t pma_board_timer_elapsed_ns(void)
{
    uint32_t ticks = 0xFFFFFFFFu - CMSDK_TIMER_VALUE;
    return ticks * MPS2_TIMER_NS_PER_TICK; /* wraps mod 2^32 as documented */
}

uint32_t pma_board_timer_resolution_ns(void)
{
    return MPS2_TIMER_NS_PER_TICK;
}

const char *pma_board_name(void)
{
    return PMA_BOARD_NAME;
}

const char *pma_board_time_unit(void)
{
    return "instructions";
}
