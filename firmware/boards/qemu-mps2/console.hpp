// Line-buffered semihosting console for QEMU test images. Formats integers and raw IEEE
// bits itself: newlib's printf of floating point allocates.
#pragma once

#include <cstdint>
#include <cstring>
#include <type_traits>

#include "semihosting.h"

namespace hmpc::qemu {

class Console {
 public:
  Console& operator<<(const char* text) {
    while (*text && length_ < kCapacity - 2) line_[length_++] = *text++;
    return *this;
  }
  template <typename Integer, typename = std::enable_if_t<std::is_integral_v<Integer>>>
  Console& operator<<(Integer value) {
    std::uint64_t magnitude = static_cast<std::uint64_t>(value);
    if constexpr (std::is_signed_v<Integer>) {
      if (value < 0) {
        *this << "-";
        magnitude = static_cast<std::uint64_t>(-static_cast<std::int64_t>(value));
      }
    }
    char digits[24];
    int n = 0;
    do {
      digits[n++] = static_cast<char>('0' + magnitude % 10);
      magnitude /= 10;
    } while (magnitude != 0);
    while (n > 0 && length_ < kCapacity - 2) line_[length_++] = digits[--n];
    return *this;
  }

  // Exact bits of a double or float as hexadecimal, for bit-level comparison with the host.
  template <typename Scalar>
  Console& bits(Scalar value) {
    std::uint64_t raw = 0;
    std::memcpy(&raw, &value, sizeof(Scalar));
    for (int i = static_cast<int>(2 * sizeof(Scalar)) - 1; i >= 0 && length_ < kCapacity - 2; --i)
      line_[length_++] = "0123456789abcdef"[(raw >> (4 * i)) & 0xF];
    return *this;
  }

  void end_line() {
    line_[length_++] = '\n';
    line_[length_] = '\0';
    hmpc_semihost_write(line_);
    length_ = 0;
  }

 private:
  static constexpr int kCapacity = 192;
  char line_[kCapacity];
  int length_ = 0;
};

// SysTick driven by the processor clock, extended to 64 bits by counting wraps.
class InstructionCounter {
 public:
  void start() {
    *kReload = 0xFFFFFFu;
    *kCurrent = 0;
    *kControl = 0x7;  // enable | interrupt on wrap | processor clock
  }
  std::uint64_t ticks() const {
    std::uint32_t high_before, low, high_after;
    do {
      high_before = wraps;
      low = *kCurrent;
      high_after = wraps;
    } while (high_before != high_after);
    return (static_cast<std::uint64_t>(high_before) << 24) + (0xFFFFFFu - low);
  }
  static volatile std::uint32_t wraps;

 private:
  static inline volatile std::uint32_t* const kControl =
      reinterpret_cast<volatile std::uint32_t*>(0xE000E010);
  static inline volatile std::uint32_t* const kReload =
      reinterpret_cast<volatile std::uint32_t*>(0xE000E014);
  static inline volatile std::uint32_t* const kCurrent =
      reinterpret_cast<volatile std::uint32_t*>(0xE000E018);
};

}  // namespace hmpc::qemu
