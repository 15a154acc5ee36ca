// The fast subsystem of Sec. 2.5.2 (fast_subsystem.hpp): its leg dynamics are the full model's
// leg rows with the base acceleration zero (Eq. 2.50b), they approach the full model's leg
// motion in proportion to epsilon (Eq. 2.43) as the base's inertia grows, and the problem
// plugs into the Coarse-Fast MPC (Table 2.4).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>

#include "hmpc/humanoid/coarse_fast.hpp"
#include "hmpc/humanoid/fast_subsystem.hpp"
#include "humanoid_test_motions.hpp"

namespace {

using namespace hmpc::humanoid;

// The robot high in the air (no contact), legs moving, torso still.
State airborne() {
  State x = standing_state(ProblemConfig{}, 0.85);
  x.q[2] += 1.0;
  x.q.tail<kJoints>() << 0.1, 0.3, 0.6, -0.1, -0.05, 0.5, 0.2, 0.1;
  x.v.setZero();
  x.v.tail<kJoints>() << 1.0, -2.0, 3.0, 0.5, -1.0, 2.5, -1.5, 1.0;
  return x;
}

JointVector some_torques() {
  JointVector tau;
  tau << 10.0, -30.0, 20.0, 5.0, -8.0, 25.0, -15.0, 3.0;
  return tau;
}

TEST(HumanoidFastSubsystem, EpsilonIsSmall) {
  StepMap map;
  const double epsilon =
      perturbation_parameter(map.dynamics().mass_matrix(standing_state(ProblemConfig{}, 0.85).q));
  std::printf("epsilon at the standing posture: %.3f\n", epsilon);
  EXPECT_GT(epsilon, 0.0);
  EXPECT_LT(epsilon, 0.5);  // M_leg a perturbation of M_base (Sec. 2.5.2)
}

TEST(HumanoidFastSubsystem, LegRowsAreTheFullModelsWithTheBaseHeld) {
  // Eq. 2.50b: M22 zeta_v' = p_z. Over one tiny sub-step the leg acceleration of step_joints must
  // satisfy the full model's inverse dynamics (RNEA, independent of the CRBA the step uses)
  // with the base acceleration zero: leg rows of M [0; a_leg] + c = tau + tau_stop (the end
  // stops).
  StepMap map;
  State x = airborne();
  x.q[7 + kKnee] = -0.02;  // the left knee past full extension: its end stop engaged
  const JointVector tau = some_torques();
  const double h = 1e-6;
  const State next = map.step_joints(x, tau, h);
  EXPECT_EQ(next.q.head<7>(), x.q.head<7>());  // the base is held (Eq. 2.28)
  EXPECT_EQ(next.v.head<6>(), x.v.head<6>());
  Velocity a = Velocity::Zero();
  a.tail<kJoints>() = (next.v - x.v).tail<kJoints>() / h;
  const Velocity generalized = map.dynamics().inverse_dynamics(x.q, x.v, a);
  const Model model;
  // tau + tau_stop with the stops' linearly implicit terms (step.hpp, (S1)).
  JointVector applied = tau;
  for (int j = 0; j < kJoints; ++j) {
    const double qdot = x.v[kBaseDofs + j];
    const JointStop stop =
        joint_stop(x.q[7 + j], qdot, model.joint_lower[j], model.joint_upper[j], Parameters{});
    applied[j] += stop.torque - h * stop.stiffness * qdot -
                  (h * stop.damping + h * h * stop.stiffness) * a[kBaseDofs + j];
  }
  EXPECT_GT((applied - tau).norm(), 1e-4);  // the state touches a stop: the test sees them
  EXPECT_LT((generalized.tail<kJoints>() - applied).norm(), 1e-6 * tau.norm());
  EXPECT_LT((next.q.tail<kJoints>() - (x.q.tail<kJoints>() + h * next.v.tail<kJoints>())).norm(),
            1e-15);
}

TEST(HumanoidFastSubsystem, ReducesToTheFullModelToFirstOrderInEpsilon) {
  // Without gravity (a free fall moves base and legs alike) and with the torso's mass and
  // inertia scaled up, the full model's base barely accelerates: its leg motion approaches the
  // fast subsystem's, with an error proportional to epsilon.
  Parameters parameters;
  parameters.gravity = 0.0;
  const State x = airborne();
  const JointVector tau = some_torques();
  const double dt = kFastStep;
  double previous_error = 0.0, previous_epsilon = 0.0;
  for (double scale : {10.0, 100.0, 1000.0}) {
    Model model(parameters);
    model.bodies[0].mass *= scale;
    model.bodies[0].inertia *= scale;
    StepMap map(model, parameters);
    const double epsilon = perturbation_parameter(map.dynamics().mass_matrix(x.q));
    const State full = map.step(x, tau, dt);
    const State fast = map.step_joints(x, tau, dt);
    const double error = (to_vector(full) - to_vector(fast)).tail<kJoints>().norm() /
                         (to_vector(full) - to_vector(x)).tail<kJoints>().norm();
    std::printf("torso x%g: epsilon %.2e, relative leg-velocity error over %g s %.2e\n", scale,
                epsilon, dt, error);
    EXPECT_LT(error, 10.0 * epsilon);
    if (previous_error > 0.0) {
      // First order: the error shrinks as epsilon does, within a factor 2.
      const double ratio = (error / previous_error) / (epsilon / previous_epsilon);
      EXPECT_GT(ratio, 0.5);
      EXPECT_LT(ratio, 2.0);
    }
    previous_error = error;
    previous_epsilon = epsilon;
  }
}

TEST(HumanoidFastSubsystem, FollowsTheHeldReference) {
  constexpr int kSteps = 4;
  ProblemConfig config;
  config.step = kFastStep;
  Motion m;
  m.weights.fast = 2.0;
  m.weights.fast_control = 0.5;
  FastSubsystem<kSteps> fast(m.weights, config);
  StepMap map(Model{}, Parameters{}, ContactParameters{}, config.max_substep);
  // Reference: the leg motion itself under u_hat, so zeta stays zero with nu = 0.
  State x = standing_state(config, 0.85);
  const JointVector u_hat = some_torques();
  for (int j = 0; j <= kSteps; ++j) {
    fast.set_reference(j, to_vector(x), u_hat);
    x = map.step_joints(x, u_hat, config.step);
  }
  using Zeta = FastSubsystem<kSteps>::State;
  using Nu = FastSubsystem<kSteps>::Control;
  EXPECT_EQ(fast.deviation(to_vector(standing_state(config, 0.85))), Zeta::Zero());
  for (int j = 0; j < kSteps; ++j)
    EXPECT_EQ(fast.dynamics(Zeta::Zero(), Nu::Zero(), j), Zeta::Zero());
  // A deviation nu moves zeta away; the composed input is u_hat + nu (Eq. 2.36), bounded.
  Nu nu = Nu::Zero();
  nu[2] = 5.0;
  EXPECT_GT(fast.dynamics(Zeta::Zero(), nu, 0).norm(), 0.0);
  EXPECT_EQ(fast.compose(u_hat, nu), u_hat + nu);
  const Model model;
  EXPECT_EQ(fast.control_upper_bound(1) + u_hat, model.torque_limit);
  EXPECT_EQ(fast.control_lower_bound(1) + u_hat, -model.torque_limit);
  // Eq. 2.52 and the input deviation's cost.
  Zeta zeta = Zeta::Zero();
  zeta[0] = 0.1;
  EXPECT_DOUBLE_EQ(fast.running_cost(zeta, nu, 0), 2.0 * 0.01 + 0.5 * 25.0);
}

TEST(HumanoidFastSubsystem, CoarseFastUpdateGivesAUsablePlanWithinTheLimits) {
  const Motion motion = test::motion("I-standing");
  const State x0 = standing_state(ProblemConfig{}, motion.phases[0].height);
  ThreadPool pool(2);
  const auto mpc = make_coarse_fast(motion, x0, &pool);
  const auto offline = mpc->initialize(to_vector(x0), kOfflineIterations);
  EXPECT_LT(offline.cost, offline.initial_cost);
  mpc->update(to_vector(x0));
  ASSERT_TRUE(mpc->last_plan_usable());
  const Model model;
  for (int j = 0; j < kFastHorizon; ++j) {
    const JointVector u = mpc->planned_control(j);
    EXPECT_TRUE(u.allFinite());
    EXPECT_TRUE((u.cwiseAbs().array() <= model.torque_limit.array() + 1e-9).all()) << "step " << j;
    // Eq. 2.36: the plan is the upper input held on the fine grid plus the lower layer's nu,
    // which the closed loop's lower-layer figure reads as planned minus held.
    EXPECT_EQ(mpc->planned_control(j) - mpc->held_control(j), mpc->fast_solver().controls()[j]);
  }
}

}  // namespace
