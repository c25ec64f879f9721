/* STM32G474 register definitions: the project's own, written from RM0440
 * (STM32G4 reference manual) for exactly the registers this port uses. Not
 * ST's or CMSIS headers.
 *
 * Naming scheme (parsed mechanically by tools/check_svd_regs.py, which checks
 * every address, offset and bit field here against ST's SVD file,
 * ../shared/data/svd/STM32G474xx.svd, in tests/board/test_svd_regs.py):
 *
 *   G4_<PERIPH>_BASE                  base address of a peripheral (SVD name,
 *                                     upper case: RCC, FDCAN1, ADC12_COMMON ...)
 *   G4_<PERIPH>_<REG>_OFFSET          register offset from the base (SVD
 *                                     register name without the peripheral's
 *                                     prefix: RCC_CR -> CR, DAC_MCR -> MCR)
 *   G4_<PERIPH>_<REG>_<FIELD>_Pos     first bit of a field (SVD field name)
 *   G4_<PERIPH>_<REG>_<FIELD>_Msk     (0x<ones>u << _Pos): the field's width
 *   G4_IRQ_<NAME>                     interrupt number (SVD interrupt name)
 *   G4_<P>_SAME_LAYOUT_AS_<Q>         peripheral P has every register and field
 *                                     declared here for Q (checked too)
 * Everything else (key values, field values, the FDCAN message RAM element
 * layout, which the SVD does not describe) is named otherwise and documented
 * with its RM0440 section; only G4_MRAM_* has a base (checked against the SVD
 * block at that address).
 *
 * All registers are 32 bits wide. */
#ifndef G4_REGS_H
#define G4_REGS_H

/* ------------------------------------------------------- RCC (RM0440 7.4) -- */
#define G4_RCC_BASE 0x40021000u
#define G4_RCC_CR_OFFSET 0x00u
#define G4_RCC_CR_HSION_Pos 8u
#define G4_RCC_CR_HSION_Msk (0x1u << G4_RCC_CR_HSION_Pos)
#define G4_RCC_CR_HSIRDY_Pos 10u
#define G4_RCC_CR_HSIRDY_Msk (0x1u << G4_RCC_CR_HSIRDY_Pos)
#define G4_RCC_CR_HSEON_Pos 16u
#define G4_RCC_CR_HSEON_Msk (0x1u << G4_RCC_CR_HSEON_Pos)
#define G4_RCC_CR_HSERDY_Pos 17u
#define G4_RCC_CR_HSERDY_Msk (0x1u << G4_RCC_CR_HSERDY_Pos)
#define G4_RCC_CR_HSEBYP_Pos 18u
#define G4_RCC_CR_HSEBYP_Msk (0x1u << G4_RCC_CR_HSEBYP_Pos)
#define G4_RCC_CR_PLLON_Pos 24u
#define G4_RCC_CR_PLLON_Msk (0x1u << G4_RCC_CR_PLLON_Pos)
#define G4_RCC_CR_PLLRDY_Pos 25u
#define G4_RCC_CR_PLLRDY_Msk (0x1u << G4_RCC_CR_PLLRDY_Pos)

#define G4_RCC_CFGR_OFFSET 0x08u
#define G4_RCC_CFGR_SW_Pos 0u
#define G4_RCC_CFGR_SW_Msk (0x3u << G4_RCC_CFGR_SW_Pos)
#define G4_RCC_CFGR_SWS_Pos 2u
#define G4_RCC_CFGR_SWS_Msk (0x3u << G4_RCC_CFGR_SWS_Pos)
#define G4_RCC_CFGR_HPRE_Pos 4u
#define G4_RCC_CFGR_HPRE_Msk (0xFu << G4_RCC_CFGR_HPRE_Pos)
#define G4_RCC_CFGR_PPRE1_Pos 8u
#define G4_RCC_CFGR_PPRE1_Msk (0x7u << G4_RCC_CFGR_PPRE1_Pos)
#define G4_RCC_CFGR_PPRE2_Pos 11u
#define G4_RCC_CFGR_PPRE2_Msk (0x7u << G4_RCC_CFGR_PPRE2_Pos)
#define G4_RCC_CFGR_SW_HSI16 1u        /* SW/SWS values */
#define G4_RCC_CFGR_SW_HSE 2u
#define G4_RCC_CFGR_SW_PLL 3u
#define G4_RCC_CFGR_HPRE_DIV1 0u       /* HPRE values */
#define G4_RCC_CFGR_HPRE_DIV2 8u

#define G4_RCC_PLLCFGR_OFFSET 0x0Cu
#define G4_RCC_PLLCFGR_PLLSRC_Pos 0u
#define G4_RCC_PLLCFGR_PLLSRC_Msk (0x3u << G4_RCC_PLLCFGR_PLLSRC_Pos)
#define G4_RCC_PLLCFGR_PLLM_Pos 4u
#define G4_RCC_PLLCFGR_PLLM_Msk (0xFu << G4_RCC_PLLCFGR_PLLM_Pos)
#define G4_RCC_PLLCFGR_PLLN_Pos 8u
#define G4_RCC_PLLCFGR_PLLN_Msk (0x7Fu << G4_RCC_PLLCFGR_PLLN_Pos)
#define G4_RCC_PLLCFGR_PLLREN_Pos 24u
#define G4_RCC_PLLCFGR_PLLREN_Msk (0x1u << G4_RCC_PLLCFGR_PLLREN_Pos)
#define G4_RCC_PLLCFGR_PLLR_Pos 25u
#define G4_RCC_PLLCFGR_PLLR_Msk (0x3u << G4_RCC_PLLCFGR_PLLR_Pos)
#define G4_RCC_PLLCFGR_PLLSRC_HSI16 2u /* PLLSRC values */
#define G4_RCC_PLLCFGR_PLLSRC_HSE 3u

