// Whole-body base estimation from a torso IMU and the joint encoders, no force sensors: the
// contact-aided right-invariant EKF of Hartley, Ghaffari, Eustice and Grizzle ("Contact-aided
// invariant extended Kalman filtering for robot state estimation", IJRR 39(4), 2020).
//
// The state is the IMU frame's rotation R (IMU to world), velocity v and position p (world),
// the points d_L, d_R under the two ankles (world), as one element of the group SE_4(3), and
// the gyroscope and accelerometer biases b_g, b_a beside it (the paper's "imperfect IEKF").
// The error xi = (phi, xi_v, xi_p, xi_dL, xi_dR, zeta_g, zeta_a) (21) is right-invariant:
// X_hat = exp(xi) X. Because the IMU's process model is group-affine, the error's dynamics do
// not depend on the estimate except through the biases, so the filter stays consistent where a
// plain EKF's attitude error makes it overconfident.
//
// Each 1 ms sample: propagate with the IMU (Eqs. below), then correct with each stance foot's
// leg kinematics: its support point (where its sole bears: the sole's centre, an edge or a
// corner), seen from the IMU through the joint angles, must be the stance point d_i, fixed in
// the world. A swing foot's d_i follows the kinematics and is re-anchored each sample (its
// error copied from p's: the paper's augmentation of a new contact, xi_d = xi_p for
// d = p + R FK). Which feet stand is an input: the caller infers it (no force sensors); of two
// stance feet moving apart, the faster is flagged as slipping and re-anchored instead.
//
// Fixed-size, allocation-free; one instance per robot.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>

#include "hmpc/constants.hpp"
#include "hmpc/estimation/base_estimate.hpp"
#include "hmpc/estimation/imu_screen.hpp"
#include "hmpc/humanoid/contact.hpp"
#include "hmpc/humanoid/dynamics.hpp"
#include "hmpc/sensors/imu.hpp"

