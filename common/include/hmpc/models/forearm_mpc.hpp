// The control strategies of thesis Table 3.1 for the forearm, on the shared MPC core, and the
// settings they share (Sec. 3.3). One source of truth for the board firmware, the host
// simulations, tests and benchmarks.
#pragma once

#include <cmath>

#include "hmpc/models/forearm_problems.hpp"
#include "hmpc/mpc/compute_model.hpp"
#include "hmpc/mpc/receding_horizon_mpc.hpp"
#include "hmpc/mpc/two_layer_mpc.hpp"

namespace hmpc::forearm {

// Sec. 3.3: sampling and control period 4.0 ms; iLQR cap 50, termination 5.0e-4.
constexpr double kControlPeriod = 0.004;
constexpr int kIterationCap = 50;
constexpr double kTolerance = 5e-4;

// Table 3.1 (every strategy looks 200 ms ahead).
constexpr double kFine4Step = 0.004;
constexpr int kFine4Horizon = 50;
constexpr double kFine8Step = 0.008;
constexpr int kFine8Horizon = 25;
constexpr double kCoarse20Step = 0.020;
constexpr int kCoarse20Horizon = 10;
constexpr double kCoarse40Step = 0.040;
constexpr int kCoarse40Horizon = 5;
constexpr double kTwoStageFineStep = 0.004;
constexpr int kTwoStageFineHorizon = 20;
constexpr int kTwoStageFineStepsPerCoarseStep = 5;  // 20 ms / 4 ms
// T_v [s] of the terminal rate term (forearm_problems.hpp) in the Two-stage's two stages; 0 is
// the thesis's cost.
struct TwoStageTerminalRate {
  double first_stage = 0, second_stage = 0;
};
// The Two-stage's terminal rate term when enabled (our change to the method), chosen on the
// model and on the HIL demo's mismatched plant (tests/bench/forearm_limits_bench prints the
// sweeps). Second stage: a longer T_v lowers the error at 1.5-1.8 Hz and raises it at 0.25-1
// Hz; 0.4 s is the longest of 0.1-0.8 s that alone keeps the Two-stage the most accurate
// strategy at every frequency up to 1.8 Hz on the model. First stage, with that: 0.1 s of
// 0.05-0.15 s is the one with the Two-stage the most accurate at every frequency on both
// plants (0.15 s is better on the model, worse at 0.25-1.5 Hz on the mismatched plant).
constexpr TwoStageTerminalRate kTwoStageTerminalRate{0.1, 0.4};

enum class Strategy { kFine4, kFine8, kCoarse20, kCoarse40, kTwoStage, kPamOnly };
constexpr Strategy kAllStrategies[] = {Strategy::kFine4,    Strategy::kFine8,
                                       Strategy::kCoarse20, Strategy::kCoarse40,
                                       Strategy::kTwoStage, Strategy::kPamOnly};

inline const char* to_string(Strategy s) {
  switch (s) {
    case Strategy::kFine4: return "fine-4ms";
    case Strategy::kFine8: return "fine-8ms";
    case Strategy::kCoarse20: return "coarse-20ms";
    case Strategy::kCoarse40: return "coarse-40ms";
    case Strategy::kTwoStage: return "two-stage";
    case Strategy::kPamOnly: return "pam-only";
  }
  return "unknown";
}

template <typename Scalar>
IlqrConfig<Scalar> solver_config() {
  return IlqrConfig<Scalar>::with_cap_and_tolerance(kIterationCap, kTolerance);
}

template <typename Scalar>
struct Strategies {
  using Problem = ForearmProblem<Scalar>;
  using Fine4 = RecedingHorizonMpc<Problem, kFine4Horizon>;
  using Fine8 = RecedingHorizonMpc<Problem, kFine8Horizon>;
  using Coarse20 = RecedingHorizonMpc<Problem, kCoarse20Horizon>;
  using Coarse40 = RecedingHorizonMpc<Problem, kCoarse40Horizon>;
  using Fast = ForearmFastSubsystem<Scalar, kTwoStageFineHorizon>;
  using TwoStage = CoarseFastMpc<Problem, kCoarse20Horizon, Fast, kTwoStageFineHorizon>;
  // PAM-only (Fig. 3.8b): the Coarse 20 ms strategy with the motor held at zero.
  using PamOnly = Coarse20;