#define G4_RCC_AHB2ENR_OFFSET 0x4Cu
#define G4_RCC_AHB2ENR_GPIOAEN_Pos 0u
#define G4_RCC_AHB2ENR_GPIOAEN_Msk (0x1u << G4_RCC_AHB2ENR_GPIOAEN_Pos)
#define G4_RCC_AHB2ENR_GPIOBEN_Pos 1u
#define G4_RCC_AHB2ENR_GPIOBEN_Msk (0x1u << G4_RCC_AHB2ENR_GPIOBEN_Pos)
#define G4_RCC_AHB2ENR_ADC12EN_Pos 13u
#define G4_RCC_AHB2ENR_ADC12EN_Msk (0x1u << G4_RCC_AHB2ENR_ADC12EN_Pos)
#define G4_RCC_AHB2ENR_DAC1EN_Pos 16u
#define G4_RCC_AHB2ENR_DAC1EN_Msk (0x1u << G4_RCC_AHB2ENR_DAC1EN_Pos)

#define G4_RCC_APB1ENR1_OFFSET 0x58u
#define G4_RCC_APB1ENR1_TIM2EN_Pos 0u
#define G4_RCC_APB1ENR1_TIM2EN_Msk (0x1u << G4_RCC_APB1ENR1_TIM2EN_Pos)
#define G4_RCC_APB1ENR1_TIM6EN_Pos 4u
#define G4_RCC_APB1ENR1_TIM6EN_Msk (0x1u << G4_RCC_APB1ENR1_TIM6EN_Pos)
#define G4_RCC_APB1ENR1_FDCANEN_Pos 25u
#define G4_RCC_APB1ENR1_FDCANEN_Msk (0x1u << G4_RCC_APB1ENR1_FDCANEN_Pos)
#define G4_RCC_APB1ENR1_PWREN_Pos 28u
#define G4_RCC_APB1ENR1_PWREN_Msk (0x1u << G4_RCC_APB1ENR1_PWREN_Pos)

#define G4_RCC_CCIPR_OFFSET 0x88u
#define G4_RCC_CCIPR_FDCANSEL_Pos 24u
#define G4_RCC_CCIPR_FDCANSEL_Msk (0x3u << G4_RCC_CCIPR_FDCANSEL_Pos)
#define G4_RCC_CCIPR_ADC12SEL_Pos 28u
#define G4_RCC_CCIPR_ADC12SEL_Msk (0x3u << G4_RCC_CCIPR_ADC12SEL_Pos)
#define G4_RCC_CCIPR_FDCANSEL_PCLK1 2u /* FDCAN kernel clock = PCLK1 */
#define G4_RCC_CCIPR_ADC12SEL_SYSCLK 2u

#define G4_RCC_CSR_OFFSET 0x94u
#define G4_RCC_CSR_LSION_Pos 0u
#define G4_RCC_CSR_LSION_Msk (0x1u << G4_RCC_CSR_LSION_Pos)
#define G4_RCC_CSR_LSIRDY_Pos 1u
#define G4_RCC_CSR_LSIRDY_Msk (0x1u << G4_RCC_CSR_LSIRDY_Pos)
#define G4_RCC_CSR_RMVF_Pos 23u
#define G4_RCC_CSR_RMVF_Msk (0x1u << G4_RCC_CSR_RMVF_Pos)
#define G4_RCC_CSR_OBLRSTF_Pos 25u
#define G4_RCC_CSR_OBLRSTF_Msk (0x1u << G4_RCC_CSR_OBLRSTF_Pos)
#define G4_RCC_CSR_PINRSTF_Pos 26u
#define G4_RCC_CSR_PINRSTF_Msk (0x1u << G4_RCC_CSR_PINRSTF_Pos)
#define G4_RCC_CSR_BORRSTF_Pos 27u
#define G4_RCC_CSR_BORRSTF_Msk (0x1u << G4_RCC_CSR_BORRSTF_Pos)
#define G4_RCC_CSR_SFTRSTF_Pos 28u
#define G4_RCC_CSR_SFTRSTF_Msk (0x1u << G4_RCC_CSR_SFTRSTF_Pos)
#define G4_RCC_CSR_IWDGRSTF_Pos 29u
#define G4_RCC_CSR_IWDGRSTF_Msk (0x1u << G4_RCC_CSR_IWDGRSTF_Pos)
#define G4_RCC_CSR_WWDGRSTF_Pos 30u
#define G4_RCC_CSR_WWDGRSTF_Msk (0x1u << G4_RCC_CSR_WWDGRSTF_Pos)
#define G4_RCC_CSR_LPWRRSTF_Pos 31u
#define G4_RCC_CSR_LPWRRSTF_Msk (0x1u << G4_RCC_CSR_LPWRRSTF_Pos)

/* ------------------------------------------------------- PWR (RM0440 6.4) -- */
#define G4_PWR_BASE 0x40007000u
#define G4_PWR_CR1_OFFSET 0x00u
#define G4_PWR_CR1_VOS_Pos 9u
#define G4_PWR_CR1_VOS_Msk (0x3u << G4_PWR_CR1_VOS_Pos)
#define G4_PWR_CR1_VOS_RANGE1 1u
#define G4_PWR_SR2_OFFSET 0x14u
#define G4_PWR_SR2_VOSF_Pos 10u
#define G4_PWR_SR2_VOSF_Msk (0x1u << G4_PWR_SR2_VOSF_Pos)
#define G4_PWR_CR5_OFFSET 0x80u
#define G4_PWR_CR5_R1MODE_Pos 8u       /* 0: range 1 boost mode (needed above 150 MHz) */
#define G4_PWR_CR5_R1MODE_Msk (0x1u << G4_PWR_CR5_R1MODE_Pos)

