// The human demonstrator and retargeting (demonstrator.hpp, retargeting.hpp): each step on
// inputs whose answer is known, and the tracking term they add to the humanoid's cost.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "hmpc/ioc/retargeting.hpp"
#include "ioc_test_support.hpp"

namespace {

using namespace hmpc;
using namespace hmpc::ioc;
using humanoid::Configuration;

const Configuration& standing_pose() {
  static const Configuration q =
      humanoid::standing_state(humanoid::ProblemConfig{}, humanoid::kStartHeight).q;
  return q;
}

// A pose moving with known rates: base at velocity (0.2, -0.1, 0.3) m/s, yawing at 0.5 rad/s,
// the joints at 0.1 (j + 1) rad/s.
Configuration moving_pose(double t) {
  Configuration q = standing_pose();
  q.head<3>() += t * Eigen::Vector3d(0.2, -0.1, 0.3);
  const Eigen::Quaterniond yaw(Eigen::AngleAxisd(0.5 * t, Eigen::Vector3d::UnitZ()));
  q.segment<4>(3) << yaw.w(), yaw.x(), yaw.y(), yaw.z();
  for (int j = 0; j < 8; ++j) q[7 + j] += 0.1 * (j + 1) * t;
  return q;
}

TEST(IocRetargeting, TheDemonstratorsBodyDiffersFromTheRobots) {
  const humanoid::Parameters human = demonstrator_parameters(), robot;
  EXPECT_GT(human.stature, robot.stature);
  EXPECT_GT(human.body_mass, robot.body_mass);
  // Proportions differ, not only the size: legs are a larger fraction of the height.
  EXPECT_GT(leg_length(human) / human.stature, leg_length(robot) / robot.stature + 0.01);
  EXPECT_NEAR(leg_length(robot), 0.803, 1e-3);  // model.cpp's mid-hip height of the robot
  EXPECT_GT(demonstrator_start_height(), humanoid::kStartHeight);
}

TEST(IocRetargeting, MappingScalesTheBaseAndClampsJointsToTheRobotsRange) {
  const humanoid::Parameters robot;
  Configuration q = standing_pose();
  q[7 + humanoid::kKnee] = 2.9;        // beyond the robot's 2.36 rad knee flexion
  q[7 + 4 + humanoid::kAnkle] = -1.2;  // beyond its 0.87 rad plantarflexion
  q.segment<4>(3) *= 2.0;              // not unit
  const Configuration m = map_pose(q, 0.9, robot);
  EXPECT_NEAR((m.head<3>() - 0.9 * q.head<3>()).norm(), 0.0, 1e-15);
  EXPECT_NEAR(m.segment<4>(3).norm(), 1.0, 1e-15);
  EXPECT_DOUBLE_EQ(m[7 + humanoid::kKnee], robot.joint_upper[humanoid::kKnee]);
  EXPECT_DOUBLE_EQ(m[7 + 4 + humanoid::kAnkle], robot.joint_lower[humanoid::kAnkle]);
  EXPECT_DOUBLE_EQ(m[7 + humanoid::kHipFlexion], q[7 + humanoid::kHipFlexion]);
}

TEST(IocRetargeting, LowPassKeepsRampsAndQuartersNoise) {
  std::vector<Configuration> ramp, noisy;
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0.0, 0.01);
  for (int k = 0; k < 400; ++k) {
    ramp.push_back(moving_pose(0.03 * k));
    noisy.push_back(standing_pose());
    for (int j = 0; j < 8; ++j) noisy.back()[7 + j] += noise(rng);
  }
  const std::vector<Configuration> smooth_ramp = low_pass(ramp), smooth_noise = low_pass(noisy);
  for (int k = 2; k < 398; ++k) EXPECT_NEAR((smooth_ramp[k] - ramp[k]).norm(), 0.0, 2e-4) << k;
  double before = 0.0, after = 0.0;
  for (int k = 2; k < 398; ++k) {
    before += (noisy[k] - standing_pose()).squaredNorm();
    after += (smooth_noise[k] - standing_pose()).squaredNorm();
  }
  // White noise through (1 4 6 4 1) / 16: variance times 70 / 256.
  EXPECT_NEAR(after / before, 70.0 / 256.0, 0.05);
}

