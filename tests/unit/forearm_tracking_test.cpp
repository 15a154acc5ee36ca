// The strategies of Table 3.1 tracking the thesis's +-30 deg sinusoids for 10 s on the model
// (RK4 plant at 1 ms), each update's output delayed by its compute time on the board, a
// Cortex-M7 at 400 MHz (compute model fitted to QEMU instruction counts, 1 cycle per
// instruction). What the thesis's Figs. 3.3b, 3.6 and 3.8 show that this idealised setting
// reproduces is asserted here. Not asserted: the two-stage's lowest cost at 0.5 Hz, and Fine
// 4 ms as the costliest strategy, which the thesis owes to its fine solves overrunning 4 ms.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <memory>

#include "hmpc/models/forearm_mpc.hpp"
#include "hmpc/models/forearm_solvers.hpp"

namespace {

using namespace hmpc::forearm;
using S = Strategies<double>;
constexpr int kSamples = 2500;  // 10 s at 4 ms (Sec. 3.3)

template <class Mpc>
TrackingOutcome<double> track(Mpc& mpc, const TargetTrajectory<double>& target) {
  const Parameters<double> p;
  NoTrackingObserver observer;
  const Eigen::Vector3d x0(0, 0, equilibrium_pressure(p, 0.0));
  return simulate_tracking<double>(mpc, p, CostWeights<double>{}, target, x0, kSamples,
                                   CortexM7ComputeDelay{}, observer);
}

std::map<Strategy, TrackingOutcome<double>> run_all(double frequency) {
  TargetTrajectory<double> target;
  target.set_sinusoid(30 * M_PI / 180, frequency, 0, 0);
  S::Setup setup;
  setup.target = &target;
  std::map<Strategy, TrackingOutcome<double>> r;
  r[Strategy::kFine4] = track(*std::make_unique<S::Fine4>(S::fine4(setup)), target);
  r[Strategy::kFine8] = track(*std::make_unique<S::Fine8>(S::fine8(setup)), target);
  r[Strategy::kCoarse20] = track(*std::make_unique<S::Coarse20>(S::coarse20(setup)), target);
  r[Strategy::kCoarse40] = track(*std::make_unique<S::Coarse40>(S::coarse40(setup)), target);
  r[Strategy::kTwoStage] = track(*std::make_unique<S::TwoStage>(S::two_stage(setup)), target);
  r[Strategy::kPamOnly] = track(*std::make_unique<S::PamOnly>(S::pam_only(setup)), target);
  for (const auto& [s, o] : r)
    std::printf("%.2f Hz %-12s cost %8.1f  rms %.4f rad  motor share %.3f  overruns %d\n",
                frequency, to_string(s), o.accumulated_cost, o.rms_error, o.motor_share(),
                o.overruns);
  return r;
}

const std::map<Strategy, TrackingOutcome<double>>& at(double frequency) {
  static std::map<double, std::map<Strategy, TrackingOutcome<double>>> cache;
  auto it = cache.find(frequency);
  if (it == cache.end()) it = cache.emplace(frequency, run_all(frequency)).first;
  return it->second;
}

class ForearmTracking : public ::testing::TestWithParam<double> {};

TEST_P(ForearmTracking, EveryStrategyTracksWithinAFewDegrees) {
  for (const auto& [s, o] : at(GetParam())) {
    EXPECT_TRUE(o.final_state.allFinite()) << to_string(s);
    // A 60 deg peak-to-peak target: all strategies stay within 4 deg RMS on the model.
    EXPECT_LT(o.rms_error, 4 * M_PI / 180) << to_string(s);
  }
}

TEST_P(ForearmTracking, TwoStageTracksBestOfAllStrategies) {
  // Figs. 3.5-3.6: the two-stage MPC follows the target more closely than every standard MPC.
  const auto& r = at(GetParam());
  const double two_stage = r.at(Strategy::kTwoStage).rms_error;
  for (const auto& [s, o] : r)
    if (s != Strategy::kTwoStage) {
      EXPECT_LT(two_stage, 0.85 * o.rms_error) << to_string(s);
    }
}

TEST_P(ForearmTracking, HybridBeatsPamOnly) {
  // Fig. 3.8b: the small motor greatly improves tracking, and lowers the cost of Eq. 3.3.
  const auto& r = at(GetParam());
  EXPECT_LT(r.at(Strategy::kTwoStage).rms_error, 0.75 * r.at(Strategy::kPamOnly).rms_error);
  EXPECT_LT(r.at(Strategy::kTwoStage).accumulated_cost, r.at(Strategy::kPamOnly).accumulated_cost);
  EXPECT_LT(r.at(Strategy::kCoarse20).accumulated_cost, r.at(Strategy::kPamOnly).accumulated_cost);
}

TEST_P(ForearmTracking, MotorTorqueShareIsSmallButNonzero) {
  // Fig. 3.8a: the motor's contribution is much smaller than the PAM's.
  const TrackingOutcome<double>& o = at(GetParam()).at(Strategy::kTwoStage);
  EXPECT_GT(o.motor_share(), 0.01);
  EXPECT_LT(o.motor_share(), 0.2);
  EXPECT_EQ(at(GetParam()).at(Strategy::kPamOnly).mean_abs_motor_torque, 0.0);
}

INSTANTIATE_TEST_SUITE_P(ThesisFrequencies, ForearmTracking, ::testing::Values(0.5, 1.0));

// With the terminal rate term in both stages (our addition: Eq. 3.3b prices the angle where a
// horizon ends, not the rate) the Two-stage follows the target more closely than every other
// strategy as the thesis has it, from 0.25 Hz to 1.8 Hz, where the thesis's Two-stage falls
// behind Coarse 20 ms and 40 ms.
class ForearmTerminalRate : public ::testing::TestWithParam<double> {};

TEST_P(ForearmTerminalRate, KeepsTheTwoStageAheadOfEveryStrategy) {
  TargetTrajectory<double> target;
  target.set_sinusoid(30 * M_PI / 180, GetParam(), 0, 0);
  S::Setup setup;
  setup.target = &target;
  setup.two_stage_terminal_rate = kTwoStageTerminalRate;
  const TrackingOutcome<double> o =
      track(*std::make_unique<S::TwoStage>(S::two_stage(setup)), target);
  std::printf("%.2f Hz two-stage with the terminal rate term: cost %8.1f  rms %.4f rad\n",
              GetParam(), o.accumulated_cost, o.rms_error);
  for (const auto& [s, other] : at(GetParam()))
    if (s != Strategy::kTwoStage) {
      EXPECT_LT(o.rms_error, other.rms_error) << to_string(s);
    }
}

INSTANTIATE_TEST_SUITE_P(UpTo1_8Hz, ForearmTerminalRate, ::testing::Values(0.25, 0.5, 1.0, 1.8));

TEST(ForearmTracking1Hz, TwoStageHasTheLowestAccumulatedCost) {
  // Fig. 3.3b at 1.0 Hz: the two-stage MPC has the lowest cost of Eq. 3.3, Fine 4 ms more.
  const auto& r = at(1.0);
  for (const auto& [s, o] : r)
    if (s != Strategy::kTwoStage) {
      EXPECT_LT(r.at(Strategy::kTwoStage).accumulated_cost, o.accumulated_cost) << to_string(s);
    }
}

}  // namespace
