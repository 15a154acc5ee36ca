// The forearm HIL over CAN: board, host and Simbody plant as separate programs in lock-step on
// vcan0 (ctest runs this binary through hil/vcan/run-with-vcan.sh). Every strategy of Table 3.1
// tracks the 1 Hz +-30 deg target end to end, with the Cortex-M7's compute time charged, a
// modest plant-model mismatch and sensor noise, and the thesis's ordering holds at 1 Hz: the
// Two-stage the lowest RMS error (Fig. 3.6); solve times grow with the problem's size, and a
// strategy whose solves overrun the period pays for it in cost; the hybrid beats PAM-only on
// RMS error; the motor's share of the torque is small but not zero. With the terminal rate term
// in its stages (the boards' --terminal-rate) the Two-stage has the lowest cost at 1 Hz (Fig.
// 3.3b) and the lowest RMS error of every strategy at 0.5, 1 and 1.8 Hz, and at 1.8 Hz, where
// the actuators are at their limits, it still follows the target. The full experiment (every
// frequency, five trials) is hmpc-forearm-hil's.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <complex>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "forearm_hil_support.hpp"
#include "hmpc/models/forearm_tracking_limit.hpp"

namespace {

namespace proto = hmpc::forearm_protocol;
using hmpc::hil::HilRunResult;
using hmpc::hil::HilRunSpec;
using hmpc::hil::test::expect_intact;
using proto::Strategy;

// The thesis's 10 s trials (Sec. 3.4): over 4 s the first second's transition from hold weighs
// too much in the cost (measured: Two-stage 1267.5 against Fine 8 ms 1267.3), and at 1.8 Hz
// the Two-stage with the terminal rate term leads most in the first seconds (below).
constexpr double kRunSeconds = 10;
constexpr double kControlPeriodS = 0.004;
constexpr double kSolveBudgetUs = 3500;  // the board's deadline for one MPC step (4 ms period)
constexpr double kDegree = M_PI / 180;

const std::vector<Strategy> kStrategies{Strategy::kFine4ms,    Strategy::kFine8ms,
                                        Strategy::kCoarse20ms, Strategy::kCoarse40ms,
                                        Strategy::kTwoStage,   Strategy::kPamOnly};

// One run: a strategy as the thesis has it, or the Two-stage with the terminal rate term.
struct StrategyRun {
  Strategy strategy = Strategy::kTwoStage;
  bool terminal_rate = false;
  double frequency_hz = 1;
  HilRunSpec spec;
  HilRunResult result;