TEST(IocRetargeting, DynamicTimeWarpingRecoversAKnownWarp) {
  // A squat-like pose sequence, and the same played 1.25 times slower after a 0.2 s pause.
  const auto pose_at = [](double t) {
    Configuration q = standing_pose();
    const double s = t < 0.3 ? 0.0 : t > 1.5 ? 1.0 : 0.5 - 0.5 * std::cos(M_PI * (t - 0.3) / 1.2);
    const double depth = std::sin(M_PI * s);
    q[2] -= 0.15 * depth;
    for (int leg = 0; leg < 2; ++leg) {
      q[7 + 4 * leg + humanoid::kHipFlexion] += 0.6 * depth;
      q[7 + 4 * leg + humanoid::kKnee] += 1.0 * depth;
      q[7 + 4 * leg + humanoid::kAnkle] += 0.3 * depth;
    }
    return q;
  };
  std::vector<Configuration> reference, slower;
  for (int k = 0; k * 0.03 <= 1.8; ++k) reference.push_back(pose_at(0.03 * k));
  for (int k = 0; k * 0.03 <= 2.45; ++k)
    slower.push_back(pose_at(std::max(0.0, 0.03 * k - 0.2) / 1.25));
  const std::vector<double> match = align(slower, reference);
  ASSERT_EQ(match.size(), reference.size());
  for (std::size_t i = 1; i < match.size(); ++i) EXPECT_GE(match[i], match[i - 1]);
  // Where the poses change (0.3 .. 1.5 s), reference sample i is the slower one's 1.25 i + 0.2 s.
  for (int i = 12; i <= 48; ++i)
    EXPECT_NEAR(match[i], 1.25 * i + 0.2 / 0.03, 1.5) << "sample " << i;
}

TEST(IocRetargeting, VelocitiesByDifferencesAndResampling) {
  std::vector<Configuration> poses;
  for (int k = 0; k < 20; ++k) poses.push_back(moving_pose(0.03 * k));
  const std::vector<humanoid::State> states = with_velocities(poses, 0.03);
  for (int k : {0, 7, 19}) {
    const humanoid::State& x = states[k];
    EXPECT_NEAR((x.v.head<3>() - Eigen::Vector3d(0, 0, 0.5)).norm(), 0.0, 1e-9)
        << k;  // torso coordinates
    const Eigen::Quaterniond attitude(x.q[3], x.q[4], x.q[5], x.q[6]);
    EXPECT_NEAR(
        (attitude * Eigen::Vector3d(x.v.segment<3>(3)) - Eigen::Vector3d(0.2, -0.1, 0.3)).norm(),
        0.0, 1e-9)
        << k;
    for (int j = 0; j < 8; ++j) EXPECT_NEAR(x.v[6 + j], 0.1 * (j + 1), 1e-9) << k;
  }
  const std::vector<Configuration> half = resample(poses, {0.0, 2.5, 30.0});
  EXPECT_NEAR((half[1] - moving_pose(0.075)).norm(), 0.0, 1e-4);
  EXPECT_NEAR((half[2] - poses.back()).norm(), 0.0, 1e-15);  // past the end: the last pose
  EXPECT_THROW(with_velocities({poses[0]}, 0.03), std::invalid_argument);
  EXPECT_THROW(resample({poses[0]}, {0.0}), std::invalid_argument);
}

TEST(IocRetargeting, AttitudeAnglesInvertTheAttitudeQuaternion) {
  for (const Eigen::Vector3d& a :
       {Eigen::Vector3d(0.1, -0.3, 2.0), Eigen::Vector3d(-1.0, 1.2, -3.0),
        Eigen::Vector3d(0.0, 0.0, 0.0)}) {
    EXPECT_NEAR((attitude_angles(humanoid::attitude_quaternion(a)) - a).norm(), 0.0, 1e-12)
        << a.transpose();
  }
}

TEST(IocRetargeting, MotionAlongTargetsEveryStep) {
  const humanoid::Motion task = test::jump_motion();
  std::vector<Configuration> poses;
  for (int k = 0; k < 30; ++k) poses.push_back(moving_pose(0.03 * k));
  const std::vector<humanoid::State> states = with_velocities(poses, 0.03);
  const humanoid::Motion m = motion_along(states, task, humanoid::ProblemConfig{});
  ASSERT_EQ(m.phase_count, 30);
  EXPECT_NEAR(m.duration, 0.87, 1e-12);
  const humanoid::StateCost cost(task, states[0], humanoid::ProblemConfig{});
  for (int k : {0, 13, 29}) {
    const humanoid::BaseFeatures f = cost.features(states[k]);
    EXPECT_NEAR(m.phase_at(0.03 * k + 1e-9).height, f.position.z(), 1e-12);
    EXPECT_NEAR((m.phases[k].velocity - f.velocity).norm(), 0.0, 1e-12);
    EXPECT_NEAR(m.phases[k].attitude.z(), 0.5 * 0.03 * k, 1e-9);
    EXPECT_EQ(m.phases[k].joints[7], poses[k][14]);
  }
  EXPECT_EQ(m.weights.height, task.weights.height);
  const std::vector<humanoid::State> too_long(humanoid::kMaxPhases + 1, states[0]);
  EXPECT_THROW(motion_along(too_long, task, humanoid::ProblemConfig{}), std::invalid_argument);
}

