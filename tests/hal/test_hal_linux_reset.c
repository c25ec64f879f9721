/* SPDX-License-Identifier: Apache-2.0 */
/* Linux port, what ends or replaces a process, checked through a helper
 * program (test_hal_linux_helper.c) run with fork/exec: the reset cause from
 * the environment (and its removal), the watchdog's re-execution with the
 * cause WATCHDOG or its exit status without argv, kicks keeping it quiet, a
 * shortened timeout, and the NVM power-cut hook at every operation of a
 * sequence with partial application, checked byte for byte in the file. */
#define _GNU_SOURCE

#include "test_hal_linux.h"

#include <errno.h>
#include <fcntl.h>
#include <sys/wait.h>

#ifndef PMA_HELPER_PATH
#error "PMA_HELPER_PATH: the helper program's path (tests/hal/CMakeLists.txt)"
#endif

extern char **environ;

static char dir[256];
static char out[16384];

/* Every test: a fresh directory for its files. */
void setUp(void)
{
    dir[0] = '\0';
    linux_test_mkdtemp(dir, sizeof dir);
}

/* After every test, also one that failed: the port down, the directory removed. */
void tearDown(void)
{
    pma_hal_deinit();
    if (dir[0] != '\0') linux_test_rmdir(dir);
}

/* Runs the helper with args (NULL-terminated, after the program name) and
 * our environment plus PMA_HAL_LINUX_RESET_CAUSE=cause (NULL: unset);
 * collects its stdout and stderr in `out`; returns its exit status, or
 * 128 + signal. */
static int run_helper(const char *cause, const char *const *args)
{
    static char *argv[16];
    static char *envp[4096];
    static char cause_entry[64];
    size_t n = 0;
    argv[n++] = (char *)PMA_HELPER_PATH;
    for (size_t i = 0; args[i] != NULL && n + 1u < sizeof argv / sizeof argv[0]; ++i) {
        argv[n++] = (char *)args[i];
    }
    argv[n] = NULL;
    const size_t prefix = strlen(PMA_HAL_LINUX_RESET_CAUSE_ENV "=");
    n = 0;
    for (char **e = environ; *e != NULL && n + 2u < sizeof envp / sizeof envp[0]; ++e) {
        if (strncmp(*e, PMA_HAL_LINUX_RESET_CAUSE_ENV "=", prefix) != 0) envp[n++] = *e;
    }
    if (cause != NULL) {
        (void)snprintf(cause_entry, sizeof cause_entry, "%s=%s", PMA_HAL_LINUX_RESET_CAUSE_ENV,
                       cause);
        envp[n++] = cause_entry;
    }
    envp[n] = NULL;

    int fds[2];
    TEST_ASSERT_EQUAL_INT(0, pipe2(fds, O_CLOEXEC));
    fflush(NULL);
    const pid_t pid = fork();
    if (pid < 0) {
        (void)close(fds[0]);
        (void)close(fds[1]);
    }
    TEST_ASSERT_TRUE(pid >= 0);
    if (pid == 0) {
        (void)dup2(fds[1], STDOUT_FILENO);
        (void)dup2(fds[1], STDERR_FILENO);
        execve(PMA_HELPER_PATH, argv, envp);
        _exit(127);
    }
    (void)close(fds[1]);
    size_t used = 0;
    for (;;) {
        const ssize_t r = read(fds[0], out + used, sizeof out - 1u - used);
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0) break;
        used += (size_t)r;
        if (used == sizeof out - 1u) break;
    }
    out[used] = '\0';
    (void)close(fds[0]);
    int status;
    while (waitpid(pid, &status, 0) < 0) TEST_ASSERT_EQUAL_INT(EINTR, errno);
    printf("--- helper %s%s%s:\n%s--- end\n", args[0], cause ? " with cause " : "",
           cause ? cause : "", out);
    if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
    return WEXITSTATUS(status);
}

static void test_reset_cause_from_environment(void)
{
    static const char *const cause[] = {"cause", NULL};
    TEST_ASSERT_EQUAL_INT(0, run_helper(NULL, cause));
    assert_contains(out, "cause=1 env=(unset)\n"); /* POWER_ON */
    TEST_ASSERT_EQUAL_INT(0, run_helper("WATCHDOG", cause));
    assert_contains(out, "cause=2 env=(unset)\n"); /* read, then removed */
    assert_contains(out, "after init cause=2\n");
    TEST_ASSERT_EQUAL_INT(0, run_helper("SOFTWARE", cause));
    assert_contains(out, "cause=3 env=(unset)\n");
    TEST_ASSERT_EQUAL_INT(0, run_helper("no such cause", cause));
    assert_contains(out, "cause=0 env=(unset)\n"); /* UNKNOWN */
}

static void test_watchdog_reexecutes(void)
{
    static const char *const args[] = {"watchdog", "50", "1", NULL};
    TEST_ASSERT_EQUAL_INT(0, run_helper(NULL, args));
    assert_contains(out, "start cause=1\nstarted\n");
    assert_contains(out, "watchdog expired");
    assert_contains(out, "start cause=2\nafter reset env=(unset)\n");
}

