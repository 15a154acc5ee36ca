// Unit tests of the iLQR in a receding horizon (thesis Sec. 2.2, 2.4): the warm start's time
// shift (Eq. 2.22), the penalty on the change of inputs against the input applied last, and
// RecedingHorizonMpc's shifts.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <utility>

#include "hmpc/models/singularly_perturbed_example_mpc.hpp"
#include "hmpc/mpc/receding_horizon_mpc.hpp"
#include "hmpc/solver/ilqr.hpp"
#include "ilqr_test_problems.hpp"

namespace {

using namespace ilqr_test;

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
