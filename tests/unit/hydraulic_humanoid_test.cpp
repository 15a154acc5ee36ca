// The humanoid HIL plant (hil/humanoid/hydraulic_humanoid.hpp): its linearly implicit 1 ms step
// against Simbody's error-controlled integration of the same system (valves opening and
// closing, a push), standing with the valves centred (each joint locked by its oil), the mass
// mismatch, and its bad input.
#include "hydraulic_humanoid.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "hmpc/humanoid/hydraulic_legs.hpp"
#include "hmpc/humanoid/problem.hpp"

namespace {

using namespace hmpc::humanoid;
using hmpc::hil::HumanoidMismatch;
using hmpc::hil::Push;
using hmpc::hil::SimbodyHydraulicHumanoid;

// Table 2.2's standing height, the HIL's starting stance.
BasicState<0> standing() { return standing_state<0>(ProblemConfig{}, 0.85); }

// Valves opening and closing: both knees and ankles at 2 Hz, 5 and 3 % of the valve's range.
JointVector valves(double t) {
  JointVector u = JointVector::Zero();
  for (int leg = 0; leg < 2; ++leg) {
    u[leg * kJointsPerLeg + kKnee] = 0.05 * std::sin(2 * M_PI * 2 * t);
    u[leg * kJointsPerLeg + kAnkle] = -0.03 * std::sin(2 * M_PI * 2 * t);
  }
  return u;
}

double vertical_load(const SimbodyHydraulicHumanoid& plant) {
  double load = 0;
  for (const Vector3& f : plant.sole_forces()) load += f.z();
  return load;
}

// 0.4 s of knees and ankles driven by their valves, with a 60 N push on the torso for 0.1 s: the
// implicit step stays within 5 % of each quantity's own range of Runge-Kutta-Merson's solution
// (what a first-order 1 ms step adds is then small against the plant mismatch the HIL runs
// with, 5 to 20 %).
TEST(HydraulicHumanoid, ImplicitStepFollowsSimbodysIntegrator) {
  SimbodyHydraulicHumanoid plant(Parameters{}, ContactParameters{}, {}, standing());
  SimbodyHydraulicHumanoid reference(Parameters{}, ContactParameters{}, {}, standing());
  Push push;
  push.body = 0;
  push.force = Vector3(60, 20, 0);
  push.start = 0.1;
  push.duration = 0.1;
  plant.push(push);
  reference.push(push);
  const BasicState<0> start = standing();
  JointVector joint_error = JointVector::Zero(), joint_range = JointVector::Zero();
  JointVector torque_error = JointVector::Zero();
  JointVector torque_min = JointVector::Constant(1e9), torque_max = JointVector::Constant(-1e9);
  double height_error = 0, height_range = 0, forward_error = 0, forward_range = 0;
  for (int k = 0; k < 400; ++k) {
    const double t = 1e-3 * k;
    plant.step(valves(t));
    reference.step_reference(valves(t), SimbodyHydraulicHumanoid::kStep);
    const BasicState<0> a = plant.state(), b = reference.state();
    joint_error = joint_error.cwiseMax((a.q.tail<kJoints>() - b.q.tail<kJoints>()).cwiseAbs());
    joint_range = joint_range.cwiseMax((b.q.tail<kJoints>() - start.q.tail<kJoints>()).cwiseAbs());
    height_error = std::max(height_error, std::abs(a.q[2] - b.q[2]));
    height_range = std::max(height_range, std::abs(b.q[2] - start.q[2]));
    forward_error = std::max(forward_error, std::abs(a.q[0] - b.q[0]));
    forward_range = std::max(forward_range, std::abs(b.q[0] - start.q[0]));
    const JointVector tau = reference.joint_torques();
    // The torques from the first 20 ms on: the chambers start torque-free, and the oil springs
    // take up the weight in a ringing of a few milliseconds that the 1 ms step damps.
    if (k >= 20) torque_error = torque_error.cwiseMax((plant.joint_torques() - tau).cwiseAbs());
    torque_min = torque_min.cwiseMin(tau);
    torque_max = torque_max.cwiseMax(tau);
  }
  std::printf(
      "largest difference over 0.4 s: knee %.2e of %.3f rad, ankle %.2e of %.3f rad, "
      "height %.2e of %.2e m, forward %.2e of %.2e m, knee torque %.2f of %.1f N m\n",
      joint_error[kKnee], joint_range[kKnee], joint_error[kAnkle], joint_range[kAnkle],
      height_error, height_range, forward_error, forward_range, torque_error[kKnee],
      torque_max[kKnee] - torque_min[kKnee]);
  for (int leg = 0; leg < 2; ++leg) {
    for (int joint : {kKnee, kAnkle}) {
      const int j = leg * kJointsPerLeg + joint;
      EXPECT_GT(joint_range[j], 0.02) << "the valves should move joint " << j;
      EXPECT_LT(joint_error[j], 0.05 * joint_range[j]) << "joint " << j;
      EXPECT_LT(torque_error[j], 0.05 * (torque_max[j] - torque_min[j])) << "joint " << j;
    }
  }
  EXPECT_LT(height_error, 0.05 * height_range);
  EXPECT_GT(forward_range, 0.005) << "the push should move the robot";
  EXPECT_LT(forward_error, 0.05 * forward_range);
}

// Valves centred: the oil holds each joint (a 30 N m load compresses it by 2 mrad at most:
// hydraulic_legs.hpp's cylinders are stiffer than 15 kN m/rad about mid-stroke), the feet carry
// the weight, and the base stays put.
TEST(HydraulicHumanoid, StandsOnItsLockedJointsWithTheValvesCentred) {
  const BasicState<0> start = standing();
  SimbodyHydraulicHumanoid plant(Parameters{}, ContactParameters{}, {}, start);
  for (int k = 0; k < 1000; ++k) plant.step(JointVector::Zero());
  const BasicState<0> x = plant.state();
  EXPECT_LT((x.q.tail<kJoints>() - start.q.tail<kJoints>()).cwiseAbs().maxCoeff(), 2e-3);
  EXPECT_LT(std::abs(x.q[0] - start.q[0]), 0.01);
  EXPECT_LT(x.v.norm(), 0.05);
  const double weight = plant.model().total_mass() * 9.81;
  EXPECT_NEAR(vertical_load(plant), weight, 0.02 * weight);
  EXPECT_NEAR(plant.time(), 1.0, 1e-9);
}

// A plant 20 % heavier than the model carries 20 % more on its feet.
TEST(HydraulicHumanoid, AMassMismatchLoadsTheFeetAccordingly) {
  HumanoidMismatch heavier;
  heavier.mass_scale = 1.2;
  SimbodyHydraulicHumanoid plant(Parameters{}, ContactParameters{}, heavier, standing());
  for (int k = 0; k < 500; ++k) plant.step(JointVector::Zero());
  const double nominal = Model(Parameters{}).total_mass() * 9.81;
  EXPECT_NEAR(vertical_load(plant), 1.2 * nominal, 0.02 * nominal);
}

// The actuators are those of hydraulic_legs.hpp, the mismatch applied; the end caps lie beyond
// every joint's range of motion.
TEST(HydraulicHumanoid, DrivesEachJointWithItsLegActuator) {
  HumanoidMismatch m;
  m.bulk_modulus_scale = 0.8;
  m.joint_friction_scale = 1.5;
  SimbodyHydraulicHumanoid plant(Parameters{}, ContactParameters{}, m, standing());
  const Parameters p;
  for (int j = 0; j < kJoints; ++j) {
    const auto nominal = leg_actuator(p, LegJoint(j % kJointsPerLeg));
    const auto& a = plant.plant_actuators()[std::size_t(j)];
    EXPECT_DOUBLE_EQ(a.bulk_modulus, 0.8 * nominal.bulk_modulus);
    EXPECT_DOUBLE_EQ(a.coulomb_friction, 1.5 * nominal.coulomb_friction);
    EXPECT_DOUBLE_EQ(a.lever, nominal.lever);
    const auto joint = std::size_t(j % kJointsPerLeg);
    EXPECT_LT(a.mid_stroke_angle - a.theta_limit(), p.joint_lower[joint]);
    EXPECT_GT(a.mid_stroke_angle + a.theta_limit(), p.joint_upper[joint]);
    // Pulling on the rod side reaches the MPC's torque limit with a fifth to spare.
    EXPECT_LT(a.stall_torque_negative(), -1.2 * p.torque_limit[joint]);
  }
}

TEST(HydraulicHumanoid, CentresAValveWhoseCommandIsNotFinite) {
  SimbodyHydraulicHumanoid plant(Parameters{}, ContactParameters{}, {}, standing());
  JointVector u = JointVector::Zero();
  u[2] = std::numeric_limits<double>::quiet_NaN();
  u[5] = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 10; ++k) plant.step(u);
  EXPECT_EQ(plant.rejected_commands(), 20u);
  for (const auto& a : plant.actuators()) EXPECT_EQ(a.spool, 0.0);
  EXPECT_TRUE(plant.state().q.allFinite());
}

