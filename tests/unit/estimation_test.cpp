// The contact-aided invariant EKF (hmpc/estimation/invariant_ekf.hpp) on recorded truth: the
// humanoid under Coarse-Fast MPC on the 1 ms simulator, read by the simulated sensors (a BMI088
// IMU with its noise and power-up biases, 16-bit encoders, the boards' filtered velocities),
// after a rest in its starting stance; the errors are against the simulator's truth. Which feet
// stand comes from the simulator's contact forces, a stand-in for a contact detector.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "hmpc/estimation/biped_state_estimator.hpp"
#include "hmpc/estimation/invariant_ekf.hpp"
#include "hmpc/estimation/whole_body_ukf.hpp"
#include "hmpc/humanoid/closed_loop.hpp"
#include "hmpc/humanoid/physical_checks.hpp"
#include "hmpc/humanoid/sensors.hpp"
#include "hmpc/humanoid/step.hpp"
#include "hmpc/platform/linux/heap_monitor.hpp"
#include "humanoid_test_motions.hpp"

namespace {

namespace est = hmpc::estimation;
namespace sensors = hmpc::sensors;
using namespace hmpc::humanoid;

constexpr double kDt = 1e-3;
constexpr double kRestSeconds = 0.5;

// What the robot did and what its sensors read, every millisecond: sample k is the motion
// over the simulator's step k (IMU) and the joints at its end (encoders, boards' velocities).
struct Recording {
  std::vector<State> truth;  // at the end of each step
  std::vector<sensors::ImuReading> imu;
  std::vector<JointVector> angles, rates;
  std::vector<JointVector> torque;  // applied over each step (the rest's: zero, unused)
  std::vector<Vector3> gyroscope_bias, accelerometer_bias;  // the sensor's, at each step
  // Feet carrying at least kStanceForce, from the simulator's contact forces: a stand-in for
  // the contact detector the estimator's caller needs (no force sensors on the robot).
  std::vector<std::array<bool, est::kFeet>> stance;
};

// 5 % of the robot's weight (46 kg): above a swing foot's grazing contacts.
constexpr double kStanceForce = 23.0;

// `motion` in closed loop with Coarse-Fast MPC on the 1 ms simulator, untruncated (the same
// numbers on any machine), read by the sensors with `seed`.
Recording record(const std::string& motion, double seconds, std::uint64_t seed) {
  ClosedLoopConfig config;
  config.mpc = MpcKind::kCoarseFast;
  config.duration = seconds;
  config.truncate = false;
  config.record_milliseconds = true;
  const ClosedLoopRun run = run_closed_loop(test::motion(motion), config);
  EXPECT_FALSE(run.fell()) << motion;
  const Model model;
  SensorConfig sensor_config;
  sensor_config.seed = seed;
  BipedSensors readings(model, sensor_config);
  readings.start_at_rest(run.initial.q);
  Recording r;
  // The robot held still in its starting stance for `kRestSeconds` before the MPC takes over,
  // as a real one is held by its joint controllers while the estimator starts.
  std::vector<SimulatorStep> steps(static_cast<std::size_t>(std::lround(kRestSeconds / kDt)));
  for (std::size_t k = 0; k < steps.size(); ++k) {
    steps[k].time = (k + 1.0) * kDt - kRestSeconds;
    steps[k].state = run.initial;
    steps[k].acceleration.setZero();
    steps[k].torque.setZero();
  }
  steps.insert(steps.end(), run.milliseconds.begin(), run.milliseconds.end());
  const ProblemConfig problem{};
  StepMap contact(model, problem.parameters, problem.contact, kDt);
  for (const SimulatorStep& step : steps) {
    const auto& forces = contact.evaluate_contact(step.state);
    std::array<double, est::kFeet> load{};
    for (int i = 0; i < kSolePoints; ++i) load[i / kFootPoints] += forces.force[i].z();
    r.stance.push_back({load[0] > kStanceForce, load[1] > kStanceForce});
    const SensorReadings reading = readings.measure(step.state.q, step.state.v, step.acceleration);
    r.imu.push_back(reading.imu);
    r.gyroscope_bias.push_back(readings.imu().gyroscope_bias());
    r.accelerometer_bias.push_back(readings.imu().accelerometer_bias());
    r.angles.push_back(reading.angles);
    r.rates.push_back(reading.rates);
    r.truth.push_back(step.state);
    r.torque.push_back(step.torque);
  }
  return r;
}

struct Errors {
  double height_rms = 0, horizontal_velocity_rms = 0, tilt_rms = 0;  // m, m/s, rad
  double yaw_drift = 0, horizontal_drift = 0;                        // at the end
  Vector3 gyroscope_bias_error = Vector3::Zero(), accelerometer_bias_error = Vector3::Zero();
  double accelerometer_bias_sigma_vertical = 0;
  double contact_agreement = 0;  // of the feet the filter used with the simulator's contacts
  Vector3 final_sigma = Vector3::Zero();  // of the gyroscope bias (invariant EKF)
};

// Which feet stand: the recording's (the simulator's forces) or the filter's own, from the legs.
enum class Contact { kFromForces, kFromLegs };

// The errors of an estimate against the recording's truth, sample by sample.
class ErrorSum {
 public:
  explicit ErrorSum(const Recording& r) : r_(r) {}

  void add(std::size_t k, const est::BaseEstimate& e) {
    last_ = e;
    for (int foot = 0; foot < est::kFeet; ++foot) {
      agree_ += e.stance[foot] == r_.stance[k][foot] ? 1 : 0;
      ++feet_;
    }
    // The targets hold while in contact: a flight phase has no measurement but the IMU.
    if (!r_.stance[k][0] && !r_.stance[k][1]) return;
    const State& x = r_.truth[k];
    const Eigen::Quaterniond q(x.q[3], x.q[4], x.q[5], x.q[6]);
    const Vector3 velocity = q * x.v.segment<3>(3);
    height2_ += std::pow(e.position.z() - x.q[2], 2);
    velocity2_ += (e.velocity - velocity).head<2>().squaredNorm();
    const Vector3 up = q * Vector3::UnitZ(), up_estimated = e.orientation * Vector3::UnitZ();
    tilt2_ += std::pow(std::acos(std::clamp(up.dot(up_estimated), -1.0, 1.0)), 2);
    ++n_;
  }

