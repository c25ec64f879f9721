/* SPDX-License-Identifier: Apache-2.0 */
/* The vendor headers of the STM32G474 port, fetched (never copied into the
 * repository) by tools/fetch-deps.sh into .deps/ and found through the
 * include directories cmake/PmaDeps.cmake checks:
 *   stm32g4xx.h, stm32g474xx.h  ST cmsis_device_g4 v1.2.4 (Apache-2.0): the
 *                               register structs (RCC_TypeDef, FDCAN_GlobalTypeDef
 *                               ...), base addresses, bit definitions (X_Pos,
 *                               X_Msk), IRQn_Type, SET_BIT/MODIFY_REG ...
 *   core_cm4.h                  Arm CMSIS_6 v6.3.0 (Apache-2.0), included by
 *                               ST's header: NVIC_Type, SCB, _VAL2FLD/_FLD2VAL,
 *                               and on the board __WFI, __disable_irq ...
 * The device is selected by STM32G474xx (hal/CMakeLists.txt). What these
 * headers do not define is in g4_port_defs.h. */
#ifndef G4_CMSIS_H
#define G4_CMSIS_H

#if !defined(__arm__)
/* Host build (tests/board/test_g4_drivers.c against a RAM register file).
 * core_cm4.h includes cmsis_compiler.h -> cmsis_gcc.h, which includes
 * <arm_acle.h> and so does not compile for x86. The host needs only the
 * types, addresses and bit definitions, never a CMSIS function (the one
 * file with CPU instructions, g4_cpu.c, is board-only), so cmsis_compiler.h
 * is marked as included and the few macros that core_cm4.h's declarations
 * use are defined here instead, with no instruction behind them. */
#define __CMSIS_COMPILER_H
#define __ASM __asm__
#define __INLINE inline
#define __STATIC_INLINE static inline
#define __STATIC_FORCEINLINE static inline
#define __NO_RETURN __attribute__((__noreturn__))
#define __RESTRICT __restrict
#define __COMPILER_BARRIER() __asm__ volatile("" ::: "memory")
#define __DSB() __COMPILER_BARRIER()
#define __ISB() __COMPILER_BARRIER()
#define __DMB() __COMPILER_BARRIER()
#define __NOP() ((void)0)
#endif

#include "stm32g4xx.h"

#endif /* G4_CMSIS_H */
