// The humanoid's host controller on DDS over loopback: its topics carry the standard types with
// what the controller has; mode commands run, hold and stop it, and a commander who leaves
// hands the robot back to its boards' hold; a task command switches the MPC to the squat; learned
// weights are adopted; malformed commands, tasks and weights are rejected, counted by reason,
// and change nothing. The robot is the whole chain in one process (plant, boards, host:
// humanoid_in_process.hpp), the bridge polled before each host tick and publishing after it.
#include "hmpc/dds/humanoid_dds.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "hmpc/dds/cost_weights.hpp"
#include "hmpc/dds/endpoint.hpp"
#include "hmpc/humanoid/motion.hpp"
#include "hmpc/ioc/weights.hpp"
#include "humanoid_in_process.hpp"

namespace {

namespace dds = hmpc::dds;
namespace hm = hmpc::humanoid;
namespace jp = hmpc::joint_protocol;
using hmpc::host::HostPhase;
using hmpc::host::HumanoidHostConfig;
using hmpc::test::HumanoidInProcess;

// Domains 107..110: no other test uses them (tests/dds/CMakeLists.txt lists them all).
constexpr std::uint32_t kTopicsDomain = 107, kModesDomain = 108, kRejectsDomain = 109,
                        kWeightsDomain = 110;
// A host tick under a sanitizer may take longer than the real deadline of wall time; the
// commander's leaving, not its deadline, is what these tests take away (the deadline itself:
// forearm_dds_bridge_test, the same reader).
constexpr double kTestDeadlineS = 60;
constexpr double kPatienceS = 30;

hm::Motion motion(const char* name) {
  return hm::load_motion(hm::motion_path(name, HMPC_HUMANOID_MOTIONS));
}

// The robot in one process with the bridge on `domain`.
struct Rig {
  Rig(std::uint32_t domain, const HumanoidHostConfig& config, const hm::Motion& task)
      : robot(config, task), bridge(domain, dds::HumanoidTaskLimits::around(task.phases[0].height),
                                    dds::loopback_config(), {}, kTestDeadlineS) {}

  void tick() {
    bridge.poll(robot.host());
    robot.tick();
    EXPECT_TRUE(bridge.publish(robot.host(), robot.ticks() - 1));
  }
  void run(double seconds) {
    for (int i = 0; i < int(std::lround(seconds * 1e3)); ++i) tick();
  }
  // Ticks until `done` or `most` ticks; how many it took, or -1.
  template <class Done>
  int until(Done&& done, int most) {
    for (int i = 0; i < most; ++i) {
      if (done()) return i;
      tick();
    }
    return done() ? most : -1;
  }

  HumanoidInProcess robot;
  dds::HumanoidDdsBridge bridge;
};

HumanoidHostConfig host_config(double hold_seconds) {
  HumanoidHostConfig c;
  c.hold_seconds = hold_seconds;
  c.solve_time = hmpc::host::SolveTime::kModel;  // the same plans however slow the build
  return c;
}

// An operator's writers, as a ROS 2 node would have them.
struct Operator {
  explicit Operator(std::uint32_t domain)
      : participant(domain, dds::loopback_config()),
        commands(participant, "/hmpc/humanoid/command", dds::Qos::command(kTestDeadlineS)),
        tasks(participant, "/hmpc/humanoid/task", dds::Qos::state()),
        weights(participant, dds::kHumanoidCostWeightsTopic, dds::Qos::state()) {}

