/* SPDX-License-Identifier: Apache-2.0 */
/* PID baseline: parallel form on the error e = r - y (note: the opposite sign
 * of the paper's e = x - x_r, so positive gains suit a positive plant gain),
 * derivative on the measurement (no kick on reference steps) through a
 * first-order filter, integrator with back-calculation anti-windup, output
 * limits. Discretisation at the fixed period T (backward Euler):
 *   P(k) = kp e(k)
 *   D(k) = tf/(tf+T) D(k-1) - kd/(tf+T) (y(k) - y(k-1))
 *   v(k) = P(k) + I(k) + D(k);  u(k) = clamp(v(k), u_min, u_max)
 *   I(k+1) = I(k) + T (ki e(k) + k_aw (u(k) - v(k)))   (then clamped to the limits)
 * Units: y, r in cm; kp [input/cm], ki [input/(cm s)], kd [input s/cm],
 * tf [s] (tf = 0: unfiltered difference), k_aw [1/s], T [s]. */
#ifndef PMA_PID_H
#define PMA_PID_H

#include <stdint.h>
#include "pma/fixed.h"

typedef struct pma_pid_config {
    float kp, ki, kd;      /* >= 0, finite */
    float tf_s;            /* derivative filter time constant >= 0 */
    float k_aw_per_s;      /* back-calculation gain >= 0 (0: integrator clamp only) */
    float period_s;        /* > 0 */
    float u_min, u_max;    /* u_min < u_max */
} pma_pid_config_t;

void pma_pid_default_config(pma_pid_config_t *cfg);
int pma_pid_validate_config(const pma_pid_config_t *cfg);

#define PMA_PID_FLAG_SAT_HIGH 0x04u
#define PMA_PID_FLAG_SAT_LOW  0x08u

typedef struct pma_pid_f32 {
    pma_pid_config_t cfg;
    float d_a, d_b;              /* tf/(tf+T), kd/(tf+T) */
    float i, d, y1, p;           /* integrator, derivative, y(k-1), last P term */
    uint32_t flags;
    uint8_t ready, primed;       /* primed: y1 holds a sample */
} pma_pid_f32_t;

int pma_pid_init_f32(pma_pid_f32_t *s, const pma_pid_config_t *cfg);
void pma_pid_reset_f32(pma_pid_f32_t *s);
int pma_pid_step_f32(pma_pid_f32_t *s, float r_cm, float y_cm, float *u);

typedef struct pma_pid_q16 {
    pma_q16_t kp, u_min, u_max;
    pma_q30_t d_a;               /* tf/(tf+T) in [0,1] */
    pma_q16_t d_b;               /* kd/(tf+T) */
    int32_t ki_t;                /* ki T in Q8.24 (ki T < 128) */
    int32_t kaw_t;               /* k_aw T in Q8.24 (k_aw T < 128) */
    int64_t i_q32;               /* integrator, 32 fractional bits: small increments are kept */
    pma_q16_t d, y1, p;
    uint32_t flags;
    uint8_t ready, primed;
} pma_pid_q16_t;

int pma_pid_init_q16(pma_pid_q16_t *s, const pma_pid_config_t *cfg);
void pma_pid_reset_q16(pma_pid_q16_t *s);
int pma_pid_step_q16(pma_pid_q16_t *s, pma_q16_t r_cm, pma_q16_t y_cm, pma_q16_t *u);

#endif /* PMA_PID_H */