  Errors errors() const {
    Errors out;
    out.height_rms = std::sqrt(height2_ / n_);
    out.horizontal_velocity_rms = std::sqrt(velocity2_ / n_);
    out.tilt_rms = std::sqrt(tilt2_ / n_);
    out.contact_agreement = static_cast<double>(agree_) / feet_;
    const State& x = r_.truth.back();
    const Eigen::Quaterniond q(x.q[3], x.q[4], x.q[5], x.q[6]);
    const Vector3 forward = q * Vector3::UnitX(),
                  forward_estimated = last_.orientation * Vector3::UnitX();
    out.yaw_drift = std::atan2(forward_estimated.y(), forward_estimated.x()) -
                    std::atan2(forward.y(), forward.x());
    out.horizontal_drift = (last_.position - x.q.head<3>()).head<2>().norm();
    out.gyroscope_bias_error = last_.gyroscope_bias - r_.gyroscope_bias.back();
    out.accelerometer_bias_error = last_.accelerometer_bias - r_.accelerometer_bias.back();
    return out;
  }

 private:
  const Recording& r_;
  est::BaseEstimate last_;
  double height2_ = 0, velocity2_ = 0, tilt2_ = 0;
  int n_ = 0, agree_ = 0, feet_ = 0;
};

// Runs the filter: a rest of `rest_seconds` to start, then every sample.
Errors run_filter(const Recording& r, double rest_seconds, Contact contact = Contact::kFromForces,
                  const est::InvariantEkfConfig& config = {}) {
  est::InvariantEkf filter({}, config);
  est::ImuRest rest;
  const int rest_samples = static_cast<int>(std::lround(rest_seconds / kDt));
  ErrorSum sum(r);
  for (std::size_t k = 0; k < r.imu.size(); ++k) {
    if (static_cast<int>(k) < rest_samples) {
      rest.add(r.imu[k], kDt);
      if (static_cast<int>(k) + 1 == rest_samples) filter.initialize_at_rest(rest, r.angles[k]);
      continue;
    }
    filter.propagate(r.imu[k], kDt);
    if (contact == Contact::kFromForces) {
      filter.correct(r.angles[k], r.rates[k], r.stance[k]);
    } else {
      filter.correct(r.angles[k], r.rates[k]);
    }
    sum.add(k, filter.estimate());
  }
  Errors out = sum.errors();
  out.final_sigma = filter.covariance().diagonal().cwiseSqrt().segment<3>(15);
  return out;
}

// The thesis's design (whole_body_ukf.hpp) on the same recording, with the torques applied
// (plus white noise of `torque_noise` [N m] per joint and sample, seeded) and a model of the
// robot with `parameters`; microseconds per sample into `us_per_sample` if given.
Errors run_ukf(const Recording& r, double rest_seconds, const Parameters& parameters = {},
               const est::WholeBodyUkfConfig& config = {}, double torque_noise = 0.0,
               double* us_per_sample = nullptr) {
  est::WholeBodyUkf filter(parameters, config);
  est::ImuRest rest;
  const int rest_samples = static_cast<int>(std::lround(rest_seconds / kDt));
  std::mt19937_64 random(5);
  std::normal_distribution<double> normal(0.0, 1.0);
  ErrorSum sum(r);
  double seconds = 0;
  for (std::size_t k = 0; k < r.imu.size(); ++k) {
    if (static_cast<int>(k) < rest_samples) {
      rest.add(r.imu[k], kDt);
      if (static_cast<int>(k) + 1 == rest_samples) filter.initialize_at_rest(rest, r.angles[k]);
      continue;
    }
    JointVector tau = r.torque[k];
    for (int j = 0; j < kJoints; ++j) tau[j] += torque_noise * normal(random);
    const auto start = std::chrono::steady_clock::now();
    filter.update(tau, {r.imu[k], r.angles[k], r.rates[k]}, kDt);
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    est::BaseEstimate e = filter.estimate();
    EXPECT_NE(e.trust, est::Trust::kLost) << k;
    e.stance = r.stance[k];  // it detects no contact: nothing to compare
    sum.add(k, e);
  }
  if (us_per_sample)
    *us_per_sample = 1e6 * seconds / static_cast<double>(r.imu.size() - rest_samples);
  return sum.errors();
}

void print(const char* what, const Errors& e) {
  std::printf(
      "%s: height %.2f mm, horizontal velocity %.4f m/s, tilt %.3f deg RMS; yaw drift %.3f deg, "
      "horizontal drift %.1f mm; gyro bias error %.4f deg/s (sigma %.4f), accel bias error "
      "%.4f m/s^2; contact as the simulator's %.1f %%\n",
      what, 1e3 * e.height_rms, e.horizontal_velocity_rms, e.tilt_rms * 180 / M_PI,
      e.yaw_drift * 180 / M_PI, 1e3 * e.horizontal_drift,
      e.gyroscope_bias_error.norm() * 180 / M_PI, e.final_sigma.norm() * 180 / M_PI,
      e.accelerometer_bias_error.norm(), 100 * e.contact_agreement);
}

// The targets the MPC needs (our choice): height within 1 cm, horizontal velocity within
// 0.05 m/s, tilt within 1 degree, RMS while in contact (run_filter's RMS).
void expect_within_targets(const Errors& e) {
  EXPECT_LT(e.height_rms, 0.01);
  EXPECT_LT(e.horizontal_velocity_rms, 0.05);
  EXPECT_LT(e.tilt_rms, 1.0 * M_PI / 180);
}

TEST(InvariantEkf, StandingStillMeetsTheTargetsAndFindsTheGyroscopeBias) {
  const Recording r = record("I-standing", 8.0, 21);
  const Errors e = run_filter(r, kRestSeconds);
  print("standing", e);
  expect_within_targets(e);
  // The power-up gyroscope bias (1 deg/s per axis) is found by the rest and kept: within
  // three of the filter's own standard deviations per axis.
  for (int i = 0; i < 3; ++i) {
    EXPECT_LT(std::abs(e.gyroscope_bias_error[i]), 3 * e.final_sigma[i]) << i;
  }
}

const char* name_of(Contact contact) {
  return contact == Contact::kFromForces ? "contact from the forces" : "contact from the legs";
}

// The thesis's slow squat (Sec. 2.7.3): 4 cm at 0.25 Hz, both soles on the compliant ground,
// rocking onto their heels at the bottom; which feet stand from the simulator's forces or, as
// a robot without force sensors knows it, from the legs (InvariantEkfConfig's
// touchdown_height).
TEST(InvariantEkf, SlowSquattingMeetsTheTargets) {
  const Recording r = record("slow-squat", 10.0, 24);
  for (const Contact contact : {Contact::kFromForces, Contact::kFromLegs}) {
    SCOPED_TRACE(name_of(contact));
    const Errors e = run_filter(r, kRestSeconds, contact);
    print((std::string("slow squat, ") + name_of(contact)).c_str(), e);
    expect_within_targets(e);
  }
}

// A robot standing still in the MPC's standing posture, its filter started after a 0.1 s rest;
// its IMU has noise and biases, so readings change every sample as a live one's do.
struct StandingStill {
  State x = standing_state(ProblemConfig{}, 0.80);
  sensors::ImuModel imu{sensors::bmi088(kDt), 5};
  est::InvariantEkf filter;

