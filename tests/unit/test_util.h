/* Shared helpers of the C unit tests (cmocka). */
#ifndef PMA_TEST_UTIL_H
#define PMA_TEST_UTIL_H

#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>

#include "pma/fixed.h"

/* Fails with the values printed when |got - want| > tol. */
#define assert_near(got, want, tol)                                                       \
    do {                                                                                  \
        const double g_ = (double)(got), w_ = (double)(want), t_ = (double)(tol);         \
        if (!(fabs(g_ - w_) <= t_)) {                                                     \
            print_error("%s = %.9g, expected %.9g +- %.3g\n", #got, g_, w_, t_);          \
            fail();                                                                       \
        }                                                                                 \
    } while (0)

#define Q16(x) pma_q16_from_f32((float)(x))
#define F16(x) ((double)pma_q16_to_f32(x))

/* Deterministic pseudo-random numbers for tests (xorshift32); uniform in
 * [-1, 1) and approximately Gaussian (sum of 12 uniforms). */
static inline uint32_t test_rand_u32(uint32_t *state)
{
    uint32_t x = *state;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    *state = x;
    return x;
}

static inline double test_rand_uniform(uint32_t *state)
{
    return (double)test_rand_u32(state) / 2147483648.0 - 1.0;
}

static inline double test_rand_gauss(uint32_t *state)
{
    double s = 0.0;
    for (int i = 0; i < 12; ++i) s += 0.5 * (test_rand_uniform(state) + 1.0);
    return s - 6.0;
}

#endif /* PMA_TEST_UTIL_H */
