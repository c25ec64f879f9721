/* The STM32G474 port's drivers on the host, against a register file in RAM
 * (cmocka; ASan + UBSan on the host preset).
 *
 * Every peripheral base in g4_io points at an array here. Plain RAM has no
 * behaviour, so the two places where the drivers depend on it are this
 * file's (g4_io.h): g4_wait() first does what the hardware would have done
 * by then (ready bits follow their enables, SWS follows SW, ADCAL and BSY
 * clear, a page erase fills the page with 0xFF), unless a test breaks that
 * device; g4_w1c() clears write-1-to-clear bits. A test can also make a
 * flash error appear with the next operation. The expected register values
 * are written out from RM0440 here, not computed with the drivers' code. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <string.h>

#include "g4_drivers.h"
#include "pma_hal_stm32g474.h"

/* ------------------------------------------------------- register file -- */

static uint32_t r_rcc[64], r_pwr[64], r_flash[16], r_gpioa[16], r_gpiob[16], r_tim2[16],
    r_tim6[16], r_adc1[64], r_adc12c[4], r_dac1[32], r_fdcan1[80], r_mram[G4_MRAM_SIZE / 4u],
    r_iwdg[8], r_dbg[4], r_nvic[256];
static uint32_t nvm_mem[G4_NVM_BYTES / 4u];

#define REG(arr, off) ((arr)[(off) / 4u])

/* broken devices and injected errors */
static int hse_broken, pll_broken, flash_stuck_busy, iwdg_stuck, adc_broken;
static uint32_t flash_error_next; /* SR error bits the next flash operation ends with */
static uint32_t flash_cr_at_wait[8];
static unsigned flash_waits, flash_unlocks;
static unsigned wfi_count, wfi_ticks; /* tick interrupts WFI "sleeps" until */

static void fake_reset(void)
{
    memset(r_rcc, 0, sizeof r_rcc);
    memset(r_pwr, 0, sizeof r_pwr);
    memset(r_flash, 0, sizeof r_flash);
    memset(r_gpioa, 0, sizeof r_gpioa);
    memset(r_gpiob, 0, sizeof r_gpiob);
    memset(r_tim2, 0, sizeof r_tim2);
    memset(r_tim6, 0, sizeof r_tim6);
    memset(r_adc1, 0, sizeof r_adc1);
    memset(r_adc12c, 0, sizeof r_adc12c);
    memset(r_dac1, 0, sizeof r_dac1);
    memset(r_fdcan1, 0, sizeof r_fdcan1);
    memset(r_mram, 0xA5, sizeof r_mram); /* message RAM is not cleared by reset */
    memset(r_iwdg, 0, sizeof r_iwdg);
    memset(r_nvic, 0, sizeof r_nvic);
    memset(nvm_mem, 0xFF, sizeof nvm_mem);
    /* reset values that matter (RM0440) */
    REG(r_rcc, G4_RCC_CR_OFFSET) = G4_RCC_CR_HSION_Msk | G4_RCC_CR_HSIRDY_Msk;
    REG(r_rcc, G4_RCC_CFGR_OFFSET) = 0x5u;                    /* SW = SWS = HSI16 */
    REG(r_pwr, G4_PWR_CR5_OFFSET) = G4_PWR_CR5_R1MODE_Msk;     /* boost off */
    REG(r_pwr, G4_PWR_CR1_OFFSET) = 1u << 9;                   /* VOS range 1 */
    REG(r_flash, G4_FLASH_CR_OFFSET) = G4_FLASH_CR_LOCK_Msk;
    REG(r_flash, G4_FLASH_OPTR_OFFSET) = G4_FLASH_OPTR_DBANK_BIT; /* dual bank */
    REG(r_adc1, G4_ADC1_CR_OFFSET) = G4_ADC1_CR_DEEPPWD_Msk;
    REG(r_fdcan1, G4_FDCAN1_CCCR_OFFSET) = G4_FDCAN1_CCCR_INIT_Msk;
    REG(r_fdcan1, G4_FDCAN1_TXFQS_OFFSET) = 3u;                /* 3 free, put index 0 */
    hse_broken = pll_broken = flash_stuck_busy = iwdg_stuck = adc_broken = 0;
    flash_error_next = 0;
    flash_waits = 0;
    flash_unlocks = 0;
    wfi_count = 0;
    wfi_ticks = 1;
    g4_io = (g4_io_t){
        .rcc = (uintptr_t)r_rcc, .pwr = (uintptr_t)r_pwr, .flash = (uintptr_t)r_flash,
        .gpioa = (uintptr_t)r_gpioa, .gpiob = (uintptr_t)r_gpiob, .tim2 = (uintptr_t)r_tim2,
        .tim6 = (uintptr_t)r_tim6, .adc1 = (uintptr_t)r_adc1, .adc12_common = (uintptr_t)r_adc12c,
        .dac1 = (uintptr_t)r_dac1, .fdcan1 = (uintptr_t)r_fdcan1, .mram = (uintptr_t)r_mram,
        .iwdg = (uintptr_t)r_iwdg, .dbgmcu = (uintptr_t)r_dbg, .nvic = (uintptr_t)r_nvic,
        .nvm = (uintptr_t)nvm_mem,
    };
}

static int setup(void **state)
{
    (void)state;
    fake_reset();
    return 0;
}