  void mode(dds::CommandMode mode, const char* strategy = dds::kHumanoidStrategy) {
    dds::msg::ModeCommand c{};
    c.header.frame_id = dds::borrow("");
    c.sequence_number = ++sequence;
    c.mode = static_cast<std::uint8_t>(mode);
    c.strategy = dds::borrow(strategy);
    send(commands, c);
  }
  void task(const char* name, const std::vector<std::pair<const char*, double>>& parameters) {
    std::vector<const char*> names;
    std::vector<double> values;
    for (const auto& [n, v] : parameters) {
      names.push_back(n);
      values.push_back(v);
    }
    dds::msg::TaskCommand t{};
    t.header.frame_id = dds::borrow("");
    t.sequence_number = ++sequence;
    t.task = dds::borrow(name);
    t.parameter_names = dds::borrow(names.data(), names.size());
    t.parameter_values = dds::borrow(values.data(), values.size());
    send(tasks, t);
  }
  void weight_message(const std::vector<const char*>& names, const std::vector<double>& values) {
    dds::msg::CostWeights w{};
    w.header.frame_id = dds::borrow("");
    w.names = dds::borrow(names.data(), names.size());
    w.values = dds::borrow(values.data(), values.size());
    send(weights, w);
  }
  template <class Message>
  static void send(const dds::Writer<Message>& writer, const Message& m) {
    ASSERT_TRUE(writer.wait_for_reader(kPatienceS)) << writer.ros_name();
    ASSERT_TRUE(writer.write(m));
    ASSERT_TRUE(writer.wait_for_acks(kPatienceS));  // in the bridge's reader: its next poll
  }

