/* SPDX-License-Identifier: Apache-2.0 */
/* Shared comparison, reporting and test-registration helpers of the golden-vector tests
 * (tests/golden/test_golden_*.c). Header-only (static functions), included once per test.
 *
 * Every comparison is |got - expected| <= tol with a tolerance the caller computes and
 * documents; a NaN or infinite result never passes. On a mismatch the set, row, field,
 * expected, got and tolerance are printed (printf) and the test fails at the end of the set,
 * after at most GOLDEN_MAX_REPORTS messages. Each set ends with one summary line:
 *
 *   GOLDEN <module> <set> <variant> rows=<n> max_abs_u=<g> max_rel=<g> tol_use=<g>
 *
 * max_abs_u: largest |got - expected| of the module's main output (u for the controllers,
 *            v for velest, x_r for ref) over the set;
 * max_rel:   largest |got - expected| / (1 + |expected|) over every compared field;
 * tol_use:   largest |got - expected| / tol over every compared field (1 = at the limit).
 *
 * Each (set, variant) is one Unity test named <set>_<variant> (golden_run_all below).
 *
 * Memory: a golden_stats_t on the stack (about 60 bytes), and one case and one name buffer
 * (static); nothing else. */
#ifndef GOLDEN_CHECK_H
#define GOLDEN_CHECK_H

#include <math.h>
#include <stdint.h>
#include <stdio.h>

#include "pma_test.h"

#define GOLDEN_MAX_REPORTS 12u
#define GOLDEN_LSB16 (1.0 / 65536.0)
/* Largest / smallest Q16.16 values: expected values beyond them are compared saturated. */
#define GOLDEN_Q16_MAXV (2147483647.0 / 65536.0)
#define GOLDEN_Q16_MINV (-32768.0)

typedef enum golden_variant { GOLDEN_F32 = 0, GOLDEN_Q16 = 1 } golden_variant_t;

typedef struct golden_stats {
    const char *module, *set, *variant;
    uint32_t rows, failures;
    double max_abs_u, max_rel, tol_use;
} golden_stats_t;

static inline void golden_stats_init(golden_stats_t *st, const char *module, const char *set,
                              golden_variant_t variant, uint32_t rows)
{
    st->module = module;
    st->set = set;
    st->variant = variant == GOLDEN_F32 ? "f32" : "q16";
    st->rows = rows;
    st->failures = 0;
    st->max_abs_u = 0.0;
    st->max_rel = 0.0;
    st->tol_use = 0.0;
}

static inline void golden_fail_msg(golden_stats_t *st, uint32_t row, const char *field,
                            const char *what)
{
    st->failures++;
    if (st->failures <= GOLDEN_MAX_REPORTS) {
        printf("GOLDEN-MISMATCH %s %s %s row %u field %s: %s\n", st->module, st->set,
               st->variant, (unsigned)row, field, what);
    }
}

/* Compare one value; is_main marks the module's main output (max_abs_u). */
static inline void golden_check(golden_stats_t *st, uint32_t row, const char *field, double expected,
                         double got, double tol, int is_main)
{
    double d = fabs(got - expected);
    if (!isfinite(got) || !(d <= tol)) {
        char buf[160];
        snprintf(buf, sizeof buf, "expected %.9g got %.9g |d| %.3g > tol %.3g", expected, got,
                 d, tol);
        golden_fail_msg(st, row, field, buf);
        if (!isfinite(got)) return;
    }
    if (is_main && d > st->max_abs_u) st->max_abs_u = d;
    if (d / (1.0 + fabs(expected)) > st->max_rel) st->max_rel = d / (1.0 + fabs(expected));
    if (tol > 0.0 && d / tol > st->tol_use) st->tol_use = d / tol;
}

static inline void golden_check_flags(golden_stats_t *st, uint32_t row, const char *field,
                               uint32_t expected, uint32_t got)
{
    if (expected != got) {
        char buf[80];
        snprintf(buf, sizeof buf, "expected 0x%02x got 0x%02x", (unsigned)expected,
                 (unsigned)got);
        golden_fail_msg(st, row, field, buf);
    }
}

static inline void golden_check_status(golden_stats_t *st, uint32_t row, const char *call, int rc)
{
    if (rc != 0) {
        char buf[80];
        snprintf(buf, sizeof buf, "returned %d, expected 0 (PMA_OK)", rc);
        golden_fail_msg(st, row, call, buf);
    }
}

/* Expected value as the Q16.16 variant can represent it (saturated to the format). */
static inline double golden_q16_sat(double x)
{
    return x > GOLDEN_Q16_MAXV ? GOLDEN_Q16_MAXV : x < GOLDEN_Q16_MINV ? GOLDEN_Q16_MINV : x;
}

/* The summary line of a set (see above). */
static inline void golden_print_summary(const golden_stats_t *st)
{
    printf("GOLDEN %s %s %s rows=%u max_abs_u=%.3g max_rel=%.3g tol_use=%.3g\n", st->module,
           st->set, st->variant, (unsigned)st->rows, st->max_abs_u, st->max_rel, st->tol_use);
}

/* Summary line, then fail the test if anything mismatched. A macro, so that Unity reports the
 * failure at the line of the test file's call (Unity prints every failure with the name of
 * the file that called UNITY_BEGIN). */
#define golden_finish(st)                                                                 \
    do {                                                                                  \
        const golden_stats_t *const gst_ = (st);                                          \
        golden_print_summary(gst_);                                                       \
        if (gst_->failures != 0) {                                                        \
            const unsigned shown_ = gst_->failures < GOLDEN_MAX_REPORTS                   \
                                        ? (unsigned)gst_->failures                        \
                                        : (unsigned)GOLDEN_MAX_REPORTS;                   \
            pma_test_fail("%s %s %s: %u mismatching values (first %u shown above)",       \
                          gst_->module, gst_->set, gst_->variant,                         \
                          (unsigned)gst_->failures, shown_);                              \
        }                                                                                 \
    } while (0)

/* One Unity test per (set, variant). The test function takes no argument: it reads the case
 * it runs from golden_current, which golden_run_all sets before each run. */
typedef struct golden_case {
    uint32_t set;
    golden_variant_t variant;
} golden_case_t;

static golden_case_t golden_current;

/* Run fn once per set and variant (nsets sets x 2 variants) as its own Unity test, named
 * <set_name(i)>_f32 / _q16, between UNITY_BEGIN() and UNITY_END(); line: the caller's (what
 * Unity reports for the test). */
#define GOLDEN_NAME_LEN 48
static inline void golden_run_all(uint32_t nsets, const char *(*set_name)(uint32_t),
                                  UnityTestFunction fn, int line)
{
    static char name[GOLDEN_NAME_LEN];
    for (uint32_t i = 0; i < nsets; i++) {
        for (int v = 0; v < 2; v++) {
            golden_current.set = i;
            golden_current.variant = v == 0 ? GOLDEN_F32 : GOLDEN_Q16;
            snprintf(name, sizeof name, "%s_%s", set_name(i), v == 0 ? "f32" : "q16");
            UnityDefaultTestRun(fn, name, line);
        }
    }
}

#endif /* GOLDEN_CHECK_H */
