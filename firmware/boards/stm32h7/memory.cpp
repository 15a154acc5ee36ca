// AXI SRAM zeroing and L1 cache enabling (ARMv7-M ARM, cache maintenance operations).
#include "memory.hpp"

#include <cstdint>

#include "registers.hpp"

extern "C" std::uint32_t _saxisram[], _eaxisram[];

namespace hmpc::stm32h7 {
namespace {

// startup.c zeroes only .bss; .axisram is NOLOAD in another region. Running from
// .preinit_array zeroes it before any static constructor can build an object there.
void zero_axi_sram() {
  for (std::uint32_t* word = _saxisram; word < _eaxisram; ++word) *word = 0;
}
__attribute__((section(".preinit_array"),
               used)) void (*const zero_axi_sram_at_boot)() = zero_axi_sram;

}  // namespace

void enable_caches() {
  // Instruction cache: invalidate all, then enable.
  dsb();
  isb();
  scb::ICIALLU() = 0;
  dsb();
  isb();
  scb::CCR() = scb::CCR() | scb::kCcrIc;
  dsb();
  isb();

  // Data cache: its contents are undefined after reset, so every line is invalidated by
  // set and way before enabling (CCSIDR: sets in [27:13], ways in [12:3], line size [2:0]).
  scb::CSSELR() = 0;
  dsb();
  const std::uint32_t ccsidr = scb::CCSIDR();
  const std::uint32_t sets = ((ccsidr >> 13) & 0x7FFFu) + 1;
  const std::uint32_t ways = ((ccsidr >> 3) & 0x3FFu) + 1;
  const std::uint32_t set_shift = (ccsidr & 0x7u) + 4;  // log2 of the line size in bytes
  const std::uint32_t way_shift =
      ways > 1 ? static_cast<std::uint32_t>(__builtin_clz(ways - 1)) : 0;
  for (std::uint32_t set = 0; set < sets; ++set)
    for (std::uint32_t way = 0; way < ways; ++way)
      scb::DCISW() = (way << way_shift) | (set << set_shift);
  dsb();
  scb::CCR() = scb::CCR() | scb::kCcrDc;
  dsb();
  isb();
}

}  // namespace hmpc::stm32h7
