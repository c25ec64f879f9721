/* SPDX-License-Identifier: Apache-2.0 */
/* Host implementation of pma_board.h: wall-clock time from CLOCK_MONOTONIC. */
#define _POSIX_C_SOURCE 199309L

#include "pma_board.h"

#include <time.h>

#ifndef PMA_BOARD_NAME
#define PMA_BOARD_NAME "host"
#endif

static struct timespec pma_start;

void pma_board_timer_start(void)
{
    clock_gettime(CLOCK_MONOTONIC, &pma_start);
}

uint32_t pma_board_timer_elapsed_ns(void)
{
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    int64_t ns = (int64_t)(now.tv_sec - pma_start.tv_sec) * 1000000000 +
                 (int64_t)(now.tv_nsec - pma_start.tv_nsec);
    return (uint32_t)ns;
}

uint32_t pma_board_timer_resolution_ns(void)
{
    return 1u;
}

const char *pma_board_name(void)
{
    return PMA_BOARD_NAME;
}

const char *pma_board_time_unit(void)
{
    return "ns";
}
