// Cortex-M test image: the Sec. 2.4 MPCs closed loop on the target's FPU, reporting results
// (exact bits) for comparison with the host and instructions per MPC update counted by
// SysTick under QEMU -icount shift=0.
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "console.hpp"
#include "sec24_runs.hpp"

#ifndef HMPC_SCALAR
#define HMPC_SCALAR double
#endif
using Scalar = HMPC_SCALAR;

volatile std::uint32_t hmpc::qemu::InstructionCounter::wraps = 0;
extern "C" void SysTick_Handler(void) {
  hmpc::qemu::InstructionCounter::wraps = hmpc::qemu::InstructionCounter::wraps + 1;
}
extern "C" std::uint32_t hmpc_stack_high_water(void);
extern "C" [[noreturn]] void hmpc_fatal(const char* what) {
  hmpc_semihost_write(what);
  hmpc_semihost_exit(99);
}

namespace {

using hmpc::qemu::Console;
using hmpc::qemu::InstructionCounter;

Console console;
InstructionCounter counter;
std::uint64_t instructions_per_tick_x1000 = 0;
std::uint32_t update_instructions[hmpc::sec24::kSamples];

// Exactly two instructions per iteration: calibrates instructions per SysTick tick.
__attribute__((noinline)) void spin(std::uint32_t n) {
  __asm__ volatile("1: subs %0, %0, #1\n bne 1b" : "+r"(n) : : "cc");
}

struct TickObserver {
  std::uint64_t start = 0;
  void before_update(int) { start = counter.ticks(); }
  template <class Vector, class Mpc>
  void after_update(int k, const Vector&, const Vector&, const Mpc&) {
    const std::uint64_t ticks = counter.ticks() - start;
    update_instructions[k] = static_cast<std::uint32_t>(ticks * instructions_per_tick_x1000 / 1000);
  }
};

struct Report {
  bool ok = true;
  template <class Outcome>
  void method(const char* name, const Outcome& outcome, const hmpc::sec24::check::Totals& t) {
    console << "result " << name << " final_y " ;
    console.bits(outcome.final_state(0)).end_line();
    console << "result " << name << " final_z ";
    console.bits(outcome.final_state(1)).end_line();
    console << "result " << name << " cost ";
    console.bits(outcome.accumulated_cost).end_line();
    console << "count " << name << " iterations " << static_cast<std::int64_t>(t.iterations)
            << " unusable " << static_cast<std::int64_t>(t.unusable);
    console.end_line();

    std::uint64_t total = 0;
    for (std::uint32_t v : update_instructions) total += v;
    std::uint32_t* begin = update_instructions;
    std::uint32_t* end = begin + hmpc::sec24::kSamples;
    const std::uint32_t max = *std::max_element(begin, end);
    std::nth_element(begin, begin + hmpc::sec24::kSamples / 2, end);
    console << "instructions " << name << " per_update max " << max << " median "
            << begin[hmpc::sec24::kSamples / 2] << " mean "
            << total / static_cast<std::uint64_t>(hmpc::sec24::kSamples);
    console.end_line();
    ok = ok && std::isfinite(outcome.accumulated_cost) && t.unusable == 0 && t.iterations > 0;
  }
};

}  // namespace

int main() {
  counter.start();
  console << "hmpc solver image: " << HMPC_IMAGE_TAG << ", sizeof(Scalar) "
          << static_cast<unsigned>(sizeof(Scalar));
  console.end_line();

  const std::uint32_t spins = 2000000;
  const std::uint64_t t0 = counter.ticks();
  spin(spins);
  const std::uint64_t t1 = counter.ticks();
  instructions_per_tick_x1000 = 2ull * spins * 1000ull / (t1 - t0);
  console << "calibration instructions_per_tick_x1000 " << instructions_per_tick_x1000;
  console.end_line();

  TickObserver observer;
  Report report;
  hmpc::sec24::check::run_all<Scalar>(observer, report);
  console << "stack_high_water_bytes " << hmpc_stack_high_water();
  console.end_line();
  console << (report.ok ? "self-check ok" : "self-check FAILED");
  console.end_line();
  hmpc_semihost_exit(report.ok ? 0 : 3);
}
