/* SPDX-License-Identifier: Apache-2.0 */
/* Velocity estimation from sampled positions (the paper's controller needs
 * x', which no sensor on the rig measures). Two estimators:
 *
 * PMA_VELEST_FILTERED_DIFF: backward difference through a first-order
 *   low-pass with cut-off fc:  v(k) = p v(k-1) + (1-p)/T (x(k) - x(k-1)),
 *   p = exp(-2 pi fc T). Lags a ramp by 1/(2 pi fc) s. White position noise
 *   of std sigma gives velocity noise of std
 *   sigma (1-p)/T sqrt(2/(1+p))          (exact, for this recursion).
 *
 * PMA_VELEST_TRACKING: a second-order tracking differentiator (critically
 *   damped alpha-beta observer) with both poles at p = exp(-2 pi fc T):
 *     predict  xp = xh + T vh;   residual r = x(k) - xp
 *     update   xh = xp + ga r;   vh = vh + (gb/T) r
 *   with ga = 1 - p^2, gb = (1 - p)^2; fc sets the bandwidth. Both
 *   estimators recover a ramp's slope exactly in steady state; under constant
 *   acceleration the filtered difference lags by T (1+p)/(2(1-p)) ~ 1/(2 pi fc)
 *   and this observer by T (1/2 + 2p/(1-p)) ~ 1/(pi fc). Its second-order
 *   roll-off gives a
 *   lower noise gain than the filtered difference at the same fc (at 30 Hz,
 *   1 kHz: 41 vs 180 (cm/s) per cm of position noise std; see
 *   docs/controllers.md and tests/unit/test_velest.c).
 *
 * Units: x in cm, v in cm/s, fc in Hz, T in s. Requires 0 < fc < 1/(2T).
 * Fixed point also requires T < 2 s and (1-p)/T or gb/T below 32767 1/s
 * (else PMA_ERR_FIXED_RANGE; only periods below ~30 us reach that). */
#ifndef PMA_VELEST_H
#define PMA_VELEST_H

#include <stdint.h>
#include "pma/fixed.h"

typedef enum pma_velest_kind {
    PMA_VELEST_FILTERED_DIFF = 0,
    PMA_VELEST_TRACKING = 1,
} pma_velest_kind_t;

typedef struct pma_velest_config {
    uint8_t kind;          /* pma_velest_kind_t */
    float fc_hz;           /* bandwidth, 0 < fc < 1/(2 period) */
    float period_s;        /* > 0 */
} pma_velest_config_t;

/* Defaults: filtered difference, fc = 30 Hz, T = 1 ms. */
void pma_velest_default_config(pma_velest_config_t *cfg);
int pma_velest_validate_config(const pma_velest_config_t *cfg);
/* Standard deviation of the velocity estimate per unit std of white position
 * noise [1/s] (steady state, exact for the discrete recursion). */
float pma_velest_noise_gain(const pma_velest_config_t *cfg);

typedef struct pma_velest_f32 {
    pma_velest_config_t cfg;
    float c1, c2;          /* diff: p, (1-p)/T;  tracking: ga, gb/T */
    float x1, xh, v;       /* last x, position estimate, velocity estimate */
    uint8_t ready, primed;
} pma_velest_f32_t;

int pma_velest_init_f32(pma_velest_f32_t *s, const pma_velest_config_t *cfg);
/* Forget history: the next sample primes the estimator (v = 0). */
void pma_velest_reset_f32(pma_velest_f32_t *s);
/* Returns PMA_OK and writes v [cm/s]; non-finite x: PMA_ERR_NOT_FINITE, state unchanged. */
int pma_velest_step_f32(pma_velest_f32_t *s, float x_cm, float *v_cm_s);

typedef struct pma_velest_q16 {
    uint8_t kind;
    pma_q30_t c1;          /* p or ga, Q2.30 */
    pma_q16_t c2;          /* (1-p)/T or gb/T, Q16.16 [1/s] */
    pma_q30_t ct;          /* T in Q2.30 [s] (tracking predict step) */
    pma_q16_t x1, v;
    int64_t xh_q32;        /* tracking position estimate, 32 fractional bits */
    uint8_t ready, primed;
} pma_velest_q16_t;

int pma_velest_init_q16(pma_velest_q16_t *s, const pma_velest_config_t *cfg);
void pma_velest_reset_q16(pma_velest_q16_t *s);
int pma_velest_step_q16(pma_velest_q16_t *s, pma_q16_t x_cm, pma_q16_t *v_cm_s);

#endif /* PMA_VELEST_H */
