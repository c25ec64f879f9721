/* SPDX-License-Identifier: Apache-2.0 */
/* The test support's functions (pma_test.h). */
#include "pma_test.h"

#include <stdarg.h>

/* Default fixture of every C test: Unity calls setUp() before and tearDown() after each test.
 * Weak, so that a test file that needs a fixture defines its own. */
__attribute__((weak)) void setUp(void) {}
__attribute__((weak)) void tearDown(void) {}

void pma_test_failf(unsigned line, const char *fmt, ...)
{
    char msg[PMA_TEST_MSG_CHARS]; /* on the stack: the M0's 16 KB of RAM have no room for it */
    va_list ap;
    va_start(ap, fmt);
    (void)vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    UNITY_TEST_FAIL((UNITY_LINE_TYPE)line, msg); /* does not return: ends the test */
}
