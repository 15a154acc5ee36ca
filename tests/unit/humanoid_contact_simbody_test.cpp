// Our smooth ground contact (contact.hpp, stepped by step.hpp) against Simbody's own compliant
// contact on the same model (SimbodyHumanoid with ground contact): a qualitative comparison,
// since the two contact models differ (standing load ~ m g, split alike). Both start from
// standing_state at the 0.85 m standing height of Table 2.2 and are held for 1 s by the same
// joint torques computed from each one's own state every 1 ms; after that both carry the
// weight, split it alike between the feet, stand at the same height and have not slid.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "hmpc/humanoid/problem.hpp"
#include "hmpc/humanoid/step.hpp"
#include "simbody_humanoid.hpp"

namespace {

using namespace hmpc::humanoid;

constexpr double kDt = 1e-3;  // the simulator and HIL step (thesis Sec. 2.7)
constexpr int kSteps = 1000;  // 1 s: 5 periods of the 5 Hz whole-body bounce (contact.hpp)
constexpr double kStandingHeight = 0.85;  // [m], Table 2.2

// The torques both simulators get (as humanoid_contact_test's controller): the static joint
// torques that hold the start pose on our soles (gravity compensation, so the PD starts with no
// error to correct), a joint PD about the pose (Kp = 800 N m/rad, Kd critically damping each
// joint's own inertia, h Kd / M_jj < 2 at 1 ms), and at the ankles the torso's world pitch fed
// back (K = 1200 N m/rad, D = 200 N m s/rad per ankle): the 1 cm-compliant soles alone are
// too soft in pitch to hold the body upright against gravity (see humanoid_contact_test).
class Controller {
 public:
  static constexpr double kp = 800.0, k_pitch = 1200.0, d_pitch = 200.0;

  Controller(StepMap& map, const State& start) : target_(start.q.tail<kJoints>()) {
    Dynamics& dynamics = map.dynamics();
    const MassMatrix& M = dynamics.mass_matrix(start.q);
    for (int j = 0; j < kJoints; ++j) {
      kd_[j] = 2.0 * std::sqrt(kp * M(kBaseDofs + j, kBaseDofs + j));
    }
    const Velocity hold = dynamics.bias_forces(start.q, start.v) -
                          ContactModel::generalized_force(map.evaluate_contact(start));
    feedforward_ = hold.tail<kJoints>();
    pitch_ = pitch(start);
  }
  JointVector operator()(const State& x) const {
    JointVector tau =
        feedforward_ + kp * (target_ - x.q.tail<kJoints>()) - kd_.cwiseProduct(x.v.tail<kJoints>());
    for (int leg = 0; leg < 2; ++leg) {
      tau[leg * kJointsPerLeg + kAnkle] += k_pitch * (pitch_ - pitch(x)) - d_pitch * x.v[1];
    }
    return tau;
  }
  const JointVector& feedforward() const { return feedforward_; }

