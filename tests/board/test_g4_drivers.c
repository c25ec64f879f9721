/* SPDX-License-Identifier: Apache-2.0 */
/* The STM32G474 port's drivers on the host, against a register file in RAM
 * (Unity; ASan + UBSan on the host preset).
 *
 * The register file is made of ST's register structs (RCC_TypeDef, ...,
 * stm32g474xx.h) and Arm's NVIC_Type (core_cm4.h), through g4_cmsis.h,
 * which on the host stands in for the Arm-only cmsis_gcc.h; the FDCAN
 * message RAM, which ST's header does not describe, is an array of words.
 * Every register-block pointer in g4_io points at one of them here. Plain
 * RAM has no behaviour, so the two places where the drivers depend on it
 * are this file's (g4_io.h): g4_wait() first does what the hardware would
 * have done by then (ready bits follow their enables, SWS follows SW, ADCAL
 * and BSY clear, a page erase fills the page with 0xFF), unless a test
 * breaks that device; g4_w1c() clears write-1-to-clear bits. A test can
 * also make a flash error appear with the next operation. The expected
 * register values are written out from RM0440 here, not computed with the
 * drivers' code. */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "g4_drivers.h"
#include "pma/status.h" /* pma_status_name, for assert_status */
#include "pma_hal_stm32g474.h"
#include "pma_test.h"

/* ------------------------------------------------------- register file -- */

static RCC_TypeDef r_rcc;
static PWR_TypeDef r_pwr;
static FLASH_TypeDef r_flash;
static GPIO_TypeDef r_gpioa, r_gpiob;
static TIM_TypeDef r_tim2, r_tim6;
static ADC_TypeDef r_adc1;
static ADC_Common_TypeDef r_adc12c;
static DAC_TypeDef r_dac1;
static FDCAN_GlobalTypeDef r_fdcan1;
static FDCAN_Config_TypeDef r_fdcan_cfg;
static uint32_t r_mram[G4_MRAM_SIZE / 4u];
static IWDG_TypeDef r_iwdg;
static NVIC_Type r_nvic;
static uint32_t nvm_mem[G4_NVM_BYTES / 4u];
static uint8_t r_uid[PMA_HAL_STM32G474_UID_BYTES]; /* UID_BASE */

/* broken devices and injected errors */
static int hse_broken, pll_broken, flash_stuck_busy, iwdg_stuck, adc_broken;
static uint32_t flash_error_next; /* SR error bits the next flash operation ends with */
static uint32_t flash_cr_at_wait[8];
static unsigned flash_waits, flash_unlocks;
static unsigned wfi_count, wfi_ticks; /* tick interrupts WFI "sleeps" until */

static void fake_reset(void)
{
    memset(&r_rcc, 0, sizeof r_rcc);
    memset(&r_pwr, 0, sizeof r_pwr);
    memset(&r_flash, 0, sizeof r_flash);
    memset(&r_gpioa, 0, sizeof r_gpioa);
    memset(&r_gpiob, 0, sizeof r_gpiob);
    memset(&r_tim2, 0, sizeof r_tim2);
    memset(&r_tim6, 0, sizeof r_tim6);
    memset(&r_adc1, 0, sizeof r_adc1);
    memset(&r_adc12c, 0, sizeof r_adc12c);
    memset(&r_dac1, 0, sizeof r_dac1);
    memset(&r_fdcan1, 0, sizeof r_fdcan1);
    memset(&r_fdcan_cfg, 0, sizeof r_fdcan_cfg);
    memset(r_mram, 0xA5, sizeof r_mram); /* message RAM is not cleared by reset */
    memset(&r_iwdg, 0, sizeof r_iwdg);
    memset(&r_nvic, 0, sizeof r_nvic);
    memset(nvm_mem, 0xFF, sizeof nvm_mem);
    for (unsigned k = 0; k < sizeof r_uid; ++k) r_uid[k] = (uint8_t)(0x30u + 7u * k);
    /* reset values that matter (RM0440) */
    r_rcc.CR = RCC_CR_HSION | RCC_CR_HSIRDY;
    r_rcc.CFGR = 0x5u;                   /* SW = SWS = HSI16 */
    r_pwr.CR5 = PWR_CR5_R1MODE;          /* boost off */
    r_pwr.CR1 = 1u << 9;                 /* VOS range 1 */
    r_flash.CR = FLASH_CR_LOCK;
    r_flash.OPTR = FLASH_OPTR_DBANK;     /* dual bank */
    r_adc1.CR = ADC_CR_DEEPPWD;
    r_fdcan1.CCCR = FDCAN_CCCR_INIT;
    r_fdcan1.TXFQS = 3u;                 /* 3 free, put index 0 */
    hse_broken = pll_broken = flash_stuck_busy = iwdg_stuck = adc_broken = 0;
    flash_error_next = 0;
    flash_waits = 0;
    flash_unlocks = 0;
    wfi_count = 0;
    wfi_ticks = 1;
    g4_io = (g4_io_t){
        .rcc = &r_rcc, .pwr = &r_pwr, .flash = &r_flash, .gpioa = &r_gpioa, .gpiob = &r_gpiob,
        .tim2 = &r_tim2, .tim6 = &r_tim6, .adc1 = &r_adc1, .adc12_common = &r_adc12c,
        .dac1 = &r_dac1, .fdcan1 = &r_fdcan1, .fdcan_config = &r_fdcan_cfg, .mram = r_mram,
        .iwdg = &r_iwdg, .nvic = &r_nvic, .nvm = (uintptr_t)nvm_mem, .uid = r_uid,
    };
}

/* Unity's fixture: every test starts from the reset state. */
void setUp(void)
{
    fake_reset();
}

void tearDown(void) {}

