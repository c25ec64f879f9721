/* SPDX-License-Identifier: Apache-2.0 */
/* The fixed-point stages at the two ends of a tick, for the Q16.16 builds
 * (PMA_CTRL_Q16: cores without an FPU, where the float functions they stand for
 * cost about 300 (input) and 1,300 (output) instructions a tick in software
 * float). The float functions stay the definition: each stage is built from
 * the same configuration and tested against them (tests/app/test_app_scaling.c).
 *
 * Input: the sensor's counts to cm (pma_adc_counts_to_cm) in integers:
 *   x       Q16.16 cm, offset_cm + gain_cm_per_count counts with the offset
 *           and the product each rounded to Q16.16 (within one LSB, 2^-16 cm,
 *           of the float function's value); the factor (the gain in Q16.16 cm
 *           per count) a 30-bit mantissa and a shift (relative rounding below
 *           2^-29);
 *   the wire-break and range checks on the counts, as the float function.
 * pma_input_q16_build() refuses (PMA_ERR_FIXED_RANGE) a scaling whose valid
 * counts reach beyond Q16.16 (|x| >= 32767 cm at raw_min or raw_max); it
 * returns the scaling's validation code as it is.
 *
 * Output: the actuator's law and the DAC scaling of a tick
 * (pma_actuator_active_kpa, then pma_dac_kpa_to_counts), formats:
 *   u       Q16.16 in the controller's unit (the slot's range, |u| < 32768);
 *   p       Q16.16 kPa (the actuator's range is 0..1000 kPa: rounding 2^-17 kPa);
 *   counts  the DAC code, computed in Q16.16 counts in 64 bits, then rounded
 *           half up and saturated to [min_counts, max_counts] as the float
 *           function does.
 * The factors act.polarity * act.kpa_per_u (1e-6..1e4 kPa per unit) and
 * dac.counts_per_kpa (|.| <= 1000) are a 30-bit mantissa and a shift (relative
 * rounding below 2^-29). Every sum saturates; a pressure beyond Q16.16 before
 * the actuator's limits is saturated, and the limits then apply as in float.
 *
 * pma_output_q16_build() refuses (PMA_ERR_FIXED_RANGE) what this stage cannot
 * represent: a slew step per tick below half an LSB (slower than 2^-17 kPa per
 * tick) or any value outside Q16.16; the application then keeps the float
 * functions for that configuration. It returns the configurations'
 * validation codes as they are. */
#ifndef PMA_IO_Q16_H
#define PMA_IO_Q16_H

#include <stdint.h>
#include <string.h>

#include "actuator.h"
#include "pma/fixed.h"
#include "pma/status.h"
#include "scaling.h"

typedef struct pma_scale_q {   /* x m 2^-s */
    int32_t m;                 /* |m| < 2^30 */
    uint8_t s;                 /* 1..62 */
} pma_scale_q_t;

/* x m 2^-s rounded (ties away from zero); |x| < 2^31 */
static inline int64_t pma_scale_q_apply(pma_scale_q_t sc, int32_t x)
{
#if defined(__ARM_ARCH_6M__)
    if (sc.s < 32u) {
        /* the usual shifts (a factor of 2^-1 .. 2^30): the magnitudes' product rounded and
         * shifted word by word, no 64-bit shift or negation of the product on the way (Thumb-1
         * has neither); the same value as the general form below */
        const uint32_t um = sc.m < 0 ? 0u - (uint32_t)sc.m : (uint32_t)sc.m;
        const uint32_t ux = x < 0 ? 0u - (uint32_t)x : (uint32_t)x;
        uint32_t hi;   /* < 2^30: |m| < 2^30, |x| <= 2^31 */
        const uint32_t lo = pma_umul32_v6m(um, ux, &hi);
        const uint32_t lo_r = lo + ((uint32_t)1 << (sc.s - 1u));
        hi += lo_r < lo;   /* the rounding's carry */
        const uint64_t r = ((uint64_t)(hi >> sc.s) << 32) | (hi << (32u - sc.s)) | (lo_r >> sc.s);
        return ((sc.m < 0) != (x < 0)) ? -(int64_t)r : (int64_t)r;
    }
#endif
    return pma_rshift_round(pma_mul32(sc.m, x), sc.s);
}

typedef struct pma_input_q16 {
    int64_t x0;                   /* offset_cm, Q16.16 in 64 bits */
    pma_scale_q_t k;              /* counts -> cm: gain_cm_per_count 2^16 */
    uint16_t wire_break_below_counts, raw_min_counts, raw_max_counts;
} pma_input_q16_t;

int pma_input_q16_build(pma_input_q16_t *in, const pma_adc_scaling_t *s);

/* pma_adc_counts_to_cm in Q16.16: the same status codes (*x_cm unchanged on an error). */
static inline int pma_input_q16_cm(const pma_input_q16_t *in, uint16_t raw_counts, pma_q16_t *x_cm)
{
    if (raw_counts < in->wire_break_below_counts) return PMA_ERR_WIRE_BREAK;
    if (raw_counts < in->raw_min_counts || raw_counts > in->raw_max_counts) return PMA_ERR_RANGE;
    *x_cm = (pma_q16_t)(in->x0 + pma_scale_q_apply(in->k, raw_counts));   /* checked at build */
    return PMA_OK;
}

typedef struct pma_output_q16 {
    pma_q16_t p0, p_min, p_max;   /* kPa */
    pma_q16_t step;               /* slew limit per tick [kPa]; 0: none */
    pma_scale_q_t k;              /* u -> p - p0: polarity * kpa_per_u */
    int64_t c0;                   /* counts at 0 kPa, Q16.16 */
    pma_scale_q_t cpk;            /* p -> counts - c0: counts_per_kpa */
    uint16_t min_counts, max_counts;
} pma_output_q16_t;

int pma_output_q16_build(pma_output_q16_t *o, const pma_actuator_config_t *ac,
                         const pma_dac_scaling_t *ds, float period_s);

/* Whether v is a value this stage takes as u or p: finite, |v| < 2^15 (from
 * its bits: no float operation). */
static inline int pma_output_q16_takes(float v)
{
    uint32_t b;
    memcpy(&b, &v, sizeof b);
    return ((b >> 23) & 0xFFu) < 127u + 15u;
}

/* pma_actuator_active_kpa for finite u and p_prev: p0 + k u, limited to
 * [p_min, p_max], then to p_prev +- step. */
pma_q16_t pma_output_q16_kpa(const pma_output_q16_t *o, pma_q16_t u, pma_q16_t p_prev_kpa);

/* pma_dac_kpa_to_counts of p. */
uint16_t pma_output_q16_counts(const pma_output_q16_t *o, pma_q16_t p_kpa);

#endif /* PMA_IO_Q16_H */
