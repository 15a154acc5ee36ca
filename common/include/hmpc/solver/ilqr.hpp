// Iterative LQR (thesis Sec. 2.2, Eqs. 2.1-2.22) on fixed-size Eigen.
//
// Model/data split: the Problem (dynamics, costs, limits; see problem.hpp) is immutable
// during a solve; Ilqr owns one workspace sized at compile time by the problem's dimensions
// and the horizon N, allocated once with the object. Nothing here allocates, throws or
// dispatches virtually, so the same code runs in the actuator firmware and on the host.
//
// Improvements over the plain recursion, after iLQG (Tassa, Erez & Todorov, IROS 2012), as
// the thesis does: Levenberg-Marquardt regularisation of Q_uu, a backtracking line search on
// the feedforward term, and box limits on the controls handled as in box-DDP (a projected-
// Newton QP per step, clamped directions removed from the feedback gain).
//
// A penalty on the change of the inputs (problem.hpp's control_change_weight), which ties each
// input to the one before, is solved exactly as DDP on the state augmented with the previous
// input, z_t = (x_t, p_t), p_t = u_{t-1}, p_{t+1} = u_t, without storing the augmented Jacobians:
// the value function gains the terms V_p, V_pp, V_xp and the policy a feedback K_p on the
// previous input's deviation (see backward_pass).
//
// Horizon convention: N control intervals, so N controls u_0..u_{N-1} and N+1 states
// x_0..x_N, as in the sums of Eqs. 2.38-2.40.
//
// Size note: the workspace holds O(N (n^2 + n m)) scalars; keep large instances in static
// storage or allocate them once at start-up, never on a small stack.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <utility>

#include "hmpc/solver/box_qp.hpp"
#include "hmpc/solver/problem.hpp"

namespace hmpc {

enum class SolveStatus : std::uint8_t {
  kConverged = 0,     // cost reduction or gradient below tolerance
  kIterationCap,      // config.max_iterations reached
  kBudgetExhausted,   // the caller's iteration budget ran out or its stop predicate fired
  kStalled,           // regularisation reached its maximum without finding a descent step
  kInvalidInput,      // non-finite x0, bad change penalty: previous plan kept untouched
  kNumericalFailure,  // the model produced non-finite values even from safe controls
};

inline const char* to_string(SolveStatus status) {
  switch (status) {
    case SolveStatus::kConverged: return "converged";
    case SolveStatus::kIterationCap: return "iteration-cap";
    case SolveStatus::kBudgetExhausted: return "budget-exhausted";
    case SolveStatus::kStalled: return "stalled";
    case SolveStatus::kInvalidInput: return "invalid-input";
    case SolveStatus::kNumericalFailure: return "numerical-failure";
  }
  return "unknown";
}

// True when the returned plan was computed for the given initial state and may be applied.
inline bool plan_is_usable(SolveStatus status) {
  return status != SolveStatus::kInvalidInput && status != SolveStatus::kNumericalFailure;
}

template <typename Scalar>
struct IlqrConfig {
  int max_iterations = 50;
  // Converged when an accepted iteration lowers J by less than this (absolute, as iLQG's
  // tolFun), or when the normalised feedforward |k| falls below gradient_tolerance.
  Scalar tolerance = Scalar(1e-6);
  Scalar gradient_tolerance = Scalar(1e-5);
  // Levenberg-Marquardt term mu added to Q_uu; schedule of Tassa et al. 2012, Sec. II-F.
  Scalar regularization_init = Scalar(1);
  Scalar regularization_min = Scalar(1e-6);
  Scalar regularization_max = Scalar(1e10);
  Scalar regularization_factor = Scalar(1.6);
  // Line search: alpha_i = 10^(-3 i / (steps - 1)), accepted when the actual over the
  // expected reduction exceeds min_reduction_ratio.
  int line_search_steps = 11;
  Scalar min_reduction_ratio = Scalar(0);

