// A MEMS IMU on the robot's torso: a triaxial gyroscope and accelerometer, each reading the
// truth plus a bias (a constant drawn at power-up plus a random walk) and white noise, clipped
// to its range and quantised to its resolution, optionally some samples late. The usual
// continuous-time model of inertial sensors (e.g. Kalibr's IMU noise model; Furgale et al.,
// IROS 2013): reading = truth + b + n, n white with density sigma_n, b' = white with density
// sigma_b; sampled every dt: n_k ~ N(0, sigma_n^2 / dt), b_k = b_{k-1} + N(0, sigma_b^2 dt).
// Allocation-free, fixed-size; seeded, so a run repeats exactly.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <random>

namespace hmpc::sensors {

using Vector3 = Eigen::Vector3d;
using Matrix3 = Eigen::Matrix3d;

// What an ideal IMU would read, in its own frame (mounted aligned with the body it sits on).
struct ImuTruth {
  Vector3 angular_velocity = Vector3::Zero();  // [rad/s]
  Vector3 specific_force = Vector3::Zero();    // [m/s^2]: acceleration minus gravity
};

// The truth at a point `offset` of a rigid body (body coordinates) from the body's motion:
// rotation body-to-world R, angular velocity w and the velocity v of the body's origin, both in
// body coordinates, and their time derivatives (as forward dynamics gives them for a floating
// base in body coordinates). The origin's acceleration in body coordinates is v' + w x v; the
// point's adds w' x r + w x (w x r); an accelerometer reads that minus gravity, R^T g.
inline ImuTruth imu_truth(const Matrix3& rotation, const Vector3& angular_velocity,
                          const Vector3& angular_acceleration, const Vector3& velocity,
                          const Vector3& velocity_derivative, const Vector3& offset,
                          const Vector3& gravity_world) {
  const Vector3& w = angular_velocity;
  const Vector3 acceleration = velocity_derivative + w.cross(velocity) +
                               angular_acceleration.cross(offset) + w.cross(w.cross(offset));
  return {w, acceleration - rotation.transpose() * gravity_world};
}

// One sensor's (gyroscope's or accelerometer's) error model, per axis.
struct InertialSensorConfig {
  double noise_density = 0.0;     // sigma_n [unit / sqrt(Hz)], unit rad/s or m/s^2
  double bias_random_walk = 0.0;  // sigma_b [unit * sqrt(Hz)]
  double initial_bias = 0.0;      // standard deviation of the power-up bias [unit]
  double range = 0.0;             // readings clip at +-range [unit]
  double resolution = 0.0;        // one least significant bit [unit]; 0: not quantised
};

struct ImuConfig {
  InertialSensorConfig gyroscope;
  InertialSensorConfig accelerometer;
  double period = 1e-3;  // [s] between samples
  int latency = 0;       // samples between the motion and its reading, 0..kMaxImuLatency
};

inline constexpr int kMaxImuLatency = 16;

// A Bosch BMI088, a MEMS IMU common on legged robots and drones, from its data sheet
// (BST-BMI088-DS001, specification tables of the gyroscope and the accelerometer, as quoted
// for revision 1.9): gyroscope rate noise density 0.014 deg/s/sqrt(Hz), zero-rate offset
// 1 deg/s (typical, taken as the power-up bias's standard deviation per axis); accelerometer
// noise density 160 (x, y) to 190 (z) ug/sqrt(Hz), 190 taken for all axes, zero-g offset 20 mg
// (typical, as 1 sigma). Ranges and resolutions of the 16-bit outputs (Bosch's BMI08x driver):
// +-1000 deg/s at 32.768 LSB per deg/s, enough for a fall; +-12 g at 2730 LSB per g, above a
// landing's impacts. The data sheet gives no bias random walk; we take those of Kalibr's
// example IMU configuration (ADIS16448): 4e-6 rad/s^2/sqrt(Hz) and 2e-4 m/s^3/sqrt(Hz). White
// noise is drawn per sample at density / sqrt(period) (Kalibr's convention): the angle and
// velocity random walks an estimator integrates are the data sheet's, while each sample is
// noisier than the chip's output filter would leave it.
inline ImuConfig bmi088(double period = 1e-3) {
  constexpr double kDegree = 0.017453292519943295;  // rad
  constexpr double kG = 9.80665;                    // m/s^2, standard gravity
  ImuConfig c;
  c.period = period;
  c.gyroscope.noise_density = 0.014 * kDegree;
  c.gyroscope.bias_random_walk = 4e-6;
  c.gyroscope.initial_bias = 1.0 * kDegree;
  c.gyroscope.range = 1000.0 * kDegree;
  c.gyroscope.resolution = kDegree / 32.768;
  c.accelerometer.noise_density = 190e-6 * kG;
  c.accelerometer.bias_random_walk = 2e-4;
  c.accelerometer.initial_bias = 20e-3 * kG;
  c.accelerometer.range = 12.0 * kG;
  c.accelerometer.resolution = kG / 2730.0;
  return c;
}

struct ImuReading {
  Vector3 angular_velocity = Vector3::Zero();  // [rad/s]
  Vector3 specific_force = Vector3::Zero();    // [m/s^2]
  bool saturated = false;                      // an axis at its range's end
};

class ImuModel {
 public:
  // Draws the power-up biases from the seed. A latency outside 0..kMaxImuLatency is clipped.
  ImuModel(const ImuConfig& config, std::uint64_t seed)
      : config_(config), random_(seed), latency_(std::clamp(config.latency, 0, kMaxImuLatency)) {
    for (int i = 0; i < 3; ++i) {
      gyroscope_bias_[i] = config_.gyroscope.initial_bias * gaussian_(random_);
      accelerometer_bias_[i] = config_.accelerometer.initial_bias * gaussian_(random_);
    }
  }

