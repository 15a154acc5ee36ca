// The humanoid's torso IMU truth (hmpc/humanoid/imu.hpp) from the state layout and forward
// dynamics' acceleration, against the IMU point's motion integrated with RK4 and differenced.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

#include "hmpc/humanoid/dynamics.hpp"
#include "hmpc/humanoid/imu.hpp"
#include "humanoid_random_state.hpp"

namespace {

using namespace hmpc::humanoid;
using State = BasicState<0>;

// dx/dt of the free-floating robot under generalized force tau (no ground): p' = R v_o,
// quaternion' = quaternion * (0, omega) / 2, joint angles' = joint rates, v' = forward dynamics.
struct Derivative {
  Eigen::Matrix<double, kConfigurationSize, 1> q_dot;
  Velocity v_dot;
};

Derivative derivative(Dynamics& dynamics, const State& x, const Velocity& tau) {
  const Eigen::Quaterniond r(x.q[3], x.q[4], x.q[5], x.q[6]);
  Derivative d;
  d.q_dot.head<3>() = r.toRotationMatrix() * x.v.segment<3>(3);
  const Eigen::Quaterniond spin = r * Eigen::Quaterniond(0, x.v[0], x.v[1], x.v[2]);
  d.q_dot.segment<4>(3) << 0.5 * spin.w(), 0.5 * spin.x(), 0.5 * spin.y(), 0.5 * spin.z();
  d.q_dot.tail<kJoints>() = x.v.tail<kJoints>();
  d.v_dot = dynamics.forward_dynamics(x.q, x.v, tau);
  return d;
}

State rk4(Dynamics& dynamics, const State& x, const Velocity& tau, double h) {
  auto add = [](const State& s, const Derivative& d, double dt) {
    State out{s.q + dt * d.q_dot, s.v + dt * d.v_dot};
    return out;
  };
  const Derivative k1 = derivative(dynamics, x, tau);
  const Derivative k2 = derivative(dynamics, add(x, k1, h / 2), tau);
  const Derivative k3 = derivative(dynamics, add(x, k2, h / 2), tau);
  const Derivative k4 = derivative(dynamics, add(x, k3, h), tau);
  State out = x;
  out.q += h / 6 * (k1.q_dot + 2 * k2.q_dot + 2 * k3.q_dot + k4.q_dot);
  out.v += h / 6 * (k1.v_dot + 2 * k2.v_dot + 2 * k3.v_dot + k4.v_dot);
  return out;
}

Vector3 imu_in_world(const Model& model, const State& x) {
  const Eigen::Quaterniond r(x.q[3], x.q[4], x.q[5], x.q[6]);
  return x.q.head<3>() + r.normalized().toRotationMatrix() * model.imu;
}

TEST(HumanoidImu, ReadsTheTorsoPointsMotionFromStateAndForwardDynamics) {
  const Model model;
  Dynamics dynamics(model);
  std::mt19937 rng(11);
  const double h = 1e-3;
  for (int trial = 0; trial < 5; ++trial) {
    const State x = test_states::random_state(model, rng);
    const Velocity tau = test_states::random_generalized_force(model, rng);
    const Velocity a = dynamics.forward_dynamics(x.q, x.v, tau);
    const hmpc::sensors::ImuTruth truth = torso_imu_truth(model, x.q, x.v, a);

    const State ahead = rk4(dynamics, x, tau, h), behind = rk4(dynamics, x, tau, -h);
    const Vector3 acceleration =
        (imu_in_world(model, ahead) - 2 * imu_in_world(model, x) + imu_in_world(model, behind)) /
        (h * h);
    const Eigen::Quaterniond r(x.q[3], x.q[4], x.q[5], x.q[6]);
    const Vector3 expected = r.toRotationMatrix().transpose() * (acceleration - model.gravity);
    // Central differences err by h^2 / 12 times the fourth derivative: ~1e-5 of these
    // accelerations (tens of m/s^2 from rates of 3 rad/s and 8 rad/s at the joints).
    EXPECT_LT((truth.specific_force - expected).norm(), 1e-3 * expected.norm()) << trial;
    EXPECT_EQ(truth.angular_velocity, x.v.head<3>());
  }
}

TEST(HumanoidImu, StandingStillReadsGravityUpAndSitsInThePelvis) {
  const Model model;
  State x;
  x.q.setZero();
  x.q[3] = 1.0;
  x.q[2] = 0.9;
  x.v.setZero();
  const hmpc::sensors::ImuTruth truth = torso_imu_truth(model, x.q, x.v, Velocity::Zero().eval());
  EXPECT_TRUE(truth.specific_force.isApprox(Vector3(0, 0, 9.81)));
  EXPECT_NEAR(model.imu.z(), 0.10, 0.001);  // 0.063 of 1.59 m
  EXPECT_LT(model.imu.head<2>().norm(), 1e-12);
}

}  // namespace
