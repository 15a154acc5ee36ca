// hmpc-forearm-cli as a separate process against a bridge in this one: DDS discovery and
// delivery between processes over loopback (no multicast), the CLI's checks and exit status.
// Each case has its own domain id.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdio>
#include <future>
#include <string>
#include <thread>
#include <vector>

#include "hmpc/dds/forearm_dds.hpp"

namespace {

namespace dds = hmpc::dds;
namespace proto = hmpc::forearm_protocol;

constexpr double kPatience_s = 30;
constexpr double kPi = 3.14159265358979323846;

struct Outcome {
  int status = -1;     // exit status; -1 if it did not exit normally
  std::string output;  // stdout and stderr
};

// Runs the CLI with these arguments (a shell word list) and --dds-loopback.
Outcome run_cli(const std::string& arguments) {
  const std::string command =
      std::string("'") + HMPC_FOREARM_CLI + "' --dds-loopback " + arguments + " 2>&1";
  Outcome outcome;
  std::FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return outcome;
  char buffer[4096];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) outcome.output.append(buffer, n);
  const int status = pclose(pipe);
  if (status != -1 && WIFEXITED(status)) outcome.status = WEXITSTATUS(status);
  return outcome;
}

// Polls the bridge until `count` commands were accepted or rejected, or the CLI ended and a
// last poll found nothing more.
std::vector<dds::ForearmCommandSample> poll_while(dds::ForearmDdsBridge& bridge,
                                                  std::future<Outcome>& cli, std::size_t count) {
  std::vector<dds::ForearmCommandSample> accepted;
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(2 * kPatience_s);
  for (;;) {
    const bool cli_done = cli.wait_for(std::chrono::milliseconds(10)) == std::future_status::ready;
    bridge.poll_commands([&](const dds::ForearmCommandSample& c) { accepted.push_back(c); });
    if (accepted.size() + bridge.rejected_commands() >= count) break;
    if (cli_done || std::chrono::steady_clock::now() > deadline) break;
  }
  return accepted;
}

TEST(ForearmCli, RunCommandReachesTheBridge) {
  dds::ForearmDdsBridge bridge(95, 1, dds::loopback_config());
  auto cli = std::async(std::launch::async, [] {
    return run_cli(
        "--domain 95 --node 1 --timeout 30 run --strategy coarse_20ms --sine 20 0.5 "
        "--offset 10 --duration 12 --sequence 42");
  });
  const std::vector<dds::ForearmCommandSample> accepted = poll_while(bridge, cli, 1);
  const Outcome outcome = cli.get();
  EXPECT_EQ(outcome.status, 0) << outcome.output;
  EXPECT_NE(outcome.output.find("sent run command 42 to node 1"), std::string::npos)
      << outcome.output;
  ASSERT_EQ(accepted.size(), 1u) << outcome.output;
  const dds::ForearmCommandSample& c = accepted[0];
  EXPECT_EQ(c.node, 1);
  EXPECT_EQ(c.sequence_number, 42u);
  EXPECT_EQ(c.mode, proto::RequestedMode::kRun);
  EXPECT_EQ(c.strategy, proto::Strategy::kCoarse20ms);
  EXPECT_FALSE(c.clear_faults);
  EXPECT_EQ(c.target.kind, dds::TargetKind::kSinusoid);
  EXPECT_NEAR(c.target.amplitude_rad, 20 * kPi / 180, 1e-12);
  EXPECT_EQ(c.target.frequency_hz, 0.5);
  EXPECT_NEAR(c.target.offset_rad, 10 * kPi / 180, 1e-12);
  EXPECT_EQ(c.target.duration_s, 12);
  EXPECT_EQ(bridge.rejected_commands(), 0u);
}

TEST(ForearmCli, IdleWithClearFaultsHoldsNoTarget) {
  dds::ForearmDdsBridge bridge(96, 0, dds::loopback_config());
  auto cli = std::async(std::launch::async,
                        [] { return run_cli("--domain 96 --timeout 30 idle --clear-faults"); });
  const std::vector<dds::ForearmCommandSample> accepted = poll_while(bridge, cli, 1);
  const Outcome outcome = cli.get();
  EXPECT_EQ(outcome.status, 0) << outcome.output;
  ASSERT_EQ(accepted.size(), 1u) << outcome.output;
  EXPECT_EQ(accepted[0].mode, proto::RequestedMode::kIdle);
  EXPECT_TRUE(accepted[0].clear_faults);
  EXPECT_EQ(accepted[0].target.kind, dds::TargetKind::kHoldCurrent);
}

