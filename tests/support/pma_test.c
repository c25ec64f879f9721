/* Default fixture of every C test: Unity calls setUp() before and tearDown() after each test.
 * Weak, so that a test file that needs a fixture defines its own. */
#include "pma_test.h"

__attribute__((weak)) void setUp(void) {}
__attribute__((weak)) void tearDown(void) {}