  dds::Participant participant;
  dds::Writer<dds::msg::ModeCommand> commands;
  dds::Writer<dds::msg::TaskCommand> tasks;
  dds::Writer<dds::msg::CostWeights> weights;
  std::uint32_t sequence = 0;
};

bool is_symmetric_psd_diagonal(const double (&c)[36]) {
  for (int r = 0; r < 6; ++r) {
    if (!(c[r * 7] > 0)) return false;
    for (int k = 0; k < 6; ++k) {
      if (std::abs(c[r * 6 + k] - c[k * 6 + r]) > 1e-12 * (1 + std::abs(c[r * 6 + k]))) {
        return false;
      }
      // Every 2x2 principal minor of a covariance is non-negative.
      if (c[r * 6 + k] * c[r * 6 + k] > c[r * 7] * c[k * 7] * (1 + 1e-9)) return false;
    }
  }
  return true;
}

TEST(HumanoidDds, TheRobotIsOnTheStandardTopicsAndATaskSwitchesTheMpcToTheSquat) {
  Rig rig(kTopicsDomain, host_config(0.6), motion("hip-hold"));
  const dds::Participant reader_side(kTopicsDomain, dds::loopback_config());
  const dds::Reader<dds::msg::JointState> joints(reader_side, "/hmpc/humanoid/joint_states",
                                                 dds::Qos::state());
  const dds::Reader<dds::msg::Imu> imu(reader_side, "/hmpc/humanoid/imu", dds::Qos::sensor_data());
  const dds::Reader<dds::msg::Odometry> odometry(reader_side, "/hmpc/humanoid/odometry",
                                                 dds::Qos::state());
  const dds::Reader<dds::msg::MpcPlan> plans(reader_side, "/hmpc/humanoid/plan", dds::Qos::state());
  const dds::Reader<dds::msg::DiagnosticArray> diagnostics(reader_side, "/diagnostics",
                                                           dds::Qos::state());
  Operator op(kTopicsDomain);
  // Up, held, then the MPC for 0.3 s (hold 0.6 s after the bring-up).
  ASSERT_GE(rig.until([&] { return rig.robot.host().phase() == HostPhase::kMpc; }, 2000), 0);
  rig.run(0.3);
  const auto& host = rig.robot.host();
  ASSERT_EQ(host.phase(), HostPhase::kMpc) << host.reason();

  int joint_samples = 0;
  joints.take([&](const dds::msg::JointState& m) {
    ++joint_samples;
    ASSERT_EQ(m.name._length, std::uint32_t(hm::kLegJoints));
    for (int j = 0; j < hm::kLegJoints; ++j) {
      EXPECT_STREQ(m.name._buffer[j], hm::kLegJointNames[std::size_t(j)]);
    }
    EXPECT_EQ(m.position._length, std::uint32_t(hm::kLegJoints));
    EXPECT_EQ(m.velocity._length, std::uint32_t(hm::kLegJoints));
    EXPECT_EQ(m.effort._length, std::uint32_t(hm::kLegJoints));
    const dds::Verdict v = dds::validate(m, dds::unix_time_s(), {});
    EXPECT_TRUE(v.ok) << v.detail;
  });
  // Kept: the last 10 of the reliable topics (ROS 2's default depth).
  EXPECT_EQ(joint_samples, 10);

  int imu_samples = 0;
  imu.take([&](const dds::msg::Imu& m) {
    ++imu_samples;
    EXPECT_EQ(m.orientation_covariance[0], -1.0);  // no orientation from this IMU
    EXPECT_GT(m.angular_velocity_covariance[0], 0.0);
    // Standing: the specific force is gravity's, within the tilts and sways of a hold.
    const double g = std::sqrt(m.linear_acceleration.x * m.linear_acceleration.x +
                               m.linear_acceleration.y * m.linear_acceleration.y +
                               m.linear_acceleration.z * m.linear_acceleration.z);
    EXPECT_NEAR(g, 9.81, 1.0);
  });
  EXPECT_GE(imu_samples, 1);

  int odometry_samples = 0;
  const hm::BasicState<0> truth = rig.robot.plant().state();
  odometry.take([&](const dds::msg::Odometry& m) {
    ++odometry_samples;
    EXPECT_STREQ(m.header.frame_id, "odom");
    EXPECT_STREQ(m.child_frame_id, "torso");
    EXPECT_TRUE(is_symmetric_psd_diagonal(m.pose.covariance));
    EXPECT_TRUE(is_symmetric_psd_diagonal(m.twist.covariance));
    // Within 16 ms of the truth now, and the estimate within a centimetre (State estimation's
    // standing figures: 0.5 mm RMS).
    EXPECT_NEAR(m.pose.pose.position.z, truth.q[2], 0.01);
    const auto& o = m.pose.pose.orientation;
    const double norm = std::sqrt(o.w * o.w + o.x * o.x + o.y * o.y + o.z * o.z);
    EXPECT_NEAR(norm, 1.0, 1e-9);
  });
  EXPECT_EQ(odometry_samples, 10);

  std::uint32_t last_sequence = 0;
  int plan_samples = 0;
  double hold_descent = 0;  // m, over the horizon of the last plan before the squat
  plans.take([&](const dds::msg::MpcPlan& m) {
    ++plan_samples;
    EXPECT_GT(m.sequence_number, last_sequence);
    last_sequence = m.sequence_number;
    EXPECT_STREQ(m.controller, dds::kHumanoidStrategy);
    ASSERT_EQ(m.joints.points._length, std::uint32_t(hm::kCoarseHorizon + 1));
    ASSERT_EQ(m.base_poses._length, m.joints.points._length);
    ASSERT_EQ(m.base_twists._length, m.joints.points._length);
    ASSERT_EQ(m.joints.joint_names._length, std::uint32_t(hm::kLegJoints));
    for (std::uint32_t k = 0; k < m.joints.points._length; ++k) {
      // Sec. 2.7.3's upper layer: 12 ms apart.
      EXPECT_NEAR(dds::to_seconds(m.joints.points._buffer[k].time_from_start), 0.012 * k, 1e-9);
      EXPECT_EQ(m.joints.points._buffer[k].effort._length, std::uint32_t(hm::kLegJoints));
    }
    hold_descent =
        m.base_poses._buffer[0].position.z - m.base_poses._buffer[hm::kCoarseHorizon].position.z;
  });
  EXPECT_EQ(plan_samples, 10);
  EXPECT_EQ(last_sequence, host.last_plan().sequence);

  bool saw_mpc = false;
  diagnostics.take([&](const dds::msg::DiagnosticArray& m) {
    ASSERT_EQ(m.status._length, 1u);
    saw_mpc = saw_mpc || std::strcmp(m.status._buffer[0].message, "mpc") == 0;
  });
  EXPECT_TRUE(saw_mpc);

  // The squat, 2 cm every 2 s, from the hip's height now.
  op.task("squat", {{"depth", 0.02}, {"period", 2.0}});
  rig.tick();
  const hm::Phase& phase = host.task().phases[0];
  EXPECT_EQ(host.task().phase_count, 1);
  EXPECT_EQ(phase.squat_depth, 0.02);
  EXPECT_EQ(phase.squat_period, 2.0);
  EXPECT_EQ(rig.bridge.tasks(), 1u);
  EXPECT_LE(host.motion_time(rig.robot.ticks() - 1), 0.001);  // its clock starts on the command
  // Half a second in, the target sinks at pi/2 * 2 cm / 2 s = 3.1 cm/s: 3.8 mm over the 120 ms
  // horizon, where holding the plan's hip moved less than a millimetre.
  rig.run(0.5);
  EXPECT_LT(std::abs(hold_descent), 0.001);
  double squat_descent = 0;
  plans.take([&](const dds::msg::MpcPlan& m) {
    squat_descent =
        m.base_poses._buffer[0].position.z - m.base_poses._buffer[hm::kCoarseHorizon].position.z;
  });
  EXPECT_GT(squat_descent, 0.002);
  std::printf(
      "planned hip descent over the 120 ms horizon: %.2f mm holding, %.2f mm 0.5 s into "
      "the squat (target 3.8 mm)\n",
      1e3 * hold_descent, 1e3 * squat_descent);

  // Back to standing at the motion's height.
  op.task("stand", {});
  rig.tick();
  EXPECT_EQ(host.task().phases[0].squat_period, 0.0);
  EXPECT_EQ(host.task().phases[0].height, motion("hip-hold").phases[0].height);
  EXPECT_EQ(rig.bridge.rejects().total(), 0u) << rig.bridge.rejects().summary();
}

TEST(HumanoidDds, ModeCommandsRunHoldAndStopTheRobotAndALeavingCommanderHandsItToTheHold) {
  Rig rig(kModesDomain, host_config(10), motion("hip-hold"));
  const auto& host = rig.robot.host();
  auto op = std::make_unique<Operator>(kModesDomain);
  // Up and held until the estimator runs (its rest: the hold's first 0.5 s).
  ASSERT_GE(rig.until([&] { return host.estimating(); }, 3000), 0);
  ASSERT_EQ(host.phase(), HostPhase::kHolding);

  // Run: the MPC now, 9 s before its configured start.
  op->mode(dds::CommandMode::kRun);
  EXPECT_EQ(rig.until([&] { return host.phase() == HostPhase::kMpc; }, 2), 1);
  rig.run(0.1);
  EXPECT_GE(host.solves().size(), 8u);
  EXPECT_EQ(host.master().board(0).status.mode, jp::BoardMode::kRun);

  // Hold: the boards' posture hold, and it stays there.
  op->mode(dds::CommandMode::kHold);
  rig.tick();
  EXPECT_EQ(host.phase(), HostPhase::kHolding);
  const std::size_t solves = host.solves().size();
  rig.run(0.3);
  EXPECT_EQ(host.phase(), HostPhase::kHolding);
  EXPECT_EQ(host.solves().size(), solves);
  for (int b = 0; b < hm::kLegBoards; ++b) {
    EXPECT_EQ(host.master().board(b).status.mode, jp::BoardMode::kHold);
  }

  // Run again, then the commander leaves: back to the hold within its departure's news.
  op->mode(dds::CommandMode::kRun);
  EXPECT_EQ(rig.until([&] { return host.phase() == HostPhase::kMpc; }, 2), 1);
  rig.run(0.05);
  op.reset();
  EXPECT_GE(rig.until([&] { return host.phase() == HostPhase::kHolding; }, 5000), 0);
  EXPECT_EQ(rig.bridge.commander_silences(), 1u);

  // Idle: the E-stop; safe for good.
  Operator second(kModesDomain);
  second.mode(dds::CommandMode::kIdle);
  rig.tick();
  EXPECT_EQ(host.phase(), HostPhase::kSafe);
  EXPECT_EQ(host.reason(), "E-stop");
  second.mode(dds::CommandMode::kRun);
  rig.run(0.05);
  EXPECT_EQ(host.phase(), HostPhase::kSafe);
  EXPECT_EQ(rig.bridge.commands(), 5u);
  EXPECT_EQ(rig.bridge.rejects().total(), 0u) << rig.bridge.rejects().summary();
}

TEST(HumanoidDds, MalformedCommandsTasksAndWeightsAreRejectedAndChangeNothing) {
  const hm::Motion task = motion("hip-hold");
  hmpc::host::HumanoidHost host(host_config(10), task);
  dds::HumanoidDdsBridge bridge(kRejectsDomain, dds::HumanoidTaskLimits::around(0.85),
                                dds::loopback_config(), {}, kTestDeadlineS);
  Operator op(kRejectsDomain);
  const double nan = std::numeric_limits<double>::quiet_NaN();

  op.mode(dds::CommandMode::kRun, "two_stage");  // the forearm's strategy
  op.mode(static_cast<dds::CommandMode>(7));
  op.task("jump", {});
  op.task("squat", {{"depth", 0.05}});                     // deeper than 2 cm
  op.task("squat", {{"height", 0.835}, {"depth", 0.02}});  // below 0.83 m at the bottom
  op.task("stand", {{"depth", 0.01}});                     // not a stand's parameter
  op.task("stand", {{"height", nan}});
  op.weight_message({"w_height"}, {nan});
  op.weight_message({"w_foo"}, {1.0});
  op.weight_message({"w_height"}, {-1.0});
  op.weight_message({"w_height"}, {2e6});
  op.weight_message({"w_height", "w_vx"}, {1.0});
  op.weight_message({"w_height", "w_height"}, {1.0, 2.0});
  bridge.poll(host);

  const dds::RejectCounters& r = bridge.rejects();
  EXPECT_EQ(r.total(), 13u) << r.summary();
  EXPECT_EQ(r.count(dds::Rejection::kUnknownValue), 5u) << r.summary();
  EXPECT_EQ(r.count(dds::Rejection::kOutOfRange), 4u) << r.summary();
  EXPECT_EQ(r.count(dds::Rejection::kNotFinite), 2u) << r.summary();
  EXPECT_EQ(r.count(dds::Rejection::kLengthMismatch), 1u) << r.summary();
  EXPECT_EQ(r.count(dds::Rejection::kDuplicateName), 1u) << r.summary();
  EXPECT_EQ(bridge.commands() + bridge.tasks() + bridge.weights(), 0u);
  EXPECT_EQ(host.task().phases[0].height, task.phases[0].height);
  EXPECT_EQ(host.task().phase_count, task.phase_count);
  EXPECT_EQ(host.task().weights.height, task.weights.height);
}

TEST(HumanoidDds, WeightsLearnedByIocAreAdoptedAndTheOthersKept) {
  const hm::Motion task = motion("hip-hold");
  hmpc::host::HumanoidHost host(host_config(10), task);
  dds::HumanoidDdsBridge bridge(kWeightsDomain, dds::HumanoidTaskLimits::around(0.85),
                                dds::loopback_config());
  // What hmpc-ioc learn --publish-domain sends: the 13 weights of Eq. 4.31 by name.
  hmpc::ioc::Weights learned;
  std::vector<std::pair<std::string, double>> named;
  for (int k = 0; k < hmpc::ioc::kWeightCount; ++k) {
    learned[k] = 0.5 + k;
    named.emplace_back(hmpc::ioc::kWeightNames[k], learned[k]);
  }
  std::string error;
  ASSERT_TRUE(dds::publish_cost_weights(kWeightsDomain, dds::loopback_config(),
                                        dds::kHumanoidCostWeightsTopic, named, kPatienceS, error))
      << error;
  bridge.poll(host);
  EXPECT_EQ(bridge.weights(), 1u);
  EXPECT_EQ(hmpc::ioc::weights_of(host.task().weights), learned);
  // Not among them: kept as the motion has them.
  EXPECT_EQ(host.task().weights.position, task.weights.position);
  EXPECT_EQ(host.task().weights.fast, task.weights.fast);
  EXPECT_EQ(host.task().weights.attitude[3], task.weights.attitude[3]);
}

}  // namespace
