/* SPDX-License-Identifier: Apache-2.0 */
/* Linux port: a software watchdog, the reset cause and the system reset.
 *
 * The watchdog is a thread (started by the first pma_hal_watchdog_start(),
 * never stopped) that sleeps until the last kick plus the timeout. When it
 * wakes and no kick moved the deadline, it "resets" the program: it prints
 * "watchdog expired" to stderr and re-executes /proc/self/exe with the argv
 * given at pma_hal_init(), with PMA_HAL_LINUX_RESET_CAUSE=WATCHDOG in the
 * environment; without argv it _exit()s with PMA_HAL_LINUX_EXIT_WATCHDOG.
 * A kick is a clock read and one atomic store (no lock, no system call): the
 * thread re-reads the kick time whenever it wakes. Only a new timeout wakes
 * it early.
 *
 * The thread runs on a static stack (glibc keeps the thread's descriptor in
 * it too), so the port allocates no memory for it.
 *
 * pma_hal_system_reset() resets the same way from the main thread, with
 * PMA_HAL_LINUX_RESET_CAUSE=SOFTWARE, after the CAN send queue has drained;
 * without argv it _exit()s with PMA_HAL_LINUX_EXIT_RESET. The re-executed
 * program opens the CAN socket and the storage file again (every descriptor
 * is close-on-exec, so the file's lock goes with the old image). */
#define _GNU_SOURCE

#include "linux_internal.h"

#include <errno.h>
#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

extern char **environ;

#define THREAD_STACK_BYTES (64u * 1024u)
#define ENV_MAX 4096u /* environment entries passed on by the re-execution */

/* Static: one watchdog and one reset cause per process. */
static struct {
    bool cause_latched;
    pma_reset_cause_t cause;
    pthread_mutex_t lock;          /* guards the fields below, not the atomics */
    pthread_cond_t wake;           /* a new timeout */
    bool thread_started;
    char *const *argv;             /* what the re-execution runs (NULL: exit instead) */
    sigset_t exec_mask;            /* the starting thread's signal mask, for the new program */
    _Atomic uint64_t kick_us;      /* last kick (or start), pma_hal_time_us() */
    _Atomic uint32_t timeout_ms;   /* 0: not started */
} wd = {.lock = PTHREAD_MUTEX_INITIALIZER};

static _Alignas(4096) unsigned char thread_stack[THREAD_STACK_BYTES];
static char *env_out[ENV_MAX];
static char env_watchdog[] = PMA_HAL_LINUX_RESET_CAUSE_ENV "=WATCHDOG";
static char env_software[] = PMA_HAL_LINUX_RESET_CAUSE_ENV "=SOFTWARE";

/* ------------------------------------------------------------ reset cause -- */

static const struct {
    const char *name;
    pma_reset_cause_t cause;
} cause_names[] = {
    {"POWER_ON", PMA_RESET_POWER_ON}, {"WATCHDOG", PMA_RESET_WATCHDOG},
    {"SOFTWARE", PMA_RESET_SOFTWARE}, {"PIN", PMA_RESET_PIN},
    {"BROWNOUT", PMA_RESET_BROWNOUT}, {"UNKNOWN", PMA_RESET_UNKNOWN},
};

pma_reset_cause_t pma_linux_reset_cause_parse(const char *value)
{
    if (value == NULL) return PMA_RESET_POWER_ON; /* a fresh start */
    for (size_t i = 0; i < sizeof cause_names / sizeof cause_names[0]; ++i) {
        if (strcmp(value, cause_names[i].name) == 0) return cause_names[i].cause;
    }
    return PMA_RESET_UNKNOWN;
}

void pma_linux_reset_cause_latch(void)
{
    if (wd.cause_latched) return;
    wd.cause = pma_linux_reset_cause_parse(getenv(PMA_HAL_LINUX_RESET_CAUSE_ENV));
    /* Programs this one starts must not inherit it, nor a later start see it. */
    (void)unsetenv(PMA_HAL_LINUX_RESET_CAUSE_ENV);
    wd.cause_latched = true;
}

pma_reset_cause_t pma_hal_reset_cause(void)
{
    pma_linux_reset_cause_latch();
    return wd.cause;
}

/* --------------------------------------------------------------- watchdog -- */

void pma_linux_watchdog_set_argv(char *const *argv)
{
    pthread_mutex_lock(&wd.lock);
    wd.argv = argv;
    pthread_mutex_unlock(&wd.lock);
}

/* The environment for the re-executed program: ours, with the reset cause. */
static char **reset_environment(char *cause)
{
    const size_t prefix_len = strlen(PMA_HAL_LINUX_RESET_CAUSE_ENV "=");
    size_t n = 0;
    for (char **e = environ; e != NULL && *e != NULL; ++e) {
        if (strncmp(*e, PMA_HAL_LINUX_RESET_CAUSE_ENV "=", prefix_len) == 0) continue;
        if (n + 2u > ENV_MAX) return NULL;
        env_out[n++] = *e;
    }
    env_out[n++] = cause;
    env_out[n] = NULL;
    return env_out;
}

/* Writes a message to stderr unbuffered (no stdio lock: the main thread may
 * hold it, stuck in the very place that made the watchdog expire). */
static void say(const char *msg, int len, size_t capacity)
{
    if (len <= 0) return;
    const size_t n = (size_t)len < capacity ? (size_t)len : capacity - 1u;
    while (write(STDERR_FILENO, msg, n) < 0 && errno == EINTR) {
    }
}

/* Re-executes the program with the reset cause `cause` (or exits with
 * exit_status without argv); never returns. */
