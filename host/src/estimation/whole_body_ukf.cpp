#include "hmpc/estimation/whole_body_ukf.hpp"

#include <algorithm>
#include <cmath>

#include "hmpc/humanoid/imu.hpp"

namespace hmpc::estimation {

namespace {

using humanoid::kJoints;
using Quaternion = Eigen::Quaterniond;

constexpr int kN = kUkfErrorSize;
// Error-state blocks.
constexpr int kDp = 0, kDtheta = 3, kDjoint = 6, kDv = 14;
// Measurement blocks.
constexpr int kZangle = 0, kZrate = 8, kZgyro = 16, kZaccel = 19, kZp = 22, kZv = 25;
// q's quaternion (w, x, y, z).
constexpr int kQw = 3;
// v's blocks: torso angular, torso linear (torso coordinates), joints.
constexpr int kVangular = 0, kVlinear = 3, kVjoint = 6;

// GRP with a = 1, f = 2 (a + 1) = 4 (USQUE's choice): p = f q_v / (a + q_w), which equals the
// rotation vector to second order, and back.
constexpr double kGrpF = 4.0;

Quaternion quaternion_of_grp(const Vector3& p) {
  const double n2 = p.squaredNorm();
  const double w = (kGrpF * kGrpF - n2) / (kGrpF * kGrpF + n2);
  const Vector3 v = (1.0 + w) * p / kGrpF;
  return Quaternion(w, v.x(), v.y(), v.z());
}

Vector3 grp_of_quaternion(Quaternion q) {
  if (q.w() < 0) q.coeffs() = -q.coeffs();  // the shorter of the two rotations
  return kGrpF * q.vec() / (1.0 + q.w());
}

Quaternion orientation_of(const humanoid::State& x) {
  return Quaternion(x.q[kQw], x.q[kQw + 1], x.q[kQw + 2], x.q[kQw + 3]);
}

Matrix3 skew(const Vector3& a) {
  Matrix3 s;
  s << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
  return s;
}

}  // namespace

WholeBodyUkf::WholeBodyUkf(const humanoid::Parameters& parameters, const WholeBodyUkfConfig& config)
    : model_(parameters), step_map_(model_, parameters, config.contact), config_(config),
      base_(config.imu), screen_(config.imu, config.stuck_samples) {
  lambda_ = config_.alpha * config_.alpha * kN - kN;
  weight_mean0_ = lambda_ / (kN + lambda_);
  weight_cov0_ = weight_mean0_ + 1.0 - config_.alpha * config_.alpha + config_.beta;
  weight_ = 1.0 / (2.0 * (kN + lambda_));
}

humanoid::State WholeBodyUkf::plus(const State& x, const ErrorVector& delta) {
  State y = x;
  y.q.head<3>() += delta.segment<3>(kDp);
  const Quaternion q =
      (orientation_of(x) * quaternion_of_grp(delta.segment<3>(kDtheta))).normalized();
  y.q.segment<4>(kQw) << q.w(), q.x(), q.y(), q.z();
  y.q.tail<kJoints>() += delta.segment<kJoints>(kDjoint);
  y.v += delta.segment<humanoid::kDofs>(kDv);
  return y;
}

WholeBodyUkf::ErrorVector WholeBodyUkf::minus(const State& y, const State& x) {
  ErrorVector d;
  d.segment<3>(kDp) = y.q.head<3>() - x.q.head<3>();
  d.segment<3>(kDtheta) = grp_of_quaternion(orientation_of(x).conjugate() * orientation_of(y));
  d.segment<kJoints>(kDjoint) = y.q.tail<kJoints>() - x.q.tail<kJoints>();
  d.segment<humanoid::kDofs>(kDv) = y.v - x.v;
  return d;
}

void WholeBodyUkf::imu_point(const State& x, Vector3& p, Vector3& v) const {
  const Matrix3 r = orientation_of(x).normalized().toRotationMatrix();
  const Vector3 w = x.v.segment<3>(kVangular);
  p = x.q.head<3>() + r * model_.imu;
  v = r * (x.v.segment<3>(kVlinear) + w.cross(model_.imu));
}

void WholeBodyUkf::predict_measurement(const State& before, const State& after, double dt,
                                       Measurement& z) const {
  // The IMU as the simulated one reads it: the state at the step's end, its mean acceleration.
  const humanoid::Velocity a = (after.v - before.v) / dt;
  const sensors::ImuTruth imu = humanoid::torso_imu_truth(model_, after.q, after.v, a);
  z.segment<kJoints>(kZangle) = after.q.tail<kJoints>();
  z.segment<kJoints>(kZrate) = after.v.tail<kJoints>();
  z.segment<3>(kZgyro) = imu.angular_velocity + gyroscope_bias_;
  z.segment<3>(kZaccel) = imu.specific_force + base_.accelerometer_bias();
  Vector3 p, v;
  imu_point(after, p, v);
  z.segment<3>(kZp) = p;
  z.segment<3>(kZv) = v;
}

void WholeBodyUkf::initialize_at_rest(const ImuRest& rest, const JointVector& joint_angles) {
  const double g = model_.gravity.norm();
  const Vector3 force = rest.mean_specific_force();
  const Vector3 up = force.normalized();
  const Quaternion q = Quaternion::FromTwoVectors(up, Vector3::UnitZ());
  gyroscope_bias_ = rest.mean_angular_velocity();
  state_.q.setZero();
  state_.q.segment<4>(kQw) << q.w(), q.x(), q.y(), q.z();
  state_.q.tail<kJoints>() = joint_angles;
  state_.v.setZero();
  // The lower sole's points sunk as by the robot's weight on eight points.
  humanoid::Kinematics kinematics;
  step_map_.dynamics().kinematics(state_.q, state_.v, kinematics);
  double lowest = 1e9;
  for (int i = 0; i < humanoid::kSolePoints; ++i) {
    const humanoid::ContactPoint& point = step_map_.contact_model().point(i);
    lowest = std::min(
        lowest,
        (kinematics.position[point.body] + kinematics.rotation[point.body] * point.local).z());
  }
  state_.q[2] = -humanoid::standing_sink(model_.total_mass() * g, config_.contact) - lowest;

  covariance_.setZero();
  const double a = config_.initial_attitude, p = config_.initial_position;
  const double v = config_.initial_velocity;
  covariance_.block<3, 3>(kDp, kDp) = p * p * Matrix3::Identity();
  // Yaw is zero by convention: a small variance keeps the matrix positive definite.
  covariance_.block<3, 3>(kDtheta, kDtheta) = Vector3(a * a, a * a, 1e-4).asDiagonal();
  covariance_.block<kJoints, kJoints>(kDjoint, kDjoint)
      .diagonal()
      .setConstant(config_.initial_joint_angle * config_.initial_joint_angle);
  covariance_.block<6, 6>(kDv, kDv).diagonal().setConstant(v * v);
  covariance_.block<kJoints, kJoints>(kDv + kVjoint, kDv + kVjoint)
      .diagonal()
      .setConstant(config_.initial_joint_velocity * config_.initial_joint_velocity);

  // The base filter: the rest's mean leaves white noise of density / sqrt(seconds) in the
  // accelerometer's bias along gravity; across it the power-up spread stays.
  const auto& imu = config_.imu;
  const double t = std::max(rest.seconds, imu.period);
  const double sa = imu.accelerometer.noise_density / std::sqrt(t);
  const double sh = imu.accelerometer.initial_bias;
  const Matrix3 vertical = up * up.transpose();
  Vector3 p_imu, v_imu;
  imu_point(state_, p_imu, v_imu);
  base_.initialize(p_imu, v_imu, p, v, (force.norm() - g) * up,
                   sa * sa * vertical + sh * sh * (Matrix3::Identity() - vertical));
  screen_.start(rest.mean_angular_velocity(), force);
  degraded_samples_ = 0;
  lost_ = false;
  initialized_ = true;
}

void WholeBodyUkf::update(const JointVector& torque, const humanoid::SensorReadings& reading,
                          double dt) {
  if (!initialized_ || lost_) return;
  if (!std::isfinite(dt) || dt <= 0 || dt > config_.max_interval) {
    ++rejected_.bad_interval;
    lost_ = true;
    return;
  }
  const bool imu_good = screen_.check(reading.imu, rejected_);
  const bool joints_finite = reading.angles.allFinite() && reading.rates.allFinite();
  if (!joints_finite) ++rejected_.joints_not_finite;
  if (!imu_good || !joints_finite || !torque.allFinite()) {
    degraded_samples_ = config_.recovery_samples;
  } else if (degraded_samples_ > 0) {
    --degraded_samples_;
  }
  saved_state_ = state_;
  saved_covariance_ = covariance_;
  saved_base_ = base_;

  // The base filter runs on the IMU with the attitude the whole-body filter has now.
  base_.propagate(orientation_of(state_).normalized().toRotationMatrix(),
                  screen_.last_good().specific_force, model_.gravity, dt);
  const JointVector tau = torque.allFinite() ? torque : JointVector::Zero();
  const bool ok = run_unscented(tau, reading, imu_good, joints_finite, dt);
  if (ok) correct_base_filter();
  const bool finite_now = state_.q.allFinite() && state_.v.allFinite() && covariance_.allFinite() &&
                          base_.covariance().allFinite() && base_.position().allFinite() &&
                          base_.velocity().allFinite();
  if (!ok || !finite_now) {
    ++rejected_.state_not_finite;
    state_ = saved_state_;
    covariance_ = saved_covariance_;
    base_ = saved_base_;
    lost_ = true;
  }
}

bool WholeBodyUkf::run_unscented(const JointVector& torque, const humanoid::SensorReadings& reading,
                                 bool imu_good, bool joints_finite, double dt) {
  // (U1) sigma points.
  square_root_.compute((kN + lambda_) * covariance_);
  if (square_root_.info() != Eigen::Success) return false;
  const Covariance l = square_root_.matrixL();
  sigma_[0] = state_;
  for (int i = 0; i < kN; ++i) {
    sigma_[1 + i] = plus(state_, l.col(i));
    sigma_[1 + kN + i] = plus(state_, -l.col(i));
  }
  // (U2) through the dynamics.
  for (int i = 0; i < kSigmaPoints; ++i) {
    propagated_[i] = step_map_.step(sigma_[i], torque, dt);
    predict_measurement(sigma_[i], propagated_[i], dt, predicted_[i]);
  }
  // (U3) the mean and the predicted covariance.
  ErrorVector mean = ErrorVector::Zero();
  for (int i = 0; i < kSigmaPoints; ++i) {
    deviation_[i] = minus(propagated_[i], propagated_[0]);
    mean += (i == 0 ? weight_mean0_ : weight_) * deviation_[i];
  }
  const State predicted = plus(propagated_[0], mean);
  Covariance p = Covariance::Zero();
  for (int i = 0; i < kSigmaPoints; ++i) {
    deviation_[i] -= mean;
    p.noalias() += (i == 0 ? weight_cov0_ : weight_) * deviation_[i] * deviation_[i].transpose();
  }
  // Q: torque errors through the inverse inertia, dv = M^-1 tau_err dt.
  const humanoid::MassMatrix& m = step_map_.dynamics().mass_matrix(predicted.q);
  const Eigen::LLT<humanoid::MassMatrix> inertia(m);
  humanoid::MassMatrix g = inertia.solve(humanoid::MassMatrix::Identity()) * dt;
  humanoid::Velocity torque_variance;
  torque_variance << Vector3::Constant(config_.base_moment_noise * config_.base_moment_noise),
      Vector3::Constant(config_.base_force_noise * config_.base_force_noise),
      JointVector::Constant(config_.joint_torque_noise * config_.joint_torque_noise);
  p.block<humanoid::kDofs, humanoid::kDofs>(kDv, kDv).noalias() +=
      g * torque_variance.asDiagonal() * g.transpose();
  if (!joints_finite) {
    state_ = predicted;
    covariance_ = 0.5 * (p + p.transpose());
    return true;
  }

  // (U4) the correction.
  Measurement z_mean = Measurement::Zero();
  for (int i = 0; i < kSigmaPoints; ++i) {
    z_mean += (i == 0 ? weight_mean0_ : weight_) * predicted_[i];
  }
  innovation_covariance_.setZero();
  cross_covariance_.setZero();
  for (int i = 0; i < kSigmaPoints; ++i) {
    const Measurement dz = predicted_[i] - z_mean;
    const double w = i == 0 ? weight_cov0_ : weight_;
    innovation_covariance_.noalias() += w * dz * dz.transpose();
    cross_covariance_.noalias() += w * deviation_[i] * dz.transpose();
  }
  const auto& imu = config_.imu;
  const double gyro = imu.gyroscope.noise_density / std::sqrt(imu.period);
  const double accel = imu.accelerometer.noise_density / std::sqrt(imu.period);
  const double accel2 =
      accel * accel + config_.acceleration_model_noise * config_.acceleration_model_noise;
  auto r = innovation_covariance_.diagonal();
  r.segment<kJoints>(kZangle).array() += config_.encoder_noise * config_.encoder_noise;
  r.segment<kJoints>(kZrate).array() += config_.joint_rate_noise * config_.joint_rate_noise;
  // A refused IMU reading: its rows are uninformative (a variance far beyond any reading).
  constexpr double kUnused = 1e12;
  r.segment<3>(kZgyro).array() += imu_good ? gyro * gyro : kUnused;
  r.segment<3>(kZaccel).array() += imu_good ? accel2 : kUnused;
  innovation_covariance_.block<6, 6>(kZp, kZp) +=
      config_.exchange_inflation * base_.covariance().topLeftCorner<6, 6>();
  Measurement z;
  const sensors::ImuReading& imu_reading = imu_good ? reading.imu : screen_.last_good();
  z << reading.angles, reading.rates, imu_reading.angular_velocity, imu_reading.specific_force,
      base_.position(), base_.velocity();
  innovation_llt_.compute(innovation_covariance_);
  if (innovation_llt_.info() != Eigen::Success) return false;
  // K = P_xz P_zz^-1, from P_zz K^T = P_xz^T.
  const Eigen::Matrix<double, kN, kUkfMeasurementSize> gain =
      innovation_llt_.solve(cross_covariance_.transpose()).transpose();
  state_ = plus(predicted, gain * (z - z_mean));
  p.noalias() -= gain * innovation_covariance_ * gain.transpose();
  covariance_ = 0.5 * (p + p.transpose());
  return true;
}

void WholeBodyUkf::correct_base_filter() {
  // The IMU point's position and velocity and their covariance J P J^T to first order:
  //   p_imu = p + R r:                dp_imu = dp - R [r]x dtheta,
  //   v_imu = R (v_lin + w x r):      dv_imu = -R [v_lin + w x r]x dtheta + R dv_lin - R [r]x dw.
  const Matrix3 rotation = orientation_of(state_).normalized().toRotationMatrix();
  const Vector3 w = state_.v.segment<3>(kVangular);
  const Vector3 body_velocity = state_.v.segment<3>(kVlinear) + w.cross(model_.imu);
  Eigen::Matrix<double, 6, kN> j = Eigen::Matrix<double, 6, kN>::Zero();
  j.block<3, 3>(0, kDp).setIdentity();
  j.block<3, 3>(0, kDtheta) = -rotation * skew(model_.imu);
  j.block<3, 3>(3, kDtheta) = -rotation * skew(body_velocity);
  j.block<3, 3>(3, kDv + kVlinear) = rotation;
  j.block<3, 3>(3, kDv + kVangular) = -rotation * skew(model_.imu);
  const BaseKalmanFilter::Matrix6 noise =
      config_.exchange_inflation * j * covariance_ * j.transpose();
  Vector3 p, v;
  imu_point(state_, p, v);
  base_.correct(p, v, noise);
}

Spread WholeBodyUkf::spread() const {
  const Matrix3 rotation = orientation_of(state_).normalized().toRotationMatrix();
  const Matrix3 velocity =
      rotation * covariance_.block<3, 3>(kDv + kVlinear, kDv + kVlinear) * rotation.transpose();
  const Matrix3 attitude =
      rotation * covariance_.block<3, 3>(kDtheta, kDtheta) * rotation.transpose();
  Spread s;
  s.height = std::sqrt(covariance_(kDp + 2, kDp + 2));
  s.horizontal_velocity = std::sqrt(velocity(0, 0) + velocity(1, 1));
  s.tilt = std::sqrt(attitude(0, 0) + attitude(1, 1));
  return s;
}

Trust WholeBodyUkf::trust() const {
  if (!initialized_ || lost_) return Trust::kLost;
  const Spread s = spread();
  if (!(s.tilt <= config_.trusted_tilt_sigma) ||
      !(s.horizontal_velocity <= config_.trusted_velocity_sigma)) {
    return Trust::kLost;
  }
  return degraded_samples_ > 0 ? Trust::kDegraded : Trust::kTracking;
}

BaseEstimate WholeBodyUkf::estimate() const {
  BaseEstimate e;
  const Quaternion q = orientation_of(state_).normalized();
  e.position = state_.q.head<3>();
  e.orientation = q;
  e.velocity = q * state_.v.segment<3>(kVlinear);
  e.angular_velocity = state_.v.segment<3>(kVangular);
  e.gyroscope_bias = gyroscope_bias_;
  e.accelerometer_bias = base_.accelerometer_bias();
  e.spread = spread();
  e.trust = trust();
  return e;
}

}  // namespace hmpc::estimation
