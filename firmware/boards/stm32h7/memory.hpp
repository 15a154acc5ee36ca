// Memory set-up of the STM32H743 image: the AXI SRAM section and the Cortex-M7 caches.
#pragma once

// Places a large object (an MPC workspace) in the 512 KB AXI SRAM instead of the 128 KB DTCM.
// The section is zeroed before C++ constructors run, so it behaves like .bss.
#define HMPC_AXI_SRAM __attribute__((section(".axisram")))

namespace hmpc::stm32h7 {

// Invalidates, then enables the L1 instruction and data caches (16 KB each). Flash and the
// AXI SRAM are cached; DTCM never is. Safe without an MPU set-up: nothing uses DMA, and the
// peripheral region (FDCAN registers and message RAM) is Device memory, never cached.
void enable_caches();

}  // namespace hmpc::stm32h7
