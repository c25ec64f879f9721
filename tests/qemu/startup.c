/* SPDX-License-Identifier: Apache-2.0 */
/*
 * Bare-metal startup for the emulated boards (QEMU mps2-an385/an386, microbit), used only by
 * test and benchmark executables (linked through the `pma_board` library, cmake/PmaTest.cmake).
 *
 *   - vector table (placed at address 0 by pma_sections.ld) and Reset_Handler: enable the FPU
 *     (Cortex-M4F), copy .data, zero .bss, set up newlib's semihosting I/O (rdimon), run the
 *     constructors, call main and exit() with its return value: QEMU exits with that status;
 *   - every other exception (HardFault, NMI, MemManage/BusFault/UsageFault, SVC, PendSV,
 *     SysTick, IRQs) prints a report on the semihosting console and makes QEMU exit with
 *     PMA_BOARD_FAULT_EXIT_STATUS. The names are weak: a test may define its own handler;
 *   - _sbrk: newlib's heap, bounded by the linker script (__pma_heap_start..__pma_heap_end,
 *     which ends where the stack region begins), so malloc fails cleanly instead of running
 *     into the stack; the whole region is handed to malloc at start-up (heap_claim_all);
 *   - a guard at the bottom of the stack, checked at exit: a program that overflowed its stack
 *     fails even if nothing else noticed.
 */
#include <errno.h>
#include <limits.h>
#include <malloc.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

#include "pma_board.h"

#ifndef PMA_BOARD_NAME
#define PMA_BOARD_NAME "qemu"
#endif

/* Linker script symbols (pma_sections.ld). */
extern uint32_t __pma_data_load[];
extern uint32_t __pma_data_start[];
extern uint32_t __pma_data_end[];
extern uint32_t __pma_bss_start[];
extern uint32_t __pma_bss_end[];
extern char __pma_heap_start[];
extern char __pma_heap_end[];
extern uint32_t __pma_stack_limit[];
extern uint32_t __pma_stack_top[];

/* newlib */
extern void initialise_monitor_handles(void);
extern void __libc_init_array(void);
void *_sbrk(ptrdiff_t incr);
void _init(void);
void _fini(void);

int main(void);

void Reset_Handler(void);
void pma_exception_entry(void);
void pma_exception_report(const uint32_t *frame, uint32_t exc_return);

/* ---------------------------------------------------------------------------------------- */
/* Semihosting (ARM semihosting v2, BKPT 0xAB on M-profile), used directly where the C library
 * cannot be trusted any more (faults). */
#define SEMIHOST_SYS_WRITE0 0x04u
#define SEMIHOST_SYS_EXIT 0x18u
#define SEMIHOST_SYS_EXIT_EXTENDED 0x20u
#define ADP_STOPPED_APPLICATION_EXIT 0x20026u
#define ADP_STOPPED_RUNTIME_ERROR_UNKNOWN 0x20023u

