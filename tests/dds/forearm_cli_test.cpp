// hmpc-forearm-cli as a separate process against a bridge in this one: DDS discovery and
// delivery between processes over loopback (no multicast), the CLI's targets, its repeated
// command while it runs, its checks and exit status. Each case has its own domain id.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <future>
#include <string>
#include <thread>
#include <vector>

#include "hmpc/dds/forearm_dds.hpp"
#include "hmpc/platform/linux/child_process.hpp"

namespace {

namespace dds = hmpc::dds;
namespace proto = hmpc::forearm_protocol;
using hmpc::trajectory::TrajectoryPoint;

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

// What the bridge handed on while a CLI ran.
struct Received {
  std::vector<dds::ModeCommandSample> commands;
  std::vector<std::vector<TrajectoryPoint>> trajectories;
  int silences_while_running = 0;
  dds::ForearmDdsHandlers handlers() {
    return {[this](const dds::ModeCommandSample& c) { commands.push_back(c); },
            [this](const dds::TrajectoryView& v) {
              trajectories.emplace_back(v.points, v.points + v.count);
              return dds::Verdict::accept();
            },
            [this] {
              if (!commands.empty() && commands.back().mode == proto::RequestedMode::kRun)
                ++silences_while_running;
            },
            {}};
  }
};

// Polls the bridge every millisecond, as the host loop does, until the CLI ended, then once more.
Received poll_until_done(dds::ForearmDdsBridge& bridge, std::future<Outcome>& cli) {
  Received got;
  const auto handlers = got.handlers();
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(2 * kPatience_s);
  while (cli.wait_for(std::chrono::milliseconds(1)) != std::future_status::ready &&
         std::chrono::steady_clock::now() < deadline) {
    bridge.poll(handlers);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  bridge.poll(handlers);
  return got;
}

TEST(ForearmCli, RunSendsItsSinusoidRepeatsTheCommandWhileItLastsThenHolds) {
  dds::ForearmDdsBridge bridge(98, 1, dds::loopback_config());
  auto cli = std::async(std::launch::async, [] {
    return run_cli(
        "--domain 98 --node 1 run --strategy coarse_20ms --sine 20 0.5 --offset 10 "
        "--duration 1 --sequence 42");
  });
  const Received got = poll_until_done(bridge, cli);
  const Outcome outcome = cli.get();
  EXPECT_EQ(outcome.status, 0) << outcome.output;
  EXPECT_NE(outcome.output.find("sent run command 42 to node 1 with a target of 51 points"),
            std::string::npos)
      << outcome.output;
  EXPECT_NE(outcome.output.find("sent hold"), std::string::npos) << outcome.output;

  ASSERT_EQ(got.trajectories.size(), 1u);
  const std::vector<TrajectoryPoint>& points = got.trajectories[0];
  ASSERT_EQ(points.size(), 51u) << "1 s every 20 ms, both ends";
  const double a = 20 * kPi / 180, w = 2 * kPi * 0.5, offset = 10 * kPi / 180;
  for (const TrajectoryPoint& p : points) {
    EXPECT_NEAR(p.position, offset + a * std::sin(w * p.time_s), 1e-12) << p.time_s;
    EXPECT_NEAR(p.velocity, a * w * std::cos(w * p.time_s), 1e-12) << p.time_s;
    EXPECT_TRUE(p.has_velocity);
  }
  EXPECT_DOUBLE_EQ(points.back().time_s, 1.0);

  // Every kCommandDeadlineS / 5 for 1 s: about 10 runs; a loaded machine may send fewer, but a
  // CLI that sent once and left would send 1.
  ASSERT_GE(got.commands.size(), 4u);
  for (std::size_t i = 0; i + 1 < got.commands.size(); ++i) {
    EXPECT_EQ(got.commands[i].mode, proto::RequestedMode::kRun) << i;
    EXPECT_EQ(got.commands[i].strategy, proto::Strategy::kCoarse20ms) << i;
    EXPECT_EQ(got.commands[i].sequence_number, 42u) << i;
  }
  EXPECT_EQ(got.commands.back().mode, proto::RequestedMode::kHold);
  EXPECT_EQ(got.silences_while_running, 0) << "the run's commander never fell silent";
  EXPECT_EQ(bridge.rejects().total(), 0u) << bridge.rejects().summary();
}

std::string temp_file(const std::string& name, const std::string& text) {
  const char* tmp = std::getenv("TMPDIR");
  std::string path = std::string(tmp ? tmp : "/tmp") + "/hmpc-forearm-cli-" + name;
  std::ofstream(path) << text;
  return path;
}

// A target from a CSV file goes out as the file's points, velocities where the file gives them.
TEST(ForearmCli, RunSendsTheTargetOfACsvFile) {
  const std::string file =
      temp_file("target.csv", "time_s,position_rad,velocity_rad_s\n0,0,0\n0.5,0.2\n1.5,0.3,0\n");
  dds::ForearmDdsBridge bridge(107, 1, dds::loopback_config());
  auto cli = std::async(std::launch::async, [&] {
    return run_cli("--domain 107 --node 1 run --target-file " + file + " --duration 0.3");
  });
  const Received got = poll_until_done(bridge, cli);
  const Outcome outcome = cli.get();
  EXPECT_EQ(outcome.status, 0) << outcome.output;
  ASSERT_EQ(got.trajectories.size(), 1u);
  const std::vector<TrajectoryPoint>& points = got.trajectories[0];
  ASSERT_EQ(points.size(), 3u);
  EXPECT_EQ(points[1].time_s, 0.5);
  EXPECT_EQ(points[1].position, 0.2);
  EXPECT_FALSE(points[1].has_velocity);
  EXPECT_EQ(points[2].position, 0.3);
  EXPECT_TRUE(points[2].has_velocity);
  EXPECT_EQ(bridge.rejects().total(), 0u) << bridge.rejects().summary();
}

TEST(ForearmCli, AnInterruptedRunEndsInHold) {
  dds::ForearmDdsBridge bridge(100, 0, dds::loopback_config());
  Received got;
  const auto handlers = got.handlers();
  hmpc::platform::Child cli;
  std::string error;
  const std::string out = std::string(std::getenv("TMPDIR") ? std::getenv("TMPDIR") : "/tmp") +
                          "/hmpc-forearm-cli-interrupted.out";
  ASSERT_TRUE(cli.start(HMPC_FOREARM_CLI,
                        {"--dds-loopback", "--domain", "100", "run", "--offset", "5"}, out, error))
      << error;
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(kPatience_s);
  while (got.commands.size() < 3 && std::chrono::steady_clock::now() < deadline) {
    bridge.poll(handlers);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  ASSERT_GE(got.commands.size(), 3u) << cli.output() << cli.errors();
  EXPECT_EQ(cli.stop(kPatience_s), 0) << cli.output() << cli.errors();
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  bridge.poll(handlers);
  EXPECT_NE(cli.output().find("(interrupted): sent hold"), std::string::npos) << cli.output();
  EXPECT_EQ(got.commands.back().mode, proto::RequestedMode::kHold);
  ASSERT_EQ(got.trajectories.size(), 1u);
  ASSERT_EQ(got.trajectories[0].size(), 1u) << "a constant target: one point";
  EXPECT_NEAR(got.trajectories[0][0].position, 5 * kPi / 180, 1e-12);
  EXPECT_EQ(got.trajectories[0][0].time_s, 1.0) << "reached in a second";
}

TEST(ForearmCli, IdleWithClearFaultsSendsOneCommandAndNoTarget) {
  dds::ForearmDdsBridge bridge(101, 2, dds::loopback_config());
  auto cli = std::async(std::launch::async, [] {
    return run_cli("--domain 101 --node 2 idle --clear-faults --strategy pam_only");
  });
  const Received got = poll_until_done(bridge, cli);
  const Outcome outcome = cli.get();
  EXPECT_EQ(outcome.status, 0) << outcome.output;
  ASSERT_EQ(got.commands.size(), 1u) << outcome.output;
  EXPECT_EQ(got.commands[0].mode, proto::RequestedMode::kIdle);
  EXPECT_EQ(got.commands[0].strategy, proto::Strategy::kPamOnly);
  EXPECT_TRUE(got.commands[0].clear_faults);
  EXPECT_TRUE(got.trajectories.empty());
}

TEST(ForearmCli, WeightsReachTheBridge) {
  dds::ForearmDdsBridge bridge(104, 5, dds::loopback_config());
  std::vector<proto::CostWeights> got;
  dds::ForearmDdsHandlers handlers;
  handlers.weights = [&](const proto::CostWeights& w) { got.push_back(w); };
  auto cli = std::async(std::launch::async, [] {
    return run_cli("--domain 104 --node 5 weights w_theta=80 w_tau=0.2");
  });
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(2 * kPatience_s);
  while (cli.wait_for(std::chrono::milliseconds(1)) != std::future_status::ready &&
         std::chrono::steady_clock::now() < deadline) {
    bridge.poll(handlers);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  bridge.poll(handlers);
  const Outcome outcome = cli.get();
  EXPECT_EQ(outcome.status, 0) << outcome.output;
  EXPECT_NE(outcome.output.find("sent 2 cost weights to node 5"), std::string::npos)
      << outcome.output;
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].w_theta, 80.0f);
  EXPECT_EQ(got[0].w_tau, 0.2f);
  EXPECT_EQ(got[0].w_p, 0.0f);
  EXPECT_EQ(got[0].w_v, 0.0f);
}

TEST(ForearmCli, WatchPrintsJointStateTelemetryAndDiagnostics) {
  dds::ForearmDdsBridge bridge(102, 4, dds::loopback_config());
  dds::ForearmStateSample state;
  state.theta = 0.4321;
  state.telemetry.mode = proto::BoardMode::kHold;
  state.telemetry.solve_status = proto::SolveStatusCode::kBudgetExhausted;
  state.telemetry.solve_time_us = 2345;
  auto cli = std::async(std::launch::async, [] {
    return run_cli("--domain 102 --node 4 --timeout 30 watch --samples 400");
  });
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(2 * kPatience_s);
  // Published as the host loop does, every 4 ms, until the CLI exits; the mode changes every
  // 25 samples, and with it the diagnostics, which go out at once.
  for (int i = 0; cli.wait_for(std::chrono::milliseconds(4)) != std::future_status::ready &&
                  std::chrono::steady_clock::now() < deadline;
       ++i) {
    state.telemetry.mode = (i / 25) % 2 ? proto::BoardMode::kRun : proto::BoardMode::kHold;
    bridge.publish(state);
  }
  const Outcome outcome = cli.get();
  EXPECT_EQ(outcome.status, 0) << outcome.output;
  EXPECT_NE(outcome.output.find("joint     elbow position 0.4321 rad"), std::string::npos)
      << outcome.output;
  EXPECT_NE(outcome.output.find("telemetry mode hold"), std::string::npos) << outcome.output;
  EXPECT_NE(outcome.output.find("status budget_exhausted"), std::string::npos) << outcome.output;
  EXPECT_NE(outcome.output.find("solve 2345 us"), std::string::npos) << outcome.output;
  EXPECT_NE(outcome.output.find("diagnostics hmpc/forearm_4/board OK 'run, two_stage' (forearm "
                                "board node 4): mode=run faults=0x00 strategy=two_stage"),
            std::string::npos)
      << outcome.output;
}

TEST(ForearmCli, NoBridgeIsAnErrorNamingTheTopicAndDomain) {
  const Outcome outcome = run_cli("--domain 99 --timeout 1 hold");
  EXPECT_EQ(outcome.status, 1) << outcome.output;
  EXPECT_NE(outcome.output.find("no forearm bridge subscribed to /hmpc/forearm_0/command on "
                                "domain 99"),
            std::string::npos)
      << outcome.output;
}

// Bad arguments and targets, target files among them (not a target the joint can follow, or
// not a file at all), exit 2 naming the problem before any DDS.
TEST(ForearmCli, BadArgumentsAndTargetsExit2NamingTheProblem) {
  struct Case {
    std::string arguments;
    const char* message;
  };
  const Case cases[] = {
      {"", "no command given"},
      {"jump", "unknown command 'jump'"},
      {"--frobnicate run", "unknown option '--frobnicate'"},
      {"run --strategy", "--strategy needs a value"},
      {"run --strategy fine2", "--strategy must be one of"},
      {"run --sine 20", "--sine frequency needs a value"},
      {"run --sine 20x 1 --duration 1", "--sine amplitude needs a finite number, got '20x'"},
      {"run --sine nan 1 --duration 1", "--sine amplitude needs a finite number, got 'nan'"},
      {"run --sine 20 1", "--sine needs a --duration"},
      {"hold --offset 10", "--sine, --offset and --target-file are targets of run"},
      {"--node 16 run", "--node must be an integer in 0..15"},
      {"--domain 233 run", "--domain must be an integer in 0..232"},
      {"--timeout 0 run", "--timeout must be a number of seconds"},
      {"run --sine 80 1 --duration 1", "(elbow) = -1.26338 is outside -1.2..1.6"},
      {"run --sine 20 9 --duration 1",
       "invalid target: points[0].velocities[0] (elbow) = 19.7392 rad/s is beyond the joint's 10"},
      {"run --offset 100", "invalid target: points[0].positions[0] (elbow) = 1.74533 is outside"},
      {"run --sine 1 0.1 --duration 200", "points, at most 8192"},
      {"run --duration -1", "--duration must not be negative"},
      {"watch --samples 0", "--samples must be an integer in 1..1000000"},
      {"idle extra", "unexpected argument 'extra'"},
      {"weights", "weights needs at least one NAME=VALUE"},
      {"weights w_theta", "weights takes NAME=VALUE, got 'w_theta'"},
      {"weights w_theta=x", "needs a finite number, got 'x'"},
      {"weights w_theta=1000", "invalid weights: values[0] (w_theta) = 1000 is outside 0.05..400"},
      {"weights w_q=1", "invalid weights: names[0] 'w_q' is not one of: w_theta, w_p, w_tau, w_v"},
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