  struct Setup {
    Parameters<Scalar> parameters{};
    CostWeights<Scalar> weights{};
    const TargetTrajectory<Scalar>* target = nullptr;
    // The terminal rate term's T_v [s] (forearm_problems.hpp) in Fine's and Coarse's problem
    // (the limits bench's study), and in the Two-stage's stages; 0 is the thesis's cost.
    Scalar terminal_rate_time = 0;
    TwoStageTerminalRate two_stage_terminal_rate{};
  };

  static int samples_per_step(double step) {
    return static_cast<int>(std::lround(step / kControlPeriod));
  }
  static Problem problem(const Setup& s, double step, double terminal_rate_time) {
    Problem p(s.parameters, s.weights, Scalar(step), s.target);
    p.set_terminal_rate_time(Scalar(terminal_rate_time));
    return p;
  }
  template <class Mpc>
  static Mpc single(const Setup& s, double step) {
    return Mpc(problem(s, step, double(s.terminal_rate_time)),
               {samples_per_step(step), solver_config<Scalar>()});
  }

  static Fine4 fine4(const Setup& s) { return single<Fine4>(s, kFine4Step); }
  static Fine8 fine8(const Setup& s) { return single<Fine8>(s, kFine8Step); }
  static Coarse20 coarse20(const Setup& s) { return single<Coarse20>(s, kCoarse20Step); }
  static Coarse40 coarse40(const Setup& s) { return single<Coarse40>(s, kCoarse40Step); }
  static PamOnly pam_only(const Setup& s) {
    PamOnly mpc = coarse20(s);
    mpc.problem().set_motor_enabled(false);
    return mpc;
  }
  static TwoStage two_stage(const Setup& s) {
    Fast fast(s.parameters, s.weights, Scalar(kTwoStageFineStep), s.target);
    fast.set_terminal_rate_time(Scalar(s.two_stage_terminal_rate.second_stage));
    return TwoStage(problem(s, kCoarse20Step, s.two_stage_terminal_rate.first_stage), fast,
                    {kTwoStageFineStepsPerCoarseStep, samples_per_step(kCoarse20Step),
                     solver_config<Scalar>(), solver_config<Scalar>()});
  }
};

// Points every problem of an MPC at the current time, so theta_d is read along its horizon.
template <class Problem, int N>
void set_time(RecedingHorizonMpc<Problem, N>& mpc, typename Problem::Scalar t) {
  mpc.problem().set_start_time(t);
}
template <class Upper, int Nu, class Fast, int Nf, class Layer>
void set_time(TwoLayerMpc<Upper, Nu, Fast, Nf, Layer>& mpc, typename Upper::Scalar t) {
  mpc.upper_problem().set_start_time(t);
  mpc.fast_subsystem().set_start_time(t);
}

// Gives every problem of an MPC the tracking-cost weights (Eq. 3.3), e.g. between two steps.
template <class Problem, int N>
void set_weights(RecedingHorizonMpc<Problem, N>& mpc,
                 const CostWeights<typename Problem::Scalar>& w) {
  mpc.problem().set_weights(w);
}
template <class Upper, int Nu, class Fast, int Nf, class Layer>
void set_weights(TwoLayerMpc<Upper, Nu, Fast, Nf, Layer>& mpc,
                 const CostWeights<typename Upper::Scalar>& w) {
  mpc.upper_problem().set_weights(w);
  mpc.fast_subsystem().set_weights(w);
}

// Offset-free control's setting and disturbance estimate for every problem of an MPC, before
// an update.
template <class Problem, int N>
void set_offset_free(RecedingHorizonMpc<Problem, N>& mpc,
                     const OffsetFree<typename Problem::Scalar>& o) {
  mpc.problem().set_offset_free(o);
}
template <class Upper, int Nu, class Fast, int Nf, class Layer>
void set_offset_free(TwoLayerMpc<Upper, Nu, Fast, Nf, Layer>& mpc,
                     const OffsetFree<typename Upper::Scalar>& o) {
  mpc.upper_problem().set_offset_free(o);
  mpc.fast_subsystem().set_offset_free(o);
}

// Compute time of the forearm strategies on the STM32H743 board (Cortex-M7 at the 400 MHz our
// board image runs at, firmware/boards/stm32h7; 480 MHz parts run 1.2x faster), double FPU:
// instructions per unit of solver work, a least-squares fit (R^2 0.9997 over 1500 updates of
// all six strategies) to the per-update instruction counts of the Cortex-M7 image under QEMU
// (tests/firmware, forearm runs; that test fails if this model drifts more than 15 % from what
// the image measures: re-fit it from the test's output when the solver changes). One cycle
// per instruction is an assumption: QEMU counts instructions, not cycles.
constexpr ComputeCostModel kCortexM7ComputeModel{
    2964, {918.6, 3782.8}, {1276.4, 1276.4}, 400e6, 1.0};

// No computation delay: the new input acts at the sample it was computed for.
struct NoComputeDelay {
  double operator()(const LayerWork&) const { return 0; }
};

// The board's computation delay: each update's compute time on the Cortex-M7.
struct CortexM7ComputeDelay {
  double operator()(const LayerWork& w) const { return kCortexM7ComputeModel.seconds(w); }
};

// An observer of simulate_tracking that looks at nothing.
struct NoTrackingObserver {
  void before_update(int) {}
  template <class X, class U, class M>
  void after_update(int, const X&, const U&, const M&) {}
};

template <typename Scalar>
struct TrackingOutcome {
  Eigen::Matrix<Scalar, 3, 1> final_state;
  Scalar accumulated_cost = 0;       // Eq. 3.3a summed over control periods
  Scalar rms_error = 0;              // RMS of theta - theta_d over control periods [rad]
  Scalar mean_abs_pam_torque = 0;    // N·m, for the torque share of Fig. 3.8a
  Scalar mean_abs_motor_torque = 0;  // N·m
  int overruns = 0;                  // control periods skipped because a solve was still running