// --raw-sample skips the CLI's own check: the bridge must refuse the sample itself.
TEST(ForearmCli, RawMalformedSamplesAreRejectedByTheBridge) {
  dds::ForearmDdsBridge bridge(97, 2, dds::loopback_config());
  const char* const malformed[] = {
      "--node 2 --raw-sample run --sine nan 1",
      "--node 2 --raw-sample run --strategy 9",
      "--node 16 --raw-sample hold",
  };
  std::size_t sent = 0;
  for (const char* arguments : malformed) {
    ++sent;
    auto cli = std::async(std::launch::async, [arguments] {
      return run_cli(std::string("--domain 97 --timeout 30 ") + arguments);
    });
    const std::vector<dds::ForearmCommandSample> accepted = poll_while(bridge, cli, sent);
    const Outcome outcome = cli.get();
    EXPECT_EQ(outcome.status, 0) << arguments << "\n" << outcome.output;
    EXPECT_TRUE(accepted.empty()) << arguments;
    EXPECT_EQ(bridge.rejected_commands(), sent) << arguments;
  }
}

// Watches while the bridge publishes as the host loop does, every 4 ms, until the CLI exits.
template <class Sample>
Outcome watch_while_publishing(dds::ForearmDdsBridge& bridge, const Sample& sample) {
  auto cli = std::async(std::launch::async, [] {
    return run_cli("--domain 98 --node 4 --timeout 30 watch --samples 3");
  });
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(2 * kPatience_s);
  while (cli.wait_for(std::chrono::milliseconds(4)) != std::future_status::ready &&
         std::chrono::steady_clock::now() < deadline) {
    bridge.publish(sample);
  }
  return cli.get();
}

TEST(ForearmCli, WatchPrintsTheBridgesStateAndTelemetry) {
  dds::ForearmDdsBridge bridge(98, 4, dds::loopback_config());
  dds::ForearmStateSample state;
  state.mode = proto::BoardMode::kHold;
  state.theta = 0.4321;
  const Outcome states = watch_while_publishing(bridge, state);
  EXPECT_EQ(states.status, 0) << states.output;
  EXPECT_NE(states.output.find("state     node 4 "), std::string::npos) << states.output;
  EXPECT_NE(states.output.find("mode hold"), std::string::npos) << states.output;
  EXPECT_NE(states.output.find("theta 0.4321 rad"), std::string::npos) << states.output;

  dds::ForearmTelemetrySample telemetry;
  telemetry.solve_status = proto::SolveStatusCode::kBudgetExhausted;
  telemetry.solve_time_us = 2345;
  const Outcome telemetries = watch_while_publishing(bridge, telemetry);
  EXPECT_EQ(telemetries.status, 0) << telemetries.output;
  EXPECT_NE(telemetries.output.find("telemetry node 4 "), std::string::npos) << telemetries.output;
  EXPECT_NE(telemetries.output.find("status budget_exhausted"), std::string::npos)
      << telemetries.output;
  EXPECT_NE(telemetries.output.find("solve 2345 us"), std::string::npos) << telemetries.output;
}

TEST(ForearmCli, NoBridgeIsAnErrorNamingTheDomain) {
  const Outcome outcome = run_cli("--domain 99 --timeout 1 hold");
  EXPECT_EQ(outcome.status, 1) << outcome.output;
  EXPECT_NE(outcome.output.find("no forearm bridge subscribed to commands on domain 99"),
            std::string::npos)
      << outcome.output;
}

TEST(ForearmCli, BadArgumentsExit2NamingTheProblem) {
  struct Case {
    const char* arguments;
    const char* message;
  };
  const Case cases[] = {
      {"", "no command given"},
      {"jump", "unknown command 'jump'"},
      {"--frobnicate run", "unknown option '--frobnicate'"},
      {"run --strategy", "--strategy needs a value"},
      {"run --strategy fine2", "--strategy must be one of"},
      {"run --sine 20", "--sine frequency needs a value"},
      {"run --sine 20x 1", "--sine amplitude needs a number, got '20x'"},
      {"--node 16 run", "invalid command: node 16 is outside 0..15"},
      {"--domain 233 run", "--domain must be an integer in 0..232"},
      {"--timeout 0 run", "--timeout must be a number of seconds"},
      {"run --sine 80 1", "invalid command: target.amplitude_rad"},
      {"run --sine nan 1", "invalid command: target.amplitude_rad is not finite"},
      {"run --sine 20 9", "invalid command: target.frequency_hz 9 is outside 0..5 Hz"},
      {"hold --offset 60 --sine 40 0.5", "invalid command: target.offset_rad"},
      {"run --duration -1", "invalid command: target.duration_s -1"},
      {"watch --samples 0", "--samples must be an integer in 1..1000000"},
      {"idle extra", "unexpected argument 'extra'"},
  };
  for (const Case& c : cases) {
    const Outcome outcome = run_cli(c.arguments);
    EXPECT_EQ(outcome.status, 2) << c.arguments << "\n" << outcome.output;
    EXPECT_NE(outcome.output.find(c.message), std::string::npos)
        << c.arguments << ": no '" << c.message << "' in\n"
        << outcome.output;
  }
}

}  // namespace
