/* SPDX-License-Identifier: Apache-2.0 */
/*
 * Smoke test of the test infrastructure itself: Unity runs, asserts are evaluated, floating
 * point (FPU or soft-float), 64-bit division (libgcc's __aeabi_*ldivmod on ARM) and printf of
 * floats (newlib-nano needs -u _printf_float) work on the target, and a failure reaches the exit
 * status (on ARM through semihosting to QEMU's exit status).
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>

#include "pma_board.h"
#include "pma_test.h"

/* Operands are volatile so the compiler cannot fold the results: the target computes them. */

static void test_float_math(void)
{
    volatile float a = 1.5f;
    volatile float b = 2.25f;
    volatile float two = 2.0f;

    TEST_ASSERT_FLOAT_WITHIN(0.0f, 3.375f, a * b); /* exact in binary */
    TEST_ASSERT_FLOAT_WITHIN(1e-7f, 0.6666667f, a / b);
    float r = sqrtf(two);
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 2.0f, r * r);
}

static void test_int64_division(void)
{
    volatile uint64_t n = 0x123456789ABCDEF0u;
    volatile uint64_t d = 12345u;
    volatile int64_t sn = -1000000000007;
    volatile int64_t sd = 7;

    TEST_ASSERT_EQUAL_UINT64(106259090114523u, n / d);
    TEST_ASSERT_EQUAL_UINT64(3885u, n % d);
    TEST_ASSERT_EQUAL_INT64(-142857142858, sn / sd); /* C truncates toward zero */
    TEST_ASSERT_EQUAL_INT64(-1, sn % sd);
}

static void test_printf_float(void)
{
    volatile double x = 3.14159;
    char buf[32];

    int len = snprintf(buf, sizeof buf, "%.3f|%g", x, x * 1000.0);
    TEST_ASSERT_EQUAL_INT(13, len);
    TEST_ASSERT_EQUAL_STRING("3.142|3141.59", buf);
}

int main(void)
{
    printf("smoke test on %s\n", pma_board_name());
    UNITY_BEGIN();
    RUN_TEST(test_float_math);
    RUN_TEST(test_int64_division);
    RUN_TEST(test_printf_float);
    return UNITY_END();
}
