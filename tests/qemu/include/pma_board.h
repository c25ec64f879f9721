/* SPDX-License-Identifier: Apache-2.0 */
/*
 * Board support for tests and benchmarks: timing and identification.
 *
 * Implementations:
 *   tests/qemu/board_mps2.c      QEMU mps2-an385 / mps2-an386 (Cortex-M3 / Cortex-M4F):
 *                                CMSDK APB TIMER0 (0x40000000), 32-bit down-counter at 25 MHz,
 *                                resolution 40 ns.
 *   tests/qemu/board_microbit.c  QEMU microbit (nRF51, Cortex-M0): TIMER0 (0x40008000), 32-bit
 *                                timer mode, 16 MHz (prescaler 0), resolution 62.5 ns.
 *   tests/qemu/board_host.c      host: clock_gettime(CLOCK_MONOTONIC), wall-clock ns.
 *
 * On QEMU, time is VIRTUAL time. Benchmarks run under `-icount shift=0` (the run-<bench> targets),
 * where QEMU advances virtual time by exactly 1 ns per executed instruction: elapsed ns ==
 * instructions executed (exact and repeatable, to the timer's resolution). Instructions are not
 * cycles, but they compare code variants fairly. Without -icount (e.g. under ctest) virtual time
 * follows the host clock and the figures mean little.
 *
 * The ARM variants also provide the startup code (tests/qemu/startup.c): main's return value and
 * exit(n) become QEMU's exit status; a fault or unexpected exception prints a report on the
 * semihosting console and exits with PMA_BOARD_FAULT_EXIT_STATUS.
 */
#ifndef PMA_BOARD_H
#define PMA_BOARD_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Exit status of a program stopped by a fault (HardFault etc.) or by a stack overflow. */
#define PMA_BOARD_FAULT_EXIT_STATUS 125

/** (Re)start the interval timer. */
void pma_board_timer_start(void);

/**
 * Nanoseconds since the last pma_board_timer_start() (virtual ns on QEMU: instructions under
 * -icount shift=0). Wraps after 2^32 ns (about 4.29 s): time at most a few hundred million
 * instructions per interval.
 */
uint32_t pma_board_timer_elapsed_ns(void);

/** Resolution of pma_board_timer_elapsed_ns() in ns, rounded up (40, 63, or 1 on host). */
uint32_t pma_board_timer_resolution_ns(void);

/** "cortex-m4f/mps2-an386", "cortex-m3/mps2-an385", "cortex-m0/microbit" or "host". */
const char *pma_board_name(void);

/** Unit of pma_board_timer_elapsed_ns() for printing: "instructions" on QEMU
 *  (valid under -icount shift=0, as run by the run-* targets), "ns" on host. */
const char *pma_board_time_unit(void);

#ifdef __cplusplus
}
#endif

#endif /* PMA_BOARD_H */
