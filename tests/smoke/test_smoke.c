/*
 * Smoke test of the test infrastructure itself: cmocka runs, asserts are evaluated, floating
 * point (FPU or soft-float), 64-bit division (libgcc's __aeabi_*ldivmod on ARM) and printf of
 * floats (newlib-nano needs -u _printf_float) work on the target, and a failure reaches the exit
 * status (on ARM through semihosting to QEMU's exit status).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <stdio.h>

#include "pma_board.h"

/* Operands are volatile so the compiler cannot fold the results: the target computes them. */

static void test_float_math(void **state)
{
    (void)state;
    volatile float a = 1.5f;
    volatile float b = 2.25f;
    volatile float two = 2.0f;

    assert_float_equal(a * b, 3.375f, 0.0f); /* exact in binary */
    assert_float_equal(a / b, 0.6666667f, 1e-7f);
    float r = sqrtf(two);
    assert_float_equal(r * r, 2.0f, 1e-6f);
}

static void test_int64_division(void **state)
{
    (void)state;
    volatile uint64_t n = 0x123456789ABCDEF0u;
    volatile uint64_t d = 12345u;
    volatile int64_t sn = -1000000000007;
    volatile int64_t sd = 7;

    assert_int_equal(n / d, 106259090114523u);
    assert_int_equal(n % d, 3885u);
    assert_true(sn / sd == -142857142858); /* C truncates toward zero */
    assert_true(sn % sd == -1);
}

static void test_printf_float(void **state)
{
    (void)state;
    volatile double x = 3.14159;
    char buf[32];

    int len = snprintf(buf, sizeof buf, "%.3f|%g", x, x * 1000.0);
    assert_int_equal(len, 13);
    assert_string_equal(buf, "3.142|3141.59");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_float_math),
        cmocka_unit_test(test_int64_division),
        cmocka_unit_test(test_printf_float),
    };
    print_message("smoke test on %s\n", pma_board_name());
    return cmocka_run_group_tests_name("smoke", tests, NULL, NULL);
}
