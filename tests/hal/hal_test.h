/* Shared helpers of the HAL, fake-port and storage tests (cmocka). */
#ifndef PMA_HAL_TEST_H
#define PMA_HAL_TEST_H

#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include "pma/status.h"

/* Compares status codes and prints their names on a mismatch. */
#define assert_status(got, want)                                                         \
    do {                                                                                  \
        const int g_ = (got), w_ = (want);                                                \
        if (g_ != w_) {                                                                   \
            print_error("%s = %s (%d), expected %s (%d)\n", #got, pma_status_name(g_),    \
                        g_, pma_status_name(w_), w_);                                     \
            fail();                                                                       \
        }                                                                                 \
    } while (0)

#endif /* PMA_HAL_TEST_H */
