// The forearm DDS bridge (host/dds) over Cyclone DDS on loopback: mode commands and target
// trajectories in, joint state, telemetry and diagnostics out, malformed samples of every type
// refused and counted by reason, a silent commander noticed. Every case runs on its own domain
// id with loopback_config(), so cases and other test programs do not hear each other.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "hmpc/dds/endpoint.hpp"
#include "hmpc/dds/forearm_dds.hpp"

namespace {

namespace dds = hmpc::dds;
namespace msg = hmpc::dds::msg;
namespace proto = hmpc::forearm_protocol;
using hmpc::trajectory::TrajectoryPoint;

// Discovery on loopback takes well under a second here; a loaded machine or an emulated
// guest gets a wide margin.
constexpr double kPatience_s = 30;

// Polls until done() or kPatience_s passed; true if done.
template <class Done>
bool eventually(Done done) {
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(kPatience_s);
  while (!done()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return true;
}

// What a bridge handed on.
struct Received {
  std::vector<dds::ModeCommandSample> commands;
  std::vector<std::vector<TrajectoryPoint>> trajectories;
  std::vector<double> start_delays;
  int silences = 0;
  dds::ForearmDdsHandlers handlers() {
    return {[this](const dds::ModeCommandSample& c) { commands.push_back(c); },
            [this](const dds::TrajectoryView& v) {
              trajectories.emplace_back(v.points, v.points + v.count);
              start_delays.push_back(v.start_delay_s);
              return dds::Verdict::accept();
            },
            [this] { ++silences; },
            {}};
  }
};

dds::ModeCommandSample run_command(std::uint32_t sequence) {
  return {sequence, proto::RequestedMode::kRun, proto::Strategy::kCoarse40ms, true};
}

TEST(ForearmDdsBridge, CommandsAndTrajectoriesFromAClientReachTheHandlers) {
  dds::ForearmDdsBridge bridge(91, 3, dds::loopback_config());
  dds::ForearmDdsClient client(91, 3, dds::loopback_config());
  ASSERT_TRUE(client.wait_for_bridge(kPatience_s));
  const std::vector<TrajectoryPoint> points = {
      {0.0, 0.1, 0.0, true}, {0.5, 0.4, 1.0, true}, {1.25, -0.2, 0.0, true}};
  ASSERT_TRUE(client.send(points));
  ASSERT_TRUE(client.send(run_command(7)));
  ASSERT_TRUE(client.wait_for_delivery(kPatience_s));
  Received got;
  const auto handlers = got.handlers();
  ASSERT_TRUE(eventually([&] {
    bridge.poll(handlers);
    return got.commands.size() == 1 && got.trajectories.size() == 1;
  }));
  const dds::ModeCommandSample& c = got.commands[0];
  EXPECT_EQ(c.sequence_number, 7u);
  EXPECT_EQ(c.mode, proto::RequestedMode::kRun);
  EXPECT_EQ(c.strategy, proto::Strategy::kCoarse40ms);
  EXPECT_TRUE(c.clear_faults);
  ASSERT_EQ(got.trajectories[0].size(), points.size());
  for (std::size_t k = 0; k < points.size(); ++k) {
    EXPECT_DOUBLE_EQ(got.trajectories[0][k].time_s, points[k].time_s) << k;
    EXPECT_EQ(got.trajectories[0][k].position, points[k].position) << k;
    EXPECT_EQ(got.trajectories[0][k].velocity, points[k].velocity) << k;
    EXPECT_TRUE(got.trajectories[0][k].has_velocity) << k;
  }
  EXPECT_EQ(got.start_delays[0], 0.0) << "an unstamped trajectory starts on receipt";
  EXPECT_EQ(bridge.rejects().total(), 0u);
  EXPECT_EQ(bridge.ros_namespace(), "/hmpc/forearm_3");
}

// Raw samples, as any DDS or ROS 2 node could send them, through the generic layer.
class RawSender {
 public:
  explicit RawSender(std::uint32_t domain)
      : participant_(domain, dds::loopback_config()),
        commands_(participant_, "/hmpc/forearm_0/command",
                  dds::Qos::command(dds::kCommandDeadlineS)),
        trajectories_(participant_, "/hmpc/forearm_0/joint_trajectory", dds::Qos::state()) {}

  bool ready() {
    return commands_.wait_for_reader(kPatience_s) && trajectories_.wait_for_reader(kPatience_s);
  }
  // mode 3, "two_stage", stamped now unless given.
  bool command(std::uint8_t mode, const char* strategy, msg::Time stamp = now()) {
    msg::ModeCommand c{};
    c.header.stamp = stamp;
    c.header.frame_id = dds::borrow("");
    c.mode = mode;
    c.strategy = dds::borrow(strategy);
    return commands_.write(c);
  }
  // One joint named `names`, points (t, position[, velocity]) as given.
  bool trajectory(std::vector<const char*> names, const std::vector<std::vector<double>>& points,
                  std::size_t positions_per_point = 1) {
    std::vector<msg::JointTrajectoryPoint> out(points.size());
    for (std::size_t k = 0; k < points.size(); ++k) {
      out[k].time_from_start = dds::from_seconds<msg::Duration>(points[k][0]);
      if (points[k][0] == -1) out[k].time_from_start = {0, 1000000000u};  // a bad nanosec
      out[k].positions = dds::borrow(&points[k][1], positions_per_point);
      if (points[k].size() > 2) out[k].velocities = dds::borrow(&points[k][2], 1);
    }
    msg::JointTrajectory t{};
    t.header.frame_id = dds::borrow("");
    t.joint_names = dds::borrow(names.data(), names.size());
    t.points = dds::borrow<decltype(t.points)>(out.data(), out.size());
    return trajectories_.write(t);
  }
  bool delivered() {
    return commands_.wait_for_acks(kPatience_s) && trajectories_.wait_for_acks(kPatience_s);
  }
  static msg::Time now() { return dds::from_seconds<msg::Time>(dds::unix_time_s()); }

 private:
  dds::Participant participant_;
  dds::Writer<msg::ModeCommand> commands_;
  dds::Writer<msg::JointTrajectory> trajectories_;
};

TEST(ForearmDdsBridge, MalformedSamplesOfEveryTypeAreCountedByReasonAndNeverPassedOn) {
  dds::ForearmDdsBridge bridge(92, 0, dds::loopback_config());
  RawSender send(92);
  ASSERT_TRUE(send.ready());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double limit = dds::forearm_joint_limits().max_position;
  using R = dds::Rejection;
  struct Expected {
    R reason;
    int count;
  };
  // The bridge keeps the last 10 samples of a topic, as ROS 2's default QoS: it takes each
  // before the next, as its 1 kHz loop would.
  Received got;
  const auto handlers = got.handlers();
  const auto sent = [&](bool written) {
    const bool delivered = written && send.delivered();
    bridge.poll(handlers);
    return delivered;
  };
  // Commands.
  ASSERT_TRUE(sent(send.command(3, "two_stage")));                    // good
  ASSERT_TRUE(sent(send.command(0, "two_stage")));                    // no mode
  ASSERT_TRUE(sent(send.command(7, "two_stage")));                    // no such mode
  ASSERT_TRUE(sent(send.command(3, "fastest")));                      // no such strategy
  ASSERT_TRUE(sent(send.command(3, "two_stage", {5, 1000000000u})));  // nanosec out of range
  msg::Time hour_ahead = RawSender::now();
  hour_ahead.sec += 3600;
  ASSERT_TRUE(sent(send.command(3, "two_stage", hour_ahead)));  // a clock an hour off
  ASSERT_TRUE(sent(send.command(2, "pam_only", {0, 0})));       // good: unstamped
  // Trajectories.
  ASSERT_TRUE(sent(send.trajectory({"elbow"}, {{0, 0.1}, {1, 0.2}})));  // good
  ASSERT_TRUE(sent(send.trajectory({"wrist"}, {{0, 0.1}})));            // unknown joint
  ASSERT_TRUE(sent(send.trajectory({"elbow", "elbow"}, {{0, 0.1}})));   // two names, one joint
  ASSERT_TRUE(sent(send.trajectory({"elbow"}, {})));                    // no points
  ASSERT_TRUE(sent(send.trajectory({"elbow"}, {{0, nan}})));            // NaN position
  ASSERT_TRUE(sent(send.trajectory({"elbow"}, {{0, 0.1}, {0.5, 0.2, nan}})));  // NaN velocity
  ASSERT_TRUE(sent(send.trajectory({"elbow"}, {{0, limit + 0.1}})));       // beyond the joint limit
  ASSERT_TRUE(sent(send.trajectory({"elbow"}, {{1, 0.1}, {1, 0.2}})));     // time not increasing
  ASSERT_TRUE(sent(send.trajectory({"elbow"}, {{-1, 0.1}})));              // nanosec out of range
  ASSERT_TRUE(sent(send.trajectory({"elbow"}, {{0, 0.0}, {0.01, 0.5}})));  // 50 rad/s
  // Hermite overshoot: both ends inside the limit, the curve between them beyond it.
  ASSERT_TRUE(
      sent(send.trajectory({"elbow"}, {{0, limit - 0.05, 8.0}, {0.5, limit - 0.05, -8.0}})));
  ASSERT_TRUE(sent(send.trajectory({"elbow"}, {{0, 0.1}}, 0)));  // no positions
  {
    std::vector<std::vector<double>> many(dds::kMaxTrajectoryPoints + 1);
    for (std::size_t k = 0; k < many.size(); ++k) many[k] = {0.01 * double(k), 0.0};
    ASSERT_TRUE(sent(send.trajectory({"elbow"}, many)));  // too many points
  }
  ASSERT_TRUE(sent(send.trajectory({"elbow"}, {{0.5, -0.3, 0.0}})));  // good

  const Expected expected[] = {
      {R::kUnknownValue, 3 + 1},                           // modes, strategy; the joint name
      {R::kBadTimeStamp, 2 + 1}, {R::kLengthMismatch, 3},  // two names, no points, no positions
      {R::kNotFinite, 2},        {R::kOutOfRange, 2},      // beyond the limit, the overshoot
      {R::kNotIncreasing, 1},    {R::kRateLimit, 1},      {R::kTooLarge, 1}};
  int bad = 0;
  for (const Expected& e : expected) bad += e.count;
  ASSERT_TRUE(eventually([&] {
    bridge.poll(handlers);
    return got.commands.size() + got.trajectories.size() + bridge.rejects().total() >=
           std::size_t(4 + bad);
  })) << "accepted "
      << got.commands.size() + got.trajectories.size() << ", rejected "
      << bridge.rejects().summary();
  EXPECT_EQ(got.commands.size(), 2u);
  EXPECT_EQ(got.trajectories.size(), 2u);
  for (const Expected& e : expected) {
    EXPECT_EQ(bridge.rejects().count(e.reason), std::uint64_t(e.count))
        << dds::rejection_name(e.reason) << " in " << bridge.rejects().summary();
  }
  EXPECT_EQ(bridge.rejects().total(), std::uint64_t(bad));
  ASSERT_EQ(got.commands.size(), 2u);
  EXPECT_EQ(got.commands[1].mode, proto::RequestedMode::kHold);
  EXPECT_EQ(got.commands[1].strategy, proto::Strategy::kPamOnly);
}

TEST(ForearmDdsBridge, ARejectionByTheTrajectoryHandlerIsCounted) {
  dds::ForearmDdsBridge bridge(93, 0, dds::loopback_config());
  dds::ForearmDdsClient client(93, 0, dds::loopback_config());
  ASSERT_TRUE(client.wait_for_bridge(kPatience_s));
  ASSERT_TRUE(client.send(std::vector<TrajectoryPoint>{{0.2, 0.5, 0, false}}));
  ASSERT_TRUE(client.wait_for_delivery(kPatience_s));
  dds::ForearmDdsHandlers handlers;
  handlers.trajectory = [](const dds::TrajectoryView&) {
    return dds::Verdict::reject(dds::Rejection::kRateLimit, "too fast from here");
  };
  ASSERT_TRUE(eventually([&] {
    bridge.poll(handlers);
    return bridge.rejects().total() == 1;
  }));
  EXPECT_EQ(bridge.rejects().count(dds::Rejection::kRateLimit), 1u);
}

TEST(ForearmDdsBridge, PublishedStateReachesAClientAsJointStateTelemetryAndDiagnostics) {
  dds::ForearmDdsBridge bridge(94, 2, dds::loopback_config());
  dds::ForearmDdsClient client(94, 2, dds::loopback_config());
  dds::ForearmStateSample state;
  state.theta = 0.4321;
  state.theta_dot = -1.25;
  dds::ForearmTelemetrySample& t = state.telemetry;
  t.mode = proto::BoardMode::kRun;
  t.faults = 0;
  t.strategy = proto::Strategy::kFine8ms;
  t.solve_status = proto::SolveStatusCode::kBudgetExhausted;
  t.coarse_iterations = 3;
  t.fine_iterations = 4;
  t.solve_time_us = 2345;
  t.theta_d = 0.5;
  t.tracking_error = 0.0679;
  t.pressure_pa = 312500;
  t.v_p = 1.5;
  t.v_m = -0.75;
  t.tau_p = 2.5;
  t.tau_m = 0.125;
  state.rejected_frames = 5;
  state.overruns = 9;
  std::vector<dds::JointStateSample> joints;
  std::vector<dds::ForearmTelemetrySample> telemetry;
  std::vector<dds::DiagnosticSample> diagnostics;
  ASSERT_TRUE(eventually([&] {
    EXPECT_TRUE(bridge.publish(state));
    client.poll_joint_states([&](const dds::JointStateSample& j) { joints.push_back(j); });
    client.poll_telemetry([&](const dds::ForearmTelemetrySample& m) { telemetry.push_back(m); });
    client.poll_diagnostics([&](const dds::DiagnosticSample& d) { diagnostics.push_back(d); });
    return !joints.empty() && !telemetry.empty() && !diagnostics.empty();
  }));
  const double now = dds::unix_time_s();
  EXPECT_EQ(joints[0].position, 0.4321);
  EXPECT_EQ(joints[0].velocity, -1.25);
  EXPECT_EQ(joints[0].effort, 2.625) << "the joint's torque: muscle and motor";
  EXPECT_NEAR(joints[0].stamp_s, now, kPatience_s) << "stamped with Unix time";
  const dds::ForearmTelemetrySample& m = telemetry[0];
  EXPECT_EQ(m.mode, t.mode);
  EXPECT_EQ(m.strategy, t.strategy);
  EXPECT_EQ(m.solve_status, t.solve_status);
  EXPECT_EQ(m.coarse_iterations, 3);
  EXPECT_EQ(m.fine_iterations, 4);
  EXPECT_EQ(m.solve_time_us, 2345u);
  EXPECT_EQ(m.theta_d, 0.5);
  EXPECT_EQ(m.tracking_error, 0.0679);
  EXPECT_EQ(m.pressure_pa, 312500);
  EXPECT_EQ(m.v_p, 1.5);
  EXPECT_EQ(m.v_m, -0.75);
  EXPECT_EQ(m.tau_p, 2.5);
  EXPECT_EQ(m.tau_m, 0.125);
  const dds::DiagnosticSample& d = diagnostics[0];
  EXPECT_EQ(d.level, dds::DiagnosticLevel::kOk);
  EXPECT_EQ(d.name, "hmpc/forearm_2/board");
  EXPECT_EQ(d.hardware_id, "forearm board node 2");
  EXPECT_EQ(d.message, "run, fine_8ms");
  const auto value = [&](const std::string& key) {
    for (const auto& [k, v] : d.values)
      if (k == key) return v;
    return std::string("(missing)");
  };
  EXPECT_EQ(value("mode"), "run");
  EXPECT_EQ(value("faults"), "0x00");
  EXPECT_EQ(value("rejected_frames"), "5");
  EXPECT_EQ(value("overruns"), "9");
  EXPECT_EQ(value("solve_status"), "budget_exhausted");
  EXPECT_EQ(client.rejects().total(), 0u);

  // A fault changes the diagnostics at once, without waiting for the period.
  state.telemetry.mode = proto::BoardMode::kFault;
  state.telemetry.faults = proto::fault::kHeartbeatTimeout;
  diagnostics.clear();
  ASSERT_TRUE(eventually([&] {
    EXPECT_TRUE(bridge.publish(state));
    client.poll_diagnostics([&](const dds::DiagnosticSample& s) { diagnostics.push_back(s); });
    return !diagnostics.empty();
  }));
  EXPECT_EQ(diagnostics.back().level, dds::DiagnosticLevel::kError);
  EXPECT_EQ(diagnostics.back().message, "fault 0x01");
}

TEST(ForearmDdsBridge, ACommanderThatStopsIsNoticedWithinTheDeadline) {
  dds::ForearmDdsBridge bridge(95, 0, dds::loopback_config());
  Received got;
  const auto handlers = got.handlers();
  auto client = std::make_unique<dds::ForearmDdsClient>(95, 0, dds::loopback_config());
  ASSERT_TRUE(client->wait_for_bridge(kPatience_s));
  // Commands at 10 Hz for a second: no silence, even when another operator's client (with its
  // own command writer) comes and goes meanwhile.
  auto other = std::make_unique<dds::ForearmDdsClient>(95, 0, dds::loopback_config());
  ASSERT_TRUE(other->wait_for_bridge(kPatience_s));
  auto last = std::chrono::steady_clock::now();
  for (int i = 0; i < 10; ++i) {
    if (i == 3) other.reset();
    ASSERT_TRUE(client->send(run_command(std::uint32_t(i))));
    last = std::chrono::steady_clock::now();
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    bridge.poll(handlers);
  }
  EXPECT_EQ(got.silences, 0);
  EXPECT_GE(got.commands.size(), 5u);
  // Then nothing, the commander still there.
  ASSERT_TRUE(eventually([&] {
    bridge.poll(handlers);
    return got.silences == 1;
  }));
  const double noticed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - last).count();
  // Not before the deadline; after it within a poll and a scheduling delay, with room for a
  // stalled shared machine.
  EXPECT_GE(noticed, 0.9 * dds::kCommandDeadlineS);
  EXPECT_LE(noticed, dds::kCommandDeadlineS + 1.0);
  EXPECT_EQ(bridge.commander_silences(), 1u);

  // Commanding again, then the commander's process going away: noticed too, once.
  ASSERT_TRUE(client->send(run_command(20)));
  ASSERT_TRUE(client->wait_for_delivery(kPatience_s));
  ASSERT_TRUE(eventually([&] {
    bridge.poll(handlers);
    return got.commands.size() >= 11;
  }));
  client.reset();
  ASSERT_TRUE(eventually([&] {
    bridge.poll(handlers);
    return got.silences == 2;
  }));
  std::this_thread::sleep_for(std::chrono::duration<double>(2 * dds::kCommandDeadlineS));
  bridge.poll(handlers);
  EXPECT_EQ(got.silences, 2) << "one notice per silence";
}

TEST(ForearmDdsBridge, ACommanderOfferingNoDeadlineIsNotHeard) {
  // DDS matches a reader requesting a deadline only with writers offering one at least as
  // tight: a commander that never promised to keep sending cannot start a run.
  dds::ForearmDdsBridge bridge(96, 0, dds::loopback_config());
  dds::Participant participant(96, dds::loopback_config());
  const dds::Writer<msg::ModeCommand> careless(participant, "/hmpc/forearm_0/command",
                                               dds::Qos::state());
  const dds::Writer<msg::ModeCommand> careful(participant, "/hmpc/forearm_0/command",
                                              dds::Qos::command(dds::kCommandDeadlineS));
  ASSERT_TRUE(careful.wait_for_reader(kPatience_s));
  msg::ModeCommand c{};
  c.header.frame_id = dds::borrow("");
  c.mode = 3;
  c.strategy = dds::borrow("two_stage");
  c.sequence_number = 1;
  EXPECT_TRUE(careless.write(c));
  c.sequence_number = 2;
  EXPECT_TRUE(careful.write(c));
  EXPECT_TRUE(careful.wait_for_acks(kPatience_s));
  EXPECT_EQ(careless.matched_readers(), 0u);
  Received got;
  const auto handlers = got.handlers();
  ASSERT_TRUE(eventually([&] {
    bridge.poll(handlers);
    return !got.commands.empty();
  }));
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  bridge.poll(handlers);
  ASSERT_EQ(got.commands.size(), 1u);
  EXPECT_EQ(got.commands[0].sequence_number, 2u);
}

TEST(ForearmDdsBridge, CostWeightsAreCheckedAndHandedOnAsTheCanFrame) {
  // The names and ranges are the CAN frame's signals', not a copy.
  const auto& limits = dds::forearm_weight_limits();
  const proto::Signal signals[] = {
      proto::Signal::kCostWeightsTheta, proto::Signal::kCostWeightsPressure,
      proto::Signal::kCostWeightsTorque, proto::Signal::kCostWeightsValve};
  for (std::size_t i = 0; i < limits.size(); ++i) {
    const auto& spec = hmpc::protocol::signal_spec(signals[i]);
    EXPECT_STREQ(limits[i].name, spec.name);
    EXPECT_EQ(limits[i].min, spec.factor) << "the smallest non-zero weight; 0 means keep";
    EXPECT_EQ(limits[i].max, spec.max);
  }
  dds::ForearmDdsBridge bridge(103, 0, dds::loopback_config());
  dds::ForearmDdsClient client(103, 0, dds::loopback_config());
  ASSERT_TRUE(client.wait_for_bridge(kPatience_s));
  std::vector<proto::CostWeights> got;
  dds::ForearmDdsHandlers handlers;
  handlers.weights = [&](const proto::CostWeights& w) { got.push_back(w); };
  const auto sent = [&](const std::vector<std::pair<std::string, double>>& weights) {
    const bool delivered = client.send(weights) && client.wait_for_delivery(kPatience_s);
    bridge.poll(handlers);
    return delivered;
  };
  ASSERT_TRUE(sent({{"w_v", 0.004}, {"w_theta", 80.0}}));
  ASSERT_TRUE(sent({{"w_x", 1.0}}));                                       // unknown
  ASSERT_TRUE(sent({{"w_theta", 500.0}}));                                 // above its range
  ASSERT_TRUE(sent({{"w_tau", 0.0}}));                                     // 0 is not a weight
  ASSERT_TRUE(sent({{"w_p", std::numeric_limits<double>::quiet_NaN()}}));  // not finite
  ASSERT_TRUE(sent({{"w_p", 1.0}, {"w_p", 2.0}}));                         // twice
  ASSERT_TRUE(eventually([&] {
    bridge.poll(handlers);
    return got.size() + bridge.rejects().total() >= 6;
  }));
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].w_theta, 80.0f);
  EXPECT_EQ(got[0].w_p, 0.0f) << "not given: the board keeps it";
  EXPECT_EQ(got[0].w_tau, 0.0f);
  EXPECT_EQ(got[0].w_v, 0.004f);
  EXPECT_EQ(bridge.rejects().count(dds::Rejection::kUnknownValue), 1u);
  EXPECT_EQ(bridge.rejects().count(dds::Rejection::kOutOfRange), 2u);
  EXPECT_EQ(bridge.rejects().count(dds::Rejection::kNotFinite), 1u);
  EXPECT_EQ(bridge.rejects().count(dds::Rejection::kDuplicateName), 1u);
}

