// Rigid-body dynamics of the humanoid (thesis Eq. 2.41) by Featherstone's algorithms
// ("Rigid Body Dynamics Algorithms", 2008): the composite-rigid-body algorithm for M(q)
// (Table 6.2), the recursive Newton-Euler algorithm for inverse dynamics and the bias forces
// (Table 5.1, floating base as a 6-DoF joint whose motion subspace is the identity, gravity as
// a fictitious base acceleration), and forward dynamics by a fixed-size Cholesky
// factorisation of M. The CRBA's products with the joint transforms skip the terms that are exact
// zeros for every angle and add the rest in the dense products' order, so M has the dense
// CRBA's bits at about two thirds of its cost (common/src/humanoid/joint_transform.hpp).
//
// Each joint's reflected actuator inertia (Model::armature) adds to M's diagonal, and its
// armature times the joint acceleration to the RNEA's torque: the rotor's own gyroscopic and
// base-coupling terms are neglected (the usual model, as MuJoCo's armature), the rigid bodies
// are exact.
//
// Sign convention: M(q) a + c(q, v) = tau, i.e. c is Featherstone's bias force C (Coriolis,
// centrifugal and gravity). The thesis writes Eq. 2.41a as M v_dot = c + u, so its c is -c here.
// tau's first six entries are a spatial force on the torso in torso coordinates (moment about
// the torso origin first); they are zero for the robot, whose base is unactuated.
//
// Everything is fixed-size Eigen and no call allocates. An instance holds its workspace, so
// use one instance per thread.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <array>

#include "hmpc/humanoid/model.hpp"

namespace hmpc::humanoid {

using Vector6 = Eigen::Matrix<double, 6, 1>;
using Matrix6 = Eigen::Matrix<double, 6, 6>;

// Poses and velocities of every body, for costs, contact and checks.
template <int ArmJoints>
struct BasicKinematics {
  static constexpr int kBodies = Dimensions<ArmJoints>::kBodies;
  std::array<Matrix3, kBodies> rotation;  // body to world
  std::array<Vector3, kBodies> position;  // body origin in world
  std::array<Vector6, kBodies> velocity;  // spatial velocity (omega, v_origin), body coords
};

// The RNEA's passes at one (q, v, a), kept so that a change confined to one subtree is redone
// on that subtree and its path to the root only (BasicDynamics::inverse_dynamics_in_subtree).
template <int ArmJoints>
struct BasicInverseDynamicsPasses {
  static constexpr int kBodies = Dimensions<ArmJoints>::kBodies;
  std::array<Vector6, kBodies> velocity, acceleration;  // body coordinates
  std::array<Vector6, kBodies> own_force;               // I a + v x* I v, before the children's
  std::array<Vector6, kBodies> force;                   // with the children's carried to it
  std::array<Vector6, kBodies> carried;  // X^T force, the body's force in its parent's coordinates
  BasicVelocity<ArmJoints> tau;
};

template <int ArmJoints>
class BasicDynamics {
 public:
  using Model = BasicModel<ArmJoints>;
  using Kinematics = BasicKinematics<ArmJoints>;
  using Configuration = BasicConfiguration<ArmJoints>;
  using Velocity = BasicVelocity<ArmJoints>;
  using MassMatrix = BasicMassMatrix<ArmJoints>;
  using InverseDynamicsPasses = BasicInverseDynamicsPasses<ArmJoints>;

  explicit BasicDynamics(const Model& model = Model{});

  const Model& model() const { return model_; }

  // CRBA: the joint-space inertia matrix M(q), symmetric positive definite.
  const MassMatrix& mass_matrix(const Configuration& q);
  // RNEA: tau = M(q) a + c(q, v).
  Velocity inverse_dynamics(const Configuration& q, const Velocity& v, const Velocity& a);

  // The same two at the configuration of the last set_configuration() (or of any call above
  // that takes q), without recomputing its joint transforms: the step map's linearisation
  // evaluates many (v, a) and one M at each q.
  void set_configuration(const Configuration& q);
  const MassMatrix& mass_matrix();
  Velocity inverse_dynamics(const Velocity& v, const Velocity& a);
  // kinematics(q, v, out) at that configuration, with the same numbers and no trigonometry.
  void kinematics(const Velocity& v, Kinematics& out) const;