/* What the hardware has done by the time a driver polls a register. */
static void hardware_settles(const volatile uint32_t *reg)
{
    if (reg == &r_rcc.CR) {
        uint32_t cr = r_rcc.CR;
        cr = (cr & RCC_CR_HSEON) && !hse_broken ? cr | RCC_CR_HSERDY : cr & ~RCC_CR_HSERDY;
        cr = (cr & RCC_CR_PLLON) && !pll_broken ? cr | RCC_CR_PLLRDY : cr & ~RCC_CR_PLLRDY;
        cr = (cr & RCC_CR_HSION) ? cr | RCC_CR_HSIRDY : cr & ~RCC_CR_HSIRDY;
        r_rcc.CR = cr;
    } else if (reg == &r_rcc.CFGR) {
        const uint32_t cfgr = r_rcc.CFGR;
        const uint32_t sw = cfgr & 3u;
        /* the switch to the PLL happens only with the PLL locked */
        if (sw != 3u || (r_rcc.CR & RCC_CR_PLLRDY)) {
            r_rcc.CFGR = (cfgr & ~RCC_CFGR_SWS) | (sw << 2);
        }
    } else if (reg == &r_pwr.SR2) {
        r_pwr.SR2 &= ~PWR_SR2_VOSF;
    } else if (reg == &r_flash.SR) {
        const uint32_t cr = r_flash.CR;
        if (flash_waits < 8u) flash_cr_at_wait[flash_waits] = cr;
        ++flash_waits;
        if (cr & FLASH_CR_STRT) {
            /* page erase: bank 2 pages follow bank 1's 256 KB (dual bank, 2 KB pages) */
            const uint32_t pnb = (cr & FLASH_CR_PNB) >> FLASH_CR_PNB_Pos;
            const int dual = (r_flash.OPTR & FLASH_OPTR_DBANK) != 0;
            const uint32_t page = dual ? 2048u : 4096u;
            const uint32_t addr = dual ? ((cr & FLASH_CR_BKER) ? 0x08040000u : 0x08000000u) +
                                             pnb * page
                                       : 0x08000000u + pnb * page;
            if (addr >= 0x0807E000u && addr + page <= 0x08080000u && !flash_error_next) {
                memset((uint8_t *)nvm_mem + (addr - 0x0807E000u), 0xFF, page);
            }
            r_flash.CR = cr & ~FLASH_CR_STRT; /* STRT clears itself */
        }
        uint32_t sr = r_flash.SR;
        sr = flash_stuck_busy ? sr | FLASH_SR_BSY : sr & ~FLASH_SR_BSY;
        if (!(sr & FLASH_SR_BSY)) sr |= flash_error_next | FLASH_SR_EOP;
        r_flash.SR = sr;
    } else if (reg == &r_flash.CR) {
        if (r_flash.KEYR == 0xCDEF89ABu) { /* the key sequence's end */
            r_flash.CR &= ~FLASH_CR_LOCK;
            r_flash.KEYR = 0u;
            ++flash_unlocks;
        }
    } else if (reg == &r_adc1.CR) {
        r_adc1.CR &= ~ADC_CR_ADCAL;
        if (r_adc1.CR & ADC_CR_ADSTP) r_adc1.CR &= ~(ADC_CR_ADSTP | ADC_CR_ADSTART);
    } else if (reg == &r_adc1.ISR) {
        const uint32_t cr = r_adc1.CR;
        if ((cr & ADC_CR_ADEN) && !adc_broken) r_adc1.ISR |= ADC_ISR_ADRDY;
        if ((cr & ADC_CR_ADSTART) && !adc_broken) r_adc1.ISR |= ADC_ISR_EOC;
    } else if (reg == &r_dac1.SR) {
        if (r_dac1.CR & DAC_CR_EN1) r_dac1.SR |= DAC_SR_DAC1RDY;
    } else if (reg == &r_iwdg.SR) {
        r_iwdg.SR = iwdg_stuck ? IWDG_SR_PVU : 0u;
    }
}

int g4_wait(const volatile uint32_t *reg, uint32_t mask, uint32_t want, uint32_t max_polls)
{
    TEST_ASSERT_GREATER_THAN_UINT32(0u, max_polls);
    hardware_settles(reg);
    return (*reg & mask) == want ? 0 : -1;
}

void g4_w1c(volatile uint32_t *reg, uint32_t bits)
{
    *reg &= ~bits;
    if (reg == &r_flash.SR) {
        /* cleared before an operation starts: the injected error comes with it */
    }
}

void g4_cpu_wait_for_interrupt(void)
{
    /* the timer update interrupt that ends the sleep */
    ++wfi_count;
    for (unsigned i = 0; i < wfi_ticks; ++i) {
        r_tim6.SR |= TIM_SR_UIF;
        g4_tick_isr();
    }
}

void g4_cpu_system_reset(void) {} /* pma_hal_system_reset() is board-only (not linked here) */
void g4_cpu_irq_disable(void) {}
void g4_cpu_irq_enable(void) {}
void g4_cpu_delay_cycles(uint32_t cycles)
{
    (void)cycles;
}

/* ---------------------------------------------------------------- clock -- */

static uint32_t pll_out_hz(uint32_t src_hz)
{
    const uint32_t p = r_rcc.PLLCFGR;
    const uint32_t m = ((p >> 4) & 0xFu) + 1u, n = (p >> 8) & 0x7Fu, r = 2u * (((p >> 25) & 3u) + 1u);
    return (uint32_t)((uint64_t)src_hz / m * n / r);
}

static void test_clock_hse_170mhz(void)
{
    TEST_ASSERT_EQUAL_INT(G4_CLOCK_HSE, g4_clock_init(1));
    const uint32_t p = r_rcc.PLLCFGR;
    /* PLLSRC = HSE (3), PLLM = /6 (5), PLLN = 85, PLLR = /2 (0), PLLREN */
    TEST_ASSERT_EQUAL_HEX32(3u | (5u << 4) | (85u << 8) | (1u << 24), p);
    TEST_ASSERT_EQUAL_INT(170000000u, pll_out_hz(24000000u));
    TEST_ASSERT_EQUAL_INT(170000000u, g4_clock_sysclk_hz());
    const uint32_t cfgr = r_rcc.CFGR;
    TEST_ASSERT_EQUAL_UINT32(3u, cfgr & 0x3u);            /* SW = PLL */
    TEST_ASSERT_EQUAL_INT(0u, (cfgr >> 4) & 0xFu);     /* HPRE /1 after the /2 step */
    TEST_ASSERT_EQUAL_INT(0u, (cfgr >> 8) & 0x3Fu);    /* PPRE1, PPRE2 /1 */
    const uint32_t acr = r_flash.ACR;
    TEST_ASSERT_EQUAL_UINT32(4u, acr & 0xFu);             /* 4 wait states */
    TEST_ASSERT_EQUAL_HEX32(0x700u, acr & 0x700u);       /* PRFTEN, ICEN, DCEN */
    TEST_ASSERT_EQUAL_UINT32(0u, r_pwr.CR5 & (1u << 8)); /* boost mode */
    TEST_ASSERT_EQUAL_UINT32(1u, (r_pwr.CR1 >> 9) & 3u);  /* range 1 */
    TEST_ASSERT_BITS_HIGH((1u << 16), r_rcc.CR);         /* HSEON */
    TEST_ASSERT_EQUAL_UINT32(0u, r_rcc.CR & (1u << 18)); /* crystal, no bypass */
}

