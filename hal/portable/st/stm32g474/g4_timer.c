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
    g4_rmw(g4_io.rcc, G4_RCC_APB1ENR1_OFFSET, 0u, G4_RCC_APB1ENR1_TIM2EN_Msk);
    (void)g4_rd(g4_io.rcc, G4_RCC_APB1ENR1_OFFSET);
    g4_wr(g4_io.tim2, G4_TIM2_CR1_OFFSET, 0u);
    g4_wr(g4_io.tim2, G4_TIM2_PSC_OFFSET, G4_FIELD(psc_for_1mhz(timclk_hz), G4_TIM2_PSC_PSC));
    g4_wr(g4_io.tim2, G4_TIM2_ARR_OFFSET, 0xFFFFFFFFu);
    /* URS: only an overflow raises UIF, not the UG that loads the prescaler */
    g4_wr(g4_io.tim2, G4_TIM2_CR1_OFFSET, G4_TIM2_CR1_URS_Msk);
    g4_wr(g4_io.tim2, G4_TIM2_EGR_OFFSET, G4_TIM2_EGR_UG_Msk);
    g4_wr(g4_io.tim2, G4_TIM2_SR_OFFSET, 0u);
    g4_wr(g4_io.tim2, G4_TIM2_DIER_OFFSET, G4_TIM2_DIER_UIE_Msk);
    tim2_wraps = 0;
    g4_nvic_enable(G4_IRQ_TIM2, TIM_PRIO);
    g4_wr(g4_io.tim2, G4_TIM2_CR1_OFFSET, G4_TIM2_CR1_URS_Msk | G4_TIM2_CR1_CEN_Msk);
}

void g4_time_isr(void)
{
    if (g4_rd(g4_io.tim2, G4_TIM2_SR_OFFSET) & G4_TIM2_SR_UIF_Msk) {
        g4_wr(g4_io.tim2, G4_TIM2_SR_OFFSET, ~G4_TIM2_SR_UIF_Msk); /* rc_w0: write 0 clears */
        tim2_wraps = tim2_wraps + 1u;
    }
}

uint64_t g4_time_us(void)
{
    uint32_t hi, lo, pending;
    do {
        hi = tim2_wraps;
        lo = g4_rd(g4_io.tim2, G4_TIM2_CNT_OFFSET);
        pending = g4_rd(g4_io.tim2, G4_TIM2_SR_OFFSET) & G4_TIM2_SR_UIF_Msk;
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
    g4_rmw(g4_io.rcc, G4_RCC_APB1ENR1_OFFSET, 0u, G4_RCC_APB1ENR1_TIM6EN_Msk);
    (void)g4_rd(g4_io.rcc, G4_RCC_APB1ENR1_OFFSET);
    g4_wr(g4_io.tim6, G4_TIM6_CR1_OFFSET, 0u);
    g4_wr(g4_io.tim6, G4_TIM6_DIER_OFFSET, 0u);
    g4_wr(g4_io.tim6, G4_TIM6_PSC_OFFSET, G4_FIELD(r.psc, G4_TIM6_PSC_PSC));
    g4_wr(g4_io.tim6, G4_TIM6_ARR_OFFSET, G4_FIELD(r.arr, G4_TIM6_ARR_ARR));
    g4_wr(g4_io.tim6, G4_TIM6_CR1_OFFSET, G4_TIM6_CR1_URS_Msk | G4_TIM6_CR1_ARPE_Msk);
    g4_wr(g4_io.tim6, G4_TIM6_EGR_OFFSET, G4_TIM6_EGR_UG_Msk); /* load PSC, counter to 0 */
    g4_wr(g4_io.tim6, G4_TIM6_SR_OFFSET, 0u);
    ticks_served = ticks;                  /* the first tick falls one period from now */
    tick_running = 1;
    g4_wr(g4_io.tim6, G4_TIM6_DIER_OFFSET, G4_TIM6_DIER_UIE_Msk);
    g4_nvic_enable(G4_IRQ_TIM6_DACUNDER, TIM_PRIO);
    g4_wr(g4_io.tim6, G4_TIM6_CR1_OFFSET,
          G4_TIM6_CR1_URS_Msk | G4_TIM6_CR1_ARPE_Msk | G4_TIM6_CR1_CEN_Msk);
    return PMA_OK;
}

void g4_tick_stop(void)
{
    g4_wr(g4_io.tim6, G4_TIM6_CR1_OFFSET, 0u);
    g4_wr(g4_io.tim6, G4_TIM6_DIER_OFFSET, 0u);
    g4_nvic_disable(G4_IRQ_TIM6_DACUNDER);
    tick_running = 0;
}

void g4_tick_isr(void)
{
    if (g4_rd(g4_io.tim6, G4_TIM6_SR_OFFSET) & G4_TIM6_SR_UIF_Msk) {
        g4_wr(g4_io.tim6, G4_TIM6_SR_OFFSET, ~G4_TIM6_SR_UIF_Msk);
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