/* What the hardware has done by the time a driver polls a register. */
static void hardware_settles(uintptr_t base, uint32_t offset)
{
    if (base == (uintptr_t)r_rcc && offset == G4_RCC_CR_OFFSET) {
        uint32_t cr = REG(r_rcc, offset);
        cr = (cr & G4_RCC_CR_HSEON_Msk) && !hse_broken ? cr | G4_RCC_CR_HSERDY_Msk
                                                       : cr & ~G4_RCC_CR_HSERDY_Msk;
        cr = (cr & G4_RCC_CR_PLLON_Msk) && !pll_broken ? cr | G4_RCC_CR_PLLRDY_Msk
                                                       : cr & ~G4_RCC_CR_PLLRDY_Msk;
        cr = (cr & G4_RCC_CR_HSION_Msk) ? cr | G4_RCC_CR_HSIRDY_Msk : cr & ~G4_RCC_CR_HSIRDY_Msk;
        REG(r_rcc, offset) = cr;
    } else if (base == (uintptr_t)r_rcc && offset == G4_RCC_CFGR_OFFSET) {
        const uint32_t cfgr = REG(r_rcc, offset);
        const uint32_t sw = cfgr & 3u;
        /* the switch to the PLL happens only with the PLL locked */
        if (sw != 3u || (REG(r_rcc, G4_RCC_CR_OFFSET) & G4_RCC_CR_PLLRDY_Msk)) {
            REG(r_rcc, offset) = (cfgr & ~G4_RCC_CFGR_SWS_Msk) | (sw << 2);
        }
    } else if (base == (uintptr_t)r_pwr && offset == G4_PWR_SR2_OFFSET) {
        REG(r_pwr, offset) &= ~G4_PWR_SR2_VOSF_Msk;
    } else if (base == (uintptr_t)r_flash && offset == G4_FLASH_SR_OFFSET) {
        const uint32_t cr = REG(r_flash, G4_FLASH_CR_OFFSET);
        if (flash_waits < 8u) flash_cr_at_wait[flash_waits] = cr;
        ++flash_waits;
        if (cr & G4_FLASH_CR_STRT_Msk) {
            /* page erase: bank 2 pages follow bank 1's 256 KB (dual bank, 2 KB pages) */
            const uint32_t pnb = (cr & G4_FLASH_CR_PNB_Msk) >> G4_FLASH_CR_PNB_Pos;
            const int dual = (REG(r_flash, G4_FLASH_OPTR_OFFSET) & G4_FLASH_OPTR_DBANK_BIT) != 0;
            const uint32_t page = dual ? 2048u : 4096u;
            const uint32_t addr = dual ? ((cr & G4_FLASH_CR_BKER_BIT) ? 0x08040000u : 0x08000000u) +
                                             pnb * page
                                       : 0x08000000u + pnb * page;
            if (addr >= 0x0807E000u && addr + page <= 0x08080000u && !flash_error_next) {
                memset((uint8_t *)nvm_mem + (addr - 0x0807E000u), 0xFF, page);
            }
            REG(r_flash, G4_FLASH_CR_OFFSET) = cr & ~G4_FLASH_CR_STRT_Msk; /* STRT clears itself */
        }
        uint32_t sr = REG(r_flash, offset);
        sr = flash_stuck_busy ? sr | G4_FLASH_SR_BSY_Msk : sr & ~G4_FLASH_SR_BSY_Msk;
        if (!(sr & G4_FLASH_SR_BSY_Msk)) sr |= flash_error_next | G4_FLASH_SR_EOP_Msk;
        REG(r_flash, offset) = sr;
    } else if (base == (uintptr_t)r_flash && offset == G4_FLASH_CR_OFFSET) {
        if (REG(r_flash, G4_FLASH_KEYR_OFFSET) == 0xCDEF89ABu) { /* the key sequence's end */
            REG(r_flash, offset) &= ~G4_FLASH_CR_LOCK_Msk;
            REG(r_flash, G4_FLASH_KEYR_OFFSET) = 0u;
            ++flash_unlocks;
        }
    } else if (base == (uintptr_t)r_adc1 && offset == G4_ADC1_CR_OFFSET) {
        REG(r_adc1, offset) &= ~G4_ADC1_CR_ADCAL_Msk;
        if (REG(r_adc1, offset) & G4_ADC1_CR_ADSTP_Msk) {
            REG(r_adc1, offset) &= ~(G4_ADC1_CR_ADSTP_Msk | G4_ADC1_CR_ADSTART_Msk);
        }
    } else if (base == (uintptr_t)r_adc1 && offset == G4_ADC1_ISR_OFFSET) {
        const uint32_t cr = REG(r_adc1, G4_ADC1_CR_OFFSET);
        if ((cr & G4_ADC1_CR_ADEN_Msk) && !adc_broken) REG(r_adc1, offset) |= G4_ADC1_ISR_ADRDY_Msk;
        if ((cr & G4_ADC1_CR_ADSTART_Msk) && !adc_broken) REG(r_adc1, offset) |= G4_ADC1_ISR_EOC_Msk;
    } else if (base == (uintptr_t)r_dac1 && offset == G4_DAC1_SR_OFFSET) {
        if (REG(r_dac1, G4_DAC1_CR_OFFSET) & G4_DAC1_CR_EN1_Msk) REG(r_dac1, offset) |= G4_DAC1_SR_DAC1RDY_Msk;
    } else if (base == (uintptr_t)r_iwdg && offset == G4_IWDG_SR_OFFSET) {
        REG(r_iwdg, offset) = iwdg_stuck ? G4_IWDG_SR_PVU_Msk : 0u;
    }
}

int g4_wait(uintptr_t base, uint32_t offset, uint32_t mask, uint32_t want, uint32_t max_polls)
{
    assert_true(max_polls > 0);
    hardware_settles(base, offset);
    return (g4_rd(base, offset) & mask) == want ? 0 : -1;
}

void g4_w1c(uintptr_t base, uint32_t offset, uint32_t bits)
{
    *(volatile uint32_t *)(base + offset) &= ~bits;
    if (base == (uintptr_t)r_flash && offset == G4_FLASH_SR_OFFSET) {
        /* cleared before an operation starts: the injected error comes with it */
    }
}

void g4_cpu_wait_for_interrupt(void)
{
    /* the timer update interrupt that ends the sleep */
    ++wfi_count;
    for (unsigned i = 0; i < wfi_ticks; ++i) {
        REG(r_tim6, G4_TIM6_SR_OFFSET) |= G4_TIM6_SR_UIF_Msk;
        g4_tick_isr();
    }
}

void g4_cpu_irq_disable(void) {}
void g4_cpu_irq_enable(void) {}
void g4_cpu_delay_cycles(uint32_t cycles)
{
    (void)cycles;
}

/* ---------------------------------------------------------------- clock -- */

static uint32_t pll_out_hz(uint32_t src_hz)
{
    const uint32_t p = REG(r_rcc, G4_RCC_PLLCFGR_OFFSET);
    const uint32_t m = ((p >> 4) & 0xFu) + 1u, n = (p >> 8) & 0x7Fu, r = 2u * (((p >> 25) & 3u) + 1u);
    return (uint32_t)((uint64_t)src_hz / m * n / r);
}