static void test_clock_falls_back_to_hsi16(void)
{
    hse_broken = 1;
    TEST_ASSERT_EQUAL_INT(G4_CLOCK_HSI16, g4_clock_init(1));
    /* PLLSRC = HSI16 (2), PLLM = /4 (3), PLLN = 85, PLLR = /2 */
    TEST_ASSERT_EQUAL_HEX32(2u | (3u << 4) | (85u << 8) | (1u << 24), r_rcc.PLLCFGR);
    TEST_ASSERT_EQUAL_INT(170000000u, pll_out_hz(16000000u));
    TEST_ASSERT_EQUAL_UINT32(0u, r_rcc.CR & (1u << 16)); /* HSE switched off again */
    TEST_ASSERT_EQUAL_UINT32(3u, r_rcc.CFGR & 3u);
}

static void test_clock_pll_failure_keeps_hsi(void)
{
    pll_broken = 1;
    TEST_ASSERT_EQUAL_INT(0, g4_clock_init(0));
    TEST_ASSERT_EQUAL_UINT32(1u, r_rcc.CFGR & 3u); /* still on HSI16 */
}

static void test_pll_dividers(void)
{
    g4_pll_t pll;
    assert_status(g4_pll_for(8000000u, RCC_PLLCFGR_PLLSRC_HSE, &pll), PMA_OK); /* ST-LINK MCO */
    TEST_ASSERT_EQUAL_INT(2u, pll.m);
    TEST_ASSERT_EQUAL_INT(170000000u, 8000000u / pll.m * pll.n / pll.r);
    assert_status(g4_pll_for(25000000u, RCC_PLLCFGR_PLLSRC_HSE, &pll), PMA_ERR_RANGE);
    assert_status(g4_pll_for(0u, RCC_PLLCFGR_PLLSRC_HSE, &pll), PMA_ERR_RANGE);
}

static void test_reset_cause(void)
{
    const uint32_t pin = 1u << 26, bor = 1u << 27, sft = 1u << 28, iwdg = 1u << 29, wwdg = 1u << 30;
    TEST_ASSERT_EQUAL_INT(PMA_RESET_POWER_ON, g4_reset_cause_from_csr(pin | bor));
    TEST_ASSERT_EQUAL_INT(PMA_RESET_PIN, g4_reset_cause_from_csr(pin));
    TEST_ASSERT_EQUAL_INT(PMA_RESET_WATCHDOG, g4_reset_cause_from_csr(pin | iwdg));
    TEST_ASSERT_EQUAL_INT(PMA_RESET_WATCHDOG, g4_reset_cause_from_csr(pin | wwdg));
    TEST_ASSERT_EQUAL_INT(PMA_RESET_SOFTWARE, g4_reset_cause_from_csr(pin | sft));
    TEST_ASSERT_EQUAL_INT(PMA_RESET_UNKNOWN, g4_reset_cause_from_csr(0u));
    r_rcc.CSR = pin | iwdg;
    TEST_ASSERT_EQUAL_INT(PMA_RESET_WATCHDOG, g4_reset_latch());
    TEST_ASSERT_BITS_HIGH((1u << 23), r_rcc.CSR); /* RMVF written */
}

/* The unique device id: the 12 bytes at UID_BASE, byte 0 first. */
static void test_device_uid(void)
{
    uint8_t uid[PMA_HAL_STM32G474_UID_BYTES];
    memset(uid, 0, sizeof uid);
    pma_hal_stm32g474_device_uid(uid);
    TEST_ASSERT_EQUAL_MEMORY(r_uid, uid, sizeof uid);
    TEST_ASSERT_EQUAL_HEX8(0x30, uid[0]);
    TEST_ASSERT_EQUAL_HEX8(0x30 + 77, uid[11]);
}

/* ----------------------------------------------------------------- time -- */

static void test_tick_registers_for_each_rate(void)
{
    g4_tick_regs_t r;
    assert_status(g4_tick_config(170000000u, 1000u, &r), PMA_OK);
    TEST_ASSERT_EQUAL_INT(169u, r.psc); /* 1 MHz counter */
    TEST_ASSERT_EQUAL_INT(999u, r.arr);
    /* every rate sys.tick_hz allows (50..5000 Hz), as the app rounds its period */
    for (uint32_t hz = 50u; hz <= 5000u; ++hz) {
        const uint32_t period_us = (1000000u + hz / 2u) / hz;
        assert_status(g4_tick_config(170000000u, period_us, &r), PMA_OK);
        TEST_ASSERT_EQUAL_UINT64(170ull * period_us, (uint64_t)(r.psc + 1u) * (r.arr + 1u));
        TEST_ASSERT_LESS_OR_EQUAL_UINT32(0xFFFFu, r.arr);
    }
    assert_status(g4_tick_config(170000000u, 0u, &r), PMA_ERR_RANGE);
    assert_status(g4_tick_config(170000000u, 65537u, &r), PMA_ERR_RANGE);
}

static void test_tick_start_and_wait(void)
{
    uint32_t late = 99;
    assert_status(g4_tick_wait(&late), PMA_ERR_NOT_READY);
    assert_status(g4_tick_start(170000000u, 1000u), PMA_OK);
    TEST_ASSERT_EQUAL_UINT32(169u, r_tim6.PSC);
    TEST_ASSERT_EQUAL_UINT32(999u, r_tim6.ARR);
    TEST_ASSERT_EQUAL_HEX32(0x85u, r_tim6.CR1); /* ARPE | URS | CEN */
    TEST_ASSERT_EQUAL_UINT32(1u, r_tim6.DIER);   /* UIE */
    TEST_ASSERT_BITS_HIGH((1u << 4), r_rcc.APB1ENR1); /* TIM6EN */
    TEST_ASSERT_BITS_HIGH((1u << (54 - 32)), r_nvic.ISER[1]);               /* ISER1: TIM6_DAC */
    /* no tick yet: sleeps (WFI) until the interrupt, late 0 */
    assert_status(g4_tick_wait(&late), PMA_OK);
    TEST_ASSERT_EQUAL_INT(0u, late);
    TEST_ASSERT_EQUAL_INT(1u, wfi_count);
    /* three ticks pass while the loop works: served at once, late 3 */
    for (int i = 0; i < 3; ++i) {
        r_tim6.SR |= 1u;
        g4_tick_isr();
    }
    assert_status(g4_tick_wait(&late), PMA_OK);
    TEST_ASSERT_EQUAL_INT(3u, late);
    TEST_ASSERT_EQUAL_INT(1u, wfi_count);
    TEST_ASSERT_EQUAL_UINT32(0u, r_tim6.SR & 1u); /* UIF cleared by the handler */
    g4_tick_stop();
    assert_status(g4_tick_wait(&late), PMA_ERR_NOT_READY);
}

