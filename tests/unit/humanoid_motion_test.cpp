// Motion files (motion.hpp): the shipped files hold Tables 2.2-2.3, the loader rejects bad
// files with the file, line and key, and the attitude quaternion keeps the flip count.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <initializer_list>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "hmpc/humanoid/motion.hpp"
#include "hmpc/humanoid/problem.hpp"

namespace {

using namespace hmpc::humanoid;

std::string motion_path(const std::string& name) {
  return std::string(HMPC_HUMANOID_MOTIONS) + "/" + name + ".motion";
}

// One phase per row of {start, roll, pitch, yaw, height, v_x, v_y, v_z}.
struct Row {
  double start, roll, pitch, yaw, height, vx, vy, vz;
};

void expect_schedule(const std::string& name, const std::vector<Row>& rows) {
  SCOPED_TRACE(name);
  const Motion m = load_motion(motion_path(name));
  ASSERT_EQ(m.phase_count, static_cast<int>(rows.size()));
  for (int i = 0; i < m.phase_count; ++i) {
    const Phase& p = m.phases[i];
    const Row& r = rows[i];
    EXPECT_DOUBLE_EQ(p.start, r.start) << "phase " << i + 1;
    EXPECT_NEAR((p.attitude - Eigen::Vector3d(r.roll, r.pitch, r.yaw)).norm(), 0.0, 1e-12)
        << "phase " << i + 1;
    EXPECT_DOUBLE_EQ(p.height, r.height) << "phase " << i + 1;
    EXPECT_NEAR((p.velocity - Eigen::Vector3d(r.vx, r.vy, r.vz)).norm(), 0.0, 1e-12)
        << "phase " << i + 1;
  }
  EXPECT_GT(m.duration, rows.back().start);
}

TEST(HumanoidMotion, ShippedFilesHoldTable22) {
  expect_schedule("I-standing", {{0, 0, 0, 0, 0.85, 0, 0, 0}});
  expect_schedule("II-walking", {{0, 0, 0, 0, 0.85, 1.2, 0, 0}});
  expect_schedule("III-running", {{0, 0, 0, 0, 0.85, 2.0, 0, 0}});
}

TEST(HumanoidMotion, ShippedFilesHoldTable23OrOurDocumentedChanges) {
  const double pi = M_PI;
  expect_schedule("IV-sitting", {{0, 0, 0, 0, 0.65, -1.5, 0, 0},
                                 {0.3, 0, 0, 0, 0.65, 0, 0, 0},
                                 {1.5, 0, 0, 0, 0.85, 1.5, 0, 0},
                                 {1.8, 0, 0, 0, 0.85, 0, 0, 0}});
  // V and VI jump to 1.05 m, not Table 2.3's unreachable 1.8 m (see the files' comments).
  expect_schedule("V-low-jump", {{0, 0, 0, 0, 0.85, 0, 0, 0},
                                 {0.4, 0, 0, 0, 1.05, 0, 0, 0},
                                 {0.8, 0, 0, 0, 0.75, 0, 0, 0},
                                 {1.5, 0, 0, 0, 0.85, 0, 0, 0}});
  expect_schedule("VI-half-turn-jump", {{0, 0, 0, 0, 0.85, 0, 0, 0},
                                        {0.4, 0, 0, pi, 1.05, 0, 0, 0},
                                        {0.8, 0, 0, pi, 0.75, 0, 0, 0},
                                        {1.5, 0, 0, pi, 0.85, 0, 0, 0}});
  // VII crouches to 0.6 m and jumps to 1.2 m (see the file's comments).
  expect_schedule("VII-high-jump", {{0, 0, 0, 0, 0.6, 2.0, 0, 0},
                                    {0.4, 0, 0, 0, 1.2, 0, 0, 0},
                                    {0.8, 0, 0, 0, 0.75, 0, 0, 0},
                                    {1.5, 0, 0, 0, 0.85, 0, 0, 0}});
  // Six phases: execution and landing repeated one turn on; the landing between the flips
  // crouches to 0.6 m, not 0.75 m (see the file's comment).
  expect_schedule("VIII-double-flip", {{0, 0, 0, 0, 0.0, 2.0, 0, 0},
                                       {0.4, 0, 1.5 * pi, 0, 1.9, 0, 0, 0},
                                       {0.6, 0, 2.0 * pi, 0, 0.6, 0, 0, 0},
                                       {1.7, 0, 3.5 * pi, 0, 1.9, 0, 0, 0},
                                       {2.2, 0, 4.0 * pi, 0, 0.75, 0, 0, 0},
                                       {2.8, 0, 4.0 * pi, 0, 0.85, 0, 0, 0}});
  const Motion sitting = load_motion(motion_path("IV-sitting"));
  EXPECT_TRUE(sitting.chair);
  EXPECT_LT(sitting.seat_x_min, sitting.seat_x_max);
  EXPECT_FALSE(load_motion(motion_path("V-low-jump")).chair);
}

TEST(HumanoidMotion, WeightsAreRead) {
  const Motion m = load_motion(motion_path("I-standing"));
  for (double w : m.weights.control) EXPECT_GT(w, 0.0);
  EXPECT_GT(m.weights.height, 0.0);
  EXPECT_GT(m.weights.attitude.minCoeff(), 0.0);
  EXPECT_GT(m.weights.fast, 0.0);
}

TEST(HumanoidMotion, PhaseAtPicksTheLatestStarted) {
  const Motion m = load_motion(motion_path("V-low-jump"));
  EXPECT_DOUBLE_EQ(m.phase_at(-1.0).height, 0.85);
  EXPECT_DOUBLE_EQ(m.phase_at(0.39).height, 0.85);
  EXPECT_DOUBLE_EQ(m.phase_at(0.4).height, 1.05);
  EXPECT_DOUBLE_EQ(m.phase_at(1.0).height, 0.75);
  EXPECT_DOUBLE_EQ(m.phase_at(100.0).height, 0.85);
  Motion one = m;
  one.phase_count = 1;
  EXPECT_DOUBLE_EQ(one.phase_at(1.0).height, 0.85);
}

void expect_same_motion(const Motion& a, const Motion& b) {
  EXPECT_EQ(a.duration, b.duration);
  EXPECT_EQ(a.model_substep, b.model_substep);
  EXPECT_EQ(a.chair, b.chair);
  EXPECT_EQ(a.seat_height, b.seat_height);
  EXPECT_EQ(a.seat_x_min, b.seat_x_min);
  EXPECT_EQ(a.seat_x_max, b.seat_x_max);
  EXPECT_EQ(a.gait.period, b.gait.period);
  EXPECT_EQ(a.gait.swing_height, b.gait.swing_height);
  EXPECT_EQ(a.gait.swing_fraction, b.gait.swing_fraction);
  const CostWeights &u = a.weights, &v = b.weights;
  EXPECT_EQ(u.control, v.control);
  EXPECT_EQ(u.attitude, v.attitude);
  EXPECT_EQ(u.height, v.height);
  EXPECT_EQ(u.velocity, v.velocity);
  EXPECT_EQ(u.alpha, v.alpha);
  EXPECT_EQ(u.beta, v.beta);
  EXPECT_EQ(u.angular_velocity, v.angular_velocity);
  EXPECT_EQ(u.fast, v.fast);
  EXPECT_EQ(u.fast_control, v.fast_control);
  EXPECT_EQ(u.foot, v.foot);
  EXPECT_EQ(u.position, v.position);
  EXPECT_EQ(u.joint_velocity, v.joint_velocity);
  EXPECT_EQ(u.torque_change, v.torque_change);
  EXPECT_EQ(a.reach.active, b.reach.active);
  EXPECT_EQ(a.reach.target, b.reach.target);
  EXPECT_EQ(a.reach.start, b.reach.start);
  EXPECT_EQ(a.reach.weight, b.reach.weight);
  EXPECT_EQ(a.reach.control, b.reach.control);
  ASSERT_EQ(a.phase_count, b.phase_count);
  for (int k = 0; k < a.phase_count; ++k) {
    EXPECT_EQ(a.phases[k].start, b.phases[k].start) << "phase " << k;
    EXPECT_EQ(a.phases[k].attitude, b.phases[k].attitude) << "phase " << k;
    EXPECT_EQ(a.phases[k].height, b.phases[k].height) << "phase " << k;
    EXPECT_EQ(a.phases[k].velocity, b.phases[k].velocity) << "phase " << k;
    EXPECT_EQ(a.phases[k].squat_depth, b.phases[k].squat_depth) << "phase " << k;
    EXPECT_EQ(a.phases[k].squat_period, b.phases[k].squat_period) << "phase " << k;
  }
}

Motion written_and_read(const Motion& m) {
  std::stringstream file;
  write_motion(file, m, "a comment\non two lines");
  return parse_motion(file, "written");
}

TEST(HumanoidMotion, WrittenMotionsReadBackExactly) {
  for (const char* name : {"II-walking", "IV-sitting", "V-low-jump", "VIII-double-flip", "reaching",
                           "squatting", "slow-squat", "hip-hold", "hip-squat"}) {
    SCOPED_TRACE(name);
    const Motion m = load_motion(motion_path(name));
    expect_same_motion(m, written_and_read(m));
  }
  // A demonstration's targets: one phase per 30 ms step, every number with all its digits.
  Motion m = load_motion(motion_path("V-low-jump"));
  m.model_substep = 0.004;
  m.phase_count = kMaxPhases;
  for (int k = 0; k < kMaxPhases; ++k) {
    m.phases[k].start = 0.03 * k;
    m.phases[k].attitude = Eigen::Vector3d(std::sin(k), 0.1 / (k + 3.0), -M_PI / (k + 1));
    m.phases[k].height = 0.8 + 1e-3 * std::cos(k) + 1e-17;
    m.phases[k].velocity = Eigen::Vector3d(1.0 / 3.0, -k * 1e-9, 2.0 / 7.0);
  }
  m.duration = 0.03 * kMaxPhases;
  const Motion read = written_and_read(m);
  expect_same_motion(m, read);
  EXPECT_EQ(read.phase_at(0.03 * 100 + 1e-9).height, m.phases[100].height);
}

TEST(HumanoidMotion, RejectsMoreThanMaxPhases) {
  Motion m = load_motion(motion_path("V-low-jump"));
  m.phase_count = kMaxPhases;
  for (int k = 0; k < kMaxPhases; ++k) m.phases[k] = m.phases[0], m.phases[k].start = 0.03 * k;
  std::stringstream file;
  write_motion(file, m, "");
  file.seekp(0, std::ios::end);
  file << "\n[phase]\nstart = 100\nattitude = 0 0 0\nheight = 0.85\nvelocity = 0 0 0\n";
  try {
    parse_motion(file, "long.motion");
    FAIL() << "accepted " << kMaxPhases + 1 << " phases";
  } catch (const MotionFileError& e) {
    EXPECT_NE(std::string(e.what()).find("more than " + std::to_string(kMaxPhases) + " phases"),
              std::string::npos)
        << e.what();
  }
}

TEST(HumanoidMotion, AttitudeQuaternionMatchesEulerComposition) {
  const Eigen::Vector3d a(0.3, -0.7, 2.1);
  const Eigen::Quaterniond expected = Eigen::AngleAxisd(a.z(), Eigen::Vector3d::UnitZ()) *
                                      Eigen::AngleAxisd(a.y(), Eigen::Vector3d::UnitY()) *
                                      Eigen::AngleAxisd(a.x(), Eigen::Vector3d::UnitX());
  const Eigen::Vector4d q = attitude_quaternion(a);
  EXPECT_NEAR((q - Eigen::Vector4d(expected.w(), expected.x(), expected.y(), expected.z())).norm(),
              0.0, 1e-14);
  // One full flip is the quaternion -1, two are +1: Eq. 4.25 counts turns modulo two.
  EXPECT_NEAR((attitude_quaternion({0, 2 * M_PI, 0}) - Eigen::Vector4d(-1, 0, 0, 0)).norm(), 0,
              1e-15);
  EXPECT_NEAR((attitude_quaternion({0, 4 * M_PI, 0}) - Eigen::Vector4d(1, 0, 0, 0)).norm(), 0,
              1e-15);
}

// A valid file, edited per case below.
const std::string kValid = R"(# comment
hmpc-humanoid-motion 1
[motion]
duration = 1.0
chair = none
gait = none
[weights]
w_HAA = 1
w_HFE = 1
w_KFE = 1
w_AFE = 1
w_q1 = 1
w_q2 = 1
w_q3 = 1
w_q4 = 1
w_height = 1
w_vx = 1
w_vy = 1
w_vz = 1
w_alpha = 1
w_beta = 1
w_omega_x = 1
w_omega_y = 1
w_omega_z = 1
w_fast = 1
w_fast_control = 1
w_foot = 1
[phase]
start = 0
attitude = 0 0 pi   # yaw half a turn
height = 0.85
velocity = 0 0 0
[phase]
start = 0.5
attitude = 0 -1.5pi 0
height = 0.75
velocity = 1 0 0
)";

