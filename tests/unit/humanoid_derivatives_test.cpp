// The step map's linearisation (step.hpp, (L1)-(L2): chain rule over the sub-steps, analytic
// derivatives of the residual r) against central differences of whole steps, through the two
// problems' dynamics_derivatives: standing, random and seated states, in and out of contact,
// with the rotation guard shortening sub-steps, and the fast subsystem's legs; the next state
// is step()'s; nothing allocates.
//
// References and tolerances (every Jacobian column within the tolerance of the reference's,
// relative to max(1, |reference column|)):
//   - the problems' reference path (Linearisation::kWholeStepDifferences, ProblemBase's central
//     differences with step eps^(1/3) = 6e-6) where that step is accurate: kReferenceTolerance;
//   - elsewhere in contact it is not: a 30 ms step through the stiff contact (1 mm softplus
//     length, 5 ms sub-steps) curves so sharply that at one of the random stances below its
//     6e-6 step is 30 % off, converging to the linearisation as the step shrinks (1 % at 1e-6,
//     1e-4 at 1e-7). There the reference is the same central difference Richardson-
//     extrapolated from steps 4e-7 and 2e-7 (truncation O(step^4)), kRefinedTolerance.
// The linearisation's own error is round-off; the forward differences of r it replaced (kept
// as ResidualJacobian::kForwardDifferences) erred by their step sqrt(eps) = 1.5e-8 against the
// contact's 1 mm length, 1.5e-5 relative, 8e-6 measured against the refined reference. The
// analytic one measures 3e-7 against the refined reference (the reference's own error) and
// 1.9e-5 against the reference path (seated, the path's error; each test prints its errors),
// so the tolerances leave a factor of 2.5 or more.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>

#include "hmpc/humanoid/fast_subsystem.hpp"
#include "hmpc/platform/linux/heap_monitor.hpp"
#include "humanoid_test_motions.hpp"

namespace {

using namespace hmpc::humanoid;
namespace heap_monitor = hmpc::platform::heap_monitor;

constexpr double kReferenceTolerance = 1e-4;
constexpr double kRefinedTolerance = 5e-5;

// Central differences of f at x, Richardson-extrapolated from steps 4e-7 and 2e-7.
template <class Function, class Vector, class Jacobian>
void refined_difference(const Function& f, const Vector& x, Jacobian& jacobian) {
  for (int i = 0; i < x.size(); ++i) {
    const auto central = [&](double step) {
      Vector plus = x, minus = x;
      plus[i] += step;
      minus[i] -= step;
      return decltype(f(x))((f(plus) - f(minus)) / (2.0 * step));
    };
    jacobian.col(i) = (4.0 * central(2e-7) - central(4e-7)) / 3.0;
  }
}

template <class A, class B>
double worst_column_error(const A& linearised, const B& reference) {
  double worst = 0.0;
  for (int c = 0; c < reference.cols(); ++c) {
    const double scale = std::max(1.0, reference.col(c).norm());
    worst = std::max(worst, (linearised.col(c) - reference.col(c)).norm() / scale);
  }
  return worst;
}

using test::bare_motion;

ProblemConfig reference_config(ProblemConfig config) {
  config.linearisation = Linearisation::kWholeStepDifferences;
  return config;
}

// The full model's Jacobians through HumanoidProblem (one horizon step), and the references.
struct FullModel {
  using Problem = HumanoidProblem<1>;
  ProblemConfig config;
  std::unique_ptr<Problem> linearised, reference;
  std::unique_ptr<StepMap> map;
  explicit FullModel(const ProblemConfig& c = ProblemConfig{}) : config(c) {
    const State x0 = standing_state(config, 0.85);
    linearised = std::make_unique<Problem>(bare_motion(), x0, config);
    reference = std::make_unique<Problem>(bare_motion(), x0, reference_config(config));
    map = std::make_unique<StepMap>(Model(config.parameters), config.parameters, config.contact,
                                    config.max_substep);
  }
  // Worst column errors of fx and fu against the reference path, or the refined reference.
  std::pair<double, double> errors(const State& x, const JointVector& tau, bool refined) const {
    Problem::StateJacobian fx, fx_reference;
    Problem::ControlJacobian fu, fu_reference;
    linearised->dynamics_derivatives(to_vector(x), tau, 0, fx, fu);
    if (refined) {
      refined_difference(
          [&](const StateVector& xp) {
            return to_vector(map->step(to_state(xp), tau, config.step));
          },
          to_vector(x), fx_reference);
      refined_difference(
          [&](const JointVector& up) { return to_vector(map->step(x, up, config.step)); }, tau,
          fu_reference);
    } else {
      reference->dynamics_derivatives(to_vector(x), tau, 0, fx_reference, fu_reference);
    }
    return {worst_column_error(fx, fx_reference), worst_column_error(fu, fu_reference)};
  }
};

State standing() { return standing_state(ProblemConfig{}, 0.85); }

// Joint angles and rates, base velocity, tilt and height drawn around the stance; `lift`
// raises the body (0: feet in the ground as standing).
State random_state(std::mt19937& rng, double lift) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  State x = standing();
  for (int i = 0; i < kJoints; ++i) x.q[7 + i] += 0.1 * unit(rng);
  Eigen::Vector4d quaternion(1.0, 0.05 * unit(rng), 0.05 * unit(rng), 0.2 * unit(rng));
  x.q.segment<4>(3) = quaternion.normalized();
  x.q[2] += lift;
  for (int i = 0; i < kBaseDofs; ++i) x.v[i] = 0.3 * unit(rng);
  for (int i = kBaseDofs; i < kDofs; ++i) x.v[i] = 2.0 * unit(rng);
  return x;
}

