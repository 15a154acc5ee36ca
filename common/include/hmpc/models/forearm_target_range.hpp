// What a forearm target may ask of the joint, for every program that checks one (the host
// controller, its DDS bridge and CLI, the HIL runner) before it reaches the board.
#pragma once

#include "hmpc/models/forearm.hpp"
#include "hmpc/trajectory/joint_target.hpp"

namespace hmpc::forearm {

// Fastest target motion accepted: above the 8.2 rad/s peak of a +-30 deg sinusoid at 2.5 Hz, the
// highest frequency we ask the forearm to try, where the thesis tracked up to 1.8 Hz
// (Sec. 3.4.2).
inline constexpr double kMaxTargetSpeed = 10.0;  // rad/s

// The board's software joint limits (past which it faults) and kMaxTargetSpeed.
inline trajectory::JointRange target_range() {
  const Parameters<double> arm{};
  return {arm.soft_limit_lower, arm.soft_limit_upper, kMaxTargetSpeed};
}

}  // namespace hmpc::forearm
