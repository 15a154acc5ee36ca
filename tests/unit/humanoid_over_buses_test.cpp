// The humanoid's whole chain in one process (humanoid_in_process.hpp), every frame encoded and
// decoded as on the buses: the host's bring-up, the boards' zeroing and hold, the estimate from
// the bus's frames, the MPC taking over through the boards' torque loops on the hydraulic plant,
// and the host's reactions to a failing solver and an E-stop.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "hmpc/humanoid/motion.hpp"
#include "hmpc/humanoid/physical_checks.hpp"
#include "humanoid_in_process.hpp"

namespace {

namespace hm = hmpc::humanoid;
namespace jp = hmpc::joint_protocol;
using hmpc::host::HostPhase;
using hmpc::test::HumanoidInProcess;

hm::Motion motion(const char* name) {
  return hm::load_motion(std::string(HMPC_HUMANOID_MOTIONS) + "/" + name + ".motion");
}

hmpc::host::HumanoidHostConfig config(double hold_seconds) {
  hmpc::host::HumanoidHostConfig c;
  c.hold_seconds = hold_seconds;
  c.solve_time = hmpc::host::SolveTime::kModel;  // the same run on any machine
  return c;
}

double tilt(const hm::BasicState<0>& x) {
  const Eigen::Quaterniond q(x.q[3], x.q[4], x.q[5], x.q[6]);
  return std::acos(std::min(1.0, (q.normalized() * hm::Vector3::UnitZ()).z()));
}

// Bring-up: both boards and the IMU heard, the encoders zeroed in the standing posture (each
// encoder mounted off by its own angle would fail this), the posture held; the estimate, from
// the bus's IMU and joint frames only, started from the hold's rest and within the estimator's
// targets (1 cm, 0.05 m/s, 1 degree) of the plant's truth.
TEST(HumanoidOverBuses, BringsTheRobotUpAndEstimatesItFromTheBus) {
  HumanoidInProcess robot(config(10), motion("hip-hold"));
  robot.run(1.5);
  ASSERT_EQ(robot.host().phase(), HostPhase::kHolding) << robot.host().reason();
  for (int b = 0; b < hm::kLegBoards; ++b) {
    EXPECT_TRUE(robot.board(b).zeroed());
    EXPECT_EQ(robot.board(b).mode(), jp::BoardMode::kHold);
    EXPECT_EQ(robot.board(b).faults(), 0);
  }
  const hm::BasicState<0> x = robot.plant().state();
  // The boards' zeroed angles as the host hears them: the truth to within 1 mrad, the
  // encoder's count (0.1 mrad), the frame's resolution (0.1 mrad) and what the loaded joints'
  // oil gave between the start and the zeroing (13 N m on an ankle's ~2e4 N m/rad: 0.7 mrad).
  const hmpc::host::RobotReadings& r = robot.host().master().readings();
  for (int j = 0; j < hm::kJoints; ++j) EXPECT_NEAR(r.angle[j], x.q[7 + j], 1e-3) << "joint " << j;
  ASSERT_TRUE(robot.host().estimating());
  const hm::BasicState<0> e = robot.host().estimator().state();
  EXPECT_NEAR(e.q[2], x.q[2], 0.01);
  const Eigen::Quaterniond qe(e.q[3], e.q[4], e.q[5], e.q[6]), qx(x.q[3], x.q[4], x.q[5], x.q[6]);
  EXPECT_LT(qe.angularDistance(qx), M_PI / 180);
  EXPECT_LT(tilt(x), 0.05);
}

// After the hold the MPC takes over: a solve every 12 ms (Sec. 2.7.3), each plan in effect
// after its charged compute time rounded up to ticks, the boards in run following the host's
// torques.
TEST(HumanoidOverBuses, TheMpcTakesOverFromTheBoardsHold) {
  HumanoidInProcess robot(config(1.0), motion("hip-hold"));
  robot.run(1.8);
  ASSERT_EQ(robot.host().phase(), HostPhase::kMpc) << robot.host().reason();
  const auto& solves = robot.host().solves();
  ASSERT_GE(solves.size(), 10u);
  for (std::size_t i = 1; i < solves.size(); ++i) {
    EXPECT_EQ(solves[i].tick - solves[i - 1].tick, 12u);
    EXPECT_TRUE(solves[i].usable);
    EXPECT_EQ(solves[i].effective_tick - solves[i].tick,
              std::max(1u, std::uint32_t(std::ceil(solves[i].charged_ms))));
  }
  for (int b = 0; b < hm::kLegBoards; ++b) {
    EXPECT_EQ(robot.board(b).mode(), jp::BoardMode::kRun);
    for (int c = 0; c < hm::kJointsPerBoard; ++c) {
      // The reference the board follows is the host's, within one rate-limited control step
      // (2 kN m/s over 6 ms) and the frame's 0.05 N m.
      EXPECT_NEAR(robot.board(b).applied_references()[std::size_t(c)],
                  robot.host().master().references()[hm::joint_of(b, c)], 12.05);
    }
  }
  EXPECT_LT(tilt(robot.plant().state()), 0.1);
}

// Sec. 2.7.3's first task, holding the hip, for the thesis's 10 s through the boards' torque
// loops on the hydraulic plant, the MPC solving from the plant's truth: the hip check of the
// simulated closed loop (physical_checks.hpp: within kHipHoldTolerance of where it started),
// the torso within 0.1 rad of upright, both feet loaded. On the estimate from the bus it does
// not yet (README, Humanoid over CAN).
TEST(HumanoidOverBuses, HoldsTheHipForTenSecondsOnTheTruth) {
  HumanoidInProcess robot(config(1.0), motion("hip-hold"));
  robot.solve_from_truth();
  robot.run(1.0);
  while (robot.host().phase() != HostPhase::kMpc && robot.ticks() < 3000) robot.tick();
  ASSERT_EQ(robot.host().phase(), HostPhase::kMpc);
  const hm::BasicState<0> taken_over = robot.plant().state();
  double drift = 0, worst_tilt = 0, least_load = 1e9;
  for (int k = 0; k < 10000; ++k) {
    robot.tick();
    const hm::BasicState<0> x = robot.plant().state();
    drift = std::max(drift, (x.q.head<2>() - taken_over.q.head<2>()).norm());
    worst_tilt = std::max(worst_tilt, tilt(x));
    if (k % 12 == 0) {
      const auto f = robot.plant().sole_forces();
      least_load = std::min({least_load, f[0].z() + f[1].z() + f[2].z() + f[3].z(),
                             f[4].z() + f[5].z() + f[6].z() + f[7].z()});
    }
  }
  std::printf(
      "10 s of hip hold on the truth: hip drift %.4f m, tilt up to %.3f rad, least foot "
      "load %.0f N\n",
      drift, worst_tilt, least_load);
  EXPECT_EQ(robot.host().phase(), HostPhase::kMpc) << robot.host().reason();
  EXPECT_LE(drift, hm::kHipHoldTolerance);
  EXPECT_LT(worst_tilt, 0.1);
  // Each foot carries at least a tenth of the weight (physical_checks.hpp's loaded foot).
  EXPECT_GT(least_load, 0.1 * robot.plant().model().total_mass() * 9.81);
}

// A solver that fails: the previous plan bridges two failures, the third in a row has the
// boards hold their posture (within three sampling periods of the first failure).
TEST(HumanoidOverBuses, ThreeFailedSolvesInARowHandTheRobotToTheBoardsHold) {
  hmpc::host::HumanoidHostConfig c = config(1.0);
  c.fail_solver_at_s = 1.6;
  HumanoidInProcess robot(c, motion("hip-hold"));
  robot.run(1.6);
  ASSERT_EQ(robot.host().phase(), HostPhase::kMpc);
  const std::uint32_t first_failure = robot.ticks();
  while (robot.host().phase() == HostPhase::kMpc && robot.ticks() < first_failure + 100)
    robot.tick();
  ASSERT_EQ(robot.host().phase(), HostPhase::kSafe);
  EXPECT_EQ(robot.host().reason(), "three failed solves in a row");
  EXPECT_LE(robot.ticks() - first_failure, 3u * 12u);
  int failed = 0;
  for (const auto& s : robot.host().solves()) failed += s.usable ? 0 : 1;
  EXPECT_EQ(failed, 3);
  robot.run(0.03);
  for (int b = 0; b < hm::kLegBoards; ++b) EXPECT_EQ(robot.board(b).mode(), jp::BoardMode::kHold);
  robot.run(0.5);
  EXPECT_LT(tilt(robot.plant().state()), 0.1);
}

// An E-stop from the host latches every board's safe state in the tick it arrives.
TEST(HumanoidOverBuses, AnEStopLatchesEveryBoard) {
  HumanoidInProcess robot(config(10), motion("hip-hold"));
  robot.run(1.0);
  robot.host().estop();
  robot.tick();
  for (int b = 0; b < hm::kLegBoards; ++b) {
    EXPECT_EQ(robot.board(b).mode(), jp::BoardMode::kFault);
    EXPECT_NE(robot.board(b).faults() & jp::fault::kEStop, 0);
  }
  EXPECT_EQ(robot.host().phase(), HostPhase::kSafe);
}

}  // namespace