JointVector random_torques(std::mt19937& rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  JointVector tau;
  for (int i = 0; i < kJoints; ++i) tau[i] = 20.0 * unit(rng);
  return tau;
}

TEST(HumanoidDerivatives, StandingMatchesTheReference) {
  const FullModel model;
  JointVector tau;
  tau << 5.0, -10.0, 15.0, -5.0, -5.0, 10.0, -15.0, 5.0;
  StepMap map;
  ASSERT_GT(vertical_load(map.evaluate_contact(standing())).sole, 400.0);  // in contact
  const auto [fx, fu] = model.errors(standing(), tau, false);
  std::printf("standing: worst column error fx %.1e, fu %.1e\n", fx, fu);
  EXPECT_LT(fx, kReferenceTolerance);
  EXPECT_LT(fu, kReferenceTolerance);
}

TEST(HumanoidDerivatives, RandomStatesMatchTheRefinedReference) {
  const FullModel model;
  StepMap map;
  std::mt19937 rng(5);
  int in_contact = 0;
  for (int trial = 0; trial < 8; ++trial) {
    // Half of them in the ground, half 2-20 cm above it (falling, touching down or not).
    const double lift = trial % 2 == 0 ? 0.0 : 0.02 + 0.02 * trial;
    const State x = random_state(rng, lift);
    const JointVector tau = random_torques(rng);
    in_contact += vertical_load(map.evaluate_contact(x)).sole > 10.0 ? 1 : 0;
    const auto [fx, fu] = model.errors(x, tau, true);
    std::printf("random state %d: worst column error fx %.1e, fu %.1e\n", trial, fx, fu);
    EXPECT_LT(fx, kRefinedTolerance) << "trial " << trial;
    EXPECT_LT(fu, kRefinedTolerance) << "trial " << trial;
  }
  EXPECT_GE(in_contact, 4);
}

TEST(HumanoidDerivatives, ShortenedSubStepsMatchTheReference) {
  // Joint rates up to 50 rad/s exceed the rotation guard's 0.2 rad per 5 ms sub-step: the
  // sub-step lengths depend on the state, and their derivatives enter. (One fastest joint:
  // at a tie the guard's rate, a max, has no derivative.) Feet 4 cm above the ground.
  const FullModel model;
  State x = standing();
  x.q[2] += 0.05;
  x.v.tail<kJoints>() << 50.0, -45.0, 48.0, 30.0, -20.0, 44.0, -40.0, 10.0;
  const auto [fx, fu] = model.errors(x, JointVector::Constant(5.0), false);
  std::printf("shortened sub-steps: worst column error fx %.1e, fu %.1e\n", fx, fu);
  EXPECT_LT(fx, kReferenceTolerance);
  EXPECT_LT(fu, kReferenceTolerance);
}