  // The two settings a thesis experiment states: iteration cap and termination criterion.
  static IlqrConfig with_cap_and_tolerance(int cap, double tol) {
    IlqrConfig c;
    c.max_iterations = cap;
    c.tolerance = Scalar(tol);
    return c;
  }
};

// Work done by one solve, counted in model-step units. Deterministic for a given problem and
// input, so a compute-time model for a target processor can be built on it (instructions
// per unit measured once on the target, e.g. under QEMU).
struct SolveWork {
  std::int32_t rollout_steps = 0;     // dynamics + running cost evaluations
  std::int32_t derivative_steps = 0;  // linearisations of dynamics and cost
  std::int32_t backward_steps = 0;    // Riccati-like steps of the backward pass

  SolveWork& operator+=(const SolveWork& o) {
    rollout_steps += o.rollout_steps;
    derivative_steps += o.derivative_steps;
    backward_steps += o.backward_steps;
    return *this;
  }
};

// Work of one MPC update, by layer (a single-layer MPC has no fast layer).
struct LayerWork {
  SolveWork upper{};
  SolveWork fast{};
};

template <typename Scalar>
struct SolveResult {
  SolveStatus status = SolveStatus::kInvalidInput;
  int iterations = 0;                 // backward + forward passes performed
  Scalar cost = Scalar(0);            // J of the returned plan
  Scalar initial_cost = Scalar(0);    // J of the warm-start rollout
  Scalar regularization = Scalar(0);  // mu after the solve
  SolveWork work{};
};

// Default stop predicate: never stops early. A caller with a deadline passes a functor that
// reads its clock; it is checked before every iteration. A predicate that also has
// `bool expired()` is asked after each batch of line-search rollouts too: true there ends the
// solve at once with the nominal plan (the iteration's step is abandoned), so a long search
// (up to line_search_steps rollouts) cannot carry the solve far past its deadline.
struct NeverStop {
  constexpr bool operator()() const { return false; }
};

namespace detail {
template <class Stop, class = void>
struct HasExpired : std::false_type {};
template <class Stop>
struct HasExpired<Stop, std::void_t<decltype(std::declval<Stop&>().expired())>> : std::true_type {};

template <class Stop>
bool expired(Stop& stop) {
  if constexpr (HasExpired<Stop>::value) {
    return stop.expired();
  } else {
    return false;
  }
}
}  // namespace detail

template <class Problem, int N>
class Ilqr {
 public:
  static_assert(N >= 1, "horizon must have at least one control interval");
  using Scalar = typename Problem::Scalar;
  static constexpr int kStateDim = Problem::kStateDim;
  static constexpr int kControlDim = Problem::kControlDim;
  static constexpr int kHorizon = N;
  // Most line-search rollouts the problem may run at once (problem.hpp's for_each_rollout).
  static constexpr int kLanes = Problem::kRolloutLanes;
  static_assert(kLanes >= 1, "a problem has at least one rollout lane");
  using State = Eigen::Matrix<Scalar, kStateDim, 1>;
  using Control = Eigen::Matrix<Scalar, kControlDim, 1>;
  using Gain = Eigen::Matrix<Scalar, kControlDim, kStateDim>;
  using StateTrajectory = std::array<State, N + 1>;
  using ControlTrajectory = std::array<Control, N>;
  using GainTrajectory = std::array<Gain, N>;
  using Config = IlqrConfig<Scalar>;
  using Result = SolveResult<Scalar>;

  explicit Ilqr(const Config& config = Config{}) : config_(config) { reset(); }

  // Cold start: zero controls and gains, initial regularisation.
  void reset() {
    for (auto& u : u_) u.setZero();
    for (auto& x : x_) x.setZero();
    for (auto& k : k_) k.setZero();
    for (auto& K : K_) K.setZero();
    for (auto& Kp : Kp_) Kp.setZero();
    mu_ = config_.regularization_init;
    dmu_ = Scalar(1);
    cost_ = std::numeric_limits<Scalar>::infinity();
    // Factorisations start valid, so the solver object can be copied before its first solve.
    llt_.compute(ControlMatrix::Identity());
    box_.free_factor.compute(ControlMatrix::Identity());
    box_.x.setZero();
    box_.free_mask.setOnes();
  }

  const Config& config() const { return config_; }
  void set_config(const Config& config) { config_ = config; }

  // Initial control sequence for the next solve (e.g. offline-optimised inputs, Fig. 2.2).
  // Rejected, leaving the current plan, if any entry is not finite.
  bool set_controls(const ControlTrajectory& controls) {
    for (const auto& u : controls)
      if (!u.allFinite()) return false;
    u_ = controls;
    return true;
  }

