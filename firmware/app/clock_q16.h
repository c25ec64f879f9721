/* SPDX-License-Identifier: Apache-2.0 */
/* The control time of the Q16.16 builds: k / hz seconds after START in Q16.16, counted in
 * integers (no division and no float in a tick, where the float build computes
 * (float)k * (1.0f / hz), about 150 instructions of software float on a Cortex-M0).
 *
 * Invariant: t hz + rem = k 2^16 + floor(hz / 2) with 0 <= rem < hz, so t is k / hz s
 * rounded half up to Q16.16: exact (the float build's time carries single-precision
 * rounding, e.g. up to 4 us at 100 s, where an LSB here is 15 us). t saturates at
 * PMA_Q16_MAX (32768 s), beyond the controller slot's end of time (PMA_CTRL_Q16_T_END). */
#ifndef PMA_CLOCK_Q16_H
#define PMA_CLOCK_Q16_H

#include <stdint.h>

#include "pma/fixed.h"

typedef struct pma_clock_q16 {
    pma_q16_t t_s;                /* the control time [s], Q16.16 */
    uint32_t rem, hz, inc_q, inc_r;   /* the remainder above; 2^16 / hz as quotient, remainder */
} pma_clock_q16_t;

/* k = 0 at tick rate hz [Hz] (1..65536) */
static inline void pma_clock_q16_start(pma_clock_q16_t *c, uint32_t hz)
{
    c->t_s = 0;
    c->hz = hz;
    c->rem = hz / 2u;
    c->inc_q = 65536u / hz;
    c->inc_r = 65536u % hz;
}

/* k + 1 */
static inline void pma_clock_q16_advance(pma_clock_q16_t *c)
{
    if (c->t_s > PMA_Q16_MAX - (pma_q16_t)c->inc_q - 1) {
        c->t_s = PMA_Q16_MAX;
        return;
    }
    c->t_s += (pma_q16_t)c->inc_q;
    c->rem += c->inc_r;
    if (c->rem >= c->hz) {
        c->rem -= c->hz;
        ++c->t_s;
    }
}

#endif /* PMA_CLOCK_Q16_H */