static void test_clock_hse_170mhz(void **state)
{
    (void)state;
    assert_int_equal(g4_clock_init(1), G4_CLOCK_HSE);
    const uint32_t p = REG(r_rcc, G4_RCC_PLLCFGR_OFFSET);
    /* PLLSRC = HSE (3), PLLM = /6 (5), PLLN = 85, PLLR = /2 (0), PLLREN */
    assert_int_equal(p, 3u | (5u << 4) | (85u << 8) | (1u << 24));
    assert_int_equal(pll_out_hz(24000000u), 170000000u);
    assert_int_equal(g4_clock_sysclk_hz(), 170000000u);
    const uint32_t cfgr = REG(r_rcc, G4_RCC_CFGR_OFFSET);
    assert_int_equal(cfgr & 0x3u, 3u);            /* SW = PLL */
    assert_int_equal((cfgr >> 4) & 0xFu, 0u);     /* HPRE /1 after the /2 step */
    assert_int_equal((cfgr >> 8) & 0x3Fu, 0u);    /* PPRE1, PPRE2 /1 */
    const uint32_t acr = REG(r_flash, G4_FLASH_ACR_OFFSET);
    assert_int_equal(acr & 0xFu, 4u);             /* 4 wait states */
    assert_int_equal(acr & 0x700u, 0x700u);       /* PRFTEN, ICEN, DCEN */
    assert_int_equal(REG(r_pwr, G4_PWR_CR5_OFFSET) & (1u << 8), 0u); /* boost mode */
    assert_int_equal((REG(r_pwr, G4_PWR_CR1_OFFSET) >> 9) & 3u, 1u);  /* range 1 */
    assert_true(REG(r_rcc, G4_RCC_CR_OFFSET) & (1u << 16));         /* HSEON */
    assert_int_equal(REG(r_rcc, G4_RCC_CR_OFFSET) & (1u << 18), 0u); /* crystal, no bypass */
}

static void test_clock_falls_back_to_hsi16(void **state)
{
    (void)state;
    hse_broken = 1;
    assert_int_equal(g4_clock_init(1), G4_CLOCK_HSI16);
    /* PLLSRC = HSI16 (2), PLLM = /4 (3), PLLN = 85, PLLR = /2 */
    assert_int_equal(REG(r_rcc, G4_RCC_PLLCFGR_OFFSET), 2u | (3u << 4) | (85u << 8) | (1u << 24));
    assert_int_equal(pll_out_hz(16000000u), 170000000u);
    assert_int_equal(REG(r_rcc, G4_RCC_CR_OFFSET) & (1u << 16), 0u); /* HSE switched off again */
    assert_int_equal(REG(r_rcc, G4_RCC_CFGR_OFFSET) & 3u, 3u);
}

static void test_clock_pll_failure_keeps_hsi(void **state)
{
    (void)state;
    pll_broken = 1;
    assert_int_equal(g4_clock_init(0), 0);
    assert_int_equal(REG(r_rcc, G4_RCC_CFGR_OFFSET) & 3u, 1u); /* still on HSI16 */
}

static void test_pll_dividers(void **state)
{
    (void)state;
    g4_pll_t pll;
    assert_int_equal(g4_pll_for(8000000u, G4_RCC_PLLCFGR_PLLSRC_HSE, &pll), PMA_OK); /* ST-LINK MCO */
    assert_int_equal(pll.m, 2u);
    assert_int_equal(8000000u / pll.m * pll.n / pll.r, 170000000u);
    assert_int_equal(g4_pll_for(25000000u, G4_RCC_PLLCFGR_PLLSRC_HSE, &pll), PMA_ERR_RANGE);
    assert_int_equal(g4_pll_for(0u, G4_RCC_PLLCFGR_PLLSRC_HSE, &pll), PMA_ERR_RANGE);
}

static void test_reset_cause(void **state)
{
    (void)state;
    const uint32_t pin = 1u << 26, bor = 1u << 27, sft = 1u << 28, iwdg = 1u << 29, wwdg = 1u << 30;
    assert_int_equal(g4_reset_cause_from_csr(pin | bor), PMA_RESET_POWER_ON);
    assert_int_equal(g4_reset_cause_from_csr(pin), PMA_RESET_PIN);
    assert_int_equal(g4_reset_cause_from_csr(pin | iwdg), PMA_RESET_WATCHDOG);
    assert_int_equal(g4_reset_cause_from_csr(pin | wwdg), PMA_RESET_WATCHDOG);
    assert_int_equal(g4_reset_cause_from_csr(pin | sft), PMA_RESET_SOFTWARE);
    assert_int_equal(g4_reset_cause_from_csr(0u), PMA_RESET_UNKNOWN);
    REG(r_rcc, G4_RCC_CSR_OFFSET) = pin | iwdg;
    assert_int_equal(g4_reset_latch(), PMA_RESET_WATCHDOG);
    assert_true(REG(r_rcc, G4_RCC_CSR_OFFSET) & (1u << 23)); /* RMVF written */
}

/* ----------------------------------------------------------------- time -- */

static void test_tick_registers_for_each_rate(void **state)
{
    (void)state;
    g4_tick_regs_t r;
    assert_int_equal(g4_tick_config(170000000u, 1000u, &r), PMA_OK);
    assert_int_equal(r.psc, 169u); /* 1 MHz counter */
    assert_int_equal(r.arr, 999u);
    /* every rate sys.tick_hz allows (50..5000 Hz), as the app rounds its period */
    for (uint32_t hz = 50u; hz <= 5000u; ++hz) {
        const uint32_t period_us = (1000000u + hz / 2u) / hz;
        assert_int_equal(g4_tick_config(170000000u, period_us, &r), PMA_OK);
        assert_int_equal((uint64_t)(r.psc + 1u) * (r.arr + 1u), 170ull * period_us);
        assert_true(r.arr <= 0xFFFFu);
    }
    assert_int_equal(g4_tick_config(170000000u, 0u, &r), PMA_ERR_RANGE);
    assert_int_equal(g4_tick_config(170000000u, 65537u, &r), PMA_ERR_RANGE);
}

static void test_tick_start_and_wait(void **state)
{
    (void)state;
    uint32_t late = 99;
    assert_int_equal(g4_tick_wait(&late), PMA_ERR_NOT_READY);
    assert_int_equal(g4_tick_start(170000000u, 1000u), PMA_OK);
    assert_int_equal(REG(r_tim6, G4_TIM6_PSC_OFFSET), 169u);
    assert_int_equal(REG(r_tim6, G4_TIM6_ARR_OFFSET), 999u);
    assert_int_equal(REG(r_tim6, G4_TIM6_CR1_OFFSET), 0x85u); /* ARPE | URS | CEN */
    assert_int_equal(REG(r_tim6, G4_TIM6_DIER_OFFSET), 1u);   /* UIE */
    assert_true(REG(r_rcc, G4_RCC_APB1ENR1_OFFSET) & (1u << 4)); /* TIM6EN */
    assert_true(r_nvic[1] & (1u << (54 - 32)));               /* ISER1: TIM6_DAC */
    /* no tick yet: sleeps (WFI) until the interrupt, late 0 */
    assert_int_equal(g4_tick_wait(&late), PMA_OK);
    assert_int_equal(late, 0u);
    assert_int_equal(wfi_count, 1u);
    /* three ticks pass while the loop works: served at once, late 3 */
    for (int i = 0; i < 3; ++i) {
        REG(r_tim6, G4_TIM6_SR_OFFSET) |= 1u;
        g4_tick_isr();
    }
    assert_int_equal(g4_tick_wait(&late), PMA_OK);
    assert_int_equal(late, 3u);
    assert_int_equal(wfi_count, 1u);
    assert_int_equal(REG(r_tim6, G4_TIM6_SR_OFFSET) & 1u, 0u); /* UIF cleared by the handler */
    g4_tick_stop();
    assert_int_equal(g4_tick_wait(&late), PMA_ERR_NOT_READY);
}