  void set_zero_controls() {
    for (auto& u : u_) u.setZero();
  }

  // Warm start by time shift, Eq. 2.22: drop the first `steps` controls and repeat the last.
  void shift(int steps = 1) {
    if (steps <= 0) return;
    if (steps > N) steps = N;
    for (int t = 0; t < N; ++t) u_[t] = u_[t + steps < N ? t + steps : N - 1];
  }

  Result solve(const Problem& problem, const State& x0) {
    return solve(problem, x0, config_.max_iterations, NeverStop{});
  }

  // Solves from x0 starting at the current control sequence. At most
  // min(iteration_budget, config.max_iterations) iterations; `stop()` is checked before each.
  // The nominal trajectory only ever changes to one of lower cost, so whatever ends the
  // solve, controls()/states() hold the best plan found.
  template <class StopPredicate = NeverStop>
  Result solve(const Problem& problem, const State& x0, int iteration_budget,
               StopPredicate&& stop = StopPredicate{}) {
    Result result;
    work_ = SolveWork{};
    if (!x0.allFinite()) {
      result.status = SolveStatus::kInvalidInput;
      result.cost = result.initial_cost = std::numeric_limits<Scalar>::quiet_NaN();
      return result;
    }
    change_weight_ = problem.control_change_weight();
    previous_ = problem.previous_control();
    changes_ = (change_weight_.array() > Scalar(0)).any();
    if (!change_weight_.allFinite() || (change_weight_.array() < Scalar(0)).any() ||
        (changes_ && !previous_.allFinite())) {
      result.status = SolveStatus::kInvalidInput;
      result.cost = result.initial_cost = std::numeric_limits<Scalar>::quiet_NaN();
      return result;
    }
    bounded_ = false;
    for (int t = 0; t < N; ++t) {
      lower_[t] = problem.control_lower_bound(t);
      upper_[t] = problem.control_upper_bound(t);
      bounded_ = bounded_ || (lower_[t].array() > -std::numeric_limits<Scalar>::infinity()).any() ||
                 (upper_[t].array() < std::numeric_limits<Scalar>::infinity()).any();
    }

    // Eqs. 2.18-2.20 with alpha = 0 and no feedback: roll the warm start out from x0.
    Scalar cost = rollout_open_loop(problem, x0);
    work_.rollout_steps += lane_steps_[0];
    if (!std::isfinite(cost)) {  // garbage warm start: fall back to the safe zero sequence
      set_zero_controls();
      cost = rollout_open_loop(problem, x0);
      work_.rollout_steps += lane_steps_[0];
    }
    if (!std::isfinite(cost)) {
      result.status = SolveStatus::kNumericalFailure;
      result.cost = result.initial_cost = cost;
      result.work = work_;
      return result;
    }
    commit_candidate(cost);
    result.initial_cost = cost_;
    // mu carries over between receding-horizon solves, but never above its initial value:
    // a previous stall must not leave the solver stalled.
    if (mu_ > config_.regularization_init) {
      mu_ = config_.regularization_init;
      dmu_ = Scalar(1);
    }

    const int budget =
        iteration_budget < config_.max_iterations ? iteration_budget : config_.max_iterations;
    // The nominal trajectory is linearised when an iteration is about to use it, so a solve
    // ended by its budget or the caller's stop does not pay for derivatives it never uses.
    bool linearised = false;
    result.status = SolveStatus::kIterationCap;
    while (true) {
      if (result.iterations >= budget) {
        result.status = budget < config_.max_iterations ? SolveStatus::kBudgetExhausted
                                                        : SolveStatus::kIterationCap;
        break;
      }
      if (stop()) {
        result.status = SolveStatus::kBudgetExhausted;
        break;
      }
      if (!linearised) {
        if (!compute_derivatives(problem)) {
          result.status = SolveStatus::kNumericalFailure;
          break;
        }
        linearised = true;
      }

      // Backward pass, raising mu until Q_uu + mu I is positive definite (Eq. 2.11-2.16).
      Scalar expected_linear = 0;
      Scalar expected_quadratic = 0;
      bool stalled = false;
      while (!backward_pass(expected_linear, expected_quadratic)) {
        if (!increase_regularization()) {
          stalled = true;
          break;
        }
      }
      if (stalled) {
        result.status = SolveStatus::kStalled;
        break;
      }
      ++result.iterations;

      // Converged when the feedforward is negligible (iLQG) or the quadratic model predicts
      // less improvement than the tolerance: nothing a line search could still resolve.
      const Scalar predicted = -(expected_linear + expected_quadratic);
      if ((feedforward_norm() < config_.gradient_tolerance && mu_ < Scalar(1e-5)) ||
          predicted < config_.tolerance) {
        decrease_regularization();
        result.status = SolveStatus::kConverged;
        break;
      }

      // Forward pass with backtracking line search (Eqs. 2.18-2.20 with u + alpha k + K dx):
      // the first alpha of the sequence whose reduction is accepted. The problem may roll out
      // several alphas at once (its lanes); they are judged in sequence order, so the step
      // taken is the same as one at a time.
      const int requested = problem.rollout_lanes();
      const int lanes = requested < 1 ? 1 : (requested > kLanes ? kLanes : requested);
      bool accepted = false, out_of_time = false;
      Scalar reduction = 0;
      for (int first = 0; first < config_.line_search_steps && !accepted && !out_of_time;
           first += lanes) {
        const int count =
            config_.line_search_steps - first < lanes ? config_.line_search_steps - first : lanes;
        problem.for_each_rollout(count, [&](int lane) {
          lane_cost_[lane] =
              rollout_closed_loop(problem, x0, line_search_alpha(first + lane), lane);
        });
        for (int lane = 0; lane < count; ++lane) work_.rollout_steps += lane_steps_[lane];
        for (int lane = 0; lane < count; ++lane) {
          const Scalar alpha = line_search_alpha(first + lane);
          if (!std::isfinite(lane_cost_[lane])) continue;
          reduction = cost_ - lane_cost_[lane];
          const Scalar expected = -alpha * (expected_linear + alpha * expected_quadratic);
          const Scalar ratio = expected > Scalar(0)
                                   ? reduction / expected
                                   : (reduction > Scalar(0) ? Scalar(1) : Scalar(-1));
          if (ratio > config_.min_reduction_ratio && reduction > Scalar(0)) {
            commit_candidate(lane_cost_[lane], lane);
            accepted = true;
            break;
          }
        }
        out_of_time = !accepted && detail::expired(stop);
      }
      if (out_of_time) {
        result.status = SolveStatus::kBudgetExhausted;
        break;
      }

      if (accepted) {
        decrease_regularization();
        if (reduction < config_.tolerance) {
          result.status = SolveStatus::kConverged;
          break;
        }
        linearised = false;
      } else if (!increase_regularization()) {
        result.status = SolveStatus::kStalled;
        break;
      }
    }
    result.cost = cost_;
    result.regularization = mu_;
    result.work = work_;
    return result;
  }

