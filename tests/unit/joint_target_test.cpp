// Joint targets as users give them: each shape is the curve it promises (between its points
// too), every check refuses what a joint cannot follow, and a CSV file's problems are named
// with their line.
#include "hmpc/trajectory/joint_target.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "hmpc/models/forearm_target_range.hpp"

namespace {

using hmpc::trajectory::check_points;
using hmpc::trajectory::JointRange;
using hmpc::trajectory::JointTrajectoryTarget;
using hmpc::trajectory::kMaxPoints;
using hmpc::trajectory::kSampleSpacingS;
using hmpc::trajectory::make_points;
using hmpc::trajectory::read_points_csv;
using hmpc::trajectory::TargetShape;
using hmpc::trajectory::TargetSpec;
using hmpc::trajectory::TrajectoryPoint;

constexpr double kPi = 3.14159265358979323846;
const JointRange kRange{-1.2, 1.6, 10.0};

// The target's points, or a failure naming why.
std::vector<TrajectoryPoint> points_of(const TargetSpec& spec) {
  std::vector<TrajectoryPoint> points;
  std::string error;
  EXPECT_TRUE(make_points(spec, kRange, kMaxPoints, points, error)) << error;
  return points;
}

JointTrajectoryTarget target_of(const std::vector<TrajectoryPoint>& points) {
  JointTrajectoryTarget target(points.size());
  EXPECT_TRUE(target.assign(points.data(), points.size()));
  return target;
}

// The largest |position(t) - curve(t)| over a 1 ms grid of [0, duration].
template <typename Curve>
double worst_error(const JointTrajectoryTarget& target, double duration, Curve curve) {
  double worst = 0;
  for (double t = 0; t <= duration; t += 1e-3)
    worst = std::max(worst, std::abs(target.position(t) - curve(t)));
  return worst;
}

std::string write_file(const std::string& name, const std::string& text) {
  const char* tmp = std::getenv("TMPDIR");
  std::string path = std::string(tmp ? tmp : "/tmp") + "/joint_target_test_" + name;
  std::ofstream(path) << text;
  return path;
}

TEST(JointTarget, TheSineIsItsCurveWithinTheHermiteBound) {
  TargetSpec spec;
  spec.amplitude = 30 * kPi / 180;
  spec.frequency_hz = 2.5;
  spec.offset = 0.1;
  spec.duration_s = 2;
  const auto points = points_of(spec);
  ASSERT_EQ(points.size(), std::size_t(std::lround(2 / kSampleSpacingS)) + 1);
  const double w = 2 * kPi * spec.frequency_hz;
  const double worst = worst_error(target_of(points), 2, [&](double t) {
    return spec.offset + spec.amplitude * std::sin(w * t);
  });
  // Cubic Hermite interpolation's error bound: h^4 / 384 max |theta''''| = A (w h)^4 / 384.
  const double bound = spec.amplitude * std::pow(w * kSampleSpacingS, 4) / 384;
  EXPECT_LE(worst, bound);
  EXPECT_GT(worst, bound / 10);  // interpolated, not sampled at every millisecond
}

TEST(JointTarget, TheChirpSweepsItsFrequencyLinearly) {
  TargetSpec spec;
  spec.shape = TargetShape::kChirp;
  spec.amplitude = 0.4;
  spec.frequency_hz = 0.5;
  spec.chirp_end_hz = 2.0;
  spec.duration_s = 6;
  const auto target = target_of(points_of(spec));
  const double sweep = (spec.chirp_end_hz - spec.frequency_hz) / spec.duration_s;
  const auto chirp = [&](double t) {
    return spec.amplitude * std::sin(2 * kPi * (spec.frequency_hz * t + sweep * t * t / 2));
  };
  EXPECT_LE(worst_error(target, spec.duration_s, chirp),
            spec.amplitude * std::pow(2 * kPi * spec.chirp_end_hz * kSampleSpacingS, 4) / 384 *
                2);  // the sweep adds terms of the same order
  // Its upward zero crossings where the phase passes whole turns: f0 t + sweep t^2 / 2 = k.
  std::vector<double> crossings;
  for (double t = 1e-3; t <= spec.duration_s; t += 1e-3)
    if (target.position(t - 1e-3) < 0 && target.position(t) >= 0) crossings.push_back(t);
  ASSERT_EQ(crossings.size(), 7u);  // turns 1..7 of the 7.5 the chirp makes
  for (std::size_t k = 0; k < crossings.size(); ++k) {
    const double turn = double(k + 1);
    const double f0 = spec.frequency_hz;
    const double t_k = (-f0 + std::sqrt(f0 * f0 + 2 * sweep * turn)) / sweep;
    EXPECT_NEAR(crossings[k], t_k, 1e-3) << "turn " << turn;
  }
}

TEST(JointTarget, TheStepHoldsThenMovesAtItsRate) {
  TargetSpec spec;
  spec.shape = TargetShape::kStep;
  spec.offset = 0.1;
  spec.amplitude = -0.5;
  spec.step_at_s = 1;
  spec.step_rate = 2;
  spec.duration_s = 3;
  const auto points = points_of(spec);
  const auto target = target_of(points);
  EXPECT_EQ(target.position(0), 0.1);
  EXPECT_EQ(target.position(0.999), 0.1);
  EXPECT_NEAR(target.position(1.125), 0.1 - 0.25, 1e-12);  // halfway at 2 rad/s
  EXPECT_NEAR(target.position(1.25), -0.4, 1e-12);
  EXPECT_NEAR(target.position(3), -0.4, 1e-12);
  double fastest = 0;
  for (std::size_t k = 1; k < points.size(); ++k)
    fastest =
        std::max(fastest, hmpc::trajectory::segment_bounds(points[k - 1], points[k]).max_speed);
  EXPECT_NEAR(fastest, spec.step_rate, 1e-9);
}

TEST(JointTarget, TheRampIsATriangleWaveAtFourAmplitudesPerPeriod) {
  TargetSpec spec;
  spec.shape = TargetShape::kRamp;
  spec.amplitude = 0.5;
  spec.frequency_hz = 0.5;
  spec.duration_s = 4.2;
  const auto points = points_of(spec);
  const auto target = target_of(points);
  EXPECT_NEAR(target.position(0), 0, 1e-12);
  EXPECT_NEAR(target.position(0.5), 0.5, 1e-12);   // quarter period
  EXPECT_NEAR(target.position(1.5), -0.5, 1e-12);  // three quarters
  EXPECT_NEAR(target.position(1.0), 0, 1e-12);
  EXPECT_NEAR(target.position(2.5), 0.5, 1e-12);
  EXPECT_GE(points.back().time_s, spec.duration_s);  // no corner missing before the end
  for (std::size_t k = 1; k < points.size(); ++k) {
    EXPECT_NEAR(hmpc::trajectory::segment_bounds(points[k - 1], points[k]).max_speed,
                4 * spec.amplitude * spec.frequency_hz, 1e-12);
  }
}

TEST(JointTarget, ShapesTheJointCannotFollowAreRefusedWithTheReason) {
  const auto refusal = [](const TargetSpec& spec) {
    std::vector<TrajectoryPoint> points;
    std::string error;
    EXPECT_FALSE(make_points(spec, kRange, kMaxPoints, points, error));
    return error;
  };
  TargetSpec too_fast;
  too_fast.frequency_hz = 3.5;  // peak 2 pi 3.5 0.52 = 11.5 rad/s
  EXPECT_NE(refusal(too_fast).find("rad/s, beyond the joint's 10 rad/s"), std::string::npos);
  TargetSpec too_far;
  too_far.shape = TargetShape::kStep;
  too_far.amplitude = 1.0;
  too_far.offset = 0.8;
  EXPECT_NE(refusal(too_far).find("asks for 1.8 rad, outside the joint's -1.2..1.6 rad"),
            std::string::npos);
  TargetSpec late;
  late.shape = TargetShape::kStep;
  late.step_at_s = 10;
  EXPECT_NE(refusal(late).find("the step at 10 s must lie within the target's 10 s"),
            std::string::npos);
  TargetSpec no_rate;
  no_rate.shape = TargetShape::kStep;
  no_rate.step_rate = 0;
  EXPECT_NE(refusal(no_rate).find("rate must be positive"), std::string::npos);
  TargetSpec still;
  still.shape = TargetShape::kRamp;
  still.frequency_hz = 0;
  EXPECT_NE(refusal(still).find("a ramp needs a frequency above 0"), std::string::npos);
  TargetSpec long_sine;
  long_sine.duration_s = 200;  // 10001 points
  EXPECT_NE(refusal(long_sine).find("10001 points, at most 8192"), std::string::npos);
  TargetSpec nan;
  nan.offset = NAN;
  EXPECT_NE(refusal(nan).find("must be finite"), std::string::npos);
}

TEST(JointTarget, CheckPointsRefusesEachKindOfBadPoint) {
  const auto check = [](std::vector<TrajectoryPoint> p) {
    return check_points(p.data(), p.size(), kRange);
  };
  EXPECT_EQ(check({{0, 0, 0, false}, {1, 0.5, 0, false}}), "");
  EXPECT_EQ(check({}), "the target has no points");
  EXPECT_NE(check({{0, 0, 0, false}, {1, INFINITY, 0, false}}).find("point 1 is not finite"),
            std::string::npos);
  EXPECT_NE(check({{0, 0, NAN, true}}).find("point 0 is not finite"), std::string::npos);
  EXPECT_NE(check({{-0.5, 0, 0, false}}).find("point 0 is at -0.5 s, before the start"),
            std::string::npos);
  EXPECT_NE(check({{0, 0, 0, false}, {1, 0, 0, false}, {1, 0.1, 0, false}})
                .find("point 2 at 1 s does not follow point 1 at 1 s"),
            std::string::npos);
  EXPECT_NE(check({{0, 0, 11, true}}).find("point 0 (t = 0 s) asks for 11 rad/s"),
            std::string::npos);
  // Both ends inside and slow, but the Hermite between them overshoots the upper limit.
  EXPECT_NE(check({{0, 1.5, 3, true}, {0.5, 1.5, -3, true}})
                .find("between points 0 and 1 (t = 0..0.5 s) the target swings to"),
            std::string::npos);
  EXPECT_NE(check({{0, 0, 0, false}, {0.05, 0.6, 0, false}})
                .find("between points 0 and 1 (t = 0..0.05 s) the target moves at 12 rad/s"),
            std::string::npos);
}

TEST(JointTarget, ACsvFileGivesItsPointsWithOrWithoutVelocities) {
  const std::string path = write_file("good.csv",
                                      "time_s,position_rad,velocity_rad_s\n"
                                      "# a comment\n"
                                      "\n"
                                      "0, 0.0, 0\n"
                                      "0.5,0.25\n"
                                      "1.0,0.5,0.1\r\n");
  TargetSpec spec;
  spec.shape = TargetShape::kFile;
  spec.file = path;
  const auto points = points_of(spec);
  ASSERT_EQ(points.size(), 3u);
  EXPECT_TRUE(points[0].has_velocity);
  EXPECT_FALSE(points[1].has_velocity);
  EXPECT_EQ(points[1].position, 0.25);
  EXPECT_EQ(points[2].velocity, 0.1);
  EXPECT_NEAR(target_of(points).position(0.75), 0.375, 1e-12);  // linear: [1] has no velocity
}

TEST(JointTarget, ACsvFilesProblemsAreNamedWithTheirLine) {
  struct Case {
    const char* name;
    const char* text;
    const char* message;
  };
  const Case cases[] = {
      {"columns.csv", "0,0\n1\n", "columns.csv:2: expected time_s,position_rad[,velocity_rad_s]"},
      {"four.csv", "0,0,0,0\n", "four.csv:1: expected time_s,position_rad"},
      {"word.csv", "t,p\n0,0\n1,abc\n", "word.csv:3: not a number in '1,abc'"},
      {"late_header.csv", "0,0\ntime,position\n", "late_header.csv:2: not a number"},
      {"semicolon.csv", "0;0\n", "semicolon.csv:1: expected time_s,position_rad"},
      {"empty.csv", "time_s,position_rad\n# nothing\n", "empty.csv: no points"},
      {"overflow.csv", "0,1e999\n", "overflow.csv:1: not a number"},
  };
  for (const Case& c : cases) {
    std::vector<TrajectoryPoint> points;
    std::string error;
    EXPECT_FALSE(read_points_csv(write_file(c.name, c.text), kMaxPoints, points, error)) << c.name;
    EXPECT_NE(error.find(c.message), std::string::npos) << c.name << ": " << error;
  }
  std::vector<TrajectoryPoint> points;
  std::string error;
  EXPECT_FALSE(read_points_csv(write_file("three.csv", "0,0\n1,0\n2,0\n"), 2, points, error));
  EXPECT_NE(error.find("three.csv:3: more than 2 points"), std::string::npos) << error;
  EXPECT_FALSE(read_points_csv("/nonexistent/target.csv", kMaxPoints, points, error));
  EXPECT_NE(error.find("/nonexistent/target.csv: cannot open"), std::string::npos) << error;
  // Values that parse are the checks' business: a file's nan is refused by make_points.
  TargetSpec spec;
  spec.shape = TargetShape::kFile;
  spec.file = write_file("nan.csv", "0,0\n1,nan\n");
  EXPECT_FALSE(make_points(spec, kRange, kMaxPoints, points, error));
  EXPECT_NE(error.find("nan.csv: point 1 is not finite"), std::string::npos) << error;
}

TEST(JointTarget, TheForearmsRangeIsTheBoardsSoftLimitsAndTheTargetSpeed) {
  const hmpc::forearm::Parameters<double> arm{};
  const JointRange range = hmpc::forearm::target_range();
  EXPECT_EQ(range.min_position, arm.soft_limit_lower);
  EXPECT_EQ(range.max_position, arm.soft_limit_upper);
  EXPECT_EQ(range.max_speed, hmpc::forearm::kMaxTargetSpeed);
}

}  // namespace