static void test_time_us_extends_to_64_bits(void)
{
    g4_time_init(170000000u);
    TEST_ASSERT_EQUAL_UINT32(169u, r_tim2.PSC);
    TEST_ASSERT_EQUAL_HEX32(0xFFFFFFFFu, r_tim2.ARR);
    r_tim2.CNT = 0xFFFFFFF0u;
    TEST_ASSERT_EQUAL_UINT64(0xFFFFFFF0ull, g4_time_us());
    /* wrapped, interrupt still pending: the small count is already the next period */
    r_tim2.CNT = 5u;
    r_tim2.SR = 1u;
    TEST_ASSERT_EQUAL_UINT64(0x100000005ull, g4_time_us());
    g4_time_isr();
    TEST_ASSERT_EQUAL_UINT32(0u, r_tim2.SR & 1u);
    TEST_ASSERT_EQUAL_UINT64(0x100000005ull, g4_time_us());
}

/* ------------------------------------------------------------ ADC / DAC -- */

static void test_adc_init_and_read(void)
{
    assert_status(g4_adc_init(), PMA_OK);
    const uint32_t cr = r_adc1.CR;
    TEST_ASSERT_EQUAL_UINT32(0u, cr & (1u << 29));                   /* out of deep power-down */
    TEST_ASSERT_BITS_HIGH((1u << 28), cr);                            /* regulator on */
    TEST_ASSERT_BITS_HIGH(0x5u, cr);                        /* ADEN, ADSTART */
    TEST_ASSERT_EQUAL_UINT32(1u, (r_adc1.SQR1 >> 6) & 0x1Fu); /* channel 1 = PA0 */
    TEST_ASSERT_EQUAL_UINT32(0u, r_adc1.SQR1 & 0xFu);         /* one conversion */
    const uint32_t cfgr = r_adc1.CFGR;
    TEST_ASSERT_BITS_HIGH((1u << 13), cfgr);                          /* CONT */
    TEST_ASSERT_BITS_HIGH((1u << 12), cfgr);                          /* OVRMOD: newest result */
    TEST_ASSERT_EQUAL_INT(0u, (cfgr >> 3) & 3u);                  /* 12 bits */
    /* 16x oversampling, shift 4: still 12 bits */
    TEST_ASSERT_EQUAL_HEX32(1u | (3u << 2) | (4u << 5), r_adc1.CFGR2);
    TEST_ASSERT_EQUAL_UINT32(3u, (r_adc12c.CCR >> 16) & 3u); /* HCLK/4 */
    TEST_ASSERT_EQUAL_UINT32(3u, r_gpioa.MODER & 3u);                   /* PA0 analog */
    r_adc1.DR = 2048u;
    uint16_t raw = 0;
    assert_status(g4_adc_read(&raw), PMA_OK);
    TEST_ASSERT_EQUAL_INT(2048u, raw);
    r_adc1.DR = 4095u;
    assert_status(g4_adc_read(&raw), PMA_OK);
    TEST_ASSERT_EQUAL_INT(4095u, raw);
    /* the conversions stopped (e.g. an ADC error): an I/O error, never a stale number */
    r_adc1.CR &= ~ADC_CR_ADSTART;
    assert_status(g4_adc_read(&raw), PMA_ERR_IO);
}

static void test_adc_that_never_gets_ready_fails(void)
{
    adc_broken = 1;
    assert_status(g4_adc_init(), PMA_ERR_IO);
    uint16_t raw;
    assert_status(g4_adc_read(&raw), PMA_ERR_IO);
}

static void test_dac_init_and_write(void)
{
    assert_status(g4_dac_init(), PMA_OK);
    TEST_ASSERT_EQUAL_HEX32((2u << 14) | 2u, r_dac1.MCR); /* HFSEL > 160 MHz, MODE1 010: pin, no buffer */
    TEST_ASSERT_BITS_HIGH(1u, r_dac1.CR);       /* EN1 */
    TEST_ASSERT_EQUAL_UINT32(0u, r_dac1.DHR12R1);   /* starts at 0 V */
    TEST_ASSERT_EQUAL_UINT32(3u, (r_gpioa.MODER >> 8) & 3u);                /* PA4 analog */
    assert_status(g4_dac_write(4095u), PMA_OK);
    TEST_ASSERT_EQUAL_UINT32(4095u, r_dac1.DHR12R1);
    assert_status(g4_dac_write(1365u), PMA_OK);
    TEST_ASSERT_EQUAL_UINT32(1365u, r_dac1.DHR12R1);
    assert_status(g4_dac_write(4096u), PMA_ERR_RANGE);        /* 12-bit converter */
    TEST_ASSERT_EQUAL_UINT32(1365u, r_dac1.DHR12R1); /* unchanged */
}

/* ---------------------------------------------------------------- FDCAN -- */

static void test_can_bit_timing(void)
{
    g4_can_timing_t t;
    assert_status(g4_can_timing_for(170000000u, 1000000u, &t), PMA_OK);
    /* 170 MHz / 10 = 17 MHz: 17 tq per bit, sample point after 14 (82.4 %) */
    TEST_ASSERT_EQUAL_INT(10u, t.prescaler);
    TEST_ASSERT_EQUAL_INT(13u, t.tseg1_tq);
    TEST_ASSERT_EQUAL_INT(3u, t.tseg2_tq);
    TEST_ASSERT_EQUAL_INT(3u, t.sjw_tq);
    /* NBTP: NSJW = 2, NBRP = 9, NTSEG1 = 12, NTSEG2 = 2 (all minus one) */
    TEST_ASSERT_EQUAL_HEX32((2u << 25) | (9u << 16) | (12u << 8) | 2u, g4_nbtp_value(&t));
    const uint32_t rates[] = {1000000u, 500000u, 250000u, 125000u};
    for (size_t i = 0; i < 4; ++i) {
        assert_status(g4_can_timing_for(170000000u, rates[i], &t), PMA_OK);
        const uint32_t tq = 1u + t.tseg1_tq + t.tseg2_tq;
        TEST_ASSERT_EQUAL_UINT64(170000000ull, (uint64_t)t.prescaler * tq * rates[i]); /* exact rate */
        const uint32_t sp_permille = 1000u * (1u + t.tseg1_tq) / tq;
        TEST_ASSERT_TRUE(sp_permille >= 750u && sp_permille <= 900u);
        TEST_ASSERT_TRUE(t.sjw_tq >= 1u && t.sjw_tq <= t.tseg2_tq);
        TEST_ASSERT_TRUE(t.prescaler <= 512u && t.tseg1_tq <= 256u && t.tseg2_tq <= 128u);
    }
    assert_status(g4_can_timing_for(170000000u, 333333u, &t), PMA_ERR_RANGE);
    assert_status(g4_can_timing_for(170000000u, 0u, &t), PMA_ERR_RANGE);
}

