/* SPDX-License-Identifier: Apache-2.0 */
/* Float trigonometry for the float controllers (see pma/trig.h).
 * Coefficients from tools/fit_fixed_poly.py (tan: the degree-4 fit; cos: the
 * same degree-4 fit as the fixed-point version). */
#include "pma/trig.h"

#include <math.h>

float pma_tan_halfpi_f32(float r)
{
    const float ar = fabsf(r);
    if (!(ar < 1.0f)) return r < 0.0f ? -INFINITY : INFINITY;   /* also NaN -> +inf */
    const float u = ar * ar;
    const float g = 1.5707962693008455f +
                    u * (-0.2788653919540693f +
                         u * (-0.016867171182124833f +
                              u * (-0.0015889029594850495f + u * -0.00023520905138608606f)));
    const float t = ar * g / ((1.0f - ar) * (1.0f + ar));
    return r < 0.0f ? -t : t;
}

float pma_cos_pi_f32(float s)
{
    float a = fabsf(s);
    float sign = 1.0f;
    if (a > 0.5f) {            /* cos(pi s) = -cos(pi (1 - s)) */
        a = 1.0f - a;
        sign = -1.0f;
    }
    const float x = a * a;
    const float c = 1.0f + x * (-4.93479532408054f +
                                x * (4.0584472586995f +
                                     x * (-1.332068065877649f + x * 0.2200300516253903f)));
    return sign * c;
}