Motion parse(const std::string& text) {
  std::istringstream in(text);
  return parse_motion(in, "test.motion");
}

std::string replace(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

// The error message of parsing `text`, or "" if it parses.
std::string error_of(const std::string& text) {
  try {
    parse(text);
  } catch (const MotionFileError& e) {
    return e.what();
  }
  return "";
}

TEST(HumanoidMotion, ParsesTheValidFile) {
  const Motion m = parse(kValid);
  ASSERT_EQ(m.phase_count, 2);
  EXPECT_DOUBLE_EQ(m.phases[0].attitude.z(), M_PI);
  EXPECT_DOUBLE_EQ(m.phases[1].attitude.y(), -1.5 * M_PI);
  EXPECT_DOUBLE_EQ(m.phases[1].velocity.x(), 1.0);
  EXPECT_FALSE(m.chair);
  const Motion chair = parse(replace(kValid, "chair = none", "chair = 0.5 -0.6 -0.1"));
  EXPECT_TRUE(chair.chair);
  EXPECT_DOUBLE_EQ(chair.seat_height, 0.5);
  EXPECT_DOUBLE_EQ(chair.seat_x_max, -0.1);
  EXPECT_EQ(m.gait.period, 0.0);
  EXPECT_DOUBLE_EQ(m.weights.foot, 1.0);
  const Motion gait = parse(replace(kValid, "gait = none", "gait = 0.6 0.05 0.4"));
  EXPECT_DOUBLE_EQ(gait.gait.period, 0.6);
  EXPECT_DOUBLE_EQ(gait.gait.swing_height, 0.05);
  EXPECT_DOUBLE_EQ(gait.gait.swing_fraction, 0.4);
}

// The optional [reach] section (Eq. 2.53): read into Motion::reach; without it, no reaching.
const std::string kReach = kValid + R"([reach]
target = 0.7 -0.12 0.7
start = 0.8
w_reach = 1e4
w_SFE = 1e-3
)";

