// What the humanoid's torso IMU would read, exactly, from the robot's state and acceleration
// (the noise-free input of hmpc/sensors/imu.hpp's ImuModel).
#pragma once

#include <Eigen/Geometry>

#include "hmpc/humanoid/model.hpp"
#include "hmpc/sensors/imu.hpp"

namespace hmpc::humanoid {

// q, v as model.hpp lays them out, a = dv/dt (forward dynamics' output): the torso's spatial
// velocity is in torso coordinates, so a's first six entries are its derivative in those
// coordinates, as sensors::imu_truth takes them.
template <int A>
sensors::ImuTruth torso_imu_truth(const BasicModel<A>& model, const BasicConfiguration<A>& q,
                                  const BasicVelocity<A>& v, const BasicVelocity<A>& a) {
  const Eigen::Quaterniond orientation(q[3], q[4], q[5], q[6]);
  return sensors::imu_truth(orientation.normalized().toRotationMatrix(), v.template head<3>(),
                            a.template head<3>(), v.template segment<3>(3),
                            a.template segment<3>(3), model.imu, model.gravity);
}

}  // namespace hmpc::humanoid
