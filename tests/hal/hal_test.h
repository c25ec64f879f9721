/* SPDX-License-Identifier: Apache-2.0 */
/* Shared header of the HAL, fake-port and storage tests: the project's test
 * support (Unity and assert_status, tests/support/pma_test.h) and the
 * declaration of pma_status_name() that assert_status prints with. */
#ifndef PMA_HAL_TEST_H
#define PMA_HAL_TEST_H

#include <stdint.h>

#include "pma/status.h"
#include "pma_test.h"

#endif /* PMA_HAL_TEST_H */