static void can_up(void)
{
    assert_status(g4_can_init(170000000u, 1000000u), PMA_OK);
}

static void test_can_init_registers(void)
{
    can_up();
    TEST_ASSERT_EQUAL_HEX32((2u << 25) | (9u << 16) | (12u << 8) | 2u, r_fdcan1.NBTP);
    const uint32_t cccr = r_fdcan1.CCCR;
    TEST_ASSERT_EQUAL_UINT32(0u, cccr & 0x3u);             /* INIT and CCE cleared: on the bus */
    TEST_ASSERT_EQUAL_UINT32(0u, cccr & (3u << 8));        /* FDOE, BRSE off: classic CAN */
    TEST_ASSERT_EQUAL_UINT32(0u, cccr & (1u << 6));        /* DAR 0: automatic retransmission */
    /* no filter: accept every standard frame into FIFO 0; extended and remote rejected */
    TEST_ASSERT_EQUAL_HEX32((2u << 2) | 3u, r_fdcan1.RXGFC);
    TEST_ASSERT_EQUAL_HEX32(1u | 4u | (1u << 9), r_fdcan1.IE);
    TEST_ASSERT_EQUAL_UINT32(1u, r_fdcan1.ILE);
    TEST_ASSERT_EQUAL_UINT32(2u, (r_rcc.CCIPR >> 24) & 3u); /* kernel clock PCLK1 */
    TEST_ASSERT_BITS_HIGH((1u << 25), r_rcc.APB1ENR1);      /* FDCANEN */
    /* PA11, PA12: alternate function 9 */
    TEST_ASSERT_EQUAL_HEX32(0xAu, (r_gpioa.MODER >> 22) & 0xFu);
    TEST_ASSERT_EQUAL_HEX32(0x99u, (r_gpioa.AFR[1] >> 12) & 0xFFu);
    TEST_ASSERT_BITS_HIGH((1u << 21), r_nvic.ISER[0]);           /* FDCAN1_IT0 enabled */
    for (size_t i = 0; i < G4_MRAM_SIZE / 4u; ++i) TEST_ASSERT_EQUAL_UINT32(0u, r_mram[i]); /* RAM cleared */
}

