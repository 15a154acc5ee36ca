// Unit tests of the iLQR core (thesis Sec. 2.2): exactness on LQR problems, convergence on a
// nonlinear swing-up, box limits, warm start, iteration budgets and bad input.
#include "hmpc/solver/ilqr.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <utility>

#include "hmpc/models/singularly_perturbed_example_mpc.hpp"
#include "hmpc/mpc/receding_horizon_mpc.hpp"

namespace {

constexpr int kNx = 4;
constexpr int kNu = 2;
constexpr int kN = 30;
using Vx = Eigen::Matrix<double, kNx, 1>;
using Vu = Eigen::Matrix<double, kNu, 1>;
using Mxx = Eigen::Matrix<double, kNx, kNx>;
using Mxu = Eigen::Matrix<double, kNx, kNu>;
using Muu = Eigen::Matrix<double, kNu, kNu>;
using Mux = Eigen::Matrix<double, kNu, kNx>;

struct LqData {
  Mxx A, Q, Qf;
  Mxu B;
  Muu R;
  Vu lower = Vu::Constant(-std::numeric_limits<double>::infinity());
  Vu upper = Vu::Constant(std::numeric_limits<double>::infinity());
};

LqData random_lq(unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  LqData d;
  for (int i = 0; i < kNx; ++i)
    for (int j = 0; j < kNx; ++j) d.A(i, j) = (i == j ? 1.0 : 0.0) + 0.15 * n(rng);
  for (int i = 0; i < kNx; ++i)
    for (int j = 0; j < kNu; ++j) d.B(i, j) = 0.5 * n(rng);
  Mxx L;
  for (int i = 0; i < kNx; ++i)
    for (int j = 0; j < kNx; ++j) L(i, j) = n(rng);
  d.Q = L * L.transpose() * 0.1 + Mxx::Identity();
  d.Qf = 5.0 * d.Q;
  d.R = Muu::Identity() * 0.3;
  d.R(0, 1) = d.R(1, 0) = 0.05;
  return d;
}

// Linear dynamics, quadratic cost. FdLq leaves the derivatives to the finite-difference
// defaults of ProblemBase; AnalyticLq supplies them.
template <class Self>
class LqBase : public hmpc::ProblemBase<Self, double, kNx, kNu> {
 public:
  explicit LqBase(const LqData& d) : d_(d) {}
  Vx dynamics(const Vx& x, const Vu& u, int) const { return d_.A * x + d_.B * u; }
  double running_cost(const Vx& x, const Vu& u, int) const {
    return 0.5 * x.dot(d_.Q * x) + 0.5 * u.dot(d_.R * u);
  }
  double terminal_cost(const Vx& x, int) const { return 0.5 * x.dot(d_.Qf * x); }
  Vu control_lower_bound(int) const { return d_.lower; }
  Vu control_upper_bound(int) const { return d_.upper; }

 protected:
  const LqData& d_;
};

class FdLq : public LqBase<FdLq> {
 public:
  using LqBase<FdLq>::LqBase;
};

class AnalyticLq : public LqBase<AnalyticLq> {
 public:
  using LqBase<AnalyticLq>::LqBase;
  void dynamics_derivatives(const Vx&, const Vu&, int, Mxx& fx, Mxu& fu) const {
    fx = d_.A;
    fu = d_.B;
  }
  void running_cost_derivatives(const Vx& x, const Vu& u, int, RunningDerivatives& l) const {
    l.lx = d_.Q * x;
    l.lu = d_.R * u;
    l.lxx = d_.Q;
    l.luu = d_.R;
    l.lux.setZero();
  }
  void terminal_cost_derivatives(const Vx& x, int, TerminalDerivatives& l) const {
    l.lx = d_.Qf * x;
    l.lxx = d_.Qf;
  }
};

// Finite-horizon discrete Riccati recursion: u_t = K_t x_t.
struct RiccatiSolution {
  std::array<Mux, kN> K;
  std::array<Vu, kN> u;
  std::array<Vx, kN + 1> x;
};
RiccatiSolution riccati(const LqData& d, const Vx& x0) {
  RiccatiSolution s;
  Mxx P = d.Qf;
  for (int t = kN - 1; t >= 0; --t) {
    const Muu H = d.R + d.B.transpose() * P * d.B;
    s.K[t] = -H.ldlt().solve(d.B.transpose() * P * d.A);
    P = d.Q + d.A.transpose() * P * (d.A + d.B * s.K[t]);
    P = 0.5 * (P + P.transpose()).eval();
  }
  s.x[0] = x0;
  for (int t = 0; t < kN; ++t) {
    s.u[t] = s.K[t] * s.x[t];
    s.x[t + 1] = d.A * s.x[t] + d.B * s.u[t];
  }
  return s;
}

hmpc::IlqrConfig<double> exact_newton_config() {
  hmpc::IlqrConfig<double> c;
  c.regularization_init = 0;  // plain Newton: one step solves an LQR problem exactly
  c.tolerance = 1e-12;
  return c;
}

TEST(IlqrLqr, MatchesRiccatiWithAnalyticDerivatives) {
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const LqData d = random_lq(seed);
    const AnalyticLq problem(d);
    hmpc::Ilqr<AnalyticLq, kN> solver(exact_newton_config());
    const Vx x0(1.0, -2.0, 0.5, 3.0);
    const auto result = solver.solve(problem, x0);
    ASSERT_EQ(result.status, hmpc::SolveStatus::kConverged) << "seed " << seed;
    const RiccatiSolution ref = riccati(d, x0);
    for (int t = 0; t < kN; ++t) {
      EXPECT_LT((solver.controls()[t] - ref.u[t]).norm(), 1e-9 * (1 + ref.u[t].norm()))
          << "seed " << seed << " t " << t;
      EXPECT_LT((solver.feedback_gains()[t] - ref.K[t]).norm(), 1e-9 * (1 + ref.K[t].norm()))
          << "seed " << seed << " t " << t;
    }
    EXPECT_LE(result.iterations, 2);
  }
}

