// The forearm HIL over CAN: board, host and Simbody plant as separate programs in lock-step on
// vcan0 (ctest runs this binary through hil/vcan/run-with-vcan.sh). Every strategy of Table 3.1
// tracks the 1 Hz +-30 deg target end to end, with the Cortex-M7's compute time charged, a
// modest plant-model mismatch and sensor noise, and the thesis's ordering holds (Fig. 3.3b at
// 1 Hz): Two-stage the lowest accumulated cost; solve times grow with the problem's size, and
// a strategy whose solves overrun the period pays for it in cost; the hybrid beats PAM-only on
// RMS error; the motor's share of the torque is small but not zero. The full experiment (every
// frequency, five trials) is hmpc-forearm-hil's.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "forearm_hil_support.hpp"

namespace {

namespace proto = hmpc::forearm_protocol;
using hmpc::hil::HilRunResult;
using hmpc::hil::HilRunSpec;
using hmpc::hil::test::expect_intact;
using proto::Strategy;

// The thesis's 10 s trials (Sec. 3.4): over 4 s the first second's transition from hold weighs
// too much (measured: Two-stage 1267.5 against Fine 8 ms 1267.3).
constexpr double kRunSeconds = 10;
constexpr double kControlPeriodS = 0.004;
constexpr double kSolveBudgetUs = 3500;  // the board's deadline for one MPC step (4 ms period)

class ForearmHilStrategies : public ::testing::Test {
 protected:
  // Two runs at a time, each with its own board node id on the shared bus (ctest gives the
  // launcher's guest two CPUs for this test); a lock-step run's figures do not depend on it.
  static void SetUpTestSuite() {
    const std::vector<Strategy> strategies{Strategy::kFine4ms,    Strategy::kFine8ms,
                                           Strategy::kCoarse20ms, Strategy::kCoarse40ms,
                                           Strategy::kTwoStage,   Strategy::kPamOnly};
    for (Strategy s : strategies) {
      specs_[s] = hmpc::hil::test::spec(s, name_of(s));
      specs_[s].run_for_s = kRunSeconds;
      results_[s] = HilRunResult{};
    }
    std::atomic<std::size_t> next{0};
    const auto worker = [&](hmpc::forearm_protocol::NodeId node) {
      for (std::size_t i = next++; i < strategies.size(); i = next++) {
        HilRunSpec spec = specs_.at(strategies[i]);
        spec.node = node;
        results_.at(strategies[i]) = hmpc::hil::run_hil(spec, hmpc::hil::HilPrograms::built());
      }
    };
    std::thread second(worker, 1);
    worker(0);
    second.join();
    for (Strategy s : strategies) {
      const HilRunResult& r = results_.at(s);
      std::printf(
          "%-12s cost %8.1f  RMS %.3f deg  max solve %.2f ms  median %.2f ms  misses %.0f"
          "  motor share %.1f %%  plant RTF %.2f\n",
          name_of(s).c_str(), r.accumulated_cost, r.rms_error * 180 / M_PI,
          r.solve_time_max_us / 1e3, r.solve_time_median_us / 1e3, r.deadline_misses,
          100 * r.motor_share(), r.number(r.plant, "real_time_factor"));
    }
  }
  static std::string name_of(Strategy s) {
    return proto::value_name(proto::kStrategyValues, std::uint32_t(s));
  }
  static const HilRunResult& result(Strategy s) { return results_.at(s); }
  static std::map<Strategy, HilRunSpec> specs_;
  static std::map<Strategy, HilRunResult> results_;
};
std::map<Strategy, HilRunSpec> ForearmHilStrategies::specs_;
std::map<Strategy, HilRunResult> ForearmHilStrategies::results_;

TEST_F(ForearmHilStrategies, EveryStrategyRunsEndToEndOverCan) {
  for (const auto& [strategy, r] : results_) {
    SCOPED_TRACE(name_of(strategy));
    ASSERT_NO_FATAL_FAILURE(expect_intact(r, specs_[strategy]));
    EXPECT_EQ(r.host.at("board_mode"), "hold");  // the script's end: run, then hold
    EXPECT_EQ(r.number(r.host, "board_faults"), 0);
    EXPECT_EQ(r.number(r.board, "fallbacks"), 0);
    EXPECT_EQ(r.number(r.board, "rejected_frames"), 0);
    // Every control period solved, but for the periods a charged solve still occupies.
    EXPECT_GT(r.number(r.host, "solves"), 0.3 * kRunSeconds / kControlPeriodS);
    EXPECT_LT(r.rms_error, 10 * M_PI / 180);  // it tracks
  }
}

// Fig. 3.3b at 1 Hz: the Two-stage MPC has the lowest accumulated cost of all.
TEST_F(ForearmHilStrategies, TwoStageHasTheLowestCost) {
  const double two_stage = result(Strategy::kTwoStage).accumulated_cost;
  for (const auto& [strategy, r] : results_) {
    if (strategy != Strategy::kTwoStage) {
      EXPECT_LT(two_stage, r.accumulated_cost) << name_of(strategy);
    }
  }
}

// Fig. 3.3a: solve time grows with the problem solved each period (horizon N = 50, 25, 10, 5
// on the same model), and the Two-stage, a Coarse 20 ms solve and a 20-step fast one, fits
// the period. Misses are counted exactly where a charged solve exceeds the board's budget.
TEST_F(ForearmHilStrategies, SolveTimesGrowWithTheProblemAndMissesFollowThem) {
  EXPECT_GT(result(Strategy::kFine4ms).solve_time_max_us,
            result(Strategy::kFine8ms).solve_time_max_us);
  EXPECT_GT(result(Strategy::kFine8ms).solve_time_max_us,
            result(Strategy::kCoarse20ms).solve_time_max_us);
  EXPECT_GT(result(Strategy::kCoarse20ms).solve_time_max_us,
            result(Strategy::kCoarse40ms).solve_time_max_us);
  EXPECT_GT(result(Strategy::kTwoStage).solve_time_max_us,
            result(Strategy::kCoarse20ms).solve_time_max_us);
  EXPECT_LT(result(Strategy::kTwoStage).solve_time_max_us, kSolveBudgetUs);
  for (const auto& [strategy, r] : results_) {
    SCOPED_TRACE(name_of(strategy));
    EXPECT_EQ(r.deadline_misses > 0, r.solve_time_max_us > kSolveBudgetUs);
  }
}

// Sec. 3.4.2: a solve that overruns delays the control. Where Fine 4 ms overruns on the
// Cortex-M7, it costs more than the strategies of the same or coarser resolution that fit the
// period; where it fits, nothing is asserted (the finest model may then be the best).
TEST_F(ForearmHilStrategies, AnOverrunningFineMpcCostsMoreThanTheOnesThatFit) {
  const HilRunResult& fine4 = result(Strategy::kFine4ms);
  if (fine4.deadline_misses == 0)
    GTEST_SKIP() << "Fine 4 ms fits the period on the target: no overrun to pay for";
  for (Strategy s : {Strategy::kFine8ms, Strategy::kCoarse20ms, Strategy::kTwoStage}) {
    EXPECT_GT(fine4.accumulated_cost, result(s).accumulated_cost) << name_of(s);
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

}  // namespace
