// DDS to CAN, end to end: hmpc-forearm-cli sends mode commands and a JointTrajectory over
// Cyclone DDS (loopback, its own domain id) to hmpc-forearm-host, which drives
// hmpc-forearm-board over vcan0 with the Simbody plant in lock-step. The board's mode and
// target, as the host publishes them back over DDS, must follow the CLI, and so must the
// MPC's cost weights; a malformed sample must be rejected and counted, never acted on; a
// commander that hangs must leave the arm holding.
// ctest runs this binary through hil/vcan/run-with-vcan.sh.
#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "hil_run.hpp"
#include "hmpc/dds/endpoint.hpp"
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

// Waits until the host's telemetry shows this mode (and strategy, in run).
bool await_mode(hmpc::dds::ForearmDdsClient& client, proto::BoardMode mode,
                proto::Strategy strategy = proto::Strategy::kTwoStage) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(kWaitS);
  bool seen = false;
  while (!seen && std::chrono::steady_clock::now() < end) {
    client.wait_for_data(1.0);
    client.poll_telemetry([&](const hmpc::dds::ForearmTelemetrySample& t) {
      seen = seen || (t.mode == mode && (mode != proto::BoardMode::kRun || t.strategy == strategy));
    });
    client.poll_joint_states([](const hmpc::dds::JointStateSample&) {});
    client.poll_diagnostics([](const hmpc::dds::DiagnosticSample&) {});
  }
  return seen;
}

// Waits until the host's stderr says `text`.
bool await_errors(const Child& program, const std::string& text) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(kWaitS);
  while (program.errors().find(text) == std::string::npos) {
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return true;
}

// A trajectory with a NaN position, as a broken ROS 2 node could send it.
bool send_malformed_trajectory() {
  namespace msg = hmpc::dds::msg;
  const hmpc::dds::Participant participant(kDomain, hmpc::dds::loopback_config());
  const hmpc::dds::Writer<msg::JointTrajectory> writer(
      participant, hmpc::dds::default_namespace(0) + "/joint_trajectory", hmpc::dds::Qos::state());
  const double nan = std::nan("");
  msg::JointTrajectoryPoint point{};
  point.positions = hmpc::dds::borrow(&nan, 1);
  const char* names[] = {hmpc::dds::kJointName};
  msg::JointTrajectory t{};
  t.header.frame_id = hmpc::dds::borrow("");
  t.joint_names = hmpc::dds::borrow(names, 1);
  t.points = hmpc::dds::borrow<decltype(t.points)>(&point, 1);
  return writer.wait_for_reader(kWaitS) && writer.write(t) && writer.wait_for_acks(kWaitS);
}

