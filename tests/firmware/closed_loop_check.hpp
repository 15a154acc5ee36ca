// Shared by the Cortex-M test images and their host reference: counting of iterations and
// work around any closed-loop run. Each runs header (sec24_runs.hpp, forearm_runs.hpp)
// defines, in namespace hmpc::closed_loop_check,
//   constexpr int kSamples;                       // updates per run
//   template <typename Scalar, class Observer, class Report> void run_all(Observer&, Report&);
// calling report.method(name, final_state, accumulated_cost, totals) after each run. Image and
// host execute the same code, so their results can be compared line by line.
#pragma once

#include <cstdint>

#include "hmpc/solver/ilqr.hpp"

namespace hmpc::closed_loop_check {

struct Totals {
  std::int64_t iterations = 0;
  std::int64_t unusable = 0;
  LayerWork work{};
};

// Wraps a board-specific observer (timing) and counts iterations, work and unusable plans.
template <class Inner>
struct Counting {
  Inner& inner;
  Totals totals{};
  void before_update(int k) { inner.before_update(k); }
  template <class State, class Control, class Mpc>
  void after_update(int k, const State& x, const Control& u, const Mpc& mpc) {
    inner.after_update(k, x, u, mpc);
    totals.iterations += mpc.last_iterations();
    totals.unusable += mpc.last_plan_usable() ? 0 : 1;
    const LayerWork w = mpc.last_work();
    totals.work.upper += w.upper;
    totals.work.fast += w.fast;
  }
};

}  // namespace hmpc::closed_loop_check