TEST(HumanoidDerivatives, JointsAtTheirStopsMatchTheRefinedReference) {
  // The end stops (Parameters::stop_*), linearly implicit in the step map: knees 0.03 rad past
  // full extension and moving further, a hip at its flexion limit, an ankle inside the stop's
  // rounded corner; the body 3 cm above the ground.
  const FullModel model;
  const Model limits;
  State x = standing();
  x.q[2] += 0.03;
  x.q[7 + kKnee] = limits.joint_lower[kKnee] - 0.03;
  x.q[7 + kJointsPerLeg + kKnee] = limits.joint_lower[kKnee] - 0.03;
  x.q[7 + kHipFlexion] = limits.joint_upper[kHipFlexion];
  x.q[7 + kJointsPerLeg + kAnkle] = limits.joint_upper[kAnkle] - 0.01;
  x.v.tail<kJoints>() << 0.5, 2.0, -3.0, 1.0, -0.5, 1.0, -2.5, 1.5;
  JointVector tau;
  tau << 5.0, 30.0, -40.0, 5.0, -5.0, 10.0, -40.0, 20.0;
  double stop_torque = 0.0;
  for (int j = 0; j < kJoints; ++j) {
    stop_torque += std::abs(joint_stop(x.q[7 + j], x.v[kBaseDofs + j], limits.joint_lower[j],
                                       limits.joint_upper[j], Parameters{})
                                .torque);
  }
  ASSERT_GT(stop_torque, 100.0);  // the stops are engaged
  const auto [fx, fu] = model.errors(x, tau, true);
  std::printf("joints at their stops: worst column error fx %.1e, fu %.1e\n", fx, fu);
  EXPECT_LT(fx, kRefinedTolerance);
  EXPECT_LT(fu, kRefinedTolerance);
}

TEST(HumanoidDerivatives, SeatedMatchesTheReference) {
  // Motion IV's chair: the seat points carry the body (thighs level, torso upright).
  ProblemConfig config;
  config.contact.chair = true;
  const FullModel model(config);
  State x = standing();
  x.q.tail<kJoints>() << 0.0, 1.5, 1.5, 0.0, 0.0, 1.5, 1.5, 0.0;
  x.q[0] = 0.0;
  x.q[2] = config.contact.seat_height + config.contact.ischium_below_hip - 0.005;
  x.v.setZero();
  x.v[3] = 0.05;
  StepMap map(Model{}, Parameters{}, config.contact);
  ASSERT_GT(vertical_load(map.evaluate_contact(x)).seat, 10.0);
  const auto [fx, fu] = model.errors(x, JointVector::Constant(2.0), false);
  std::printf("seated: worst column error fx %.1e, fu %.1e\n", fx, fu);
  EXPECT_LT(fx, kReferenceTolerance);
  EXPECT_LT(fu, kReferenceTolerance);
}

TEST(HumanoidDerivatives, LegsMatchTheReference) {
  // The fast subsystem (base held) at the standing stance and at random ones.
  const ProblemConfig config = [] {
    ProblemConfig c;
    c.step = 0.01;
    return c;
  }();
  using Fast = FastSubsystem<1>;
  Fast linearised(CostWeights{}, config);
  Fast reference(CostWeights{}, reference_config(config));
  std::mt19937 rng(11);
  for (int trial = 0; trial < 4; ++trial) {
    const State x = trial == 0 ? standing() : random_state(rng, 0.0);
    const JointVector u_hat = random_torques(rng);
    for (Fast* fast : {&linearised, &reference}) {
      fast->set_reference(0, to_vector(x), u_hat);
      fast->set_reference(1, to_vector(x), u_hat);
    }
    Fast::State zeta = Fast::State::Zero();
    zeta.tail<kJoints>().setConstant(0.1);
    const Fast::Control nu = Fast::Control::Constant(3.0);
    Fast::StateJacobian fz, fz_reference;
    Fast::ControlJacobian fu, fu_reference;
    linearised.dynamics_derivatives(zeta, nu, 0, fz, fu);
    reference.dynamics_derivatives(zeta, nu, 0, fz_reference, fu_reference);
    const double z_error = worst_column_error(fz, fz_reference);
    const double u_error = worst_column_error(fu, fu_reference);
    std::printf("legs %d: worst column error fz %.1e, fu %.1e\n", trial, z_error, u_error);
    EXPECT_LT(z_error, kReferenceTolerance) << "trial " << trial;
    EXPECT_LT(u_error, kReferenceTolerance) << "trial " << trial;
  }
}