  // Differencing in one coordinate at a time moves one subtree only: a joint's rate or angle
  // changes the bodies it carries, and the forces on their path to the root. These redo just
  // that and give the full calls' numbers to the last bit (the same expressions in the same
  // order; the bodies left out would compute what they computed before).
  // The RNEA at the current configuration, keeping its passes.
  Velocity inverse_dynamics(const Velocity& v, const Velocity& a, InverseDynamicsPasses& passes);
  // The RNEA at (v, a) where only body's joint angle (set_joint_angle) or the rates and
  // accelerations of the joints in body's subtree differ from those passes' (body 0, the
  // torso, carries everything: the full RNEA).
  Velocity inverse_dynamics_in_subtree(int body, const Velocity& v, const Velocity& a,
                                       const InverseDynamicsPasses& passes);
  // Turns one joint (body >= 1) to angle, as set_configuration() would; moves the base only
  // (q's position and quaternion), as it would.
  void set_joint_angle(int body, double angle);
  void set_base_pose(const Configuration& q);
  // out, the kinematics before the joint angle of body (>= 1) or its subtree's rates changed,
  // updated on that subtree.
  void kinematics_in_subtree(int body, const Velocity& v, Kinematics& out) const;
  // c(q, v) = RNEA with a = 0.
  Velocity bias_forces(const Configuration& q, const Velocity& v);
  // a = M^-1 (tau - c), by Cholesky (LLT) of M.
  Velocity forward_dynamics(const Configuration& q, const Velocity& v, const Velocity& tau);

  void kinematics(const Configuration& q, const Velocity& v, Kinematics& out) const;

 private:
  static constexpr int kBodies = Dimensions<ArmJoints>::kBodies;
  // The RNEA's steps for body i: velocity and acceleration from the parent's in from; the
  // body's own force; its torque, and its force carried into the parent's.
  void forward_pass(int i, const InverseDynamicsPasses& from, InverseDynamicsPasses& to,
                    const Velocity& v, const Velocity& a) const;
  void own_force(int i, InverseDynamicsPasses& passes) const;
  void backward_pass(int i, InverseDynamicsPasses& passes, const Velocity& a) const;

  Model model_;
  std::array<Matrix6, kBodies> inertia_;   // spatial inertia about the body origin
  std::array<Vector6, kBodies> subspace_;  // motion subspace S of revolute joints
  // Each joint transform's zero pattern (joint_transform.hpp), for the CRBA's products.
  std::array<int, kBodies> transform_pattern_{};
  // The joints in each body's subtree in the CRBA's order (its children's, as carried up, then
  // its own), how many, and where a body's list starts in its parent's; which bodies have
  // children, and which child is carried into its parent first.
  std::array<std::array<int, kBodies>, kBodies> subtree_dof_{};
  std::array<int, kBodies> subtree_size_{};
  std::array<int, kBodies> offset_in_parent_{};
  std::array<bool, kBodies> has_children_{}, first_into_parent_{};
  // in_subtree_[b][i]: body i is b or one of its descendants.
  std::array<std::array<bool, kBodies>, kBodies> in_subtree_{};
  // Workspace.
  Configuration configuration_;             // of set_configuration()
  std::array<Matrix6, kBodies> transform_;  // X from parent (or world) to body coordinates
  InverseDynamicsPasses passes_;
  std::array<Matrix6, kBodies> composite_;
  // The CRBA's forces I^c_k S_k of the joints k in a body's subtree, carried to that body.
  std::array<Eigen::Matrix<double, 6, kBodies, Eigen::RowMajor>, kBodies> subtree_force_;
  MassMatrix mass_matrix_;
  // Factorised once at construction, so that a copy never reads an uninitialised state.
  Eigen::LLT<MassMatrix> cholesky_{MassMatrix::Identity()};
};

// The hand's centre (Eq. 2.53's p_hand, ArmModel::hand) in world coordinates.
inline Vector3 hand_position(const BasicModel<1>& model, const BasicKinematics<1>& kinematics) {
  constexpr int arm = Dimensions<1>::kArmBody;
  return kinematics.position[arm] + kinematics.rotation[arm] * model.hand;
}

using Kinematics = BasicKinematics<0>;
using Dynamics = BasicDynamics<0>;
using ArmDynamics = BasicDynamics<1>;

}  // namespace hmpc::humanoid