  explicit StandingStill(const est::InvariantEkfConfig& config = {}) : filter({}, config) {
    est::ImuRest rest;
    for (int k = 0; k < 100; ++k) rest.add(read(), kDt);
    filter.initialize_at_rest(rest, angles());
  }
  sensors::ImuReading read() { return imu.measure({Vector3::Zero(), Vector3(0, 0, 9.81)}); }
  JointVector angles() const { return x.q.tail<kJoints>(); }
  // `n` samples standing, which feet stand inferred from the legs.
  void stand_on_legs(int n) {
    for (int k = 0; k < n; ++k) {
      filter.propagate(read(), kDt);
      filter.correct(angles(), JointVector::Zero());
    }
  }
  // `n` samples of the legs standing.
  void stand(int n) {
    for (int k = 0; k < n; ++k) {
      filter.propagate(read(), kDt);
      filter.correct(angles(), JointVector::Zero(), {true, true});
    }
  }
};

// The tilt of an estimate of an upright robot.
double tilt(const est::InvariantEkf& filter) {
  return std::acos(std::clamp((filter.estimate().orientation * Vector3::UnitZ()).z(), -1.0, 1.0));
}

// The soles standing level at rest tell roll and pitch, which the accelerometer's horizontal
// power-up offset hides. Fused with gravity's direction (1.15 degrees per axis against the
// soles' 0.5), the start's tilt error is about 0.5^2 / (0.5^2 + 1.15^2) = 16 % of the offset's
// (the simulated legs' kinematics are exact), and the offset is found to within as much. Soles
// tilted 6 degrees against gravity (a slope, a foot on a step) fail the gate: the attitude is
// gravity's alone, as without the soles.
TEST(InvariantEkf, LevelSolesAtRestRevealTheAccelerometersOffset) {
  StandingStill robot;
  const Vector3 offset = robot.imu.accelerometer_bias();
  const double hidden = std::atan(offset.head<2>().norm() / 9.81);
  ASSERT_GT(hidden, 0.2 * M_PI / 180);  // an offset to find
  EXPECT_LT(tilt(robot.filter), 0.25 * hidden);
  const Vector3 found = robot.filter.estimate().accelerometer_bias;
  EXPECT_LT((found - offset).head<2>().norm(), 0.25 * offset.head<2>().norm());

  est::InvariantEkfConfig blind;
  blind.level_sole_noise = 1.0;  // rad: the soles tell nothing
  const StandingStill unaided(blind);
  EXPECT_GT(tilt(unaided.filter), 0.9 * hidden);

  JointVector sloped = robot.angles();
  sloped[kAnkle] += 0.1;
  sloped[kJointsPerLeg + kAnkle] += 0.1;
  est::ImuRest rest;
  for (int k = 0; k < 100; ++k) rest.add(robot.read(), kDt);
  est::InvariantEkf filter;
  filter.initialize_at_rest(rest, sloped);
  EXPECT_GT(tilt(filter), 0.9 * hidden);
}

// A rest that is not still: held by its joints' controllers a robot sags, and here its hips
// turn the torso forward at 4 mrad/s on feet that stay flat and fixed (what the hydraulic legs
// did under the boards' hold). The gyroscope's mean over the rest is then its bias plus that
// rate; the legs' angles at the rest's start and end tell the rate, so the filter started
// with them finds the bias to within the rest's noise, and without them is off by the rate.
TEST(InvariantEkf, ARestThatTurnsTheTorsoStillGivesTheGyroscopeBias) {
  constexpr double kRate = 0.004;  // rad/s of hip flexion, both legs
  constexpr int kSamples = 500;
  const State start = standing_state(ProblemConfig{}, 0.80);
  const Model model{Parameters{}};
  Dynamics dynamics(model);
  Dynamics::Kinematics kinematics;
  const int sole = Model::body_of(0, kAnkle);
  // The torso's attitude on the fixed left sole: R = R_fit(0) R_fit(t)^T (R_fit: the sole in
  // torso coordinates), upright at the start.
  auto angles_at = [&](int k) {
    JointVector a = start.q.tail<kJoints>();
    a[kHipFlexion] += kRate * kDt * k;
    a[kJointsPerLeg + kHipFlexion] += kRate * kDt * k;
    return a;
  };
  auto sole_in_torso = [&](const JointVector& a) {
    Configuration q;
    q << 0, 0, 0, 1, 0, 0, 0, a;
    dynamics.kinematics(q, Velocity::Zero(), kinematics);
    return Matrix3(kinematics.rotation[sole]);
  };
  const Matrix3 at_start = sole_in_torso(angles_at(0));
  sensors::ImuModel imu{sensors::bmi088(kDt), 5};
  est::ImuRest rest;
  Matrix3 torso = Matrix3::Identity();
  for (int k = 0; k < kSamples; ++k) {
    const Matrix3 next = at_start * sole_in_torso(angles_at(k + 1)).transpose();
    const Eigen::AngleAxisd turned(torso.transpose() * next);
    rest.add(imu.measure(
                 {turned.angle() * turned.axis() / kDt, torso.transpose() * Vector3(0, 0, 9.81)}),
             kDt);
    torso = next;
  }
  const Vector3 bias = imu.gyroscope_bias();
  est::InvariantEkf filter;
  filter.initialize_at_rest(rest, angles_at(0), angles_at(kSamples - 1), kDt * (kSamples - 1));
  // The gyroscope bias's y in the error (phi, v, p, d_L, d_R, b_g, b_a): index 16.
  const double sigma = std::sqrt(filter.covariance()(16, 16));
  EXPECT_LT(std::abs(filter.estimate().gyroscope_bias.y() - bias.y()), 3 * sigma);
  EXPECT_LT(3 * sigma, 0.5 * kRate);  // the test tells the two apart
  est::InvariantEkf unaided;
  unaided.initialize_at_rest(rest, angles_at(kSamples - 1));
  EXPECT_GT(std::abs(unaided.estimate().gyroscope_bias.y() - bias.y()), 0.5 * kRate);
}

bool finite(const est::BaseEstimate& e) {
  return e.position.allFinite() && e.orientation.coeffs().allFinite() && e.velocity.allFinite() &&
         e.angular_velocity.allFinite() && e.gyroscope_bias.allFinite() &&
         e.accelerometer_bias.allFinite();
}

// A robot standing still whose left leg's kinematics jump by 5 cm in one sample (a foot
// kicked away, a bad encoder frame): that foot's innovation is gated out and the estimate does
// not move; once the jump lasts, the foot is re-anchored where the legs now put it.
TEST(InvariantEkf, AJumpInOneLegsKinematicsIsGatedOut) {
  StandingStill robot;
  est::InvariantEkf& filter = robot.filter;
  robot.stand(500);
  const est::BaseEstimate before = filter.estimate();
  JointVector kicked = robot.angles();
  kicked[kHipFlexion] += 0.06;  // about 5 cm at the sole
  filter.propagate(robot.read(), kDt);
  filter.correct(kicked, JointVector::Zero(), {true, true});
  const est::BaseEstimate after = filter.estimate();
  EXPECT_TRUE(after.gated[0]);
  EXPECT_FALSE(after.gated[1]);
  EXPECT_LT((after.position - before.position).norm(), 1e-3);
  EXPECT_LT(after.orientation.angularDistance(before.orientation), 1e-3);
  // The left foot was not used, so it was re-anchored: the next sample with the same legs is
  // consistent again.
  filter.propagate(robot.read(), kDt);
  filter.correct(kicked, JointVector::Zero(), {true, true});
  EXPECT_FALSE(filter.estimate().gated[0]);
  EXPECT_LT((filter.estimate().position - before.position).norm(), 1e-3);
}

// Each bad IMU reading is counted by its reason and replaced by the last good one with its
// uncertainty added; the estimate is degraded for recovery_samples and then tracking again.
TEST(InvariantEkf, BadImuReadingsAreCountedReplacedAndReported) {
  StandingStill robot;
  est::InvariantEkf& filter = robot.filter;
  const est::InvariantEkfConfig config;
  robot.stand(200);
  EXPECT_EQ(filter.trust(), est::Trust::kTracking);
  const double attitude_variance = filter.covariance()(0, 0);

  sensors::ImuReading nan = robot.read();
  nan.angular_velocity.y() = std::nan("");
  filter.propagate(nan, kDt);
  EXPECT_EQ(filter.rejected().imu_not_finite, 1);
  EXPECT_EQ(filter.trust(), est::Trust::kDegraded);
  EXPECT_TRUE(finite(filter.estimate()));
  // The stand-in's uncertainty: (unknown_rate dt)^2 on each attitude axis, at least.
  EXPECT_GT(filter.covariance()(0, 0),
            attitude_variance + 0.9 * std::pow(config.unknown_rate * kDt, 2));

  sensors::ImuReading saturated = robot.read();
  saturated.saturated = true;
  filter.propagate(saturated, kDt);
  sensors::ImuReading beyond = robot.read();
  beyond.specific_force.x() = 2 * config.imu.accelerometer.range;
  filter.propagate(beyond, kDt);
  EXPECT_EQ(filter.rejected().imu_out_of_range, 2);

  robot.stand(config.recovery_samples - 1);
  EXPECT_EQ(filter.trust(), est::Trust::kDegraded);
  robot.stand(1);
  EXPECT_EQ(filter.trust(), est::Trust::kTracking);

  // A stuck sensor: the same reading 60 times; the first stuck_samples - 1 repeats pass.
  const sensors::ImuReading stuck = robot.read();
  for (int k = 0; k < 60; ++k) {
    filter.propagate(stuck, kDt);
    filter.correct(robot.angles(), JointVector::Zero(), {true, true});
  }
  EXPECT_EQ(filter.rejected().imu_stuck, 60 - (config.stuck_samples - 1));
  EXPECT_EQ(filter.trust(), est::Trust::kDegraded);
  EXPECT_EQ(filter.rejected().imu_not_finite, 1);
}

// Without an IMU and without a foot on the ground nothing bounds the velocity: once its
// standard deviation passes trusted_velocity_sigma the estimate is lost, and finite.
TEST(InvariantEkf, WithoutImuOrFeetTheEstimateIsLostNotNonFinite) {
  StandingStill robot;
  est::InvariantEkf& filter = robot.filter;
  robot.stand(100);
  sensors::ImuReading dead;
  dead.angular_velocity.setConstant(std::numeric_limits<double>::infinity());
  for (int k = 0; k < 2000; ++k) {
    filter.propagate(dead, kDt);
    filter.correct(robot.angles(), JointVector::Zero(), {false, false});
  }
  EXPECT_EQ(filter.trust(), est::Trust::kLost);
  EXPECT_TRUE(finite(filter.estimate()));
}

// Bad intervals and joint samples: a non-positive or non-finite interval and a non-finite
// joint sample are skipped and counted, the estimate unchanged; a gap beyond max_interval
// loses the estimate until the filter is started again.
TEST(InvariantEkf, BadIntervalsAndJointSamplesAreSkippedAndAGapLosesTheEstimate) {
  StandingStill robot;
  est::InvariantEkf& filter = robot.filter;
  robot.stand(200);
  const est::BaseEstimate before = filter.estimate();
  filter.propagate(robot.read(), 0.0);
  filter.propagate(robot.read(), -kDt);
  filter.propagate(robot.read(), std::nan(""));
  JointVector broken = robot.angles();
  broken[3] = std::numeric_limits<double>::infinity();
  filter.correct(broken, JointVector::Zero(), {true, true});
  EXPECT_EQ(filter.rejected().bad_interval, 3);
  EXPECT_EQ(filter.rejected().joints_not_finite, 1);
  EXPECT_EQ(filter.estimate().position, before.position);
  EXPECT_EQ(filter.estimate().velocity, before.velocity);
  EXPECT_EQ(filter.trust(), est::Trust::kDegraded);

  filter.propagate(robot.read(), 0.2);  // 200 samples dropped
  EXPECT_EQ(filter.rejected().bad_interval, 4);
  robot.stand(500);
  EXPECT_EQ(filter.trust(), est::Trust::kLost);
  est::ImuRest rest;
  for (int k = 0; k < 100; ++k) rest.add(robot.read(), kDt);
  filter.initialize_at_rest(rest, robot.angles());
  EXPECT_EQ(filter.trust(), est::Trust::kTracking);
}

// Garbage of every kind, seeded: huge, infinite and NaN readings, intervals and joint angles,
// random stance flags. The estimate stays finite throughout.
TEST(InvariantEkf, GarbageInputNeverMakesTheEstimateNonFinite) {
  StandingStill robot;
  est::InvariantEkf& filter = robot.filter;
  std::mt19937_64 random(7);
  const std::array<double, 7> values = {
      0.0, 1.0, -3.0, 1e3, 1e300, std::nan(""), std::numeric_limits<double>::infinity()};
  auto pick = [&] { return values[random() % values.size()] * (random() % 2 ? 1 : -1); };
  for (int k = 0; k < 20000; ++k) {
    sensors::ImuReading r = robot.read();
    if (random() % 4 == 0) {
      for (int i = 0; i < 3; ++i) r.angular_velocity[i] = pick();
      for (int i = 0; i < 3; ++i) r.specific_force[i] = pick();
    }
    const double dt = random() % 8 == 0 ? pick() * 1e-3 : kDt;
    filter.propagate(r, dt);
    JointVector angles = robot.angles();
    if (random() % 4 == 0) angles[random() % kJoints] = pick();
    if (random() % 2 == 0) {
      filter.correct(angles, JointVector::Zero(), {random() % 2 == 0, random() % 2 == 0});
    } else {
      filter.correct(angles, JointVector::Zero());  // contact from the legs
    }
    ASSERT_TRUE(finite(filter.estimate())) << k;
    ASSERT_TRUE(filter.covariance().allFinite()) << k;
  }
}

// Walking and a jump land on heels and roll onto toes; the jump has a flight phase. Contact
// from the forces or from the legs (and the IMU: flight_force). Height, velocity and tilt
// within the targets. The accelerometer's horizontal power-up offset b, which alone reads at
// rest as a tilt of atan(|b_xy| / g) (BMI088: 20 mg, 1.15 degrees per axis) and which a
// straight walk reveals only slowly (its yaw never turns the offset against gravity), is found
// at rest from the level soles (InvariantEkfConfig::level_sole_noise), to 16 % of it. Walking's
// tilt, measured over seeds 21, 22, 23 and 25 (hidden tilts 1.0-2.6 degrees): 0.38-0.46
// degrees RMS with contact from the forces, 0.73-0.86 from the legs; seed 26's offset (3.6
// degrees, beyond twice the spread) leaves 1.06 from the legs.
TEST(InvariantEkf, WalkingAndALowJumpMeetTheTargets) {
  for (const char* motion : {"II-walking", "V-low-jump"}) {
    const Recording r = record(motion, 6.0, 22);
    const double hidden = std::atan(r.accelerometer_bias.front().head<2>().norm() / 9.81);
    std::printf("%s: the offset's hidden tilt %.3f deg\n", motion, hidden * 180 / M_PI);
    for (const Contact contact : {Contact::kFromForces, Contact::kFromLegs}) {
      SCOPED_TRACE(std::string(motion) + ", " + name_of(contact));
      const Errors e = run_filter(r, kRestSeconds, contact);
      print((std::string(motion) + ", " + name_of(contact)).c_str(), e);
      EXPECT_LT(e.height_rms, 0.01);
      EXPECT_LT(e.horizontal_velocity_rms, 0.05);
      EXPECT_LT(e.tilt_rms, 1.0 * M_PI / 180);
    }
  }
}

// A robot standing still lifts its left foot (hip and knee flexed a further 0.4 and 0.8 rad,
// the ankle keeping the sole level: over 5 cm up from its bent-knee stance) and puts it back: from
// the legs alone the foot is off the ground while up and standing again once down; the right foot
// stands throughout.
TEST(InvariantEkf, ContactFromTheLegsSeesAFootLiftedAndSetDown) {
  StandingStill robot;
  est::InvariantEkf& filter = robot.filter;
  robot.stand_on_legs(200);
  EXPECT_TRUE(filter.estimate().stance[0]);
  JointVector lifted = robot.angles();
  lifted[kHipFlexion] += 0.4;
  lifted[kKnee] += 0.8;
  lifted[kAnkle] += 0.4;
  filter.propagate(robot.read(), kDt);
  filter.correct(lifted, JointVector::Zero());
  const est::BaseEstimate up = filter.estimate();
  EXPECT_FALSE(up.stance[0]);
  EXPECT_TRUE(up.stance[1]);
  EXPECT_GT(up.stance_points[0].z() - up.stance_points[1].z(), 0.05);
  filter.propagate(robot.read(), kDt);
  filter.correct(robot.angles(), JointVector::Zero());
  EXPECT_TRUE(filter.estimate().stance[0]);
  EXPECT_TRUE(filter.estimate().stance[1]);
}

// The IMU overrules the legs (InvariantEkfConfig::flight_force). Reading a free fall's specific
// force, no foot stands though the legs put both soles on the ground. Landing with both feet
// above liftoff_height in the estimate (a flight's end, a push-off on the toes), the lower one
// stands while within support_reach: the right foot drawn up about 2 cm stands (and would not
// without the rule), drawn up 6 cm it does not; the left, 17 cm up, never.
TEST(InvariantEkf, TheImuTellsAFlightFromAStance) {
  const sensors::ImuTruth free_fall{Vector3::Zero(), Vector3::Zero()};
  {
    StandingStill robot;
    robot.stand_on_legs(200);
    robot.filter.propagate(robot.imu.measure(free_fall), kDt);
    robot.filter.correct(robot.angles(), JointVector::Zero());
    EXPECT_FALSE(robot.filter.estimate().stance[0]);
    EXPECT_FALSE(robot.filter.estimate().stance[1]);
    robot.filter.propagate(robot.read(), kDt);
    robot.filter.correct(robot.angles(), JointVector::Zero());
    EXPECT_TRUE(robot.filter.estimate().stance[0]);
    EXPECT_TRUE(robot.filter.estimate().stance[1]);
  }
  // Stands still, takes off with its legs drawn up, lands with them so: which feet stand, and
  // the right stance point's height above where it stood.
  const auto land = [&](double right_flexion, double reach, double* rise) {
    est::InvariantEkfConfig config;
    config.support_reach = reach;
    StandingStill robot(config);
    robot.stand_on_legs(200);
    const double stood = robot.filter.estimate().stance_points[1].z();
    JointVector drawn = robot.angles();
    drawn[kHipFlexion] += 0.4;
    drawn[kKnee] += 0.8;
    drawn[kAnkle] += 0.4;
    drawn[kJointsPerLeg + kHipFlexion] += right_flexion;
    drawn[kJointsPerLeg + kKnee] += 2 * right_flexion;
    drawn[kJointsPerLeg + kAnkle] += right_flexion;
    robot.filter.propagate(robot.imu.measure(free_fall), kDt);
    robot.filter.correct(drawn, JointVector::Zero());
    robot.filter.propagate(robot.read(), kDt);
    robot.filter.correct(drawn, JointVector::Zero());
    *rise = robot.filter.estimate().stance_points[1].z() - stood;
    return robot.filter.estimate().stance;
  };
  double rise = 0;
  const est::InvariantEkfConfig defaults;
  const std::array<bool, est::kFeet> near = land(0.07, defaults.support_reach, &rise);
  EXPECT_GT(rise, defaults.liftoff_height);
  EXPECT_LT(rise, defaults.support_reach);
  EXPECT_FALSE(near[0]);
  EXPECT_TRUE(near[1]);
  EXPECT_FALSE(land(0.07, 0.0, &rise)[1]);
  const std::array<bool, est::kFeet> far = land(0.2, defaults.support_reach, &rise);
  EXPECT_GT(rise, defaults.support_reach);
  EXPECT_FALSE(far[0]);
  EXPECT_FALSE(far[1]);
}

TEST(InvariantEkf, AnUpdateAllocatesNothing) {
  namespace heap_monitor = hmpc::platform::heap_monitor;
  const Recording r = record("I-standing", 0.3, 23);
  est::InvariantEkf filter;
  est::ImuRest rest;
  rest.add(r.imu[0], kDt);
  filter.initialize_at_rest(rest, r.angles[0]);
  const auto before = heap_monitor::allocations();
  heap_monitor::arm();
  for (std::size_t k = 1; k < r.imu.size(); ++k) {
    filter.propagate(r.imu[k], kDt);
    if (k % 2 == 0) {
      filter.correct(r.angles[k], r.rates[k], {k % 50 < 40, true});
    } else {
      filter.correct(r.angles[k], r.rates[k]);  // contact from the legs
    }
    static_cast<void>(filter.estimate());
  }
  heap_monitor::disarm();
  EXPECT_EQ(heap_monitor::allocations() - before, 0u);

  // The controller's side of the same: sensor readings in, the MPC's state out.
  BipedSensors sensors(Model{});
  est::BipedStateEstimator estimator;
  sensors.start_at_rest(r.truth[0].q);
  estimator.rest(sensors.measure(r.truth[0].q, Velocity::Zero(), Velocity::Zero()), kDt);
  estimator.start();
  const auto before_loop = heap_monitor::allocations();
  heap_monitor::arm();
  for (std::size_t k = 1; k < r.truth.size(); ++k) {
    estimator.update(sensors.measure(r.truth[k].q, r.truth[k].v, Velocity::Zero()), kDt);
    static_cast<void>(estimator.state());
  }
  heap_monitor::disarm();
  EXPECT_EQ(heap_monitor::allocations() - before_loop, 0u);

  // The whole-body UKF.
  est::WholeBodyUkf ukf;
  ukf.initialize_at_rest(rest, r.angles[0]);
  const auto before_ukf = heap_monitor::allocations();
  heap_monitor::arm();
  for (std::size_t k = 1; k < r.truth.size(); ++k) {
    ukf.update(r.torque[k], {r.imu[k], r.angles[k], r.rates[k]}, kDt);
    static_cast<void>(ukf.estimate());
  }
  heap_monitor::disarm();
  EXPECT_EQ(heap_monitor::allocations() - before_ukf, 0u);
  EXPECT_NE(ukf.trust(), est::Trust::kLost);
}

// Motion I for 6 s on `feedback` with the sensors of `seed`, untruncated: the robot must stay
// up and the estimate never be lost or non-finite.
ClosedLoopRun stand_on(StateFeedback feedback, std::uint64_t seed) {
  ClosedLoopConfig config;
  config.duration = 6.0;
  config.truncate = false;
  config.feedback = feedback;
  config.sensors.seed = seed;
  ClosedLoopRun run = run_closed_loop(test::motion("I-standing"), config);
  EXPECT_FALSE(run.fell()) << seed;
  EXPECT_FALSE(run.estimate_lost()) << seed;
  EXPECT_EQ(run.samples.size(), 200u) << seed;
  for (const ClosedLoopSample& sample : run.samples) {
    EXPECT_TRUE(sample.feedback.q.allFinite() && sample.feedback.v.allFinite()) << seed;
    EXPECT_NE(sample.trust, est::Trust::kLost) << seed;
  }
  return run;
}

// The MPC solving from the estimate (ClosedLoopConfig::feedback), untruncated so that the
// figures repeat on any machine; the truth judges the motion. Standing on five sensor seeds:
// the robot stays up, the estimate is never lost or non-finite, and what the MPC was given is
// the estimate (it differs from the truth). The targets and motion I's check are printed, not
// asserted: on the estimate they are not met on every seed yet (README, state estimation).
TEST(ClosedLoopThroughTheEstimator, StandingOnTheEstimateStaysUpOnEverySeed) {
  const Motion& motion = test::motion("I-standing");
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const ClosedLoopRun run = stand_on(StateFeedback::kInvariantEkf, seed);
    // Fed the truth, these would be zero.
    const FeedbackErrors e = feedback_errors(run);
    EXPECT_GT(e.height_rms, 0.0) << seed;
    EXPECT_GT(e.tilt_rms, 0.0) << seed;
    const PhysicalCheck check = check_motion("I", motion, run);
    std::printf(
        "standing on the estimate, seed %d: height %.2f mm, horizontal velocity %.4f m/s, tilt "
        "%.3f deg RMS; mean iterations %.2f (on the truth: 2); motion I's check %s: %s\n",
        static_cast<int>(seed), 1e3 * e.height_rms, e.horizontal_velocity_rms,
        e.tilt_rms * 180 / M_PI, summarise(run).mean_iterations, check.passed ? "passed" : "FAILED",
        check.verdict.c_str());
  }
}

