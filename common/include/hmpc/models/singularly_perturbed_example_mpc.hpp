// Settings of the Sec. 2.4 comparison (Table 2.1 and Sec. 2.4.1) and the four MPCs built on
// the problems of singularly_perturbed_example.hpp. One source of truth for the host
// scenario, its tests and benchmark, and the Cortex-M test image.
#pragma once

#include "hmpc/models/singularly_perturbed_example.hpp"
#include "hmpc/mpc/receding_horizon_mpc.hpp"
#include "hmpc/mpc/two_layer_mpc.hpp"

namespace hmpc::sec24 {

// Table 2.1 (step sizes in seconds).
constexpr double kFineStep = 0.001;
constexpr int kFineHorizon = 400;
constexpr double kCoarseStep = 0.010;
constexpr int kCoarseHorizon = 40;
constexpr double kFastStep = 0.001;
constexpr int kFastHorizon = 30;
constexpr int kFineStepsPerCoarseStep = 10;  // M = Delta t_c / Delta t_f, Eq. 2.35

// Sec. 2.4.1: 0.4 s simulated at 1.0 ms sampling; iLQR cap 50 and tolerance 1e-6.
constexpr double kSamplingPeriod = 0.001;
constexpr int kSamples = 400;
constexpr int kIterationCap = 50;
constexpr double kTolerance = 1e-6;
constexpr int kSamplesPerCoarseStep = 10;

// Offline optimisation of the initial inputs (Algorithm 1, line 1). Our choice: enough
// iterations to converge from zero inputs at 1e-6; the thesis gives no number.
constexpr int kOfflineIterations = 500;

// The thesis gives no initial state. We start at rest at the origin: y = 0 is the case the
// thesis names where Eq. 2.25 has no unique root, so the slow subsystem is tested there.
template <typename Scalar>
Vector2<Scalar> initial_state() {
  return Vector2<Scalar>::Zero();
}

template <typename Scalar>
IlqrConfig<Scalar> solver_config() {
  return IlqrConfig<Scalar>::with_cap_and_tolerance(kIterationCap, kTolerance);
}

template <typename Scalar>
struct Mpcs {
  using Fine = RecedingHorizonMpc<FullProblem<Scalar>, kFineHorizon>;
  using Coarse = RecedingHorizonMpc<FullProblem<Scalar>, kCoarseHorizon>;
  using Fast = FastSubsystem<Scalar, kFastHorizon>;
  using CoarseFast = CoarseFastMpc<FullProblem<Scalar>, kCoarseHorizon, Fast, kFastHorizon>;
  using SlowFast = SlowFastMpc<SlowSubsystem<Scalar>, kCoarseHorizon, Fast, kFastHorizon>;

  static Fine fine(const Parameters<Scalar>& p = {}) {
    return Fine(FullProblem<Scalar>(p, Scalar(kFineStep)), {1, solver_config<Scalar>()});
  }
  static Coarse coarse(const Parameters<Scalar>& p = {}) {
    return Coarse(FullProblem<Scalar>(p, Scalar(kCoarseStep)),
                  {kSamplesPerCoarseStep, solver_config<Scalar>()});
  }
  static typename CoarseFast::Config two_layer_config() {
    return {kFineStepsPerCoarseStep, kSamplesPerCoarseStep, solver_config<Scalar>(),
            solver_config<Scalar>()};
  }
  static CoarseFast coarse_fast(const Parameters<Scalar>& p = {}) {
    return CoarseFast(FullProblem<Scalar>(p, Scalar(kCoarseStep)), Fast(p, Scalar(kFastStep)),
                      two_layer_config());
  }
  static SlowFast slow_fast(const Parameters<Scalar>& p = {}) {
    return SlowFast(SlowSubsystem<Scalar>(p, Scalar(kCoarseStep)), Fast(p, Scalar(kFastStep)),
                    {kFineStepsPerCoarseStep, kSamplesPerCoarseStep, solver_config<Scalar>(),
                     solver_config<Scalar>()});
  }
};

template <typename Scalar>
struct ClosedLoopOutcome {
  Vector2<Scalar> final_state;
  Scalar accumulated_cost;  // sum over samples of the stage cost of Eq. 2.38 times Delta t
};

// The closed loop of Sec. 2.4.1: Algorithm 1's offline initialisation, then one MPC update
// per 1 ms sample on the plant of Eq. 2.37. The observer sees each update:
//   observer.before_update(k);  observer.after_update(k, x, u, mpc);
template <typename Scalar, class Mpc, class Observer>
ClosedLoopOutcome<Scalar> simulate_closed_loop(Mpc& mpc, int samples, Observer& observer) {
  const Parameters<Scalar> p;
  const Scalar dt = Scalar(kSamplingPeriod);
  Vector2<Scalar> x = initial_state<Scalar>();
  Scalar cost = 0;
  mpc.initialize(x, kOfflineIterations);
  for (int k = 0; k < samples; ++k) {
    observer.before_update(k);
    const Vector2<Scalar> u = mpc.update(x);
    observer.after_update(k, x, u, mpc);
    cost += regulator_cost(p, x, u) * dt;
    x = integrate_plant(p, x, u, dt);
  }
  return {x, cost};
}

}  // namespace hmpc::sec24
