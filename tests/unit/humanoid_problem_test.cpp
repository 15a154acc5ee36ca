// The humanoid's optimal control problem (problem.hpp) and its parallel linearisation on the
// thread pool (thread_pool.hpp; the pool itself: thread_pool_test): the stance helper, each
// cost term of Sec. 4.3.1 against its definition, the Gauss-Newton derivatives, parallel ==
// serial bit for bit, no allocation.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>
#include <memory>
#include <vector>

#include "hmpc/humanoid/coarse_fast.hpp"
#include "hmpc/humanoid/problem.hpp"
#include "hmpc/platform/linux/heap_monitor.hpp"
#include "hmpc/solver/ilqr.hpp"
#include "humanoid_mirror.hpp"
#include "humanoid_test_motions.hpp"

namespace {

using namespace hmpc::humanoid;
namespace heap_monitor = hmpc::platform::heap_monitor;

using test::bare_motion;

State standing() { return standing_state(ProblemConfig{}, 0.85); }

TEST(HumanoidProblem, StandingStateIsAQuietStanceAtTheTarget) {
  const ProblemConfig config;
  const State x = standing();
  const StateCost cost(bare_motion(), x, config);
  const BaseFeatures f = cost.features(x);
  EXPECT_NEAR(f.position.z(), 0.85, 1e-9);
  EXPECT_NEAR((f.quaternion - Eigen::Vector4d(1, 0, 0, 0)).norm(), 0.0, 1e-15);
  // Feet flat, soles sunk by the mean static sink.
  StepMap map;
  const ContactState& c = map.evaluate_contact(x);
  const Model model;
  const double weight = model.total_mass() * -model.gravity.z();
  for (int i = 0; i < kSolePoints; ++i)
    EXPECT_NEAR(c.position[i].z(), -weight / (kSolePoints * config.contact.stiffness), 1e-12);
  // Nearly static: the soles carry the weight and the base rows of M a = tau - c + J'f need
  // under 1 % of it (the joints' torques are free to balance the rest).
  EXPECT_NEAR(vertical_load(c).sole, weight, 0.01 * weight);
  const Velocity residual =
      map.dynamics().bias_forces(x.q, x.v) - ContactModel::generalized_force(c);
  EXPECT_LT(residual.head<6>().norm(), 0.01 * weight);
}

TEST(HumanoidProblem, EachCostTermFollowsItsEquation) {
  const ProblemConfig config;
  const State x0 = standing();
  Motion m = bare_motion();

  // Eq. 4.26: w_height (p_z^r - p_z)^2.
  m.weights = CostWeights{};
  m.weights.height = 3.0;
  State x = x0;
  x.q[2] += 0.01;
  EXPECT_NEAR(StateCost(m, x0, config).value(to_vector(x), 0.0), 3.0 * 0.01 * 0.01, 1e-15);

  // Eq. 4.27: (v^r - v)' W_velocity (v^r - v), world velocity of the base point.
  m.weights = CostWeights{};
  m.weights.velocity << 1.0, 2.0, 3.0;
  m.phases[0].velocity << 0.1, 0.0, 0.0;
  x = x0;
  x.v.segment<3>(3) << 0.3, -0.1, 0.2;
  EXPECT_NEAR(StateCost(m, x0, config).value(to_vector(x), 0.0),
              1.0 * 0.2 * 0.2 + 2.0 * 0.1 * 0.1 + 3.0 * 0.2 * 0.2, 1e-14);
  m.phases[0].velocity.setZero();

  // Eq. 4.25: a yaw of 0.3 rad against the upright target, unit weights: |q - 1|^2.
  m.weights = CostWeights{};
  m.weights.attitude.setOnes();
  x = x0;
  x.q.segment<4>(3) << std::cos(0.15), 0.0, 0.0, std::sin(0.15);
  EXPECT_NEAR(StateCost(m, x0, config).value(to_vector(x), 0.0), 2.0 - 2.0 * std::cos(0.15), 1e-14);
  // ... and zero against a target of that yaw.
  m.phases[0].attitude.z() = 0.3;
  EXPECT_NEAR(StateCost(m, x0, config).value(to_vector(x), 0.0), 0.0, 1e-15);
  m.phases[0].attitude.setZero();

  // Eq. 4.30: omega' W_omega omega, in world coordinates (the torso is yawed here).
  m.weights = CostWeights{};
  m.weights.angular_velocity << 1.0, 0.0, 0.0;
  x.v.head<3>() << 0.2, 0.0, 0.0;  // body x, which the yaw turns off world x
  EXPECT_NEAR(StateCost(m, x0, config).value(to_vector(x), 0.0), std::pow(0.2 * std::cos(0.3), 2),
              1e-14);

  // Sec. 2.7.3's hip position: w_position |p_xy - p_xy(initial)|^2, the base point's, whatever
  // the height; measured from the state the cost was made with.
  m.weights = CostWeights{};
  m.weights.position = 400.0;
  x = x0;
  x.q.head<3>() += Vector3(0.03, -0.04, 0.2);
  EXPECT_NEAR(StateCost(m, x0, config).value(to_vector(x), 0.0), 400.0 * 0.05 * 0.05, 1e-12);
  EXPECT_NEAR(StateCost(m, x, config).value(to_vector(x), 0.0), 0.0, 1e-15);

  // Sec. 2.7.3's joint rates: w_joint_velocity |v_joints|^2 over the legs' joints.
  m.weights = CostWeights{};
  m.weights.joint_velocity = 0.1;
  x = x0;
  x.v.tail<kJoints>() << 1.0, 0.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0;
  x.v.head<6>().setConstant(5.0);  // the base's rates are not the joints'
  EXPECT_NEAR(StateCost(m, x0, config).value(to_vector(x), 0.0), 0.1 * (1.0 + 4.0), 1e-14);
}

TEST(HumanoidProblem, LegAngleTermsFollowTheirEquations) {
  const ProblemConfig config;
  const State x0 = standing();
  Motion m = bare_motion();
  m.weights.alpha = 2.0;
  m.weights.beta = 5.0;
  const StateCost cost(m, x0, config);
  const int left_hip = 7 + kHipFlexion, right_hip = 7 + kJointsPerLeg + kHipFlexion;

  // Eq. 4.29: zero at the initial posture.
  EXPECT_NEAR(cost.residual(to_vector(x0), 0.0).segment<2>(9).norm(), 0.0, 1e-15);

  // Eq. 4.28: straight legs scissored symmetrically put the base midway: alpha_R = alpha_L.
  State x = x0;
  x.q.tail<kJoints>().setZero();
  x.q[left_hip] = 0.2;
  x.q[right_hip] = -0.2;
  BaseFeatures f = cost.features(x);
  EXPECT_LT(f.alpha_right, -0.05);  // right foot behind the base
  EXPECT_NEAR(f.alpha_right - f.alpha_left, 0.0, 1e-12);
  EXPECT_NEAR(cost.residual(to_vector(x), 0.0)[8], 0.0, 1e-12);
  // Both legs forward: the base is behind both feet, and the term grows.
  x.q[right_hip] = 0.2;
  f = cost.features(x);
  EXPECT_NEAR(f.alpha_right, -f.alpha_left, 1e-12);
  EXPECT_NEAR(cost.residual(to_vector(x), 0.0)[8], std::sqrt(2.0) * (f.alpha_right - f.alpha_left),
              1e-15);
  EXPECT_GT(std::abs(f.alpha_right - f.alpha_left), 0.3);

  // Eq. 4.29: abducting the left hip moves beta_L only.
  x = x0;
  x.q[7 + kHipAbduction] += 0.1;
  const StateCost::CostResidual r = cost.residual(to_vector(x), 0.0);
  EXPECT_NEAR(r[9], 0.0, 1e-15);
  EXPECT_GT(std::abs(r[10]), std::sqrt(5.0) * 0.05);
}

TEST(HumanoidProblem, FootHeightTermFollowsTheGait) {
  const ProblemConfig config;
  const State x0 = standing();
  Motion m = bare_motion();
  m.weights.foot = 4.0;
  const Model model;
  const double sink =
      model.total_mass() * -model.gravity.z() / (kSolePoints * config.contact.stiffness);
  State lifted = x0;
  lifted.q[7 + kHipFlexion] = 0.6;  // left thigh forward: the left foot off the ground
  lifted.q[7 + kKnee] = 0.6;
  // Without a gait both feet are asked to stay down: standing feet are at their standing
  // height (sunk by the static load), a lifted one is penalised.
  const StateCost down(m, x0, config);
  for (int k = 0; k < 4; ++k) {
    EXPECT_NEAR(down.features(x0).sole_height[k], -sink, 1e-9);
    EXPECT_NEAR(down.residual(to_vector(x0), 0.1)[14 + k], 2.0 * -sink, 1e-9);
  }
  const BaseFeatures lifted_features = down.features(lifted);
  EXPECT_NEAR(down.residual(to_vector(lifted), 0.1)[14], 2.0 * lifted_features.sole_height[0],
              1e-12);
  EXPECT_NEAR(down.residual(to_vector(lifted), 0.1)[15], 2.0 * lifted_features.sole_height[1],
              1e-12);
  // With a gait the lifted foot's target follows the swing.
  m.gait = Gait{0.6, 0.05, 0.4};
  const StateCost cost(m, x0, config);
  // t = 0.12 s: the left foot half-way through its swing, 5 cm up; the right in stance.
  const StateCost::CostResidual r = cost.residual(to_vector(x0), 0.12);
  EXPECT_NEAR(r[14], 2.0 * (-sink - 0.05), 1e-9);  // left heel
  EXPECT_NEAR(r[15], 2.0 * (-sink - 0.05), 1e-9);  // left toe
  EXPECT_NEAR(r[16], 2.0 * -sink, 1e-9);           // right heel
  EXPECT_NEAR(r[17], 2.0 * -sink, 1e-9);
  const BaseFeatures f = cost.features(lifted);
  EXPECT_GT(f.sole_height[0], 0.02);
  EXPECT_NEAR(cost.residual(to_vector(lifted), 0.12)[14], 2.0 * (f.sole_height[0] - 0.05), 1e-12);
}

// Without a gait (whose left foot steps first) and with upright targets the cost is left-right
// symmetric, like the plant (HumanoidContact.MotionsMirrorInTheSagittalPlane): a lopsided
// state and its mirror image cost the same. Not so with VI's yaw target of pi: Eq. 4.25's
// quaternion difference tells q from -q, and the mirror image of (0, 0, 0, 1) is
// (0, 0, 0, -1), so the half turn costs less one way round than the other.
TEST(HumanoidProblem, CostIsMirrorSymmetric) {
  const Motion m = test::motion("V-low-jump");
  ASSERT_EQ(m.gait.period, 0.0);
  const ProblemConfig config;
  const StateCost cost(m, standing(), config);
  State x = standing();
  x.q.segment<4>(3) = Eigen::Vector4d(1.0, 0.1, 0.2, 0.3).normalized();
  x.q[7 + kHipAbduction] = 0.2;
  x.q[7 + kJointsPerLeg + kKnee] = 0.5;
  x.q[7 + kJointsPerLeg + kAnkle] = -0.2;
  x.v << 0.3, -0.2, 0.5, 1.0, 0.4, -0.3, 1.0, -2.0, 0.5, 0.0, 0.3, 0.1, -0.4, 0.2;
  for (const double t : {0.0, 0.5, 1.0}) {
    const double a = cost.value(to_vector(x), t), b = cost.value(to_vector(test::mirrored(x)), t);
    EXPECT_GT(a, 1.0);
    EXPECT_NEAR(a, b, 1e-12 * a) << "at t = " << t;
  }
  const StateCost half_turn(test::motion("VI-half-turn-jump"), standing(), config);
  const double a = half_turn.value(to_vector(x), 1.0),
               b = half_turn.value(to_vector(test::mirrored(x)), 1.0);
  EXPECT_GT(std::abs(a - b), 0.1 * a);
}

TEST(HumanoidProblem, GaussNewtonGradientIsExactAndHessianPositiveSemidefinite) {
  const ProblemConfig config;
  const State x0 = standing();
  const Motion m = test::motion("V-low-jump");
  const StateCost cost(m, x0, config);
  StateVector x = to_vector(x0);
  Eigen::Matrix<double, kStateSize, 1> perturbation;
  perturbation.setRandom();
  x += 0.05 * perturbation;
  x.segment<4>(3).normalize();
  StateVector lx;
  StateMatrix lxx;
  const double time = 0.5;  // in the jump phase: every term active
  cost.derivatives(x, time, lx, lxx);
  // The walking motion adds the foot heights (its gait).
  const StateCost walking(test::motion("II-walking"), x0, config);
  ASSERT_GT(walking.motion().gait.period, 0.0);
  StateVector walking_lx;
  StateMatrix walking_lxx;
  walking.derivatives(x, time, walking_lx, walking_lxx);
  Eigen::Matrix<double, 1, kStateSize> walking_gradient;
  hmpc::central_difference_jacobian(
      [&](const StateVector& xp) { return Eigen::Matrix<double, 1, 1>(walking.value(xp, time)); },
      x, walking_gradient);
  EXPECT_LT((walking_lx - walking_gradient.transpose()).norm(), 1e-5 * walking_gradient.norm());
  // The hip hold adds the horizontal position and the joint rates (columns set exactly).
  const StateCost hold(test::motion("hip-hold"), x0, config);
  ASSERT_GT(hold.motion().weights.position * hold.motion().weights.joint_velocity, 0.0);
  StateVector hold_lx;
  StateMatrix hold_lxx;
  hold.derivatives(x, time, hold_lx, hold_lxx);
  Eigen::Matrix<double, 1, kStateSize> hold_gradient;
  hmpc::central_difference_jacobian(
      [&](const StateVector& xp) { return Eigen::Matrix<double, 1, 1>(hold.value(xp, time)); }, x,
      hold_gradient);
  EXPECT_LT((hold_lx - hold_gradient.transpose()).norm(), 1e-5 * hold_gradient.norm());
  // The horizontal position and the joint rates enter their own terms alone.
  const CostWeights& w = hold.motion().weights;
  const Vector3 moved = hold.features(to_state(x)).position - hold.features(x0).position;
  EXPECT_NEAR(hold_lx[0], 2.0 * w.position * moved.x(), 1e-9 * std::abs(hold_lx[0]));
  EXPECT_NEAR(hold_lx[1], 2.0 * w.position * moved.y(), 1e-9 * std::abs(hold_lx[1]));
  EXPECT_LT((hold_lx.tail<kJoints>() - 2.0 * w.joint_velocity * x.tail<kJoints>()).norm(), 1e-12);
  Eigen::Matrix<double, 1, kStateSize> gradient;
  hmpc::central_difference_jacobian(
      [&](const StateVector& xp) { return Eigen::Matrix<double, 1, 1>(cost.value(xp, time)); }, x,
      gradient);
  const StateVector numeric = gradient.transpose();
  EXPECT_LT((lx - numeric).norm(), 1e-5 * numeric.norm());
  EXPECT_NEAR((lxx - lxx.transpose()).norm(), 0.0, 1e-12 * lxx.norm());
  const Eigen::SelfAdjointEigenSolver<StateMatrix> eigen(lxx);
  EXPECT_GT(eigen.eigenvalues().minCoeff(), -1e-9 * lxx.norm());
}

TEST(HumanoidProblem, DynamicsIsTheStepMapAndTorquesAreBounded) {
  const ProblemConfig config;
  const State x0 = standing();
  auto problem = std::make_unique<HumanoidProblem<3>>(bare_motion(), x0, config);
  JointVector tau;
  tau.setLinSpaced(-20.0, 20.0);
  StepMap map(Model{}, Parameters{}, ContactParameters{}, config.max_substep);
  const State expected = map.step(x0, tau, config.step);
  EXPECT_EQ(problem->dynamics(to_vector(x0), tau, 2), to_vector(expected));
  const Model model;
  EXPECT_EQ(problem->control_upper_bound(0), model.torque_limit);
  EXPECT_EQ(problem->control_lower_bound(1), -model.torque_limit);
  // The running cost adds Eq. 4.24 to the state terms.
  Motion m = bare_motion();
  m.weights.control = {1.0, 2.0, 3.0, 4.0};
  const HumanoidProblem<3> weighted(m, x0, config);
  JointVector u = JointVector::Zero();
  u[2] = 10.0;  // left knee
  u[7] = -1.0;  // right ankle
  EXPECT_NEAR(weighted.running_cost(to_vector(x0), u, 0), 3.0 * 100.0 + 4.0 * 1.0, 1e-12);
}

// Sec. 2.7.3's change of torques is the iLQR's change penalty (problem.hpp), against the torque
// applied last, off until one is set.
TEST(HumanoidProblem, TorqueChangeIsTheSolversChangePenaltyAgainstTheAppliedTorque) {
  const State x0 = standing();
  Motion m = bare_motion();
  m.weights.torque_change = 0.5;
  auto problem = std::make_unique<HumanoidProblem<3>>(m, x0, ProblemConfig{});
  EXPECT_EQ(problem->control_change_weight(), JointVector::Zero()) << "nothing applied yet";
  JointVector applied = JointVector::Zero();
  applied[1] = 1.0;
  applied[6] = -2.0;
  problem->set_applied_torque(applied);
  EXPECT_EQ(problem->control_change_weight(), JointVector::Constant(0.5));
  EXPECT_EQ(problem->previous_control(), applied);
  const auto plain = std::make_unique<HumanoidProblem<3>>(bare_motion(), x0, ProblemConfig{});
  JointVector u = JointVector::Zero();
  u[1] = 4.0;
  EXPECT_EQ(problem->running_cost(to_vector(x0), u, 0), plain->running_cost(to_vector(x0), u, 0))
      << "the solver adds the term, not the running cost";
}

// One capped iLQR solve of the coarse problem, with or without a pool.
struct Solve {
  using Problem = HumanoidProblem<kCoarseHorizon>;
  using Solver = hmpc::Ilqr<Problem, kCoarseHorizon>;
  StateVector x0 = to_vector(standing());
  std::unique_ptr<Problem> problem;
  std::unique_ptr<Solver> solver;
  explicit Solve(ThreadPool* pool) {
    const Motion m = test::motion("I-standing");
    problem = std::make_unique<Problem>(m, to_state(x0), ProblemConfig{}, pool);
    solver = std::make_unique<Solver>(hmpc::IlqrConfig<double>::with_cap_and_tolerance(3, 1e-9));
  }
  Solver::Result run() { return solver->solve(*problem, x0); }
};

TEST(HumanoidProblem, ParallelLinearisationIsBitIdenticalToSerial) {
  Solve serial(nullptr);
  const auto reference = serial.run();
  ASSERT_TRUE(hmpc::plan_is_usable(reference.status));
  ASSERT_GE(reference.iterations, 2);
  for (int threads : {2, 3}) {
    ThreadPool pool(threads);
    Solve parallel(&pool);
    const auto result = parallel.run();
    EXPECT_EQ(result.iterations, reference.iterations) << threads << " threads";
    EXPECT_EQ(result.cost, reference.cost) << threads << " threads";
    for (int t = 0; t < kCoarseHorizon; ++t) {
      EXPECT_EQ(parallel.solver->controls()[t], serial.solver->controls()[t]) << "step " << t;
      EXPECT_EQ(parallel.solver->feedback_gains()[t], serial.solver->feedback_gains()[t])
          << "step " << t;
    }
    EXPECT_EQ(parallel.solver->states().back(), serial.solver->states().back());
  }
}

TEST(HumanoidProblem, ParallelSolveDoesNotAllocate) {
  ThreadPool pool(2);
  Solve solve(&pool);
  solve.run();  // warm-up
  solve.solver->set_zero_controls();
  const auto before = heap_monitor::allocations();
  heap_monitor::arm();
  const auto result = solve.run();
  heap_monitor::disarm();
  EXPECT_EQ(heap_monitor::allocations() - before, 0u);
  EXPECT_GE(result.iterations, 1);
}

// Eq. 2.53 on the robot with an arm: the last three residuals are sqrt(w_reach) times the
// hand's offset from the target from the reach's start on, zero before; the shoulder torque
// is weighted by w_SFE.
TEST(HumanoidProblem, ReachTermPullsTheHandFromItsStart) {
  const ProblemConfig config;
  const Motion m = test::motion("reaching");
  const BasicState<1> x0 = standing_state<1>(config, 0.85);
  const BasicStateCost<1> cost(m, x0, config);
  const Vector3 hand = cost.features(x0).hand;
  const auto before = cost.residual(to_vector(x0), m.reach.start - 0.01);
  const auto after = cost.residual(to_vector(x0), m.reach.start);
  EXPECT_EQ(before.tail<3>(), Vector3::Zero());
  EXPECT_LE((after.tail<3>() - std::sqrt(m.reach.weight) * (hand - m.reach.target)).norm(), 1e-12);
  EXPECT_EQ(before.head<kCostResiduals<0>>(), after.head<kCostResiduals<0>>());
  EXPECT_EQ(cost.control_weights()[Dimensions<1>::kArmJoint], m.reach.control);
  // Raising the arm forward brings the hand closer: the term's gradient points the right way.
  BasicStateCost<1>::StateVector lx;
  BasicStateCost<1>::StateMatrix lxx;
  cost.derivatives(to_vector(x0), m.reach.start, lx, lxx);
  EXPECT_LT(lx[7 + Dimensions<1>::kArmJoint], 0.0);
}

}  // namespace
