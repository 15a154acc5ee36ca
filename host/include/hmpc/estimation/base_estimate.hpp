// What a base estimator gives the controller, whichever design: the torso's pose and velocity,
// the IMU's biases, the estimate's spread and how far it can be trusted; and the rest that
// starts a filter on a robot standing still.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>

#include "hmpc/humanoid/model.hpp"
#include "hmpc/sensors/imu.hpp"

namespace hmpc::estimation {

using humanoid::Matrix3;
using humanoid::Vector3;

inline constexpr int kFeet = 2;

// How far the controller can trust the estimate. kLost: hold the robot (or stop it); the filter
// must be started again (initialize_at_rest) unless only its covariance was too large.
enum class Trust : std::uint8_t { kTracking, kDegraded, kLost };
inline const char* to_string(Trust trust) {
  switch (trust) {
    case Trust::kTracking: return "tracking";
    case Trust::kDegraded: return "degraded";
    case Trust::kLost: return "lost";
  }
  return "unknown";
}

// Inputs the filter refused, by reason.
struct RejectedInputs {
  int imu_not_finite = 0, imu_out_of_range = 0, imu_stuck = 0;  // out of range: or saturated
  int bad_interval = 0;  // not finite, not positive, or above max_interval
  int joints_not_finite = 0;
  int state_not_finite = 0;  // an update that would have made the estimate non-finite
};

// One standard deviation of what the MPC needs most, from the covariance: the height, the
// horizontal velocity and the tilt (the attitude error about the world's x and y axes).
struct Spread {
  double height = 0.0;               // [m]
  double horizontal_velocity = 0.0;  // [m/s]
  double tilt = 0.0;                 // [rad]
};

// The robot's base as the MPC needs it: the torso frame's origin and rotation, its velocity in
// world coordinates and angular velocity in torso coordinates.
struct BaseEstimate {
  Vector3 position = Vector3::Zero();                               // torso origin, world [m]
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  // torso to world
  Vector3 velocity = Vector3::Zero();                               // torso origin, world [m/s]
  Vector3 angular_velocity = Vector3::Zero();                       // torso coordinates [rad/s]
  Vector3 gyroscope_bias = Vector3::Zero();
  Vector3 accelerometer_bias = Vector3::Zero();
  std::array<Vector3, kFeet> stance_points{};  // d_L, d_R, world
  std::array<bool, kFeet> stance{};            // used as fixed at the last correction
  std::array<bool, kFeet> slipping{};          // asked to stand, found moving
  std::array<bool, kFeet> gated{};             // asked to stand, its innovation rejected
  // The sole corners a stance foot bears on (bit c: corner c, hmpc/humanoid/contact.hpp's
  // order heel left, heel right, toe left, toe right; all four: flat).
  std::array<std::uint8_t, kFeet> support{};
  Spread spread;  // of the IMU frame's state
  Trust trust = Trust::kLost;
};

// IMU readings averaged over a rest before the filter starts.
struct ImuRest {
  Vector3 angular_velocity_sum = Vector3::Zero();
  Vector3 specific_force_sum = Vector3::Zero();
  int samples = 0;
  double seconds = 0.0;

  void add(const sensors::ImuReading& imu, double dt) {
    angular_velocity_sum += imu.angular_velocity;
    specific_force_sum += imu.specific_force;
    ++samples;
    seconds += dt;
  }
  Vector3 mean_angular_velocity() const { return angular_velocity_sum / samples; }
  Vector3 mean_specific_force() const { return specific_force_sum / samples; }
};

}  // namespace hmpc::estimation
