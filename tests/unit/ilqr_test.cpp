// Unit tests of the iLQR core (thesis Sec. 2.2): exactness on LQR problems, convergence on a
// nonlinear swing-up, box limits, line search lanes, iteration budgets and bad input. The
// receding-horizon side (warm start, change of inputs) is in ilqr_receding_horizon_test.cpp,
// a file of its own so that the two compile in parallel.
#include "hmpc/solver/ilqr.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>

#include "ilqr_test_problems.hpp"

namespace {

using namespace ilqr_test;

// FdLq leaves the derivatives to the finite-difference defaults of ProblemBase; AnalyticLq
// supplies them.
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

}  // namespace