static void test_time_us_extends_to_64_bits(void **state)
{
    (void)state;
    g4_time_init(170000000u);
    assert_int_equal(REG(r_tim2, G4_TIM2_PSC_OFFSET), 169u);
    assert_int_equal(REG(r_tim2, G4_TIM2_ARR_OFFSET), 0xFFFFFFFFu);
    REG(r_tim2, G4_TIM2_CNT_OFFSET) = 0xFFFFFFF0u;
    assert_int_equal(g4_time_us(), 0xFFFFFFF0ull);
    /* wrapped, interrupt still pending: the small count is already the next period */
    REG(r_tim2, G4_TIM2_CNT_OFFSET) = 5u;
    REG(r_tim2, G4_TIM2_SR_OFFSET) = 1u;
    assert_int_equal(g4_time_us(), 0x100000005ull);
    g4_time_isr();
    assert_int_equal(REG(r_tim2, G4_TIM2_SR_OFFSET) & 1u, 0u);
    assert_int_equal(g4_time_us(), 0x100000005ull);
}

/* ------------------------------------------------------------ ADC / DAC -- */

static void test_adc_init_and_read(void **state)
{
    (void)state;
    assert_int_equal(g4_adc_init(), PMA_OK);
    const uint32_t cr = REG(r_adc1, G4_ADC1_CR_OFFSET);
    assert_int_equal(cr & (1u << 29), 0u);                   /* out of deep power-down */
    assert_true(cr & (1u << 28));                            /* regulator on */
    assert_true((cr & 0x5u) == 0x5u);                        /* ADEN, ADSTART */
    assert_int_equal((REG(r_adc1, G4_ADC1_SQR1_OFFSET) >> 6) & 0x1Fu, 1u); /* channel 1 = PA0 */
    assert_int_equal(REG(r_adc1, G4_ADC1_SQR1_OFFSET) & 0xFu, 0u);         /* one conversion */
    const uint32_t cfgr = REG(r_adc1, G4_ADC1_CFGR_OFFSET);
    assert_true(cfgr & (1u << 13));                          /* CONT */
    assert_true(cfgr & (1u << 12));                          /* OVRMOD: newest result */
    assert_int_equal((cfgr >> 3) & 3u, 0u);                  /* 12 bits */
    /* 16x oversampling, shift 4: still 12 bits */
    assert_int_equal(REG(r_adc1, G4_ADC1_CFGR2_OFFSET), 1u | (3u << 2) | (4u << 5));
    assert_int_equal((REG(r_adc12c, G4_ADC12_COMMON_CCR_OFFSET) >> 16) & 3u, 3u); /* HCLK/4 */
    assert_int_equal(r_gpioa[0] & 3u, 3u);                   /* PA0 analog */
    REG(r_adc1, G4_ADC1_DR_OFFSET) = 2048u;
    uint16_t raw = 0;
    assert_int_equal(g4_adc_read(&raw), PMA_OK);
    assert_int_equal(raw, 2048u);
    REG(r_adc1, G4_ADC1_DR_OFFSET) = 4095u;
    assert_int_equal(g4_adc_read(&raw), PMA_OK);
    assert_int_equal(raw, 4095u);
    /* the conversions stopped (e.g. an ADC error): an I/O error, never a stale number */
    REG(r_adc1, G4_ADC1_CR_OFFSET) &= ~G4_ADC1_CR_ADSTART_Msk;
    assert_int_equal(g4_adc_read(&raw), PMA_ERR_IO);
}

static void test_adc_that_never_gets_ready_fails(void **state)
{
    (void)state;
    adc_broken = 1;
    assert_int_equal(g4_adc_init(), PMA_ERR_IO);
    uint16_t raw;
    assert_int_equal(g4_adc_read(&raw), PMA_ERR_IO);
}

static void test_dac_init_and_write(void **state)
{
    (void)state;
    assert_int_equal(g4_dac_init(), PMA_OK);
    assert_int_equal(REG(r_dac1, G4_DAC1_MCR_OFFSET), (2u << 14) | 2u); /* HFSEL > 160 MHz, MODE1 010: pin, no buffer */
    assert_true(REG(r_dac1, G4_DAC1_CR_OFFSET) & 1u);            /* EN1 */
    assert_int_equal(REG(r_dac1, G4_DAC1_DHR12R1_OFFSET), 0u);   /* starts at 0 V */
    assert_int_equal((r_gpioa[0] >> 8) & 3u, 3u);                /* PA4 analog */
    assert_int_equal(g4_dac_write(4095u), PMA_OK);
    assert_int_equal(REG(r_dac1, G4_DAC1_DHR12R1_OFFSET), 4095u);
    assert_int_equal(g4_dac_write(1365u), PMA_OK);
    assert_int_equal(REG(r_dac1, G4_DAC1_DHR12R1_OFFSET), 1365u);
    assert_int_equal(g4_dac_write(4096u), PMA_ERR_RANGE);        /* 12-bit converter */
    assert_int_equal(REG(r_dac1, G4_DAC1_DHR12R1_OFFSET), 1365u); /* unchanged */
}

/* ---------------------------------------------------------------- FDCAN -- */

