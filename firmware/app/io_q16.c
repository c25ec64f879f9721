/* SPDX-License-Identifier: Apache-2.0 */
/* The fixed-point input and output stages (io_q16.h). */
#include "io_q16.h"

#include <math.h>
#include <stddef.h>

#include "pma/status.h"

/* r as m 2^-s with |m| in [2^29, 2^30) (r != 0); PMA_ERR_FIXED_RANGE when r is
 * too large or too small for a shift of 1..62 */
static int to_scale(float r, pma_scale_q_t *sc)
{
    if (r == 0.0f) {
        sc->m = 0;
        sc->s = 1;
        return PMA_OK;
    }
    int e = 0;
    const float f = frexpf(r, &e);              /* r = f 2^e, 0.5 <= |f| < 1 */
    const int s = 30 - e;
    if (s < 1 || s > 62) return PMA_ERR_FIXED_RANGE;
    sc->m = (int32_t)lroundf(ldexpf(f, 30));    /* |m| <= 2^30 */
    sc->s = (uint8_t)s;
    return PMA_OK;
}

static int q16_of(float v, pma_q16_t *q)
{
    if (!(v > -32767.0f && v < 32767.0f)) return PMA_ERR_FIXED_RANGE;
    *q = pma_q16_from_f32(v);
    return PMA_OK;
}

int pma_input_q16_build(pma_input_q16_t *in, const pma_adc_scaling_t *s)
{
    if (in == NULL) return PMA_ERR_NULL;
    const int rc = pma_adc_validate_scaling(s);
    if (rc != PMA_OK) return rc;
    /* the valid counts' positions (an affine map: its ends) must fit Q16.16, with the
     * offset's and the product's rounding */
    const float ends[] = {s->offset_cm + s->gain_cm_per_count * (float)s->raw_min_counts,
                          s->offset_cm + s->gain_cm_per_count * (float)s->raw_max_counts, s->offset_cm};
    for (unsigned i = 0; i < sizeof ends / sizeof ends[0]; ++i) {
        if (!(fabsf(ends[i]) < 32767.0f)) return PMA_ERR_FIXED_RANGE;
    }
    pma_input_q16_t n;
    if (to_scale(ldexpf(s->gain_cm_per_count, 16), &n.k) != PMA_OK) return PMA_ERR_FIXED_RANGE;
    n.x0 = pma_q16_from_f32(s->offset_cm);
    n.wire_break_below_counts = s->wire_break_below_counts;
    n.raw_min_counts = s->raw_min_counts;
    n.raw_max_counts = s->raw_max_counts;
    *in = n;
    return PMA_OK;
}

int pma_output_q16_build(pma_output_q16_t *o, const pma_actuator_config_t *ac,
                         const pma_dac_scaling_t *ds, float period_s)
{
    if (o == NULL || ac == NULL || ds == NULL) return PMA_ERR_NULL;
    int rc = pma_actuator_validate(ac);
    if (rc == PMA_OK) rc = pma_dac_validate_scaling(ds);
    if (rc != PMA_OK) return rc;
    if (!(period_s > 0.0f)) return PMA_ERR_RANGE;
    pma_output_q16_t n;
    rc = q16_of(ac->p0_kpa, &n.p0);
    if (rc == PMA_OK) rc = q16_of(ac->p_min_kpa, &n.p_min);
    if (rc == PMA_OK) rc = q16_of(ac->p_max_kpa, &n.p_max);
    n.step = 0;
    if (rc == PMA_OK && ac->slew_kpa_s > 0.0f) {
        /* the float function's step, slew * period, in Q16.16; a step that rounds to 0
         * would stop the output where float still moves it */
        const float step = ac->slew_kpa_s * period_s;
        rc = step < 32767.0f ? PMA_OK : PMA_ERR_FIXED_RANGE;
        if (rc == PMA_OK) n.step = pma_q16_from_f32(step);
        if (rc == PMA_OK && n.step == 0) rc = PMA_ERR_FIXED_RANGE;
    }
    if (rc == PMA_OK) rc = to_scale((float)ac->polarity * ac->kpa_per_u, &n.k);
    if (rc == PMA_OK) rc = to_scale(ds->counts_per_kpa, &n.cpk);
    if (rc != PMA_OK) return rc;
    n.c0 = (int64_t)llroundf(ldexpf(ds->counts_at_zero_kpa, 16));   /* |c0| <= 65535: < 2^32 */
    n.min_counts = ds->min_counts;
    n.max_counts = ds->max_counts;
    *o = n;
    return PMA_OK;
}

pma_q16_t pma_output_q16_kpa(const pma_output_q16_t *o, pma_q16_t u, pma_q16_t p_prev_kpa)
{
    pma_q16_t p = pma_q16_sat64((int64_t)o->p0 + pma_scale_q_apply(o->k, u));
    p = pma_q16_clamp(p, o->p_min, o->p_max);
    if (o->step > 0) {
        /* within p_prev +- step, the float function's order (upper bound first) */
        const pma_q16_t hi = pma_q16_sadd(p_prev_kpa, o->step);
        const pma_q16_t lo = pma_q16_ssub(p_prev_kpa, o->step);
        if (p > hi) p = hi;
        if (p < lo) p = lo;
    }
    return p;
}

uint16_t pma_output_q16_counts(const pma_output_q16_t *o, pma_q16_t p_kpa)
{
    const int64_t v = o->c0 + pma_scale_q_apply(o->cpk, p_kpa);                 /* Q16.16 counts */
    if (!(v > (int64_t)o->min_counts * 65536)) return o->min_counts;
    if (!(v < (int64_t)o->max_counts * 65536)) return o->max_counts;
    return (uint16_t)((v + 32768) >> 16);                           /* v > 0 here */
}