/* ----------------------------------------------------- FLASH (RM0440 3.7) -- */
#define G4_FLASH_BASE 0x40022000u
#define G4_FLASH_ACR_OFFSET 0x00u
#define G4_FLASH_ACR_LATENCY_Pos 0u
#define G4_FLASH_ACR_LATENCY_Msk (0xFu << G4_FLASH_ACR_LATENCY_Pos)
#define G4_FLASH_ACR_PRFTEN_Pos 8u
#define G4_FLASH_ACR_PRFTEN_Msk (0x1u << G4_FLASH_ACR_PRFTEN_Pos)
#define G4_FLASH_ACR_ICEN_Pos 9u
#define G4_FLASH_ACR_ICEN_Msk (0x1u << G4_FLASH_ACR_ICEN_Pos)
#define G4_FLASH_ACR_DCEN_Pos 10u
#define G4_FLASH_ACR_DCEN_Msk (0x1u << G4_FLASH_ACR_DCEN_Pos)
#define G4_FLASH_ACR_DCRST_Pos 12u
#define G4_FLASH_ACR_DCRST_Msk (0x1u << G4_FLASH_ACR_DCRST_Pos)
#define G4_FLASH_KEYR_OFFSET 0x08u
#define G4_FLASH_KEY1 0x45670123u      /* RM0440 3.3.5: unlock sequence */
#define G4_FLASH_KEY2 0xCDEF89ABu
#define G4_FLASH_SR_OFFSET 0x10u
#define G4_FLASH_SR_EOP_Pos 0u
#define G4_FLASH_SR_EOP_Msk (0x1u << G4_FLASH_SR_EOP_Pos)
#define G4_FLASH_SR_OPERR_Pos 1u
#define G4_FLASH_SR_OPERR_Msk (0x1u << G4_FLASH_SR_OPERR_Pos)
#define G4_FLASH_SR_PROGERR_Pos 3u
#define G4_FLASH_SR_PROGERR_Msk (0x1u << G4_FLASH_SR_PROGERR_Pos)
#define G4_FLASH_SR_WRPERR_Pos 4u
#define G4_FLASH_SR_WRPERR_Msk (0x1u << G4_FLASH_SR_WRPERR_Pos)
#define G4_FLASH_SR_PGAERR_Pos 5u
#define G4_FLASH_SR_PGAERR_Msk (0x1u << G4_FLASH_SR_PGAERR_Pos)
#define G4_FLASH_SR_SIZERR_Pos 6u
#define G4_FLASH_SR_SIZERR_Msk (0x1u << G4_FLASH_SR_SIZERR_Pos)
#define G4_FLASH_SR_PGSERR_Pos 7u
#define G4_FLASH_SR_PGSERR_Msk (0x1u << G4_FLASH_SR_PGSERR_Pos)
#define G4_FLASH_SR_MISERR_Pos 8u
#define G4_FLASH_SR_MISERR_Msk (0x1u << G4_FLASH_SR_MISERR_Pos)
#define G4_FLASH_SR_FASTERR_Pos 9u
#define G4_FLASH_SR_FASTERR_Msk (0x1u << G4_FLASH_SR_FASTERR_Pos)
#define G4_FLASH_SR_RDERR_Pos 14u
#define G4_FLASH_SR_RDERR_Msk (0x1u << G4_FLASH_SR_RDERR_Pos)
#define G4_FLASH_SR_OPTVERR_Pos 15u
#define G4_FLASH_SR_OPTVERR_Msk (0x1u << G4_FLASH_SR_OPTVERR_Pos)
#define G4_FLASH_SR_BSY_Pos 16u
#define G4_FLASH_SR_BSY_Msk (0x1u << G4_FLASH_SR_BSY_Pos)
#define G4_FLASH_CR_OFFSET 0x14u
#define G4_FLASH_CR_PG_Pos 0u
#define G4_FLASH_CR_PG_Msk (0x1u << G4_FLASH_CR_PG_Pos)
#define G4_FLASH_CR_PER_Pos 1u
#define G4_FLASH_CR_PER_Msk (0x1u << G4_FLASH_CR_PER_Pos)
#define G4_FLASH_CR_PNB_Pos 3u
#define G4_FLASH_CR_PNB_Msk (0x7Fu << G4_FLASH_CR_PNB_Pos)
#define G4_FLASH_CR_STRT_Pos 16u
#define G4_FLASH_CR_STRT_Msk (0x1u << G4_FLASH_CR_STRT_Pos)
#define G4_FLASH_CR_LOCK_Pos 31u
#define G4_FLASH_CR_LOCK_Msk (0x1u << G4_FLASH_CR_LOCK_Pos)
/* BKER (bit 11, bank select of a page erase in dual-bank mode) is missing
 * from ST's SVD (RM0440 3.7.5 has it): defined as a value, not a field. */
#define G4_FLASH_CR_BKER_BIT (1u << 11)
#define G4_FLASH_ECCR_OFFSET 0x18u
#define G4_FLASH_ECCR_ADDR_ECC_Pos 0u
#define G4_FLASH_ECCR_ADDR_ECC_Msk (0x7FFFFu << G4_FLASH_ECCR_ADDR_ECC_Pos)
#define G4_FLASH_ECCR_BK_ECC_Pos 21u
#define G4_FLASH_ECCR_BK_ECC_Msk (0x1u << G4_FLASH_ECCR_BK_ECC_Pos)
#define G4_FLASH_ECCR_ECCC_Pos 30u
#define G4_FLASH_ECCR_ECCC_Msk (0x1u << G4_FLASH_ECCR_ECCC_Pos)
#define G4_FLASH_ECCR_ECCD_Pos 31u
#define G4_FLASH_ECCR_ECCD_Msk (0x1u << G4_FLASH_ECCR_ECCD_Pos)
#define G4_FLASH_OPTR_OFFSET 0x20u
/* DBANK (bit 22: 1 = dual bank, 2 KB pages; 0 = single bank, 4 KB pages) is
 * missing from ST's SVD too (RM0440 3.7.8). */
#define G4_FLASH_OPTR_DBANK_BIT (1u << 22)