TEST(IlqrLqr, FiniteDifferenceDerivativesAgreeWithRiccati) {
  const LqData d = random_lq(7);
  const FdLq problem(d);
  hmpc::Ilqr<FdLq, kN> solver(exact_newton_config());
  const Vx x0(1.0, -2.0, 0.5, 3.0);
  solver.solve(problem, x0);
  const RiccatiSolution ref = riccati(d, x0);
  for (int t = 0; t < kN; ++t)
    EXPECT_LT((solver.controls()[t] - ref.u[t]).norm(), 1e-5 * (1 + ref.u[t].norm()));
}

TEST(IlqrLqr, RegularisedStartStillReachesRiccati) {
  const LqData d = random_lq(3);
  const AnalyticLq problem(d);
  hmpc::IlqrConfig<double> config;  // default mu_init = 1: damped first steps
  config.tolerance = 1e-14;
  config.gradient_tolerance = 1e-12;
  config.max_iterations = 200;
  hmpc::Ilqr<AnalyticLq, kN> solver(config);
  const Vx x0(1.0, -2.0, 0.5, 3.0);
  solver.solve(problem, x0);
  const RiccatiSolution ref = riccati(d, x0);
  for (int t = 0; t < kN; ++t)
    EXPECT_LT((solver.controls()[t] - ref.u[t]).norm(), 1e-9 * (1 + ref.u[t].norm()));
}

// Box limits: every returned control lies inside its bounds, and the bounds are active.
TEST(IlqrBox, LimitsNeverViolated) {
  for (unsigned seed = 11; seed <= 15; ++seed) {
    LqData d = random_lq(seed);
    const Vx x0(3.0, -4.0, 2.0, 5.0);
    const RiccatiSolution free = riccati(d, x0);
    double largest = 0;
    for (const auto& u : free.u) largest = std::max(largest, u.cwiseAbs().maxCoeff());
    d.lower = Vu::Constant(-0.3 * largest);
    d.upper = Vu::Constant(0.25 * largest);
    const AnalyticLq problem(d);
    hmpc::Ilqr<AnalyticLq, kN> solver;
    const auto result = solver.solve(problem, x0);
    EXPECT_TRUE(hmpc::plan_is_usable(result.status));
    int active = 0;
    for (const auto& u : solver.controls()) {
      for (int i = 0; i < kNu; ++i) {
        EXPECT_GE(u(i), d.lower(i)) << "seed " << seed;
        EXPECT_LE(u(i), d.upper(i)) << "seed " << seed;
        active += (u(i) == d.lower(i) || u(i) == d.upper(i));
      }
    }
    EXPECT_GT(active, 0) << "bounds chosen to be active";
    EXPECT_LT(result.cost, result.initial_cost);
    // Clamped directions carry no feedback (box-DDP).
    for (int t = 0; t < kN; ++t)
      for (int i = 0; i < kNu; ++i) {
        const double u = solver.controls()[t](i);
        if (u == d.lower(i) || u == d.upper(i)) {
          EXPECT_EQ(solver.feedback_gains()[t].row(i).norm(), 0.0);
        }
      }
  }
}

