// The humanoid's two leg boards (firmware/app/humanoid_leg_board.hpp) holding the HIL plant
// (hil/humanoid/hydraulic_humanoid.hpp) under their PID, in one process with the host that
// zeroes them and asks for hold (humanoid_in_process.hpp).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "hmpc/humanoid/motion.hpp"
#include "humanoid_in_process.hpp"

namespace {

namespace hm = hmpc::humanoid;
namespace jp = hmpc::joint_protocol;
using hmpc::host::HostPhase;

// Sec. 2.7.3: "the robot first holds its posture" under the boards' PID, for the thesis's 10 s:
// zeroed in its standing posture, the torso stays within 0.05 rad (3 degrees) of upright and
// the hip within 2 cm of where it stood, the boards in hold without a fault.
TEST(HumanoidLegBoards, HoldTheRobotStandingForTenSeconds) {
  hmpc::host::HumanoidHostConfig config;
  config.hold_seconds = 20;  // the MPC never takes over
  hmpc::test::HumanoidInProcess robot(
      config, hm::load_motion(std::string(HMPC_HUMANOID_MOTIONS) + "/hip-hold.motion"));
  while (robot.host().phase() != HostPhase::kHolding && robot.ticks() < 2000) robot.tick();
  ASSERT_EQ(robot.host().phase(), HostPhase::kHolding) << robot.host().reason();
  for (int b = 0; b < hm::kLegBoards; ++b) ASSERT_TRUE(robot.board(b).zeroed());
  double tilt = 0, drift = 0;
  for (int k = 0; k < 10000; ++k) {
    robot.tick();
    const hm::BasicState<0> x = robot.plant().state();
    const Eigen::Quaterniond attitude(x.q[3], x.q[4], x.q[5], x.q[6]);
    tilt = std::max(tilt,
                    std::acos(std::min(1.0, (attitude.normalized() * hm::Vector3::UnitZ()).z())));
    drift = std::max(drift, (x.q.head<2>() - robot.start().q.head<2>()).norm());
  }
  std::printf("largest tilt %.4f rad, hip drift %.4f m over 10 s of hold\n", tilt, drift);
  EXPECT_LT(tilt, 0.05);
  EXPECT_LT(drift, 0.02);
  for (int b = 0; b < hm::kLegBoards; ++b) {
    EXPECT_EQ(robot.board(b).mode(), jp::BoardMode::kHold);
    EXPECT_EQ(robot.board(b).faults(), 0);
  }
}

}  // namespace