/* ------------------------------------------------ GPIO (RM0440 9.4) -- */
#define G4_GPIOA_BASE 0x48000000u
#define G4_GPIOB_BASE 0x48000400u
#define G4_GPIOB_SAME_LAYOUT_AS_GPIOA 1
#define G4_GPIOA_MODER_OFFSET 0x00u
#define G4_GPIOA_MODER_MODER0_Pos 0u   /* 2 bits per pin: stride = MODER1 - MODER0 */
#define G4_GPIOA_MODER_MODER0_Msk (0x3u << G4_GPIOA_MODER_MODER0_Pos)
#define G4_GPIOA_MODER_MODER1_Pos 2u
#define G4_GPIOA_MODER_MODER1_Msk (0x3u << G4_GPIOA_MODER_MODER1_Pos)
#define G4_GPIOA_OSPEEDR_OFFSET 0x08u
#define G4_GPIOA_OSPEEDR_OSPEEDR0_Pos 0u
#define G4_GPIOA_OSPEEDR_OSPEEDR0_Msk (0x3u << G4_GPIOA_OSPEEDR_OSPEEDR0_Pos)
#define G4_GPIOA_OSPEEDR_OSPEEDR1_Pos 2u
#define G4_GPIOA_OSPEEDR_OSPEEDR1_Msk (0x3u << G4_GPIOA_OSPEEDR_OSPEEDR1_Pos)
#define G4_GPIOA_PUPDR_OFFSET 0x0Cu
#define G4_GPIOA_PUPDR_PUPDR0_Pos 0u
#define G4_GPIOA_PUPDR_PUPDR0_Msk (0x3u << G4_GPIOA_PUPDR_PUPDR0_Pos)
#define G4_GPIOA_PUPDR_PUPDR1_Pos 2u
#define G4_GPIOA_PUPDR_PUPDR1_Msk (0x3u << G4_GPIOA_PUPDR_PUPDR1_Pos)
#define G4_GPIOA_BSRR_OFFSET 0x18u
#define G4_GPIOA_BSRR_BS0_Pos 0u       /* set pin n: bit n; reset pin n: bit 16 + n */
#define G4_GPIOA_BSRR_BS0_Msk (0x1u << G4_GPIOA_BSRR_BS0_Pos)
#define G4_GPIOA_BSRR_BR0_Pos 16u
#define G4_GPIOA_BSRR_BR0_Msk (0x1u << G4_GPIOA_BSRR_BR0_Pos)
#define G4_GPIOA_AFRL_OFFSET 0x20u     /* pins 0..7, 4 bits each */
#define G4_GPIOA_AFRL_AFRL0_Pos 0u
#define G4_GPIOA_AFRL_AFRL0_Msk (0xFu << G4_GPIOA_AFRL_AFRL0_Pos)
#define G4_GPIOA_AFRL_AFRL1_Pos 4u
#define G4_GPIOA_AFRL_AFRL1_Msk (0xFu << G4_GPIOA_AFRL_AFRL1_Pos)
#define G4_GPIOA_AFRH_OFFSET 0x24u     /* pins 8..15 */
#define G4_GPIOA_AFRH_AFRH8_Pos 0u
#define G4_GPIOA_AFRH_AFRH8_Msk (0xFu << G4_GPIOA_AFRH_AFRH8_Pos)
#define G4_GPIO_MODE_INPUT 0u          /* MODER values */
#define G4_GPIO_MODE_OUTPUT 1u
#define G4_GPIO_MODE_AF 2u
#define G4_GPIO_MODE_ANALOG 3u
#define G4_GPIO_AF9_FDCAN1 9u          /* PA11/PA12, PB8/PB9: datasheet DS12288 table 13 */

/* --------------------------------------- TIM2 / TIM6 (RM0440 28.5, 30.4) -- */
/* TIM2 is the 32-bit free-running microsecond time base; its CNT and ARR are
 * 32 bits on the G474 (RM0440 28.5.21), the SVD describes 16: they are used
 * as whole registers, without field macros. */
#define G4_TIM2_BASE 0x40000000u
#define G4_TIM2_CR1_OFFSET 0x00u
#define G4_TIM2_CR1_CEN_Pos 0u
#define G4_TIM2_CR1_CEN_Msk (0x1u << G4_TIM2_CR1_CEN_Pos)
#define G4_TIM2_CR1_URS_Pos 2u
#define G4_TIM2_CR1_URS_Msk (0x1u << G4_TIM2_CR1_URS_Pos)
#define G4_TIM2_DIER_OFFSET 0x0Cu
#define G4_TIM2_DIER_UIE_Pos 0u
#define G4_TIM2_DIER_UIE_Msk (0x1u << G4_TIM2_DIER_UIE_Pos)
#define G4_TIM2_SR_OFFSET 0x10u
#define G4_TIM2_SR_UIF_Pos 0u
#define G4_TIM2_SR_UIF_Msk (0x1u << G4_TIM2_SR_UIF_Pos)
#define G4_TIM2_EGR_OFFSET 0x14u
#define G4_TIM2_EGR_UG_Pos 0u
#define G4_TIM2_EGR_UG_Msk (0x1u << G4_TIM2_EGR_UG_Pos)
#define G4_TIM2_CNT_OFFSET 0x24u
#define G4_TIM2_PSC_OFFSET 0x28u
#define G4_TIM2_PSC_PSC_Pos 0u
#define G4_TIM2_PSC_PSC_Msk (0xFFFFu << G4_TIM2_PSC_PSC_Pos)
#define G4_TIM2_ARR_OFFSET 0x2Cu

#define G4_TIM6_BASE 0x40001000u
#define G4_TIM6_CR1_OFFSET 0x00u
#define G4_TIM6_CR1_CEN_Pos 0u
#define G4_TIM6_CR1_CEN_Msk (0x1u << G4_TIM6_CR1_CEN_Pos)
#define G4_TIM6_CR1_URS_Pos 2u
#define G4_TIM6_CR1_URS_Msk (0x1u << G4_TIM6_CR1_URS_Pos)
#define G4_TIM6_CR1_ARPE_Pos 7u
#define G4_TIM6_CR1_ARPE_Msk (0x1u << G4_TIM6_CR1_ARPE_Pos)
#define G4_TIM6_DIER_OFFSET 0x0Cu
#define G4_TIM6_DIER_UIE_Pos 0u
#define G4_TIM6_DIER_UIE_Msk (0x1u << G4_TIM6_DIER_UIE_Pos)
#define G4_TIM6_SR_OFFSET 0x10u
#define G4_TIM6_SR_UIF_Pos 0u
#define G4_TIM6_SR_UIF_Msk (0x1u << G4_TIM6_SR_UIF_Pos)
#define G4_TIM6_EGR_OFFSET 0x14u
#define G4_TIM6_EGR_UG_Pos 0u
#define G4_TIM6_EGR_UG_Msk (0x1u << G4_TIM6_EGR_UG_Pos)
#define G4_TIM6_CNT_OFFSET 0x24u
#define G4_TIM6_PSC_OFFSET 0x28u
#define G4_TIM6_PSC_PSC_Pos 0u
#define G4_TIM6_PSC_PSC_Msk (0xFFFFu << G4_TIM6_PSC_PSC_Pos)
#define G4_TIM6_ARR_OFFSET 0x2Cu
#define G4_TIM6_ARR_ARR_Pos 0u
#define G4_TIM6_ARR_ARR_Msk (0xFFFFu << G4_TIM6_ARR_ARR_Pos)

