/* SPDX-License-Identifier: Apache-2.0 */
/*
 * Smoke benchmark: times a known loop and prints the cost per iteration.
 * Under `cmake --build --preset <arm> --target bench` QEMU runs with -icount shift=0, so the
 * figure is instructions per iteration (exact and repeatable); on host it is wall-clock ns.
 * Benchmarks print figures and never assert.
 */
#include <stdint.h>
#include <stdio.h>

#include "pma_board.h"

#define ITERATIONS 200000u

/* A multiply-add recurrence the compiler cannot turn into a closed form; the empty asm keeps
 * the accumulator in a register each iteration so the loop body stays as written. */
__attribute__((noinline)) static uint32_t known_loop(uint32_t n)
{
    uint32_t acc = 1u;
    for (uint32_t i = 0; i < n; i++) {
        acc = acc * 31u + i;
        __asm__ volatile("" : "+r"(acc));
    }
    return acc;
}

static uint32_t time_loop(uint32_t n, uint32_t *result)
{
    pma_board_timer_start();
    *result = known_loop(n);
    return pma_board_timer_elapsed_ns();
}

int main(void)
{
    uint32_t r0 = 0;
    uint32_t r1 = 0;
    uint32_t overhead = time_loop(0u, &r0); /* call + timer access, measured */
    uint32_t total = time_loop(ITERATIONS, &r1);
    double per_iteration = (double)(total - overhead) / (double)ITERATIONS;

    printf("bench_smoke [%s]: known_loop: %.2f %s/iteration "
           "(%lu iterations, %lu %s total, overhead %lu, timer resolution %lu, result 0x%08lx)\n",
           pma_board_name(), per_iteration, pma_board_time_unit(), (unsigned long)ITERATIONS,
           (unsigned long)total, pma_board_time_unit(), (unsigned long)overhead,
           (unsigned long)pma_board_timer_resolution_ns(), (unsigned long)(r0 ^ r1));
    return 0;
}
