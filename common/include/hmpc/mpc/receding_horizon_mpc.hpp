// Single-layer MPC (thesis Sec. 2.2): one iLQR problem re-solved every sampling period.
// With the model's step equal to the sampling period this is the thesis's "Fine MPC"; with a
// coarser step (Delta t_c > Delta t) it is the "Coarse MPC" of Sec. 2.3.3.
#pragma once

#include <array>

#include "hmpc/mpc/sampling.hpp"
#include "hmpc/solver/ilqr.hpp"

namespace hmpc {

template <class Problem, int N>
class RecedingHorizonMpc {
 public:
  using Solver = Ilqr<Problem, N>;
  using Scalar = typename Problem::Scalar;
  using State = typename Solver::State;
  using Control = typename Solver::Control;
  using Result = typename Solver::Result;

  struct Config {
    // Sampling periods per model step: the plan is time-shifted (Eq. 2.22) once a whole
    // model step has elapsed. 1 for a Fine MPC.
    int samples_per_step = 1;
    IlqrConfig<Scalar> solver{};
    // Model steps per sampling period, for a model step shorter than the period (the
    // humanoid's Fine MPC: 10 ms steps, 30 ms sampling, Table 2.4): the inputs of steps
    // 0..steps_per_sample-1 are applied in turn (planned_control) and the plan shifts by that
    // many steps each period. 1..kMaxStepsPerSample; used only with samples_per_step = 1.
    int steps_per_sample = 1;
  };
  static constexpr int kMaxStepsPerSample = 8;

  RecedingHorizonMpc(const Problem& problem, const Config& config)
      : problem_(problem), config_(config), solver_(config.solver), clock_(config.samples_per_step),
        steps_per_sample_(config.steps_per_sample < 1 ? 1
                          : config.steps_per_sample > kMaxStepsPerSample
                              ? kMaxStepsPerSample
                              : config.steps_per_sample) {}

  Problem& problem() { return problem_; }
  const Problem& problem() const { return problem_; }
  const Solver& solver() const { return solver_; }
  const Result& last_result() const { return result_; }
  int last_iterations() const { return result_.iterations; }
  LayerWork last_work() const { return {result_.work, SolveWork{}}; }
  bool last_plan_usable() const { return plan_is_usable(result_.status); }

  // Offline optimisation of the initial input sequence (Algorithm 1, line 1; Fig. 2.2). A
  // board that must keep its control period passes a `stop` at its deadline: the sequence is
  // then as good as the time allowed, and the online solves go on improving it.
  template <class StopPredicate = NeverStop>
  Result initialize(const State& x0, int offline_iterations,
                    StopPredicate&& stop = StopPredicate{}) {
    solver_.reset();
    clock_.reset();
    auto config = config_.solver;
    config.max_iterations = offline_iterations;
    solver_.set_config(config);
    result_ = solver_.solve(problem_, x0, offline_iterations, stop);
    solver_.set_config(config_.solver);
    return result_;
  }

  // One sampling period: solve from the measured state and return the input to apply. On an
  // unusable solve (non-finite measurement or model) the previous plan, already time
  // shifted, supplies the input; the caller sees why in last_result().
  template <class StopPredicate = NeverStop>
  Control update(const State& x, StopPredicate&& stop = StopPredicate{}) {
    result_ = solver_.solve(problem_, x, config_.solver.max_iterations, stop);
    for (int j = 0; j < steps_per_sample_; ++j) applied_[j] = solver_.controls()[j < N ? j : N - 1];
    if (clock_.advance()) solver_.shift(steps_per_sample_);  // Eq. 2.22
    return applied_[0];
  }
  // The input for model step j (0 <= j < steps_per_sample) of the current sampling period.
  Control planned_control(int j) const {
    return applied_[j < 0 ? 0 : j >= steps_per_sample_ ? steps_per_sample_ - 1 : j];
  }

 private:
  Problem problem_;
  Config config_;
  Solver solver_;
  SampleClock clock_;
  int steps_per_sample_;
  std::array<Control, kMaxStepsPerSample> applied_{};
  Result result_{};
};

}  // namespace hmpc
