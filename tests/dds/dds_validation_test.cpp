// The checks of incoming DDS samples (host/dds validation) on messages built in memory, and the
// trajectory interpolant they judge: no DDS traffic.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "forearm_board.hpp"
#include "hmpc/dds/forearm_dds.hpp"
#include "hmpc/dds/validation.hpp"
#include "hmpc/models/forearm_target_range.hpp"
#include "hmpc/trajectory/joint_trajectory.hpp"

namespace {

namespace dds = hmpc::dds;
namespace msg = hmpc::dds::msg;
using dds::Rejection;
using hmpc::trajectory::TrajectoryPoint;

constexpr double kNow = 1.8e9;  // a Unix time in 2027
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A trajectory message over caller-owned points (t, positions..., velocities...).
struct Trajectory {
  Trajectory(std::vector<const char*> n, std::vector<std::vector<double>> p,
             std::vector<std::vector<double>> v, std::vector<double> t)
      : names(std::move(n)), positions(std::move(p)), velocities(std::move(v)),
        times(std::move(t)) {}

  std::vector<const char*> names;
  std::vector<std::vector<double>> positions, velocities;
  std::vector<double> times;
  std::vector<msg::JointTrajectoryPoint> points;
  msg::JointTrajectory message{};

  const msg::JointTrajectory& build() {
    points.assign(times.size(), msg::JointTrajectoryPoint{});
    for (std::size_t k = 0; k < times.size(); ++k) {
      points[k].time_from_start = dds::from_seconds<msg::Duration>(times[k]);
      points[k].positions = dds::borrow(positions[k].data(), positions[k].size());
      if (k < velocities.size()) {
        points[k].velocities = dds::borrow(velocities[k].data(), velocities[k].size());
      }
    }
    message.joint_names = dds::borrow(names.data(), names.size());
    message.points = dds::borrow<decltype(message.points)>(points.data(), points.size());
    return message;
  }
};

const dds::JointLimits kTwoJoints[] = {{"hip", -1.0, 1.0, 5.0}, {"knee", -2.0, 0.0, 8.0}};

dds::Verdict check(Trajectory& t) {
  return dds::validate(t.build(), kTwoJoints, 2, dds::TrajectoryLimits{4, 10.0}, kNow, {});
}

TEST(DdsValidation, AcceptsATrajectoryOfBothJointsInEitherOrder) {
  Trajectory t{{"knee", "hip"}, {{-0.5, 0.2}, {-1.0, 0.9}}, {{0, 0}, {0, 0}}, {0.0, 1.0}};
  const dds::Verdict v = check(t);
  EXPECT_TRUE(v.ok) << v.detail;
  EXPECT_TRUE(v.detail.empty());
}

TEST(DdsValidation, RejectsEachBadTrajectoryNamingWhy) {
  struct Case {
    const char* what;
    Trajectory t;
    Rejection reason;
    const char* named;  // the detail must contain it
  };
  Case cases[] = {
      {"an unknown joint",
       {{"hip", "ankle"}, {{0, 0}}, {}, {0}},
       Rejection::kUnknownValue,
       "ankle"},
      {"a joint twice", {{"hip", "hip"}, {{0, 0}}, {}, {0}}, Rejection::kDuplicateName, "hip"},
      {"a joint missing", {{"hip"}, {{0}}, {}, {0}}, Rejection::kLengthMismatch, "joint_names"},
      {"too many points",
       {{"hip", "knee"}, {{0, 0}, {0, 0}, {0, 0}, {0, 0}, {0, 0}}, {}, {0, 1, 2, 3, 4}},
       Rejection::kTooLarge,
       "5 points"},
      {"a short position array",
       {{"hip", "knee"}, {{0}}, {}, {0}},
       Rejection::kLengthMismatch,
       "positions"},
      {"a short velocity array",
       {{"hip", "knee"}, {{0, 0}}, {{0}}, {0}},
       Rejection::kLengthMismatch,
       "velocities"},
      {"a NaN position",
       {{"hip", "knee"}, {{0, kNaN}}, {}, {0}},
       Rejection::kNotFinite,
       "positions[1]"},
      {"a knee beyond its range",
       {{"hip", "knee"}, {{0, 0.5}}, {}, {0}},
       Rejection::kOutOfRange,
       "knee"},
      {"a fast given velocity",
       {{"hip", "knee"}, {{0, 0}}, {{6, 0}}, {0}},
       Rejection::kRateLimit,
       "hip"},
      {"a fast segment",
       {{"hip", "knee"}, {{0, 0}, {0.9, 0}}, {}, {0, 0.1}},
       Rejection::kRateLimit,
       "between points[0] and [1]"},
      {"time going back",
       {{"hip", "knee"}, {{0, 0}, {0, 0}}, {}, {1, 0.5}},
       Rejection::kNotIncreasing,
       "points[1]"},
      {"a time beyond the longest",
       {{"hip", "knee"}, {{0, 0}}, {}, {11}},
       Rejection::kOutOfRange,
       "time_from_start"},
  };
  for (Case& c : cases) {
    const dds::Verdict v = check(c.t);
    EXPECT_FALSE(v.ok) << c.what;
    EXPECT_EQ(v.reason, c.reason) << c.what << ": " << dds::rejection_name(v.reason);
    EXPECT_NE(v.detail.find(c.named), std::string::npos) << c.what << ": " << v.detail;
  }
}

TEST(DdsValidation, StampsAreZeroOrNearThisClockWithNanosecondsBelowASecond) {
  const dds::StampPolicy policy{10.0};
  EXPECT_TRUE(dds::check_stamp({0, 0}, kNow, policy).ok) << "unstamped";
  EXPECT_TRUE(dds::check_stamp(dds::from_seconds<msg::Time>(kNow - 9.9), kNow, policy).ok);
  EXPECT_TRUE(dds::check_stamp(dds::from_seconds<msg::Time>(kNow + 9.9), kNow, policy).ok);
  EXPECT_EQ(dds::check_stamp(dds::from_seconds<msg::Time>(kNow + 10.1), kNow, policy).reason,
            Rejection::kBadTimeStamp);
  EXPECT_EQ(dds::check_stamp(dds::from_seconds<msg::Time>(kNow - 3600), kNow, policy).reason,
            Rejection::kBadTimeStamp);
  const dds::Verdict v = dds::check_stamp({5, 1000000000u}, kNow, policy);
  EXPECT_EQ(v.reason, Rejection::kBadTimeStamp);
  EXPECT_NE(v.detail.find("nanosec"), std::string::npos) << v.detail;
}

TEST(DdsValidation, ModeCommandsNeedAKnownModeAndStrategy) {
  const char* strategies[] = {"slow", "fast"};
  msg::ModeCommand c{};
  c.mode = 2;
  c.strategy = dds::borrow("fast");
  EXPECT_TRUE(dds::validate(c, strategies, 2, kNow, {}).ok);
  c.mode = 4;
  EXPECT_EQ(dds::validate(c, strategies, 2, kNow, {}).reason, Rejection::kUnknownValue);
  c.mode = 1;
  c.strategy = dds::borrow("Fast");
  const dds::Verdict v = dds::validate(c, strategies, 2, kNow, {});
  EXPECT_EQ(v.reason, Rejection::kUnknownValue);
  EXPECT_NE(v.detail.find("slow, fast"), std::string::npos) << "lists the known: " << v.detail;
  c.strategy = nullptr;
  EXPECT_EQ(dds::validate(c, strategies, 2, kNow, {}).reason, Rejection::kUnknownValue);
}

TEST(DdsValidation, CostWeightsAreKnownOnceFiniteAndInRange) {
  const dds::NamedRange known[] = {{"q_theta", 0, 1e6}, {"r_motor", 1e-6, 10}};
  const char* names[] = {"r_motor", "q_theta"};
  double values[] = {0.5, 1000};
  msg::CostWeights w{};
  w.names = dds::borrow(names, 2);
  w.values = dds::borrow(values, 2);
  EXPECT_TRUE(dds::validate(w, known, 2, kNow, {}).ok);
  w.names = dds::borrow(names, 1);
  w.values = dds::borrow(values, 1);
  EXPECT_TRUE(dds::validate(w, known, 2, kNow, {}).ok) << "a subset is fine";
  w.values = dds::borrow(values, 2);
  EXPECT_EQ(dds::validate(w, known, 2, kNow, {}).reason, Rejection::kLengthMismatch);
  w.names = dds::borrow(names, 2);
  values[0] = 0;
  EXPECT_EQ(dds::validate(w, known, 2, kNow, {}).reason, Rejection::kOutOfRange);
  values[0] = kNaN;
  EXPECT_EQ(dds::validate(w, known, 2, kNow, {}).reason, Rejection::kNotFinite);
  const char* twice[] = {"q_theta", "q_theta"};
  values[0] = 1;
  w.names = dds::borrow(twice, 2);
  EXPECT_EQ(dds::validate(w, known, 2, kNow, {}).reason, Rejection::kDuplicateName);
  const char* unknown[] = {"q_theta", "q_pressure"};
  w.names = dds::borrow(unknown, 2);
  EXPECT_EQ(dds::validate(w, known, 2, kNow, {}).reason, Rejection::kUnknownValue);
}

TEST(DdsValidation, TaskCommandsNameAKnownTaskAndOnlyItsParameters) {
  const dds::NamedRange squat[] = {{"hip_height", 0.4, 0.9}, {"period", 1.0, 10.0}};
  const dds::NamedRange walk[] = {{"speed", 0.0, 0.5}};
  const dds::TaskSpec tasks[] = {{"stand", nullptr, 0}, {"squat", squat, 2}, {"walk", walk, 1}};
  msg::TaskCommand c{};
  c.task = dds::borrow("stand");
  EXPECT_TRUE(dds::validate(c, tasks, 3, kNow, {}).ok) << "no parameters: the task's defaults";
  const char* names[] = {"period", "hip_height"};
  double values[] = {4.0, 0.7};
  c.task = dds::borrow("squat");
  c.parameter_names = dds::borrow(names, 2);
  c.parameter_values = dds::borrow(values, 2);
  EXPECT_TRUE(dds::validate(c, tasks, 3, kNow, {}).ok);
  c.task = dds::borrow("walk");
  dds::Verdict v = dds::validate(c, tasks, 3, kNow, {});
  EXPECT_EQ(v.reason, Rejection::kUnknownValue) << "walk takes no period";
  EXPECT_NE(v.detail.find("parameter_names[0] 'period' is not one of: speed"), std::string::npos)
      << v.detail;
  c.task = dds::borrow("jump");
  v = dds::validate(c, tasks, 3, kNow, {});
  EXPECT_EQ(v.reason, Rejection::kUnknownValue);
  EXPECT_NE(v.detail.find("task 'jump' is not one of: stand, squat, walk"), std::string::npos)
      << v.detail;
  c.task = nullptr;
  EXPECT_EQ(dds::validate(c, tasks, 3, kNow, {}).reason, Rejection::kUnknownValue);
  c.task = dds::borrow("squat");
  values[1] = 0.2;
  v = dds::validate(c, tasks, 3, kNow, {});
  EXPECT_EQ(v.reason, Rejection::kOutOfRange);
  EXPECT_NE(v.detail.find("parameter_values[1] (hip_height)"), std::string::npos) << v.detail;
  values[1] = kNaN;
  EXPECT_EQ(dds::validate(c, tasks, 3, kNow, {}).reason, Rejection::kNotFinite);
  values[1] = 0.7;
  c.parameter_values = dds::borrow(values, 1);
  EXPECT_EQ(dds::validate(c, tasks, 3, kNow, {}).reason, Rejection::kLengthMismatch);
  const char* twice[] = {"period", "period"};
  c.parameter_names = dds::borrow(twice, 2);
  c.parameter_values = dds::borrow(values, 2);
  EXPECT_EQ(dds::validate(c, tasks, 3, kNow, {}).reason, Rejection::kDuplicateName);
  c.parameter_names = dds::borrow(names, 2);
  c.header.stamp = dds::from_seconds<msg::Time>(kNow - 60.0);
  EXPECT_EQ(dds::validate(c, tasks, 3, kNow, {}).reason, Rejection::kBadTimeStamp);
}

TEST(DdsValidation, JointStatesNeedConsistentFiniteArrays) {
  const char* names[] = {"a", "b"};
  const double two[] = {0.1, 0.2};
  const double one[] = {0.1};
  const double bad[] = {0.1, kNaN};
  msg::JointState s{};
  s.name = dds::borrow(names, 2);
  s.position = dds::borrow(two, 2);
  EXPECT_TRUE(dds::validate(s, kNow, {}).ok) << "velocity and effort may be empty";
  s.velocity = dds::borrow(one, 1);
  EXPECT_EQ(dds::validate(s, kNow, {}).reason, Rejection::kLengthMismatch);
  s.velocity = dds::borrow(bad, 2);
  EXPECT_EQ(dds::validate(s, kNow, {}).reason, Rejection::kNotFinite);
}

TEST(DdsValidation, RejectCountersCountAndSummariseByReason) {
  dds::RejectCounters counters;
  EXPECT_EQ(counters.summary(), "none");
  counters.add(Rejection::kRateLimit);
  counters.add(Rejection::kNotFinite);
  counters.add(Rejection::kRateLimit);
  EXPECT_EQ(counters.total(), 3u);
  EXPECT_EQ(counters.count(Rejection::kRateLimit), 2u);
  EXPECT_EQ(counters.summary(), "not_finite=1 rate_limit=2");
}

// segment_bounds is exact: a dense sampling of the interpolant never goes beyond it and comes
// within the sampling's resolution of it.
TEST(JointTrajectory, SegmentBoundsAreTheInterpolantsExtremes) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-3, 3);
  for (int trial = 0; trial < 500; ++trial) {
    const bool hermite = trial % 4 != 0;
    const TrajectoryPoint a{0.2, u(rng), u(rng), hermite};
    const TrajectoryPoint b{0.2 + 0.05 + std::abs(u(rng)), u(rng), u(rng), hermite};
    const hmpc::trajectory::SegmentBounds bounds = hmpc::trajectory::segment_bounds(a, b);
    const hmpc::trajectory::SegmentCubic c(a, b);
    double lo = 1e9, hi = -1e9, speed = 0;
    for (int i = 0; i <= 20000; ++i) {
      const double s = i / 20000.0;
      lo = std::min(lo, c.position(s));
      hi = std::max(hi, c.position(s));
      speed = std::max(speed, std::abs(c.velocity(s)));
    }
    EXPECT_GE(lo, bounds.min_position - 1e-12) << trial;
    EXPECT_LE(hi, bounds.max_position + 1e-12) << trial;
    EXPECT_LE(speed, bounds.max_speed + 1e-9) << trial;
    EXPECT_NEAR(lo, bounds.min_position, 1e-6) << trial;
    EXPECT_NEAR(hi, bounds.max_position, 1e-6) << trial;
    EXPECT_NEAR(speed, bounds.max_speed, 1e-3) << trial;
  }
}

