// Faults in the forearm HIL over CAN (board, host and Simbody plant as separate programs in
// lock-step on vcan0; ctest runs this binary through hil/vcan/run-with-vcan.sh): dropped,
// corrupted and delayed frames, a dead host, windows of silence. The board ends in its safe
// state or rides through as specified, the joint never leaves its mechanical range, and every
// log is complete. Where a watchdog acts, its latency is read off the board's tick log and the
// plant's log in lock-step ticks (1 ms, a quarter of the 4 ms MPC period), which are the
// board's own clock whatever the speed of the machine.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "child_process.hpp"
#include "forearm_hil_support.hpp"

namespace {

namespace proto = hmpc::forearm_protocol;
using hmpc::hil::BoardTickRow;
using hmpc::hil::HilRunResult;
using hmpc::hil::HilRunSpec;
using hmpc::hil::test::expect_intact;
using hmpc::hil::test::lines_of;
using hmpc::hil::test::work_dir;
using proto::Strategy;

// 1.2 s of Two-stage run at 1 Hz after the hold; faults start at 0.8 s, inside the run.
constexpr double kFaultAtS = 0.8;
constexpr std::uint32_t kFaultAtTick = 800;

HilRunResult run_fault(const std::string& name, std::vector<std::string> plant_args,
                       std::vector<std::string> host_args, HilRunSpec& s) {
  s = hmpc::hil::test::spec(Strategy::kTwoStage, "fault_" + name);
  s.run_for_s = 1.2;
  s.plant_args = std::move(plant_args);
  s.host_args = std::move(host_args);
  HilRunResult r = hmpc::hil::run_hil(s, hmpc::hil::HilPrograms::built());
  std::printf("%s: board mode %s faults %s, RMS %.3f deg, theta [%.3f, %.3f]\n", name.c_str(),
              r.host.count("board_mode") ? r.host.at("board_mode").c_str() : "?",
              r.host.count("board_faults") ? r.host.at("board_faults").c_str() : "?",
              r.rms_error * 180 / M_PI, r.theta_min, r.theta_max);
  return r;
}

// The board's first tick in fault, or nullptr.
const BoardTickRow* first_fault(const HilRunResult& r) {
  for (const BoardTickRow& row : r.board_log) {
    if (row.mode == "fault") return &row;
  }
  return nullptr;
}

// The board in fault with exactly `bits` from its first fault tick on, its outputs safe (valve
// vented, motor off) from that tick, and the plant applying them from the step that tick
// answered to the end of the run. Returns the first fault tick (0: none).
std::uint32_t expect_safe_fault(const HilRunResult& r, unsigned bits) {
  EXPECT_EQ(r.host.at("board_mode"), "fault");
  EXPECT_EQ(unsigned(r.number(r.host, "board_faults")), bits);
  EXPECT_EQ(r.board.at("mode"), "fault");
  const BoardTickRow* fault = first_fault(r);
  if (fault == nullptr) {
    ADD_FAILURE() << "no tick in fault in the board's log";
    return 0;
  }
  bool board_safe = true;
  for (const BoardTickRow* row = fault; row != r.board_log.data() + r.board_log.size(); ++row) {
    board_safe =
        board_safe && row->mode == "fault" && row->faults == bits && row->v_p == 0 && row->v_m == 0;
  }
  EXPECT_TRUE(board_safe) << "the board left the safe state after tick " << fault->tick;
  // Plant row k: step k, driven by the answer to Sync k, computed in board tick k + 1.
  bool plant_safe = fault->tick >= 1;
  for (std::size_t k = fault->tick - 1; k < r.plant_log.size(); ++k) {
    plant_safe = plant_safe && r.plant_log[k].v_p == 0 && r.plant_log[k].v_m == 0;
  }
  EXPECT_TRUE(plant_safe) << "the plant did not apply the safe outputs from the step of tick "
                          << fault->tick;
  EXPECT_EQ(r.number(r.plant, "last_v_p"), 0);
  EXPECT_EQ(r.number(r.plant, "last_v_m"), 0);
  return fault->tick;
}

// The heartbeat watchdog's latency: it trips on the first tick on which the last accepted
// heartbeat is older than its timeout, and a heartbeat the host sends in its tick h reaches
// the board before the board's tick h + 2 (the plant waits for it before the next Sync).
void expect_heartbeat_trip_latency(const HilRunResult& r, std::uint32_t fault_tick) {
  const double timeout = r.number(r.board, "heartbeat_timeout_ticks");
  const BoardTickRow& row = r.board_log.at(fault_tick - r.board_log.front().tick);
  EXPECT_EQ(double(row.heartbeat_age), timeout + 1);
  const double last_sent_tick = std::round(r.number(r.host, "last_heartbeat_s") * 1e3);
  std::printf(
      "heartbeat watchdog: last heartbeat sent at host tick %.0f, safe outputs from "
      "board tick %u (%.0f ticks, %.1f MPC periods; timeout %.0f ticks)\n",
      last_sent_tick, fault_tick, fault_tick - last_sent_tick, (fault_tick - last_sent_tick) / 4,
      timeout);
  EXPECT_GT(double(fault_tick), last_sent_tick + timeout);
  EXPECT_LE(double(fault_tick), last_sent_tick + timeout + 2);
}

TEST(ForearmHilFaults, DeadHostTripsTheWatchdogIntoTheSafeState) {
  HilRunSpec s;
  const HilRunResult r = run_fault("dead_host", {"--host-timeout", "0.3"},
                                   {"--stop-heartbeat-at", std::to_string(kFaultAtS)}, s);
  ASSERT_NO_FATAL_FAILURE(expect_intact(r, s));
  const std::uint32_t fault_tick = expect_safe_fault(r, proto::fault::kHeartbeatTimeout);
  ASSERT_GT(fault_tick, 0u);
  expect_heartbeat_trip_latency(r, fault_tick);
  EXPECT_LT(r.number(r.host, "last_heartbeat_s"), kFaultAtS);
  EXPECT_EQ(r.number(r.board, "watchdog_trips"), 1);
}

TEST(ForearmHilFaults, HundredMillisecondsOfHostSilenceTripTheWatchdog) {
  HilRunSpec s;
  const HilRunResult r =
      run_fault("host_silence", {"--host-timeout", "0.3"},
                {"--silence-at", std::to_string(kFaultAtS), "--silence-ms", "100"}, s);
  ASSERT_NO_FATAL_FAILURE(expect_intact(r, s));
  const std::uint32_t fault_tick = expect_safe_fault(r, proto::fault::kHeartbeatTimeout);
  ASSERT_GT(fault_tick, 0u);
  // The heartbeats resume after the silence, but the fault is latched: the trip's latency is
  // from the last heartbeat before the silence.
  const double timeout = r.number(r.board, "heartbeat_timeout_ticks");
  const BoardTickRow& row = r.board_log.at(fault_tick - r.board_log.front().tick);
  EXPECT_EQ(double(row.heartbeat_age), timeout + 1);
  EXPECT_GT(double(fault_tick), kFaultAtTick - 10 + timeout);  // heartbeats every 10 ticks
  EXPECT_LE(double(fault_tick), kFaultAtTick + timeout + 2);
}

// The sensor watchdog: Sensor frames stop at 0.8 s (the plant's step 800 sends none; the board
// read the last one before its tick 800). The watchdog trips on the first tick on which that
// reading is older than its timeout.
TEST(ForearmHilFaults, HundredMillisecondsOfSensorSilenceFaultTheBoard) {
  HilRunSpec s;
  const HilRunResult r = run_fault(
      "sensor_silence", {"--silence-at", std::to_string(kFaultAtS), "--silence-ms", "100"}, {}, s);
  ASSERT_NO_FATAL_FAILURE(expect_intact(r, s));
  const std::uint32_t fault_tick = expect_safe_fault(r, proto::fault::kSensorTimeout);
  ASSERT_GT(fault_tick, 0u);
  EXPECT_EQ(r.number(r.plant, "sensor_silenced"), 100);
  const double timeout = r.number(r.board, "sensor_timeout_ticks");
  const BoardTickRow& row = r.board_log.at(fault_tick - r.board_log.front().tick);
  EXPECT_EQ(double(row.sensor_age), timeout + 1);
  std::printf(
      "sensor watchdog: readings stop after board tick %u, safe outputs from tick %u "
      "(%u ticks; timeout %.0f ticks)\n",
      kFaultAtTick, fault_tick, fault_tick - kFaultAtTick, timeout);
  EXPECT_GE(double(fault_tick), kFaultAtTick + timeout);
  EXPECT_LE(double(fault_tick), kFaultAtTick + timeout + 1);
}

TEST(ForearmHilFaults, CorruptedAndDroppedSensorFramesAreRiddenThrough) {
  // 5 % lost and 5 % corrupted: five readings in a row go missing with probability 1e-5 per
  // tick, so the board keeps running on the readings it accepts and rejects the corrupt ones.
  HilRunSpec s;
  const HilRunResult r =
      run_fault("sensor_loss", {"--drop-percent", "5", "--corrupt-percent", "5"}, {}, s);
  ASSERT_NO_FATAL_FAILURE(expect_intact(r, s));
  EXPECT_EQ(r.host.at("board_mode"), "hold");  // the run ended normally
  EXPECT_EQ(r.number(r.host, "board_faults"), 0);
  EXPECT_GT(r.number(r.plant, "sensor_dropped"), 20);
  EXPECT_GT(r.number(r.plant, "sensor_corrupted"), 20);
  // Every corrupted frame rejected (a flipped bit fails the CRC-8), and nothing else.
  EXPECT_EQ(r.number(r.board, "rejected_frames"), r.number(r.plant, "sensor_corrupted"));
  EXPECT_LT(r.rms_error, 10 * M_PI / 180);
}

TEST(ForearmHilFaults, DelayedSensorsStillTrack) {
  HilRunSpec s;
  const HilRunResult r = run_fault("sensor_delay", {"--sensor-delay-ms", "4"}, {}, s);
  ASSERT_NO_FATAL_FAILURE(expect_intact(r, s));
  EXPECT_EQ(r.host.at("board_mode"), "hold");
  EXPECT_EQ(r.number(r.host, "board_faults"), 0);
  EXPECT_LT(r.rms_error, 10 * M_PI / 180);
}

// 20 % of the host's frames with a bit flipped: the board rejects every one (CRC-8) and acts
// on none, and the run's outcome is the one the intact heartbeats dictate: the board faults,
// for the heartbeat alone, exactly when two heartbeats in a row were lost, i.e. when the
// longest interval between intact heartbeats in hold or run exceeds the watchdog's timeout.
TEST(ForearmHilFaults, CorruptedHostFramesAreRejectedNeverActedOn) {
  HilRunSpec s;
  const HilRunResult r =
      run_fault("host_corrupt", {"--host-timeout", "0.3"}, {"--corrupt-percent", "20"}, s);
  ASSERT_NO_FATAL_FAILURE(expect_intact(r, s));
  EXPECT_GT(r.number(r.host, "frames_corrupted"), 10);
  EXPECT_EQ(r.number(r.board, "rejected_frames"), r.number(r.host, "frames_corrupted"));
  const double gap = r.number(r.host, "heartbeat_max_gap_ms");
  const bool must_fault = gap > r.number(r.board, "heartbeat_timeout_ticks");
  std::printf("longest interval between intact heartbeats %.0f ms: the board must %s\n", gap,
              must_fault ? "fault" : "keep running");
  if (must_fault) {
    const std::uint32_t fault_tick = expect_safe_fault(r, proto::fault::kHeartbeatTimeout);
    ASSERT_GT(fault_tick, 0u);
    const BoardTickRow& row = r.board_log.at(fault_tick - r.board_log.front().tick);
    EXPECT_EQ(double(row.heartbeat_age), r.number(r.board, "heartbeat_timeout_ticks") + 1);
  } else {
    EXPECT_EQ(r.host.at("board_mode"), "hold");
    EXPECT_EQ(r.number(r.host, "board_faults"), 0);
    EXPECT_EQ(first_fault(r), nullptr);
  }
}

// Without --lockstep a 1 kHz timer paces the plant: one Sensor frame per step, no Sync, and the
// run takes its simulated time on the wall clock. Where the machine is too slow for that (the
// Simbody plant under QEMU without KVM runs at ~0.25x), it says so: the steps it took late
// are counted as deadline misses and its real-time factor is below 1.
TEST(ForearmPlantNode, RealTimeModeIsPacedByTheClockAndReportsItsSpeed) {
  const std::string out = work_dir() + "/plant_real_time";
  std::filesystem::create_directories(out);
  hmpc::hil::Child plant;
  std::string error;
  ASSERT_TRUE(plant.start(hmpc::hil::HilPrograms::built().plant,
                          {"--node", "9", "--duration", "0.5", "--log", out + "/plant.csv"},
                          out + "/plant.out", error))
      << error;
  ASSERT_EQ(plant.wait(120), 0) << plant.errors();
  const auto s = hmpc::hil::parse_summary(plant.output());
  std::printf("real time: %s s wall for 0.5 s, real-time factor %s, deadline misses %s\n",
              s.at("wall_seconds").c_str(), s.at("real_time_factor").c_str(),
              s.at("deadline_misses").c_str());
  EXPECT_EQ(s.at("steps"), "500");
  EXPECT_EQ(s.at("sensor_frames"), "500");
  EXPECT_EQ(s.at("syncs"), "0");
  const double wall = std::stod(s.at("wall_seconds"));
  EXPECT_GE(wall, 0.49);  // paced by the clock, never faster
  EXPECT_NEAR(std::stod(s.at("real_time_factor")), 0.5 / wall, 0.01);
  if (wall > 0.6) {
    EXPECT_GT(std::stod(s.at("deadline_misses")), 0);
  }
  EXPECT_EQ(double(lines_of(out + "/plant.csv")), 501);
}

}  // namespace
