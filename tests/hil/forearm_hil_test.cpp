// The forearm HIL over CAN: board, host and Simbody plant as separate programs in
// lock-step on vcan0 (ctest runs this binary through hil/vcan/run-with-vcan.sh).
//  - Every strategy of Table 3.1 tracks the 1 Hz +-30 deg target for 10 s end to end, with the
//    Cortex-M7's compute time charged, a modest plant-model mismatch and sensor noise, and the
//    thesis's ordering holds (Fig. 3.3b at 1 Hz): Two-stage the lowest accumulated cost, Fine
//    4 ms above the strategies that fit the period (see below for Coarse 40 ms); the hybrid
//    beats PAM-only on RMS error; the motor's share of the torque is small but not zero.
//  - Faults (dropped, corrupted, delayed frames; a dead host; 100 ms of silence): the board
//    ends in its safe state or rides through as specified, the joint never leaves its
//    mechanical range, and every log is complete.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>

#include "child_process.hpp"
#include "hil_run.hpp"

namespace {

namespace proto = hmpc::forearm_protocol;
using hmpc::hil::HilRunResult;
using hmpc::hil::HilRunSpec;
using proto::Strategy;

std::string work_dir() {
  const char* tmp = std::getenv("TMPDIR");
  return std::string(tmp ? tmp : "/tmp") + "/hmpc-forearm-hil-test";
}

HilRunSpec spec(Strategy strategy, const std::string& name) {
  HilRunSpec s;
  s.strategy = strategy;
  s.frequency_hz = 1.0;
  s.noise_scale = 1;
  s.seed = 1;
  s.mismatch = {1.05, 1.2, 1.1};  // as the demo's default (hmpc-forearm-hil)
  s.directory = work_dir() + "/" + name;
  return s;
}

std::size_t lines_of(const std::string& path) {
  std::ifstream in(path);
  std::size_t n = 0;
  for (std::string line; std::getline(in, line);) ++n;
  return n;
}

// Every program finished cleanly and wrote all it should: one plant log row per simulated
// millisecond, one host row per SolveTelemetry report, the joint within the stops.
void expect_intact(const HilRunResult& r, const HilRunSpec& s) {
  ASSERT_TRUE(r.ok) << r.error;
  const double steps = r.number(r.plant, "steps");
  EXPECT_EQ(steps, std::round((s.run_at_s + s.run_for_s + s.settle_s) * 1e3));
  EXPECT_EQ(double(lines_of(s.directory + "/plant.csv")), steps + 1);  // with the header
  EXPECT_EQ(double(lines_of(s.directory + "/host.csv")),
            r.number(r.host, "telemetry_frames") + 1);
  EXPECT_TRUE(r.within_stops) << "theta range [" << r.theta_min << ", " << r.theta_max << "]";
  EXPECT_EQ(r.number(r.board, "heap_allocations_in_loop"), 0);
}

class ForearmHilStrategies : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    for (Strategy s : {Strategy::kFine4ms, Strategy::kFine8ms, Strategy::kCoarse20ms,
                       Strategy::kCoarse40ms, Strategy::kTwoStage, Strategy::kPamOnly}) {
      const std::string name = proto::value_name(proto::kStrategyValues, std::uint32_t(s));
      specs_[s] = spec(s, name);
      results_[s] = hmpc::hil::run_hil(specs_[s], hmpc::hil::HilPrograms::built());
      const HilRunResult& r = results_[s];
      std::printf("%-12s cost %8.1f  RMS %.3f deg  max solve %.2f ms  median %.2f ms  misses %.0f"
                  "  motor share %.1f %%  plant RTF %.2f\n",
                  name.c_str(), r.accumulated_cost, r.rms_error * 180 / M_PI,
                  r.solve_time_max_us / 1e3, r.solve_time_median_us / 1e3, r.deadline_misses,
                  100 * r.motor_share(), r.number(r.plant, "real_time_factor"));
    }
  }
  static std::map<Strategy, HilRunSpec> specs_;
  static std::map<Strategy, HilRunResult> results_;
};
std::map<Strategy, HilRunSpec> ForearmHilStrategies::specs_;
std::map<Strategy, HilRunResult> ForearmHilStrategies::results_;

