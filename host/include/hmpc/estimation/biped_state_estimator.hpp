// The base estimator as a controller runs it on the biped's sensor readings (one per 1 ms,
// hmpc/humanoid/sensors.hpp): a rest of the robot held still starts the invariant EKF, then each
// reading propagates it with the IMU and corrects it with the legs, which feet stand inferred
// from the legs (no force sensors); the state an MPC solves from joins the estimated base to
// the encoders' angles and the boards' velocities. Allocation-free.
#pragma once

#include "hmpc/estimation/invariant_ekf.hpp"
#include "hmpc/humanoid/sensors.hpp"

namespace hmpc::estimation {

class BipedStateEstimator {
 public:
  explicit BipedStateEstimator(const humanoid::Parameters& parameters = {},
                               const InvariantEkfConfig& config = {})
      : filter_(parameters, config) {}

  // A reading `dt` after the last while the robot is held still, before start().
  void rest(const humanoid::SensorReadings& reading, double dt) {
    if (rest_.samples == 0) {
      rest_start_angles_ = reading.angles;
      rest_span_ = 0;
    } else {
      rest_span_ += dt;
    }
    rest_.add(reading.imu, dt);
    last_ = reading;
  }
  // Starts the filter from the rest so far (at least one reading), with what the legs say of
  // the torso's turning meanwhile.
  void start() { filter_.initialize_at_rest(rest_, rest_start_angles_, last_.angles, rest_span_); }

  // A reading `dt` after the last, once started.
  void update(const humanoid::SensorReadings& reading, double dt) {
    filter_.propagate(reading.imu, dt);
    filter_.correct(reading.angles, reading.rates);
    last_ = reading;
  }

  // The robot's state as model.hpp lays it out: the estimated base, the joints as read.
  humanoid::BasicState<0> state() const { return state(filter_.estimate()); }
  // The same from an estimate the caller already has from filter().
  humanoid::BasicState<0> state(const BaseEstimate& e) const {
    humanoid::BasicState<0> x;
    x.q << e.position, e.orientation.w(), e.orientation.x(), e.orientation.y(), e.orientation.z(),
        last_.angles;
    // v's linear part is the torso origin's velocity in torso coordinates.
    x.v << e.angular_velocity, e.orientation.conjugate() * e.velocity, last_.rates;
    return x;
  }

  const InvariantEkf& filter() const { return filter_; }

 private:
  InvariantEkf filter_;
  ImuRest rest_;
  humanoid::JointVector rest_start_angles_ = humanoid::JointVector::Zero();
  double rest_span_ = 0;  // from the rest's first reading to its last [s]
  humanoid::SensorReadings last_;
};

}  // namespace hmpc::estimation