// The thesis's whole-body UKF in the same loop, on the same seeds: motion I's check passes and
// the estimate the MPC got meets the height and velocity targets on every seed. The tilt target
// (1 degree) is printed, not asserted: seed 2 misses it (1.05 degrees RMS; README, state
// estimation). Its model is the simulator's (whole_body_ukf.hpp).
TEST(ClosedLoopThroughTheEstimator, StandingOnTheWholeBodyUkfPassesOnEverySeed) {
  const Motion& motion = test::motion("I-standing");
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const ClosedLoopRun run = stand_on(StateFeedback::kWholeBodyUkf, seed);
    const FeedbackErrors e = feedback_errors(run);
    EXPECT_GT(e.height_rms, 0.0) << seed;  // fed the truth, it would be zero
    EXPECT_LT(e.height_rms, 0.01) << seed;
    EXPECT_LT(e.horizontal_velocity_rms, 0.05) << seed;
    const PhysicalCheck check = check_motion("I", motion, run);
    EXPECT_TRUE(check.passed) << seed << ": " << check.verdict;
    std::printf(
        "standing on the whole-body UKF, seed %d: height %.2f mm, horizontal velocity %.4f m/s, "
        "tilt %.3f deg RMS; mean iterations %.2f (on the truth: 2)\n",
        static_cast<int>(seed), 1e3 * e.height_rms, e.horizontal_velocity_rms,
        e.tilt_rms * 180 / M_PI, summarise(run).mean_iterations);
  }
}

