/* Cortex-M reset and vector table shared by every bare-metal board: enables the FPU before
 * any floating-point instruction can run, copies .data, zeroes .bss, paints the stack for a
 * high-water mark, runs C++ static constructors, then main(). */
#include <stdint.h>

#ifndef HMPC_NUM_IRQ
#define HMPC_NUM_IRQ 32
#endif
#define STACK_PAINT 0xA5A5A5A5u

extern uint32_t _sidata[], _sdata[], _edata[], _sbss[], _ebss[], _sstack[], _estack[];
extern void (*__preinit_array_start[])(void), (*__preinit_array_end[])(void);
extern void (*__init_array_start[])(void), (*__init_array_end[])(void);
int main(void);
void Reset_Handler(void);

/* Boards override this to put their outputs in a safe state and report. */
__attribute__((weak, noreturn)) void hmpc_fatal(const char *what) {
  (void)what;
  for (;;) {
  }
}

static void default_handler(void) { hmpc_fatal("unexpected interrupt\n"); }
static void hard_fault_handler(void) { hmpc_fatal("hard fault\n"); }
void NMI_Handler(void) __attribute__((weak, alias("default_handler")));
void HardFault_Handler(void) __attribute__((weak, alias("hard_fault_handler")));
void MemManage_Handler(void) __attribute__((weak, alias("hard_fault_handler")));
void BusFault_Handler(void) __attribute__((weak, alias("hard_fault_handler")));
void UsageFault_Handler(void) __attribute__((weak, alias("hard_fault_handler")));
void SVC_Handler(void) __attribute__((weak, alias("default_handler")));
void DebugMon_Handler(void) __attribute__((weak, alias("default_handler")));
void PendSV_Handler(void) __attribute__((weak, alias("default_handler")));
void SysTick_Handler(void) __attribute__((weak, alias("default_handler")));

typedef void (*vector_t)(void);
__attribute__((section(".isr_vector"), used)) const vector_t hmpc_vectors[16 + HMPC_NUM_IRQ] = {
    (vector_t)_estack,
    Reset_Handler,
    NMI_Handler,
    HardFault_Handler,
    MemManage_Handler,
    BusFault_Handler,
    UsageFault_Handler,
    0,
    0,
    0,
    0,
    SVC_Handler,
    DebugMon_Handler,
    0,
    PendSV_Handler,
    SysTick_Handler,
    [16 ... 16 + HMPC_NUM_IRQ - 1] = default_handler,
};

static __attribute__((noreturn, used)) void reset_continue(void) {
  /* The linker script's section bounds: one region each, which cppcheck cannot know. */
  /* cppcheck-suppress comparePointers */
  for (uint32_t *src = _sidata, *dst = _sdata; dst < _edata;) *dst++ = *src++;
  /* cppcheck-suppress comparePointers */
  for (uint32_t *dst = _sbss; dst < _ebss;) *dst++ = 0;
  uint32_t *sp;
  __asm__ volatile("mov %0, sp" : "=r"(sp));
  for (uint32_t *p = _sstack; p < sp - 16; ++p) *p = STACK_PAINT;
  for (void (**f)(void) = __preinit_array_start; f < __preinit_array_end; ++f) (*f)();
  for (void (**f)(void) = __init_array_start; f < __init_array_end; ++f) (*f)();
  (void)main();
  hmpc_fatal("main returned\n");
}

/* Naked: the compiler may not emit FP instructions before CPACR grants access to CP10/11. */
__attribute__((naked, noreturn)) void Reset_Handler(void) {
#if defined(__ARM_FP)
  __asm__ volatile(
      "ldr r0, =0xE000ED88\n"
      "ldr r1, [r0]\n"
      "orr r1, r1, #(0xF << 20)\n"
      "str r1, [r0]\n"
      "dsb\n"
      "isb\n");
#endif
  __asm__ volatile("b reset_continue");
}

/* Bytes of stack ever used: the painted words the stack never overwrote are unused. */
uint32_t hmpc_stack_high_water(void) {
  const uint32_t *p = _sstack;
  /* cppcheck-suppress comparePointers ; both bound the one stack region */
  while (p < _estack && *p == STACK_PAINT) ++p;
  return (uint32_t)((uintptr_t)_estack - (uintptr_t)p);
}

/* newlib's abort() drags in signals and _kill/_getpid; a firmware abort is a fatal fault. */
void abort(void) { hmpc_fatal("abort\n"); }
