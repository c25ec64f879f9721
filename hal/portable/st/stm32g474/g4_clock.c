/* SPDX-License-Identifier: Apache-2.0 */
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
    return (pll->pllsrc & RCC_PLLCFGR_PLLSRC_Msk) | _VAL2FLD(RCC_PLLCFGR_PLLM, pll->m - 1u) |
           _VAL2FLD(RCC_PLLCFGR_PLLN, pll->n) | _VAL2FLD(RCC_PLLCFGR_PLLR, pll->r / 2u - 1u) |
           RCC_PLLCFGR_PLLREN;
}

static int start_hse(void)
{
    RCC_TypeDef *const rcc = g4_io.rcc;
    MODIFY_REG(rcc->CR, RCC_CR_HSEBYP, (G4_HSE_BYPASS ? RCC_CR_HSEBYP : 0u));
    SET_BIT(rcc->CR, RCC_CR_HSEON);
    if (g4_wait(&rcc->CR, RCC_CR_HSERDY, RCC_CR_HSERDY, G4_POLLS_LONG) == 0) return 0;
    CLEAR_BIT(rcc->CR, RCC_CR_HSEON); /* no crystal: give up on it */
    return -1;
}

static int start_pll(const g4_pll_t *pll)
{
    RCC_TypeDef *const rcc = g4_io.rcc;
    WRITE_REG(rcc->PLLCFGR, g4_pllcfgr_value(pll));
    SET_BIT(rcc->CR, RCC_CR_PLLON);
    return g4_wait(&rcc->CR, RCC_CR_PLLRDY, RCC_CR_PLLRDY, G4_POLLS_SHORT);
}

g4_clock_source_t g4_clock_init(int prefer_hse)
{
    RCC_TypeDef *const rcc = g4_io.rcc;
    /* 1. range 1 boost mode (R1MODE = 0), required above 150 MHz */
    SET_BIT(rcc->APB1ENR1, RCC_APB1ENR1_PWREN);
    (void)READ_REG(rcc->APB1ENR1); /* the enable takes 2 cycles: read back */
    MODIFY_REG(g4_io.pwr->CR1, PWR_CR1_VOS, PWR_CR1_VOS_0); /* VOS 01: range 1 */
    CLEAR_BIT(g4_io.pwr->CR5, PWR_CR5_R1MODE);
    (void)g4_wait(&g4_io.pwr->SR2, PWR_SR2_VOSF, 0u, G4_POLLS_SHORT);

    /* 2. flash wait states before the clock rises; prefetch and caches on */
    MODIFY_REG(g4_io.flash->ACR, FLASH_ACR_LATENCY,
               _VAL2FLD(FLASH_ACR_LATENCY, G4_FLASH_LATENCY_170MHZ) | FLASH_ACR_PRFTEN |
                   FLASH_ACR_ICEN | FLASH_ACR_DCEN);
    if (_FLD2VAL(FLASH_ACR_LATENCY, READ_REG(g4_io.flash->ACR)) != G4_FLASH_LATENCY_170MHZ) {
        return (g4_clock_source_t)0; /* never raise the clock without the wait states */
    }

    /* 3. oscillator and PLL: HSE if asked for and it starts, else HSI16 */
    g4_clock_source_t src = G4_CLOCK_HSI16;
    g4_pll_t pll;
    if (prefer_hse && start_hse() == 0 &&
        g4_pll_for(G4_HSE_HZ, RCC_PLLCFGR_PLLSRC_HSE, &pll) == PMA_OK) {
        src = G4_CLOCK_HSE;
    } else {
        SET_BIT(rcc->CR, RCC_CR_HSION);
        (void)g4_wait(&rcc->CR, RCC_CR_HSIRDY, RCC_CR_HSIRDY, G4_POLLS_SHORT);
        (void)g4_pll_for(G4_HSI16_HZ, RCC_PLLCFGR_PLLSRC_HSI, &pll);
    }
    if (start_pll(&pll) != 0) return (g4_clock_source_t)0;

    /* 4. switch with AHB /2 first: a step of the load current straight to
     * 170 MHz is not allowed in boost mode (RM0440 7.2.7); APB1, APB2 /1 */
    MODIFY_REG(rcc->CFGR, RCC_CFGR_HPRE | RCC_CFGR_PPRE1 | RCC_CFGR_PPRE2 | RCC_CFGR_SW,
               RCC_CFGR_HPRE_DIV2 | RCC_CFGR_SW_PLL);
    if (g4_wait(&rcc->CFGR, RCC_CFGR_SWS, RCC_CFGR_SWS_PLL, G4_POLLS_SHORT) != 0) {
        return (g4_clock_source_t)0;
    }
    g4_cpu_delay_cycles(G4_SYSCLK_HZ / 2u / 1000000u * 2u); /* >= 1 us at 85 MHz */
    MODIFY_REG(rcc->CFGR, RCC_CFGR_HPRE, RCC_CFGR_HPRE_DIV1);
    sysclk_hz = G4_SYSCLK_HZ;
    return src;
}

uint32_t g4_clock_sysclk_hz(void)
{
    return sysclk_hz;
}

/* ----------------------------------------------------------------- GPIO -- */

void g4_gpio_mode(GPIO_TypeDef *port, uint32_t pin, uint32_t mode)
{
    const uint32_t stride = GPIO_MODER_MODE1_Pos - GPIO_MODER_MODE0_Pos;
    MODIFY_REG(port->MODER, GPIO_MODER_MODE0_Msk << (stride * pin), (mode & 3u) << (stride * pin));
}

void g4_gpio_af(GPIO_TypeDef *port, uint32_t pin, uint32_t af)
{
    /* AFR[0] = AFRL (pins 0..7), AFR[1] = AFRH (pins 8..15), 4 bits each */
    const uint32_t stride = GPIO_AFRL_AFSEL1_Pos - GPIO_AFRL_AFSEL0_Pos;
    const uint32_t shift = stride * (pin & 7u);
    MODIFY_REG(port->AFR[pin < 8u ? 0 : 1], GPIO_AFRL_AFSEL0_Msk << shift, (af & 0xFu) << shift);
    g4_gpio_mode(port, pin, G4_GPIO_MODE_AF);
}

void g4_gpio_write(GPIO_TypeDef *port, uint32_t pin, int high)
{
    /* BSRR: atomic, no read-modify-write of ODR */
    WRITE_REG(port->BSRR, high ? (GPIO_BSRR_BS0 << pin) : (GPIO_BSRR_BR0 << pin));
}

/* ---------------------------------------------------------------- reset -- */

pma_reset_cause_t g4_reset_cause_from_csr(uint32_t csr)
{
    /* Order matters: the reset pin flag is set by every internal reset too
     * (the MCU drives NRST), and BORRSTF by every power-on (POR and BOR are
     * one circuit), so the specific causes come first. */
    if (csr & (RCC_CSR_IWDGRSTF | RCC_CSR_WWDGRSTF)) return PMA_RESET_WATCHDOG;
    if (csr & RCC_CSR_SFTRSTF) return PMA_RESET_SOFTWARE;
    if (csr & RCC_CSR_BORRSTF) return PMA_RESET_POWER_ON;
    if (csr & RCC_CSR_PINRSTF) return PMA_RESET_PIN;
    return PMA_RESET_UNKNOWN; /* option byte load, low-power reset, or no flag */
}

pma_reset_cause_t g4_reset_latch(void)
{
    const pma_reset_cause_t c = g4_reset_cause_from_csr(READ_REG(g4_io.rcc->CSR));
    SET_BIT(g4_io.rcc->CSR, RCC_CSR_RMVF);
    return c;
}