TEST(HydraulicHumanoid, RefusesWhatIsNotARobot) {
  HumanoidMismatch m;
  m.mass_scale = 3;
  EXPECT_THROW(SimbodyHydraulicHumanoid(Parameters{}, ContactParameters{}, m, standing()),
               std::invalid_argument);
  m.mass_scale = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(SimbodyHydraulicHumanoid(Parameters{}, ContactParameters{}, m, standing()),
               std::invalid_argument);
  BasicState<0> bent = standing();
  bent.q[7 + kKnee] = -0.2;  // beyond the knee's end cap
  EXPECT_THROW(SimbodyHydraulicHumanoid(Parameters{}, ContactParameters{}, {}, bent),
               std::invalid_argument);
  BasicState<0> nan = standing();
  nan.v[3] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(SimbodyHydraulicHumanoid(Parameters{}, ContactParameters{}, {}, nan),
               std::invalid_argument);
  SimbodyHydraulicHumanoid plant(Parameters{}, ContactParameters{}, {}, standing());
  Push onto_hip_link;
  onto_hip_link.body = Model::body_of(0, kHipAbduction);
  EXPECT_THROW(plant.push(onto_hip_link), std::invalid_argument);
  Push nowhere;
  nowhere.body = kBodies;
  EXPECT_THROW(plant.push(nowhere), std::invalid_argument);
  Push endless;
  endless.duration = -1;
  EXPECT_THROW(plant.push(endless), std::invalid_argument);
}

}  // namespace