static void test_watchdog_exits_without_argv(void)
{
    static const char *const args[] = {"watchdog", "30", "0", NULL};
    TEST_ASSERT_EQUAL_INT(PMA_HAL_LINUX_EXIT_WATCHDOG, run_helper(NULL, args));
    assert_contains(out, "started\n");
    assert_contains(out, "watchdog expired");
    assert_contains(out, "exiting (no argv");
}

/* A new, shorter timeout applies at once (the thread does not sleep out the old one). */
static void test_watchdog_shortened(void)
{
    static const char *const args[] = {"shorten", NULL};
    TEST_ASSERT_EQUAL_INT(PMA_HAL_LINUX_EXIT_WATCHDOG, run_helper(NULL, args));
    assert_contains(out, "shortened\n");
    assert_contains(out, "watchdog expired (no kick for more than 20 ms)");
}

/* Kicks every 2 ms for 1.2 s against a 500 ms timeout (this fails only if the
 * helper is not scheduled for half a second), then the reset, which the
 * re-executed helper checks came more than 500 ms after the last kick. */
static void test_watchdog_kicked(void)
{
    char file[300];
    (void)snprintf(file, sizeof file, "%s/last_kick", dir);
    const char *const args[] = {"kick", "500", "1200", file, NULL};
    TEST_ASSERT_EQUAL_INT(0, run_helper(NULL, args));
    assert_contains(out, "kicked for 1200 ms\n");
    assert_contains(out, "watchdog expired");
    assert_contains(out, "reset no earlier than the timeout after the last kick\n");
}

/* ------------------------------------------------------------ power cut -- */

/* The helper's operation sequence on 2 blocks of 64 bytes, applied to a
 * model: every operation before the cut whole, the cut one in part. */
static void model(uint8_t mem[128], int32_t cut_after, uint32_t permille)
{
    uint8_t a[64], b[64];
    for (unsigned i = 0; i < 64; ++i) {
        a[i] = (uint8_t)i;
        b[i] = (uint8_t)(0x40u + i);
    }
    memset(mem, 0xFF, 128);
    const struct {
        uint32_t at, len;
        const uint8_t *src; /* NULL: erase */
    } ops[] = {{0, 64, a}, {64, 64, b}, {0, 64, NULL}, {8, 16, a}};
    for (int32_t i = 0; i < 4; ++i) {
        uint32_t len = ops[i].len;
        if (i == cut_after) len = (uint32_t)((uint64_t)len * permille / 1000u);
        if (ops[i].src != NULL) {
            memcpy(mem + ops[i].at, ops[i].src, len);
        } else {
            memset(mem + ops[i].at, 0xFF, len);
        }
        if (i == cut_after) return;
    }
}

static void test_power_cut(void)
{
    static const struct {
        int32_t after;
        uint32_t permille;
    } cases[] = {{0, 500}, {0, 0}, {1, 1000}, {1, 125}, {2, 0}, {2, 500}, {2, 1000},
                 {3, 250}, {3, 1000}, {-1, 0}};
    char path[300], after[16], permille[16];
    (void)snprintf(path, sizeof path, "%s/nvm.bin", dir);
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; ++c) {
        (void)unlink(path);
        (void)snprintf(after, sizeof after, "%d", (int)cases[c].after);
        (void)snprintf(permille, sizeof permille, "%u", (unsigned)cases[c].permille);
        const char *const args[] = {"powercut", path, after, permille, NULL};
        const int status = run_helper(NULL, args);
        if (cases[c].after < 0) {
            TEST_ASSERT_EQUAL_INT(0, status);
            assert_contains(out, "op3 0\n");
        } else {
            TEST_ASSERT_EQUAL_INT(PMA_HAL_LINUX_EXIT_POWER_CUT, status);
            assert_contains(out, "power cut");
            char line[16];
            (void)snprintf(line, sizeof line, "op%d", (int)cases[c].after);
            TEST_ASSERT_NULL(strstr(out, line)); /* the cut operation never returned */
        }
        uint8_t want[128], got[128];
        model(want, cases[c].after, cases[c].permille);
        /* what is in the file after the "power cut", read through the HAL */
        pma_hal_linux_config_t lc = PMA_HAL_LINUX_CONFIG_INIT;
        lc.no_can = 1;
        lc.storage_path = path;
        lc.nvm_block_size = 64;
        lc.nvm_block_count = 2;
        const pma_hal_config_t cfg = {.can_bitrate_bps = 0, .port = &lc};
        assert_status(pma_hal_init(&cfg), PMA_OK); /* the lock died with the process */
        assert_status(pma_hal_nvm_read(0, 0, got, 64), PMA_OK);
        assert_status(pma_hal_nvm_read(1, 0, got + 64, 64), PMA_OK);
        pma_hal_deinit();
        TEST_ASSERT_EQUAL_MEMORY(want, got, sizeof want);
    }
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_reset_cause_from_environment);
    RUN_TEST(test_watchdog_reexecutes);
    RUN_TEST(test_watchdog_exits_without_argv);
    RUN_TEST(test_watchdog_shortened);
    RUN_TEST(test_watchdog_kicked);
    RUN_TEST(test_power_cut);
    return UNITY_END();
}