TEST(ForearmDdsOverCan, CliCommandsDriveTheBoardMalformedSamplesAreRejectedASilentCommanderHolds) {
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

  hmpc::dds::ForearmDdsClient client(kDomain, 0, hmpc::dds::loopback_config());
  ASSERT_TRUE(client.wait_for_bridge(60));
  ASSERT_TRUE(await_mode(client, proto::BoardMode::kIdle)) << "the host publishes no idle state";

  std::string output;
  ASSERT_EQ(run_cli({"hold"}, output), 0) << output;
  EXPECT_TRUE(await_mode(client, proto::BoardMode::kHold)) << "the board never entered hold";

  // A run with a 2 Hz sinusoid of 160 s (8001 target points, near the host's 8192): the CLI
  // keeps repeating its command until it is stopped below.
  Child run;
  ASSERT_TRUE(
      run.start(HMPC_FOREARM_CLI_PROGRAM,
                {"--domain", std::to_string(kDomain), "--dds-loopback", "--timeout", "60", "run",
                 "--strategy", "coarse_20ms", "--sine", "20", "2", "--duration", "160"},
                dir() + "/run.out", error))
      << error;
  EXPECT_TRUE(await_mode(client, proto::BoardMode::kRun, proto::Strategy::kCoarse20ms))
      << "the board never ran Coarse 20 ms: " << run.output() << run.errors();
  ASSERT_TRUE(await_errors(host, "DDS trajectory of 8001 points")) << host.errors();

  // The JointTrajectory reaches the board: over a period of host time (125 telemetry samples,
  // one per 4 ms MPC period) its target swings through the +-20 deg sinusoid. Each watch has
  // kWaitS of its own: emulated with ASan, a sample can take half a second.
  const auto watch = [&](int samples, auto&& on_sample) {
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::duration<double>(kWaitS);
    int seen = 0;
    while (seen < samples && std::chrono::steady_clock::now() < give_up) {
      client.wait_for_data(1.0);
      client.poll_telemetry([&](const hmpc::dds::ForearmTelemetrySample& t) {
        ++seen;
        on_sample(t);
      });
      client.poll_joint_states([](const hmpc::dds::JointStateSample&) {});
      client.poll_diagnostics([](const hmpc::dds::DiagnosticSample&) {});
    }
    return seen;
  };
  double low = 1, high = -1;
  EXPECT_EQ(watch(125,
                  [&](const hmpc::dds::ForearmTelemetrySample& t) {
                    low = std::min(low, t.theta_d);
                    high = std::max(high, t.theta_d);
                  }),
            125);
  const double a = 20 * M_PI / 180;
  EXPECT_LT(low, -0.9 * a) << "target range " << low << ".." << high;
  EXPECT_GT(high, 0.9 * a) << "target range " << low << ".." << high;
  EXPECT_GE(low, -a - 1e-6);
  EXPECT_LE(high, a + 1e-6);

  // Ended (SIGTERM: the CLI asks for hold), then a run without a target and without an end, so
  // that what follows does not depend on how long an emulated test takes.
  EXPECT_EQ(run.stop(kWaitS), 0) << run.output() << run.errors();
  EXPECT_TRUE(await_mode(client, proto::BoardMode::kHold)) << "the ended run never held";
  Child endless;
  ASSERT_TRUE(endless.start(HMPC_FOREARM_CLI_PROGRAM,
                            {"--domain", std::to_string(kDomain), "--dds-loopback", "--timeout",
                             "60", "run", "--strategy", "coarse_20ms"},
                            dir() + "/endless.out", error))
      << error;
  EXPECT_TRUE(await_mode(client, proto::BoardMode::kRun, proto::Strategy::kCoarse20ms))
      << "the board never ran again: " << endless.output() << endless.errors();

  // A trajectory with a NaN: rejected by the host's bridge; the board keeps running as it
  // was, with the same strategy, holding its angle inside +-20 deg, for the 50 MPC periods
  // (0.2 s of host time) watched after the host has said so.
  ASSERT_TRUE(send_malformed_trajectory());
  ASSERT_TRUE(await_errors(host, "not_finite")) << "the host never rejected it: " << host.errors();
  int unchanged = 0;
  const int watched = watch(50, [&](const hmpc::dds::ForearmTelemetrySample& t) {
    unchanged += t.mode == proto::BoardMode::kRun && t.strategy == proto::Strategy::kCoarse20ms &&
                 std::abs(t.theta_d) <= a + 1e-6;
  });
  EXPECT_EQ(watched, 50);
  EXPECT_EQ(unchanged, watched) << "the rejected sample changed the board's mode, strategy or "
                                   "target";

  // New cost weights while it runs: over DDS to the host, over CAN to the board, which adopts
  // them (its summary at the end) and runs on.
  ASSERT_EQ(run_cli({"weights", "w_theta=80", "w_v=0.004"}, output), 0) << output;
  ASSERT_TRUE(await_errors(host, "DDS cost weights")) << host.errors();
  EXPECT_EQ(watch(25,
                  [&](const hmpc::dds::ForearmTelemetrySample& t) {
                    EXPECT_EQ(t.mode, proto::BoardMode::kRun);
                  }),
            25);

  // The commander hangs: the host notices within the command deadline and holds.
  endless.signal(SIGSTOP);
  ASSERT_TRUE(await_errors(host, "commander silent at")) << host.errors();
  EXPECT_TRUE(await_mode(client, proto::BoardMode::kHold)) << "the board never held";
  endless.signal(SIGKILL);
  endless.signal(SIGCONT);

  // A valid command after it proves the bridge is still listening.
  ASSERT_EQ(run_cli({"idle"}, output), 0) << output;
  EXPECT_TRUE(await_mode(client, proto::BoardMode::kIdle)) << "the board never went idle";

  EXPECT_EQ(plant.stop(30), 0) << plant.errors();
  EXPECT_EQ(host.stop(30), 0) << host.errors();
  EXPECT_EQ(board.stop(30), 0) << board.errors();
  const auto summary = hmpc::platform::parse_summary(host.output());
  EXPECT_GE(std::stoi(summary.at("dds_commands")), 4) << "hold, run repeated, idle";
  EXPECT_EQ(summary.at("dds_trajectories"), "1");
  EXPECT_EQ(summary.at("dds_rejected"), "1");
  EXPECT_EQ(summary.at("dds_rejects"), "not_finite=1");
  EXPECT_GE(std::stoi(summary.at("dds_commander_silences")), 1);
  const std::string errors = host.errors();
  EXPECT_EQ(errors.find("commander silent at"), errors.rfind("commander silent at"))
      << "only the run's silence holds the arm: " << errors;
  const auto board_summary = hmpc::platform::parse_summary(board.output());
  EXPECT_EQ(board_summary.at("cost_weight_updates"), "1");
  EXPECT_EQ(board_summary.at("w_theta"), "80");
  EXPECT_EQ(board_summary.at("w_p"), "30") << "kept";
  EXPECT_EQ(board_summary.at("w_v"), "0.004");
  EXPECT_EQ(summary.at("dds_weights"), "1");
  EXPECT_EQ(board_summary.at("faults"), "0x00");
  EXPECT_EQ(board_summary.at("rejected_frames"), "0");
}

}  // namespace
