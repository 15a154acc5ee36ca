// Hierarchical two-layer MPC of thesis Sec. 2.3, generic over the model.
//
//   upper layer: Coarse-Fast MPC (Sec. 2.3.3) solves the full model with the coarse step
//                Delta t_c, horizon N_c (Eq. 2.34); Slow-Fast MPC (Sec. 2.3.2) solves the
//                slow subsystem of Eq. 2.27 with Delta t_s, N_s (Eq. 2.30).
//   lower layer: the fast subsystem (Eq. 2.29) for the deviation nu of the fast inputs with
//                Delta t_f, N_f (Eq. 2.31), around the upper plan held on the fine grid by a
//                zero-order hold (Eq. 2.35); the inputs are composed by Eq. 2.36 (2.33).
//
// The fast subsystem is an iLQR problem (problem.hpp) that additionally provides
//   using FullState, FullControl;
//   void set_reference(int j, const FullState& x_hat, const FullControl& u_hat);  // j=0..N_f
//   State deviation(const FullState& x) const;        // zeta_0 = z - z_hat_0
//   FullControl compose(const FullControl& u_hat, const Control& nu) const;  // Eq. 2.36
// A slow upper layer additionally provides
//   State slow_state(const FullState& x) const;                           // y from x
//   FullState full_state(const State& y, const FullControl& u) const;     // [y; z_hat], Eq. 2.26
#pragma once

#include <array>

#include "hmpc/mpc/sampling.hpp"
#include "hmpc/solver/ilqr.hpp"

namespace hmpc {

// The coarse layer plans on the full model: its state is the full state.
struct FullModelUpperLayer {
  template <class Upper, class FullState>
  static typename Upper::State to_upper(const Upper&, const FullState& x) {
    return x;
  }
  template <class Upper, class FullControl>
  static typename Upper::State to_full(const Upper&, const typename Upper::State& x,
                                       const FullControl&) {
    return x;
  }
};

// The slow layer plans on y only; the fast state comes from the root of Eq. 2.25.
struct SlowSubsystemUpperLayer {
  template <class Upper, class FullState>
  static typename Upper::State to_upper(const Upper& upper, const FullState& x) {
    return upper.slow_state(x);
  }
  template <class Upper, class FullControl>
  static auto to_full(const Upper& upper, const typename Upper::State& y, const FullControl& u) {
    return upper.full_state(y, u);
  }
};

template <class UpperProblem, int NUpper, class FastSubsystem, int NFast, class UpperLayer>
class TwoLayerMpc {
 public:
  using UpperSolver = Ilqr<UpperProblem, NUpper>;
  using FastSolver = Ilqr<FastSubsystem, NFast>;
  using Scalar = typename UpperProblem::Scalar;
  using FullState = typename FastSubsystem::FullState;
  using FullControl = typename FastSubsystem::FullControl;
  using UpperResult = typename UpperSolver::Result;
  using FastResult = typename FastSolver::Result;
  static_assert(UpperProblem::kControlDim == FullControl::RowsAtCompileTime,
                "the upper layer plans the full input vector");

  struct Config {
    int fine_steps_per_upper_step = 1;  // M = Delta t_c / Delta t_f of Eq. 2.35
    int samples_per_upper_step = 1;     // sampling periods per upper step (plan shift)
    IlqrConfig<Scalar> upper{};
    IlqrConfig<Scalar> fast{};
    // How the upper states are held on the fine grid. Eq. 2.35 holds them (zero order);
    // kLinear interpolates between consecutive upper states, so the reference moves smoothly
    // (the upper inputs are held in both cases). For a model whose frozen slow state pins the
    // fast one (the humanoid's base over its stance feet), a held base that jumps every M fine
    // steps jumps the contacts with it (see host/include/hmpc/humanoid/coarse_fast.hpp).
    enum class StateHold { kZeroOrder, kLinear };
    StateHold state_hold = StateHold::kZeroOrder;
  };

  TwoLayerMpc(const UpperProblem& upper, const FastSubsystem& fast, const Config& config)
      : upper_problem_(upper), fast_problem_(fast), config_(config), upper_solver_(config.upper),
        fast_solver_(config.fast), clock_(config.samples_per_upper_step) {}

  UpperProblem& upper_problem() { return upper_problem_; }
  const UpperProblem& upper_problem() const { return upper_problem_; }
  FastSubsystem& fast_subsystem() { return fast_problem_; }
  const FastSubsystem& fast_subsystem() const { return fast_problem_; }
  const UpperSolver& upper_solver() const { return upper_solver_; }
  const FastSolver& fast_solver() const { return fast_solver_; }
  const UpperResult& last_upper_result() const { return upper_result_; }
  const FastResult& last_fast_result() const { return fast_result_; }
  int last_iterations() const { return upper_result_.iterations + fast_result_.iterations; }
  LayerWork last_work() const { return {upper_result_.work, fast_result_.work}; }
  bool last_plan_usable() const {
    return plan_is_usable(upper_result_.status) && plan_is_usable(fast_result_.status);
  }

