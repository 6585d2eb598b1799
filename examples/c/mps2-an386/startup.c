/* Start-up for the C examples on QEMU's mps2-an386 (Cortex-M4F) with newlib and semihosting: the
 * vector table, the FPU switched on, .bss cleared, newlib's semihosting standard streams opened,
 * main() run and its status returned to QEMU. Any fault ends the run with status 1 instead of
 * hanging QEMU. Linked with link.ld, `--specs=rdimon.specs -nostartfiles`.
 *
 * It also measures the program's deepest stack: the free RAM between the heap's reserve and the
 * stack is painted with a pattern before main(), and at exit the lowest word no longer holding it
 * tells how far the stack reached (`stack high-water: N bytes` on standard error). */

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
extern uint32_t __bss_start__, __bss_end__, __stack_top;
extern uint32_t end[]; /* the start of newlib's heap (link.ld) */
extern void *sbrk(ptrdiff_t increment);
extern int main(void);
extern void initialise_monitor_handles(void);
extern void __libc_init_array(void);

/* newlib's __libc_init_array calls these (gcc's crti/crtn are left out with -nostartfiles). */
void _init(void) {}
void _fini(void) {}

/* Ends the run through semihosting's SYS_EXIT with "run-time error": QEMU exits with status 1. */
static void fault(void) {
    register uint32_t op __asm__("r0") = 0x18;        /* SYS_EXIT */
    register uint32_t arg __asm__("r1") = 0x20023;    /* ADP_Stopped_RunTimeErrorUnknown */
    __asm__ volatile("bkpt 0xab" : : "r"(op), "r"(arg) : "memory");
    for (;;) {
    }
}

/* The heap (stdio's buffers) stays below this many bytes above `end`; the stack above it. */
enum { HEAP_RESERVE = 256 * 1024 };
static const uint32_t PAINT = 0xA5A5A5A5u;

static uint32_t *paint_start(void) { return end + HEAP_RESERVE / sizeof(uint32_t); }

static void report_stack(void) {
    const uint32_t *p = paint_start();
    while (p < &__stack_top && *p == PAINT) {
        p++;
    }
    if ((char *)sbrk(0) > (char *)paint_start()) {
        fprintf(stderr, "stack high-water: unknown (the heap grew past its reserve)\n");
    } else {
        fprintf(stderr, "stack high-water: %lu bytes\n", (unsigned long)((const char *)&__stack_top - (const char *)p));
    }
}

void reset_handler(void) {
    uint32_t *p, *sp;
    /* CPACR: full access to CP10 and CP11, the FPU, before any floating-point instruction. */
    *(volatile uint32_t *)0xE000ED88 |= 0xFu << 20;
    __asm__ volatile("dsb\n\tisb" ::: "memory");
    memset(&__bss_start__, 0, (size_t)((char *)&__bss_end__ - (char *)&__bss_start__));
    __asm__ volatile("mov %0, sp" : "=r"(sp));
    for (p = paint_start(); p < sp - 16; p++) {
        *p = PAINT;
    }
    initialise_monitor_handles();
    __libc_init_array();
    atexit(report_stack);
    exit(main());
}

void nmi_handler(void) { fault(); }
void hard_fault_handler(void) { fault(); }
void other_handler(void) { fault(); }

/* Initial stack pointer, reset, then the other exceptions of the Cortex-M4 (as addresses: ISO C
 * has no conversion between object and function pointers). */
__attribute__((section(".vectors"), used)) static const uintptr_t vectors[16] = {
    (uintptr_t)&__stack_top,
    (uintptr_t)reset_handler,
    (uintptr_t)nmi_handler,
    (uintptr_t)hard_fault_handler,
    (uintptr_t)other_handler, /* MemManage */
    (uintptr_t)other_handler, /* BusFault */
    (uintptr_t)other_handler, /* UsageFault */
    0, 0, 0, 0,
    (uintptr_t)other_handler, /* SVCall */
    (uintptr_t)other_handler, /* DebugMonitor */
    0,
    (uintptr_t)other_handler, /* PendSV */
    (uintptr_t)other_handler, /* SysTick */
};