/* ------------------------------------------------- ADC (RM0440 21.7, 21.8) -- */
#define G4_ADC1_BASE 0x50000000u
#define G4_ADC1_ISR_OFFSET 0x00u
#define G4_ADC1_ISR_ADRDY_Pos 0u
#define G4_ADC1_ISR_ADRDY_Msk (0x1u << G4_ADC1_ISR_ADRDY_Pos)
#define G4_ADC1_ISR_EOC_Pos 2u
#define G4_ADC1_ISR_EOC_Msk (0x1u << G4_ADC1_ISR_EOC_Pos)
#define G4_ADC1_ISR_OVR_Pos 4u
#define G4_ADC1_ISR_OVR_Msk (0x1u << G4_ADC1_ISR_OVR_Pos)
#define G4_ADC1_CR_OFFSET 0x08u
#define G4_ADC1_CR_ADEN_Pos 0u
#define G4_ADC1_CR_ADEN_Msk (0x1u << G4_ADC1_CR_ADEN_Pos)
#define G4_ADC1_CR_ADDIS_Pos 1u
#define G4_ADC1_CR_ADDIS_Msk (0x1u << G4_ADC1_CR_ADDIS_Pos)
#define G4_ADC1_CR_ADSTART_Pos 2u
#define G4_ADC1_CR_ADSTART_Msk (0x1u << G4_ADC1_CR_ADSTART_Pos)
#define G4_ADC1_CR_ADSTP_Pos 4u
#define G4_ADC1_CR_ADSTP_Msk (0x1u << G4_ADC1_CR_ADSTP_Pos)
#define G4_ADC1_CR_ADVREGEN_Pos 28u
#define G4_ADC1_CR_ADVREGEN_Msk (0x1u << G4_ADC1_CR_ADVREGEN_Pos)
#define G4_ADC1_CR_DEEPPWD_Pos 29u
#define G4_ADC1_CR_DEEPPWD_Msk (0x1u << G4_ADC1_CR_DEEPPWD_Pos)
#define G4_ADC1_CR_ADCALDIF_Pos 30u
#define G4_ADC1_CR_ADCALDIF_Msk (0x1u << G4_ADC1_CR_ADCALDIF_Pos)
#define G4_ADC1_CR_ADCAL_Pos 31u
#define G4_ADC1_CR_ADCAL_Msk (0x1u << G4_ADC1_CR_ADCAL_Pos)
#define G4_ADC1_CFGR_OFFSET 0x0Cu
#define G4_ADC1_CFGR_RES_Pos 3u
#define G4_ADC1_CFGR_RES_Msk (0x3u << G4_ADC1_CFGR_RES_Pos)
#define G4_ADC1_CFGR_OVRMOD_Pos 12u
#define G4_ADC1_CFGR_OVRMOD_Msk (0x1u << G4_ADC1_CFGR_OVRMOD_Pos)
#define G4_ADC1_CFGR_CONT_Pos 13u
#define G4_ADC1_CFGR_CONT_Msk (0x1u << G4_ADC1_CFGR_CONT_Pos)
#define G4_ADC1_CFGR_ALIGN_Pos 15u
#define G4_ADC1_CFGR_ALIGN_Msk (0x1u << G4_ADC1_CFGR_ALIGN_Pos)
#define G4_ADC1_CFGR2_OFFSET 0x10u
#define G4_ADC1_CFGR2_ROVSE_Pos 0u
#define G4_ADC1_CFGR2_ROVSE_Msk (0x1u << G4_ADC1_CFGR2_ROVSE_Pos)
#define G4_ADC1_CFGR2_OVSR_Pos 2u
#define G4_ADC1_CFGR2_OVSR_Msk (0x7u << G4_ADC1_CFGR2_OVSR_Pos)
#define G4_ADC1_CFGR2_OVSS_Pos 5u
#define G4_ADC1_CFGR2_OVSS_Msk (0xFu << G4_ADC1_CFGR2_OVSS_Pos)
#define G4_ADC1_SMPR1_OFFSET 0x14u
#define G4_ADC1_SMPR1_SMP1_Pos 3u
#define G4_ADC1_SMPR1_SMP1_Msk (0x7u << G4_ADC1_SMPR1_SMP1_Pos)
#define G4_ADC1_SQR1_OFFSET 0x30u
#define G4_ADC1_SQR1_L_Pos 0u
#define G4_ADC1_SQR1_L_Msk (0xFu << G4_ADC1_SQR1_L_Pos)
#define G4_ADC1_SQR1_SQ1_Pos 6u
#define G4_ADC1_SQR1_SQ1_Msk (0x1Fu << G4_ADC1_SQR1_SQ1_Pos)
#define G4_ADC1_DR_OFFSET 0x40u
#define G4_ADC1_DR_RDATA_Pos 0u
#define G4_ADC1_DR_RDATA_Msk (0xFFFFu << G4_ADC1_DR_RDATA_Pos)

