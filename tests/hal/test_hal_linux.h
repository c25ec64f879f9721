/* SPDX-License-Identifier: Apache-2.0 */
/* Shared helpers of the Linux port's tests (test_hal_linux_*.c). */
#ifndef PMA_TEST_HAL_LINUX_H
#define PMA_TEST_HAL_LINUX_H

#include "hal_test.h"

#include <dirent.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "pma/hal.h"
#include "pma_hal_linux.h"

/* Fails the test unless `sub` occurs in `s`, printing both (their first 110
 * characters: the message has PMA_TEST_MSG_CHARS). */
#define assert_contains(s, sub)                                                          \
    do {                                                                                  \
        const char *s_ = (s), *sub_ = (sub);                                              \
        if (s_ == NULL || strstr(s_, sub_) == NULL) {                                     \
            pma_test_fail("\"%.110s\" does not contain \"%.110s\"", s_ ? s_ : "(null)",   \
                          sub_);                                                          \
        }                                                                                 \
    } while (0)

/* A fresh directory for the test's files, under TMPDIR or /tmp. */
static inline void linux_test_mkdtemp(char *dir, size_t capacity)
{
    const char *base = getenv("TMPDIR");
    if (base == NULL || base[0] == '\0') base = "/tmp";
    const int n = snprintf(dir, capacity, "%s/pma_hal_linux_XXXXXX", base);
    TEST_ASSERT_TRUE(n > 0 && (size_t)n < capacity);
    TEST_ASSERT_NOT_NULL(mkdtemp(dir));
}

/* Removes the directory and the plain files in it. */
static inline void linux_test_rmdir(const char *dir)
{
    DIR *d = opendir(dir);
    if (d == NULL) return;
    char path[512];
    for (struct dirent *e = readdir(d); e != NULL; e = readdir(d)) {
        if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0) continue;
        (void)snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        (void)unlink(path);
    }
    (void)closedir(d);
    (void)rmdir(dir);
}

#endif /* PMA_TEST_HAL_LINUX_H */