// Torque-limited pendulum: theta'' = -(g/l) sin(theta) - b theta' + u / (m l^2).
class Pendulum : public hmpc::ProblemBase<Pendulum, double, 2, 1> {
 public:
  static constexpr double kDt = 0.05, kG = 9.81, kL = 1.0, kM = 1.0, kB = 0.1;
  double torque_limit = 2.0;  // below m g l: a swing-up needs pumping
  State dynamics(const State& x, const Control& u, int) const {
    const double acc = -kG / kL * std::sin(x(0)) - kB * x(1) + u(0) / (kM * kL * kL);
    return State(x(0) + kDt * x(1), x(1) + kDt * acc);
  }
  void dynamics_derivatives(const State& x, const Control&, int, StateJacobian& fx,
                            ControlJacobian& fu) const {
    fx << 1.0, kDt, -kDt * kG / kL * std::cos(x(0)), 1.0 - kDt * kB;
    fu << 0.0, kDt / (kM * kL * kL);
  }
  double running_cost(const State& x, const Control& u, int) const {
    return 0.01 * u.squaredNorm() + 0.001 * goal_error(x);
  }
  double terminal_cost(const State& x, int) const { return 100.0 * goal_error(x); }
  Control control_lower_bound(int) const { return Control(-torque_limit); }
  Control control_upper_bound(int) const { return Control(torque_limit); }

 private:
  static double goal_error(const State& x) {
    return (x(0) - M_PI) * (x(0) - M_PI) + 0.1 * x(1) * x(1);
  }
};

TEST(IlqrPendulum, SwingUpConvergesWithinTorqueLimit) {
  Pendulum problem;
  hmpc::IlqrConfig<double> config;
  config.max_iterations = 300;
  config.tolerance = 1e-8;
  hmpc::Ilqr<Pendulum, 100> solver(config);
  const auto result = solver.solve(problem, Pendulum::State(0.0, 0.0));
  EXPECT_EQ(result.status, hmpc::SolveStatus::kConverged);
  const auto& xN = solver.states()[100];
  EXPECT_NEAR(xN(0), M_PI, 0.05);
  EXPECT_NEAR(xN(1), 0.0, 0.2);
  double peak = 0;
  for (const auto& u : solver.controls()) {
    EXPECT_LE(std::abs(u(0)), problem.torque_limit);
    peak = std::max(peak, std::abs(u(0)));
  }
  EXPECT_DOUBLE_EQ(peak, problem.torque_limit) << "the limit binds during the swing-up";
  // The plan is dynamically consistent: rolling its controls out reproduces its states.
  Pendulum::State x(0.0, 0.0);
  for (int t = 0; t < 100; ++t) x = problem.dynamics(x, solver.controls()[t], t);
  EXPECT_LT((x - xN).norm(), 1e-12);
}

// The pendulum with line-search lanes (hmpc/solver/problem.hpp): up to three rollouts per
// round, run here in reverse order, as a thread pool may finish them in any order.
class LanedPendulum : public hmpc::ProblemBase<LanedPendulum, double, 2, 1> {
 public:
  // Hides ProblemBase's 1 on purpose: the solver reads it from the problem type.
  // cppcheck-suppress duplInheritedMember
  static constexpr int kRolloutLanes = 3;
  int lanes = kRolloutLanes;
  mutable std::array<int, kRolloutLanes> lane_steps{};  // rollout_dynamics calls per lane

  int rollout_lanes() const { return lanes; }
  State rollout_dynamics(const State& x, const Control& u, int t, int lane) const {
    ++lane_steps[lane];
    return pendulum.dynamics(x, u, t);
  }
  template <class LaneFunction>
  void for_each_rollout(int count, const LaneFunction& rollout) const {
    for (int lane = count - 1; lane >= 0; --lane) rollout(lane);
  }
  State dynamics(const State& x, const Control& u, int t) const {
    return pendulum.dynamics(x, u, t);
  }
  void dynamics_derivatives(const State& x, const Control& u, int t, StateJacobian& fx,
                            ControlJacobian& fu) const {
    pendulum.dynamics_derivatives(x, u, t, fx, fu);
  }
  double running_cost(const State& x, const Control& u, int t) const {
    return pendulum.running_cost(x, u, t);
  }
  double terminal_cost(const State& x, int t) const { return pendulum.terminal_cost(x, t); }
  Control control_lower_bound(int t) const { return pendulum.control_lower_bound(t); }
  Control control_upper_bound(int t) const { return pendulum.control_upper_bound(t); }

 private:
  Pendulum pendulum;
};