TEST(HumanoidMotion, ReadsTheReachSection) {
  EXPECT_FALSE(parse(kValid).reach.active);
  const Motion m = parse(kReach);
  ASSERT_TRUE(m.reach.active);
  EXPECT_EQ(m.reach.target, Eigen::Vector3d(0.7, -0.12, 0.7));
  EXPECT_DOUBLE_EQ(m.reach.start, 0.8);
  EXPECT_DOUBLE_EQ(m.reach.weight, 1e4);
  EXPECT_DOUBLE_EQ(m.reach.control, 1e-3);
  for (const auto& [text, expected] : std::initializer_list<std::pair<std::string, std::string>>{
           {replace(kReach, "w_SFE = 1e-3\n", ""), "w_SFE: missing key in [reach]"},
           {replace(kReach, "start = 0.8", "start = -1"), "start: must be >= 0"},
           {replace(kReach, "w_reach = 1e4", "w_reach = -1"), "w_reach: a weight must be >= 0"},
           {replace(kReach, "target = 0.7 -0.12 0.7", "target = 0.7 -0.12"),
            "target: expected 3 numbers"},
           {kReach + "[reach]\ntarget = 0 0 0\nstart = 0\nw_reach = 1\nw_SFE = 1\n",
            "section [reach] repeated"}}) {
    const std::string message = error_of(text);
    EXPECT_NE(message.find(expected), std::string::npos)
        << "got '" << message << "', expected '" << expected << "'";
  }
}