// Motion V, the low jump, on the whole-body UKF (its file's 2 s, untruncated), seeds 1-3: a
// flight and an upright landing (motion V's check), the estimate never lost and within the
// height and velocity targets. On the invariant EKF the check passes on some seeds only
// (README, state estimation).
TEST(ClosedLoopThroughTheEstimator, TheLowJumpOnTheWholeBodyUkfPassesOnEverySeed) {
  const Motion& motion = test::motion("V-low-jump");
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    ClosedLoopConfig config;
    config.duration = motion.duration;
    config.truncate = false;
    config.feedback = StateFeedback::kWholeBodyUkf;
    config.sensors.seed = seed;
    const ClosedLoopRun run = run_closed_loop(motion, config);
    const FeedbackErrors e = feedback_errors(run);
    const PhysicalCheck check = check_motion("V", motion, run);
    std::printf(
        "low jump on the whole-body UKF, seed %d: height %.2f mm, horizontal velocity %.4f m/s, "
        "tilt %.3f deg RMS; motion V's check: %s\n",
        static_cast<int>(seed), 1e3 * e.height_rms, e.horizontal_velocity_rms,
        e.tilt_rms * 180 / M_PI, check.verdict.c_str());
    EXPECT_TRUE(check.passed) << seed << ": " << check.verdict;
    EXPECT_FALSE(run.estimate_lost()) << seed;
    EXPECT_GT(e.height_rms, 0.0) << seed;  // fed the truth, it would be zero
    EXPECT_LT(e.height_rms, 0.01) << seed;
    EXPECT_LT(e.horizontal_velocity_rms, 0.05) << seed;
  }
}

