/* SPDX-License-Identifier: Apache-2.0 */
/*
 * The xstate shim of tools/vcan/with-vcan, an LD_PRELOAD library for linux.uml.
 *
 * linux.uml saves and restores a guest task's FPU/vector registers with PTRACE_[GS]ETREGSET NT_X86_XSTATE and a buffer sized for
 * the features it knows (2696 bytes on an AVX-512 host; 832 in older UML).
 * Host kernels since 5.14 refuse a SETREGSET that is not exactly their
 * full XSAVE size (11008 bytes with AMX) with EFAULT: the guest panics at
 * once ("userspace - ptrace set fp regs failed, errno = 14"). This
 * LD_PRELOAD library keeps a full-size copy per UML register buffer (one
 * per guest task), so what lies beyond UML's part (AMX tiles, or the
 * AVX-512 state an older UML omits) is kept per task, and hands the host
 * whole buffers. Calls whose size already fits pass through unchanged.
 *
 * Built by with-vcan at run time (gcc -std=gnu11 -Wall -Wextra), and by the host build with
 * the project's warnings as errors (tools/vcan/CMakeLists.txt), so a warning is seen in CI.
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <elf.h>
#include <errno.h>
#include <stdarg.h>
#include <stdint.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/ptrace.h>
#include <sys/syscall.h>
#include <sys/types.h>
#include <sys/uio.h>
#include <unistd.h>

#define SLOTS 8192u
#define PROBE (1u << 16)

struct slot {
    const void *key; /* UML's register buffer (one per guest task) */
    unsigned char *buf; /* full-size copy of that task's XSAVE state */
};

static struct slot table[SLOTS];
static size_t full_size; /* host XSAVE size, learnt on first use */
static unsigned char *scratch;

static long sys_ptrace(long req, pid_t pid, void *addr, void *data)
{
    return syscall(SYS_ptrace, req, (long)pid, addr, data);
}

static void *page_alloc(size_t n)
{
    void *p = mmap(NULL, n, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    return p == MAP_FAILED ? NULL : p;
}

static int xstate_get(pid_t pid, unsigned char *buf, size_t len)
{
    struct iovec iov = { buf, len };
    return (int)sys_ptrace(PTRACE_GETREGSET, pid, (void *)(uintptr_t)NT_X86_XSTATE, &iov);
}

static int learn_size(pid_t pid)
{
    if (full_size)
        return 0;
    unsigned char *probe = page_alloc(PROBE);
    if (!probe)
        return -1;
    struct iovec iov = { probe, PROBE };
    long r = sys_ptrace(PTRACE_GETREGSET, pid, (void *)(uintptr_t)NT_X86_XSTATE, &iov);
    if (r == 0)
        full_size = iov.iov_len;
    munmap(probe, PROBE);
    return r == 0 ? 0 : -1;
}

static unsigned char *slot_buffer(const void *key, int create)
{
    uintptr_t h = ((uintptr_t)key >> 4) * (uintptr_t)0x9E3779B97F4A7C15ull;
    for (unsigned i = 0; i < SLOTS; i++) {
        struct slot *s = &table[(h + i) % SLOTS];
        if (s->key == key)
            return s->buf;
        if (!s->key) {
            if (!create)
                return NULL;
            unsigned char *b = page_alloc(full_size);
            if (!b)
                return NULL;
            s->key = key;
            s->buf = b;
            return b;
        }
    }
    return NULL; /* table full: callers fall back to the scratch buffer */
}

static unsigned char *scratch_buffer(void)
{
    if (!scratch)
        scratch = page_alloc(full_size);
    return scratch;
}

/* 1 if handled (result in *ret), 0 to pass the call through. */
static int xstate(long req, pid_t pid, struct iovec *iov, long *ret)
{
    if (learn_size(pid) != 0 || iov->iov_len >= full_size)
        return 0;
    size_t n = iov->iov_len;
    unsigned char *b;
    if (req == PTRACE_GETREGSET) {
        b = slot_buffer(iov->iov_base, 1);
        if (!b && !(b = scratch_buffer()))
            return 0;
        *ret = xstate_get(pid, b, full_size);
        if (*ret == 0)
            memcpy(iov->iov_base, b, n);
        return 1;
    }
    /* PTRACE_SETREGSET: the host kernel takes only a whole buffer. Complete
       UML's part with what this task had (or has now) beyond it. */
    b = slot_buffer(iov->iov_base, 0);
    if (!b) {
        if (!(b = scratch_buffer()) || xstate_get(pid, b, full_size) != 0)
            return 0;
    }
    memcpy(b, iov->iov_base, n);
    struct iovec big = { b, full_size };
    *ret = sys_ptrace(PTRACE_SETREGSET, pid, (void *)(uintptr_t)NT_X86_XSTATE, &big);
    return 1;
}

long ptrace(enum __ptrace_request req, ...)
{
    static long (*next)(enum __ptrace_request, ...);
    va_list ap;
    va_start(ap, req);
    pid_t pid = va_arg(ap, pid_t);
    void *addr = va_arg(ap, void *);
    void *data = va_arg(ap, void *);
    va_end(ap);

    if ((req == PTRACE_GETREGSET || req == PTRACE_SETREGSET) &&
        (uintptr_t)addr == NT_X86_XSTATE && data) {
        long ret;
        int saved = errno;
        if (xstate(req, pid, data, &ret))
            return ret;
        errno = saved;
    }
    if (!next)
        next = (long (*)(enum __ptrace_request, ...))dlsym(RTLD_NEXT, "ptrace");
    return next(req, pid, addr, data);
}
