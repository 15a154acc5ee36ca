// The Sec. 2.4 closed-loop runs of the Cortex-M solver test.
#pragma once

#include "closed_loop_check.hpp"
#include "hmpc/models/singularly_perturbed_example_mpc.hpp"
#include "hmpc/mpc/compute_model.hpp"

namespace hmpc::closed_loop_check {

constexpr int kSamples = sec24::kSamples;

template <typename Scalar, class Mpc, class Observer, class Report>
void run_one(const char* name, Mpc& mpc, Observer& observer, Report& report) {
  Counting<Observer> counting{observer};
  const auto outcome = sec24::simulate_closed_loop<Scalar>(mpc, kSamples, counting);
  report.method(name, outcome.final_state, outcome.accumulated_cost, counting.totals);
}

// Fine (N = 400) only where double is native: on the single-precision M4 the firmware
// method, Coarse-Fast, is what matters.
template <typename Scalar>
constexpr bool kDoubleTarget = sizeof(Scalar) == 8;

// MPC workspaces live in static storage: the Fine MPC alone is ~130 kB, far beyond a stack.
template <typename Scalar>
struct Sec24Storage {
  using M = sec24::Mpcs<Scalar>;
  static inline typename M::Coarse coarse = M::coarse();
  static inline typename M::CoarseFast coarse_fast = M::coarse_fast();
};
template <typename Scalar>
struct Sec24FineStorage {
  static inline typename sec24::Mpcs<Scalar>::Fine fine = sec24::Mpcs<Scalar>::fine();
};

template <typename Scalar, class Observer, class Report>
void run_all(Observer& observer, Report& report) {
  if constexpr (kDoubleTarget<Scalar>) {
    run_one<Scalar>("fine", Sec24FineStorage<Scalar>::fine, observer, report);
    run_one<Scalar>("coarse", Sec24Storage<Scalar>::coarse, observer, report);
  }
  run_one<Scalar>("coarse-fast", Sec24Storage<Scalar>::coarse_fast, observer, report);
}

// Sec. 2.4 has no compute model to keep in step with the target.
template <typename Scalar>
const ComputeCostModel* compute_model_to_verify() {
  return nullptr;
}

}  // namespace hmpc::closed_loop_check
