/* SPDX-License-Identifier: Apache-2.0 */
/*
 * The project's test support, shared by every C test (unit, golden, app, hal, board, smoke):
 * Unity (ThrowTheSwitch) plus the assertion helpers that print the project's names and values
 * on a failure. Link `pma_test` (cmake/PmaTest.cmake's pma_add_test does).
 *
 * A test file defines `static void test_x(void)` functions and a main():
 *
 *     int main(void)
 *     {
 *         UNITY_BEGIN();
 *         RUN_TEST(test_x);
 *         return UNITY_END();   // the number of failures: the exit status (QEMU's too)
 *     }
 *
 * Unity calls setUp() before and tearDown() after every test. pma_test.c defines both as weak,
 * empty functions: a file that needs a fixture defines its own.
 *
 * The helpers are macros so that a failure reports the line of the call. The name functions
 * (pma_status_name, pma_fault_name, pma_app_state_name) are looked up where a helper is used:
 * include the header that declares the one you use.
 */
#ifndef PMA_TEST_H
#define PMA_TEST_H

#include <math.h>
#include <stdint.h>
#include <stdio.h>

#include "unity.h"

/** Size of the message buffer of pma_test_fail (longer messages are truncated). */
#define PMA_TEST_MSG_CHARS 256

/** Fails the current test at `line` with a printf-style message (pma_test.c; formatted in a
 *  function, so no call site inlines the buffer). Use pma_test_fail(). */
void pma_test_failf(unsigned line, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/** Fails the current test with a printf-style message, reported at the line of the call. */
#define pma_test_fail(...) pma_test_failf((unsigned)__LINE__, __VA_ARGS__)

/** Fails with the values printed when |got - want| > tol (or either is NaN). */
#define assert_near(got, want, tol)                                                       \
    do {                                                                                  \
        const double g_ = (double)(got), w_ = (double)(want), t_ = (double)(tol);         \
        if (!(fabs(g_ - w_) <= t_)) {                                                     \
            pma_test_fail("%s = %.9g, expected %.9g +- %.3g", #got, g_, w_, t_);          \
        }                                                                                 \
    } while (0)

/** Compares two codes of one enum and prints both with name_of() on a mismatch. */
#define pma_assert_named(got, want, name_of)                                              \
    do {                                                                                  \
        const int g_ = (int)(got), w_ = (int)(want);                                      \
        if (g_ != w_) {                                                                   \
            pma_test_fail("%s = %s (%d), expected %s (%d)", #got, name_of(g_), g_,        \
                          name_of(w_), w_);                                               \
        }                                                                                 \
    } while (0)

/** Status codes (pma/status.h: pma_status_name). */
#define assert_status(got, want) pma_assert_named(got, want, pma_status_name)
/** Fault codes (the application's supervisor.h: pma_fault_name). */
#define assert_fault(got, want) pma_assert_named(got, want, pma_fault_name)
/** Application states (the application's app.h: pma_app_state_name). */
#define assert_state(got, want) pma_assert_named(got, want, pma_app_state_name)

/* Deterministic pseudo-random numbers for tests (xorshift32); uniform in [-1, 1) and
 * approximately Gaussian (sum of 12 uniforms). */
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

#endif /* PMA_TEST_H */
