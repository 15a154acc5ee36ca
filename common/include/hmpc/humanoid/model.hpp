// The seven-link humanoid as a kinematic tree (thesis Sec. 2.5.1; Featherstone, "Rigid Body
// Dynamics Algorithms", 2008, Ch. 4), built once from Parameters.
//
// Frames: world z up, x forward, y to the left. The torso (floating base) frame has its origin
// at the mid-hip point (between the hip joint centres) and, like every body frame, is parallel
// to the world frame when the robot stands upright with all joints at zero. Each leg has four
// revolute joints; the two hip rotations meet at the hip joint centre, so a massless hip link
// sits between them (it carries no inertia, so Simbody's Universal mobilizer is the same joint).
//
// Generalized coordinates (n = 15 + 14 = 29, thesis Sec. 2.6.2):
//   q = [ p (3): torso origin in world,
//         quaternion (4): w, x, y, z, torso-to-world rotation,
//         joints (8): left hip abduction, hip flexion, knee, ankle; then the right leg ]
//   v = [ omega (3), v_o (3): the torso's spatial velocity in torso coordinates (Featherstone
//         Sec. 2.2, angular first: angular velocity and velocity of the torso origin),
//         joint rates (8) ]
// so p_dot = R v_o and quaternion_dot = 0.5 quaternion * (0, omega).
// Joint axes (right-handed, positive as in Parameters): hip abduction about +x (left leg) or
// -x (right leg); hip flexion and ankle dorsiflexion about -y; knee flexion about +y.
//
// The reaching variant (thesis Sec. 2.6.2: "a humanoid robot with a right arm. Its state
// dimensionality n is 31") adds one body, the right arm, on a shoulder flexion joint at the
// torso's right shoulder, about -y like hip flexion (positive raises the arm forward). Its angle
// and rate come last in q and v (joint 8), its body last (body 9). Everything else is the same:
// the types below are templates on the number of arm joints, 0 (Model, n = 29) or 1 (ArmModel,
// n = 31), explicitly instantiated for both in the .cpp files.
#pragma once

#include <Eigen/Core>
#include <array>

#include "hmpc/humanoid/parameters.hpp"

namespace hmpc::humanoid {

constexpr int kBaseDofs = 6;
constexpr int kLegJoints = 2 * kJointsPerLeg;  // 8

// The leg joints' names in q's order, as the robot's topics carry them: the side, then the
// joint as the thesis's weights name it (hip abduction HAA, hip flexion HFE, knee KFE, ankle
// AFE).
inline constexpr std::array<const char*, kLegJoints> kLegJointNames = {
    "left_HAA",  "left_HFE",  "left_KFE",  "left_AFE",
    "right_HAA", "right_HFE", "right_KFE", "right_AFE"};

// The sizes of a variant with `ArmJoints` arm joints (0: the biped, 1: the reaching robot).
template <int ArmJoints>
struct Dimensions {
  static_assert(ArmJoints == 0 || ArmJoints == 1, "the humanoid has no arm or a one-joint arm");
  static constexpr int kArmJoints = ArmJoints;
  static constexpr int kJoints = kLegJoints + ArmJoints;         // 8 or 9
  static constexpr int kDofs = kBaseDofs + kJoints;              // dim v: 14 or 15
  static constexpr int kConfigurationSize = 7 + kJoints;         // dim q: 15 or 16
  static constexpr int kStateSize = kConfigurationSize + kDofs;  // n: 29 or 31
  // torso + per leg (hip link, thigh, shank, foot) + the arm
  static constexpr int kBodies = 1 + 2 * kJointsPerLeg + ArmJoints;
  static constexpr int kArmBody = 1 + 2 * kJointsPerLeg;  // the arm's, if it has one
  static constexpr int kArmJoint = kLegJoints;            // its joint index
};

using Vector3 = Eigen::Vector3d;
using Matrix3 = Eigen::Matrix3d;
template <int A>
using BasicConfiguration = Eigen::Matrix<double, Dimensions<A>::kConfigurationSize, 1>;
template <int A>
using BasicVelocity = Eigen::Matrix<double, Dimensions<A>::kDofs, 1>;
template <int A>
using BasicJointVector = Eigen::Matrix<double, Dimensions<A>::kJoints, 1>;
template <int A>
using BasicMassMatrix = Eigen::Matrix<double, Dimensions<A>::kDofs, Dimensions<A>::kDofs>;

// The robot's state x = (q, v) (thesis Sec. 2.6.2: n = 29, or 31 with the arm).
template <int ArmJoints>
struct BasicState {
  BasicConfiguration<ArmJoints> q;
  BasicVelocity<ArmJoints> v;
};

// Body i > 0 is moved by joint i - 1 (velocity index kBaseDofs + i - 1); body 0 is the torso.
// Leg bodies are numbered leg * 4 + 1 + LegJoint (left leg 0, right leg 1), then the arm.
struct Body {
  int parent = -1;                         // -1: the world (floating base)
  Vector3 axis = Vector3::Zero();          // revolute axis, parent and body coordinates
  Vector3 joint_origin = Vector3::Zero();  // in parent coordinates, at zero joint angle
  double mass = 0.0;                       // [kg]
  Vector3 com = Vector3::Zero();           // centre of mass, body coordinates [m]
  Matrix3 inertia = Matrix3::Zero();       // rotational inertia about the CoM [kg m^2]
};

template <int ArmJoints>
struct BasicModel {
  using JointVector = BasicJointVector<ArmJoints>;
  std::array<Body, Dimensions<ArmJoints>::kBodies> bodies;
  Vector3 gravity;                 // world coordinates
  Vector3 vertex;                  // top of the head, torso coordinates
  Vector3 hand = Vector3::Zero();  // the hand's centre (Eq. 2.53's p_hand), arm coordinates
  Vector3 imu;                     // the torso IMU's position, torso coordinates
  double sole_height;              // sole plane below the ankle joint (foot frame z)
  JointVector joint_lower, joint_upper, torque_limit;
  JointVector armature;  // reflected actuator inertia (Parameters::armature)

  explicit BasicModel(const Parameters& p = Parameters{});

  double total_mass() const;
  static constexpr int body_of(int leg, int joint) { return leg * kJointsPerLeg + 1 + joint; }
};

// The biped of motions I-VIII (n = 29) and the reaching robot (n = 31).
using Model = BasicModel<0>;
using ArmModel = BasicModel<1>;
// The biped's sizes and types, for code that only ever runs it.
using Biped = Dimensions<0>;
constexpr int kJoints = Biped::kJoints;
constexpr int kDofs = Biped::kDofs;
constexpr int kConfigurationSize = Biped::kConfigurationSize;
constexpr int kStateSize = Biped::kStateSize;  // 29 (thesis: n = 29)
constexpr int kBodies = Biped::kBodies;
using Configuration = BasicConfiguration<0>;
using Velocity = BasicVelocity<0>;
using JointVector = BasicJointVector<0>;
using MassMatrix = BasicMassMatrix<0>;

}  // namespace hmpc::humanoid