static void test_can_bit_timing(void **state)
{
    (void)state;
    g4_can_timing_t t;
    assert_int_equal(g4_can_timing_for(170000000u, 1000000u, &t), PMA_OK);
    /* 170 MHz / 10 = 17 MHz: 17 tq per bit, sample point after 14 (82.4 %) */
    assert_int_equal(t.prescaler, 10u);
    assert_int_equal(t.tseg1_tq, 13u);
    assert_int_equal(t.tseg2_tq, 3u);
    assert_int_equal(t.sjw_tq, 3u);
    /* NBTP: NSJW = 2, NBRP = 9, NTSEG1 = 12, NTSEG2 = 2 (all minus one) */
    assert_int_equal(g4_nbtp_value(&t), (2u << 25) | (9u << 16) | (12u << 8) | 2u);
    const uint32_t rates[] = {1000000u, 500000u, 250000u, 125000u};
    for (size_t i = 0; i < 4; ++i) {
        assert_int_equal(g4_can_timing_for(170000000u, rates[i], &t), PMA_OK);
        const uint32_t tq = 1u + t.tseg1_tq + t.tseg2_tq;
        assert_int_equal((uint64_t)t.prescaler * tq * rates[i], 170000000ull); /* exact rate */
        const uint32_t sp_permille = 1000u * (1u + t.tseg1_tq) / tq;
        assert_true(sp_permille >= 750u && sp_permille <= 900u);
        assert_true(t.sjw_tq >= 1u && t.sjw_tq <= t.tseg2_tq);
        assert_true(t.prescaler <= 512u && t.tseg1_tq <= 256u && t.tseg2_tq <= 128u);
    }
    assert_int_equal(g4_can_timing_for(170000000u, 333333u, &t), PMA_ERR_RANGE);
    assert_int_equal(g4_can_timing_for(170000000u, 0u, &t), PMA_ERR_RANGE);
}

static void can_up(void)
{
    assert_int_equal(g4_can_init(170000000u, 1000000u), PMA_OK);
}

static void test_can_init_registers(void **state)
{
    (void)state;
    can_up();
    assert_int_equal(REG(r_fdcan1, G4_FDCAN1_NBTP_OFFSET), (2u << 25) | (9u << 16) | (12u << 8) | 2u);
    const uint32_t cccr = REG(r_fdcan1, G4_FDCAN1_CCCR_OFFSET);
    assert_int_equal(cccr & 0x3u, 0u);             /* INIT and CCE cleared: on the bus */
    assert_int_equal(cccr & (3u << 8), 0u);        /* FDOE, BRSE off: classic CAN */
    assert_int_equal(cccr & (1u << 6), 0u);        /* DAR 0: automatic retransmission */
    /* no filter: accept every standard frame into FIFO 0; extended and remote rejected */
    assert_int_equal(REG(r_fdcan1, G4_FDCAN1_RXGFC_OFFSET), (2u << 2) | 3u);
    assert_int_equal(REG(r_fdcan1, G4_FDCAN1_IE_OFFSET), 1u | 4u | (1u << 9));
    assert_int_equal(REG(r_fdcan1, G4_FDCAN1_ILE_OFFSET), 1u);
    assert_int_equal((REG(r_rcc, G4_RCC_CCIPR_OFFSET) >> 24) & 3u, 2u); /* kernel clock PCLK1 */
    assert_true(REG(r_rcc, G4_RCC_APB1ENR1_OFFSET) & (1u << 25));      /* FDCANEN */
    /* PA11, PA12: alternate function 9 */
    assert_int_equal((r_gpioa[0] >> 22) & 0xFu, 0xAu);
    assert_int_equal((REG(r_gpioa, G4_GPIOA_AFRH_OFFSET) >> 12) & 0xFFu, 0x99u);
    assert_true(r_nvic[0] & (1u << 21));           /* FDCAN1_IT0 enabled */
    for (size_t i = 0; i < G4_MRAM_SIZE / 4u; ++i) assert_int_equal(r_mram[i], 0u); /* RAM cleared */
}

static void test_can_filters(void **state)
{
    (void)state;
    can_up();
    /* the application's: this node's ids (node 3), and the broadcast id 0 */
    const pma_can_filter_t f[2] = {{.id = 3u, .mask = 0x00Fu}, {.id = 0x000u, .mask = 0x7FFu}};
    assert_int_equal(g4_can_set_filters(f, 2), PMA_OK);
    /* SFT = 2 (classic id + mask), SFEC = 1 (Rx FIFO 0), SFID1 = id, SFID2 = mask */
    assert_int_equal(r_mram[0], 0x8803000Fu);
    assert_int_equal(r_mram[1], 0x880007FFu);
    assert_int_equal(r_mram[2], 0u);
    /* LSS = 2, non-matching standard and extended frames rejected, remote rejected */
    assert_int_equal(REG(r_fdcan1, G4_FDCAN1_RXGFC_OFFSET), (2u << 16) | (2u << 4) | (2u << 2) | 3u);
    assert_int_equal(REG(r_fdcan1, G4_FDCAN1_CCCR_OFFSET) & 3u, 0u); /* back on the bus */
    /* refused changes leave everything as it was */
    pma_can_filter_t nine[9];
    memset(nine, 0, sizeof nine);
    assert_int_equal(g4_can_set_filters(nine, 9), PMA_ERR_RANGE);
    const pma_can_filter_t bad = {.id = 0x800u, .mask = 0x7FFu};
    assert_int_equal(g4_can_set_filters(&bad, 1), PMA_ERR_RANGE);
    assert_int_equal(r_mram[0], 0x8803000Fu);
    assert_int_equal((REG(r_fdcan1, G4_FDCAN1_RXGFC_OFFSET) >> 16) & 0x1Fu, 2u);
    /* back to accept-all */
    assert_int_equal(g4_can_set_filters(NULL, 0), PMA_OK);
    assert_int_equal(REG(r_fdcan1, G4_FDCAN1_RXGFC_OFFSET), (2u << 2) | 3u);
    assert_int_equal(r_mram[0], 0u);
}

static pma_can_frame_t frame(uint16_t id, uint8_t dlc, uint8_t seed)
{
    pma_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.dlc = dlc;
    for (uint8_t i = 0; i < dlc; ++i) f.data[i] = (uint8_t)(seed + i);
    return f;
}

