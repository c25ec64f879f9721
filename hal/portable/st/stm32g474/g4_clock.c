/* Clock tree, GPIO and reset cause (RM0440 sections 6, 7, 9). */
#include "g4_drivers.h"

static uint32_t sysclk_hz = G4_HSI16_HZ;

int g4_pll_for(uint32_t src_hz, uint32_t pllsrc, g4_pll_t *pll)
{
    if (pll == NULL) return PMA_ERR_NULL;
    if (src_hz == 0 || src_hz % G4_PLL_IN_HZ != 0) return PMA_ERR_RANGE;
    const uint32_t m = src_hz / G4_PLL_IN_HZ;
    if (m < 1u || m > 16u) return PMA_ERR_RANGE;
    *pll = (g4_pll_t){.pllsrc = pllsrc, .m = m, .n = G4_PLL_N, .r = G4_PLL_R};
    return PMA_OK;
}

uint32_t g4_pllcfgr_value(const g4_pll_t *pll)
{
    /* register codes: PLLM = M - 1, PLLN = N, PLLR: 0 = /2, 1 = /4, 2 = /6, 3 = /8 */
    return G4_FIELD(pll->pllsrc, G4_RCC_PLLCFGR_PLLSRC) | G4_FIELD(pll->m - 1u, G4_RCC_PLLCFGR_PLLM) |
           G4_FIELD(pll->n, G4_RCC_PLLCFGR_PLLN) | G4_FIELD(pll->r / 2u - 1u, G4_RCC_PLLCFGR_PLLR) |
           G4_RCC_PLLCFGR_PLLREN_Msk;
}

static int start_hse(void)
{
    g4_rmw(g4_io.rcc, G4_RCC_CR_OFFSET, G4_RCC_CR_HSEBYP_Msk,
           (G4_HSE_BYPASS ? G4_RCC_CR_HSEBYP_Msk : 0u));
    g4_rmw(g4_io.rcc, G4_RCC_CR_OFFSET, 0u, G4_RCC_CR_HSEON_Msk);
    if (g4_wait(g4_io.rcc, G4_RCC_CR_OFFSET, G4_RCC_CR_HSERDY_Msk, G4_RCC_CR_HSERDY_Msk,
                G4_POLLS_LONG) == 0) {
        return 0;
    }
    g4_rmw(g4_io.rcc, G4_RCC_CR_OFFSET, G4_RCC_CR_HSEON_Msk, 0u); /* no crystal: give up on it */
    return -1;
}

static int start_pll(const g4_pll_t *pll)
{
    g4_wr(g4_io.rcc, G4_RCC_PLLCFGR_OFFSET, g4_pllcfgr_value(pll));
    g4_rmw(g4_io.rcc, G4_RCC_CR_OFFSET, 0u, G4_RCC_CR_PLLON_Msk);
    return g4_wait(g4_io.rcc, G4_RCC_CR_OFFSET, G4_RCC_CR_PLLRDY_Msk, G4_RCC_CR_PLLRDY_Msk,
                   G4_POLLS_SHORT);
}

