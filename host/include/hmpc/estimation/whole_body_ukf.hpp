// The thesis's whole-body state estimator (Sec. 2.7.2): an unscented Kalman filter whose sigma
// points are moved by the robot's full-body dynamics with contact (the MPC's own step map,
// hmpc/humanoid/step.hpp) under the torques the joints were commanded, so that contact is in the
// prediction and needs no detector; their weighted mean is corrected by the encoders, the
// boards' joint velocities and the torso IMU. Beside it runs a base Kalman filter on the
// accelerometer with its bias (base_kalman_filter.hpp); each filter takes the other's estimate
// of the IMU point's position and velocity as an observation. Attitude errors are generalised
// Rodrigues parameters (GRP), as in Crassidis and Markley's USQUE ("Unscented filtering for
// spacecraft attitude estimation", J. Guidance, Control, and Dynamics 26(4), 2003).
//
// Error state (28): delta = (dp (3, world), dtheta (3, GRP of q_hat^-1 q, torso coordinates),
// dq_j (8), dv (14, model.hpp's v)); x = x_hat [+] delta adds p, q_j, v and right-multiplies
// the quaternion. Each 1 ms sample:
//   (U1) sigma points x_i = x_hat [+] (+-sqrt((n + lambda) P))_i and x_0 = x_hat, n = 28,
//        lambda = alpha^2 n - n (kappa = 0), weights Wm_0 = lambda / (n + lambda),
//        Wc_0 = Wm_0 + 1 - alpha^2 + beta, Wm_i = Wc_i = 1 / (2 (n + lambda));
//   (U2) y_i = step(x_i, tau, dt); what each would make the sensors read: its joints, its torso
//        IMU (from its mean acceleration (v_i+ - v_i) / dt, as the simulated IMU) plus the
//        biases, and its IMU point's position and velocity;
//   (U3) the mean: delta_i = y_i [-] y_0, mean delta_bar = sum Wm_i delta_i, x_bar = y_0 [+]
//        delta_bar; P_bar = sum Wc_i e_i e_i^T + Q, e_i = delta_i - delta_bar;
//   (U4) z_bar = sum Wm_i Z_i, P_zz = sum Wc_i dZ_i dZ_i^T + R, P_xz = sum Wc_i e_i dZ_i^T,
//        K = P_xz P_zz^-1, x_hat = x_bar [+] K (z - z_bar), P = P_bar - K P_zz K^T.
// Q is a torque error per step on every degree of freedom (the boards' torque tracking on the
// joints; on the base, the contact model's error as a wrench), dv = M^-1 tau_err dt.
//
// This estimator's model is the MPC's, which on our simulator is also the plant: it has the
// plant's exact dynamics, as the thesis's had its simulator's. A real robot's model errors are
// only in Q here.
//
// Fixed-size, allocation-free; one instance per robot (it holds a step map and its workspace).
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>

#include "hmpc/estimation/base_estimate.hpp"
#include "hmpc/estimation/base_kalman_filter.hpp"
#include "hmpc/estimation/imu_screen.hpp"
#include "hmpc/humanoid/sensors.hpp"
#include "hmpc/humanoid/step.hpp"

namespace hmpc::estimation {

inline constexpr int kUkfErrorSize = 28;
inline constexpr int kUkfMeasurementSize = 28;
inline constexpr int kSigmaPoints = 2 * kUkfErrorSize + 1;

struct WholeBodyUkfConfig {
  sensors::ImuConfig imu = sensors::bmi088();
  humanoid::ContactParameters contact{};
  // Joint readings' standard deviations. Encoders: a 16-bit count is 9.6e-5 rad, its rounding
  // 2.8e-5 rad RMS; 1e-4 allows for play. The boards' velocities lag the joints by their filter
  // (hmpc/sensors/joint_sensors.hpp): choice 0.05 rad/s, a few ms of a joint accelerating.
  double encoder_noise = 1e-4;     // [rad]
  double joint_rate_noise = 0.05;  // [rad/s]
  // The accelerometer's reading beyond its white noise: the model's acceleration at contact
  // is stiff (a 1 mm error of a sole's sink is 5.8 N at one point), choice 0.5 m/s^2.
  double acceleration_model_noise = 0.5;  // [m/s^2]
  // Q: torque errors per 1 ms step. Joints: choice 2 N m, a few percent of the hydraulic
  // joints' torques; base: the contact model's error as a wrench on the torso, choices 20 N
  // (4 % of the weight) and 5 N m.
  double joint_torque_noise = 2.0;  // [N m]
  double base_force_noise = 20.0;   // [N]
  double base_moment_noise = 5.0;   // [N m]
  // The other filter's estimate is correlated with this one's (each observes the other), so its
  // covariance is inflated by this factor where it is taken as an observation. Measured on the
  // recorded standing, slow squat and walking (estimation_test): at 2 and at 10 the two filters
  // talked each other into a drift (metres per second within two seconds; the base filter's
  // covariance, corrected by the UKF's, came back as an observation too certain to refuse); at
  // 100 both stay put and walking's horizontal velocity error is 0.012 m/s, against 0.045
  // without the exchange (1e6).
  double exchange_inflation = 100.0;
  // The unscented transform's spread: alpha 0.5 puts sigma points 2.6 standard deviations out
  // (sqrt(alpha^2 n)), inside the compliant contact's range where 5.3 (alpha 1) would lift a
  // standing sole clear of the ground or bury it; beta 2 for Gaussian priors.
  double alpha = 0.5;
  double beta = 2.0;
  // Initial standard deviations beyond what the rest gives.
  double initial_attitude = 0.02;        // rad, roll and pitch from gravity with bias errors
  double initial_position = 0.01;        // m
  double initial_velocity = 0.01;        // m/s and rad/s, at rest
  double initial_joint_angle = 1e-4;     // rad, the encoders
  double initial_joint_velocity = 0.01;  // rad/s
  // IMU readings refused (imu_screen.hpp): stuck after stuck_samples equal readings in a row,
  // as the invariant EKF's.
  int stuck_samples = 20;
  double max_interval = 0.05;           // [s], as the invariant EKF's
  int recovery_samples = 100;           // degraded after a bad input, as the invariant EKF's
  double trusted_tilt_sigma = 0.0873;   // rad, 5 degrees, as the invariant EKF's
  double trusted_velocity_sigma = 0.5;  // m/s
};

class WholeBodyUkf {
 public:
  using State = humanoid::State;
  using JointVector = humanoid::JointVector;
  using ErrorVector = Eigen::Matrix<double, kUkfErrorSize, 1>;
  using Covariance = Eigen::Matrix<double, kUkfErrorSize, kUkfErrorSize>;
  using Measurement = Eigen::Matrix<double, kUkfMeasurementSize, 1>;