  // Algorithm 1, line 1: the initial input sequence of the upper layer optimised offline; a
  // `stop` bounds it in time (as RecedingHorizonMpc::initialize).
  template <class StopPredicate = NeverStop>
  UpperResult initialize(const FullState& x0, int offline_iterations,
                         StopPredicate&& stop = StopPredicate{}) {
    upper_solver_.reset();
    fast_solver_.reset();
    clock_.reset();
    auto config = config_.upper;
    config.max_iterations = offline_iterations;
    upper_solver_.set_config(config);
    upper_result_ = upper_solver_.solve(upper_problem_, UpperLayer::to_upper(upper_problem_, x0),
                                        offline_iterations, stop);
    upper_solver_.set_config(config_.upper);
    return upper_result_;
  }

  // Algorithm 1, lines 3-7, for one sampling period. Returns the composed input u_0 of
  // Eq. 2.36; later inputs of the composed plan are available from planned_control(j).
  template <class StopPredicate = NeverStop>
  FullControl update(const FullState& x, StopPredicate&& stop = StopPredicate{}) {
    return update(x, stop, stop);
  }
  // The same with a stop predicate per layer (e.g. a deadline for each within the period).
  template <class UpperStop, class FastStop>
  FullControl update(const FullState& x, UpperStop&& upper_stop, FastStop&& fast_stop) {
    // Line 3: upper optimisation from the measured state, warm-started (Eq. 2.34 / 2.30).
    upper_result_ = upper_solver_.solve(upper_problem_, UpperLayer::to_upper(upper_problem_, x),
                                        config_.upper.max_iterations, upper_stop);

    // Eq. 2.35: hold each upper input, and state (or interpolate states), for M fine steps.
    const int M = config_.fine_steps_per_upper_step;
    const auto& xs = upper_solver_.states();
    const auto& us = upper_solver_.controls();
    for (int j = 0; j <= NFast; ++j) {
      const int k = j / M < NUpper ? j / M : NUpper - 1;
      held_controls_[j] = us[k];
      auto x_hat = UpperLayer::to_full(upper_problem_, xs[k], us[k]);
      if (config_.state_hold == Config::StateHold::kLinear) {
        const Scalar s = static_cast<Scalar>(j - k * M) / static_cast<Scalar>(M);
        x_hat += s * (UpperLayer::to_full(upper_problem_, xs[k + 1], us[k]) - x_hat);
      }
      fast_problem_.set_reference(j, x_hat, held_controls_[j]);
    }

    // Line 5: fast optimisation (Eq. 2.31) from nu = 0 around the held plan.
    fast_solver_.set_zero_controls();
    fast_result_ = fast_solver_.solve(fast_problem_, fast_problem_.deviation(x),
                                      config_.fast.max_iterations, fast_stop);

    // Line 4: time shift of the upper plan once an upper step has elapsed (Eq. 2.22).
    FullControl u = planned_control(0);
    if (clock_.advance()) upper_solver_.shift(1);
    return u;
  }

  // Eq. 2.35: the upper input held at fine step j (0 <= j < N_f), before the lower layer's nu.
  const FullControl& held_control(int j) const {
    return held_controls_[j < 0 ? 0 : (j >= NFast ? NFast - 1 : j)];
  }

  // Line 6, Eq. 2.36: composed input at fine step j of the current plan (0 <= j < N_f).
  // If the fast layer failed, the held upper input is used unmodified.
  FullControl planned_control(int j) const {
    if (j < 0) j = 0;
    if (j >= NFast) j = NFast - 1;
    if (!plan_is_usable(fast_result_.status)) return held_controls_[j];
    return fast_problem_.compose(held_controls_[j], fast_solver_.controls()[j]);
  }

 private:
  UpperProblem upper_problem_;
  FastSubsystem fast_problem_;
  Config config_;
  UpperSolver upper_solver_;
  FastSolver fast_solver_;
  SampleClock clock_;
  std::array<FullControl, NFast + 1> held_controls_{};
  UpperResult upper_result_{};
  FastResult fast_result_{};
};

template <class CoarseProblem, int Nc, class FastSubsystem, int Nf>
using CoarseFastMpc = TwoLayerMpc<CoarseProblem, Nc, FastSubsystem, Nf, FullModelUpperLayer>;

template <class SlowSubsystem, int Ns, class FastSubsystem, int Nf>
using SlowFastMpc = TwoLayerMpc<SlowSubsystem, Ns, FastSubsystem, Nf, SlowSubsystemUpperLayer>;

}  // namespace hmpc