TEST_F(ForearmHilStrategies, EveryStrategyRunsEndToEndOverCan) {
  for (const auto& [strategy, r] : results_) {
    SCOPED_TRACE(proto::value_name(proto::kStrategyValues, std::uint32_t(strategy)));
    ASSERT_NO_FATAL_FAILURE(expect_intact(r, specs_[strategy]));
    EXPECT_EQ(r.host.at("board_mode"), "hold");  // the script's end: run, then hold
    EXPECT_EQ(r.number(r.host, "board_faults"), 0);
    EXPECT_EQ(r.number(r.board, "fallbacks"), 0);
    EXPECT_EQ(r.number(r.board, "rejected_frames"), 0);
    EXPECT_GT(r.number(r.host, "solves"), 0.9 * 10 / 0.004 * 0.3);  // even Fine 4 ms solves
    EXPECT_LT(r.rms_error, 10 * M_PI / 180);                        // it tracks
  }
}

// Fig. 3.3b at 1 Hz: the Two-stage MPC has the lowest accumulated cost of all. Fine 4 ms, its
// output delayed whenever a solve overruns, costs more than every strategy that fits the period
// with the same or finer resolution (Fine 8 ms, Coarse 20 ms, Two-stage). Unlike on the thesis's
// robot it is not the highest overall: our solver on the 400 MHz Cortex-M7 overruns only ~1 % of
// Fine 4 ms's periods (the thesis's took over 4 ms on a 2.6 GHz Xeon), while Coarse 40 ms's
// 40 ms steps are too coarse for the 1 Hz target (measured: Coarse 40 ms 3145, Fine 4 ms 3019).
TEST_F(ForearmHilStrategies, TwoStageHasTheLowestCostAndFine4msCostsMoreThanTheFinerOnes) {
  const double two_stage = results_.at(Strategy::kTwoStage).accumulated_cost;
  const double fine4 = results_.at(Strategy::kFine4ms).accumulated_cost;
  for (const auto& [strategy, r] : results_) {
    SCOPED_TRACE(proto::value_name(proto::kStrategyValues, std::uint32_t(strategy)));
    if (strategy != Strategy::kTwoStage) {
      EXPECT_LT(two_stage, r.accumulated_cost);
    }
  }
  for (Strategy s : {Strategy::kFine8ms, Strategy::kCoarse20ms, Strategy::kTwoStage}) {
    EXPECT_GT(fine4, results_.at(s).accumulated_cost)
        << proto::value_name(proto::kStrategyValues, std::uint32_t(s));
  }
}

TEST_F(ForearmHilStrategies, HybridBeatsPamOnlyAndTheMotorShareIsSmallButNonzero) {
  const HilRunResult& hybrid = results_.at(Strategy::kTwoStage);
  const HilRunResult& pam_only = results_.at(Strategy::kPamOnly);
  EXPECT_LT(hybrid.rms_error, pam_only.rms_error);
  EXPECT_GT(hybrid.motor_share(), 0.01);
  EXPECT_LT(hybrid.motor_share(), 0.2);
  EXPECT_EQ(pam_only.mean_abs_motor_torque, 0.0);
}

TEST_F(ForearmHilStrategies, SlowStrategiesOverrunTheControlPeriodOnTheTarget) {
  // Fig. 3.3a: the fine strategies exceed the 4 ms period on the board, the others do not.
  EXPECT_GT(results_.at(Strategy::kFine4ms).solve_time_max_us, 4000);
  EXPECT_GT(results_.at(Strategy::kFine4ms).deadline_misses, 0);
  for (Strategy s : {Strategy::kCoarse20ms, Strategy::kCoarse40ms, Strategy::kTwoStage}) {
    EXPECT_LT(results_.at(s).solve_time_max_us, 4000);
    EXPECT_EQ(results_.at(s).deadline_misses, 0);
  }
}

// ---- faults: 1.2 s of run after the hold, Two-stage, 1 Hz -----------------------------------

HilRunResult run_fault(const std::string& name, std::vector<std::string> plant_args,
                       std::vector<std::string> host_args, HilRunSpec* out_spec = nullptr) {
  HilRunSpec s = spec(Strategy::kTwoStage, "fault_" + name);
  s.run_for_s = 1.2;
  s.plant_args = std::move(plant_args);
  s.host_args = std::move(host_args);
  HilRunResult r = hmpc::hil::run_hil(s, hmpc::hil::HilPrograms::built());
  if (out_spec) *out_spec = s;
  std::printf("%s: board mode %s faults %s, RMS %.3f deg, theta [%.3f, %.3f]\n", name.c_str(),
              r.host.count("board_mode") ? r.host.at("board_mode").c_str() : "?",
              r.host.count("board_faults") ? r.host.at("board_faults").c_str() : "?",
              r.rms_error * 180 / M_PI, r.theta_min, r.theta_max);
  return r;
}