  Scalar motor_share() const {
    return mean_abs_motor_torque / (mean_abs_pam_torque + mean_abs_motor_torque);
  }
};

constexpr double kPlantStep = 0.001;  // the plant is integrated at 1 ms (RK4)
constexpr int kPlantStepsPerControlPeriod = 4;

// Closed-loop tracking on the model of Eq. 3.1 (RK4 at 1 ms), one MPC update per 4 ms
// control period. `delay(work)` gives the computation time of each update: its input acts
// only that long after the sample, the previous input holds meanwhile, and while a solve runs
// over its period no new one starts (an overrun), as on a real board without a deadline.
// The observer sees each update: observer.before_update(k); observer.after_update(k, x, u, mpc).
template <typename Scalar, class Mpc, class Delay, class Observer>
TrackingOutcome<Scalar> simulate_tracking(Mpc& mpc, const Parameters<Scalar>& plant,
                                          const CostWeights<Scalar>& weights,
                                          const TargetTrajectory<Scalar>& target,
                                          const Eigen::Matrix<Scalar, 3, 1>& x0, int samples,
                                          const Delay& delay, Observer& observer) {
  using State = Eigen::Matrix<Scalar, 3, 1>;
  using Control = Eigen::Matrix<Scalar, 2, 1>;
  TrackingOutcome<Scalar> out;
  State x = x0;
  Control applied(Scalar(0), plant.k_vp * x0(2));  // the valve holds the initial pressure
  Control pending = applied;
  double apply_at = 0, busy_until = 0;
  set_time(mpc, Scalar(0));
  mpc.initialize(x, 200);  // Algorithm 1, line 1 (offline: no time charged)
  for (int k = 0; k < samples; ++k) {
    const double t = k * kControlPeriod;
    if (t >= busy_until - 1e-12) {
      set_time(mpc, Scalar(t));
      observer.before_update(k);
      pending = mpc.update(x);
      observer.after_update(k, x, pending, mpc);
      const double d = delay(mpc.last_work());
      apply_at = busy_until = t + d;
      if (d > kControlPeriod) out.overruns += static_cast<int>(d / kControlPeriod);
    }
    for (int s = 0; s < kPlantStepsPerControlPeriod; ++s) {
      if (t + s * kPlantStep >= apply_at - 1e-12) applied = pending;
      if (s == 0) {
        const Scalar error = x(0) - target.angle(Scalar(t));
        out.accumulated_cost +=
            tracking_cost(plant, weights, x(0), target.angle(Scalar(t)), x(2), applied(0), true)
                .value +
            weights.w_v * applied.squaredNorm();
        out.rms_error += error * error;
        out.mean_abs_pam_torque += std::abs(pam_torque(plant, x(2), x(0)).tau);
        out.mean_abs_motor_torque += std::abs(plant.motor_gain * applied(0));
      }
      x = integrate(plant, x, applied, Scalar(kPlantStep));
    }
  }
  out.final_state = x;
  out.rms_error = std::sqrt(out.rms_error / Scalar(samples));
  out.mean_abs_pam_torque /= Scalar(samples);
  out.mean_abs_motor_torque /= Scalar(samples);
  return out;
}

}  // namespace hmpc::forearm