TEST(IlqrLineSearch, LanesTakeTheSameStepsAsOneAtATime) {
  hmpc::IlqrConfig<double> config;
  config.max_iterations = 300;
  config.tolerance = 1e-8;
  Pendulum serial_problem;
  hmpc::Ilqr<Pendulum, 100> serial(config);
  const auto reference = serial.solve(serial_problem, Pendulum::State(0.0, 0.0));
  ASSERT_EQ(reference.status, hmpc::SolveStatus::kConverged);
  for (int lanes : {1, 2, 3}) {
    LanedPendulum problem;
    problem.lanes = lanes;
    hmpc::Ilqr<LanedPendulum, 100> solver(config);
    const auto result = solver.solve(problem, LanedPendulum::State(0.0, 0.0));
    EXPECT_EQ(result.status, reference.status) << lanes << " lanes";
    EXPECT_EQ(result.iterations, reference.iterations) << lanes << " lanes";
    EXPECT_EQ(result.cost, reference.cost) << lanes << " lanes";
    for (int t = 0; t < 100; ++t)
      ASSERT_EQ(solver.controls()[t], serial.controls()[t]) << lanes << " lanes, step " << t;
    // Every lane asked for rolled out (the swing-up backtracks), none beyond.
    for (int lane = 0; lane < LanedPendulum::kRolloutLanes; ++lane) {
      if (lane < lanes) {
        EXPECT_GT(problem.lane_steps[lane], 0) << lanes << " lanes, lane " << lane;
      } else {
        EXPECT_EQ(problem.lane_steps[lane], 0) << lanes << " lanes, lane " << lane;
      }
    }
    // More rollouts in all (a round's later lanes are wasted when an earlier one is accepted).
    if (lanes == 1) {
      EXPECT_EQ(result.work.rollout_steps, reference.work.rollout_steps);
    } else {
      EXPECT_GT(result.work.rollout_steps, reference.work.rollout_steps);
    }
  }
}

TEST(IlqrBudget, IterationBudgetIsHonouredAndPlanImproves) {
  Pendulum problem;
  for (int budget : {1, 2, 3, 5}) {
    hmpc::Ilqr<Pendulum, 100> solver;
    const auto result = solver.solve(problem, Pendulum::State(0.0, 0.0), budget);
    EXPECT_EQ(result.iterations, budget);
    EXPECT_EQ(result.status, hmpc::SolveStatus::kBudgetExhausted);
    EXPECT_LT(result.cost, result.initial_cost);
    EXPECT_DOUBLE_EQ(result.cost, solver.cost());
    // Linearised once per iteration at most: none after the last, which nothing would use.
    EXPECT_LE(result.work.derivative_steps, budget * 100) << "budget " << budget;
  }
}

TEST(IlqrBudget, StopBeforeTheFirstIterationLinearisesNothing) {
  Pendulum problem;
  hmpc::Ilqr<Pendulum, 100> solver;
  const auto result = solver.solve(problem, Pendulum::State(0.0, 0.0), 100, [] { return true; });
  EXPECT_EQ(result.status, hmpc::SolveStatus::kBudgetExhausted);
  EXPECT_EQ(result.iterations, 0);
  EXPECT_EQ(result.work.derivative_steps, 0);
  EXPECT_EQ(result.work.rollout_steps, 100) << "the warm start's rollout only";
  EXPECT_DOUBLE_EQ(result.cost, result.initial_cost);
}

TEST(IlqrBudget, StopPredicateEndsTheSolveWithTheBestPlan) {
  Pendulum problem;
  hmpc::Ilqr<Pendulum, 100> solver;
  int checks = 0;
  const auto result =
      solver.solve(problem, Pendulum::State(0.0, 0.0), 1000, [&checks] { return ++checks > 4; });
  EXPECT_EQ(result.status, hmpc::SolveStatus::kBudgetExhausted);
  EXPECT_EQ(result.iterations, 4);
  EXPECT_LT(result.cost, result.initial_cost);
}

// A deadline that has passed (expired()) ends the solve between line-search rollouts: with
// every step rejected (an unreachable reduction ratio) the search would otherwise run all its
// 11 rollouts per iteration until the regularisation gives up.
TEST(IlqrBudget, ExpiredDeadlineCutsTheLineSearchShort) {
  struct PassedDeadline {
    int asked = 0;
    bool operator()() const { return false; }
    bool expired() { return ++asked > 0; }
  };
  Pendulum problem;
  hmpc::IlqrConfig<double> config;
  config.min_reduction_ratio = 1e9;
  hmpc::Ilqr<Pendulum, 100> unbounded(config), bounded(config);
  const auto full = unbounded.solve(problem, Pendulum::State(0.0, 0.0), 1000);
  EXPECT_EQ(full.status, hmpc::SolveStatus::kStalled);
  EXPECT_GE(full.work.rollout_steps, 100 + 11 * 100);
  PassedDeadline deadline;
  const auto cut = bounded.solve(problem, Pendulum::State(0.0, 0.0), 1000, deadline);
  EXPECT_EQ(cut.status, hmpc::SolveStatus::kBudgetExhausted);
  EXPECT_EQ(deadline.asked, 1);
  EXPECT_EQ(cut.iterations, 1);
  EXPECT_EQ(cut.work.rollout_steps, 100 + 100) << "the warm start and one line-search rollout";
  EXPECT_DOUBLE_EQ(cut.cost, cut.initial_cost) << "the nominal plan is kept";
}