  std::string name() const {
    char f[16];
    std::snprintf(f, sizeof f, "_%.2fhz", frequency_hz);
    return std::string(proto::value_name(proto::kStrategyValues, std::uint32_t(strategy))) +
           (terminal_rate ? "_terminal_rate" : "") + f;
  }
};

class ForearmHilStrategies : public ::testing::Test {
 protected:
  // Two runs at a time, each with its own board node id on the shared bus (ctest gives the
  // launcher's guest two CPUs for this test). A lock-step run's figures should not depend on
  // it, but under load one moved (Coarse 20 ms at 1 Hz: cost 0.1 %, RMS error 1 %; below).
  static void SetUpTestSuite() {
    // The thesis's Two-stage at 1 Hz only: elsewhere it is not compared.
    for (double f : {1.0, 0.5, 1.8}) {
      for (Strategy s : kStrategies)
        if (s != Strategy::kTwoStage || f == 1.0) add(s, false, f);
      add(Strategy::kTwoStage, true, f);
    }
    std::atomic<std::size_t> next{0};
    const auto worker = [&](hmpc::forearm_protocol::NodeId node) {
      for (std::size_t i = next++; i < runs_.size(); i = next++) {
        HilRunSpec spec = runs_[i].spec;
        spec.node = node;
        runs_[i].result = hmpc::hil::run_hil(spec, hmpc::hil::HilPrograms::built());
      }
    };
    std::thread second(worker, 1);
    worker(0);
    second.join();
    for (const StrategyRun& run : runs_) {
      const HilRunResult& r = run.result;
      std::printf(
          "%-32s cost %8.1f  RMS %.3f deg  max solve %.2f ms  median %.2f ms  misses %.0f"
          "  motor share %.1f %%  plant RTF %.2f\n",
          run.name().c_str(), r.accumulated_cost, r.rms_error / kDegree, r.solve_time_max_us / 1e3,
          r.solve_time_median_us / 1e3, r.deadline_misses, 100 * r.motor_share(),
          r.number(r.plant, "real_time_factor"));
    }
  }
  static void add(Strategy s, bool terminal_rate, double frequency_hz) {
    StrategyRun run{s, terminal_rate, frequency_hz, {}, {}};
    run.spec = hmpc::hil::test::spec(s, run.name());
    run.spec.target.frequency_hz = frequency_hz;
    run.spec.run_for_s = kRunSeconds;
    if (terminal_rate) run.spec.board_args.push_back("--terminal-rate");
    runs_.push_back(run);
  }
  static const StrategyRun& run(Strategy s, bool terminal_rate, double frequency_hz) {
    for (const StrategyRun& r : runs_)
      if (r.strategy == s && r.terminal_rate == terminal_rate && r.frequency_hz == frequency_hz)
        return r;
    throw std::logic_error("no such run");
  }
  // The thesis's strategies at 1 Hz, where Fig. 3.3 orders them.
  static const HilRunResult& result(Strategy s) { return run(s, false, 1.0).result; }
  static std::vector<StrategyRun> runs_;
};
std::vector<StrategyRun> ForearmHilStrategies::runs_;

TEST_F(ForearmHilStrategies, EveryStrategyRunsEndToEndOverCan) {
  for (const StrategyRun& run : runs_) {
    SCOPED_TRACE(run.name());
    const HilRunResult& r = run.result;
    ASSERT_NO_FATAL_FAILURE(expect_intact(r, run.spec));
    EXPECT_EQ(r.host.at("board_mode"), "hold");  // the script's end: run, then hold
    EXPECT_EQ(r.number(r.host, "board_faults"), 0);
    EXPECT_EQ(r.number(r.board, "fallbacks"), 0);
    EXPECT_EQ(r.number(r.board, "rejected_frames"), 0);
    EXPECT_EQ(r.board.at("two_stage_terminal_rate"), run.terminal_rate ? "1" : "0");
    // Every control period solved, but for the periods a charged solve still occupies.
    EXPECT_GT(r.number(r.host, "solves"), 0.3 * run.spec.run_for_s / kControlPeriodS);
    // It tracks, where the actuators allow it (1.8 Hz has its own test).
    if (run.frequency_hz <= 1) {
      EXPECT_LT(r.rms_error, 10 * kDegree);
    }
    // Misses are counted exactly where a charged solve exceeds the board's budget.
    EXPECT_EQ(r.deadline_misses > 0, r.solve_time_max_us > kSolveBudgetUs);
  }
}

// Fig. 3.6 at 1 Hz: the thesis's Two-stage MPC tracks with the lowest RMS error of the thesis's
// strategies (five trials over CAN: 1.90 deg against Fine 8 ms's 2.21).
TEST_F(ForearmHilStrategies, TwoStageHasTheLowestErrorAt1Hz) {
  const double two_stage = result(Strategy::kTwoStage).rms_error;
  for (Strategy s : kStrategies) {
    if (s != Strategy::kTwoStage) {
      EXPECT_LT(two_stage, result(s).rms_error) << run(s, false, 1.0).name();
    }
  }
}

// Fig. 3.3b at 1 Hz, the lowest accumulated cost: the thesis's Two-stage and Coarse 20 ms tie
// (five trials: 3000.8 against 3002.4, each trial's spread 1.4, and one seed's lock-step run of
// Coarse 20 ms gave 3004.1 alone and 3001.3 beside a sanitizer build), too close for a test to
// order them; the suite prints them. With the terminal rate term the Two-stage's cost is the lowest
// by 1.6 % (2953.3), which a test can assert.
TEST_F(ForearmHilStrategies, TwoStageWithTheTerminalRateTermHasTheLowestCostAt1Hz) {
  const double two_stage = run(Strategy::kTwoStage, true, 1.0).result.accumulated_cost;
  for (Strategy s : kStrategies) {
    EXPECT_LT(two_stage, result(s).accumulated_cost) << run(s, false, 1.0).name();
  }
}

// Fig. 3.3a: solve time grows with the problem solved each period (horizon N = 50, 25, 10, 5
// on the same model), and the Two-stage, a Coarse 20 ms solve and a 20-step fast one, fits
// the period.
TEST_F(ForearmHilStrategies, SolveTimesGrowWithTheProblem) {
  EXPECT_GT(result(Strategy::kFine4ms).solve_time_max_us,
            result(Strategy::kFine8ms).solve_time_max_us);
  EXPECT_GT(result(Strategy::kFine8ms).solve_time_max_us,
            result(Strategy::kCoarse20ms).solve_time_max_us);
  EXPECT_GT(result(Strategy::kCoarse20ms).solve_time_max_us,
            result(Strategy::kCoarse40ms).solve_time_max_us);
  EXPECT_GT(result(Strategy::kTwoStage).solve_time_max_us,
            result(Strategy::kCoarse20ms).solve_time_max_us);
  for (double f : {0.5, 1.0, 1.8}) {
    EXPECT_LT(run(Strategy::kTwoStage, true, f).result.solve_time_max_us, kSolveBudgetUs) << f;
  }
  EXPECT_LT(result(Strategy::kTwoStage).solve_time_max_us, kSolveBudgetUs);
}

// Sec. 3.4.2: a solve that overruns delays the control. Where Fine 4 ms overruns on the
// Cortex-M7, it costs more than the strategies of the same or coarser resolution that fit the
// period; where it fits, nothing is asserted (the finest model may then be the best).
TEST_F(ForearmHilStrategies, AnOverrunningFineMpcCostsMoreThanTheOnesThatFit) {
  const HilRunResult& fine4 = result(Strategy::kFine4ms);
  if (fine4.deadline_misses == 0)
    GTEST_SKIP() << "Fine 4 ms fits the period on the target: no overrun to pay for";
  for (Strategy s : {Strategy::kFine8ms, Strategy::kCoarse20ms, Strategy::kTwoStage}) {
    EXPECT_GT(fine4.accumulated_cost, result(s).accumulated_cost) << run(s, false, 1.0).name();
  }
}

TEST_F(ForearmHilStrategies, HybridBeatsPamOnlyAndTheMotorShareIsSmallButNonzero) {
  const HilRunResult& hybrid = result(Strategy::kTwoStage);
  const HilRunResult& pam_only = result(Strategy::kPamOnly);
  EXPECT_LT(hybrid.rms_error, pam_only.rms_error);
  EXPECT_GT(hybrid.motor_share(), 0.01);
  EXPECT_LT(hybrid.motor_share(), 0.2);
  EXPECT_EQ(pam_only.mean_abs_motor_torque, 0.0);
}

// With the terminal rate term (our change to Eq. 3.3b: a plan must end moving as the target
// does) the Two-stage tracks best of every strategy at 0.5, 1 and 1.8 Hz. Five trials over CAN
// (hmpc-forearm-hil) put its RMS error at 0.60x, 0.86x and 0.99x the best other's, each trial's
// spread under 0.04 deg; at 1.8 Hz its lead over Coarse 40 ms (0.15 deg) is in the first
// seconds, and over the last 5 s it is 1 % behind. The thesis's Two-stage (compared at 1 Hz
// above) is the same strategy without the term, so it is not a rival here.
TEST_F(ForearmHilStrategies, TwoStageWithTheTerminalRateTermHasTheLowestRmsError) {
  for (double f : {0.5, 1.0, 1.8}) {
    const StrategyRun& two_stage = run(Strategy::kTwoStage, true, f);
    for (Strategy s : kStrategies) {
      if (s == Strategy::kTwoStage) continue;
      const StrategyRun& other = run(s, false, f);
      EXPECT_LT(two_stage.result.rms_error, other.result.rms_error) << other.name();
    }
  }
}

// At 1.8 Hz the actuators cannot make the full +-30 deg (first-harmonic bound on the plant's
// parameters, forearm_tracking_limit.hpp: A_max about 24 deg), and every strategy lagged the
// target by about a quarter period before the terminal rate term. Following the target means a
// lag of at most an eighth of a period (45 deg, half that) at the largest amplitude the
// actuators allow: an RMS error of at most |A - A_max e^(-j pi/4)| / sqrt 2 (about 15 deg; a
// quarter period's lag is 27 deg, holding still 21 deg).
TEST_F(ForearmHilStrategies, At1_8HzTheTwoStageIsWithinTheBoundOfTheActuatorsLimit) {
  const StrategyRun& two_stage = run(Strategy::kTwoStage, true, 1.8);
  const hmpc::forearm::Parameters<double> plant =
      hmpc::hil::with_mismatch(hmpc::forearm::Parameters<double>{}, two_stage.spec.mismatch);
  const hmpc::trajectory::TargetSpec& target = two_stage.spec.target;
  const double a_max =
      hmpc::forearm::tracking_limit(plant, target.frequency_hz, target.amplitude, target.offset)
          .max_amplitude;
  ASSERT_LT(a_max, target.amplitude);  // the limit binds: else this is no test of it
  const double bound = std::abs(target.amplitude - std::polar(a_max, -M_PI / 4)) / std::sqrt(2.0);
  std::printf("1.8 Hz: A_max %.1f deg, RMS bound %.2f deg, Two-stage %.2f deg\n", a_max / kDegree,
              bound / kDegree, two_stage.result.rms_error / kDegree);
  EXPECT_LT(two_stage.result.rms_error, bound);
}

}  // namespace
