// The IMU readings a base estimator may use. A reading that is not finite, saturated or beyond
// the sensor's range, or stuck (the same six values `stuck_samples` times in a row: a live MEMS
// sensor's noise changes its least significant bits every sample), is refused and counted by
// its reason; the last good reading stands in for it. Header-only, allocation-free.
#pragma once

#include "hmpc/estimation/base_estimate.hpp"
#include "hmpc/sensors/imu.hpp"

namespace hmpc::estimation {

class ImuScreen {
 public:
  ImuScreen(const sensors::ImuConfig& imu, int stuck_samples)
      : imu_(imu), stuck_samples_(stuck_samples) {}

  // Starts from a reading known to be good (a rest's mean).
  void start(const Vector3& angular_velocity, const Vector3& specific_force) {
    last_good_.angular_velocity = angular_velocity;
    last_good_.specific_force = specific_force;
    last_good_.saturated = false;
    same_readings_ = 0;
  }

  // Whether `reading` is good; if not, its reason is counted in `rejected`.
  bool check(const sensors::ImuReading& reading, RejectedInputs& rejected) {
    const bool readable =
        reading.angular_velocity.allFinite() && reading.specific_force.allFinite();
    const bool same = readable && reading.angular_velocity == last_reading_.angular_velocity &&
                      reading.specific_force == last_reading_.specific_force;
    same_readings_ = same ? same_readings_ + 1 : 0;
    if (readable) last_reading_ = reading;
    if (!readable) {
      ++rejected.imu_not_finite;
      return false;
    }
    if (reading.saturated ||
        reading.angular_velocity.cwiseAbs().maxCoeff() > imu_.gyroscope.range ||
        reading.specific_force.cwiseAbs().maxCoeff() > imu_.accelerometer.range) {
      ++rejected.imu_out_of_range;
      return false;
    }
    if (same_readings_ + 1 >= stuck_samples_) {
      ++rejected.imu_stuck;
      return false;
    }
    last_good_ = reading;
    return true;
  }

  // The last good reading: what to use in place of a refused one.
  const sensors::ImuReading& last_good() const { return last_good_; }

 private:
  sensors::ImuConfig imu_;
  int stuck_samples_;
  sensors::ImuReading last_reading_{};  // the last finite one, to find a stuck sensor
  sensors::ImuReading last_good_{};
  int same_readings_ = 0;  // in a row
};

}  // namespace hmpc::estimation
