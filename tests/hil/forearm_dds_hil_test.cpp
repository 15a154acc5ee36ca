// DDS to CAN, end to end: hmpc-forearm-cli sends commands over Cyclone DDS (loopback,
// its own domain id) to hmpc-forearm-host, which drives hmpc-forearm-board over vcan0 with the
// Simbody plant in lock-step. The board's mode, as the host publishes it back over DDS, must
// follow the CLI's commands; a malformed command must be rejected and counted, never acted on.
// ctest runs this binary through hil/vcan/run-with-vcan.sh.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "hil_run.hpp"
#include "hmpc/dds/forearm_dds.hpp"
#include "hmpc/platform/linux/child_process.hpp"

namespace {

namespace proto = hmpc::forearm_protocol;
using hmpc::platform::Child;

constexpr std::uint32_t kDomain = 88;  // no other test uses it
constexpr double kWaitS = 120;         // lock-step under QEMU without KVM runs ~0.2x real time

std::string dir() {
  const char* tmp = std::getenv("TMPDIR");
  return std::string(tmp ? tmp : "/tmp") + "/hmpc-forearm-dds-hil-test";
}

int run_cli(const std::vector<std::string>& args, std::string& output) {
  Child cli;
  std::vector<std::string> all{"--domain", std::to_string(kDomain), "--dds-loopback", "--timeout",
                               "60"};
  all.insert(all.end(), args.begin(), args.end());
  std::string error;
  if (!cli.start(HMPC_FOREARM_CLI_PROGRAM, all, dir() + "/cli.out", error)) {
    output = error;
    return -1;
  }
  const int status = cli.wait(kWaitS);
  output = cli.output() + cli.errors();
  return status;
}

// Waits until the host publishes a state with this mode (and strategy, in run).
bool await_mode(hmpc::dds::ForearmDdsClient& client, proto::BoardMode mode,
                proto::Strategy strategy = proto::Strategy::kTwoStage) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(kWaitS);
  bool seen = false;
  while (!seen && std::chrono::steady_clock::now() < end) {
    client.wait_for_data(1.0);
    client.poll_state([&](const hmpc::dds::ForearmStateSample& s) {
      seen = seen || (s.mode == mode && (mode != proto::BoardMode::kRun || s.strategy == strategy));
    });
    client.poll_telemetry([](const hmpc::dds::ForearmTelemetrySample&) {});
  }
  return seen;
}

TEST(ForearmDdsOverCan, CliCommandsChangeTheBoardModeAndMalformedOnesAreRejected) {
  std::filesystem::create_directories(dir());
  const hmpc::hil::HilPrograms programs = hmpc::hil::HilPrograms::built();
  Child board, host, plant;
  std::string error;
  ASSERT_TRUE(board.start(programs.board, {"--lockstep"}, dir() + "/board.out", error)) << error;
  ASSERT_TRUE(host.start(programs.host,
                         {"--lockstep", "--dds-domain", std::to_string(kDomain), "--dds-loopback"},
                         dir() + "/host.out", error))
      << error;
  ASSERT_TRUE(board.await_output(": ready", 60) && host.await_output(": ready", 60))
      << board.errors() << host.errors();
  // Long enough in simulated time for every step below; stopped at the end.
  ASSERT_TRUE(plant.start(programs.plant, {"--lockstep", "--wait-host", "--duration", "600"},
                          dir() + "/plant.out", error))
      << error;

  hmpc::dds::ForearmDdsClient client(kDomain, hmpc::dds::loopback_config());
  ASSERT_TRUE(client.wait_for_bridge(60));
  ASSERT_TRUE(await_mode(client, proto::BoardMode::kIdle)) << "the host publishes no idle state";

  std::string output;
  ASSERT_EQ(run_cli({"hold"}, output), 0) << output;
  EXPECT_TRUE(await_mode(client, proto::BoardMode::kHold)) << "the board never entered hold";

  ASSERT_EQ(run_cli({"run", "--strategy", "coarse_20ms", "--sine", "20", "1"}, output), 0)
      << output;
  EXPECT_TRUE(await_mode(client, proto::BoardMode::kRun, proto::Strategy::kCoarse20ms))
      << "the board never ran Coarse 20 ms";

  // NaN amplitude: the host's bridge rejects it; the board keeps running as it was, with the
  // same strategy and the same 20 deg target, for the 0.2 s of host time watched after the
  // host has said so (50 MPC periods, time enough for a command acted on to show).
  ASSERT_EQ(
      run_cli({"--raw-sample", "run", "--strategy", "two_stage", "--sine", "nan", "1"}, output), 0)
      << output;
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::duration<double>(kWaitS);
  while (host.errors().find("amplitude") == std::string::npos &&
         std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_NE(host.errors().find("amplitude"), std::string::npos)
      << "the host never rejected the command: " << host.errors();
  double first_s = -1, last_s = -1;
  int watched = 0, unchanged = 0;
  while (!(last_s - first_s >= 0.2) && std::chrono::steady_clock::now() < give_up) {
    client.wait_for_data(1.0);
    client.poll_state([&](const hmpc::dds::ForearmStateSample& s) {
      if (first_s < 0) first_s = s.board_time_s;
      last_s = s.board_time_s;
      ++watched;
      unchanged += s.mode == proto::BoardMode::kRun && s.strategy == proto::Strategy::kCoarse20ms &&
                   std::abs(s.theta_d) <= 20 * M_PI / 180 + 1e-6;
    });
    client.poll_telemetry([](const hmpc::dds::ForearmTelemetrySample&) {});
  }
  EXPECT_GE(last_s - first_s, 0.2) << "too few states after the rejected command";
  EXPECT_GT(watched, 0);
  EXPECT_EQ(unchanged, watched)
      << "the rejected command changed the board's mode, strategy or target";
  // A valid command after it proves the bridge is still listening.
  ASSERT_EQ(run_cli({"idle"}, output), 0) << output;
  EXPECT_TRUE(await_mode(client, proto::BoardMode::kIdle)) << "the board never went idle";

  EXPECT_EQ(plant.stop(30), 0) << plant.errors();
  EXPECT_EQ(host.stop(30), 0) << host.errors();
  EXPECT_EQ(board.stop(30), 0) << board.errors();
  const auto summary = hmpc::platform::parse_summary(host.output());
  EXPECT_EQ(summary.at("dds_commands"), "3");  // hold, run, idle
  EXPECT_EQ(summary.at("dds_rejected_commands"), "1");
  EXPECT_NE(host.errors().find("amplitude"), std::string::npos)
      << "the rejection names the field: " << host.errors();
  const auto board_summary = hmpc::platform::parse_summary(board.output());
  EXPECT_EQ(board_summary.at("faults"), "0x00");
  EXPECT_EQ(board_summary.at("rejected_frames"), "0");
}

}  // namespace
