// A joint board driving one of the humanoid's legs (hmpc/humanoid/hydraulic_legs.hpp): its four
// joints on channels 0-3 in LegJoint order, each with the leg's actuator, the MPC's torque limit
// for that joint, and soft limits just inside the cylinder's end caps; and the posture at which
// the host zeroes the encoders.
#pragma once

#include <array>
#include <cstddef>

#include "hmpc/humanoid/hydraulic_legs.hpp"
#include "joint_board.hpp"

namespace hmpc::firmware {

// How far past its range of motion (parameters.hpp) a joint may go before the board faults:
// the MPC's model lets a joint press into its end stop (0.075 rad at its largest torque,
// parameters.hpp) and the end caps stop it kEndCapMargin (0.1 rad) beyond the range, so the
// limit sits between. At 0.04 a board faulted on an ankle pressing into its stop as the squat
// began (the hip squat through the boards on the plant's truth, in one process).
inline constexpr double kLegSoftLimitMargin = 0.09;

// The posture hold's stiffness [N m/rad]. The robot stands on compliant soles (contact.hpp: 1 cm
// under its weight) whose resistance to the whole body tipping about them is about 500 N m/rad,
// barely above the 415 N m/rad with which gravity tips a 47 kg body whose centre of mass is 0.9 m
// up; joints in series with the soles must be much stiffer still, or the held robot topples.
// Measured in one process (humanoid_leg_boards_test, 10 s of hold): the one-joint bench's 300
// everywhere toppled within 2 s, with 1000 at the ankles too; 1000 at hips and knees and 2000
// or 4000 at the ankles held the torso within 0.02 and 0.004 rad of upright. The damping stays
// the bench's 20 N m s/rad (60 changed nothing).
inline constexpr double kLegHoldStiffness = 1000.0;
inline constexpr double kAnkleHoldStiffness = 4000.0;

// `zero_posture`: each joint's angle [rad] when the host sends zero_encoders.
template <typename Scalar>
void configure_humanoid_leg(JointBoardConfig<Scalar>& config,
                            const std::array<double, humanoid::kJointsPerLeg>& zero_posture,
                            const humanoid::Parameters& parameters = {}) {
  config.joints = humanoid::kJointsPerBoard;
  for (std::size_t j = 0; j < std::size_t(humanoid::kJointsPerLeg); ++j) {
    JointConfig<Scalar>& joint = config.joint[j];
    joint.actuator = humanoid::leg_actuator<Scalar>(parameters, humanoid::LegJoint(j));
    joint.theta_min = Scalar(parameters.joint_lower[j] - kLegSoftLimitMargin);
    joint.theta_max = Scalar(parameters.joint_upper[j] + kLegSoftLimitMargin);
    joint.torque_limit = Scalar(parameters.torque_limit[j]);
    joint.zero_posture = Scalar(zero_posture[j]);
  }
  config.tune_defaults();
  for (std::size_t j = 0; j < std::size_t(humanoid::kJointsPerLeg); ++j) {
    config.joint[j].hold_loop.kp =
        Scalar(j == std::size_t(humanoid::kAnkle) ? kAnkleHoldStiffness : kLegHoldStiffness);
  }
}

}  // namespace hmpc::firmware
