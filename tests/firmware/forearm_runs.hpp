// The forearm strategies of Table 3.1 tracking the thesis's 1 Hz, +-30 deg sinusoid on the
// model for 1 s (250 control periods of 4 ms) in the Cortex-M solver test.
#pragma once

#include <cmath>

#include "closed_loop_check.hpp"
#include "hmpc/models/forearm_mpc.hpp"

namespace hmpc::closed_loop_check {

constexpr int kSamples = 250;

template <typename Scalar>
struct ForearmStorage {
  using S = forearm::Strategies<Scalar>;
  static inline forearm::TargetTrajectory<Scalar> target = [] {
    forearm::TargetTrajectory<Scalar> t;
    t.set_sinusoid(Scalar(30) * kPi<Scalar> / Scalar(180), Scalar(1), Scalar(0), Scalar(0));
    return t;
  }();
  static typename S::Setup setup() {
    typename S::Setup s;
    s.target = &target;
    return s;
  }
  static inline typename S::Fine4 fine4 = S::fine4(setup());
  static inline typename S::Fine8 fine8 = S::fine8(setup());
  static inline typename S::Coarse20 coarse20 = S::coarse20(setup());
  static inline typename S::Coarse40 coarse40 = S::coarse40(setup());
  static inline typename S::TwoStage two_stage = S::two_stage(setup());
  static inline typename S::PamOnly pam_only = S::pam_only(setup());
};

template <typename Scalar, class Mpc, class Observer, class Report>
void run_one(const char* name, Mpc& mpc, Observer& observer, Report& report) {
  using Store = ForearmStorage<Scalar>;
  const forearm::Parameters<Scalar> p;
  const Eigen::Matrix<Scalar, 3, 1> x0(Scalar(0), Scalar(0),
                                       forearm::equilibrium_pressure(p, Scalar(0)));
  Counting<Observer> counting{observer};
  const auto outcome =
      forearm::simulate_tracking<Scalar>(mpc, p, forearm::CostWeights<Scalar>{}, Store::target, x0,
                                         kSamples, forearm::NoComputeDelay{}, counting);
  report.method(name, outcome.final_state, outcome.accumulated_cost, counting.totals);
}

template <typename Scalar, class Observer, class Report>
void run_all(Observer& observer, Report& report) {
  using Store = ForearmStorage<Scalar>;
  run_one<Scalar>("fine-4ms", Store::fine4, observer, report);
  run_one<Scalar>("fine-8ms", Store::fine8, observer, report);
  run_one<Scalar>("coarse-20ms", Store::coarse20, observer, report);
  run_one<Scalar>("coarse-40ms", Store::coarse40, observer, report);
  run_one<Scalar>("two-stage", Store::two_stage, observer, report);
  run_one<Scalar>("pam-only", Store::pam_only, observer, report);
}

// The forearm's Cortex-M7 compute model must keep predicting what the target measures.
template <typename Scalar>
const ComputeCostModel* compute_model_to_verify() {
  if constexpr (sizeof(Scalar) == 8) return &forearm::kCortexM7ComputeModel;
  return nullptr;
}

}  // namespace hmpc::closed_loop_check
