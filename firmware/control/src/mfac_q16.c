/* SPDX-License-Identifier: Apache-2.0 */
/* CFDL-MFAC, fixed-point variant (see pma/mfac.h). Signals and parameters in
 * Q16.16, the pseudo partial derivative phi in Q8.24; the squares and quotients
 * of the update laws use 64-bit intermediates (Q32) so that du^2 and phi^2 never
 * saturate mid-computation; the estimator gain eta du / (mu + du^2) and the
 * innovation dy - phi du are kept in Q8.24 (the innovation in Q16.16 where it
 * is 128 cm or more); results saturate (phi to +-128, u to Q16.16). eps below
 * 2^-16 acts as one LSB (2^-16) for du, and as one LSB of Q8.24 (2^-24) for phi
 * where it is below that. */
#include "pma/mfac.h"
#include "pma/status.h"

#include <stddef.h>
#include <stdint.h>
#include "check.h"
#include "fixed_internal.h"

/* num / den with `frac` (16 or 24) fractional bits, saturated to int32; num
 * and den both with 32 fractional bits, den > 0. */
static int32_t div_q32(int64_t num, int64_t den, unsigned frac)
{
    const int neg = num < 0;
    const uint64_t un = (uint64_t)(neg ? -num : num);
    const uint64_t ud = (uint64_t)den;
    uint64_t q;
    if (un < ((uint64_t)1 << (62u - frac))) {
        q = pma_udiv64_q32((un << frac) + ud / 2u, ud);
    } else {
        const uint64_t dn = ud >> frac;
        q = (dn == 0u) ? UINT64_MAX : pma_udiv64_q32(un + dn / 2u, dn);
    }
    if (q > (uint64_t)INT32_MAX) return neg ? INT32_MIN : INT32_MAX;
    return neg ? -(int32_t)q : (int32_t)q;
}

int pma_mfac_init_q16(pma_mfac_q16_t *s, const pma_mfac_config_t *cfg)
{
    if (s == NULL) return PMA_ERR_NULL;
    s->ready = 0;
    PMA_CHECK(pma_mfac_validate_config(cfg));
    const float vals[] = {cfg->rho, cfg->u_min, cfg->u_max, cfg->u_init};
    for (unsigned i = 0; i < sizeof vals / sizeof vals[0]; ++i) {
        PMA_CHECK(pma_check_q16_range(vals[i]));
    }
    /* mu and lambda must keep some resolution in Q16.16 */
    if (cfg->mu < 1.0f / 1024.0f || cfg->lambda < 1.0f / 1024.0f) return PMA_ERR_FIXED_RANGE;
    if (cfg->mu > 32767.0f || cfg->lambda > 32767.0f) return PMA_ERR_FIXED_RANGE;
    s->eta = pma_to_q(cfg->eta, 16);
    s->mu = pma_to_q(cfg->mu, 16);
    s->rho = pma_to_q(cfg->rho, 16);
    s->lambda = pma_to_q(cfg->lambda, 16);
    s->eps = pma_to_q(cfg->eps, 16);
    if (s->eps == 0 && cfg->eps > 0.0f) s->eps = 1;
    if (!(cfg->phi1 > -127.0f && cfg->phi1 < 127.0f)) return PMA_ERR_FIXED_RANGE;   /* Q8.24 */
    s->phi1_q24 = pma_to_q(cfg->phi1, 24);
    s->eps_q24 = cfg->eps < 127.0f ? pma_to_q(cfg->eps, 24) : INT32_MAX;
    if (s->eps_q24 == 0 && cfg->eps > 0.0f) s->eps_q24 = 1;
    if ((s->phi1_q24 < 0 ? -s->phi1_q24 : s->phi1_q24) <= s->eps_q24) return PMA_ERR_FIXED_RANGE;
    s->u_min = pma_to_q(cfg->u_min, 16);
    s->u_max = pma_to_q(cfg->u_max, 16);
    s->u_init = pma_to_q(cfg->u_init, 16);
    pma_mfac_reset_q16(s);
    s->ready = 1;
    return PMA_OK;
}

void pma_mfac_reset_q16(pma_mfac_q16_t *s)
{
    if (s == NULL) return;
    s->phi_q24 = s->phi1_q24;
    s->u1 = s->u_init;
    s->u2 = s->u_init;
    s->y1 = 0;
    s->k = 0;
    s->resets = 0;
    s->flags = 0;
}

/* phi(k) in Q8.24 from y(k) and the inputs applied at k-1 and k-2 (pma/mfac.h, with its
 * reset rule); *flags gets PMA_MFAC_FLAG_RESET when the rule put phi back to phi(1). */