// A reaching motion needs the robot with an arm, and that robot runs nothing else: a clear
// error, not a cost without its hand term.
TEST(HumanoidMotion, ReachingAndTheRobotMustMatch) {
  const ProblemConfig config;
  EXPECT_THROW(StateCost(parse(kReach), standing_state(config, 0.85), config),
               std::invalid_argument);
  EXPECT_THROW(BasicStateCost<1>(parse(kValid), standing_state<1>(config, 0.85), config),
               std::invalid_argument);
  EXPECT_NO_THROW(BasicStateCost<1>(parse(kReach), standing_state<1>(config, 0.85), config));
}

// The optional model sub-step: left out, the MPC's model keeps ProblemConfig's; given, the
// MPC's model (model_config) uses it, and nothing else changes.
TEST(HumanoidMotion, ModelSubstepIsOptionalAndReachesTheMpcModel) {
  const ProblemConfig defaults;
  const Motion plain = parse(kValid);
  EXPECT_EQ(plain.model_substep, 0.0);
  EXPECT_EQ(model_config(plain, defaults).max_substep, defaults.max_substep);
  const Motion fine = parse(replace(kValid, "gait = none", "gait = none\nmodel_substep = 0.001"));
  EXPECT_DOUBLE_EQ(fine.model_substep, 0.001);
  const ProblemConfig model = model_config(fine, defaults);
  EXPECT_DOUBLE_EQ(model.max_substep, 0.001);
  EXPECT_EQ(model.step, defaults.step);
  EXPECT_EQ(model.contact.stiffness, defaults.contact.stiffness);
  const Motion chair = parse(replace(kValid, "chair = none", "chair = 0.5 -0.6 -0.1"));
  EXPECT_TRUE(model_config(chair, defaults).contact.chair);
  EXPECT_DOUBLE_EQ(model_config(chair, defaults).contact.seat_height, 0.5);
}