  explicit WholeBodyUkf(const humanoid::Parameters& parameters = {},
                        const WholeBodyUkfConfig& config = {});

  // Starts the filters on a robot standing still on flat ground: roll and pitch from the mean
  // specific force, the gyroscope bias from the mean rate, the accelerometer's bias along
  // gravity from the mean force's magnitude; yaw and horizontal position zero; the lower sole
  // sunk as by the robot's weight. The rest must hold at least one sample.
  void initialize_at_rest(const ImuRest& rest, const JointVector& joint_angles);

  // One sample dt after the last: the torques applied over it, then its readings. An IMU
  // reading refused by the screen (not finite, out of range, stuck) is not used: the base
  // filter integrates the last good one and the UKF corrects with the joints alone; joint
  // readings that are not finite are not used either (the dynamics alone carry the estimate).
  // Either degrades the estimate for recovery_samples. An interval that is not finite, not
  // positive or above max_interval, or an update whose result is not finite, loses it.
  void update(const JointVector& torque, const humanoid::SensorReadings& reading, double dt);

  // The robot's state as model.hpp lays it out.
  const State& state() const { return state_; }
  BaseEstimate estimate() const;
  const Covariance& covariance() const { return covariance_; }
  const BaseKalmanFilter& base_filter() const { return base_; }
  Spread spread() const;
  Trust trust() const;
  bool initialized() const { return initialized_; }
  const RejectedInputs& rejected() const { return rejected_; }

 private:
  static State plus(const State& x, const ErrorVector& delta);
  static ErrorVector minus(const State& y, const State& x);
  // The IMU point's position and velocity (world) of x.
  void imu_point(const State& x, humanoid::Vector3& p, humanoid::Vector3& v) const;
  void predict_measurement(const State& before, const State& after, double dt,
                           Measurement& z) const;
  bool run_unscented(const JointVector& torque, const humanoid::SensorReadings& reading,
                     bool imu_good, bool joints_finite, double dt);
  void correct_base_filter();

  humanoid::Model model_;
  humanoid::StepMap step_map_;
  WholeBodyUkfConfig config_;
  double lambda_;
  double weight_mean0_, weight_cov0_, weight_;

  bool initialized_ = false;
  bool lost_ = true;
  State state_{};
  Covariance covariance_ = Covariance::Identity();
  humanoid::Vector3 gyroscope_bias_ = humanoid::Vector3::Zero();
  BaseKalmanFilter base_;
  ImuScreen screen_;
  int degraded_samples_ = 0;  // left until trusted again
  RejectedInputs rejected_;

  // Workspace (members: a few tens of kB, not on the stack each sample).
  std::array<State, kSigmaPoints> sigma_{}, propagated_{};
  std::array<ErrorVector, kSigmaPoints> deviation_{};
  std::array<Measurement, kSigmaPoints> predicted_{};
  // The estimate before an update, restored if the update fails or is not finite.
  State saved_state_{};
  Covariance saved_covariance_ = Covariance::Zero();
  BaseKalmanFilter saved_base_;
  Eigen::Matrix<double, kUkfMeasurementSize, kUkfMeasurementSize> innovation_covariance_;
  Eigen::Matrix<double, kUkfErrorSize, kUkfMeasurementSize> cross_covariance_;
  Eigen::LLT<Covariance> square_root_{Covariance::Identity()};
  Eigen::LLT<Eigen::Matrix<double, kUkfMeasurementSize, kUkfMeasurementSize>> innovation_llt_{
      Eigen::Matrix<double, kUkfMeasurementSize, kUkfMeasurementSize>::Identity()};
};

}  // namespace hmpc::estimation