// The analytic residual derivatives (ResidualJacobian::kAnalytic, the default) against the
// forward-differenced ones they replaced, step for step: 5 ms (one sub-step) and 30 ms steps
// from 24 random states in the ground, sliding (feet driven sideways at up to 0.5 m/s,
// through the friction's 1 cm/s slip velocity), lifted, seated, and with joints past their
// stops; and the legs' (base held). The differenced ones carry forward-difference error,
// 1.5e-5 relative (the file comment): the tolerance kReferenceTolerance leaves a factor 6.
TEST(HumanoidDerivatives, AnalyticMatchesTheDifferencedChainRule) {
  const Model limits;
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  double worst = 0.0;
  for (int trial = 0; trial < 24; ++trial) {
    ContactParameters contact;
    contact.chair = trial % 6 == 3;
    State x = random_state(rng, trial % 6 == 1 ? 0.05 : 0.0);
    if (trial % 6 == 2) x.v.segment<2>(3) = 0.5 * Eigen::Vector2d(unit(rng), unit(rng));
    if (contact.chair) {
      x.q.tail<kJoints>() << 0.0, 1.5, 1.5, 0.0, 0.0, 1.5, 1.5, 0.0;
      x.q[0] = 0.0;
      x.q[2] = contact.seat_height + contact.ischium_below_hip - 0.005;
    }
    if (trial % 6 == 4) {
      x.q[7 + kKnee] = limits.joint_lower[kKnee] - 0.03 * std::abs(unit(rng));
      x.q[7 + kJointsPerLeg + kHipFlexion] = limits.joint_upper[kHipFlexion] + 0.02 * unit(rng);
    }
    const JointVector tau = random_torques(rng);
    StepMap analytic(Model{}, Parameters{}, contact, 5e-3, ResidualJacobian::kAnalytic);
    StepMap differenced(Model{}, Parameters{}, contact, 5e-3,
                        ResidualJacobian::kForwardDifferences);
    for (const double dt : {5e-3, 0.03}) {
      StepJacobian fx, fx_differenced;
      StepControlJacobian fu, fu_differenced;
      analytic.linearise(x, tau, dt, fx, fu);
      differenced.linearise(x, tau, dt, fx_differenced, fu_differenced);
      const double fx_error = worst_column_error(fx, fx_differenced),
                   fu_error = worst_column_error(fu, fu_differenced);
      EXPECT_LT(fx_error, kReferenceTolerance) << "trial " << trial << ", dt " << dt;
      EXPECT_LT(fu_error, kReferenceTolerance) << "trial " << trial << ", dt " << dt;
      worst = std::max({worst, fx_error, fu_error});
    }
    JointStepJacobian fz, fz_differenced;
    JointControlJacobian fl, fl_differenced;
    analytic.linearise_joints(x, tau, 0.01, fz, fl);
    differenced.linearise_joints(x, tau, 0.01, fz_differenced, fl_differenced);
    const double legs_error =
        std::max(worst_column_error(fz, fz_differenced), worst_column_error(fl, fl_differenced));
    EXPECT_LT(legs_error, kReferenceTolerance) << "trial " << trial;
    worst = std::max(worst, legs_error);
  }
  std::printf("analytic against differenced residual derivatives: worst column error %.1e\n",
              worst);
}