TEST(IlqrWarmStart, TimeShiftCutsIterations) {
  // The Coarse MPC of Sec. 2.4 (10 ms step, N = 40) closed loop for 0.4 s at 1 ms: warm
  // started by the time shift of Eq. 2.22 against a cold start from zero inputs each sample.
  using namespace hmpc::sec24;
  const Parameters<double> p;
  const FullProblem<double> coarse(p, kCoarseStep);
  hmpc::Ilqr<FullProblem<double>, kCoarseHorizon> warm(solver_config<double>());
  hmpc::Ilqr<FullProblem<double>, kCoarseHorizon> cold(solver_config<double>());
  Vector2<double> x_warm = initial_state<double>(), x_cold = x_warm;
  warm.solve(coarse, x_warm);
  int warm_iterations = 0, cold_iterations = 0;
  for (int k = 0; k < kSamples; ++k) {
    warm_iterations += warm.solve(coarse, x_warm).iterations;
    x_warm = integrate_plant(p, x_warm, Vector2<double>(warm.controls()[0]), kSamplingPeriod);
    if ((k + 1) % kSamplesPerCoarseStep == 0) warm.shift(1);
    cold.reset();
    cold_iterations += cold.solve(coarse, x_cold).iterations;
    x_cold = integrate_plant(p, x_cold, Vector2<double>(cold.controls()[0]), kSamplingPeriod);
  }
  EXPECT_LT(warm_iterations * 2, cold_iterations)
      << "warm " << warm_iterations << " cold " << cold_iterations;
  EXPECT_LT((x_warm - x_cold).norm(), 1e-3) << "both reach the same closed loop";
}

TEST(IlqrWarmStart, ShiftRepeatsTheLastControl) {
  Pendulum problem;
  hmpc::Ilqr<Pendulum, 10> solver;
  solver.solve(problem, Pendulum::State(0.3, 0.0));
  const auto before = solver.controls();
  solver.shift(3);
  for (int t = 0; t < 7; ++t) EXPECT_EQ(solver.controls()[t], before[t + 3]);
  for (int t = 7; t < 10; ++t) EXPECT_EQ(solver.controls()[t], before[9]);
}