namespace hmpc::estimation {

inline constexpr int kErrorSize = 21;
using Covariance = Eigen::Matrix<double, kErrorSize, kErrorSize>;

struct InvariantEkfConfig {
  // The IMU's noise densities and bias walks: the filter's process noise (one source with
  // the simulated sensor, hmpc/sensors/imu.hpp).
  sensors::ImuConfig imu = sensors::bmi088();
  // A stance point's velocity, white [m/s / sqrt(Hz)]: the ground's creep under a tangential
  // load (contact.hpp: 5.8 mm/s at half the friction limit) and the sole rocking on it, the
  // foot's rolling being taken by its support point. Choice: 0.01, 1 cm of drift in a second;
  // measured on the recorded runs, 0.05 (a rolling foot's, as Hartley et al. tune theirs on
  // Cassie's point feet) left walking's horizontal velocity error at 0.16 m/s RMS, 0.01 at
  // 0.015 m/s; 0.005 let the jump's tilt error grow to 1.5 degrees.
  double stance_foot_noise = 0.01;
  // The same for a sole bearing on all four corners (flat): it does not rock, and standing it
  // carries little tangential load, so mostly the creep is left: 5 mm/s near half the friction
  // limit (contact.hpp's law). Choice: 0.005, measured. On the humanoid over its buses (the
  // hydraulic plant, the MPC holding the hip on this estimate) at 0.01 a 0.015 m/s velocity
  // error from the MPC's take-over decayed only over seconds and the robot, rocking onto a
  // heel, fell within 3 s; at 0.005 it held. At 0.002 one seed of the standing closed loop
  // on the estimate fell (its height estimate off by 2 cm).
  double flat_stance_foot_noise = 0.005;
  // Leg kinematics' error [m] per axis: link lengths, joint play, the contact wandering
  // within its support. Choice: 5 mm.
  double kinematics_noise = 0.005;
  // The ground is flat at z = 0, as the MPC's contact model has it: flat stance soles sink
  // into its compliance by the load they carry, the robot's mass times the IMU's vertical
  // specific force, spread over their corners (a linear spring each). Only the feet's mean
  // height is measured, because how two feet share the load is unknown (a flat stance in
  // single support sinks 2 cm, twice the standing sink; taken as 1 cm for every flat foot, it
  // tilted the walk's estimate by 1 degree). It makes the height, otherwise unobservable
  // like the horizontal position, an estimate instead of a drift. Not while any stance foot is
  // on an edge or a corner: how deep an edge sinks depends on the load's share along the sole
  // (a heel edge 12-20 mm deep measured on the slow squat, against 10 mm flat). ground_noise
  // [m]: the load misses the legs' own accelerations and the contact's damping (c v, half the
  // spring's force at a 0.5 m/s touchdown); choice 2 cm, measured on the recorded runs (tilt
  // RMS, walking and the low jump, contact from the legs): 0.5 cm 0.57 and 1.58 degrees, 1 cm
  // 0.46 and 0.78, 2 cm 0.37 and 0.35.
  humanoid::ContactParameters contact{};
  double ground_noise = 0.02;
  // Two stance feet whose support points move apart faster than slip_speed [m/s] for
  // slip_samples in a row: the faster of them is slipping. Choices: 0.3 m/s and 20 samples
  // (20 ms): a sole rolling from heel to toe and the boards' filtered joint rates (a few ms
  // late while a joint accelerates) reach 0.3 m/s only for moments.
  double slip_speed = 0.3;
  int slip_samples = 20;
  // Where a stance foot bears: the mean of its sole's corners (the contact model's four) lying
  // within support_band [m] of the lowest, in the estimated world (a corner that left rejoins
  // within support_rejoin): the sole's centre when flat, an edge's middle when landing on the
  // heel or rolling onto the toes, a corner when on it. That point, not the one under the
  // ankle, is fixed while the foot rolls; a change of it moves the stance point along the sole.
  // Choices: on the compliant ground (1 cm standing sink) a loaded sole rocks about its centre
  // with every corner pressed in, its heel and toe up to 20 mm apart on the slow squat, so
  // 30 mm (7.5 degrees across the 0.23 m foot) before a corner counts as lifted; 15 mm to
  // rejoin, because a rule without this hysteresis toggled between flat and heels every 10 ms
  // there and each toggle ratcheted the attitude (3 degrees of tilt error; 10 mm with 5 mm:
  // 1.5 degrees on standing).
  double support_band = 0.03;
  double support_rejoin = 0.015;
  // Contact from the legs alone (correct() without stance flags; no force sensors): a foot
  // touches down once its support point, placed by the estimate and the joint angles, is
  // below touchdown_height [m] and lifts off once it rises above liftoff_height. Choices: a
  // loaded sole sits 10 mm deep (standing sink), so 5 mm above the surface admits the height
  // estimate's error at touchdown (5 mm RMS on walking); 15 mm for lift-off, hysteresis
  // against that error and well below a step's 7 cm swing (motion II).
  double touchdown_height = 0.005;
  double liftoff_height = 0.015;
  // The IMU tells a flight from a stance: in the air nothing but gravity acts, and the
  // accelerometer reads a specific force near zero (the swinging legs' reaction and the
  // torso's rotation add a little); on the ground it reads about g. Below flight_force [m/s^2]
  // no foot stands, whatever the legs say; above it the robot stands on something, so when
  // neither foot is below its touchdown or lift-off height, the lower one stands if its
  // support point is within support_reach [m]. Choices: 0.3 g, and 40 mm, a few times the
  // height error of a toe pushing off with the tilt off by 2 degrees, half a walking step's
  // swing. Measured on the recorded jump (seeds 21, 22, 23, 25): the tilt error with contact
  // from the legs went from 1.5-2.3 to 0.9-1.4 degrees; the legs alone had dropped a foot
  // pushing off on its toes (its support point 15 mm up in the estimate) and kept one
  // that had left; walking and the slow squat unchanged.
  double flight_force = 0.3 * 9.81;
  double support_reach = 0.04;
  // A stance foot whose kinematic innovation's squared Mahalanobis distance exceeds this is not
  // used in that sample (a slip the speed test has not confirmed yet, a heel strike's bounce):
  // 16.3 is the chi-square distribution's 99.9 % point for 3 degrees of freedom.
  double innovation_gate = 16.3;
  // Initial standard deviations beyond what the rest gives: yaw and horizontal position are
  // set by convention (zero), not measured. (Roll and pitch from gravity carry the
  // accelerometer's horizontal power-up spread, imu.accelerometer.initial_bias / g.)
  double initial_velocity = 0.01;  // m/s, at rest
  double initial_position = 0.01;  // m
  // At rest the soles stand flat on level ground, so the legs tell roll and pitch, which the
  // accelerometer alone cannot tell from its horizontal power-up offset (BMI088: 20 mg, 1.15
  // degrees per axis, otherwise revealed only by motion, slowly on a straight walk). Their
  // error per axis [rad]: choice 0.5 degrees, a lab floor's slope (0.1-0.3 degrees) and the
  // leg joints' zero offsets summed along hip, knee and ankle (~0.2 degrees each). A sole
  // tilted beyond a chi-square gate (2 degrees of freedom, 99.9 %: on a slope, on a step) is
  // not used.
  double level_sole_noise = 0.5 * kPi<double> / 180;

