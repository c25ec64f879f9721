/* SPDX-License-Identifier: Apache-2.0 */
/* Time base (TIM2) and control tick (TIM6), RM0440 sections 28 and 30.
 *
 * Shared with the interrupts: tim2_wraps and ticks are written only by
 * their interrupt handler and read by the main loop (single producer,
 * single consumer; 32-bit loads and stores are atomic on the Cortex-M4). */
#include "g4_drivers.h"

static volatile uint32_t tim2_wraps;     /* TIM2 overflows (2^32 us each, 71.6 min) */
static volatile uint32_t ticks;          /* TIM6 updates since g4_tick_start */
static uint32_t ticks_served;            /* the tick count tick_wait last returned for */
static uint8_t tick_running;

#define TIM_PRIO 1u                      /* above FDCAN (2): the clock never lags */

static uint32_t psc_for_1mhz(uint32_t timclk_hz)
{
    return timclk_hz / 1000000u - 1u;    /* 170 MHz: 169 */
}

void g4_time_init(uint32_t timclk_hz)
{
    TIM_TypeDef *const tim = g4_io.tim2;
    SET_BIT(g4_io.rcc->APB1ENR1, RCC_APB1ENR1_TIM2EN);
    (void)READ_REG(g4_io.rcc->APB1ENR1);
    WRITE_REG(tim->CR1, 0u);
    WRITE_REG(tim->PSC, _VAL2FLD(TIM_PSC_PSC, psc_for_1mhz(timclk_hz)));
    WRITE_REG(tim->ARR, 0xFFFFFFFFu); /* TIM2's counter is 32 bits */
    /* URS: only an overflow raises UIF, not the UG that loads the prescaler */
    WRITE_REG(tim->CR1, TIM_CR1_URS);
    WRITE_REG(tim->EGR, TIM_EGR_UG);
    WRITE_REG(tim->SR, 0u);
    WRITE_REG(tim->DIER, TIM_DIER_UIE);
    tim2_wraps = 0;
    g4_nvic_enable(TIM2_IRQn, TIM_PRIO);
    WRITE_REG(tim->CR1, TIM_CR1_URS | TIM_CR1_CEN);
}

void g4_time_isr(void)
{
    if (READ_BIT(g4_io.tim2->SR, TIM_SR_UIF)) {
        WRITE_REG(g4_io.tim2->SR, ~(uint32_t)TIM_SR_UIF); /* rc_w0: write 0 clears */
        tim2_wraps = tim2_wraps + 1u;
    }
}

uint64_t g4_time_us(void)
{
    uint32_t hi, lo, pending;
    do {
        hi = tim2_wraps;
        lo = READ_REG(g4_io.tim2->CNT);
        pending = READ_BIT(g4_io.tim2->SR, TIM_SR_UIF);
    } while (hi != tim2_wraps);
    /* the counter wrapped but its interrupt has not run yet (called with a
     * higher priority or interrupts masked): a small count belongs to the
     * next 2^32 */
    if (pending && lo < 0x80000000u) ++hi;
    return ((uint64_t)hi << 32) | lo;
}

int g4_tick_config(uint32_t timclk_hz, uint32_t period_us, g4_tick_regs_t *regs)
{
    if (regs == NULL) return PMA_ERR_NULL;
    if (period_us == 0u || period_us > 65536u || timclk_hz < 1000000u ||
        timclk_hz % 1000000u != 0u) {
        return PMA_ERR_RANGE;
    }
    regs->psc = psc_for_1mhz(timclk_hz);
    regs->arr = period_us - 1u;            /* the counter runs 0..ARR: ARR + 1 counts of 1 us */
    return PMA_OK;
}

int g4_tick_start(uint32_t timclk_hz, uint32_t period_us)
{
    g4_tick_regs_t r;
    const int rc = g4_tick_config(timclk_hz, period_us, &r);
    if (rc != PMA_OK) return rc;
    TIM_TypeDef *const tim = g4_io.tim6;
    SET_BIT(g4_io.rcc->APB1ENR1, RCC_APB1ENR1_TIM6EN);
    (void)READ_REG(g4_io.rcc->APB1ENR1);
    WRITE_REG(tim->CR1, 0u);
    WRITE_REG(tim->DIER, 0u);
    WRITE_REG(tim->PSC, _VAL2FLD(TIM_PSC_PSC, r.psc));
    WRITE_REG(tim->ARR, r.arr); /* <= 0xFFFF (g4_tick_config): TIM6 is a 16-bit timer */
    WRITE_REG(tim->CR1, TIM_CR1_URS | TIM_CR1_ARPE);
    WRITE_REG(tim->EGR, TIM_EGR_UG); /* load PSC, counter to 0 */
    WRITE_REG(tim->SR, 0u);
    ticks_served = ticks;                  /* the first tick falls one period from now */
    tick_running = 1;
    WRITE_REG(tim->DIER, TIM_DIER_UIE);
    g4_nvic_enable(TIM6_DAC_IRQn, TIM_PRIO);
    WRITE_REG(tim->CR1, TIM_CR1_URS | TIM_CR1_ARPE | TIM_CR1_CEN);
    return PMA_OK;
}

void g4_tick_stop(void)
{
    WRITE_REG(g4_io.tim6->CR1, 0u);
    WRITE_REG(g4_io.tim6->DIER, 0u);
    g4_nvic_disable(TIM6_DAC_IRQn);
    tick_running = 0;
}

void g4_tick_isr(void)
{
    if (READ_BIT(g4_io.tim6->SR, TIM_SR_UIF)) {
        WRITE_REG(g4_io.tim6->SR, ~(uint32_t)TIM_SR_UIF);
        ticks = ticks + 1u;
    }
}

int g4_tick_wait(uint32_t *late_ticks)
{
    if (!tick_running) return PMA_ERR_NOT_READY;
    uint32_t now = ticks;
    uint32_t late = now - ticks_served;     /* ticks that passed before this call */
    if (late == 0u) {
        /* sleep until the tick interrupt; interrupts masked around the check
         * so that a tick between the check and WFI cannot be slept through
         * (WFI wakes on a pending interrupt even while masked) */
        g4_cpu_irq_disable();
        while ((now = ticks) == ticks_served) {
            g4_cpu_wait_for_interrupt();
            g4_cpu_irq_enable();            /* let the handler run */
            g4_cpu_irq_disable();
        }
        g4_cpu_irq_enable();
    }
    ticks_served = now;
    if (late_ticks != NULL) *late_ticks = late;
    return PMA_OK;
}
