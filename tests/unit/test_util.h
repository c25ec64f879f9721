/* SPDX-License-Identifier: Apache-2.0 */
/* Helpers of the C unit tests (tests/unit) on top of the shared test support (pma_test.h:
 * Unity, assert_near, test_rand_*): the Q16.16 conversions the tests write their values with. */
#ifndef PMA_TEST_UTIL_H
#define PMA_TEST_UTIL_H

#include <math.h>
#include <stdint.h>
#include <stdio.h>

#include "pma_test.h"
#include "pma/fixed.h"

#define Q16(x) pma_q16_from_f32((float)(x))
#define F16(x) ((double)pma_q16_to_f32(x))
#define F30(x) ((double)pma_q30_to_f32(x))

#endif /* PMA_TEST_UTIL_H */