#define G4_ADC12_COMMON_BASE 0x50000300u
#define G4_ADC12_COMMON_CCR_OFFSET 0x08u
#define G4_ADC12_COMMON_CCR_CKMODE_Pos 16u
#define G4_ADC12_COMMON_CCR_CKMODE_Msk (0x3u << G4_ADC12_COMMON_CCR_CKMODE_Pos)
#define G4_ADC_CKMODE_HCLK_DIV4 3u     /* 170 / 4 = 42.5 MHz ADC clock */

/* -------------------------------------------------------- DAC (RM0440 22.7) -- */
#define G4_DAC1_BASE 0x50000800u
#define G4_DAC1_CR_OFFSET 0x00u
#define G4_DAC1_CR_EN1_Pos 0u
#define G4_DAC1_CR_EN1_Msk (0x1u << G4_DAC1_CR_EN1_Pos)
#define G4_DAC1_DHR12R1_OFFSET 0x08u
#define G4_DAC1_DHR12R1_DACC1DHR_Pos 0u
#define G4_DAC1_DHR12R1_DACC1DHR_Msk (0xFFFu << G4_DAC1_DHR12R1_DACC1DHR_Pos)
#define G4_DAC1_DOR1_OFFSET 0x2Cu
#define G4_DAC1_DOR1_DACC1DOR_Pos 0u
#define G4_DAC1_DOR1_DACC1DOR_Msk (0xFFFu << G4_DAC1_DOR1_DACC1DOR_Pos)
#define G4_DAC1_SR_OFFSET 0x34u
#define G4_DAC1_SR_DAC1RDY_Pos 11u
#define G4_DAC1_SR_DAC1RDY_Msk (0x1u << G4_DAC1_SR_DAC1RDY_Pos)
#define G4_DAC1_MCR_OFFSET 0x3Cu
#define G4_DAC1_MCR_MODE1_Pos 0u       /* 000: normal, buffer on; 010: normal, buffer off, to the pin */
#define G4_DAC1_MCR_MODE1_Msk (0x7u << G4_DAC1_MCR_MODE1_Pos)
#define G4_DAC1_MCR_HFSEL_Pos 14u      /* 10: AHB clock above 160 MHz */
#define G4_DAC1_MCR_HFSEL_Msk (0x3u << G4_DAC1_MCR_HFSEL_Pos)
#define G4_DAC_HFSEL_ABOVE_160MHZ 2u
#define G4_DAC_MODE_PIN_UNBUFFERED 2u  /* MODE1 010: normal mode, external pin, buffer off (RM0440 DAC_MCR) */
#define G4_DAC_MAX_COUNTS 4095u        /* 12-bit, right-aligned */

