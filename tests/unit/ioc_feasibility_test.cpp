// The motion feasibility index and the time warping against it (feasibility.hpp), on motions
// whose answer physics gives: standing, free fall, a flight under the wrong gravity.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "hmpc/humanoid/closed_loop.hpp"
#include "hmpc/ioc/feasibility.hpp"

namespace {

using namespace hmpc;
using namespace hmpc::ioc;
using humanoid::Configuration;
using humanoid::Velocity;

constexpr double kGravity = 9.81;

const humanoid::State& standing() {
  static const humanoid::State x =
      humanoid::standing_state(humanoid::ProblemConfig{}, humanoid::kStartHeight);
  return x;
}

// The torso's linear acceleration `world` (world coordinates) with no rotation and still joints:
// the whole body accelerates rigidly.
Velocity rigid_acceleration(const Configuration& q, const Eigen::Vector3d& world) {
  const Eigen::Quaterniond attitude(q[3], q[4], q[5], q[6]);
  Velocity a = Velocity::Zero();
  a.segment<3>(3) = attitude.conjugate() * world;
  return a;
}

TEST(FeasibilityIndex, StandingStillIsFeasibleOnBothSoles) {
  FeasibilityIndex index(humanoid::Parameters{});
  EXPECT_LT(index(standing().q, Velocity::Zero(), Velocity::Zero()), 1e-9);
  EXPECT_EQ(index.contacts(), humanoid::kSolePoints);
}

TEST(FeasibilityIndex, InTheAirOnlyFreeFallIsFeasible) {
  FeasibilityIndex index(humanoid::Parameters{});
  Configuration q = standing().q;
  q[2] += 0.3;
  // Held still in the air, the body needs its whole weight (index 1 in body weights, plus the
  // moment of the weight about the torso origin, a few centimetres off the centre of mass).
  const double held = index(q, Velocity::Zero(), Velocity::Zero());
  EXPECT_EQ(index.contacts(), 0);
  EXPECT_GE(held, 1.0);
  EXPECT_LT(held, 1.1);
  EXPECT_LT(index(q, Velocity::Zero(), rigid_acceleration(q, {0.0, 0.0, -kGravity})), 1e-9);
}

TEST(FeasibilityIndex, AccelerationSidewaysTipsOverTheSoles) {
  // Accelerating the standing body forward at a moves its centre of pressure forward by about
  // h a / g (h the centre of mass's height, about 0.9 m): at 0.02 g 2 cm, under the feet; at
  // 0.5 g 45 cm, far beyond the toes (the friction, mu / sqrt 2 = 0.57 g, would still hold).
  FeasibilityIndex index(humanoid::Parameters{});
  const Configuration& q = standing().q;
  EXPECT_LT(index(q, Velocity::Zero(), rigid_acceleration(q, {0.02 * kGravity, 0.0, 0.0})), 1e-9);
  EXPECT_GT(index(q, Velocity::Zero(), rigid_acceleration(q, {0.5 * kGravity, 0.0, 0.0})), 0.1);
  // Pulled down harder than gravity, the soles would have to pull: the index is the shortfall.
  EXPECT_NEAR(index(q, Velocity::Zero(), rigid_acceleration(q, {0.0, 0.0, -1.5 * kGravity})), 0.5,
              0.05);
}

// A flight sampled every `step` whose base rises and falls under `gravity`, the soles at least
// 25 cm up over the 0.3 s of 11 samples.
std::vector<Configuration> flight(double gravity, double step, int samples) {
  std::vector<Configuration> poses;
  for (int k = 0; k < samples; ++k) {
    const double t = k * step;
    Configuration q = standing().q;
    q[2] += 0.25 + 1.5 * t - 0.5 * gravity * t * t;
    poses.push_back(q);
  }
  return poses;
}

TEST(FeasibilityWarping, AFlightUnderHalfGravityPlaysSqrt2TimesFaster) {
  constexpr double kStep = 0.03;
  constexpr int kSamples = 11;
  FeasibilityIndex index(humanoid::Parameters{});
  const WarpConfig config;
  // Played as captured, the slow flight needs half its weight held up (index 0.5); sped up by
  // sqrt 2 its accelerations are g and it is ballistic. The speeds come in levels exp(0.05 j).
  const std::vector<Configuration> slow = flight(0.5 * kGravity, kStep, kSamples);
  const std::vector<double> speeds = feasible_speeds(slow, kStep, index, config);
  const std::vector<double> nominal(kSamples, 1.0);
  const std::vector<double> before = feasibility_along(slow, kStep, nominal, index);
  const std::vector<double> after = feasibility_along(slow, kStep, speeds, index);
  for (int k = 0; k < kSamples; ++k) {
    EXPECT_NEAR(std::log(speeds[k]), 0.5 * std::log(2.0), config.level_step) << "sample " << k;
    EXPECT_NEAR(before[k], 0.5, 0.05) << "sample " << k;
    EXPECT_LT(after[k], 0.1) << "sample " << k;
  }
  // A ballistic flight keeps its timeline.
  for (const double s : feasible_speeds(flight(kGravity, kStep, kSamples), kStep, index, config))
    EXPECT_NEAR(std::log(s), 0.0, config.level_step);
}

TEST(FeasibilityWarping, WarpedIndicesFollowTheSpeeds) {
  // Unit speeds: pose i at time i step; played every step / 2, two samples a pose.
  const std::vector<double> unit(5, 1.0);
  const std::vector<double> at = warped_indices(unit, 0.03, 0.015);
  ASSERT_EQ(at.size(), 9u);
  for (std::size_t k = 0; k < at.size(); ++k) EXPECT_NEAR(at[k], 0.5 * k, 1e-12);
  // Twice as fast: every other pose per step.
  const std::vector<double> fast = warped_indices(std::vector<double>(5, 2.0), 0.03, 0.03);
  ASSERT_EQ(fast.size(), 3u);
  for (std::size_t k = 0; k < fast.size(); ++k) EXPECT_NEAR(fast[k], 2.0 * k, 1e-12);
  EXPECT_THROW(warped_indices({1.0}, 0.03, 0.03), std::invalid_argument);
  EXPECT_THROW(warped_indices({1.0, 0.0}, 0.03, 0.03), std::invalid_argument);
  EXPECT_THROW(warped_indices(unit, 0.0, 0.03), std::invalid_argument);
  FeasibilityIndex index(humanoid::Parameters{});
  EXPECT_THROW(feasible_speeds({standing().q, standing().q}, 0.03, index), std::invalid_argument);
}

}  // namespace