  // Bad input. An IMU reading that is not finite, saturated or beyond the sensor's range, or
  // stuck (the same six values
  // stuck_samples times in a row: a live MEMS sensor's noise changes its LSBs every sample)
  // is replaced by the last good one, and the reading it stands for is taken as unknown within
  // unknown_rate [rad/s] and unknown_acceleration [m/s^2] (1 sigma; choices: what the torso
  // reaches in our motions, ~1 rad/s and ~1 g), added to the attitude's and the velocity's
  // covariance. A joint sample that is not finite is skipped. Choice: 20 samples (20 ms).
  int stuck_samples = 20;
  double unknown_rate = 1.0;
  double unknown_acceleration = 10.0;
  // An interval longer than max_interval [s] between IMU samples (many dropped) cannot be
  // integrated: the estimate is lost until the filter is started again. Choice: 50 ms, where
  // 1 g of unknown acceleration moves the base by 1.2 cm.
  double max_interval = 0.05;
  // The estimate is degraded for recovery_samples after a bad input (choice: 100 ms, the
  // MPC's few coarse steps), and lost while its own standard deviation of tilt or of
  // horizontal velocity exceeds the limits (choices: 5 deg, 0.5 m/s: ten times our targets,
  // past which an MPC would act on a posture or a speed the robot does not have).
  int recovery_samples = 100;
  double trusted_tilt_sigma = 0.0873;  // rad, 5 degrees
  double trusted_velocity_sigma = 0.5;
};

class InvariantEkf {
 public:
  using Model = humanoid::Model;
  using JointVector = humanoid::JointVector;

  explicit InvariantEkf(const humanoid::Parameters& parameters = {},
                        const InvariantEkfConfig& config = {});

  // Starts the filter on a robot standing still on flat ground (z = 0): roll and pitch from the
  // mean specific force, corrected by the soles standing level (level_sole_noise), which also
  // gives the accelerometer's horizontal bias; the gyroscope bias from the mean rate, the
  // accelerometer bias along gravity from the mean force's magnitude; yaw and horizontal
  // position zero (unobservable); height from the legs. Feet on the ground are the stance
  // points. The rest must hold at least one sample.
  void initialize_at_rest(const ImuRest& rest, const JointVector& joint_angles);
  // The same for a rest that was not quite still: a robot held by its joints' controllers sags
  // and turns a little while the rest is taken (on the hydraulic legs under the boards' hold,
  // ~3.7 mrad/s of pitch: taken for the gyroscope's bias it tilted the estimate by 0.01 rad
  // within 3 s). The soles flat and fixed, the legs' angles at the rest's first reading and
  // at its last, `span` [s] later, tell how the torso turned; its mean rate is the gyroscope
  // mean's share that is not bias.
  void initialize_at_rest(const ImuRest& rest, const JointVector& angles_at_start,
                          const JointVector& joint_angles, double span);

  // One IMU sample, dt after the last (bad readings and intervals: InvariantEkfConfig).
  void propagate(const sensors::ImuReading& imu, double dt);
  // The leg kinematics of this sample; `stance` says which feet the caller takes as standing.
  // A sample with a non-finite angle or rate is skipped.
  // Without `stance`, which feet stand is inferred from the legs (touchdown_height).
  void correct(const JointVector& joint_angles, const JointVector& joint_rates,
               const std::array<bool, kFeet>& stance);
  void correct(const JointVector& joint_angles, const JointVector& joint_rates);

  BaseEstimate estimate() const;
  const Covariance& covariance() const { return covariance_; }
  Spread spread() const;
  bool initialized() const { return initialized_; }
  Trust trust() const;
  const RejectedInputs& rejected() const { return rejected_; }

