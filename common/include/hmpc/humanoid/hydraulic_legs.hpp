// The humanoid's hydraulic legs (thesis Sec. 2.7: CB-i's joints are hydraulic): which actuator
// drives each of the eight leg joints, and which joint board drives it. One source for the HIL
// plant (hil/humanoid), the joint boards' configuration and the host's CAN master.
//
// Sizing (our choice; the thesis gives no actuator data): one cylinder for every joint, on the
// lever its torque needs. The MPC's torque limits (parameters.hpp: 100 N m abduction and ankle,
// 150 N m hip flexion and knee) must be reachable pulling, on the smaller rod-side area, with a
// fifth to spare for regulation: 25 mm bore, 16 mm rod (A_b = 2.9 cm^2) on a 30 mm lever pulls
// 139 N m at 16 MPa, on a 40 mm lever 186 N m (pushing 236 and 314 N m). Each cylinder is
// mounted about the middle of its joint's range of motion (parameters.hpp) with a stroke that
// covers the range and kEndCapMargin beyond each end, where the end caps stop the joint. The valve
// is a size up from the one-joint bench's (hydraulic_joint.hpp): 10 l/min at 7 MPa drop moves a
// knee at 2.8 rad/s against no load with the valve fully open, the joint rates the real robot's
// tasks (standing, squatting) and walking ask for; its bandwidth stays 250 Hz. Seal friction
// scales with the bore from the bench's 16 mm cylinder.
#pragma once

#include <cstddef>

#include "hmpc/humanoid/parameters.hpp"
#include "hmpc/models/hydraulic_joint.hpp"

namespace hmpc::humanoid {

// Range of motion beyond which the end caps stop the joint [rad]: beyond the 0.075 rad the MPC's
// model lets a joint press into its end stop at its largest torque (parameters.hpp), so that the
// plant's caps never stop a motion the MPC plans, and beyond the boards' soft limits
// (humanoid_leg_board.hpp).
inline constexpr double kEndCapMargin = 0.1;

template <typename Scalar = double>
hydraulic::JointActuatorParameters<Scalar> leg_actuator(const Parameters& parameters,
                                                        LegJoint joint) {
  constexpr double kPi = 3.14159265358979323846;
  constexpr double bore = 0.025, rod = 0.016;  // m
  const double lever = (joint == kHipFlexion || joint == kKnee) ? 0.040 : 0.030;
  const double lower = parameters.joint_lower[std::size_t(joint)];
  const double upper = parameters.joint_upper[std::size_t(joint)];
  hydraulic::JointActuatorParameters<Scalar> p;
  p.area_a = Scalar(kPi / 4 * bore * bore);
  p.area_b = Scalar(kPi / 4 * (bore * bore - rod * rod));
  p.lever = Scalar(lever);
  p.mid_stroke_angle = Scalar((lower + upper) / 2);
  p.stroke = Scalar((upper - lower + 2 * kEndCapMargin) * lever);
  // 10 l/min at 3.5 MPa per land: K = 10e-3 / 60 / sqrt(3.5e6).
  p.valve_flow_gain = Scalar(8.909e-8);
  // The bench's 20 N and 200 N s/m on a 16 mm bore, scaled by the bore's circumference.
  p.coulomb_friction = Scalar(20 * bore / 0.016);
  p.viscous_friction = Scalar(200 * bore / 0.016);
  return p;
}

// The joint boards: one per leg, node 0 the left, 1 the right, each driving its leg's four
// joints in LegJoint order on its channels 0-3. Four joints per board is the layout with the
// lowest bus load at the thesis's 6 ms period (joint protocol: 38 % for two boards of four).
inline constexpr int kLegBoards = 2;
inline constexpr int kJointsPerBoard = kJointsPerLeg;
// The torso IMU sends its frames (joint protocol's ImuAngularVelocity, ImuLinearAcceleration)
// under the node id after the boards'.
inline constexpr int kImuNode = kLegBoards;
// The model's joint index (left leg first, as q lists them) of a board's channel, and back.
constexpr int joint_of(int board, int channel) { return board * kJointsPerLeg + channel; }
constexpr int board_of(int joint) { return joint / kJointsPerLeg; }
constexpr int channel_of(int joint) { return joint % kJointsPerLeg; }

}  // namespace hmpc::humanoid