TEST(IocRetargeting, JointTrackingTermWeighsTheLegJoints) {
  humanoid::Motion m = test::jump_motion();
  const humanoid::State x =
      humanoid::standing_state(humanoid::ProblemConfig{}, humanoid::kStartHeight);
  const auto rows = [&](const humanoid::Motion& motion) {
    return humanoid::StateCost(motion, x, humanoid::ProblemConfig{})
        .residual(humanoid::to_vector(x), 0.0);
  };
  EXPECT_EQ(rows(m).segment<8>(18).norm(), 0.0);  // w_joint = 0 in every file
  m.weights.joint = 4.0;
  for (int j = 0; j < 8; ++j) m.phases[0].joints[j] = x.q[7 + j] - 0.01 * (j + 1);
  const auto r = rows(m);
  for (int j = 0; j < 8; ++j) EXPECT_NEAR(r[18 + j], 2.0 * 0.01 * (j + 1), 1e-15) << j;
}

TEST(IocRetargeting, FeasibilityWarpingSpeedsUpAFlightUnderHalfGravity) {
  // Two captures of a demonstrator in the air, its base rising and falling under g / 2. Step 1
  // scales lengths by l = l_robot / l_demonstrator and step 2b time by sqrt(l), which keeps
  // accelerations: the robot's flight is still under g / 2, half its weight missing. Step 2c plays
  // it sqrt(2) times faster, where it is ballistic (in exp(0.05 j) levels); one timeline plays
  // both captures.
  constexpr int kPoses = 21;
  Capture flight;
  for (int k = 0; k < kPoses; ++k) {
    const double t = k * humanoid::kCoarseStep;
    Configuration q = standing_pose();
    q[2] = 1.2 + 1.5 * t - 0.25 * 9.81 * t * t;
    flight.poses.push_back(q);
  }
  RetargetConfig config;
  const WarpedCaptures froude = warp_captures({flight, flight}, config);
  config.warping = TimeWarping::kFeasibility;
  const WarpedCaptures warped = warp_captures({flight, flight}, config);
  ASSERT_EQ(warped.states.size(), 2u);
  ASSERT_EQ(froude.speeds.size(), static_cast<std::size_t>(kPoses));
  for (const double s : froude.speeds) EXPECT_EQ(s, 1.0);
  EXPECT_EQ(froude.states.front().size(),
            static_cast<std::size_t>(std::floor((kPoses - 1) * froude.time_scale)) + 1);
  // The low-pass filter's window, renormalised, bends the parabola within two samples of each
  // end, and the acceleration's stencil spans two more.
  for (int k = 4; k < kPoses - 4; ++k) {
    EXPECT_NEAR(std::log(warped.speeds[k]), 0.5 * std::log(2.0), 0.06) << "sample " << k;
    EXPECT_NEAR(froude.nominal_index[k], 0.5, 0.05) << "sample " << k;
    EXPECT_LT(warped.warped_index[k], 0.1) << "sample " << k;
  }
  EXPECT_EQ(warped.states.front().size(), warped.states.back().size());
}

TEST(IocRetargeting, RejectsBadCapturesAndSettings) {
  const humanoid::Motion task = test::jump_motion();
  EXPECT_THROW(retarget({}, task, RetargetConfig{}), std::invalid_argument);
  EXPECT_THROW(retarget({Capture{{standing_pose()}}}, task, RetargetConfig{}),
               std::invalid_argument);
  CaptureConfig config;
  config.count = 0;
  EXPECT_THROW(capture_demonstrations(task, config), std::invalid_argument);
  config = CaptureConfig{};
  config.timing_spread = 0.5;
  EXPECT_THROW(capture_demonstrations(task, config), std::invalid_argument);
  config = CaptureConfig{};
  config.angle_noise = -0.01;
  EXPECT_THROW(capture_demonstrations(task, config), std::invalid_argument);
  config.angle_noise = std::nan("");
  EXPECT_THROW(capture_demonstrations(task, config), std::invalid_argument);
}

}  // namespace
