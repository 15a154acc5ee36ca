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
#pragma once

#include <Eigen/Core>
#include <array>

#include "hmpc/humanoid/parameters.hpp"

namespace hmpc::humanoid {

constexpr int kJoints = 2 * kJointsPerLeg;    // 8
constexpr int kBaseDofs = 6;
constexpr int kDofs = kBaseDofs + kJoints;    // 14 = dim v
constexpr int kConfigurationSize = 7 + kJoints;  // 15 = dim q
constexpr int kStateSize = kConfigurationSize + kDofs;  // 29 (thesis: n = 29)
constexpr int kBodies = 1 + 2 * kJointsPerLeg;  // torso + per leg (hip link, thigh, shank, foot)

using Vector3 = Eigen::Vector3d;
using Matrix3 = Eigen::Matrix3d;
using Configuration = Eigen::Matrix<double, kConfigurationSize, 1>;
using Velocity = Eigen::Matrix<double, kDofs, 1>;
using JointVector = Eigen::Matrix<double, kJoints, 1>;
using MassMatrix = Eigen::Matrix<double, kDofs, kDofs>;

// Body i > 0 is moved by joint i - 1 (velocity index kBaseDofs + i - 1); body 0 is the torso.
// Leg bodies are numbered leg * 4 + 1 + LegJoint (left leg 0, right leg 1).
struct Body {
  int parent = -1;                       // -1: the world (floating base)
  Vector3 axis = Vector3::Zero();        // revolute axis, parent and body coordinates
  Vector3 joint_origin = Vector3::Zero();  // in parent coordinates, at zero joint angle
  double mass = 0.0;                     // [kg]
  Vector3 com = Vector3::Zero();         // centre of mass, body coordinates [m]
  Matrix3 inertia = Matrix3::Zero();     // rotational inertia about the CoM [kg m^2]
};

struct Model {
  std::array<Body, kBodies> bodies;
  Vector3 gravity;                       // world coordinates
  Vector3 vertex;                        // top of the head, torso coordinates
  double sole_height;                    // sole plane below the ankle joint (foot frame z)
  JointVector joint_lower, joint_upper, torque_limit;
  JointVector armature;                  // reflected actuator inertia (Parameters::armature)

  explicit Model(const Parameters& p = Parameters{});

  double total_mass() const;
  static constexpr int body_of(int leg, int joint) { return leg * kJointsPerLeg + 1 + joint; }
};

}  // namespace hmpc::humanoid