TEST(HumanoidDerivatives, LinearisedStepIsTheStep) {
  StepMap map(Model{}, Parameters{}, ContactParameters{}, 5e-3);
  std::mt19937 rng(3);
  StepJacobian fx;
  StepControlJacobian fu;
  JointStepJacobian fz;
  JointControlJacobian fl;
  for (int trial = 0; trial < 3; ++trial) {
    const State x = random_state(rng, 0.0);
    const JointVector tau = random_torques(rng);
    EXPECT_EQ(to_vector(map.linearise(x, tau, 0.03, fx, fu)), to_vector(map.step(x, tau, 0.03)));
    EXPECT_EQ(to_vector(map.linearise_joints(x, tau, 0.01, fz, fl)),
              to_vector(map.step_joints(x, tau, 0.01)));
  }
}

TEST(HumanoidDerivatives, LinearisationDoesNotAllocate) {
  StepMap map(Model{}, Parameters{}, ContactParameters{}, 5e-3);
  const State x = standing();
  const JointVector tau = JointVector::Constant(1.0);
  StepJacobian fx;
  StepControlJacobian fu;
  JointStepJacobian fz;
  JointControlJacobian fl;
  map.linearise(x, tau, 0.03, fx, fu);  // warm-up
  const auto before = heap_monitor::allocations();
  heap_monitor::arm();
  map.linearise(x, tau, 0.03, fx, fu);
  map.linearise_joints(x, tau, 0.01, fz, fl);
  heap_monitor::disarm();
  EXPECT_EQ(heap_monitor::allocations() - before, 0u);
  EXPECT_TRUE(fx.allFinite());
}

// The reaching robot (n = 31, model.hpp): the same linearisation with the arm's joint, its
// Jacobians against the refined reference at random states around the stance (the arm
// swinging, half of them lifted off the ground), the next state step()'s, and no allocation.
TEST(HumanoidDerivatives, ArmVariantMatchesTheRefinedReference) {
  const ProblemConfig config;
  ArmStepMap map(ArmModel(config.parameters), config.parameters, config.contact,
                 config.max_substep);
  using ArmState = ArmStepMap::State;
  using ArmVector = ArmStepMap::StateVector;
  using ArmTorques = ArmStepMap::JointVector;
  const auto vector_of = [](const ArmState& x) { return (ArmVector() << x.q, x.v).finished(); };
  const auto state_of = [](const ArmVector& x) {
    return ArmState{x.head<Dimensions<1>::kConfigurationSize>(), x.tail<Dimensions<1>::kDofs>()};
  };
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int trial = 0; trial < 4; ++trial) {
    const State biped = random_state(rng, trial % 2 == 0 ? 0.0 : 0.05);
    ArmState x;
    x.q << biped.q, 0.5 + 0.3 * unit(rng);
    x.v << biped.v, 2.0 * unit(rng);
    ArmTorques tau;
    tau << random_torques(rng), 10.0 * unit(rng);
    ArmStepMap::StepJacobian fx, fx_reference;
    ArmStepMap::StepControlJacobian fu, fu_reference;
    const auto before = heap_monitor::allocations();
    heap_monitor::arm();
    const ArmState next = map.linearise(x, tau, config.step, fx, fu);
    heap_monitor::disarm();
    EXPECT_EQ(heap_monitor::allocations() - before, 0u);
    EXPECT_EQ(vector_of(next), vector_of(map.step(x, tau, config.step)));
    refined_difference(
        [&](const ArmVector& xp) { return vector_of(map.step(state_of(xp), tau, config.step)); },
        vector_of(x), fx_reference);
    refined_difference(
        [&](const ArmTorques& up) { return vector_of(map.step(x, up, config.step)); }, tau,
        fu_reference);
    const double fx_error = worst_column_error(fx, fx_reference),
                 fu_error = worst_column_error(fu, fu_reference);
    std::printf("arm variant, random state %d: worst column error fx %.1e, fu %.1e\n", trial,
                fx_error, fu_error);
    EXPECT_LT(fx_error, kRefinedTolerance) << "trial " << trial;
    EXPECT_LT(fu_error, kRefinedTolerance) << "trial " << trial;
  }
}

}  // namespace
