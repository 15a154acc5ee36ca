// Random states of the humanoid for the dynamics tests: joint angles uniform within their ranges
// of motion, the base anywhere near standing height with a uniformly random orientation
// (normalised Gaussian quaternion), the velocities of a fast motion; and generalized forces with
// every joint torque within its limit and a random wrench on the base (which exercises the base
// rows of M^-1).
#pragma once

#include <Eigen/Geometry>
#include <random>

#include "hmpc/humanoid/model.hpp"

namespace hmpc::humanoid::test_states {

template <int A>
BasicState<A> random_state(const BasicModel<A>& model, std::mt19937& rng) {
  constexpr int kJoints = Dimensions<A>::kJoints;
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::normal_distribution<double> gauss;
  BasicState<A> s;
  s.q.template head<3>() << unit(rng), unit(rng), 0.9 + 0.3 * unit(rng);
  const Eigen::Quaterniond orientation =
      Eigen::Quaterniond(gauss(rng), gauss(rng), gauss(rng), gauss(rng)).normalized();
  s.q.template segment<4>(3) << orientation.w(), orientation.x(), orientation.y(), orientation.z();
  for (int j = 0; j < kJoints; ++j) {
    const double t = 0.5 * (unit(rng) + 1.0);
    s.q[7 + j] = model.joint_lower[j] + t * (model.joint_upper[j] - model.joint_lower[j]);
  }
  for (int k = 0; k < 3; ++k) s.v[k] = 3.0 * unit(rng);  // rad/s
  for (int k = 3; k < 6; ++k) s.v[k] = 2.0 * unit(rng);  // m/s
  for (int j = 0; j < kJoints; ++j) s.v[kBaseDofs + j] = 8.0 * unit(rng);
  return s;
}

template <int A>
BasicVelocity<A> random_generalized_force(const BasicModel<A>& model, std::mt19937& rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  BasicVelocity<A> tau;
  for (int k = 0; k < kBaseDofs; ++k) tau[k] = 50.0 * unit(rng);
  for (int j = 0; j < Dimensions<A>::kJoints; ++j) {
    tau[kBaseDofs + j] = model.torque_limit[j] * unit(rng);
  }
  return tau;
}

}  // namespace hmpc::humanoid::test_states
