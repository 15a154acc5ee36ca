// Single-layer MPC (thesis Sec. 2.2): one iLQR problem re-solved every sampling period.
// With the model's step equal to the sampling period this is the thesis's "Fine MPC"; with a
// coarser step (Delta t_c > Delta t) it is the "Coarse MPC" of Sec. 2.3.3.
#pragma once

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
  };

  RecedingHorizonMpc(const Problem& problem, const Config& config)
      : problem_(problem), config_(config), solver_(config.solver),
        clock_(config.samples_per_step) {}

  Problem& problem() { return problem_; }
  const Problem& problem() const { return problem_; }
  const Solver& solver() const { return solver_; }
  const Result& last_result() const { return result_; }
  int last_iterations() const { return result_.iterations; }
  LayerWork last_work() const { return {result_.work, SolveWork{}}; }
  bool last_plan_usable() const { return plan_is_usable(result_.status); }

  // Offline optimisation of the initial input sequence (Algorithm 1, line 1; Fig. 2.2).
  Result initialize(const State& x0, int offline_iterations) {
    solver_.reset();
    clock_.reset();
    auto config = config_.solver;
    config.max_iterations = offline_iterations;
    solver_.set_config(config);
    result_ = solver_.solve(problem_, x0);
    solver_.set_config(config_.solver);
    return result_;
  }

  // One sampling period: solve from the measured state and return the input to apply. On an
  // unusable solve (non-finite measurement or model) the previous plan, already time
  // shifted, supplies the input; the caller sees why in last_result().
  template <class StopPredicate = NeverStop>
  Control update(const State& x, StopPredicate&& stop = StopPredicate{}) {
    result_ = solver_.solve(problem_, x, config_.solver.max_iterations, stop);
    const Control u = solver_.controls()[0];
    if (clock_.advance()) solver_.shift(1);  // Eq. 2.22
    return u;
  }

 private:
  Problem problem_;
  Config config_;
  Solver solver_;
  SampleClock clock_;
  Result result_{};
};

}  // namespace hmpc