 private:
  // Torso pitch about world y (forward lean positive), from the torso's z axis.
  static double pitch(const State& x) {
    const Matrix3 R = Eigen::Quaterniond(x.q[3], x.q[4], x.q[5], x.q[6]).toRotationMatrix();
    return std::atan2(R(0, 2), R(2, 2));
  }
  JointVector target_, kd_, feedforward_;
  double pitch_ = 0.0;
};

// What the test reads off a state: the soles' total and per-foot vertical force, their mean
// sink below z = 0, their worst horizontal travel since `start`, and the base height.
struct Figures {
  double total = 0.0, left = 0.0, right = 0.0, sink = 0.0, slide = 0.0, base_z = 0.0,
         base_speed = 0.0;
};

// Sole point positions by our kinematics of either state (the model Simbody mirrors to 1e-9 in
// humanoid_dynamics_test).
Figures figures(StepMap& probe, const State& x, const std::array<Vector3, kSolePoints>& force,
                const ContactState& start) {
  const ContactState& c = probe.evaluate_contact(x);
  Figures f;
  for (int i = 0; i < kSolePoints; ++i) {
    f.total += force[i].z();
    (i < kFootPoints ? f.left : f.right) += force[i].z();
    f.sink -= c.position[i].z() / kSolePoints;
    f.slide = std::max(f.slide, (c.position[i] - start.position[i]).head<2>().norm());
  }
  f.base_z = x.q[2];
  f.base_speed = x.v.segment<3>(3).norm();
  return f;
}

void print(const char* who, double t, const Figures& f) {
  std::printf(
      "%-7s t %.2f s: load %7.2f N (left %6.2f, right %6.2f), sink %.2f mm, "
      "base z %.4f m, slide %.2f mm, base speed %.1e m/s\n",
      who, t, f.total, f.left, f.right, 1e3 * f.sink, f.base_z, 1e3 * f.slide, f.base_speed);
}

// Both simulators from `start` for 1 s under the controller holding `pose`; the figures at the
// end (and some on the way, printed), and the largest total load seen.
struct Outcome {
  Figures ours, simbody;
  double ours_peak = 0.0, simbody_peak = 0.0;
};
Outcome run(const char* name, const State& pose, const State& start) {
  ProblemConfig config;
  // Like for like: the twin mirrors the rigid bodies only (simbody_humanoid.hpp).
  config.parameters = hmpc::hil::SimbodyHumanoid::rigid_parameters(config.parameters);
  const Model model(config.parameters);
  StepMap ours(model, config.parameters, config.contact, kDt);
  StepMap probe(model, config.parameters, config.contact, kDt);  // kinematics for the figures
  hmpc::hil::SimbodyHumanoid simbody(model, ours.contact_model());
  simbody.set_state(start.q, start.v);
  const Controller control(ours, pose);
  const ContactState initial = probe.evaluate_contact(start);
  std::printf("%s: feed-forward joint torques [N m]:", name);
  for (int j = 0; j < kJoints; ++j) std::printf(" %.1f", control.feedforward()[j]);
  std::printf("\n");

  const auto our_forces = [&](const State& x) {
    const ContactState& c = probe.evaluate_contact(x);
    std::array<Vector3, kSolePoints> f;
    std::copy(c.force.begin(), c.force.begin() + kSolePoints, f.begin());
    return f;
  };
  State x = start;
  Outcome out;
  double ours_seconds = 0.0, simbody_seconds = 0.0;
  for (int k = 1; k <= kSteps; ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    x = ours.step(x, control(x), kDt);
    const auto t1 = std::chrono::steady_clock::now();
    simbody.step(control(simbody.state()), kDt);
    const auto t2 = std::chrono::steady_clock::now();
    ours_seconds += std::chrono::duration<double>(t1 - t0).count();
    simbody_seconds += std::chrono::duration<double>(t2 - t1).count();
    const State y = simbody.state();
    if (!x.q.allFinite() || !y.q.allFinite()) {
      ADD_FAILURE() << "not finite at step " << k;
      return out;
    }
    out.ours = figures(probe, x, our_forces(x), initial);
    out.simbody = figures(probe, y, simbody.sole_forces(), initial);
    out.ours_peak = std::max(out.ours_peak, out.ours.total);
    out.simbody_peak = std::max(out.simbody_peak, out.simbody.total);
    if (k == 1 || k == 50 || k == 100 || k == 250 || k == 500 || k == kSteps) {
      print("ours", k * kDt, out.ours);
      print("Simbody", k * kDt, out.simbody);
    }
  }
  std::printf("peak load: ours %.1f N, Simbody %.1f N\n", out.ours_peak, out.simbody_peak);
  std::printf("wall time for 1 s: ours %.3f s, Simbody %.3f s (%d integrator steps)\n",
              ours_seconds, simbody_seconds, simbody.integrator_steps());
  std::printf("per-point normal force [N], ours:   ");
  for (const Vector3& f : our_forces(x)) std::printf(" %.1f", f.z());
  std::printf("\nper-point normal force [N], Simbody:");
  for (const Vector3& f : simbody.sole_forces()) std::printf(" %.1f", f.z());
  std::printf("\n");
  return out;
}

// The assertions, the same for every start.
void expect_alike(const Outcome& out) {
  const Model model;
  const double weight = model.total_mass() * -model.gravity.z();
  // Vertical equilibrium: at rest the soles carry m g exactly; 5 % leaves a residual vertical
  // acceleration of 0.5 m/s^2 for what is left of the bounce.
  EXPECT_NEAR(out.ours.total, weight, 0.05 * weight);
  EXPECT_NEAR(out.simbody.total, weight, 0.05 * weight);
  // The split follows the centre of mass between the feet, which the same torques hold: the
  // contact law should not move it by more than 10 % of the weight.
  EXPECT_NEAR(out.ours.left, out.simbody.left, 0.1 * weight);
  EXPECT_NEAR(out.ours.right, out.simbody.right, 0.1 * weight);
  // Both soles sink by the same W / 8k under the same load (the mapping's calibration) and the
  // same joint torques hold the pose: the base height may differ by the 1 cm sink at most.
  EXPECT_NEAR(out.ours.base_z, out.simbody.base_z, 0.01);
  // Standing exerts no net horizontal load; friction (mu = 0.8) holds the soles, whose viscous
  // creep below v_s only follows the small sway.
  EXPECT_LT(out.ours.slide, 0.01);
  EXPECT_LT(out.simbody.slide, 0.01);
}

// The main case: standing_state (soles sunk by W / 8k, at rest), held.
TEST(HumanoidContactSimbody, HoldsStandingLikeSimbody) {
  const State pose = standing_state(ProblemConfig{}, kStandingHeight);
  expect_alike(run("standing", pose, pose));
}

// The same pose released with the soles just touching (gap zero, 1 cm above the standing
// sink): both fall onto their soles, bounce at ~5 Hz and must settle within the 1 s, which
// exercises stiffness and damping rather than only the calibrated static point.
TEST(HumanoidContactSimbody, SettlesOnItsSolesLikeSimbody) {
  const ProblemConfig config;
  const State pose = standing_state(config, kStandingHeight);
  State start = pose;
  const Model model(config.parameters);
  start.q[2] += model.total_mass() * -model.gravity.z() / (kSolePoints * config.contact.stiffness);
  expect_alike(run("released at touch", pose, start));
}

}  // namespace