  const ControlTrajectory& controls() const { return u_; }
  const StateTrajectory& states() const { return x_; }
  const GainTrajectory& feedback_gains() const { return K_; }
  Scalar cost() const { return cost_; }

 private:
  using RunningDerivatives = typename Problem::RunningDerivatives;
  using TerminalDerivatives = typename Problem::TerminalDerivatives;
  using StateJacobian = Eigen::Matrix<Scalar, kStateDim, kStateDim>;
  using ControlJacobian = Eigen::Matrix<Scalar, kStateDim, kControlDim>;
  using ControlMatrix = Eigen::Matrix<Scalar, kControlDim, kControlDim>;

  Control clamp(const Control& u, int t) const { return u.cwiseMax(lower_[t]).cwiseMin(upper_[t]); }

  Scalar line_search_alpha(int i) const {
    if (config_.line_search_steps <= 1) return Scalar(1);
    using std::pow;
    return pow(Scalar(10), Scalar(-3) * Scalar(i) / Scalar(config_.line_search_steps - 1));
  }

  // Trajectory cost of lane `lane`'s candidate, Eq. 2.2; +inf if any state or cost term is
  // not finite. Counts the work in lane_steps_ (lanes may run concurrently).
  Scalar candidate_cost(const Problem& problem, int lane);