TEST(ForearmDdsBridge, RefusesABadNodeNamespaceOrConfiguration) {
  EXPECT_THROW(dds::ForearmDdsBridge(97, 16, dds::loopback_config()), std::invalid_argument);
  EXPECT_THROW(dds::ForearmDdsBridge(97, 0, dds::loopback_config(), "no/leading/slash"),
               std::invalid_argument);
  try {
    dds::ForearmDdsBridge bridge(97, 0, "<CycloneDDS><Domain><Nonsense/></Domain></CycloneDDS>");
    ADD_FAILURE() << "a broken configuration was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot create DDS domain 97"), std::string::npos)
        << e.what();
  }
  // A domain in use with one configuration refuses another, and keeps working.
  dds::ForearmDdsBridge bridge(97, 1, dds::loopback_config());
  try {
    dds::ForearmDdsClient other(97, 1, "<CycloneDDS><Domain><General/></Domain></CycloneDDS>");
    ADD_FAILURE() << "a second configuration was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("another configuration"), std::string::npos) << e.what();
  }
  dds::ForearmDdsClient client(97, 1, dds::loopback_config());
  ASSERT_TRUE(client.wait_for_bridge(kPatience_s));
  ASSERT_TRUE(client.send(run_command(1)));
  Received got;
  const auto handlers = got.handlers();
  EXPECT_TRUE(eventually([&] {
    bridge.poll(handlers);
    return got.commands.size() == 1;
  }));
}

}  // namespace
