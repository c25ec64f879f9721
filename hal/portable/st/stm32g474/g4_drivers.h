/* SPDX-License-Identifier: Apache-2.0 */
/* The STM32G474 port's drivers (one file each), below the port interface
 * (pma_hal_stm32g474.c implements pma/hal.h with them). Register access only
 * through g4_io (g4_io.h), so tests/board/test_g4_drivers.c runs every driver
 * on the host against a RAM register file. Registers, bits and fields are
 * ST's (stm32g474xx.h, g4_cmsis.h); the rest is g4_port_defs.h. Units are in
 * the names. */
#ifndef G4_DRIVERS_H
#define G4_DRIVERS_H

#include <stddef.h>
#include <stdint.h>

#include "g4_io.h"
#include "pma/hal.h"

/* ---------------------------------------------------------------- clock -- */
#define G4_SYSCLK_HZ 170000000u        /* SYSCLK = HCLK = PCLK1 = PCLK2 */
#define G4_HSI16_HZ 16000000u
#ifndef G4_HSE_HZ
#define G4_HSE_HZ 24000000u            /* NUCLEO-G474RE: 24 MHz crystal X3 */
#endif
#ifndef G4_HSE_BYPASS
#define G4_HSE_BYPASS 0                /* 1: external clock on OSC_IN (ST-LINK MCO) */
#endif
#define G4_PLL_IN_HZ 4000000u          /* VCO input after /M (2.66..8 MHz allowed) */
#define G4_PLL_N 85u                   /* VCO 340 MHz */
#define G4_PLL_R 2u                    /* SYSCLK = VCO / 2 = 170 MHz */
#define G4_FLASH_LATENCY_170MHZ FLASH_ACR_LATENCY_4WS /* RM0440 table 9: 4 WS above 136 MHz (boost) */

typedef enum g4_clock_source { G4_CLOCK_HSE = 1, G4_CLOCK_HSI16 = 2 } g4_clock_source_t;

typedef struct g4_pll {
    uint32_t pllsrc;                   /* RCC_PLLCFGR_PLLSRC_HSI or _HSE (ST's, at bit 0) */
    uint32_t m, n, r;                  /* divider values (not register codes) */
} g4_pll_t;

/* PLL dividers giving 170 MHz from src_hz (a multiple of 4 MHz, up to 64 MHz). */
int g4_pll_for(uint32_t src_hz, uint32_t pllsrc, g4_pll_t *pll);
/* PLLCFGR value of a PLL setting. */
uint32_t g4_pllcfgr_value(const g4_pll_t *pll);
/* Clock tree to 170 MHz, once after reset: boost mode, 4 wait states, HSE
 * (prefer_hse) with fall-back to HSI16 when the HSE does not start, PLL,
 * the AHB /2 step for the boost transition. Returns the source used, or 0
 * when even the PLL on HSI16 failed (the MCU stays on HSI16 at 16 MHz). */
g4_clock_source_t g4_clock_init(int prefer_hse);
uint32_t g4_clock_sysclk_hz(void);     /* after g4_clock_init; 16 MHz before */

/* ----------------------------------------------------------------- GPIO -- */
void g4_gpio_mode(GPIO_TypeDef *port, uint32_t pin, uint32_t mode);
void g4_gpio_af(GPIO_TypeDef *port, uint32_t pin, uint32_t af);
void g4_gpio_write(GPIO_TypeDef *port, uint32_t pin, int high);

/* ---------------------------------------------------------------- reset -- */
pma_reset_cause_t g4_reset_cause_from_csr(uint32_t rcc_csr);
/* Reads RCC_CSR, keeps the cause, clears the flags (RMVF). */
pma_reset_cause_t g4_reset_latch(void);

/* ----------------------------------------------------------------- time -- */
/* TIM2: 32-bit free-running counter at 1 MHz, extended to 64 bits by its
 * overflow interrupt. Started by g4_time_init (at start-up, before main). */
void g4_time_init(uint32_t timclk_hz);
uint64_t g4_time_us(void);
void g4_time_isr(void);

