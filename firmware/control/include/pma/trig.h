/* SPDX-License-Identifier: Apache-2.0 */
/* Float trigonometry of the float controllers: the two functions the paper's
 * law needs, on the ranges it uses, without libm's general argument reduction
 * (tanf + cosf cost ~120 instructions on a Cortex-M4F and ~6,000 with soft
 * float). Same identities as the fixed-point versions in pma/fixed.h (tan
 * with a degree-4 instead of degree-3 polynomial; cos with the same one), so
 * the error is at float rounding level. */
#ifndef PMA_TRIG_H
#define PMA_TRIG_H

/* tan(pi/2 * r) for |r| < 1 (|r| >= 1 returns +-INFINITY):
 * r g(r^2) / ((1 - r)(1 + r)), g of degree 4; relative error <= 7e-8 plus
 * float rounding (about 1e-7 in all). (1 - r) is exact in float for
 * r >= 1/2, so the accuracy holds right up to the pole. */
float pma_tan_halfpi_f32(float r);

/* cos(pi * s) for s in [-1, 1]; absolute error <= 6e-8 plus float rounding;
 * cos(0) = 1 exactly. */
float pma_cos_pi_f32(float s);

#endif /* PMA_TRIG_H */
