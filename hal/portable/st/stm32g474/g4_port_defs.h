/* SPDX-License-Identifier: Apache-2.0 */
/* What the STM32G474 port needs beyond ST's CMSIS device header
 * (g4_cmsis.h): values that ST keeps in its HAL drivers rather than in
 * stm32g474xx.h, and the FDCAN message RAM layout, which the header gives
 * only a base address for (SRAMCAN_BASE). Written from RM0440 (STM32G4
 * reference manual), each with its section. */
#ifndef G4_PORT_DEFS_H
#define G4_PORT_DEFS_H

#include "g4_cmsis.h"

/* Flash unlock keys (RM0440 3.3.5, FLASH_KEYR) */
#define G4_FLASH_KEY1 0x45670123u
#define G4_FLASH_KEY2 0xCDEF89ABu

/* IWDG keys (RM0440 41.4.1, IWDG_KR) and its clock */
#define G4_IWDG_KEY_START 0xCCCCu
#define G4_IWDG_KEY_ACCESS 0x5555u
#define G4_IWDG_KEY_RELOAD 0xAAAAu
#define G4_IWDG_LSI_HZ 32000u          /* nominal; datasheet DS12288: 29.5..34 kHz */

/* GPIO MODER values (RM0440 9.4.1) and the FDCAN1 alternate function */
#define G4_GPIO_MODE_INPUT 0u
#define G4_GPIO_MODE_OUTPUT 1u
#define G4_GPIO_MODE_AF 2u
#define G4_GPIO_MODE_ANALOG 3u
#define G4_GPIO_AF9_FDCAN1 9u          /* PA11/PA12, PB8/PB9: datasheet DS12288 table 13 */

/* Field values (RM0440): written with _VAL2FLD(<ST field>, value) */
#define G4_RCC_CCIPR_FDCANSEL_PCLK1 2u /* 7.4.26: FDCAN kernel clock = PCLK1 */
#define G4_ADC_CKMODE_HCLK_DIV4 3u     /* 21.7.2 ADC_CCR: 170 / 4 = 42.5 MHz ADC clock */
#define G4_DAC_HFSEL_ABOVE_160MHZ 2u   /* 22.7.16 DAC_MCR: AHB clock above 160 MHz */
#define G4_DAC_MODE_PIN_UNBUFFERED 2u  /* 22.7.16 DAC_MCR MODE1 010: normal, to the pin, buffer off */
#define G4_DAC_MAX_COUNTS 4095u        /* 12-bit, right-aligned */
#define G4_FDCAN_ANF_FIFO0 0u          /* 44.4.22 RXGFC ANFS/ANFE: accept non-matching into FIFO 0 */
#define G4_FDCAN_ANF_REJECT 2u         /*                         reject non-matching frames */

/* The G474's 102 interrupt lines (IRQn_Type 0..FMAC_IRQn) */
#define G4_IRQ_COUNT ((uint32_t)FMAC_IRQn + 1u)

/* FDCAN message RAM (RM0440 44.3.3, fig. 628): a fixed layout per instance,
 * FDCAN1 at the start (SRAMCAN_BASE), 0x350 bytes: 28 standard filters (1
 * word each), 8 extended filters (2 words), Rx FIFO 0 and 1 (3 elements of
 * 18 words), Tx event FIFO (3 x 2 words), Tx buffers (3 x 18 words). The
 * drivers reach it as words (g4_io.mram), at these byte offsets. */
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
/* standard filter element word S0 (44.3.11) */
#define G4_MRAM_SFT_SHIFT 30u          /* filter type: 2 = classic id + mask */
#define G4_MRAM_SFT_CLASSIC 2u
#define G4_MRAM_SFEC_SHIFT 27u         /* element config: 1 = store in Rx FIFO 0 */
#define G4_MRAM_SFEC_FIFO0 1u
#define G4_MRAM_SFID1_SHIFT 16u        /* the id */
#define G4_MRAM_SFID2_SHIFT 0u         /* the mask (classic filter) */
/* Rx/Tx element word 0 (R0/T0) and word 1 (R1/T1), 44.3.8 and 44.3.9 */
#define G4_MRAM_W0_XTD (1u << 30)
#define G4_MRAM_W0_RTR (1u << 29)
#define G4_MRAM_W0_STDID_SHIFT 18u     /* 11-bit id in bits 28:18 */
#define G4_MRAM_W1_DLC_SHIFT 16u       /* 4 bits */
#define G4_MRAM_W1_FDF (1u << 21)

#endif /* G4_PORT_DEFS_H */