  Scalar rollout_open_loop(const Problem& problem, const State& x0);

  // Eq. 2.18-2.20 with the line-search step alpha on the feedforward term k_t of Eq. 2.12,
  // into lane `lane`'s candidate.
  Scalar rollout_closed_loop(const Problem& problem, const State& x0, Scalar alpha, int lane);

  void commit_candidate(Scalar cost, int lane = 0) {
    x_ = x_new_[lane];
    u_ = u_new_[lane];
    cost_ = cost;
  }

  bool compute_derivatives(const Problem& problem);

  // One backward sweep. Returns false when Q_uu + mu I is not positive definite at some step
  // (or the result is not finite), in which case the caller raises mu and repeats.
  bool backward_pass(Scalar& expected_linear, Scalar& expected_quadratic);

  // Mean over the horizon of max_i |k_i| / (|u_i| + 1): iLQG's gradient-based stop.
  Scalar feedforward_norm() const {
    Scalar sum = 0;
    for (int t = 0; t < N; ++t)
      sum += (k_[t].array().abs() / (u_[t].array().abs() + Scalar(1))).maxCoeff();
    return sum / Scalar(N);
  }

  bool increase_regularization() {
    const Scalar f = config_.regularization_factor;
    dmu_ = dmu_ * f > f ? dmu_ * f : f;
    const Scalar next = mu_ * dmu_;
    mu_ = next > config_.regularization_min ? next : config_.regularization_min;
    return mu_ <= config_.regularization_max;
  }

  void decrease_regularization() {
    const Scalar f = config_.regularization_factor;
    dmu_ = dmu_ / f < Scalar(1) / f ? dmu_ / f : Scalar(1) / f;
    mu_ = mu_ * dmu_;
    if (mu_ < config_.regularization_min) mu_ = 0;
  }

  Config config_;
  BoxQpConfig<Scalar> box_config_{};
  std::array<Control, N> lower_{};  // box limits per step, read from the problem each solve
  std::array<Control, N> upper_{};
  bool bounded_ = false;
  Control change_weight_ = Control::Zero();  // read from the problem each solve
  Control previous_ = Control::Zero();       // u_{-1}
  bool changes_ = false;
  Scalar mu_ = 0;
  Scalar dmu_ = 1;
  Scalar cost_ = 0;
  SolveWork work_{};