TEST(IlqrBadInput, NonFiniteInitialStateKeepsThePreviousPlan) {
  Pendulum problem;
  hmpc::Ilqr<Pendulum, 50> solver;
  solver.solve(problem, Pendulum::State(0.1, 0.0));
  const auto plan = solver.controls();
  for (double bad :
       {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    const auto result = solver.solve(problem, Pendulum::State(bad, 0.0));
    EXPECT_EQ(result.status, hmpc::SolveStatus::kInvalidInput);
    EXPECT_FALSE(hmpc::plan_is_usable(result.status));
    for (int t = 0; t < 50; ++t) EXPECT_EQ(solver.controls()[t], plan[t]);
  }
}

TEST(IlqrBadInput, NonFiniteWarmStartIsRejected) {
  Pendulum problem;
  hmpc::Ilqr<Pendulum, 50> solver;
  hmpc::Ilqr<Pendulum, 50>::ControlTrajectory garbage{};
  garbage[7](0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(solver.set_controls(garbage));
  const auto result = solver.solve(problem, Pendulum::State(0.1, 0.0));
  EXPECT_TRUE(hmpc::plan_is_usable(result.status));
  for (const auto& u : solver.controls()) EXPECT_TRUE(u.allFinite());
}

// A model that blows up (NaN) beyond a state region, and one whose cost is NaN everywhere.
class Fragile : public hmpc::ProblemBase<Fragile, double, 1, 1> {
 public:
  bool poisoned_cost = false;
  State dynamics(const State& x, const Control& u, int) const {
    const State next(x(0) + 0.1 * u(0));
    return std::abs(next(0)) > 2.0 ? State(std::numeric_limits<double>::quiet_NaN()) : next;
  }
  double running_cost(const State& x, const Control& u, int) const {
    return poisoned_cost ? std::numeric_limits<double>::quiet_NaN()
                         : (x(0) - 5.0) * (x(0) - 5.0) + 1e-4 * u.squaredNorm();
  }
  double terminal_cost(const State& x, int) const { return 10 * (x(0) - 5.0) * (x(0) - 5.0); }
};

TEST(IlqrBadInput, NonFiniteModelOutputNeverReachesThePlan) {
  Fragile problem;  // the target x = 5 lies in the region where the model returns NaN
  hmpc::Ilqr<Fragile, 40> solver;
  const auto result = solver.solve(problem, Fragile::State(0.0));
  EXPECT_TRUE(std::isfinite(result.cost));
  for (const auto& u : solver.controls()) EXPECT_TRUE(u.allFinite());
  for (const auto& x : solver.states()) {
    EXPECT_TRUE(x.allFinite());
    EXPECT_LE(std::abs(x(0)), 2.0);
  }
  problem.poisoned_cost = true;
  const auto poisoned = solver.solve(problem, Fragile::State(0.0));
  EXPECT_EQ(poisoned.status, hmpc::SolveStatus::kNumericalFailure);
  for (const auto& u : solver.controls()) EXPECT_TRUE(u.allFinite());
}

// The change-of-inputs penalty (problem.hpp's control_change_weight) on the LQ problem: with
// it the problem stays a quadratic program in the stacked inputs, so one Newton step must land
// on the program's minimiser, where its gradient vanishes. The weights differ per input and
// the input applied before the horizon is not zero, so every term of the exact recursion shows.
class ChangingLq : public LqBase<ChangingLq> {
 public:
  ChangingLq(const LqData& d, const Vu& weight, const Vu& previous)
      : LqBase<ChangingLq>(d), weight_(weight), previous_(previous) {}
  Vu control_change_weight() const { return weight_; }
  Vu previous_control() const { return previous_; }

 private:
  Vu weight_, previous_;
};

// J(U) = 1/2 U' H U + g' U + const over the stacked inputs U = (u_0..u_{N-1}).
struct DenseQp {
  Eigen::MatrixXd H;
  Eigen::VectorXd g;
};
// With x_t = Phi_t x0 + Gamma_t U.
DenseQp dense_change_qp(const LqData& d, const Vx& x0, const Vu& w, const Vu& previous) {
  constexpr int kU = kN * kNu;
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(kU, kU);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(kU);
  Eigen::MatrixXd gamma = Eigen::MatrixXd::Zero(kNx, kU);  // x_t's dependence on U
  Vx phi = x0;                                             // x_t with U = 0
  for (int t = 0; t <= kN; ++t) {
    const Mxx& Q = t < kN ? d.Q : d.Qf;
    H += gamma.transpose() * Q * gamma;
    g += gamma.transpose() * Q * phi;
    if (t == kN) break;
    H.block<kNu, kNu>(t * kNu, t * kNu) += d.R;
    // (u_t - u_{t-1})' W (u_t - u_{t-1}), u_{-1} = previous.
    const Muu W2 = 2.0 * Muu(w.asDiagonal());
    H.block<kNu, kNu>(t * kNu, t * kNu) += W2;
    if (t > 0) {
      H.block<kNu, kNu>((t - 1) * kNu, (t - 1) * kNu) += W2;
      H.block<kNu, kNu>(t * kNu, (t - 1) * kNu) -= W2;
      H.block<kNu, kNu>((t - 1) * kNu, t * kNu) -= W2;
    } else {
      g.segment<kNu>(0) -= W2 * previous;
    }
    gamma = (d.A * gamma).eval();
    gamma.block<kNx, kNu>(0, t * kNu) += d.B;
    phi = (d.A * phi).eval();
  }
  return DenseQp{H, g};
}

TEST(IlqrInputChange, OneNewtonStepSolvesTheQuadraticProgram) {
  const Vu w(0.7, 2.0), previous(0.4, -0.3);
  const Vx x0(1.0, -2.0, 0.5, 3.0);
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const LqData d = random_lq(seed);
    const ChangingLq problem(d, w, previous);
    hmpc::Ilqr<ChangingLq, kN> solver(exact_newton_config());
    const auto result = solver.solve(problem, x0);
    ASSERT_EQ(result.status, hmpc::SolveStatus::kConverged) << "seed " << seed;
    // Newton: the first step is the solution, the next finds nothing left (seed 2's H, of
    // condition 1e12, needs a third, the penalty on or off). A recursion that
    // misses one of the previous input's terms still descends (the line search sees the true
    // cost) but takes 8 to 50 iterations here.
    EXPECT_LE(result.iterations, 3) << "seed " << seed;
    // The gradient H U + g against its terms' size (a dense solve of this H, as ill-conditioned
    // as A^30 makes it, would be no accurate reference). The recursion's own rounding leaves up
    // to 3e-8 with the penalty off (measured on these seeds, as against 1e-16 for Riccati's
    // plan): the bound is 3x that.
    const DenseQp qp = dense_change_qp(d, x0, w, previous);
    Eigen::VectorXd u(kN * kNu);
    for (int t = 0; t < kN; ++t) u.segment<kNu>(t * kNu) = solver.controls()[t];
    const double scale = (qp.H * u).norm() + qp.g.norm();
    EXPECT_LT((qp.H * u + qp.g).norm(), 1e-7 * scale) << "seed " << seed;
    // The reported cost includes the term.
    double cost = 0;
    Vx x = x0;
    for (int t = 0; t < kN; ++t) {
      const Vu& ut = solver.controls()[t];
      const Vu change = ut - (t > 0 ? solver.controls()[t - 1] : previous);
      cost += 0.5 * x.dot(d.Q * x) + 0.5 * ut.dot(d.R * ut) + change.dot(w.cwiseProduct(change));
      x = d.A * x + d.B * ut;
    }
    cost += 0.5 * x.dot(d.Qf * x);
    EXPECT_NEAR(result.cost, cost, 1e-12 * cost) << "seed " << seed;
    // Without the penalty the plan is Riccati's, which the penalty must have moved.
    const RiccatiSolution free = riccati(d, x0);
    EXPECT_GT((solver.controls()[0] - free.u[0]).norm(), 1e-3);
  }
}

// A torque-limited pendulum with analytic cost derivatives, solved twice: with the solver's
// change penalty, and as DDP on the state augmented with the previous input (x, p), p' = u,
// with (u - p)' W (u - p) in its running cost. The two are the same algorithm, so they must take
// the same steps, with the limit binding and feedback on the previous input.
struct PendulumTerms {
  static constexpr double kDt = 0.05, kG = 9.81, kB = 0.1, kLimit = 2.0, kWeight = 0.05;
  static constexpr double kPrevious = -0.8;
  static double acceleration(double theta, double omega, double u) {
    return -kG * std::sin(theta) - kB * omega + u;
  }
  // 0.01 u^2 + 0.001 r(x) per step, r = (theta - pi)^2 + 0.1 omega^2; 100 r at the end.
  static double goal(double theta, double omega) {
    return (theta - M_PI) * (theta - M_PI) + 0.1 * omega * omega;
  }
};

class ChangingPendulum : public hmpc::ProblemBase<ChangingPendulum, double, 2, 1> {
 public:
  using P = PendulumTerms;
  State dynamics(const State& x, const Control& u, int) const {
    return State(x(0) + P::kDt * x(1), x(1) + P::kDt * P::acceleration(x(0), x(1), u(0)));
  }
  void dynamics_derivatives(const State& x, const Control&, int, StateJacobian& fx,
                            ControlJacobian& fu) const {
    fx << 1.0, P::kDt, -P::kDt * P::kG * std::cos(x(0)), 1.0 - P::kDt * P::kB;
    fu << 0.0, P::kDt;
  }
  double running_cost(const State& x, const Control& u, int) const {
    return 0.01 * u.squaredNorm() + 0.001 * P::goal(x(0), x(1));
  }
  double terminal_cost(const State& x, int) const { return 100.0 * P::goal(x(0), x(1)); }
  void running_cost_derivatives(const State& x, const Control& u, int,
                                RunningDerivatives& d) const {
    d.lx << 0.002 * (x(0) - M_PI), 0.0002 * x(1);
    d.lxx << 0.002, 0.0, 0.0, 0.0002;
    d.lu = 0.02 * u;
    d.luu.setConstant(0.02);
    d.lux.setZero();
  }
  void terminal_cost_derivatives(const State& x, int, TerminalDerivatives& d) const {
    d.lx << 200.0 * (x(0) - M_PI), 20.0 * x(1);
    d.lxx << 200.0, 0.0, 0.0, 20.0;
  }
  Control control_change_weight() const { return Control(P::kWeight); }
  Control previous_control() const { return Control(P::kPrevious); }
  Control control_lower_bound(int) const { return Control(-P::kLimit); }
  Control control_upper_bound(int) const { return Control(P::kLimit); }
};

class AugmentedPendulum : public hmpc::ProblemBase<AugmentedPendulum, double, 3, 1> {
 public:
  using P = PendulumTerms;
  State dynamics(const State& x, const Control& u, int) const {
    return State(x(0) + P::kDt * x(1), x(1) + P::kDt * P::acceleration(x(0), x(1), u(0)), u(0));
  }
  void dynamics_derivatives(const State& x, const Control&, int, StateJacobian& fx,
                            ControlJacobian& fu) const {
    fx << 1.0, P::kDt, 0.0, -P::kDt * P::kG * std::cos(x(0)), 1.0 - P::kDt * P::kB, 0.0, 0.0, 0.0,
        0.0;
    fu << 0.0, P::kDt, 1.0;
  }
  double running_cost(const State& x, const Control& u, int) const {
    return 0.01 * u.squaredNorm() + 0.001 * P::goal(x(0), x(1)) +
           P::kWeight * (u(0) - x(2)) * (u(0) - x(2));
  }
  double terminal_cost(const State& x, int) const { return 100.0 * P::goal(x(0), x(1)); }
  void running_cost_derivatives(const State& x, const Control& u, int,
                                RunningDerivatives& d) const {
    const double change = u(0) - x(2);
    d.lx << 0.002 * (x(0) - M_PI), 0.0002 * x(1), -2.0 * P::kWeight * change;
    d.lxx.setZero();
    d.lxx(0, 0) = 0.002;
    d.lxx(1, 1) = 0.0002;
    d.lxx(2, 2) = 2.0 * P::kWeight;
    d.lu(0) = 0.02 * u(0) + 2.0 * P::kWeight * change;
    d.luu(0, 0) = 0.02 + 2.0 * P::kWeight;
    d.lux << 0.0, 0.0, -2.0 * P::kWeight;
  }
  void terminal_cost_derivatives(const State& x, int, TerminalDerivatives& d) const {
    d.lx << 200.0 * (x(0) - M_PI), 20.0 * x(1), 0.0;
    d.lxx.setZero();
    d.lxx(0, 0) = 200.0;
    d.lxx(1, 1) = 20.0;
  }
  Control control_lower_bound(int) const { return Control(-PendulumTerms::kLimit); }
  Control control_upper_bound(int) const { return Control(PendulumTerms::kLimit); }
};

TEST(IlqrInputChange, TakesTheStepsOfDdpOnTheStateAugmentedWithThePreviousInput) {
  constexpr int kSteps = 100;
  hmpc::IlqrConfig<double> config;
  config.tolerance = 1e-8;
  const ChangingPendulum changing;
  const AugmentedPendulum augmented;
  for (const int budget : {1, 2, 5, 300}) {
    hmpc::Ilqr<ChangingPendulum, kSteps> solver(config);
    hmpc::Ilqr<AugmentedPendulum, kSteps> reference(config);
    const auto result = solver.solve(changing, ChangingPendulum::State(0.0, 0.0), budget);
    const auto expected = reference.solve(
        augmented, AugmentedPendulum::State(0.0, 0.0, PendulumTerms::kPrevious), budget);
    ASSERT_EQ(result.iterations, expected.iterations) << "budget " << budget;
    EXPECT_EQ(result.status, expected.status) << "budget " << budget;
    EXPECT_NEAR(result.cost, expected.cost, 1e-9 * expected.cost) << "budget " << budget;
    int bound = 0;
    for (int t = 0; t < kSteps; ++t) {
      EXPECT_NEAR(solver.controls()[t](0), reference.controls()[t](0), 1e-8)
          << "budget " << budget << " t " << t;
      bound += std::abs(solver.controls()[t](0)) == PendulumTerms::kLimit;
    }
    if (budget == 300) {
      EXPECT_EQ(result.status, hmpc::SolveStatus::kConverged);
      EXPECT_GT(bound, 0) << "the limit binds during the swing-up";
      EXPECT_NEAR(solver.states()[kSteps](0), M_PI, 0.1);
    }
  }
}

TEST(IlqrBadInput, NonFinitePreviousInputKeepsThePreviousPlan) {
  const LqData d = random_lq(2);
  const Vx x0(1.0, -2.0, 0.5, 3.0);
  hmpc::Ilqr<ChangingLq, kN> solver(exact_newton_config());
  solver.solve(ChangingLq(d, Vu(1.0, 1.0), Vu::Zero()), x0);
  const auto plan = solver.controls();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const auto& [w, previous] :
       {std::pair<Vu, Vu>(Vu(1.0, 1.0), Vu(nan, 0.0)), std::pair<Vu, Vu>(Vu(1.0, nan), Vu::Zero()),
        std::pair<Vu, Vu>(Vu(std::numeric_limits<double>::infinity(), 1.0), Vu::Zero())}) {
    const auto result = solver.solve(ChangingLq(d, w, previous), x0);
    EXPECT_EQ(result.status, hmpc::SolveStatus::kInvalidInput);
    for (int t = 0; t < kN; ++t) EXPECT_EQ(solver.controls()[t], plan[t]);
  }
}