static void test_can_send_through_the_interrupt(void **state)
{
    (void)state;
    can_up();
    REG(r_fdcan1, G4_FDCAN1_TXFQS_OFFSET) = 3u | (1u << 16); /* 3 free, put index 1 */
    for (uint8_t i = 0; i < 4; ++i) {
        const pma_can_frame_t f = frame((uint16_t)(0x1A3u + i), (uint8_t)(5u + i), (uint8_t)(16u * i));
        r_nvic[64] = 0u;
        assert_int_equal(g4_can_send(&f), PMA_OK);
        assert_true(r_nvic[64] & (1u << 21)); /* ISPR0: the interrupt pended */
    }
    g4_can_isr();
    /* three frames into elements 1, 2, 0 (the put index advances per add) */
    const uint32_t idx[3] = {1u, 2u, 0u};
    for (uint32_t k = 0; k < 3; ++k) {
        const uint32_t *el = &r_mram[(G4_MRAM_TBSA + idx[k] * 72u) / 4u];
        assert_int_equal(el[0], (uint32_t)(0x1A3u + k) << 18);   /* standard id, no XTD/RTR */
        assert_int_equal(el[1], (uint32_t)(5u + k) << 16);       /* DLC, classic, no event */
        assert_int_equal(el[2], (uint32_t)(16u * k) | ((16u * k + 1u) << 8) |
                                    ((16u * k + 2u) << 16) | ((uint32_t)(uint8_t)(16u * k + 3u) << 24));
    }
    assert_int_equal(REG(r_fdcan1, G4_FDCAN1_TXBAR_OFFSET), 0x7u);
    /* the fourth waits for a free element (the Tx FIFO empty interrupt) */
    REG(r_fdcan1, G4_FDCAN1_TXFQS_OFFSET) = 3u | (1u << 16);
    REG(r_fdcan1, G4_FDCAN1_TXBAR_OFFSET) = 0u;
    g4_can_isr();
    assert_int_equal(REG(r_fdcan1, G4_FDCAN1_TXBAR_OFFSET), 0x2u);
    assert_int_equal(r_mram[(G4_MRAM_TBSA + 72u) / 4u], 0x1A6u << 18);
    /* TX ring full: 16 frames while the controller takes none */
    REG(r_fdcan1, G4_FDCAN1_TXFQS_OFFSET) = 1u << 21; /* TFQF */
    const pma_can_frame_t f = frame(0x100u, 8u, 0u);
    for (unsigned i = 0; i < G4_CAN_TX_RING; ++i) assert_int_equal(g4_can_send(&f), PMA_OK);
    assert_int_equal(g4_can_send(&f), PMA_ERR_FULL);
    const pma_can_frame_t big = frame(0x800u, 1u, 0u);
    assert_int_equal(g4_can_send(&big), PMA_ERR_RANGE);
    REG(r_fdcan1, G4_FDCAN1_PSR_OFFSET) = 1u << 7; /* bus-off */
    assert_int_equal(g4_can_send(&f), PMA_ERR_BUS_OFF);
}

static void put_rx(uint32_t gi, uint32_t r0, uint32_t r1, uint32_t d0, uint32_t d1)
{
    uint32_t *el = &r_mram[(G4_MRAM_F0SA + gi * 72u) / 4u];
    el[0] = r0;
    el[1] = r1;
    el[2] = d0;
    el[3] = d1;
    REG(r_fdcan1, G4_FDCAN1_RXF0S_OFFSET) = 1u | (gi << 8); /* fill 1, get index gi */
    REG(r_fdcan1, G4_FDCAN1_IR_OFFSET) |= 1u;               /* RF0N */
}

static void test_can_receive_through_the_interrupt(void **state)
{
    (void)state;
    can_up();
    pma_can_frame_t f;
    assert_int_equal(g4_can_recv(&f), PMA_ERR_EMPTY);
    put_rx(2u, 0x123u << 18, 8u << 16, 0x44332211u, 0x88776655u);
    g4_can_isr();
    assert_int_equal(REG(r_fdcan1, G4_FDCAN1_RXF0A_OFFSET), 2u); /* acknowledged */
    assert_int_equal(REG(r_fdcan1, G4_FDCAN1_IR_OFFSET) & 1u, 0u); /* RF0N cleared */
    assert_int_equal(g4_can_recv(&f), PMA_OK);
    assert_int_equal(f.id, 0x123u);
    assert_int_equal(f.dlc, 8u);
    for (uint8_t i = 0; i < 8; ++i) assert_int_equal(f.data[i], 0x11u * (i + 1u));
    assert_int_equal(g4_can_recv(&f), PMA_ERR_EMPTY);
    /* an extended frame never reaches the application */
    put_rx(0u, (1u << 30) | 0x123u, 2u << 16, 0u, 0u);
    g4_can_isr();
    assert_int_equal(g4_can_recv(&f), PMA_ERR_EMPTY);
    /* a frame lost in the 3-element FIFO is counted */
    REG(r_fdcan1, G4_FDCAN1_RXF0S_OFFSET) = 0u;
    REG(r_fdcan1, G4_FDCAN1_IR_OFFSET) |= 1u << 2; /* RF0L */
    g4_can_isr();
    pma_can_status_t st;
    assert_int_equal(g4_can_status(&st), PMA_OK);
    assert_int_equal(st.rx_overruns, 1u);
    /* the ring holds 32: the 33rd frame before a recv is an overrun */
    for (unsigned i = 0; i < G4_CAN_RX_RING + 1u; ++i) {
        put_rx(i % 3u, (0x200u + i) << 18, 1u << 16, i, 0u);
        g4_can_isr();
    }
    assert_int_equal(g4_can_status(&st), PMA_OK);
    assert_int_equal(st.rx_overruns, 2u);
    for (unsigned i = 0; i < G4_CAN_RX_RING; ++i) {
        assert_int_equal(g4_can_recv(&f), PMA_OK);
        assert_int_equal(f.id, 0x200u + i); /* in order */
    }
    assert_int_equal(g4_can_recv(&f), PMA_ERR_EMPTY);
}

static void test_can_error_states_and_recovery(void **state)
{
    (void)state;
    can_up();
    pma_can_status_t st;
    REG(r_fdcan1, G4_FDCAN1_ECR_OFFSET) = 100u | (5u << 8);
    assert_int_equal(g4_can_status(&st), PMA_OK);
    assert_int_equal(st.state, PMA_CAN_ERROR_ACTIVE);
    assert_int_equal(st.tec, 100u);
    assert_int_equal(st.rec, 5u);
    REG(r_fdcan1, G4_FDCAN1_ECR_OFFSET) = 130u;
    REG(r_fdcan1, G4_FDCAN1_PSR_OFFSET) = 1u << 5; /* EP */
    assert_int_equal(g4_can_status(&st), PMA_OK);
    assert_int_equal(st.state, PMA_CAN_ERROR_PASSIVE);
    assert_int_equal(st.tec, 130u);
    REG(r_fdcan1, G4_FDCAN1_ECR_OFFSET) = 1u << 15; /* RP: REC at 128 */
    assert_int_equal(g4_can_status(&st), PMA_OK);
    assert_int_equal(st.rec, 128u);
    /* bus-off: the controller has put itself in INIT */
    REG(r_fdcan1, G4_FDCAN1_PSR_OFFSET) = (1u << 7) | (1u << 5);
    REG(r_fdcan1, G4_FDCAN1_CCCR_OFFSET) |= 1u;
    assert_int_equal(g4_can_status(&st), PMA_OK);
    assert_int_equal(st.state, PMA_CAN_BUS_OFF);
    assert_int_equal(st.tec, 256u);
    assert_int_equal(g4_can_recover(), PMA_OK);
    assert_int_equal(REG(r_fdcan1, G4_FDCAN1_CCCR_OFFSET) & 1u, 0u); /* INIT cleared: recovery runs */
    /* not bus-off: recover changes nothing */
    REG(r_fdcan1, G4_FDCAN1_PSR_OFFSET) = 0u;
    REG(r_fdcan1, G4_FDCAN1_CCCR_OFFSET) |= 1u;
    assert_int_equal(g4_can_recover(), PMA_OK);
    assert_int_equal(REG(r_fdcan1, G4_FDCAN1_CCCR_OFFSET) & 1u, 1u);
}