static void test_can_filters(void)
{
    can_up();
    /* the application's: this node's ids (node 3), and the broadcast id 0 */
    const pma_can_filter_t f[2] = {{.id = 3u, .mask = 0x00Fu}, {.id = 0x000u, .mask = 0x7FFu}};
    assert_status(g4_can_set_filters(f, 2), PMA_OK);
    /* SFT = 2 (classic id + mask), SFEC = 1 (Rx FIFO 0), SFID1 = id, SFID2 = mask */
    TEST_ASSERT_EQUAL_HEX32(0x8803000Fu, r_mram[0]);
    TEST_ASSERT_EQUAL_HEX32(0x880007FFu, r_mram[1]);
    TEST_ASSERT_EQUAL_UINT32(0u, r_mram[2]);
    /* LSS = 2, non-matching standard and extended frames rejected, remote rejected */
    TEST_ASSERT_EQUAL_HEX32((2u << 16) | (2u << 4) | (2u << 2) | 3u, r_fdcan1.RXGFC);
    TEST_ASSERT_EQUAL_UINT32(0u, r_fdcan1.CCCR & 3u); /* back on the bus */
    /* refused changes leave everything as it was */
    pma_can_filter_t nine[9];
    memset(nine, 0, sizeof nine);
    assert_status(g4_can_set_filters(nine, 9), PMA_ERR_RANGE);
    const pma_can_filter_t bad = {.id = 0x800u, .mask = 0x7FFu};
    assert_status(g4_can_set_filters(&bad, 1), PMA_ERR_RANGE);
    TEST_ASSERT_EQUAL_HEX32(0x8803000Fu, r_mram[0]);
    TEST_ASSERT_EQUAL_UINT32(2u, (r_fdcan1.RXGFC >> 16) & 0x1Fu);
    /* back to accept-all */
    assert_status(g4_can_set_filters(NULL, 0), PMA_OK);
    TEST_ASSERT_EQUAL_HEX32((2u << 2) | 3u, r_fdcan1.RXGFC);
    TEST_ASSERT_EQUAL_UINT32(0u, r_mram[0]);
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

static void test_can_send_through_the_interrupt(void)
{
    can_up();
    r_fdcan1.TXFQS = 3u | (1u << 16); /* 3 free, put index 1 */
    for (uint8_t i = 0; i < 4; ++i) {
        const pma_can_frame_t f = frame((uint16_t)(0x1A3u + i), (uint8_t)(5u + i), (uint8_t)(16u * i));
        r_nvic.ISPR[0] = 0u;
        assert_status(g4_can_send(&f), PMA_OK);
        TEST_ASSERT_BITS_HIGH((1u << 21), r_nvic.ISPR[0]); /* ISPR0: the interrupt pended */
    }
    g4_can_isr();
    /* three frames into elements 1, 2, 0 (the put index advances per add) */
    const uint32_t idx[3] = {1u, 2u, 0u};
    for (uint32_t k = 0; k < 3; ++k) {
        const uint32_t *el = &r_mram[(G4_MRAM_TBSA + idx[k] * 72u) / 4u];
        TEST_ASSERT_EQUAL_HEX32((uint32_t)(0x1A3u + k) << 18, el[0]); /* standard id, no XTD/RTR */
        TEST_ASSERT_EQUAL_HEX32((uint32_t)(5u + k) << 16, el[1]);     /* DLC, classic, no event */
        TEST_ASSERT_EQUAL_HEX32((uint32_t)(16u * k) | ((16u * k + 1u) << 8) | ((16u * k + 2u) << 16) |
                                    ((uint32_t)(uint8_t)(16u * k + 3u) << 24),
                                el[2]);
    }
    TEST_ASSERT_EQUAL_HEX32(0x7u, r_fdcan1.TXBAR);
    /* the fourth waits for a free element (the Tx FIFO empty interrupt) */
    r_fdcan1.TXFQS = 3u | (1u << 16);
    r_fdcan1.TXBAR = 0u;
    g4_can_isr();
    TEST_ASSERT_EQUAL_HEX32(0x2u, r_fdcan1.TXBAR);
    TEST_ASSERT_EQUAL_HEX32(0x1A6u << 18, r_mram[(G4_MRAM_TBSA + 72u) / 4u]);
    /* TX ring full: 16 frames while the controller takes none */
    r_fdcan1.TXFQS = 1u << 21; /* TFQF */
    const pma_can_frame_t f = frame(0x100u, 8u, 0u);
    for (unsigned i = 0; i < G4_CAN_TX_RING; ++i) assert_status(g4_can_send(&f), PMA_OK);
    assert_status(g4_can_send(&f), PMA_ERR_FULL);
    const pma_can_frame_t big = frame(0x800u, 1u, 0u);
    assert_status(g4_can_send(&big), PMA_ERR_RANGE);
    r_fdcan1.PSR = 1u << 7; /* bus-off */
    assert_status(g4_can_send(&f), PMA_ERR_BUS_OFF);
}

static void test_can_tx_idle_waits_for_the_ring_and_the_controller(void)
{
    can_up();
    TEST_ASSERT_TRUE(g4_can_tx_idle());
    r_fdcan1.TXFQS = 3u; /* 3 free, put index 0 */
    const pma_can_frame_t f = frame(0x51u, 4u, 1u);
    assert_status(g4_can_send(&f), PMA_OK);
    TEST_ASSERT_FALSE(g4_can_tx_idle());        /* in the ring */
    g4_can_isr();
    r_fdcan1.TXBRP = r_fdcan1.TXBAR;            /* the controller has the request pending */
    TEST_ASSERT_FALSE(g4_can_tx_idle());
    r_fdcan1.TXBRP = 0u;                        /* sent */
    TEST_ASSERT_TRUE(g4_can_tx_idle());
    assert_status(g4_can_send(&f), PMA_OK);
    r_fdcan1.CCCR |= 1u;                        /* INIT: off the bus (bus-off), it never drains */
    TEST_ASSERT_TRUE(g4_can_tx_idle());
}

static void put_rx(uint32_t gi, uint32_t r0, uint32_t r1, uint32_t d0, uint32_t d1)
{
    uint32_t *el = &r_mram[(G4_MRAM_F0SA + gi * 72u) / 4u];
    el[0] = r0;
    el[1] = r1;
    el[2] = d0;
    el[3] = d1;
    r_fdcan1.RXF0S = 1u | (gi << 8); /* fill 1, get index gi */
    r_fdcan1.IR |= 1u;               /* RF0N */
}

static void test_can_receive_through_the_interrupt(void)
{
    can_up();
    pma_can_frame_t f;
    assert_status(g4_can_recv(&f), PMA_ERR_EMPTY);
    put_rx(2u, 0x123u << 18, 8u << 16, 0x44332211u, 0x88776655u);
    g4_can_isr();
    TEST_ASSERT_EQUAL_UINT32(2u, r_fdcan1.RXF0A); /* acknowledged */
    TEST_ASSERT_EQUAL_UINT32(0u, r_fdcan1.IR & 1u); /* RF0N cleared */
    assert_status(g4_can_recv(&f), PMA_OK);
    TEST_ASSERT_EQUAL_INT(0x123u, f.id);
    TEST_ASSERT_EQUAL_INT(8u, f.dlc);
    for (uint8_t i = 0; i < 8; ++i) TEST_ASSERT_EQUAL_INT(0x11u * (i + 1u), f.data[i]);
    assert_status(g4_can_recv(&f), PMA_ERR_EMPTY);
    /* an extended frame never reaches the application */
    put_rx(0u, (1u << 30) | 0x123u, 2u << 16, 0u, 0u);
    g4_can_isr();
    assert_status(g4_can_recv(&f), PMA_ERR_EMPTY);
    /* a frame lost in the 3-element FIFO is counted */
    r_fdcan1.RXF0S = 0u;
    r_fdcan1.IR |= 1u << 2; /* RF0L */
    g4_can_isr();
    pma_can_status_t st;
    assert_status(g4_can_status(&st), PMA_OK);
    TEST_ASSERT_EQUAL_INT(1u, st.rx_overruns);
    /* the ring holds 32: the 33rd frame before a recv is an overrun */
    for (unsigned i = 0; i < G4_CAN_RX_RING + 1u; ++i) {
        put_rx(i % 3u, (0x200u + i) << 18, 1u << 16, i, 0u);
        g4_can_isr();
    }
    assert_status(g4_can_status(&st), PMA_OK);
    TEST_ASSERT_EQUAL_INT(2u, st.rx_overruns);
    for (unsigned i = 0; i < G4_CAN_RX_RING; ++i) {
        assert_status(g4_can_recv(&f), PMA_OK);
        TEST_ASSERT_EQUAL_INT(0x200u + i, f.id); /* in order */
    }
    assert_status(g4_can_recv(&f), PMA_ERR_EMPTY);
}

static void test_can_error_states_and_recovery(void)
{
    can_up();
    pma_can_status_t st;
    r_fdcan1.ECR = 100u | (5u << 8);
    assert_status(g4_can_status(&st), PMA_OK);
    TEST_ASSERT_EQUAL_INT(PMA_CAN_ERROR_ACTIVE, st.state);
    TEST_ASSERT_EQUAL_INT(100u, st.tec);
    TEST_ASSERT_EQUAL_INT(5u, st.rec);
    r_fdcan1.ECR = 130u;
    r_fdcan1.PSR = 1u << 5; /* EP */
    assert_status(g4_can_status(&st), PMA_OK);
    TEST_ASSERT_EQUAL_INT(PMA_CAN_ERROR_PASSIVE, st.state);
    TEST_ASSERT_EQUAL_INT(130u, st.tec);
    r_fdcan1.ECR = 1u << 15; /* RP: REC at 128 */
    assert_status(g4_can_status(&st), PMA_OK);
    TEST_ASSERT_EQUAL_INT(128u, st.rec);
    /* bus-off: the controller has put itself in INIT */
    r_fdcan1.PSR = (1u << 7) | (1u << 5);
    r_fdcan1.CCCR |= 1u;
    assert_status(g4_can_status(&st), PMA_OK);
    TEST_ASSERT_EQUAL_INT(PMA_CAN_BUS_OFF, st.state);
    TEST_ASSERT_EQUAL_INT(256u, st.tec);
    assert_status(g4_can_recover(), PMA_OK);
    TEST_ASSERT_EQUAL_UINT32(0u, r_fdcan1.CCCR & 1u); /* INIT cleared: recovery runs */
    /* not bus-off: recover changes nothing */
    r_fdcan1.PSR = 0u;
    r_fdcan1.CCCR |= 1u;
    assert_status(g4_can_recover(), PMA_OK);
    TEST_ASSERT_EQUAL_UINT32(1u, r_fdcan1.CCCR & 1u);
}

/* ------------------------------------------------------------------ flash -- */

static void test_flash_geometry(void)
{
    pma_nvm_geometry_t g;
    assert_status(g4_flash_geometry(&g), PMA_OK);
    TEST_ASSERT_EQUAL_INT(2048u, g.block_size);
    TEST_ASSERT_EQUAL_INT(2u, g.block_count);
    TEST_ASSERT_EQUAL_INT(8u, g.program_size);
    r_flash.OPTR = 0u; /* single bank */
    assert_status(g4_flash_geometry(&g), PMA_OK);
    TEST_ASSERT_EQUAL_INT(4096u, g.block_size);
}

static void test_flash_erase_sequence(void)
{
    memset(nvm_mem, 0x00, sizeof nvm_mem);
    assert_status(g4_flash_erase(1u), PMA_OK);
    /* unlocked with the two keys */
    TEST_ASSERT_EQUAL_INT(1u, flash_unlocks);
    /* the erase: PER, PNB 127, BKER (bank 2), STRT */
    TEST_ASSERT_GREATER_OR_EQUAL_UINT32(2u, flash_waits);
    TEST_ASSERT_EQUAL_HEX32((1u << 1) | (127u << 3) | (1u << 11) | (1u << 16), flash_cr_at_wait[1]);
    /* bank 2 page 127 = 0x0807F800: the last 2 KB, and only those */
    const uint8_t *m = (const uint8_t *)nvm_mem;
    for (uint32_t i = 0; i < G4_NVM_BYTES; ++i) TEST_ASSERT_EQUAL_HEX8(i >= 6144u ? 0xFFu : 0u, m[i]);
    TEST_ASSERT_EQUAL_HEX32(1u << 31, r_flash.CR); /* locked again, PER cleared */
    /* single bank: page 126 (4 KB at 0x0807E000) */
    memset(nvm_mem, 0x00, sizeof nvm_mem);
    r_flash.OPTR = 0u;
    assert_status(g4_flash_erase(0u), PMA_OK);
    for (uint32_t i = 0; i < G4_NVM_BYTES; ++i) TEST_ASSERT_EQUAL_HEX8(i < 4096u ? 0xFFu : 0u, m[i]);
    assert_status(g4_flash_erase(2u), PMA_ERR_RANGE);
}

static void test_flash_program_and_read(void)
{
    uint8_t data[24];
    for (unsigned i = 0; i < sizeof data; ++i) data[i] = (uint8_t)(0xA0u + i);
    /* block 0 in dual bank: 0x0807F000, 4 KB into the area */
    assert_status(g4_flash_program(0u, 16u, data + 1, 16u), PMA_OK); /* unaligned source */
    TEST_ASSERT_EQUAL_MEMORY(data + 1, (uint8_t *)nvm_mem + 4096u + 16u, 16u);
    TEST_ASSERT_EQUAL_HEX8(0xFFu, ((uint8_t *)nvm_mem)[4096u + 15u]);
    TEST_ASSERT_EQUAL_HEX8(0xFFu, ((uint8_t *)nvm_mem)[4096u + 32u]);
    TEST_ASSERT_EQUAL_HEX32(1u, flash_cr_at_wait[1]); /* PG during the double-word program */
    TEST_ASSERT_EQUAL_HEX32(1u << 31, r_flash.CR);
    uint8_t back[16];
    assert_status(g4_flash_read(0u, 16u, back, 16u), PMA_OK);
    TEST_ASSERT_EQUAL_MEMORY(data + 1, back, 16u);
    /* over programmed bytes: refused, nothing written */
    assert_status(g4_flash_program(0u, 24u, data, 16u), PMA_ERR_NOT_ERASED);
    TEST_ASSERT_EQUAL_HEX8(0xFFu, ((uint8_t *)nvm_mem)[4096u + 32u]);
    /* alignment and range */
    assert_status(g4_flash_program(0u, 4u, data, 8u), PMA_ERR_RANGE);
    assert_status(g4_flash_program(0u, 0u, data, 12u), PMA_ERR_RANGE);
    assert_status(g4_flash_program(0u, 2048u, data, 8u), PMA_ERR_RANGE);
    assert_status(g4_flash_program(2u, 0u, data, 8u), PMA_ERR_RANGE);
    assert_status(g4_flash_read(1u, 2040u, back, 16u), PMA_ERR_RANGE);
}

static void test_flash_errors(void)
{
    uint8_t data[8] = {1, 2, 3, 4, 5, 6, 7, 8};
    /* a programming error flag ends the operation with an I/O error, locked */
    flash_error_next = FLASH_SR_PROGERR;
    assert_status(g4_flash_program(1u, 0u, data, 8u), PMA_ERR_IO);
    TEST_ASSERT_EQUAL_HEX32(1u << 31, r_flash.CR);
    TEST_ASSERT_EQUAL_UINT32(0u, r_flash.SR & FLASH_SR_PROGERR); /* cleared */
    flash_error_next = FLASH_SR_WRPERR;
    assert_status(g4_flash_erase(0u), PMA_ERR_IO);
    flash_error_next = 0;
    /* a flash that stays busy: a bounded wait, then an I/O error */
    flash_stuck_busy = 1;
    assert_status(g4_flash_erase(0u), PMA_ERR_IO);
    flash_stuck_busy = 0;
    /* a double ECC error during a read (the NMI flagged it): corrupt, and cleared */
    r_flash.ECCR = 1u << 31;
    uint8_t back[8];
    assert_status(g4_flash_read(0u, 0u, back, 8u), PMA_ERR_CORRUPT);
    TEST_ASSERT_EQUAL_UINT32(0u, r_flash.ECCR & (1u << 31));
    TEST_ASSERT_EQUAL_INT(0, g4_flash_nmi()); /* an NMI without ECCD is not the flash's */
    assert_status(g4_flash_read(0u, 0u, back, 8u), PMA_OK);
}

/* ------------------------------------------------------------------ IWDG -- */

static void test_iwdg_reload(void)
{
    g4_iwdg_regs_t r;
    const uint32_t ms[] = {1u, 100u, 500u, 1000u, 4096u, 32768u};
    const uint32_t pr[] = {0u, 0u, 0u, 1u, 3u, 6u};
    for (size_t i = 0; i < 6; ++i) {
        assert_status(g4_iwdg_config(ms[i], &r), PMA_OK);
        TEST_ASSERT_EQUAL_INT(pr[i], r.pr);
        TEST_ASSERT_LESS_OR_EQUAL_UINT32(4095u, r.rlr);
        /* the timeout (RLR + 1) x (4 << PR) / 32 kHz is the request, rounded up */
        const uint64_t t_us = (uint64_t)(r.rlr + 1u) * (4u << r.pr) * 1000000u / 32000u;
        TEST_ASSERT_GREATER_OR_EQUAL_UINT64(1000ull * ms[i], t_us);
        TEST_ASSERT_LESS_THAN_UINT64(1000ull * ms[i] + (4u << r.pr) * 1000000u / 32000u, t_us);
    }
    assert_status(g4_iwdg_config(1000u, &r), PMA_OK);
    TEST_ASSERT_EQUAL_INT(3999u, r.rlr); /* /8: 4000 counts of 250 us */
    assert_status(g4_iwdg_config(0u, &r), PMA_ERR_RANGE);
    assert_status(g4_iwdg_config(32769u, &r), PMA_ERR_RANGE);
    assert_status(g4_iwdg_start(500u), PMA_OK);
    TEST_ASSERT_EQUAL_UINT32(0u, r_iwdg.PR);
    TEST_ASSERT_EQUAL_UINT32(3999u, r_iwdg.RLR);
    TEST_ASSERT_EQUAL_HEX32(0xAAAAu, r_iwdg.KR); /* reloaded last */
    r_iwdg.KR = 0u;
    g4_iwdg_kick();
    TEST_ASSERT_EQUAL_HEX32(0xAAAAu, r_iwdg.KR);
    iwdg_stuck = 1;
    assert_status(g4_iwdg_start(500u), PMA_ERR_IO);
}

/* ----------------------------------------------------- the port (hal.h) -- */

static void test_port_over_the_drivers(void)
{
    TEST_ASSERT_EQUAL_STRING("stm32g474", pma_hal_port_name());
    uint16_t raw;
    assert_status(pma_hal_adc_read(&raw), PMA_ERR_NOT_READY);
    pma_hal_stm32g474_system_init();
    TEST_ASSERT_EQUAL_INT(1, pma_hal_stm32g474_clock_source()); /* HSE */
    TEST_ASSERT_EQUAL_UINT32(1u, (r_gpioa.MODER >> 10) & 3u);          /* PA5 (LD2) output */
    pma_hal_stm32g474_led_set(1);
    TEST_ASSERT_EQUAL_HEX32(1u << 5, r_gpioa.BSRR);
    pma_hal_stm32g474_led_set(0);
    TEST_ASSERT_EQUAL_HEX32(1u << 21, r_gpioa.BSRR);
    assert_status(pma_hal_init(NULL), PMA_OK);
    TEST_ASSERT_EQUAL_HEX32((2u << 25) | (9u << 16) | (12u << 8) | 2u, r_fdcan1.NBTP);
    const pma_hal_config_t c500 = {.can_bitrate_bps = 500000u, .port = NULL};
    assert_status(pma_hal_init(&c500), PMA_OK);
    TEST_ASSERT_EQUAL_UINT32(16u, (r_fdcan1.NBTP >> 16) & 0x1FFu); /* /17: 20 tq */
    r_adc1.DR = 1234u;
    assert_status(pma_hal_adc_read(&raw), PMA_OK);
    TEST_ASSERT_EQUAL_INT(1234u, raw);
    assert_status(pma_hal_dac_write(4096u), PMA_ERR_RANGE);
    assert_status(pma_hal_tick_start(0u), PMA_ERR_RANGE);
    assert_status(pma_hal_tick_start(1000u), PMA_OK);
    uint32_t late = 9;
    assert_status(pma_hal_tick_wait(&late), PMA_OK);
    TEST_ASSERT_EQUAL_INT(0u, late);
    pma_nvm_geometry_t g;
    assert_status(pma_hal_nvm_geometry(&g), PMA_OK);
    TEST_ASSERT_EQUAL_INT(2048u, g.block_size);
    pma_hal_deinit();
    assert_status(pma_hal_adc_read(&raw), PMA_ERR_NOT_READY);
    assert_status(pma_hal_tick_wait(&late), PMA_ERR_NOT_READY);
    TEST_ASSERT_EQUAL_UINT32(1u, r_fdcan1.CCCR & 1u); /* CAN offline */
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_clock_hse_170mhz);
    RUN_TEST(test_clock_falls_back_to_hsi16);
    RUN_TEST(test_clock_pll_failure_keeps_hsi);
    RUN_TEST(test_pll_dividers);
    RUN_TEST(test_reset_cause);
    RUN_TEST(test_device_uid);
    RUN_TEST(test_tick_registers_for_each_rate);
    RUN_TEST(test_tick_start_and_wait);
    RUN_TEST(test_time_us_extends_to_64_bits);
    RUN_TEST(test_adc_init_and_read);
    RUN_TEST(test_adc_that_never_gets_ready_fails);
    RUN_TEST(test_dac_init_and_write);
    RUN_TEST(test_can_bit_timing);
    RUN_TEST(test_can_init_registers);
    RUN_TEST(test_can_filters);
    RUN_TEST(test_can_send_through_the_interrupt);
    RUN_TEST(test_can_tx_idle_waits_for_the_ring_and_the_controller);
    RUN_TEST(test_can_receive_through_the_interrupt);
    RUN_TEST(test_can_error_states_and_recovery);
    RUN_TEST(test_flash_geometry);
    RUN_TEST(test_flash_erase_sequence);
    RUN_TEST(test_flash_program_and_read);
    RUN_TEST(test_flash_errors);
    RUN_TEST(test_iwdg_reload);
    RUN_TEST(test_port_over_the_drivers);
    return UNITY_END();
}
