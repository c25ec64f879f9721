/* SPDX-License-Identifier: Apache-2.0 */
/* Reference generators x_r(t) and the constraint band k_low < x < k_high.
 *
 *   HOLD   x_r = offset
 *   STEP   x_r = offset for t < t0, offset + amplitude afterwards
 *   RAMP   x_r = offset + rate (t - t0) for t >= t0 (offset before), limited
 *          to [offset - |amplitude|, offset + |amplitude|]
 *   SINE   x_r = offset + amplitude sin(2 pi f t + phase)
 *   CASE1  x_r = -0.5 sin(t) - 2                     (the paper's Cases 1, 2)
 *   CASE3  x_r = t sin(2 pi t (1 + t/55)/55 - pi/2)/360 - 2   (the paper's Case 3 chirp)
 *   STREAM x_r = the last value given by pma_ref_stream_*, moved towards it at
 *          most rate [cm/s] per second (rate 0: jump); starts at offset.
 * Units: x_r, offset, amplitude in cm; t, t0 in s; f in Hz; phase in rad;
 * rate in cm/s. The derivative x_r' [cm/s] is returned too (0 at steps).
 * Every generator stays within [min, max] given by pma_ref_bounds over
 * [0, t_end]; this is how a reference is checked against the band, whose
 * edges are generators too. */
#ifndef PMA_REF_H
#define PMA_REF_H

#include <stdint.h>
#include "pma/fixed.h"

typedef enum pma_ref_kind {
    PMA_REF_HOLD = 0,
    PMA_REF_STEP = 1,
    PMA_REF_RAMP = 2,
    PMA_REF_SINE = 3,
    PMA_REF_CASE1 = 4,
    PMA_REF_CASE3 = 5,
    PMA_REF_STREAM = 6,
} pma_ref_kind_t;

typedef struct pma_ref_config {
    uint8_t kind;          /* pma_ref_kind_t */
    float offset_cm;
    float amplitude_cm;
    float freq_hz;         /* SINE: >= 0 */
    float phase_rad;       /* SINE */
    float t0_s;            /* STEP, RAMP: >= 0 */
    float rate_cm_s;       /* RAMP: any sign; STREAM: >= 0 (0 = no limit) */
} pma_ref_config_t;

int pma_ref_validate_config(const pma_ref_config_t *cfg);

/* Bounds of x_r over t in [0, t_end_s]: exact for HOLD, STEP and RAMP;
 * conservative (the full amplitude or the envelope, whatever t_end) for
 * SINE, CASE1 and CASE3. STREAM reports [offset, offset] (streamed values
 * are checked one by one). */
int pma_ref_bounds(const pma_ref_config_t *cfg, float t_end_s, float *min_cm, float *max_cm);

/* Evaluate a non-STREAM reference at t_s >= 0 without an instance (pure).
 * STREAM: PMA_ERR_UNSUPPORTED. xr_dot_cm_s may be NULL. */
int pma_ref_value_f32(const pma_ref_config_t *cfg, float t_s, float *xr_cm, float *xr_dot_cm_s);

/* Output constraint band k_low(t) < x < k_high(t) (the paper's eq. 9): each
 * edge is a reference generator of any kind but STREAM, so constant, step,
 * ramp and sinusoidal bands are all expressed the same way. */
typedef struct pma_band {
    pma_ref_config_t low, high;
} pma_band_t;

/* A constant band k_low < x < k_high (HOLD edges). */
pma_band_t pma_band_constant(float k_low_cm, float k_high_cm);
/* Valid edges (not STREAM) and k_low(t) < k_high(t) on all of [0, t_end],
 * checked conservatively: max k_low < min k_high (from pma_ref_bounds).
 * PMA_OK or a negative code (PMA_ERR_BAND when the edges may cross). */
int pma_band_validate(const pma_band_t *band, float t_end_s);
/* 1 when k_low(t) < x < k_high(t), else 0 (NaN, invalid band or t: 0). */
int pma_band_contains(const pma_band_t *band, float t_s, float x_cm);
/* PMA_OK when k_low(t) < x_r(t) - margin and x_r(t) + margin < k_high(t)
 * for all t in [0, t_end] (eq. 14 with margin = w1), checked conservatively
 * from the bounds of the three generators: max k_low < min x_r - margin and
 * max x_r + margin < min k_high. Else PMA_ERR_BAND. */
int pma_band_check_ref(const pma_band_t *band, const pma_ref_config_t *cfg, float t_end_s,
                       float margin_cm);

typedef struct pma_ref_f32 {
    pma_ref_config_t cfg;
    float stream_target, stream_value, last_t;
    uint8_t ready;
} pma_ref_f32_t;

int pma_ref_init_f32(pma_ref_f32_t *s, const pma_ref_config_t *cfg);
void pma_ref_reset_f32(pma_ref_f32_t *s);
/* Evaluate at t_s >= 0. xr_dot_cm_s may be NULL. */
int pma_ref_eval_f32(pma_ref_f32_t *s, float t_s, float *xr_cm, float *xr_dot_cm_s);
/* STREAM: set a new target (finite, else PMA_ERR_NOT_FINITE; other kinds:
 * PMA_ERR_UNSUPPORTED). */
int pma_ref_stream_f32(pma_ref_f32_t *s, float target_cm);

/* Fixed point: positions Q16.16 cm, time Q16.16 s (up to 9.1 h). Sines use
 * phase in turns so long runs keep their precision. */
typedef struct pma_ref_q16 {
    uint8_t kind;
    pma_q16_t offset, amplitude, t0, rate;
    int32_t freq_q24;          /* Hz, Q8.24 (f < 127 Hz) */
    pma_q16_t omega;           /* 2 pi f [rad/s] */
    uint32_t phase_frac32;     /* phase as a fraction of a turn, Q0.32 */
    pma_q16_t stream_target, stream_value, last_t;
    uint8_t ready;
} pma_ref_q16_t;

int pma_ref_init_q16(pma_ref_q16_t *s, const pma_ref_config_t *cfg);
void pma_ref_reset_q16(pma_ref_q16_t *s);
int pma_ref_eval_q16(pma_ref_q16_t *s, pma_q16_t t_s, pma_q16_t *xr_cm, pma_q16_t *xr_dot_cm_s);
int pma_ref_stream_q16(pma_ref_q16_t *s, pma_q16_t target_cm);

#endif /* PMA_REF_H */