TEST(JointTrajectory, HermiteMeetsThePointsWithTheirVelocitiesAndHoldsTheEnds) {
  hmpc::trajectory::JointTrajectoryTarget target(3);
  const TrajectoryPoint points[] = {
      {0.5, 0.1, 1.0, true}, {1.5, 0.6, -0.5, true}, {2.0, 0.2, 0.0, false}};
  ASSERT_TRUE(target.assign(points, 3));
  EXPECT_EQ(target.position(0.0), 0.1) << "held before the first point";
  EXPECT_DOUBLE_EQ(target.position(0.5), 0.1);
  EXPECT_DOUBLE_EQ(target.position(1.5), 0.6);
  const double h = 1e-6;
  EXPECT_NEAR((target.position(0.5 + h) - target.position(0.5)) / h, 1.0, 1e-5);
  EXPECT_NEAR((target.position(1.5) - target.position(1.5 - h)) / h, -0.5, 1e-5);
  EXPECT_DOUBLE_EQ(target.position(1.75), 0.4) << "linear where a velocity is missing";
  EXPECT_EQ(target.position(9.0), 0.2) << "held after the last point";
  EXPECT_FALSE(target.assign(points, 0));
  const TrajectoryPoint four[4] = {};
  EXPECT_FALSE(target.assign(four, 4)) << "beyond capacity";
  EXPECT_DOUBLE_EQ(target.position(1.5), 0.6) << "a refused assignment keeps the old";
}

// The forearm's joint range is the board's own, not a copy that could drift from it.
TEST(ForearmJointLimits, AreTheBoardsSoftwareLimits) {
  const hmpc::firmware::BoardConfig<double> board{};
  const dds::JointLimits& limits = dds::forearm_joint_limits();
  EXPECT_EQ(limits.min_position, board.theta_min);
  EXPECT_EQ(limits.max_position, board.theta_max);
  EXPECT_STREQ(limits.name, dds::kJointName);
  EXPECT_EQ(limits.max_speed, hmpc::forearm::kMaxTargetSpeed);
}

}  // namespace