/* ---------------------------------------------------- FDCAN (RM0440 44.4) -- */
#define G4_FDCAN1_BASE 0x40006400u
#define G4_FDCAN1_ECR_OFFSET 0x40u
#define G4_FDCAN1_ECR_TEC_Pos 0u
#define G4_FDCAN1_ECR_TEC_Msk (0xFFu << G4_FDCAN1_ECR_TEC_Pos)
#define G4_FDCAN1_ECR_REC_Pos 8u
#define G4_FDCAN1_ECR_REC_Msk (0x7Fu << G4_FDCAN1_ECR_REC_Pos)
#define G4_FDCAN1_ECR_RP_Pos 15u
#define G4_FDCAN1_ECR_RP_Msk (0x1u << G4_FDCAN1_ECR_RP_Pos)
#define G4_FDCAN1_CCCR_OFFSET 0x18u
#define G4_FDCAN1_CCCR_INIT_Pos 0u
#define G4_FDCAN1_CCCR_INIT_Msk (0x1u << G4_FDCAN1_CCCR_INIT_Pos)
#define G4_FDCAN1_CCCR_CCE_Pos 1u
#define G4_FDCAN1_CCCR_CCE_Msk (0x1u << G4_FDCAN1_CCCR_CCE_Pos)
#define G4_FDCAN1_CCCR_DAR_Pos 6u
#define G4_FDCAN1_CCCR_DAR_Msk (0x1u << G4_FDCAN1_CCCR_DAR_Pos)
#define G4_FDCAN1_CCCR_FDOE_Pos 8u
#define G4_FDCAN1_CCCR_FDOE_Msk (0x1u << G4_FDCAN1_CCCR_FDOE_Pos)
#define G4_FDCAN1_CCCR_BRSE_Pos 9u
#define G4_FDCAN1_CCCR_BRSE_Msk (0x1u << G4_FDCAN1_CCCR_BRSE_Pos)
#define G4_FDCAN1_CCCR_PXHD_Pos 12u
#define G4_FDCAN1_CCCR_PXHD_Msk (0x1u << G4_FDCAN1_CCCR_PXHD_Pos)
#define G4_FDCAN1_NBTP_OFFSET 0x1Cu
#define G4_FDCAN1_NBTP_NTSEG2_Pos 0u
#define G4_FDCAN1_NBTP_NTSEG2_Msk (0x7Fu << G4_FDCAN1_NBTP_NTSEG2_Pos)
#define G4_FDCAN1_NBTP_NTSEG1_Pos 8u
#define G4_FDCAN1_NBTP_NTSEG1_Msk (0xFFu << G4_FDCAN1_NBTP_NTSEG1_Pos)
#define G4_FDCAN1_NBTP_NBRP_Pos 16u
#define G4_FDCAN1_NBTP_NBRP_Msk (0x1FFu << G4_FDCAN1_NBTP_NBRP_Pos)
#define G4_FDCAN1_NBTP_NSJW_Pos 25u
#define G4_FDCAN1_NBTP_NSJW_Msk (0x7Fu << G4_FDCAN1_NBTP_NSJW_Pos)
#define G4_FDCAN1_PSR_OFFSET 0x44u
#define G4_FDCAN1_PSR_LEC_Pos 0u
#define G4_FDCAN1_PSR_LEC_Msk (0x7u << G4_FDCAN1_PSR_LEC_Pos)
#define G4_FDCAN1_PSR_EP_Pos 5u
#define G4_FDCAN1_PSR_EP_Msk (0x1u << G4_FDCAN1_PSR_EP_Pos)
#define G4_FDCAN1_PSR_EW_Pos 6u
#define G4_FDCAN1_PSR_EW_Msk (0x1u << G4_FDCAN1_PSR_EW_Pos)
#define G4_FDCAN1_PSR_BO_Pos 7u
#define G4_FDCAN1_PSR_BO_Msk (0x1u << G4_FDCAN1_PSR_BO_Pos)
#define G4_FDCAN1_IR_OFFSET 0x50u
#define G4_FDCAN1_IR_RF0N_Pos 0u
#define G4_FDCAN1_IR_RF0N_Msk (0x1u << G4_FDCAN1_IR_RF0N_Pos)
#define G4_FDCAN1_IR_RF0L_Pos 2u
#define G4_FDCAN1_IR_RF0L_Msk (0x1u << G4_FDCAN1_IR_RF0L_Pos)
#define G4_FDCAN1_IR_TC_Pos 7u
#define G4_FDCAN1_IR_TC_Msk (0x1u << G4_FDCAN1_IR_TC_Pos)
#define G4_FDCAN1_IR_TFE_Pos 9u
#define G4_FDCAN1_IR_TFE_Msk (0x1u << G4_FDCAN1_IR_TFE_Pos)
#define G4_FDCAN1_IE_OFFSET 0x54u
#define G4_FDCAN1_IE_RF0NE_Pos 0u
#define G4_FDCAN1_IE_RF0NE_Msk (0x1u << G4_FDCAN1_IE_RF0NE_Pos)
#define G4_FDCAN1_IE_RF0LE_Pos 2u
#define G4_FDCAN1_IE_RF0LE_Msk (0x1u << G4_FDCAN1_IE_RF0LE_Pos)
#define G4_FDCAN1_IE_TFEE_Pos 9u
#define G4_FDCAN1_IE_TFEE_Msk (0x1u << G4_FDCAN1_IE_TFEE_Pos)
#define G4_FDCAN1_ILS_OFFSET 0x58u
#define G4_FDCAN1_ILE_OFFSET 0x5Cu
#define G4_FDCAN1_ILE_EINT0_Pos 0u
#define G4_FDCAN1_ILE_EINT0_Msk (0x1u << G4_FDCAN1_ILE_EINT0_Pos)
#define G4_FDCAN1_RXGFC_OFFSET 0x80u
#define G4_FDCAN1_RXGFC_RRFE_Pos 0u
#define G4_FDCAN1_RXGFC_RRFE_Msk (0x1u << G4_FDCAN1_RXGFC_RRFE_Pos)
#define G4_FDCAN1_RXGFC_RRFS_Pos 1u
#define G4_FDCAN1_RXGFC_RRFS_Msk (0x1u << G4_FDCAN1_RXGFC_RRFS_Pos)
#define G4_FDCAN1_RXGFC_ANFE_Pos 2u
#define G4_FDCAN1_RXGFC_ANFE_Msk (0x3u << G4_FDCAN1_RXGFC_ANFE_Pos)
#define G4_FDCAN1_RXGFC_ANFS_Pos 4u
#define G4_FDCAN1_RXGFC_ANFS_Msk (0x3u << G4_FDCAN1_RXGFC_ANFS_Pos)
#define G4_FDCAN1_RXGFC_LSS_Pos 16u
#define G4_FDCAN1_RXGFC_LSS_Msk (0x1Fu << G4_FDCAN1_RXGFC_LSS_Pos)
#define G4_FDCAN1_RXGFC_LSE_Pos 24u
#define G4_FDCAN1_RXGFC_LSE_Msk (0xFu << G4_FDCAN1_RXGFC_LSE_Pos)
#define G4_FDCAN_ANF_FIFO0 0u          /* ANFS/ANFE: accept non-matching into FIFO 0 */
#define G4_FDCAN_ANF_REJECT 2u         /* ANFS/ANFE: reject non-matching frames */
#define G4_FDCAN1_RXF0S_OFFSET 0x90u
#define G4_FDCAN1_RXF0S_F0FL_Pos 0u
#define G4_FDCAN1_RXF0S_F0FL_Msk (0xFu << G4_FDCAN1_RXF0S_F0FL_Pos)
#define G4_FDCAN1_RXF0S_F0GI_Pos 8u
#define G4_FDCAN1_RXF0S_F0GI_Msk (0x3u << G4_FDCAN1_RXF0S_F0GI_Pos)
#define G4_FDCAN1_RXF0S_RF0L_Pos 25u
#define G4_FDCAN1_RXF0S_RF0L_Msk (0x1u << G4_FDCAN1_RXF0S_RF0L_Pos)
#define G4_FDCAN1_RXF0A_OFFSET 0x94u
#define G4_FDCAN1_RXF0A_F0AI_Pos 0u
#define G4_FDCAN1_RXF0A_F0AI_Msk (0x7u << G4_FDCAN1_RXF0A_F0AI_Pos)
#define G4_FDCAN1_TXBC_OFFSET 0xC0u
#define G4_FDCAN1_TXBC_TFQM_Pos 24u    /* 0: Tx FIFO (frames leave in order) */
#define G4_FDCAN1_TXBC_TFQM_Msk (0x1u << G4_FDCAN1_TXBC_TFQM_Pos)
#define G4_FDCAN1_TXFQS_OFFSET 0xC4u
#define G4_FDCAN1_TXFQS_TFFL_Pos 0u
#define G4_FDCAN1_TXFQS_TFFL_Msk (0x7u << G4_FDCAN1_TXFQS_TFFL_Pos)
#define G4_FDCAN1_TXFQS_TFQPI_Pos 16u
#define G4_FDCAN1_TXFQS_TFQPI_Msk (0x3u << G4_FDCAN1_TXFQS_TFQPI_Pos)
#define G4_FDCAN1_TXFQS_TFQF_Pos 21u
#define G4_FDCAN1_TXFQS_TFQF_Msk (0x1u << G4_FDCAN1_TXFQS_TFQF_Pos)
#define G4_FDCAN1_TXBAR_OFFSET 0xCCu
#define G4_FDCAN1_CKDIV_OFFSET 0x100u
#define G4_FDCAN1_CKDIV_PDIV_Pos 0u
#define G4_FDCAN1_CKDIV_PDIV_Msk (0xFu << G4_FDCAN1_CKDIV_PDIV_Pos)