g4_clock_source_t g4_clock_init(int prefer_hse)
{
    /* 1. range 1 boost mode (R1MODE = 0), required above 150 MHz */
    g4_rmw(g4_io.rcc, G4_RCC_APB1ENR1_OFFSET, 0u, G4_RCC_APB1ENR1_PWREN_Msk);
    (void)g4_rd(g4_io.rcc, G4_RCC_APB1ENR1_OFFSET); /* the enable takes 2 cycles: read back */
    g4_rmw(g4_io.pwr, G4_PWR_CR1_OFFSET, G4_PWR_CR1_VOS_Msk,
           G4_FIELD(G4_PWR_CR1_VOS_RANGE1, G4_PWR_CR1_VOS));
    g4_rmw(g4_io.pwr, G4_PWR_CR5_OFFSET, G4_PWR_CR5_R1MODE_Msk, 0u);
    (void)g4_wait(g4_io.pwr, G4_PWR_SR2_OFFSET, G4_PWR_SR2_VOSF_Msk, 0u, G4_POLLS_SHORT);

    /* 2. flash wait states before the clock rises; prefetch and caches on */
    g4_rmw(g4_io.flash, G4_FLASH_ACR_OFFSET, G4_FLASH_ACR_LATENCY_Msk,
           G4_FIELD(G4_FLASH_LATENCY_170MHZ, G4_FLASH_ACR_LATENCY) | G4_FLASH_ACR_PRFTEN_Msk |
               G4_FLASH_ACR_ICEN_Msk | G4_FLASH_ACR_DCEN_Msk);
    if (G4_GET(g4_rd(g4_io.flash, G4_FLASH_ACR_OFFSET), G4_FLASH_ACR_LATENCY) !=
        G4_FLASH_LATENCY_170MHZ) {
        return (g4_clock_source_t)0; /* never raise the clock without the wait states */
    }

    /* 3. oscillator and PLL: HSE if asked for and it starts, else HSI16 */
    g4_clock_source_t src = G4_CLOCK_HSI16;
    g4_pll_t pll;
    if (prefer_hse && start_hse() == 0 &&
        g4_pll_for(G4_HSE_HZ, G4_RCC_PLLCFGR_PLLSRC_HSE, &pll) == PMA_OK) {
        src = G4_CLOCK_HSE;
    } else {
        g4_rmw(g4_io.rcc, G4_RCC_CR_OFFSET, 0u, G4_RCC_CR_HSION_Msk);
        (void)g4_wait(g4_io.rcc, G4_RCC_CR_OFFSET, G4_RCC_CR_HSIRDY_Msk, G4_RCC_CR_HSIRDY_Msk,
                      G4_POLLS_SHORT);
        (void)g4_pll_for(G4_HSI16_HZ, G4_RCC_PLLCFGR_PLLSRC_HSI16, &pll);
    }
    if (start_pll(&pll) != 0) return (g4_clock_source_t)0;

    /* 4. switch with AHB /2 first: a step of the load current straight to
     * 170 MHz is not allowed in boost mode (RM0440 7.2.7); APB1, APB2 /1 */
    g4_rmw(g4_io.rcc, G4_RCC_CFGR_OFFSET,
           G4_RCC_CFGR_HPRE_Msk | G4_RCC_CFGR_PPRE1_Msk | G4_RCC_CFGR_PPRE2_Msk | G4_RCC_CFGR_SW_Msk,
           G4_FIELD(G4_RCC_CFGR_HPRE_DIV2, G4_RCC_CFGR_HPRE) |
               G4_FIELD(G4_RCC_CFGR_SW_PLL, G4_RCC_CFGR_SW));
    if (g4_wait(g4_io.rcc, G4_RCC_CFGR_OFFSET, G4_RCC_CFGR_SWS_Msk,
                G4_FIELD(G4_RCC_CFGR_SW_PLL, G4_RCC_CFGR_SWS), G4_POLLS_SHORT) != 0) {
        return (g4_clock_source_t)0;
    }
    g4_cpu_delay_cycles(G4_SYSCLK_HZ / 2u / 1000000u * 2u); /* >= 1 us at 85 MHz */
    g4_rmw(g4_io.rcc, G4_RCC_CFGR_OFFSET, G4_RCC_CFGR_HPRE_Msk,
           G4_FIELD(G4_RCC_CFGR_HPRE_DIV1, G4_RCC_CFGR_HPRE));
    sysclk_hz = G4_SYSCLK_HZ;
    return src;
}

uint32_t g4_clock_sysclk_hz(void)
{
    return sysclk_hz;
}

/* ----------------------------------------------------------------- GPIO -- */

void g4_gpio_mode(uintptr_t port, uint32_t pin, uint32_t mode)
{
    const uint32_t stride = G4_GPIOA_MODER_MODER1_Pos - G4_GPIOA_MODER_MODER0_Pos;
    g4_rmw(port, G4_GPIOA_MODER_OFFSET, G4_GPIOA_MODER_MODER0_Msk << (stride * pin),
           (mode & 3u) << (stride * pin));
}

void g4_gpio_af(uintptr_t port, uint32_t pin, uint32_t af)
{
    const uint32_t stride = G4_GPIOA_AFRL_AFRL1_Pos - G4_GPIOA_AFRL_AFRL0_Pos;
    const uint32_t reg = pin < 8u ? G4_GPIOA_AFRL_OFFSET : G4_GPIOA_AFRH_OFFSET;
    const uint32_t shift = stride * (pin & 7u);
    g4_rmw(port, reg, G4_GPIOA_AFRL_AFRL0_Msk << shift, (af & 0xFu) << shift);
    g4_gpio_mode(port, pin, G4_GPIO_MODE_AF);
}

void g4_gpio_write(uintptr_t port, uint32_t pin, int high)
{
    /* BSRR: atomic, no read-modify-write of ODR */
    g4_wr(port, G4_GPIOA_BSRR_OFFSET,
          high ? (G4_GPIOA_BSRR_BS0_Msk << pin) : (G4_GPIOA_BSRR_BR0_Msk << pin));
}

/* ---------------------------------------------------------------- reset -- */

pma_reset_cause_t g4_reset_cause_from_csr(uint32_t csr)
{
    /* Order matters: the reset pin flag is set by every internal reset too
     * (the MCU drives NRST), and BORRSTF by every power-on (POR and BOR are
     * one circuit), so the specific causes come first. */
    if (csr & (G4_RCC_CSR_IWDGRSTF_Msk | G4_RCC_CSR_WWDGRSTF_Msk)) return PMA_RESET_WATCHDOG;
    if (csr & G4_RCC_CSR_SFTRSTF_Msk) return PMA_RESET_SOFTWARE;
    if (csr & G4_RCC_CSR_BORRSTF_Msk) return PMA_RESET_POWER_ON;
    if (csr & G4_RCC_CSR_PINRSTF_Msk) return PMA_RESET_PIN;
    return PMA_RESET_UNKNOWN; /* option byte load, low-power reset, or no flag */
}

pma_reset_cause_t g4_reset_latch(void)
{
    const pma_reset_cause_t c = g4_reset_cause_from_csr(g4_rd(g4_io.rcc, G4_RCC_CSR_OFFSET));
    g4_rmw(g4_io.rcc, G4_RCC_CSR_OFFSET, 0u, G4_RCC_CSR_RMVF_Msk);
    return c;
}