/* ------------------------------------------------------------------ flash -- */

static void test_flash_geometry(void **state)
{
    (void)state;
    pma_nvm_geometry_t g;
    assert_int_equal(g4_flash_geometry(&g), PMA_OK);
    assert_int_equal(g.block_size, 2048u);
    assert_int_equal(g.block_count, 2u);
    assert_int_equal(g.program_size, 8u);
    REG(r_flash, G4_FLASH_OPTR_OFFSET) = 0u; /* single bank */
    assert_int_equal(g4_flash_geometry(&g), PMA_OK);
    assert_int_equal(g.block_size, 4096u);
}

static void test_flash_erase_sequence(void **state)
{
    (void)state;
    memset(nvm_mem, 0x00, sizeof nvm_mem);
    assert_int_equal(g4_flash_erase(1u), PMA_OK);
    /* unlocked with the two keys */
    assert_int_equal(flash_unlocks, 1u);
    /* the erase: PER, PNB 127, BKER (bank 2), STRT */
    assert_true(flash_waits >= 2u);
    assert_int_equal(flash_cr_at_wait[1], (1u << 1) | (127u << 3) | (1u << 11) | (1u << 16));
    /* bank 2 page 127 = 0x0807F800: the last 2 KB, and only those */
    const uint8_t *m = (const uint8_t *)nvm_mem;
    for (uint32_t i = 0; i < G4_NVM_BYTES; ++i) assert_int_equal(m[i], i >= 6144u ? 0xFFu : 0u);
    assert_int_equal(REG(r_flash, G4_FLASH_CR_OFFSET), 1u << 31); /* locked again, PER cleared */
    /* single bank: page 126 (4 KB at 0x0807E000) */
    memset(nvm_mem, 0x00, sizeof nvm_mem);
    REG(r_flash, G4_FLASH_OPTR_OFFSET) = 0u;
    assert_int_equal(g4_flash_erase(0u), PMA_OK);
    for (uint32_t i = 0; i < G4_NVM_BYTES; ++i) assert_int_equal(m[i], i < 4096u ? 0xFFu : 0u);
    assert_int_equal(g4_flash_erase(2u), PMA_ERR_RANGE);
}

static void test_flash_program_and_read(void **state)
{
    (void)state;
    uint8_t data[24];
    for (unsigned i = 0; i < sizeof data; ++i) data[i] = (uint8_t)(0xA0u + i);
    /* block 0 in dual bank: 0x0807F000, 4 KB into the area */
    assert_int_equal(g4_flash_program(0u, 16u, data + 1, 16u), PMA_OK); /* unaligned source */
    assert_int_equal(memcmp((uint8_t *)nvm_mem + 4096u + 16u, data + 1, 16u), 0);
    assert_int_equal(((uint8_t *)nvm_mem)[4096u + 15u], 0xFFu);
    assert_int_equal(((uint8_t *)nvm_mem)[4096u + 32u], 0xFFu);
    assert_int_equal(flash_cr_at_wait[1], 1u); /* PG during the double-word program */
    assert_int_equal(REG(r_flash, G4_FLASH_CR_OFFSET), 1u << 31);
    uint8_t back[16];
    assert_int_equal(g4_flash_read(0u, 16u, back, 16u), PMA_OK);
    assert_int_equal(memcmp(back, data + 1, 16u), 0);
    /* over programmed bytes: refused, nothing written */
    assert_int_equal(g4_flash_program(0u, 24u, data, 16u), PMA_ERR_NOT_ERASED);
    assert_int_equal(((uint8_t *)nvm_mem)[4096u + 32u], 0xFFu);
    /* alignment and range */
    assert_int_equal(g4_flash_program(0u, 4u, data, 8u), PMA_ERR_RANGE);
    assert_int_equal(g4_flash_program(0u, 0u, data, 12u), PMA_ERR_RANGE);
    assert_int_equal(g4_flash_program(0u, 2048u, data, 8u), PMA_ERR_RANGE);
    assert_int_equal(g4_flash_program(2u, 0u, data, 8u), PMA_ERR_RANGE);
    assert_int_equal(g4_flash_read(1u, 2040u, back, 16u), PMA_ERR_RANGE);
}

static void test_flash_errors(void **state)
{
    (void)state;
    uint8_t data[8] = {1, 2, 3, 4, 5, 6, 7, 8};
    /* a programming error flag ends the operation with an I/O error, locked */
    flash_error_next = G4_FLASH_SR_PROGERR_Msk;
    assert_int_equal(g4_flash_program(1u, 0u, data, 8u), PMA_ERR_IO);
    assert_int_equal(REG(r_flash, G4_FLASH_CR_OFFSET), 1u << 31);
    assert_int_equal(REG(r_flash, G4_FLASH_SR_OFFSET) & G4_FLASH_SR_PROGERR_Msk, 0u); /* cleared */
    flash_error_next = G4_FLASH_SR_WRPERR_Msk;
    assert_int_equal(g4_flash_erase(0u), PMA_ERR_IO);
    flash_error_next = 0;
    /* a flash that stays busy: a bounded wait, then an I/O error */
    flash_stuck_busy = 1;
    assert_int_equal(g4_flash_erase(0u), PMA_ERR_IO);
    flash_stuck_busy = 0;
    /* a double ECC error during a read (the NMI flagged it): corrupt, and cleared */
    REG(r_flash, G4_FLASH_ECCR_OFFSET) = 1u << 31;
    uint8_t back[8];
    assert_int_equal(g4_flash_read(0u, 0u, back, 8u), PMA_ERR_CORRUPT);
    assert_int_equal(REG(r_flash, G4_FLASH_ECCR_OFFSET) & (1u << 31), 0u);
    assert_int_equal(g4_flash_nmi(), 0); /* an NMI without ECCD is not the flash's */
    assert_int_equal(g4_flash_read(0u, 0u, back, 8u), PMA_OK);
}