 private:
  // How deep `feet` flat soles sink under a vertical ground force `load` [N].
  double sink(double load, int feet) const;
  // Foot i's sole corners in IMU coordinates, and their velocities there from the joint rates
  // (the leg moving, the IMU frame held).
  void leg_kinematics(const JointVector& angles, const JointVector& rates);
  // The corners foot i bears on (support_band) in the present attitude; the mean of the
  // corners in `mask` (IMU coordinates) and of their velocities.
  std::uint8_t support_corners(int foot) const;
  Vector3 mean_of_corners(int foot, std::uint8_t mask, Vector3* velocity) const;
  void anchor_swing_foot(int foot);
  // How the torso turned [rad, rotation vector in its coordinates at `from`] while the legs
  // went from `from` to `to` with both soles fixed in the world.
  Vector3 turn_on_the_feet(const JointVector& from, const JointVector& to);
  // One step of the IMU's process model with bias-corrected rate w and force a.
  void integrate(const Vector3& w, const Vector3& a, double dt);
  // The Kalman update with z = H xi + noise (covariance n; X_true = exp(xi) X): rows of an
  // unused measurement are zero in h and z and identity in n.
  template <int Rows>
  void update(const Eigen::Matrix<double, Rows, kErrorSize>& h,
              const Eigen::Matrix<double, Rows, 1>& z, const Eigen::Matrix<double, Rows, Rows>& n,
              const Eigen::Matrix<double, Rows, Rows>& unused);
  // The soles standing level at rest, as a measurement of roll and pitch.
  void correct_with_level_soles();
  // The correction with finite joint readings; null stance flags: inferred from the legs.
  void correct_checked(const JointVector& joint_angles, const JointVector& joint_rates,
                       const std::array<bool, kFeet>* stance);
  void correct_with_legs(const JointVector& joint_angles, const JointVector& joint_rates,
                         const std::array<bool, kFeet>* asked);

  // The estimate before an update, restored if the update made it non-finite.
  struct Snapshot {
    Matrix3 rotation;
    Vector3 velocity, position, gyroscope_bias, accelerometer_bias;
    std::array<Vector3, kFeet> stance_point;
    Covariance covariance;
  };
  void save(Snapshot& out) const;
  void restore(const Snapshot& in);
  bool finite() const;

  Model model_;
  humanoid::Dynamics dynamics_;
  InvariantEkfConfig config_;
  double mass_;  // the robot's [kg]
  humanoid::Kinematics kinematics_;
  std::array<Vector3, humanoid::kFootPoints> sole_corner_{};                // foot coordinates
  std::array<std::array<Vector3, humanoid::kFootPoints>, kFeet> corner_{};  // IMU coordinates
  std::array<std::array<Vector3, humanoid::kFootPoints>, kFeet> corner_velocity_{};
  std::array<Vector3, kFeet> foot_{};           // FK_i, IMU coordinates
  std::array<Vector3, kFeet> foot_velocity_{};  // its rate from the joints, IMU coordinates

  bool initialized_ = false;
  Matrix3 rotation_ = Matrix3::Identity();
  Vector3 velocity_ = Vector3::Zero();
  Vector3 position_ = Vector3::Zero();
  std::array<Vector3, kFeet> stance_point_{};
  Vector3 gyroscope_bias_ = Vector3::Zero();
  Vector3 accelerometer_bias_ = Vector3::Zero();
  Vector3 last_rate_ = Vector3::Zero();            // bias-corrected, for the estimate
  Vector3 last_specific_force_ = Vector3::Zero();  // bias-corrected, for contact
  std::array<bool, kFeet> stance_{};
  std::array<bool, kFeet> slipping_{};
  std::array<int, kFeet> fast_samples_{};  // in a row above slip_speed
  std::array<bool, kFeet> gated_{};
  std::array<std::uint8_t, kFeet> support_{};
  std::array<bool, kFeet> on_ground_{};  // inferred from the legs
  Covariance covariance_ = Covariance::Identity();

  ImuScreen screen_;
  int degraded_samples_ = 0;  // left until trusted again
  bool lost_ = true;          // until started; after a gap or a non-finite update
  RejectedInputs rejected_;
  Snapshot snapshot_{};  // a member: no 4 kB on the stack each sample
};

}  // namespace hmpc::estimation