// A perfect base estimator (StateFeedback::kTrueBase), to tell what the joint sensors alone cost
// the closed loop: at every sampling instant the MPC gets the simulator's base exactly and the
// joints as the encoders count them (the nearest count) with the boards' filtered rates.
TEST(ClosedLoopThroughTheEstimator, TheTrueBaseGivesTheSimulatorsBaseWithTheSensorsJoints) {
  StateFeedback named = StateFeedback::kTruth;
  ASSERT_TRUE(parse_state_feedback("true-base", named));
  EXPECT_EQ(named, StateFeedback::kTrueBase);
  ClosedLoopConfig config;
  config.duration = 1.5;
  config.truncate = false;
  config.feedback = StateFeedback::kTrueBase;
  const ClosedLoopRun run = run_closed_loop(test::motion("II-walking"), config);
  ASSERT_EQ(run.samples.size(), 50u);
  const hmpc::sensors::EncoderConfig encoder = config.sensors.encoder;
  double rate_error = 0.0;
  for (std::size_t k = 1; k < run.samples.size(); ++k) {
    const State& truth = run.samples[k - 1].state;  // at the period's start
    const State& given = run.samples[k].feedback;
    EXPECT_EQ(given.q.head<kConfigurationSize - kJoints>(),
              truth.q.head<kConfigurationSize - kJoints>())
        << k;
    EXPECT_EQ(given.v.head<kBaseDofs>(), truth.v.head<kBaseDofs>()) << k;
    for (int j = 0; j < kJoints; ++j) {
      const int i = kConfigurationSize - kJoints + j;
      EXPECT_EQ(given.q[i], hmpc::sensors::quantise(encoder, truth.q[i])) << k << ", " << j;
      rate_error = std::max(rate_error, std::abs(given.v[kBaseDofs + j] - truth.v[kBaseDofs + j]));
    }
  }
  // Walking's joints accelerate: the boards' 50 Hz filter lags them.
  EXPECT_GT(rate_error, 0.01);
}