/* ------------------------------------------------------------------ IWDG -- */

static void test_iwdg_reload(void **state)
{
    (void)state;
    g4_iwdg_regs_t r;
    const uint32_t ms[] = {1u, 100u, 500u, 1000u, 4096u, 32768u};
    const uint32_t pr[] = {0u, 0u, 0u, 1u, 3u, 6u};
    for (size_t i = 0; i < 6; ++i) {
        assert_int_equal(g4_iwdg_config(ms[i], &r), PMA_OK);
        assert_int_equal(r.pr, pr[i]);
        assert_true(r.rlr <= 4095u);
        /* the timeout (RLR + 1) x (4 << PR) / 32 kHz is the request, rounded up */
        const uint64_t t_us = (uint64_t)(r.rlr + 1u) * (4u << r.pr) * 1000000u / 32000u;
        assert_true(t_us >= 1000ull * ms[i]);
        assert_true(t_us < 1000ull * ms[i] + (4u << r.pr) * 1000000u / 32000u);
    }
    assert_int_equal(g4_iwdg_config(1000u, &r), PMA_OK);
    assert_int_equal(r.rlr, 3999u); /* /8: 4000 counts of 250 us */
    assert_int_equal(g4_iwdg_config(0u, &r), PMA_ERR_RANGE);
    assert_int_equal(g4_iwdg_config(32769u, &r), PMA_ERR_RANGE);
    assert_int_equal(g4_iwdg_start(500u), PMA_OK);
    assert_int_equal(REG(r_iwdg, G4_IWDG_PR_OFFSET), 0u);
    assert_int_equal(REG(r_iwdg, G4_IWDG_RLR_OFFSET), 3999u);
    assert_int_equal(REG(r_iwdg, G4_IWDG_KR_OFFSET), 0xAAAAu); /* reloaded last */
    REG(r_iwdg, G4_IWDG_KR_OFFSET) = 0u;
    g4_iwdg_kick();
    assert_int_equal(REG(r_iwdg, G4_IWDG_KR_OFFSET), 0xAAAAu);
    iwdg_stuck = 1;
    assert_int_equal(g4_iwdg_start(500u), PMA_ERR_IO);
}

/* ----------------------------------------------------- the port (hal.h) -- */

static void test_port_over_the_drivers(void **state)
{
    (void)state;
    assert_string_equal(pma_hal_port_name(), "stm32g474");
    uint16_t raw;
    assert_int_equal(pma_hal_adc_read(&raw), PMA_ERR_NOT_READY);
    pma_hal_stm32g474_system_init();
    assert_int_equal(pma_hal_stm32g474_clock_source(), 1); /* HSE */
    assert_int_equal((r_gpioa[0] >> 10) & 3u, 1u);          /* PA5 (LD2) output */
    pma_hal_stm32g474_led_set(1);
    assert_int_equal(REG(r_gpioa, G4_GPIOA_BSRR_OFFSET), 1u << 5);
    pma_hal_stm32g474_led_set(0);
    assert_int_equal(REG(r_gpioa, G4_GPIOA_BSRR_OFFSET), 1u << 21);
    assert_int_equal(pma_hal_init(NULL), PMA_OK);
    assert_int_equal(REG(r_fdcan1, G4_FDCAN1_NBTP_OFFSET), (2u << 25) | (9u << 16) | (12u << 8) | 2u);
    const pma_hal_config_t c500 = {.can_bitrate_bps = 500000u, .port = NULL};
    assert_int_equal(pma_hal_init(&c500), PMA_OK);
    assert_int_equal((REG(r_fdcan1, G4_FDCAN1_NBTP_OFFSET) >> 16) & 0x1FFu, 16u); /* /17: 20 tq */
    REG(r_adc1, G4_ADC1_DR_OFFSET) = 1234u;
    assert_int_equal(pma_hal_adc_read(&raw), PMA_OK);
    assert_int_equal(raw, 1234u);
    assert_int_equal(pma_hal_dac_write(4096u), PMA_ERR_RANGE);
    assert_int_equal(pma_hal_tick_start(0u), PMA_ERR_RANGE);
    assert_int_equal(pma_hal_tick_start(1000u), PMA_OK);
    uint32_t late = 9;
    assert_int_equal(pma_hal_tick_wait(&late), PMA_OK);
    assert_int_equal(late, 0u);
    pma_nvm_geometry_t g;
    assert_int_equal(pma_hal_nvm_geometry(&g), PMA_OK);
    assert_int_equal(g.block_size, 2048u);
    pma_hal_deinit();
    assert_int_equal(pma_hal_adc_read(&raw), PMA_ERR_NOT_READY);
    assert_int_equal(pma_hal_tick_wait(&late), PMA_ERR_NOT_READY);
    assert_int_equal(REG(r_fdcan1, G4_FDCAN1_CCCR_OFFSET) & 1u, 1u); /* CAN offline */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_clock_hse_170mhz, setup),
        cmocka_unit_test_setup(test_clock_falls_back_to_hsi16, setup),
        cmocka_unit_test_setup(test_clock_pll_failure_keeps_hsi, setup),
        cmocka_unit_test_setup(test_pll_dividers, setup),
        cmocka_unit_test_setup(test_reset_cause, setup),
        cmocka_unit_test_setup(test_tick_registers_for_each_rate, setup),
        cmocka_unit_test_setup(test_tick_start_and_wait, setup),
        cmocka_unit_test_setup(test_time_us_extends_to_64_bits, setup),
        cmocka_unit_test_setup(test_adc_init_and_read, setup),
        cmocka_unit_test_setup(test_adc_that_never_gets_ready_fails, setup),
        cmocka_unit_test_setup(test_dac_init_and_write, setup),
        cmocka_unit_test_setup(test_can_bit_timing, setup),
        cmocka_unit_test_setup(test_can_init_registers, setup),
        cmocka_unit_test_setup(test_can_filters, setup),
        cmocka_unit_test_setup(test_can_send_through_the_interrupt, setup),
        cmocka_unit_test_setup(test_can_receive_through_the_interrupt, setup),
        cmocka_unit_test_setup(test_can_error_states_and_recovery, setup),
        cmocka_unit_test_setup(test_flash_geometry, setup),
        cmocka_unit_test_setup(test_flash_erase_sequence, setup),
        cmocka_unit_test_setup(test_flash_program_and_read, setup),
        cmocka_unit_test_setup(test_flash_errors, setup),
        cmocka_unit_test_setup(test_iwdg_reload, setup),
        cmocka_unit_test_setup(test_port_over_the_drivers, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