static void reexecute(char *const *argv, char *cause, int exit_status)
{
    char msg[200];
    if (argv != NULL) {
        char **env = reset_environment(cause);
        if (env != NULL) {
            (void)pthread_sigmask(SIG_SETMASK, &wd.exec_mask, NULL);
            (void)execve("/proc/self/exe", argv, env);
        }
        say(msg,
            snprintf(msg, sizeof msg, "pma_hal_linux: reset: cannot re-execute: %s\n",
                     env != NULL ? strerror(errno) : "environment too large"),
            sizeof msg);
    }
    _exit(exit_status);
}

/* Called with wd.lock held; never returns. */
static void expire(void)
{
    char msg[200];
    say(msg,
        snprintf(msg, sizeof msg,
                 "pma_hal_linux: watchdog expired (no kick for more than %u ms): %s\n",
                 (unsigned)atomic_load(&wd.timeout_ms),
                 wd.argv != NULL ? "resetting (re-executing /proc/self/exe)"
                                 : "exiting (no argv to re-execute)"),
        sizeof msg);
    reexecute(wd.argv, env_watchdog, PMA_HAL_LINUX_EXIT_WATCHDOG);
}

void pma_hal_system_reset(void)
{
    pma_linux_can_flush(PMA_HAL_RESET_TX_FLUSH_US);
    pthread_mutex_lock(&wd.lock); /* the watchdog thread must not re-execute meanwhile */
    char *const *argv = wd.argv;
    if (!wd.thread_started) (void)pthread_sigmask(SIG_SETMASK, NULL, &wd.exec_mask);
    char msg[120];
    say(msg,
        snprintf(msg, sizeof msg, "pma_hal_linux: software reset: %s\n",
                 argv != NULL ? "re-executing /proc/self/exe" : "exiting (no argv to re-execute)"),
        sizeof msg);
    reexecute(argv, env_software, PMA_HAL_LINUX_EXIT_RESET);
}

static void *watchdog_main(void *arg)
{
    (void)arg;
    pthread_mutex_lock(&wd.lock);
    for (;;) {
        const uint64_t deadline_us =
            atomic_load(&wd.kick_us) + (uint64_t)atomic_load(&wd.timeout_ms) * 1000u;
        if (pma_hal_time_us() > deadline_us) break; /* "more than timeout_ms" */
        const uint64_t wake_us = deadline_us + 1u;
        const struct timespec at = {.tv_sec = (time_t)(wake_us / 1000000u),
                                    .tv_nsec = (long)(wake_us % 1000000u) * 1000L};
        /* woken by the deadline, a new timeout, or spuriously: check again */
        (void)pthread_cond_timedwait(&wd.wake, &wd.lock, &at);
    }
    expire();
    return NULL;
}

/* Starts the thread with every signal blocked (signals stay the main
 * thread's business) on the static stack. */
static int start_thread(void)
{
    pthread_condattr_t ca;
    int e = pthread_condattr_init(&ca);
    if (e == 0) {
        e = pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
        if (e == 0) e = pthread_cond_init(&wd.wake, &ca);
        (void)pthread_condattr_destroy(&ca);
    }
    if (e != 0) {
        pma_linux_set_error("pma_hal_linux: watchdog condition variable: %s", strerror(e));
        return PMA_ERR_IO;
    }
    pthread_attr_t ta;
    e = pthread_attr_init(&ta);
    if (e != 0) {
        (void)pthread_cond_destroy(&wd.wake);
        pma_linux_set_error("pma_hal_linux: watchdog thread attributes: %s", strerror(e));
        return PMA_ERR_IO;
    }
    e = pthread_attr_setstack(&ta, thread_stack, sizeof thread_stack);
    if (e == 0) e = pthread_attr_setdetachstate(&ta, PTHREAD_CREATE_DETACHED);
    sigset_t all;
    (void)sigfillset(&all);
    (void)pthread_sigmask(SIG_SETMASK, NULL, &wd.exec_mask);
    if (e == 0) {
        pthread_t t;
        (void)pthread_sigmask(SIG_SETMASK, &all, NULL);
        e = pthread_create(&t, &ta, watchdog_main, NULL);
        (void)pthread_sigmask(SIG_SETMASK, &wd.exec_mask, NULL);
    }
    (void)pthread_attr_destroy(&ta);
    if (e != 0) {
        (void)pthread_cond_destroy(&wd.wake);
        pma_linux_set_error("pma_hal_linux: watchdog thread: %s", strerror(e));
        return PMA_ERR_IO;
    }
    return PMA_OK;
}

int pma_hal_watchdog_start(uint32_t timeout_ms)
{
    if (timeout_ms == 0 || timeout_ms > PMA_HAL_LINUX_WATCHDOG_MAX_MS) return PMA_ERR_RANGE;
    int rc = PMA_OK;
    pthread_mutex_lock(&wd.lock);
    atomic_store(&wd.kick_us, pma_hal_time_us());
    atomic_store(&wd.timeout_ms, timeout_ms);
    if (!wd.thread_started) {
        rc = start_thread();
        if (rc == PMA_OK) {
            wd.thread_started = true;
        } else {
            atomic_store(&wd.timeout_ms, 0u);
        }
    } else {
        (void)pthread_cond_signal(&wd.wake); /* a shorter timeout must not wait for the old one */
    }
    pthread_mutex_unlock(&wd.lock);
    return rc;
}

void pma_hal_watchdog_kick(void)
{
    if (atomic_load(&wd.timeout_ms) != 0) atomic_store(&wd.kick_us, pma_hal_time_us());
}
