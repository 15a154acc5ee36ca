// The Sec. 2.4 closed-loop runs shared by the Cortex-M test image and its host reference:
// both execute exactly this code, so their results can be compared line by line.
#pragma once

#include <cstdint>

#include "hmpc/models/singularly_perturbed_example_mpc.hpp"

namespace hmpc::sec24::check {

struct Totals {
  std::int64_t iterations = 0;
  std::int64_t unusable = 0;
};

// Wraps a board-specific observer (timing) and counts iterations and unusable plans.
template <class Inner>
struct Counting {
  Inner& inner;
  Totals totals{};
  void before_update(int k) { inner.before_update(k); }
  template <class Vector, class Mpc>
  void after_update(int k, const Vector& x, const Vector& u, const Mpc& mpc) {
    inner.after_update(k, x, u, mpc);
    totals.iterations += mpc.last_iterations();
    totals.unusable += mpc.last_plan_usable() ? 0 : 1;
  }
};

// Report receives: report.method(name, outcome, totals) after each run.
template <typename Scalar, class Mpc, class Observer, class Report>
void run_one(const char* name, Mpc& mpc, Observer& observer, Report& report) {
  Counting<Observer> counting{observer};
  const auto outcome = simulate_closed_loop<Scalar>(mpc, kSamples, counting);
  report.method(name, outcome, counting.totals);
}

// Fine (N = 400) only where double is native: on the single-precision M4 the firmware
// method, Coarse-Fast, is what matters.
template <typename Scalar>
constexpr bool kRunsFine = sizeof(Scalar) == 8;

// MPC workspaces live in static storage: the Fine MPC alone is ~130 kB, far beyond a stack.
template <typename Scalar>
struct Storage {
  static inline typename Mpcs<Scalar>::Coarse coarse = Mpcs<Scalar>::coarse();
  static inline typename Mpcs<Scalar>::CoarseFast coarse_fast = Mpcs<Scalar>::coarse_fast();
};
template <typename Scalar>
struct FineStorage {
  static inline typename Mpcs<Scalar>::Fine fine = Mpcs<Scalar>::fine();
};

template <typename Scalar, class Observer, class Report>
void run_all(Observer& observer, Report& report) {
  if constexpr (kRunsFine<Scalar>) run_one<Scalar>("fine", FineStorage<Scalar>::fine, observer, report);
  if constexpr (kRunsFine<Scalar>) run_one<Scalar>("coarse", Storage<Scalar>::coarse, observer, report);
  run_one<Scalar>("coarse-fast", Storage<Scalar>::coarse_fast, observer, report);
}

}  // namespace hmpc::sec24::check
