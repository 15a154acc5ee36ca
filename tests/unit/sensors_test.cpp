// The simulated sensors (hmpc/sensors): an encoder's quantisation, a board's velocity filter,
// the IMU's kinematic truth against finite differences of a moving body, and its error model's
// statistics against the configured densities.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <vector>

#include "hmpc/sensors/imu.hpp"
#include "hmpc/sensors/joint_sensors.hpp"

namespace {

namespace sensors = hmpc::sensors;
using sensors::Matrix3;
using sensors::Vector3;

TEST(Encoder, ReadsTheNearestCountWithinHalfAStep) {
  const sensors::EncoderConfig encoder;
  const double step = sensors::encoder_step(encoder);
  EXPECT_NEAR(step, 2 * M_PI / 65536, 1e-15);
  double worst = 0;
  for (int i = 0; i < 10000; ++i) {
    const double angle = -2.0 + 4.0 * i / 9999.0 + 1e-7 * i;
    const double read = sensors::quantise(encoder, angle);
    worst = std::max(worst, std::abs(read - angle));
    EXPECT_NEAR(std::remainder(read / step, 1.0), 0.0, 1e-9) << "a whole number of counts";
  }
  EXPECT_LE(worst, 0.5 * step + 1e-15);
  EXPECT_GT(worst, 0.45 * step) << "the sweep crosses counts";
}

TEST(JointVelocityFilter, FollowsARampAndLagsASineAsAFirstOrderLowPass) {
  const sensors::EncoderConfig encoder;
  const sensors::VelocityFilterConfig config;  // 1 ms, 50 Hz
  sensors::JointVelocityFilter ramp(config);
  double v = 0;
  for (int k = 0; k <= 2000; ++k) v = ramp.update(sensors::quantise(encoder, 0.3 * k * 1e-3));
  // Quantised steps of 9.6e-5 rad over 1 ms leave at most one count's blip, filtered.
  EXPECT_NEAR(v, 0.3, 0.03);

  // A 5 Hz sine: the first-order low-pass's gain 1/sqrt(1 + (f/fc)^2) = 0.995 and phase
  // atan(f/fc) = 5.7 degrees, plus half a period's delay of the backward difference (0.9
  // degrees).
  sensors::JointVelocityFilter sine(config);
  const double f = 5.0, w = 2 * M_PI * f;
  double peak = 0, peak_time = 0;
  for (int k = 0; k <= 950; ++k) {  // past one true peak (t = 0.8 s), short of the next
    const double t = k * 1e-3;
    const double out = sine.update(std::sin(w * t));
    if (t > 0.8 && out > peak) peak = out, peak_time = t;
  }
  EXPECT_NEAR(peak / w, 1 / std::sqrt(1 + 0.01), 0.01);
  // The true velocity w cos(w t) peaks at t = 0.8 s; the filtered one later by the lag.
  const double lag = std::remainder(peak_time, 1 / f);
  const double expected_lag = (std::atan(f / 50.0) + w * 0.5e-3) / w;
  EXPECT_NEAR(lag, expected_lag, 1.5e-3);
}

// A rigid body moving along a smooth path: rotation exp(theta(t)), origin p(t).
struct Path {
  Matrix3 rotation(double t) const {
    const Vector3 theta(0.4 * std::sin(1.3 * t), 0.7 * std::cos(0.9 * t), 1.1 * t);
    return Eigen::AngleAxisd(theta.norm(), theta.normalized()).toRotationMatrix();
  }
  Vector3 origin(double t) const {
    return {0.5 * t * t, std::sin(2.0 * t), 0.9 + 0.1 * std::cos(3.0 * t)};
  }
};

Vector3 vee(const Matrix3& s) { return {s(2, 1), s(0, 2), s(1, 0)}; }

TEST(ImuTruth, IsTheMovingPointsAccelerationLessGravityInItsFrame) {
  const Path path;
  const Vector3 offset(0.05, -0.02, 0.1);
  const Vector3 gravity(0, 0, -9.81);
  const double h = 1e-3;
  // Body-coordinate velocities by central differences (as forward dynamics would give them),
  // and their derivatives by differences of those.
  auto omega = [&](double t) {
    return Vector3(vee(path.rotation(t).transpose() *
                       (path.rotation(t + h) - path.rotation(t - h)) / (2 * h)));
  };
  auto velocity = [&](double t) {
    return Vector3(path.rotation(t).transpose() * (path.origin(t + h) - path.origin(t - h)) /
                   (2 * h));
  };
  for (double t : {0.3, 1.7, 2.9}) {
    const Matrix3 r = path.rotation(t);
    const Vector3 omega_dot = (omega(t + h) - omega(t - h)) / (2 * h);
    const Vector3 velocity_dot = (velocity(t + h) - velocity(t - h)) / (2 * h);
    const sensors::ImuTruth truth =
        sensors::imu_truth(r, omega(t), omega_dot, velocity(t), velocity_dot, offset, gravity);
    // Independently: the point's world acceleration by the second difference of its position.
    auto point = [&](double s) { return Vector3(path.origin(s) + path.rotation(s) * offset); };
    const Vector3 acceleration = (point(t + h) - 2 * point(t) + point(t - h)) / (h * h);
    const Vector3 expected = r.transpose() * (acceleration - gravity);
    EXPECT_LT((truth.specific_force - expected).norm(), 1e-4 * expected.norm()) << t;
    EXPECT_LT((truth.angular_velocity - omega(t)).norm(), 1e-12);
  }
  // At rest, upright: the accelerometer reads +g up.
  const sensors::ImuTruth rest =
      sensors::imu_truth(Matrix3::Identity(), Vector3::Zero(), Vector3::Zero(), Vector3::Zero(),
                         Vector3::Zero(), offset, gravity);
  EXPECT_TRUE(rest.specific_force.isApprox(Vector3(0, 0, 9.81)));
}

TEST(ImuModel, WhiteNoiseHasTheDensitysVarianceAndThePowerUpBiasIsHeld) {
  sensors::ImuConfig c = sensors::bmi088();
  c.gyroscope.bias_random_walk = c.accelerometer.bias_random_walk = 0;  // noise alone
  c.gyroscope.resolution = c.accelerometer.resolution = 0;
  sensors::ImuModel imu(c, 7);
  sensors::ImuTruth truth;
  truth.angular_velocity = Vector3(0.1, -0.2, 0.3);
  truth.specific_force = Vector3(0, 0, 9.81);
  constexpr int kSamples = 200000;
  Vector3 sum_g = Vector3::Zero(), sum_gg = Vector3::Zero();
  Vector3 sum_a = Vector3::Zero(), sum_aa = Vector3::Zero();
  for (int k = 0; k < kSamples; ++k) {
    const sensors::ImuReading r = imu.measure(truth);
    const Vector3 g = r.angular_velocity - truth.angular_velocity - imu.gyroscope_bias();
    const Vector3 a = r.specific_force - truth.specific_force - imu.accelerometer_bias();
    sum_g += g, sum_gg += g.cwiseProduct(g), sum_a += a, sum_aa += a.cwiseProduct(a);
    ASSERT_FALSE(r.saturated);
  }
  const double sigma_g = c.gyroscope.noise_density / std::sqrt(c.period);
  const double sigma_a = c.accelerometer.noise_density / std::sqrt(c.period);
  for (int i = 0; i < 3; ++i) {
    // The sample standard deviation of 2e5 Gaussian draws is within 1 % of sigma (its own
    // standard error is 0.16 %); the mean within 5 standard errors of zero.
    EXPECT_NEAR(std::sqrt(sum_gg[i] / kSamples) / sigma_g, 1.0, 0.01);
    EXPECT_NEAR(std::sqrt(sum_aa[i] / kSamples) / sigma_a, 1.0, 0.01);
    EXPECT_LT(std::abs(sum_g[i] / kSamples), 5 * sigma_g / std::sqrt(kSamples));
    EXPECT_LT(std::abs(sum_a[i] / kSamples), 5 * sigma_a / std::sqrt(kSamples));
  }
}

TEST(ImuModel, PowerUpBiasesAndTheirWalkHaveTheConfiguredSpread) {
  const sensors::ImuConfig c = sensors::bmi088();
  constexpr int kUnits = 400;
  constexpr int kSteps = 1000;  // 1 s
  double initial = 0, walked = 0;
  for (int unit = 0; unit < kUnits; ++unit) {
    sensors::ImuModel imu(c, 1000 + unit);
    const Vector3 start = imu.accelerometer_bias();
    initial += start.squaredNorm();
    for (int k = 0; k < kSteps; ++k) imu.measure({});
    walked += (imu.accelerometer_bias() - start).squaredNorm();
  }
  // 1200 axis draws: each variance within 12 % of the configured (4 standard errors of the
  // sample variance, sqrt(2 / 1200) = 4 %).
  const double n = 3.0 * kUnits;
  EXPECT_NEAR(std::sqrt(initial / n) / c.accelerometer.initial_bias, 1.0, 0.06);
  const double walk_sigma = c.accelerometer.bias_random_walk * std::sqrt(kSteps * c.period);
  EXPECT_NEAR(std::sqrt(walked / n) / walk_sigma, 1.0, 0.06);
}

TEST(ImuModel, RepeatsWithItsSeedClipsQuantisesAndDelays) {
  sensors::ImuConfig c = sensors::bmi088();
  sensors::ImuModel a(c, 3), b(c, 3), other(c, 4);
  sensors::ImuTruth truth;
  truth.specific_force = Vector3(0, 0, 9.81);
  const sensors::ImuReading ra = a.measure(truth), rb = b.measure(truth);
  EXPECT_EQ(ra.angular_velocity, rb.angular_velocity);
  EXPECT_EQ(ra.specific_force, rb.specific_force);
  EXPECT_NE(other.measure(truth).specific_force, ra.specific_force);

  // Readings are whole LSBs.
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(std::remainder(ra.angular_velocity[i] / c.gyroscope.resolution, 1.0), 0, 1e-6);
    EXPECT_NEAR(std::remainder(ra.specific_force[i] / c.accelerometer.resolution, 1.0), 0, 1e-6);
  }

  // A 20 g landing clips at 12 g and says so.
  sensors::ImuTruth impact;
  impact.specific_force = Vector3(0, 0, 20 * 9.81);
  const sensors::ImuReading clipped = a.measure(impact);
  EXPECT_TRUE(clipped.saturated);
  EXPECT_NEAR(clipped.specific_force.z(), c.accelerometer.range, c.accelerometer.resolution);

  // Three samples late: a step in the truth shows three readings after it.
  c.latency = 3;
  c.gyroscope.noise_density = c.accelerometer.noise_density = 0;
  sensors::ImuModel late(c, 5);
  sensors::ImuTruth still, turning;
  turning.angular_velocity = Vector3(0, 0, 1.0);
  std::vector<double> yaw;
  yaw.reserve(8);
  for (int k = 0; k < 3; ++k) yaw.push_back(late.measure(still).angular_velocity.z());
  for (int k = 0; k < 5; ++k) yaw.push_back(late.measure(turning).angular_velocity.z());
  for (int k = 0; k < 6; ++k) EXPECT_LT(std::abs(yaw[k]), 0.1) << k;
  EXPECT_GT(yaw[6], 0.9);
  EXPECT_GT(yaw[7], 0.9);
}

}  // namespace
