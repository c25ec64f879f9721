/* SPDX-License-Identifier: Apache-2.0 */
/* First-order low-pass, the discrete exponential smoother
 *     y(k) = y(k-1) + k_f (x(k) - y(k-1)),   k_f = 1 - exp(-2 pi fc T),
 * primed by its first sample (y = x: no start transient). Its pole sits where the continuous
 * filter's does (exp(-2 pi fc T)); at a frequency w well below fc it lags by atan(w / (2 pi fc))
 * plus T / 2. The paper's controller's command goes through one (ppc.u_lpf_hz,
 * docs/controllers.md "Option 7"): the sensor's noise, which the law passes on with a
 * first-order roll-off, then reaches the valve with a second-order one.
 *
 * fc = 0 is off: the output is the input. Units: fc in Hz, T in s; x and y in any one unit.
 * The output lies between the previous output and the input, so a filtered command stays
 * inside the range its inputs keep.
 *
 * Fixed point: x, y and k_f in Q16.16 (one 32 x 32 multiply a step, the M0's cheapest). k_f is
 * rounded to 2^-16, at least 1 LSB and below 1 (a k_f that rounds to 1 passes x, as off): the
 * cut-off is exact to 2^-17 / k_f, 0.1 % at 2 Hz and 1 kHz (k_f 0.0125). The step rounds
 * k_f (x - y) to the nearest LSB and saturates x - y, so y stops within 0.5 / k_f LSB of a
 * constant input (2 Hz at 1 kHz: 40 LSB, 0.0006 of the unit). */
#ifndef PMA_LPF_H
#define PMA_LPF_H

#include <math.h>
#include <stdint.h>
#include "pma/fixed.h"

typedef struct pma_lpf_config {
    float fc_hz;           /* cut-off >= 0 [Hz]; 0: off (pass-through) */
    float period_s;        /* sample period T > 0 [s] */
} pma_lpf_config_t;

/* PMA_OK, or PMA_ERR_NULL / PMA_ERR_NOT_FINITE / PMA_ERR_RANGE (fc < 0, T <= 0). */
int pma_lpf_validate_config(const pma_lpf_config_t *cfg);

typedef struct pma_lpf_f32 {
    float k;               /* k_f in (0, 1); 0 when off or not ready (the step passes x) */
    float y;               /* the last output */
    uint8_t primed;        /* 0 until the first sample (which it passes and keeps) */
} pma_lpf_f32_t;

int pma_lpf_init_f32(pma_lpf_f32_t *s, const pma_lpf_config_t *cfg);
/* Forget the history: the next sample primes the filter. */
void pma_lpf_reset_f32(pma_lpf_f32_t *s);
/* The filtered x (x itself when off, not ready, or for the priming sample). A non-finite x
 * passes through and leaves the state unchanged. Inline: it runs every control tick. */
static inline float pma_lpf_step_f32(pma_lpf_f32_t *s, float x)
{
    if (s->k == 0.0f || !isfinite(x)) return x;   /* off or not ready: k 0 */
    if (!s->primed) {
        s->primed = 1;
        s->y = x;
        return x;
    }
    const float y = s->y + s->k * (x - s->y);
    /* between the last output and x, also where the product rounds past x */
    s->y = (x >= s->y) ? fminf(y, x) : fmaxf(y, x);
    return s->y;
}

typedef struct pma_lpf_q16 {
    pma_q16_t k;           /* k_f in Q16.16, 1 ... 2^16 - 1; 0 when off or not ready */
    pma_q16_t y;           /* the last output, Q16.16 */
    uint8_t primed;        /* 0 until the first sample (which it passes and keeps) */
} pma_lpf_q16_t;

int pma_lpf_init_q16(pma_lpf_q16_t *s, const pma_lpf_config_t *cfg);
void pma_lpf_reset_q16(pma_lpf_q16_t *s);
/* The filter's step once on (pma_lpf_step_q16 calls it; not for direct use). */
pma_q16_t pma_lpf_filter_q16(pma_lpf_q16_t *s, pma_q16_t x);

/* As pma_lpf_step_f32, in Q16.16. Inline: off or not ready costs one comparison with 0 (the
 * filter itself is out of line, so that the caller's registers do not pay for it). */
static inline pma_q16_t pma_lpf_step_q16(pma_lpf_q16_t *s, pma_q16_t x)
{
    return s->k == 0 ? x : pma_lpf_filter_q16(s, x);
}

#endif /* PMA_LPF_H */
