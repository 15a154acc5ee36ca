// The biped's sensors as a real robot has them, no force sensors: the torso IMU
// (hmpc/sensors/imu.hpp, on the model's mounting point) and each leg joint's absolute encoder
// and board-filtered velocity (hmpc/sensors/joint_sensors.hpp). One reading per 1 ms step of a
// simulated plant, from the state at the step's end and the step's mean acceleration.
// Header-only, allocation-free; seeded, so a run repeats exactly.
#pragma once

#include <array>
#include <cstdint>

#include "hmpc/humanoid/imu.hpp"
#include "hmpc/humanoid/model.hpp"
#include "hmpc/sensors/imu.hpp"
#include "hmpc/sensors/joint_sensors.hpp"

namespace hmpc::humanoid {

struct SensorConfig {
  sensors::ImuConfig imu = sensors::bmi088();
  sensors::EncoderConfig encoder{};
  sensors::VelocityFilterConfig velocity{};
  std::uint64_t seed = 1;  // of the IMU's power-up biases and noise
};

struct SensorReadings {
  sensors::ImuReading imu;
  JointVector angles = JointVector::Zero();  // encoder counts as angles [rad]
  JointVector rates = JointVector::Zero();   // the boards' filtered velocities [rad/s]
};

class BipedSensors {
 public:
  explicit BipedSensors(const Model& model, const SensorConfig& config = {})
      : model_(model), imu_(config.imu, config.seed), encoder_(config.encoder) {
    velocity_.fill(sensors::JointVelocityFilter(config.velocity));
  }

  // The boards' velocity filters start from the joints at rest at `q`.
  void start_at_rest(const Configuration& q) {
    for (int j = 0; j < kJoints; ++j) {
      velocity_[j].reset(sensors::quantise(encoder_, q[kBaseConfiguration + j]));
    }
  }

  // One step: the robot at (q, v) at its end, after a mean acceleration a = dv/dt.
  SensorReadings measure(const Configuration& q, const Velocity& v, const Velocity& a) {
    SensorReadings out;
    out.imu = imu_.measure(torso_imu_truth(model_, q, v, a));
    for (int j = 0; j < kJoints; ++j) {
      out.angles[j] = sensors::quantise(encoder_, q[kBaseConfiguration + j]);
      out.rates[j] = velocity_[j].update(out.angles[j]);
    }
    return out;
  }

  // The IMU's biases now: what an estimator should find.
  const sensors::ImuModel& imu() const { return imu_; }

 private:
  // q's floating-base part: position and quaternion (model.hpp).
  static constexpr int kBaseConfiguration = kConfigurationSize - kJoints;

  Model model_;
  sensors::ImuModel imu_;
  sensors::EncoderConfig encoder_;
  std::array<sensors::JointVelocityFilter, kJoints> velocity_;
};

}  // namespace hmpc::humanoid
