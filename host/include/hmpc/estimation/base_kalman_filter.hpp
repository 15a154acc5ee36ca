// The base Kalman filter of the thesis's estimator (Sec. 2.7.2): the torso IMU's position and
// velocity (world) driven by its accelerometer, with the accelerometer's bias as a state so that
// its drift is not integrated into the velocity. It has no measurement of its own: the
// whole-body filter's estimate of the same point is its observation (whole_body_ukf.hpp).
//
// State s = (p, v, b_a) (9): p, v the IMU point's position and velocity in world coordinates,
// b_a the accelerometer's bias in IMU coordinates. With the IMU's attitude R (IMU to world) from
// the whole-body filter and its specific force f, the acceleration is a = R (f - b_a) + g and
//   p+ = p + v dt + a dt^2 / 2,  v+ = v + a dt,  b_a+ = b_a + random walk.
// Header-only, fixed-size, allocation-free.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "hmpc/humanoid/model.hpp"
#include "hmpc/sensors/imu.hpp"

namespace hmpc::estimation {

class BaseKalmanFilter {
 public:
  using Vector3 = humanoid::Vector3;
  using Matrix3 = humanoid::Matrix3;
  using Matrix6 = Eigen::Matrix<double, 6, 6>;
  using Matrix9 = Eigen::Matrix<double, 9, 9>;

  explicit BaseKalmanFilter(const sensors::ImuConfig& imu = sensors::bmi088()) : imu_(imu) {}

  // Starts at p, v with standard deviations sigma_p, sigma_v per axis and the bias b_a with
  // covariance bias_covariance.
  void initialize(const Vector3& p, const Vector3& v, double sigma_p, double sigma_v,
                  const Vector3& b_a, const Matrix3& bias_covariance) {
    position_ = p;
    velocity_ = v;
    bias_ = b_a;
    covariance_.setZero();
    covariance_.block<3, 3>(0, 0) = sigma_p * sigma_p * Matrix3::Identity();
    covariance_.block<3, 3>(3, 3) = sigma_v * sigma_v * Matrix3::Identity();
    covariance_.block<3, 3>(6, 6) = bias_covariance;
  }

  // One accelerometer reading f over dt, the IMU's attitude being R; g is gravity (world).
  void propagate(const Matrix3& rotation, const Vector3& specific_force, const Vector3& gravity,
                 double dt) {
    const Vector3 a = rotation * (specific_force - bias_) + gravity;
    position_ += velocity_ * dt + 0.5 * dt * dt * a;
    velocity_ += a * dt;
    // F = [[I, I dt, -R dt^2/2], [0, I, -R dt], [0, 0, I]].
    Matrix9 f = Matrix9::Identity();
    f.block<3, 3>(0, 3) = dt * Matrix3::Identity();
    f.block<3, 3>(0, 6) = -0.5 * dt * dt * rotation;
    f.block<3, 3>(3, 6) = -dt * rotation;
    covariance_ = f * covariance_ * f.transpose();
    // White acceleration noise (density^2 dt into v) and the bias's random walk.
    const double na = imu_.accelerometer.noise_density, nb = imu_.accelerometer.bias_random_walk;
    covariance_.block<3, 3>(3, 3) += na * na * dt * Matrix3::Identity();
    covariance_.block<3, 3>(6, 6) += nb * nb * dt * Matrix3::Identity();
  }

  // An observation of p and v (6) with covariance `noise`. Returns false, changing nothing,
  // when the innovation's covariance is not positive definite.
  bool correct(const Vector3& p, const Vector3& v, const Matrix6& noise) {
    using Gain = Eigen::Matrix<double, 9, 6>;
    Eigen::Matrix<double, 6, 1> innovation;
    innovation << p - position_, v - velocity_;
    // H = [I6 0]: S = P_11 + noise, K = P_:1 S^-1.
    const Matrix6 s = covariance_.topLeftCorner<6, 6>() + noise;
    const Eigen::LLT<Matrix6> llt(s);
    if (llt.info() != Eigen::Success) return false;
    const Gain gain = llt.solve(covariance_.topRows<6>()).transpose();
    const Eigen::Matrix<double, 9, 1> dx = gain * innovation;
    position_ += dx.head<3>();
    velocity_ += dx.segment<3>(3);
    bias_ += dx.tail<3>();
    // Joseph form keeps P symmetric positive semi-definite.
    Matrix9 a = Matrix9::Identity();
    a.leftCols<6>() -= gain;
    covariance_ = a * covariance_ * a.transpose() + gain * noise * gain.transpose();
    return true;
  }

  const Vector3& position() const { return position_; }
  const Vector3& velocity() const { return velocity_; }
  const Vector3& accelerometer_bias() const { return bias_; }
  const Matrix9& covariance() const { return covariance_; }

 private:
  sensors::ImuConfig imu_;
  Vector3 position_ = Vector3::Zero(), velocity_ = Vector3::Zero(), bias_ = Vector3::Zero();
  Matrix9 covariance_ = Matrix9::Identity();
};

}  // namespace hmpc::estimation