static uint32_t semihost(uint32_t op, const void *arg)
{
    register uint32_t r0 __asm__("r0") = op;
    register const void *r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

static void semihost_puts(const char *s)
{
    semihost(SEMIHOST_SYS_WRITE0, s);
}

__attribute__((noreturn)) static void semihost_exit(uint32_t status)
{
    const uint32_t block[2] = {ADP_STOPPED_APPLICATION_EXIT, status};
    semihost(SEMIHOST_SYS_EXIT_EXTENDED, block);
    /* Only reached if the debugger does not know SYS_EXIT_EXTENDED: plain failure. */
    semihost(SEMIHOST_SYS_EXIT, (const void *)(uintptr_t)ADP_STOPPED_RUNTIME_ERROR_UNKNOWN);
    for (;;) {
    }
}

/* ---------------------------------------------------------------------------------------- */
/* Fault and unexpected-exception reporting. */

static char *put_str(char *p, const char *s)
{
    while (*s != '\0') {
        *p++ = *s++;
    }
    return p;
}

static char *put_hex(char *p, uint32_t v)
{
    static const char digits[] = "0123456789abcdef";
    p = put_str(p, "0x");
    for (int shift = 28; shift >= 0; shift -= 4) {
        *p++ = digits[(v >> shift) & 0xFu];
    }
    return p;
}

static char *put_dec(char *p, uint32_t v)
{
    char tmp[10];
    int n = 0;
    do {
        tmp[n++] = (char)('0' + v % 10u);
        v /= 10u;
    } while (v != 0u);
    while (n > 0) {
        *p++ = tmp[--n];
    }
    return p;
}

static const char *exception_name(uint32_t n)
{
    switch (n) {
    case 2:
        return "NMI";
    case 3:
        return "HardFault";
    case 4:
        return "MemManage";
    case 5:
        return "BusFault";
    case 6:
        return "UsageFault";
    case 11:
        return "SVCall";
    case 12:
        return "DebugMonitor";
    case 14:
        return "PendSV";
    case 15:
        return "SysTick";
    default:
        return n >= 16u ? "IRQ" : "exception";
    }
}

/* Called by pma_exception_entry with the stacked frame (r0-r3, r12, lr, pc, xpsr). */
__attribute__((used, noreturn)) void pma_exception_report(const uint32_t *frame,
                                                          uint32_t exc_return)
{
    static char buf[256];
    uint32_t ipsr;
    __asm__ volatile("mrs %0, ipsr" : "=r"(ipsr));
    ipsr &= 0x1FFu;

    char *p = buf;
    p = put_str(p, "\n*** ");
    p = put_str(p, PMA_BOARD_NAME);
    p = put_str(p, ": ");
    p = put_str(p, exception_name(ipsr));
    p = put_str(p, " (exception ");
    p = put_dec(p, ipsr);
    if (ipsr >= 16u) {
        p = put_str(p, ", IRQ ");
        p = put_dec(p, ipsr - 16u);
    }
    p = put_str(p, ")\n    pc=");
    p = put_hex(p, frame[6]);
    p = put_str(p, " lr=");
    p = put_hex(p, frame[5]);
    p = put_str(p, " xpsr=");
    p = put_hex(p, frame[7]);
    p = put_str(p, " sp=");
    p = put_hex(p, (uint32_t)(uintptr_t)frame);
    p = put_str(p, " exc_return=");
    p = put_hex(p, exc_return);
#if defined(__ARM_ARCH_7M__) || defined(__ARM_ARCH_7EM__)
    p = put_str(p, "\n    cfsr=");
    p = put_hex(p, *(volatile uint32_t *)0xE000ED28u);
    p = put_str(p, " hfsr=");
    p = put_hex(p, *(volatile uint32_t *)0xE000ED2Cu);
    p = put_str(p, " mmfar=");
    p = put_hex(p, *(volatile uint32_t *)0xE000ED34u);
    p = put_str(p, " bfar=");
    p = put_hex(p, *(volatile uint32_t *)0xE000ED38u);
#endif
    p = put_str(p, "\n*** exiting with status ");
    p = put_dec(p, PMA_BOARD_FAULT_EXIT_STATUS);
    p = put_str(p, "\n");
    *p = '\0';
    semihost_puts(buf);
    semihost_exit(PMA_BOARD_FAULT_EXIT_STATUS);
}

/* Common entry of all exceptions but reset: find the stacked frame (MSP or PSP, EXC_RETURN
 * bit 2) and report. Thumb-1 only, so it assembles for Cortex-M0 too. */
__attribute__((naked)) void pma_exception_entry(void)
{
    __asm__ volatile("movs r0, #4\n\t"
                     "mov  r1, lr\n\t"
                     "tst  r0, r1\n\t"
                     "beq  1f\n\t"
                     "mrs  r0, psp\n\t"
                     "b    2f\n"
                     "1:\n\t"
                     "mrs  r0, msp\n"
                     "2:\n\t"
                     "bl   pma_exception_report\n");
}

#define PMA_WEAK_HANDLER(name) void name(void) __attribute__((weak, alias("pma_exception_entry")))
PMA_WEAK_HANDLER(NMI_Handler);
PMA_WEAK_HANDLER(HardFault_Handler);
PMA_WEAK_HANDLER(MemManage_Handler);
PMA_WEAK_HANDLER(BusFault_Handler);
PMA_WEAK_HANDLER(UsageFault_Handler);
PMA_WEAK_HANDLER(SVC_Handler);
PMA_WEAK_HANDLER(DebugMon_Handler);
PMA_WEAK_HANDLER(PendSV_Handler);
PMA_WEAK_HANDLER(SysTick_Handler);
PMA_WEAK_HANDLER(Default_Handler);

/* ---------------------------------------------------------------------------------------- */
/* Vector table: initial SP, 15 system exceptions, 32 external interrupts (mps2 and nRF51 both
 * have 32). Nothing enables an interrupt; any that fires is reported as unexpected. */
#define PMA_8_DEFAULT                                                                      \
    Default_Handler, Default_Handler, Default_Handler, Default_Handler, Default_Handler,       \
        Default_Handler, Default_Handler, Default_Handler
typedef void (*pma_handler_t)(void);
struct pma_vector_table {
    uint32_t *initial_sp;
    pma_handler_t handler[15 + 32];
};

__attribute__((section(".isr_vector"), used)) const struct pma_vector_table __pma_vectors = {
    __pma_stack_top,
    {
        Reset_Handler,
        NMI_Handler,
        HardFault_Handler,
        MemManage_Handler, /* reserved on ARMv6-M */
        BusFault_Handler,  /* reserved on ARMv6-M */
        UsageFault_Handler, /* reserved on ARMv6-M */
        0,
        0,
        0,
        0,
        SVC_Handler,
        DebugMon_Handler, /* reserved on ARMv6-M */
        0,
        PendSV_Handler,
        SysTick_Handler,
        PMA_8_DEFAULT, PMA_8_DEFAULT, PMA_8_DEFAULT, PMA_8_DEFAULT, /* IRQ 0..31 */
    },
};

/* ---------------------------------------------------------------------------------------- */
/* Stack guard, heap set-up, and stack/heap high-water marks (printed at exit when built with
 * PMA_BOARD_MEMORY_REPORT=1: CMake option PMA_QEMU_MEMORY_REPORT=ON). */
#define STACK_GUARD_WORDS 8u
#define STACK_GUARD_PATTERN 0xC0DEFA11u
#define PAINT_PATTERN 0xA5A5A5A5u
#define HEAP_PAINT_SKIP 64u /* bytes at the heap start that malloc's bookkeeping uses */

static char *heap_brk = __pma_heap_start;

#if defined(PMA_BOARD_MEMORY_REPORT) && PMA_BOARD_MEMORY_REPORT
static void paint(uint32_t *from, const uint32_t *to)
{
    while (from < to) {
        *from++ = PAINT_PATTERN;
    }
}

static void memory_report(void)
{
    const uint32_t *q = __pma_stack_limit + STACK_GUARD_WORDS;
    while (q < __pma_stack_top && *q == PAINT_PATTERN) {
        q++;
    }
    uint32_t stack_used = (uint32_t)((const char *)__pma_stack_top - (const char *)q);
    const uint32_t *h = (const uint32_t *)(const void *)__pma_heap_end;
    const uint32_t *h_min = (const uint32_t *)(const void *)(__pma_heap_start + HEAP_PAINT_SKIP);
    while (h > h_min && h[-1] == PAINT_PATTERN) {
        h--;
    }
    uint32_t heap_used = (uint32_t)((const char *)h - __pma_heap_start);

    static char buf[160];
    char *p = put_str(buf, "[pma_board] peak stack ");
    p = put_dec(p, stack_used);
    p = put_str(p, " of ");
    p = put_dec(p, (uint32_t)((const char *)__pma_stack_top - (const char *)__pma_stack_limit));
    p = put_str(p, " B, peak heap extent ");
    p = put_dec(p, heap_used);
    p = put_str(p, " of ");
    p = put_dec(p, (uint32_t)(__pma_heap_end - __pma_heap_start));
    p = put_str(p, " B\n");
    *p = '\0';
    semihost_puts(buf);
}
#endif

/* newlib's malloc grows its arena with _sbrk in 4 KB steps after the first one, and fails when
 * a whole step no longer fits: up to 4 KB of the heap would stay unusable, a third of it on the
 * 16 KB microbit. So take the whole heap region into the arena at start-up (malloc the largest
 * block that fits, free it) with trimming off: afterwards every byte of it can be allocated. */
static void heap_claim_all(void)
{
    mallopt(M_TRIM_THRESHOLD, INT_MAX);
    size_t avail = (size_t)(__pma_heap_end - __pma_heap_start);
    for (size_t n = avail; n >= 64u; n -= 64u) {
        void *p = malloc(n);
        if (p != NULL) {
            free(p);
            break;
        }
    }
    errno = 0;
}

static void stack_guard_check(void)
{
    for (uint32_t i = 0; i < STACK_GUARD_WORDS; i++) {
        if (__pma_stack_limit[i] != STACK_GUARD_PATTERN) {
            static char buf[128];
            char *p = put_str(buf, "\n*** " PMA_BOARD_NAME
                                   ": stack overflow (guard at ");
            p = put_hex(p, (uint32_t)(uintptr_t)__pma_stack_limit);
            p = put_str(p, " overwritten): exiting with status ");
            p = put_dec(p, PMA_BOARD_FAULT_EXIT_STATUS);
            p = put_str(p, "\n");
            *p = '\0';
            semihost_puts(buf);
            semihost_exit(PMA_BOARD_FAULT_EXIT_STATUS);
        }
    }
}

/* ---------------------------------------------------------------------------------------- */
/* newlib hooks. */

void *_sbrk(ptrdiff_t incr)
{
    char *prev = heap_brk;
    size_t room = (size_t)(__pma_heap_end - heap_brk);
    size_t used = (size_t)(heap_brk - __pma_heap_start);
    if ((incr > 0 && (size_t)incr > room) || (incr < 0 && (size_t)(-incr) > used)) {
        errno = ENOMEM;
        return (void *)-1;
    }
    heap_brk += incr;
    return prev;
}

/* No crti/crtn (-nostartfiles): nothing runs from .init/.fini. */
void _init(void)
{
}

void _fini(void)
{
}

/* ---------------------------------------------------------------------------------------- */

void Reset_Handler(void)
{
#if defined(__ARM_FP)
    /* CPACR: full access to CP10 and CP11, before any floating-point instruction. */
    *(volatile uint32_t *)0xE000ED88u |= 0xFu << 20;
    __asm__ volatile("dsb\n\tisb" ::: "memory");
#endif
    for (uint32_t *src = __pma_data_load, *dst = __pma_data_start; dst < __pma_data_end;) {
        *dst++ = *src++;
    }
    for (uint32_t *dst = __pma_bss_start; dst < __pma_bss_end;) {
        *dst++ = 0u;
    }
    for (uint32_t i = 0; i < STACK_GUARD_WORDS; i++) {
        __pma_stack_limit[i] = STACK_GUARD_PATTERN;
    }

    initialise_monitor_handles();
    __libc_init_array();
    heap_claim_all();
    atexit(stack_guard_check); /* atexit handlers run last-registered first */

#if defined(PMA_BOARD_MEMORY_REPORT) && PMA_BOARD_MEMORY_REPORT
    {
        /* Paint the free stack (below this frame) and the free heap for the high-water marks. */
        uint32_t sp;
        __asm__ volatile("mov %0, sp" : "=r"(sp));
        paint(__pma_stack_limit + STACK_GUARD_WORDS, (const uint32_t *)(uintptr_t)(sp - 64u));
        paint((uint32_t *)(void *)(__pma_heap_start + HEAP_PAINT_SKIP),
              (const uint32_t *)(const void *)__pma_heap_end);
        atexit(memory_report);
    }
#endif

    exit(main());
}