/* FDCAN message RAM (RM0440 44.3.3, fig. 628): fixed layout per instance,
 * FDCAN1 at the start, 0x350 bytes: 28 standard filters (1 word each), 8
 * extended filters (2 words), Rx FIFO 0 and 1 (3 elements of 18 words), Tx
 * event FIFO (3 x 2 words), Tx buffers (3 x 18 words). Not in the SVD. */
#define G4_MRAM_BASE 0x4000A400u
#define G4_MRAM_SIZE 0x350u
#define G4_MRAM_FLSSA 0x000u           /* standard filters */
#define G4_MRAM_FLESA 0x070u           /* extended filters */
#define G4_MRAM_F0SA 0x0B0u            /* Rx FIFO 0 */
#define G4_MRAM_F1SA 0x188u            /* Rx FIFO 1 */
#define G4_MRAM_EFSA 0x260u            /* Tx event FIFO */
#define G4_MRAM_TBSA 0x278u            /* Tx buffers */
#define G4_MRAM_STD_FILTERS 28u
#define G4_MRAM_ELEMENT_BYTES 72u      /* Rx/Tx element: 2 header words + 64 data bytes */
#define G4_MRAM_RX_FIFO_ELEMENTS 3u
#define G4_MRAM_TX_ELEMENTS 3u
/* standard filter element word S0 */
#define G4_MRAM_SFT_SHIFT 30u          /* filter type: 2 = classic id + mask */
#define G4_MRAM_SFT_CLASSIC 2u
#define G4_MRAM_SFEC_SHIFT 27u         /* element config: 1 = store in Rx FIFO 0 */
#define G4_MRAM_SFEC_FIFO0 1u
#define G4_MRAM_SFID1_SHIFT 16u        /* the id */
#define G4_MRAM_SFID2_SHIFT 0u         /* the mask (classic filter) */
/* Rx/Tx element word 0 (R0/T0) and word 1 (R1/T1) */
#define G4_MRAM_W0_XTD (1u << 30)
#define G4_MRAM_W0_RTR (1u << 29)
#define G4_MRAM_W0_STDID_SHIFT 18u     /* 11-bit id in bits 28:18 */
#define G4_MRAM_W1_DLC_SHIFT 16u       /* 4 bits */
#define G4_MRAM_W1_FDF (1u << 21)

/* ---------------------------------------------------- IWDG (RM0440 41.4) -- */
#define G4_IWDG_BASE 0x40003000u
#define G4_IWDG_KR_OFFSET 0x00u
#define G4_IWDG_KR_KEY_Pos 0u
#define G4_IWDG_KR_KEY_Msk (0xFFFFu << G4_IWDG_KR_KEY_Pos)
#define G4_IWDG_PR_OFFSET 0x04u
#define G4_IWDG_PR_PR_Pos 0u
#define G4_IWDG_PR_PR_Msk (0x7u << G4_IWDG_PR_PR_Pos)
#define G4_IWDG_RLR_OFFSET 0x08u
#define G4_IWDG_RLR_RL_Pos 0u
#define G4_IWDG_RLR_RL_Msk (0xFFFu << G4_IWDG_RLR_RL_Pos)
#define G4_IWDG_SR_OFFSET 0x0Cu
#define G4_IWDG_SR_PVU_Pos 0u
#define G4_IWDG_SR_PVU_Msk (0x1u << G4_IWDG_SR_PVU_Pos)
#define G4_IWDG_SR_RVU_Pos 1u
#define G4_IWDG_SR_RVU_Msk (0x1u << G4_IWDG_SR_RVU_Pos)
#define G4_IWDG_SR_WVU_Pos 2u
#define G4_IWDG_SR_WVU_Msk (0x1u << G4_IWDG_SR_WVU_Pos)
#define G4_IWDG_KEY_START 0xCCCCu
#define G4_IWDG_KEY_ACCESS 0x5555u
#define G4_IWDG_KEY_RELOAD 0xAAAAu
#define G4_IWDG_LSI_HZ 32000u          /* nominal; datasheet: 29.5..34 kHz */

/* ------------------------------------------------ DBGMCU (RM0440 47.15) -- */
#define G4_DBGMCU_BASE 0xE0042000u
#define G4_DBGMCU_APB1L_FZ_OFFSET 0x08u
#define G4_DBGMCU_APB1L_FZ_DBG_IWDG_STOP_Pos 12u
#define G4_DBGMCU_APB1L_FZ_DBG_IWDG_STOP_Msk (0x1u << G4_DBGMCU_APB1L_FZ_DBG_IWDG_STOP_Pos)

/* --------------------------------------------- Cortex-M4 core (PM0214) -- */
#define G4_NVIC_BASE 0xE000E100u
#define G4_NVIC_ISER0_OFFSET 0x000u     /* ISERn at +4n: one bit per IRQ */
#define G4_NVIC_ICER0_OFFSET 0x080u
#define G4_NVIC_ISPR0_OFFSET 0x100u
#define G4_NVIC_IPR0_OFFSET 0x300u      /* one byte per IRQ */
#define G4_FPU_CPACR_BASE 0xE000ED88u
#define G4_FPU_CPACR_CPACR_OFFSET 0x0u
#define G4_FPU_CPACR_CPACR_CP_Pos 20u   /* CP10, CP11: 0xF = full access */
#define G4_FPU_CPACR_CPACR_CP_Msk (0xFu << G4_FPU_CPACR_CPACR_CP_Pos)

/* ----------------------------------------------------------- interrupts -- */
#define G4_IRQ_FLASH 4u
#define G4_IRQ_FDCAN1_IT0 21u
#define G4_IRQ_TIM2 28u
#define G4_IRQ_TIM6_DACUNDER 54u
#define G4_IRQ_COUNT 102u               /* external interrupt lines 0..101 */

#endif /* G4_REGS_H */
