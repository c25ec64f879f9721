/* SPDX-License-Identifier: Apache-2.0 */
/* Compact-form dynamic-linearisation model-free adaptive control (CFDL-MFAC,
 * Hou and Jin), the paper's baseline. At sample k, output y(k) = x(k), input
 * u(k), reference y*(k+1) for the next sample:
 *   phi(k) = phi(k-1) + eta du(k-1) / (mu + du(k-1)^2) (dy(k) - phi(k-1) du(k-1))
 *   reset:  phi(k) = phi(1) if |phi(k)| <= eps or |du(k-1)| <= eps
 *                             or sign(phi(k)) != sign(phi(1))
 *   u(k)   = u(k-1) + rho phi(k) / (lambda + phi(k)^2) (y*(k+1) - y(k))
 * with du(k-1) = u(k-1) - u(k-2), dy(k) = y(k) - y(k-1).
 * Start: u(-1) = u(-2) = u_init and y(-1) = y(0), so the first step has
 * du = 0 and resets phi to phi(1) (as the rule demands).
 * Input limits: u(k) is clamped to [u_min, u_max] and the clamped value is
 * what enters du at the next step (the input actually applied).
 * Units: y in cm, u in the input unit; phi in cm per input unit; eta, rho
 * dimensionless; mu in input unit^2; lambda in (cm/input unit)^2; eps applies
 * to |phi| and |du| in their own units. */
#ifndef PMA_MFAC_H
#define PMA_MFAC_H

#include <stdint.h>
#include "pma/fixed.h"

typedef struct pma_mfac_config {
    float eta;      /* step size of the PPD estimate, 0 < eta <= 2 */
    float mu;       /* > 0 */
    float rho;      /* > 0 (the paper's 31.7 goes with its signal scaling) */
    float lambda;   /* > 0 */
    float eps;      /* reset threshold >= 0 (about 1e-5) */
    float phi1;     /* initial pseudo-partial derivative phi(1), |phi1| > eps */
    float u_min;    /* input limits, u_min < u_max */
    float u_max;
    float u_init;   /* u(-1) = u(-2), within the limits */
} pma_mfac_config_t;

/* Defaults: the paper's Case 3 (eta 0.5, mu 1.9, rho 31.7, lambda 0.03),
 * eps 1e-5, phi1 0.5, u in [-400, 400], u_init 0. */
void pma_mfac_default_config(pma_mfac_config_t *cfg);
int pma_mfac_validate_config(const pma_mfac_config_t *cfg);

#define PMA_MFAC_FLAG_RESET    0x01u   /* phi reset to phi(1) this step */
#define PMA_MFAC_FLAG_SAT_HIGH 0x04u
#define PMA_MFAC_FLAG_SAT_LOW  0x08u

typedef struct pma_mfac_f32 {
    pma_mfac_config_t cfg;
    float phi, u1, u2, y1;   /* phi(k-1), u(k-1), u(k-2), y(k-1) */
    uint32_t k, resets;
    uint32_t flags;          /* PMA_MFAC_FLAG_* of the last step */
    uint8_t ready;
} pma_mfac_f32_t;

int pma_mfac_init_f32(pma_mfac_f32_t *s, const pma_mfac_config_t *cfg);
void pma_mfac_reset_f32(pma_mfac_f32_t *s);
/* y_cm: y(k); yref_next_cm: y*(k+1). Writes u(k). Non-finite input:
 * PMA_ERR_NOT_FINITE, state unchanged. */
int pma_mfac_step_f32(pma_mfac_f32_t *s, float y_cm, float yref_next_cm, float *u);
/* MFAC takes charge from another controller (the paper's controller's fallback, at the
 * hand-over): u_start, clamped to [u_min, u_max], becomes u(k-1) and u(k-2), so that the next
 * step's law starts from it and its estimator, having seen no change of input, from phi(1) (the
 * reset rule's du = 0): the MFAC that starts on its own, from u_start instead of u_init.
 * (Not a phi learned beside the other controller: its input answered the output, which biases
 * such an estimate.) Non-finite u_start: PMA_ERR_NOT_FINITE, state unchanged. */
int pma_mfac_take_over_f32(pma_mfac_f32_t *s, float u_start);

/* Fixed point: y and u in Q16.16; phi in Q8.24 (|phi| < 128: a pseudo partial derivative
 * in cm per input unit is small, 0.01 cm/kPa on a muscle, and Q16.16 would hold it to 3 or 4
 * significant digits and lose its small updates); products and quotients in 64-bit
 * intermediates so du^2 (up to 2^30) never saturates mid-computation. */
typedef struct pma_mfac_q16 {
    pma_q16_t eta, mu, rho, lambda, eps, u_min, u_max, u_init;
    int32_t eps_q24, phi1_q24;   /* eps and phi(1) in Q8.24 */
    int32_t phi_q24;             /* phi(k-1), Q8.24 */
    pma_q16_t u1, u2, y1;
    uint32_t k, resets, flags;
    uint8_t ready;
} pma_mfac_q16_t;

int pma_mfac_init_q16(pma_mfac_q16_t *s, const pma_mfac_config_t *cfg);
void pma_mfac_reset_q16(pma_mfac_q16_t *s);
int pma_mfac_step_q16(pma_mfac_q16_t *s, pma_q16_t y_cm, pma_q16_t yref_next_cm, pma_q16_t *u);
int pma_mfac_take_over_q16(pma_mfac_q16_t *s, pma_q16_t u_start);                  /* as _f32 */

#endif /* PMA_MFAC_H */