// Why the MPC's model may take a wider friction slip velocity than the plant's
// (ProblemConfig::model_slip_velocity): on the true base, the boards' filtered rates differ from
// the plant's (which carry the compliant contact's vibration) by a few tenths of a rad/s, so the
// stance feet of the model slide at centimetres per second where the plant's stick; at the
// plant's 1 cm/s the model's friction is then at its Coulomb limit, the solves do not converge
// (4.4 mean iterations against 2.05 on the truth) and the slow squat unloads a foot. With 3
// cm/s, the force stays proportional to the error and the squat passes its check.
TEST(ClosedLoopThroughTheEstimator, TheSlowSquatOnTheTrueBasePassesWithTheModelsFrictionWidened) {
  const Motion& motion = test::motion("slow-squat");
  ClosedLoopConfig config;
  config.duration = motion.duration;
  config.truncate = false;
  config.feedback = StateFeedback::kTrueBase;
  config.problem.model_slip_velocity = 0.03;
  const ClosedLoopRun run = run_closed_loop(motion, config);
  const PhysicalCheck check = check_squat(motion, run);
  std::printf("slow squat on the true base, model slip velocity 3 cm/s: %s; mean iterations %.2f\n",
              check.verdict.c_str(), summarise(run).mean_iterations);
  EXPECT_TRUE(check.passed) << check.verdict;
}

}  // namespace