  // One sample: the biases take one step of their walk, then truth + bias + noise, clipped and
  // quantised; the reading returned is the one taken `latency` samples ago (the first reading
  // until that many have been taken).
  ImuReading measure(const ImuTruth& truth) {
    ImuReading now;
    walk(config_.gyroscope, gyroscope_bias_);
    walk(config_.accelerometer, accelerometer_bias_);
    now.angular_velocity =
        read(config_.gyroscope, truth.angular_velocity, gyroscope_bias_, now.saturated);
    now.specific_force =
        read(config_.accelerometer, truth.specific_force, accelerometer_bias_, now.saturated);
    if (taken_ == 0) delayed_.fill(now);
    delayed_[taken_ % delayed_.size()] = now;
    const ImuReading& out = delayed_[(taken_ + delayed_.size() - latency_) % delayed_.size()];
    ++taken_;
    return out;
  }

  // The biases now, for tests and logs of truth: what an estimator should find.
  const Vector3& gyroscope_bias() const { return gyroscope_bias_; }
  const Vector3& accelerometer_bias() const { return accelerometer_bias_; }
  const ImuConfig& config() const { return config_; }

 private:
  void walk(const InertialSensorConfig& sensor, Vector3& bias) {
    const double step = sensor.bias_random_walk * std::sqrt(config_.period);
    for (int i = 0; i < 3; ++i) bias[i] += step * gaussian_(random_);
  }

  Vector3 read(const InertialSensorConfig& sensor, const Vector3& truth, const Vector3& bias,
               bool& saturated) {
    const double sigma = sensor.noise_density / std::sqrt(config_.period);
    Vector3 out;
    for (int i = 0; i < 3; ++i) {
      double value = truth[i] + bias[i] + sigma * gaussian_(random_);
      if (std::abs(value) >= sensor.range) {
        saturated = true;
        value = std::copysign(sensor.range, value);
      }
      if (sensor.resolution > 0.0)
        value = std::round(value / sensor.resolution) * sensor.resolution;
      out[i] = value;
    }
    return out;
  }

  ImuConfig config_;
  std::mt19937_64 random_;
  std::normal_distribution<double> gaussian_{0.0, 1.0};
  int latency_;
  Vector3 gyroscope_bias_ = Vector3::Zero();
  Vector3 accelerometer_bias_ = Vector3::Zero();
  std::array<ImuReading, kMaxImuLatency + 1> delayed_{};
  std::uint64_t taken_ = 0;
};

}  // namespace hmpc::sensors