TEST(RecedingHorizonMpc, ShiftsOncePerModelStep) {
  Pendulum problem;
  using Mpc = hmpc::RecedingHorizonMpc<Pendulum, 20>;
  // With an iteration cap of 0 nothing is re-optimised online: the plan only moves by the
  // shift of Eq. 2.22, once every 5 samples.
  Mpc frozen(problem, {5, [] {
                         hmpc::IlqrConfig<double> c;
                         c.max_iterations = 0;
                         return c;
                       }()});
  frozen.initialize(Pendulum::State(0.2, 0.0), 100);
  const auto plan = frozen.solver().controls();
  for (int k = 0; k < 5; ++k) EXPECT_EQ(frozen.update(Pendulum::State(0.2, 0.0)), plan[0]);
  EXPECT_EQ(frozen.update(Pendulum::State(0.2, 0.0)), plan[1]);
}

TEST(RecedingHorizonMpc, AppliesAndShiftsSeveralStepsPerSample) {
  Pendulum problem;
  using Mpc = hmpc::RecedingHorizonMpc<Pendulum, 20>;
  Mpc::Config config;
  config.solver.max_iterations = 0;
  config.steps_per_sample = 3;
  Mpc frozen(problem, config);
  frozen.initialize(Pendulum::State(0.2, 0.0), 100);
  const auto plan = frozen.solver().controls();
  EXPECT_EQ(frozen.update(Pendulum::State(0.2, 0.0)), plan[0]);
  for (int j = 0; j < 3; ++j) EXPECT_EQ(frozen.planned_control(j), plan[j]);
  EXPECT_EQ(frozen.update(Pendulum::State(0.2, 0.0)), plan[3]);
  EXPECT_EQ(frozen.planned_control(2), plan[5]);
}

}  // namespace