  StateTrajectory x_;  // nominal (best so far)
  ControlTrajectory u_;
  // Line-search candidates, one per rollout lane (Problem::kRolloutLanes).
  std::array<StateTrajectory, kLanes> x_new_;
  std::array<ControlTrajectory, kLanes> u_new_;
  std::array<Scalar, kLanes> lane_cost_{};
  std::array<std::int32_t, kLanes> lane_steps_{};  // rollout steps each lane completed
  std::array<Control, N> k_;                       // feedforward, Eq. 2.12
  GainTrajectory K_;                               // feedback, Eq. 2.12
  std::array<ControlMatrix, N> Kp_;                // feedback on u_{t-1}'s deviation
  std::array<StateJacobian, N> fx_;
  std::array<ControlJacobian, N> fu_;
  std::array<RunningDerivatives, N> running_;
  TerminalDerivatives terminal_;
  BoxQpSolution<Scalar, kControlDim> box_;
  Eigen::LLT<ControlMatrix> llt_;
};

// The heavy members are defined outside the class, so that they are not inline: a header that
// declares an `extern template class Ilqr<P, N>` keeps every file including it from compiling
// them again for P (the humanoid's problems: a fixed-size backward pass takes GCC tens of
// seconds), and one source instantiates them.

template <class Problem, int N>
typename Ilqr<Problem, N>::Scalar Ilqr<Problem, N>::candidate_cost(const Problem& problem,
                                                                   int lane) {
  const StateTrajectory& x = x_new_[lane];
  const ControlTrajectory& u = u_new_[lane];
  lane_steps_[lane] = N;
  Scalar cost = 0;
  for (int t = 0; t < N; ++t) cost += problem.running_cost(x[t], u[t], t);
  cost += problem.terminal_cost(x[N], N);
  if (changes_) {
    for (int t = 0; t < N; ++t) {
      const Control change = u[t] - (t > 0 ? u[t - 1] : previous_);
      cost += change.dot(change_weight_.cwiseProduct(change));
    }
  }
  return std::isfinite(cost) ? cost : std::numeric_limits<Scalar>::infinity();
}

template <class Problem, int N>
typename Ilqr<Problem, N>::Scalar Ilqr<Problem, N>::rollout_open_loop(const Problem& problem,
                                                                      const State& x0) {
  StateTrajectory& x = x_new_[0];
  ControlTrajectory& u = u_new_[0];
  lane_steps_[0] = 0;
  x[0] = x0;
  for (int t = 0; t < N; ++t) {
    u[t] = clamp(u_[t], t);
    x[t + 1] = problem.rollout_dynamics(x[t], u[t], t, 0);
    if (!x[t + 1].allFinite()) return std::numeric_limits<Scalar>::infinity();
  }
  return candidate_cost(problem, 0);
}

template <class Problem, int N>
typename Ilqr<Problem, N>::Scalar Ilqr<Problem, N>::rollout_closed_loop(const Problem& problem,
                                                                        const State& x0,
                                                                        Scalar alpha, int lane) {
  StateTrajectory& x = x_new_[lane];
  ControlTrajectory& u = u_new_[lane];
  lane_steps_[lane] = 0;
  x[0] = x0;
  for (int t = 0; t < N; ++t) {
    Control ut = u_[t] + alpha * k_[t] + K_[t] * (x[t] - x_[t]);
    if (changes_ && t > 0) ut += Kp_[t] * (u[t - 1] - u_[t - 1]);  // dp_0 = 0: u_{-1} is given
    u[t] = clamp(ut, t);
    x[t + 1] = problem.rollout_dynamics(x[t], u[t], t, lane);
    if (!x[t + 1].allFinite()) return std::numeric_limits<Scalar>::infinity();
  }
  return candidate_cost(problem, lane);
}

template <class Problem, int N>
bool Ilqr<Problem, N>::compute_derivatives(const Problem& problem) {
  work_.derivative_steps += N;
  // The steps are independent: the problem decides where they run (problem.hpp).
  problem.for_each_step(N, [&](int t) {
    problem.dynamics_derivatives(x_[t], u_[t], t, fx_[t], fu_[t]);
    problem.running_cost_derivatives(x_[t], u_[t], t, running_[t]);
  });
  for (int t = 0; t < N; ++t) {
    if (!fx_[t].allFinite() || !fu_[t].allFinite() || !running_[t].lx.allFinite() ||
        !running_[t].lu.allFinite() || !running_[t].lxx.allFinite() ||
        !running_[t].luu.allFinite() || !running_[t].lux.allFinite())
      return false;
  }
  problem.terminal_cost_derivatives(x_[N], N, terminal_);
  return terminal_.lx.allFinite() && terminal_.lxx.allFinite();
}

template <class Problem, int N>
bool Ilqr<Problem, N>::backward_pass(Scalar& expected_linear, Scalar& expected_quadratic) {
  expected_linear = 0;
  expected_quadratic = 0;
  State Vx = terminal_.lx;  // V_N = l_T (text after Eq. 2.16)
  StateJacobian Vxx = terminal_.lxx;
  // The value function's terms in the previous input p (a change penalty only): V_N has none.
  Control Vp = Control::Zero();
  ControlMatrix Vpp = ControlMatrix::Zero();
  ControlJacobian Vxp = ControlJacobian::Zero();
  for (int t = N - 1; t >= 0; --t) {
    ++work_.backward_steps;
    const StateJacobian& A = fx_[t];
    const ControlJacobian& B = fu_[t];
    const RunningDerivatives& l = running_[t];
    const Eigen::Matrix<Scalar, kStateDim, kControlDim> VxxB = Vxx * B;
    const State Qx = l.lx + A.transpose() * Vx;                 // Eq. 2.7
    Control Qu = l.lu + B.transpose() * Vx;                     // Eq. 2.8
    const StateJacobian Qxx = l.lxx + A.transpose() * Vxx * A;  // Eq. 2.9
    Gain Qux = l.lux + VxxB.transpose() * A;                    // Eq. 2.10
    ControlMatrix Quu = l.luu + B.transpose() * VxxB;           // Eq. 2.11
    // The change penalty c = (u - p)' W (u - p) and p' = u: c_u = 2W(u - p) = -c_p,
    // c_uu = c_pp = 2W = -c_up; the next value's p-terms enter through du as they would
    // through a Jacobian [B; I]. Nothing in x's rows changes: p' and c do not depend on x.
    Control Qp = Control::Zero();
    ControlMatrix Qpp = ControlMatrix::Zero();
    ControlMatrix Qup = ControlMatrix::Zero();
    if (changes_) {
      const Control two_w = Scalar(2) * change_weight_;
      const Control change = u_[t] - (t > 0 ? u_[t - 1] : previous_);
      const ControlMatrix BtVxp = B.transpose() * Vxp;
      Qu += two_w.cwiseProduct(change) + Vp;
      Qux += Vxp.transpose() * A;
      Quu += ControlMatrix(two_w.asDiagonal()) + BtVxp + BtVxp.transpose() + Vpp;
      Qp = -two_w.cwiseProduct(change);
      Qpp = two_w.asDiagonal();
      Qup = -Qpp;
    }
    const ControlMatrix Quu_reg = Quu + mu_ * ControlMatrix::Identity();  // LM term

    if (bounded_) {
      // box-DDP: k from the box QP around the nominal control; K on the free set only.
      solve_box_qp(Quu_reg, Qu, Control(lower_[t] - u_[t]), Control(upper_[t] - u_[t]), k_[t], box_,
                   box_config_);
      if (!box_.usable()) return false;
      k_[t] = box_.x;
      for (int j = 0; j < kStateDim; ++j)
        K_[t].col(j) = -box_.free_factor.solve(Qux.col(j).cwiseProduct(box_.free_mask));
      if (changes_) {
        for (int j = 0; j < kControlDim; ++j)
          Kp_[t].col(j) = -box_.free_factor.solve(Qup.col(j).cwiseProduct(box_.free_mask));
      }
    } else {
      llt_.compute(Quu_reg);
      if (llt_.info() != Eigen::Success) return false;
      k_[t] = -llt_.solve(Qu);  // Eq. 2.12
      // Gains column by column: a matrix right-hand side takes Eigen's blocked triangular
      // solver, which may allocate (the firmware's heap guard refuses to link it).
      for (int j = 0; j < kStateDim; ++j) K_[t].col(j) = -llt_.solve(Qux.col(j));
      if (changes_) {
        for (int j = 0; j < kControlDim; ++j) Kp_[t].col(j) = -llt_.solve(Qup.col(j));
      }
    }
    const Control& k = k_[t];
    const Gain& K = K_[t];
    if (!k.allFinite() || !K.allFinite()) return false;

    expected_linear += k.dot(Qu);  // Eq. 2.14
    expected_quadratic += Scalar(0.5) * k.dot(Quu * k);
    // Eqs. 2.15-2.16 in the form that stays exact when k, K are not the unconstrained
    // minimisers (clamped directions, regularisation): Tassa et al. 2012, Eq. 11.
    Vx = Qx + K.transpose() * (Quu * k) + K.transpose() * Qu + Qux.transpose() * k;
    Vxx = Qxx + K.transpose() * Quu * K + K.transpose() * Qux + Qux.transpose() * K;
    Vxx = Scalar(0.5) * (Vxx + Vxx.transpose()).eval();
    if (changes_) {
      // The same formula on the augmented state's p rows, with Q_xp = 0.
      const ControlMatrix& Kp = Kp_[t];
      if (!Kp.allFinite()) return false;
      Vp = Qp + Kp.transpose() * (Quu * k) + Kp.transpose() * Qu + Qup.transpose() * k;
      Vpp = Qpp + Kp.transpose() * Quu * Kp + Kp.transpose() * Qup + Qup.transpose() * Kp;
      Vpp = Scalar(0.5) * (Vpp + Vpp.transpose()).eval();
      Vxp = K.transpose() * Quu * Kp + K.transpose() * Qup + Qux.transpose() * Kp;
    }
  }
  return true;
}

}  // namespace hmpc