namespace {

// The thesis's design against the invariant EKF (contact from the legs) on the same recordings:
// each meets the targets; the figures and the UKF's cost are printed.
TEST(WholeBodyUkf, MeetsTheTargetsBesideTheInvariantEkf) {
  const std::pair<const char*, double> motions[] = {
      {"I-standing", 3.0}, {"slow-squat", 3.0}, {"II-walking", 3.0}, {"V-low-jump", 6.0}};
  for (const auto& [motion, seconds] : motions) {
    const Recording r = record(motion, seconds, 22);
    double us = 0;
    const Errors ukf = run_ukf(r, kRestSeconds, {}, {}, 0.0, &us);
    const Errors iekf = run_filter(r, kRestSeconds, Contact::kFromLegs);
    print((std::string(motion) + ", whole-body UKF").c_str(), ukf);
    print((std::string(motion) + ", invariant EKF").c_str(), iekf);
    std::printf("  whole-body UKF: %.0f us per 1 ms sample on this machine\n", us);
    expect_within_targets(ukf);
  }
}

// The UKF's model is the simulator's own; a robot differs. A model 5 % lighter than the robot
// and joint torques off by 5 N m (white, per sample) still meet the targets on walking. A ground
// half or twice as stiff as the model's does not (printed beside the invariant EKF with the same
// error, whose only use of the ground is the standing sink): the UKF's edge needs a contact
// model identified on the robot (README, state estimation).
TEST(WholeBodyUkf, AWrongMassAndNoisyTorquesStillMeetTheTargets) {
  const Recording r = record("II-walking", 3.0, 22);
  Parameters lighter;
  lighter.body_mass *= 0.95;
  const Errors e = run_ukf(r, kRestSeconds, lighter, {}, 5.0);
  print("walking, model 5 % light, torques +-5 N m", e);
  expect_within_targets(e);
  for (const double stiffness : {0.5, 2.0}) {
    est::WholeBodyUkfConfig config;
    config.contact.stiffness *= stiffness;
    const Errors g = run_ukf(r, kRestSeconds, {}, config);
    std::printf("ground stiffness x%.1f in the model: ", stiffness);
    print("walking, UKF", g);
    est::InvariantEkfConfig iekf;
    iekf.contact.stiffness *= stiffness;
    print("walking, IEKF", run_filter(r, kRestSeconds, Contact::kFromLegs, iekf));
  }
}

// IMU readings not finite, out of range or stuck, and joint readings not finite, are not used:
// counted, the estimate stays finite and degraded, then tracking again; a gap beyond
// max_interval loses it.
TEST(WholeBodyUkf, BadReadingsAreSkippedAndAGapLosesTheEstimate) {
  const Recording r = record("I-standing", 0.4, 23);
  est::WholeBodyUkf filter;
  const est::WholeBodyUkfConfig config;
  est::ImuRest rest;
  rest.add(r.imu[0], kDt);
  filter.initialize_at_rest(rest, r.angles[0]);
  std::size_t k = 1;
  for (; k < 50; ++k) filter.update(r.torque[k], {r.imu[k], r.angles[k], r.rates[k]}, kDt);
  EXPECT_EQ(filter.trust(), est::Trust::kTracking);
  SensorReadings bad{r.imu[k], r.angles[k], r.rates[k]};
  bad.imu.specific_force.x() = std::numeric_limits<double>::quiet_NaN();
  filter.update(r.torque[k], bad, kDt);
  bad = {r.imu[k], r.angles[k], r.rates[k]};
  bad.angles[3] = std::numeric_limits<double>::infinity();
  filter.update(r.torque[k], bad, kDt);
  bad = {r.imu[k], r.angles[k], r.rates[k]};
  bad.imu.angular_velocity.z() = 2 * config.imu.gyroscope.range;
  filter.update(r.torque[k], bad, kDt);
  // A stuck IMU: the same reading from now on is refused once stuck_samples have come.
  for (int n = 0; n < config.stuck_samples; ++n, ++k) {
    filter.update(r.torque[k], {r.imu[50], r.angles[k], r.rates[k]}, kDt);
  }
  EXPECT_EQ(filter.rejected().imu_not_finite, 1);
  EXPECT_EQ(filter.rejected().imu_out_of_range, 1);
  EXPECT_EQ(filter.rejected().imu_stuck, 1);
  EXPECT_EQ(filter.rejected().joints_not_finite, 1);
  EXPECT_EQ(filter.trust(), est::Trust::kDegraded);
  EXPECT_TRUE(filter.state().q.allFinite() && filter.state().v.allFinite());
  for (int n = 0; n < config.recovery_samples; ++n, ++k) {
    filter.update(r.torque[k], {r.imu[k], r.angles[k], r.rates[k]}, kDt);
  }
  EXPECT_EQ(filter.trust(), est::Trust::kTracking);
  EXPECT_LT(std::abs(filter.state().q[2] - r.truth[k - 1].q[2]), 0.01);
  filter.update(r.torque[k], {r.imu[k], r.angles[k], r.rates[k]}, 2 * config.max_interval);
  EXPECT_EQ(filter.rejected().bad_interval, 1);
  EXPECT_EQ(filter.trust(), est::Trust::kLost);
}

}  // namespace
