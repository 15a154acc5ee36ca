// Cortex-M test image: closed-loop MPC runs (selected by HMPC_RUNS_HEADER) on the target's
// FPU, reporting results (exact bits) for comparison with the host, and instructions per MPC
// update with the solver's work counters, counted by SysTick under QEMU -icount shift=0.
// Output lines: "update <instructions> <upper rollout> <upper derivative> <fast rollout>
// <fast derivative>" (solver work in steps) for each update of a run, then
// "result/count/instructions <method> ..." when the run ends.
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "console.hpp"
#include HMPC_RUNS_HEADER

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

using hmpc::closed_loop_check::kSamples;
using hmpc::qemu::Console;
using hmpc::qemu::InstructionCounter;

Console console;
InstructionCounter counter;
std::uint64_t instructions_per_tick_x1000 = 0;
std::uint32_t update_instructions[kSamples];

// Exactly two instructions per iteration: calibrates instructions per SysTick tick.
__attribute__((noinline)) void spin(std::uint32_t n) {
  __asm__ volatile("1: subs %0, %0, #1\n bne 1b" : "+r"(n) : : "cc");
}

struct TickObserver {
  std::uint64_t start = 0;
  void before_update(int) { start = counter.ticks(); }
  template <class State, class Control, class Mpc>
  void after_update(int k, const State&, const Control&, const Mpc& mpc) {
    const std::uint64_t ticks = counter.ticks() - start;
    const auto instructions =
        static_cast<std::uint32_t>(ticks * instructions_per_tick_x1000 / 1000);
    update_instructions[k] = instructions;
    const hmpc::LayerWork w = mpc.last_work();
    console << "update " << instructions << " " << w.upper.rollout_steps << " "
            << w.upper.derivative_steps << " " << w.fast.rollout_steps << " "
            << w.fast.derivative_steps;
    console.end_line();
  }
};

struct Report {
  bool ok = true;
  template <class State>
  void method(const char* name, const State& final_state, Scalar cost,
              const hmpc::closed_loop_check::Totals& t) {
    for (int i = 0; i < final_state.size(); ++i) {
      console << "result " << name << " x" << i << " ";
      console.bits(final_state(i)).end_line();
    }
    console << "result " << name << " cost ";
    console.bits(cost).end_line();
    console << "count " << name << " iterations " << t.iterations << " unusable " << t.unusable;
    console.end_line();

    std::uint64_t total = 0;
    for (std::uint32_t v : update_instructions) total += v;
    std::uint32_t* begin = update_instructions;
    std::uint32_t* end = begin + kSamples;
    const std::uint32_t max = *std::max_element(begin, end);
    std::nth_element(begin, begin + kSamples / 2, end);
    console << "instructions " << name << " per_update max " << max << " median "
            << begin[kSamples / 2] << " mean " << total / static_cast<std::uint64_t>(kSamples);
    console.end_line();
    std::fill(begin, end, 0u);
    ok = ok && std::isfinite(cost) && t.unusable == 0 && t.iterations > 0;
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
  hmpc::closed_loop_check::run_all<Scalar>(observer, report);
  console << "stack_high_water_bytes " << hmpc_stack_high_water();
  console.end_line();
  console << (report.ok ? "self-check ok" : "self-check FAILED");
  console.end_line();
  hmpc_semihost_exit(report.ok ? 0 : 3);
}