/* TIM6: the control tick. PSC gives 1 us per count, ARR = period_us - 1. */
typedef struct g4_tick_regs {
    uint32_t psc, arr;
} g4_tick_regs_t;
int g4_tick_config(uint32_t timclk_hz, uint32_t period_us, g4_tick_regs_t *regs);
int g4_tick_start(uint32_t timclk_hz, uint32_t period_us);
void g4_tick_stop(void);
int g4_tick_wait(uint32_t *late_ticks);
void g4_tick_isr(void);

/* ------------------------------------------------------------ ADC / DAC -- */
#define G4_ADC_PIN 0u                  /* PA0 = ADC1_IN1, NUCLEO A0 */
#define G4_ADC_CHANNEL 1u
#define G4_ADC_SMP_92CYC5 5u           /* sampling time code: 92.5 ADC cycles */
#define G4_ADC_OVSR_16X 3u             /* oversampling ratio code: x16 */
#define G4_ADC_OVSS_SHIFT4 4u          /* right shift 4: the mean of 16, 12 bits */
#define G4_DAC_PIN 4u                  /* PA4 = DAC1_OUT1, NUCLEO A2 */
int g4_adc_init(void);
int g4_adc_read(uint16_t *raw_counts);
void g4_adc_stop(void);
int g4_dac_init(void);
int g4_dac_write(uint16_t counts);

/* ---------------------------------------------------------------- FDCAN -- */
typedef struct g4_can_timing {
    uint32_t prescaler, tseg1_tq, tseg2_tq, sjw_tq; /* in time quanta, not register codes */
} g4_can_timing_t;
/* Bit timing for a classic CAN bit rate from the kernel clock: the smallest
 * prescaler giving 8..25 time quanta per bit, sample point nearest 80 % at
 * >= 800 kbit/s and 87.5 % below (CiA 301). PMA_ERR_RANGE if none fits. */
int g4_can_timing_for(uint32_t kernel_hz, uint32_t bitrate_bps, g4_can_timing_t *t);
uint32_t g4_nbtp_value(const g4_can_timing_t *t);

#define G4_CAN_RX_RING 32u             /* frames (power of two) */
#define G4_CAN_TX_RING 16u
int g4_can_init(uint32_t kernel_hz, uint32_t bitrate_bps);
void g4_can_stop(void);
int g4_can_send(const pma_can_frame_t *frame);
int g4_can_recv(pma_can_frame_t *frame);
int g4_can_set_filters(const pma_can_filter_t *filters, size_t count);
int g4_can_status(pma_can_status_t *status);
int g4_can_recover(void);
void g4_can_isr(void);
/* 1 when no frame waits to be sent (the TX ring empty, no transmission request
 * pending in the controller) or the controller is off the bus. */
int g4_can_tx_idle(void);

/* ------------------------------------------------------------------ NVM -- */
/* The last two flash pages: bank 2 pages 126 and 127 (2 KB, dual-bank, the
 * default) or pages 126 and 127 (4 KB, single-bank); both inside the 8 KB
 * the linker script leaves free at 0x0807E000. */
#define G4_NVM_BASE 0x0807E000u
#define G4_NVM_BYTES 8192u
#define G4_NVM_FIRST_PAGE 126u
int g4_flash_geometry(pma_nvm_geometry_t *g);
int g4_flash_read(uint32_t block, uint32_t offset, void *buf, uint32_t len);
int g4_flash_program(uint32_t block, uint32_t offset, const void *data, uint32_t len);
int g4_flash_erase(uint32_t block);
/* The NMI handler's part: a double ECC error (ECCD) in flash is flagged for
 * the read in progress and cleared. Returns 1 when it was one. */
int g4_flash_nmi(void);

/* ------------------------------------------------------------------ IWDG -- */
#define G4_IWDG_MAX_MS 32768u          /* 4096 counts x /256 at 32 kHz */
typedef struct g4_iwdg_regs {
    uint32_t pr, rlr;                  /* register codes */
} g4_iwdg_regs_t;
int g4_iwdg_config(uint32_t timeout_ms, g4_iwdg_regs_t *regs);
int g4_iwdg_start(uint32_t timeout_ms);
void g4_iwdg_kick(void);

/* ------------------------------------------------------------------ LED -- */
#define G4_LED_PIN 5u                  /* PA5 = LD2 (green) on the NUCLEO */

#endif /* G4_DRIVERS_H */