static inline int32_t estimate(const pma_mfac_q16_t *s, pma_q16_t y_cm, uint32_t *flags)
{
    const pma_q16_t y1 = (s->k == 0) ? y_cm : s->y1;
    const pma_q16_t du = pma_q16_ssub(s->u1, s->u2);
    const pma_q16_t dy = pma_q16_ssub(y_cm, y1);
    const pma_q16_t adu = du < 0 ? pma_q16_sneg(du) : du;
    if (adu <= s->eps) {               /* the reset rule's first test, before the work it voids */
        *flags |= PMA_MFAC_FLAG_RESET;
        return s->phi1_q24;
    }
    /* phi += eta du / (mu + du^2) (dy - phi du) */
    /* k1 = eta du / (mu + du^2) <= eta / (2 sqrt(mu)) < 32 (mu >= 1/1024): Q8.24
     * keeps it precise, since it multiplies innovations of tens of cm */
    const int64_t du2_q32 = pma_mul32(du, du);
    const int32_t k1_q24 = div_q32(pma_mul32(s->eta, du), (int64_t)s->mu * 65536 + du2_q32, 24);
    /* dy - phi du in Q8.24 (phi du is Q24 x Q16 = Q40), or in Q16.16 from 128 cm on */
    const int64_t innov_q24 = (int64_t)dy * 256 - pma_rshift_round(pma_mul32(s->phi_q24, du), 16);
    int64_t dphi_q24;
    if (innov_q24 >= INT32_MIN && innov_q24 <= INT32_MAX) {
        dphi_q24 = pma_rshift_round(pma_mul32(k1_q24, (int32_t)innov_q24), 24);
    } else {
        const pma_q16_t innov = pma_q16_round_sat64(innov_q24, 8);
        dphi_q24 = pma_rshift_round(pma_mul32(k1_q24, innov), 16);
    }
    int32_t phi = pma_q16_sat64((int64_t)s->phi_q24 + dphi_q24);   /* Q8.24, saturated */
    const int32_t aphi = phi < 0 ? (phi == INT32_MIN ? INT32_MAX : -phi) : phi;
    const int sign_flip = (s->phi1_q24 > 0) ? !(phi > 0) : !(phi < 0);
    if (aphi <= s->eps_q24 || sign_flip) {
        phi = s->phi1_q24;
        *flags |= PMA_MFAC_FLAG_RESET;
    }
    return phi;
}

/* the state after step k: phi(k), the input u applied at k, y(k) */
static inline void commit(pma_mfac_q16_t *s, int32_t phi_q24, pma_q16_t u, pma_q16_t y_cm, uint32_t flags)
{
    s->phi_q24 = phi_q24;
    s->u2 = s->u1;
    s->u1 = u;
    s->y1 = y_cm;
    s->k++;
    if (flags & PMA_MFAC_FLAG_RESET) s->resets++;
    s->flags = flags;
}

int pma_mfac_step_q16(pma_mfac_q16_t *s, pma_q16_t y_cm, pma_q16_t yref_next_cm, pma_q16_t *u)
{
    if (s == NULL || u == NULL) return PMA_ERR_NULL;
    if (!s->ready) return PMA_ERR_NOT_READY;
    uint32_t flags = 0;
    const int32_t phi = estimate(s, y_cm, &flags);
    /* u = u(k-1) + rho phi / (lambda + phi^2) (y* - y): numerator and denominator in Q32 */
    const pma_q16_t k2 = div_q32(pma_rshift_round(pma_mul32(s->rho, phi), 8),
                                 (int64_t)s->lambda * 65536 + pma_rshift_round(pma_mul32(phi, phi), 16), 16);
    const pma_q16_t v = pma_q16_sadd(s->u1, pma_q16_smul(k2, pma_q16_ssub(yref_next_cm, y_cm)));
    pma_q16_t out = v;
    if (v > s->u_max) {
        out = s->u_max;
        flags |= PMA_MFAC_FLAG_SAT_HIGH;
    } else if (v < s->u_min) {
        out = s->u_min;
        flags |= PMA_MFAC_FLAG_SAT_LOW;
    }
    commit(s, phi, out, y_cm, flags);
    *u = out;
    return PMA_OK;
}

int pma_mfac_take_over_q16(pma_mfac_q16_t *s, pma_q16_t u_start)
{
    if (s == NULL) return PMA_ERR_NULL;
    if (!s->ready) return PMA_ERR_NOT_READY;
    s->u1 = s->u2 = pma_q16_clamp(u_start, s->u_min, s->u_max);
    return PMA_OK;
}
