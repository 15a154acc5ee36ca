// The forearm DDS bridge (host/dds) over Cyclone DDS on loopback: commands in, state and
// telemetry out, malformed commands refused. Every case runs on its own domain id with
// loopback_config(), so cases and other test programs do not hear each other, and nothing
// leaves 127.0.0.1.
#include <gtest/gtest.h>

#include <chrono>
#include <limits>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "hmpc/dds/forearm_dds.hpp"

namespace {

namespace dds = hmpc::dds;
namespace proto = hmpc::forearm_protocol;

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

dds::ForearmCommandSample run_command(proto::NodeId node, std::uint32_t sequence) {
  dds::ForearmCommandSample c;
  c.node = node;
  c.sequence_number = sequence;
  c.mode = proto::RequestedMode::kRun;
  c.strategy = proto::Strategy::kCoarse40ms;
  c.clear_faults = true;
  c.target.kind = dds::TargetKind::kSinusoid;
  c.target.amplitude_rad = 0.4;
  c.target.frequency_hz = 0.25;
  c.target.offset_rad = 0.3;
  c.target.duration_s = 12.5;
  return c;
}

TEST(ForearmDdsBridge, CommandFromAWriterReachesPollCommands) {
  dds::ForearmDdsBridge bridge(91, 3, dds::loopback_config());
  dds::ForearmDdsClient client(91, dds::loopback_config());
  ASSERT_TRUE(client.wait_for_bridge(kPatience_s));
  const dds::ForearmCommandSample sent = run_command(3, 41);
  ASSERT_TRUE(client.send(sent));

  std::vector<dds::ForearmCommandSample> received;
  ASSERT_TRUE(eventually([&] {
    bridge.poll_commands([&](const dds::ForearmCommandSample& c) { received.push_back(c); });
    return !received.empty();
  }));
  ASSERT_EQ(received.size(), 1u);
  const dds::ForearmCommandSample& got = received[0];
  EXPECT_EQ(got.node, sent.node);
  EXPECT_EQ(got.sequence_number, sent.sequence_number);
  EXPECT_EQ(got.mode, sent.mode);
  EXPECT_EQ(got.strategy, sent.strategy);
  EXPECT_EQ(got.clear_faults, sent.clear_faults);
  EXPECT_EQ(got.target.kind, sent.target.kind);
  EXPECT_EQ(got.target.amplitude_rad, sent.target.amplitude_rad);
  EXPECT_EQ(got.target.frequency_hz, sent.target.frequency_hz);
  EXPECT_EQ(got.target.offset_rad, sent.target.offset_rad);
  EXPECT_EQ(got.target.duration_s, sent.target.duration_s);
  EXPECT_EQ(bridge.rejected_commands(), 0u);
  EXPECT_EQ(bridge.poll_commands([](const auto&) { FAIL() << "taken twice"; }), 0u);
}

TEST(ForearmDdsBridge, MalformedCommandsAreCountedAndNeverPassedOn) {
  dds::ForearmDdsBridge bridge(92, 3, dds::loopback_config());
  dds::ForearmDdsClient client(92, dds::loopback_config());
  ASSERT_TRUE(client.wait_for_bridge(kPatience_s));

  std::vector<dds::ForearmCommandSample> bad;
  bad.push_back(run_command(3, 2));
  bad.back().target.amplitude_rad = std::numeric_limits<double>::quiet_NaN();
  bad.push_back(run_command(3, 3));
  bad.back().strategy = static_cast<proto::Strategy>(9);
  bad.push_back(run_command(3, 4));
  bad.back().mode = static_cast<proto::RequestedMode>(0);
  bad.push_back(run_command(5, 5));   // another board's command
  bad.push_back(run_command(20, 6));  // no such node
  bad.push_back(run_command(3, 7));
  bad.back().target.offset_rad = 1.0;     // each in range, but the peak of 1.9 rad is past
  bad.back().target.amplitude_rad = 0.9;  // the board's software limit

  testing::internal::CaptureStderr();
  ASSERT_TRUE(client.send(run_command(3, 1)));
  for (const auto& c : bad) ASSERT_TRUE(client.send(c));
  ASSERT_TRUE(client.send(run_command(3, 8)));
  ASSERT_TRUE(client.wait_for_delivery(kPatience_s));

  std::set<std::uint32_t> accepted;
  const bool all_arrived = eventually([&] {
    bridge.poll_commands(
        [&](const dds::ForearmCommandSample& c) { accepted.insert(c.sequence_number); });
    return accepted.size() + bridge.rejected_commands() >= bad.size() + 2;
  });
  const std::string log = testing::internal::GetCapturedStderr();
  ASSERT_TRUE(all_arrived) << "accepted " << accepted.size() << ", rejected "
                           << bridge.rejected_commands() << "\n"
                           << log;
  EXPECT_EQ(accepted, (std::set<std::uint32_t>{1, 8}));
  EXPECT_EQ(bridge.rejected_commands(), bad.size());
  for (const char* reason :
       {"command 2: target.amplitude_rad is not finite", "command 3: strategy 9 ",
        "command 4: mode 0 ", "command 5: for node 5, this bridge is node 3",
        "command 6: node 20 is outside 0..15",
        "command 7: target.offset_rad +- target.amplitude_rad spans"}) {
    EXPECT_NE(log.find(reason), std::string::npos) << "no '" << reason << "' in:\n" << log;
  }
}

TEST(ForearmDdsBridge, PublishedStateAndTelemetryReachAReaderUnchanged) {
  dds::ForearmDdsBridge bridge(93, 2, dds::loopback_config());
  dds::ForearmDdsClient client(93, dds::loopback_config());

  dds::ForearmStateSample state;
  state.node = 9;  // the bridge writes its own node
  state.board_time_s = 12.345;
  state.mode = proto::BoardMode::kRun;
  state.faults = proto::fault::kOverrun | proto::fault::kBusError;
  state.strategy = proto::Strategy::kPamOnly;
  state.theta = 0.25;
  state.theta_dot = -1.5;
  state.pressure_mpa = 0.31;
  state.theta_d = 0.27;
  state.v_p = 2.5;
  state.v_m = -0.75;
  state.tau_p = 3.25;
  state.tau_m = -0.5;
  state.rejected_frames = 4;
  state.watchdog_trips = 1;
  state.solver_failures = 300;
  state.overruns = 70000;

  dds::ForearmTelemetrySample telemetry;
  telemetry.node = 9;
  telemetry.time_s = 12.344;
  telemetry.solve_status = proto::SolveStatusCode::kIterationCap;
  telemetry.coarse_iterations = 5;
  telemetry.fine_iterations = 3;
  telemetry.solve_time_us = 1234;
  telemetry.tracking_error = -0.012;

  // Volatile topics: a sample written before the reader is discovered is not kept for it, so
  // publish as the host loop does until one arrives.
  std::vector<dds::ForearmStateSample> states;
  std::vector<dds::ForearmTelemetrySample> telemetries;
  ASSERT_TRUE(eventually([&] {
    EXPECT_TRUE(bridge.publish(state));
    EXPECT_TRUE(bridge.publish(telemetry));
    client.poll_state([&](const dds::ForearmStateSample& s) { states.push_back(s); });
    client.poll_telemetry([&](const dds::ForearmTelemetrySample& t) { telemetries.push_back(t); });
    return !states.empty() && !telemetries.empty();
  }));

  const dds::ForearmStateSample& s = states.front();
  EXPECT_EQ(s.node, 2);
  EXPECT_EQ(s.board_time_s, state.board_time_s);
  EXPECT_EQ(s.mode, state.mode);
  EXPECT_EQ(s.faults, state.faults);
  EXPECT_EQ(s.strategy, state.strategy);
  EXPECT_EQ(s.theta, state.theta);
  EXPECT_EQ(s.theta_dot, state.theta_dot);
  EXPECT_EQ(s.pressure_mpa, state.pressure_mpa);
  EXPECT_EQ(s.theta_d, state.theta_d);
  EXPECT_EQ(s.v_p, state.v_p);
  EXPECT_EQ(s.v_m, state.v_m);
  EXPECT_EQ(s.tau_p, state.tau_p);
  EXPECT_EQ(s.tau_m, state.tau_m);
  EXPECT_EQ(s.rejected_frames, state.rejected_frames);
  EXPECT_EQ(s.watchdog_trips, state.watchdog_trips);
  EXPECT_EQ(s.solver_failures, state.solver_failures);
  EXPECT_EQ(s.overruns, state.overruns);

  const dds::ForearmTelemetrySample& t = telemetries.front();
  EXPECT_EQ(t.node, 2);
  EXPECT_EQ(t.time_s, telemetry.time_s);
  EXPECT_EQ(t.solve_status, telemetry.solve_status);
  EXPECT_EQ(t.coarse_iterations, telemetry.coarse_iterations);
  EXPECT_EQ(t.fine_iterations, telemetry.fine_iterations);
  EXPECT_EQ(t.solve_time_us, telemetry.solve_time_us);
  EXPECT_EQ(t.tracking_error, telemetry.tracking_error);
}

TEST(ForearmDdsBridge, RefusesABadNodeOrConfiguration) {
  EXPECT_THROW(dds::ForearmDdsBridge(94, 16, dds::loopback_config()), std::invalid_argument);
  try {
    dds::ForearmDdsBridge bridge(94, 0,
                                 "<CycloneDDS><Domain><NoSuchSetting/></Domain></CycloneDDS>");
    FAIL() << "an invalid configuration was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot create DDS domain 94"), std::string::npos)
        << e.what();
  }
  // One process, one domain instance: a second configuration for it cannot apply.
  dds::ForearmDdsBridge bridge(94, 0, dds::loopback_config());
  try {
    dds::ForearmDdsClient client(94, dds::loopback_config() + "<!-- another -->");
    FAIL() << "a second configuration of domain 94 was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("another configuration"), std::string::npos) << e.what();
  }
  // The same one is shared, and the domain outlives whichever of its users goes first.
  auto client = std::make_unique<dds::ForearmDdsClient>(94, dds::loopback_config());
  EXPECT_TRUE(client->wait_for_bridge(kPatience_s));
  { dds::ForearmDdsBridge second(94, 1, dds::loopback_config()); }
  EXPECT_TRUE(client->send(run_command(0, 1)));
  std::size_t received = 0;
  EXPECT_TRUE(eventually([&] {
    received += bridge.poll_commands([](const auto&) {});
    return received == 1;
  }));
}

}  // namespace
