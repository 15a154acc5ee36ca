// What the IOC tests share: the shipped jump and demonstrations of it by the robot's own MPC.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "hmpc/ioc/local_ioc.hpp"

namespace hmpc::ioc::test {

inline humanoid::Motion jump_motion() {
  return humanoid::load_motion(std::string(HMPC_HUMANOID_MOTIONS) + "/V-low-jump.motion");
}

// A demonstration by the robot's own Coarse MPC (untruncated: the same on any machine).
inline Demonstration own_demonstration(const humanoid::Motion& motion, double duration,
                                       const Eigen::Vector3d& nudge) {
  humanoid::ClosedLoopConfig config;
  config.mpc = humanoid::MpcKind::kCoarse;
  config.truncate = false;
  config.duration = duration;
  config.initial_velocity = nudge;
  const humanoid::ClosedLoopRun run = humanoid::run_closed_loop(motion, config);
  EXPECT_FALSE(run.fell());
  return demonstration_of(run);
}

}  // namespace hmpc::ioc::test