// Sec. 2.7.3's two terms are optional weights: 0 left out (every motion of Tables 2.2-2.3),
// read when given, and checked as every weight is.
TEST(HumanoidMotion, Sec273WeightsAreOptional) {
  const Motion plain = parse(kValid);
  EXPECT_EQ(plain.weights.position, 0.0);
  EXPECT_EQ(plain.weights.joint_velocity, 0.0);
  EXPECT_EQ(plain.weights.torque_change, 0.0);
  const Motion held = parse(
      replace(kValid, "w_foot = 1",
              "w_foot = 1\nw_position = 400\nw_joint_velocity = 0.1\nw_torque_change = 0.02"));
  EXPECT_EQ(held.weights.position, 400.0);
  EXPECT_EQ(held.weights.joint_velocity, 0.1);
  EXPECT_EQ(held.weights.torque_change, 0.02);
  EXPECT_EQ(load_motion(motion_path("hip-hold")).weights.position, 2500.0);
  EXPECT_EQ(load_motion(motion_path("hip-squat")).weights.torque_change, 0.01);
  for (const std::string key : {"w_position", "w_torque_change"}) {
    try {
      parse(replace(kValid, "w_foot = 1", "w_foot = 1\n" + key + " = -1"));
      ADD_FAILURE() << "a negative " << key << " was accepted";
    } catch (const MotionFileError& e) {
      EXPECT_NE(std::string(e.what()).find(key + ": a weight must be >= 0"), std::string::npos)
          << e.what();
    }
  }
}

TEST(HumanoidMotion, GaitSwingsTheFeetInTurn) {
  const Gait gait{0.6, 0.05, 0.4};  // each foot swings 0.24 s of each 0.6 s stride
  // Left foot: swings over [0, 0.24) of each period, at its apex half-way.
  EXPECT_NEAR(gait.foot_height(0.12, 0), 0.05, 1e-12);
  EXPECT_NEAR(gait.foot_height(0.6 + 0.06, 0), 0.05 * std::sin(M_PI * 0.25), 1e-12);
  EXPECT_EQ(gait.foot_height(0.25, 0), 0.0);
  EXPECT_EQ(gait.foot_height(0.42, 0), 0.0);
  // Right foot: half a period later; both stand in between (double support).
  EXPECT_EQ(gait.foot_height(0.12, 1), 0.0);
  EXPECT_NEAR(gait.foot_height(0.42, 1), 0.05, 1e-12);
  EXPECT_EQ(gait.foot_height(0.27, 1), 0.0);
  // No gait: both feet down.
  EXPECT_EQ(Gait{}.foot_height(0.12, 0), 0.0);
}

// A squat phase: p_z = height - depth (1 - cos(2 pi (t - start) / T)) / 2, at rest where it
// starts, at its depth half a period later, and its rate added to the velocity target.
TEST(HumanoidMotion, ASquatPhaseLowersTheHeightTargetSinusoidally) {
  const Motion m = load_motion(motion_path("slow-squat"));
  ASSERT_EQ(m.phase_count, 2);
  const Phase& squat = m.phase_at(1.0);
  EXPECT_EQ(squat.squat_depth, 0.04);
  EXPECT_EQ(squat.squat_period, 4.0);
  EXPECT_DOUBLE_EQ(squat.height_at(1.0), 0.85);
  EXPECT_NEAR(squat.height_at(3.0), 0.81, 1e-12);
  EXPECT_NEAR(squat.height_at(5.0), 0.85, 1e-12);
  EXPECT_NEAR(squat.height_at(2.0), 0.83, 1e-12);
  for (double t : {1.0, 1.7, 2.5, 3.0, 4.2}) {
    const double h = 1e-6;
    const double rate = (squat.height_at(t + h) - squat.height_at(t - h)) / (2 * h);
    EXPECT_NEAR(squat.velocity_at(t).z(), squat.velocity.z() + rate, 1e-8) << t;
    EXPECT_EQ(squat.velocity_at(t).head<2>(), squat.velocity.head<2>()) << t;
  }
  // Without a squat the targets are the phase's own.
  const Phase& still = m.phase_at(0.5);
  EXPECT_EQ(still.height_at(0.7), still.height);
  EXPECT_EQ(still.velocity_at(0.7), still.velocity);
}

