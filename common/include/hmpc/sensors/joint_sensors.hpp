// What a joint board reads of its joint: the angle as an absolute encoder quantises it, and the
// angular velocity as the board derives it, from successive encoder readings, low-pass
// filtered (no tachometer on a hydraulic joint). Shared by the plants that emulate the sensors
// and by tests of what a controller sees; allocation-free, no state beyond one joint's filter.
#pragma once

#include <cmath>

namespace hmpc::sensors {

constexpr double kTwoPi = 6.283185307179586;

struct EncoderConfig {
  // A 16-bit absolute encoder on the joint shaft: 2 pi / 2^16 = 9.6e-5 rad per count, below the
  // 1e-4 rad resolution of the joint boards' CAN frames, so the frame does not hide it.
  int bits = 16;
};

inline double encoder_step(const EncoderConfig& config) {
  return kTwoPi / std::ldexp(1.0, config.bits);
}

// The angle the encoder reports: the nearest count. The error is at most half a count.
inline double quantise(const EncoderConfig& config, double angle) {
  const double step = encoder_step(config);
  return std::round(angle / step) * step;
}

struct VelocityFilterConfig {
  double period = 1e-3;  // [s] between encoder readings: the board's sensor loop
  // First-order low-pass on the differenced angle [Hz]. Our choice: 50 Hz passes the legs'
  // motions (the MPC's 12-30 ms sampling resolves at most 17-40 Hz) while a count's step,
  // differenced over 1 ms (0.096 rad/s), leaves a blip of 0.026 rad/s that decays in 3 ms.
  double cutoff = 50.0;
};

// One joint's velocity as its board estimates it: omega_k = omega_{k-1} + a (d_k - omega_{k-1}),
// d_k = (theta_k - theta_{k-1}) / period, a = 1 - exp(-2 pi f_c period) (the exact discrete
// first-order low-pass for a held input).
class JointVelocityFilter {
 public:
  explicit JointVelocityFilter(const VelocityFilterConfig& config = {})
      : period_(config.period), gain_(1.0 - std::exp(-kTwoPi * config.cutoff * config.period)) {}

  // Starts from a joint at rest at `angle` (as read).
  void reset(double angle) {
    last_angle_ = angle;
    velocity_ = 0.0;
    started_ = true;
  }

  // Takes the next reading, one period after the last; returns the estimate.
  double update(double angle) {
    if (!started_) reset(angle);
    const double differenced = (angle - last_angle_) / period_;
    last_angle_ = angle;
    velocity_ += gain_ * (differenced - velocity_);
    return velocity_;
  }

  double velocity() const { return velocity_; }

 private:
  double period_;
  double gain_;
  double last_angle_ = 0.0;
  double velocity_ = 0.0;
  bool started_ = false;
};

}  // namespace hmpc::sensors