// The board in fault with exactly `bits`, its last outputs to the plant safe (valve vented,
// motor off) and the plant's last applied inputs the same.
void expect_safe_fault(const HilRunResult& r, unsigned bits) {
  EXPECT_EQ(r.host.at("board_mode"), "fault");
  EXPECT_EQ(unsigned(r.number(r.host, "board_faults")), bits);
  EXPECT_EQ(r.board.at("mode"), "fault");
  EXPECT_EQ(r.number(r.plant, "last_v_p"), 0);
  EXPECT_EQ(r.number(r.plant, "last_v_m"), 0);
}

TEST(ForearmHilFaults, DeadHostTripsTheWatchdogIntoTheSafeState) {
  HilRunSpec s;
  const HilRunResult r = run_fault("dead_host", {"--host-timeout", "0.3"},
                                   {"--stop-heartbeat-at", "0.8"}, &s);
  ASSERT_NO_FATAL_FAILURE(expect_intact(r, s));
  expect_safe_fault(r, proto::fault::kHeartbeatTimeout);
  EXPECT_EQ(r.number(r.board, "watchdog_trips"), 1);
}

TEST(ForearmHilFaults, HundredMillisecondsOfHostSilenceTripTheWatchdog) {
  HilRunSpec s;
  const HilRunResult r = run_fault("host_silence", {"--host-timeout", "0.3"},
                                   {"--silence-at", "0.8", "--silence-ms", "100"}, &s);
  ASSERT_NO_FATAL_FAILURE(expect_intact(r, s));
  expect_safe_fault(r, proto::fault::kHeartbeatTimeout);
}

TEST(ForearmHilFaults, HundredMillisecondsOfSensorSilenceFaultTheBoard) {
  HilRunSpec s;
  const HilRunResult r =
      run_fault("sensor_silence", {"--silence-at", "0.8", "--silence-ms", "100"}, {}, &s);
  ASSERT_NO_FATAL_FAILURE(expect_intact(r, s));
  expect_safe_fault(r, proto::fault::kSensorTimeout);
  EXPECT_EQ(r.number(r.plant, "sensor_silenced"), 100);
}

TEST(ForearmHilFaults, CorruptedAndDroppedSensorFramesAreRiddenThrough) {
  // 5 % lost and 5 % corrupted: five readings in a row go missing with probability 1e-5 per
  // tick, so the board keeps running on the readings it accepts and rejects the corrupt ones.
  HilRunSpec s;
  const HilRunResult r = run_fault("sensor_loss",
                                   {"--drop-percent", "5", "--corrupt-percent", "5"}, {}, &s);
  ASSERT_NO_FATAL_FAILURE(expect_intact(r, s));
  EXPECT_EQ(r.host.at("board_mode"), "hold");  // the run ended normally
  EXPECT_EQ(r.number(r.host, "board_faults"), 0);
  EXPECT_GT(r.number(r.plant, "sensor_dropped"), 20);
  EXPECT_GT(r.number(r.plant, "sensor_corrupted"), 20);
  EXPECT_GT(r.number(r.board, "rejected_frames"), 20);
  EXPECT_LT(r.rms_error, 10 * M_PI / 180);
}

TEST(ForearmHilFaults, DelayedSensorsStillTrack) {
  HilRunSpec s;
  const HilRunResult r = run_fault("sensor_delay", {"--sensor-delay-ms", "4"}, {}, &s);
  ASSERT_NO_FATAL_FAILURE(expect_intact(r, s));
  EXPECT_EQ(r.host.at("board_mode"), "hold");
  EXPECT_EQ(r.number(r.host, "board_faults"), 0);
  EXPECT_LT(r.rms_error, 10 * M_PI / 180);
}

TEST(ForearmHilFaults, CorruptedHostFramesAreRejectedNeverActedOn) {
  // 20 % of the host's frames with a flipped bit: the board rejects each (CRC-8) and counts
  // it; two heartbeats in a row lost trip the watchdog, as specified. Either way: rejected,
  // and if it faulted, for the heartbeat and nothing else.
  HilRunSpec s;
  const HilRunResult r = run_fault("host_corrupt", {"--host-timeout", "0.3"},
                                   {"--corrupt-percent", "20"}, &s);
  ASSERT_NO_FATAL_FAILURE(expect_intact(r, s));
  EXPECT_GT(r.number(r.host, "frames_corrupted"), 10);
  EXPECT_GT(r.number(r.board, "rejected_frames"), 10);
  if (r.host.at("board_mode") == "fault") {
    expect_safe_fault(r, proto::fault::kHeartbeatTimeout);
  } else {
    EXPECT_EQ(r.number(r.host, "board_faults"), 0);
  }
}

// ---- real time ---------------------------------------------------------------------------

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