struct BadCase {
  const char* what;
  std::string text;
  std::string expected;  // the message must contain "test.motion:<line>: <key>" and this
};

TEST(HumanoidMotion, RejectsBadFilesNamingFileLineAndKey) {
  const std::vector<BadCase> cases{
      {"unknown key", replace(kValid, "w_vz = 1", "w_vw = 1"), "test.motion:19: w_vw: unknown key"},
      {"missing key", replace(kValid, "w_beta = 1\n", ""), "test.motion:7: w_beta: missing key"},
      {"negative weight", replace(kValid, "w_height = 1", "w_height = -2"),
       "test.motion:16: w_height: a weight must be >= 0"},
      {"nan weight", replace(kValid, "w_alpha = 1", "w_alpha = nan"),
       "test.motion:20: w_alpha: not finite"},
      {"infinite weight", replace(kValid, "w_q2 = 1", "w_q2 = inf"),
       "test.motion:13: w_q2: not finite"},
      {"phases out of order", replace(kValid, "start = 0.5", "start = 0"),
       "test.motion:34: start: phases out of order"},
      {"first phase late", replace(kValid, "start = 0\n", "start = 0.1\n"),
       "test.motion:29: start: the first phase must start at 0"},
      {"duplicate key", replace(kValid, "w_KFE = 1", "w_HFE = 2"),
       "test.motion:10: w_HFE: duplicate key"},
      {"garbage number", replace(kValid, "height = 0.85", "height = 0.8x"),
       "test.motion:31: height: not a number"},
      {"wrong count", replace(kValid, "velocity = 1 0 0", "velocity = 1 0"),
       "test.motion:37: velocity: expected 3 numbers"},
      {"missing value", replace(kValid, "duration = 1.0", "duration ="),
       "test.motion:4: duration: missing value"},
      {"zero duration", replace(kValid, "duration = 1.0", "duration = 0"),
       "test.motion:4: duration: must be > 0"},
      {"bad chair", replace(kValid, "chair = none", "chair = 0.5 0.2 0.1"),
       "test.motion:5: chair: expected"},
      {"bad gait", replace(kValid, "gait = none", "gait = 0.6 0.05 1.5"),
       "test.motion:6: gait: expected"},
      {"short gait", replace(kValid, "gait = none", "gait = 0.6 0.05"),
       "test.motion:6: gait: expected 3 numbers"},
      {"zero model sub-step", replace(kValid, "gait = none", "gait = none\nmodel_substep = 0"),
       "test.motion:7: model_substep: must be > 0 s and at most 0.01 s"},
      {"unstable model sub-step",
       replace(kValid, "gait = none", "gait = none\nmodel_substep = 0.02"),
       "test.motion:7: model_substep: must be > 0 s and at most 0.01 s"},
      {"squat without a period",
       replace(kValid, "velocity = 1 0 0", "velocity = 1 0 0\nsquat = 0.04 0"),
       "test.motion:38: squat: the period must be > 0"},
      {"squat with one number",
       replace(kValid, "velocity = 1 0 0", "velocity = 1 0 0\nsquat = 0.04"),
       "test.motion:38: squat: expected 2 numbers"},
      {"bad version", replace(kValid, "hmpc-humanoid-motion 1", "hmpc-humanoid-motion 2"),
       "test.motion:2: expected the version line"},
      {"unknown section", replace(kValid, "[weights]", "[weight]"),
       "test.motion:7: unknown section [weight]"},
      {"no phase", kValid.substr(0, kValid.find("[phase]")),
       "test.motion: missing section [phase]"},
      {"setting outside a section", replace(kValid, "[motion]\n", ""),
       "test.motion:3: duration: setting outside"},
  };
  for (const BadCase& c : cases) {
    const std::string message = error_of(c.text);
    EXPECT_NE(message.find(c.expected), std::string::npos)
        << c.what << ": got '" << message << "', expected it to contain '" << c.expected << "'";
  }
}

TEST(HumanoidMotion, MissingFileIsAnErrorNamingIt) {
  try {
    load_motion("/nonexistent/x.motion");
    FAIL() << "no error";
  } catch (const MotionFileError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/x.motion"), std::string::npos);
  }
}

}  // namespace
