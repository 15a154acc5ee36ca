/* ARM semihosting on M-profile (BKPT 0xAB): console output and exit status for images run
 * under QEMU or a debug probe. On a board with no debugger attached BKPT hard-faults, so
 * only test images use it. */
#pragma once
#include <stdint.h>
#ifdef __cplusplus
extern "C" {
#endif
static inline int hmpc_semihost_call(int op, const void *arg) {
  register int r0 __asm__("r0") = op;
  register const void *r1 __asm__("r1") = arg;
  __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
  return r0;
}
static inline void hmpc_semihost_write(const char *text) { hmpc_semihost_call(0x04, text); }
/* SYS_EXIT_EXTENDED (0x20): ADP_Stopped_ApplicationExit with a real status code. */
static inline __attribute__((noreturn)) void hmpc_semihost_exit(int status) {
  const uint32_t block[2] = {0x20026u, (uint32_t)status};
  hmpc_semihost_call(0x20, block);
  for (;;) {
  }
}
#ifdef __cplusplus
}
#endif
