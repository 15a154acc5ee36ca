// Analytic derivatives of the humanoid's inverse dynamics tau = RNEA(q, v, a) (dynamics.hpp)
// with respect to the configuration and the velocity, after Carpentier and Mansard ("Analytical
// Derivatives of Rigid Body Dynamics Algorithms", RSS 2018): the recursions written in the
// world frame, where a joint's motion subspace S_j is the only thing its angle moves, so that
//   dS_k/dq_j = S_j x S_k                      (j an ancestor of k, or j = k),
//   dI_i/dq_j = S_j x* I_i - I_i S_j x         (body i in j's subtree; I_i its world inertia),
// and RNEA's forward pass (v_i = v_parent + S_i qd_i, a_i = a_parent + S_i qdd_i + Sdot_i qd_i,
// Sdot_i = v_i x S_i, f_i = I_i a_i + v_i x* I_i v_i) and backward pass (F_i = f_i + sum of the
// children's F, tau_i = S_i^T F_i) are differentiated term by term, one column (a joint, or a
// base direction) at a time over that column's subtree: only its descendants move.
//
// The configuration derivative is taken in the tangent space: a joint's column is d/dq_j; a
// base column c is the right perturbation of the torso's pose by the unit twist e_c in torso
// coordinates (rotation R exp(eps e_c^), or origin p + eps R e_c), the base's 6 motion subspace
// columns S_0 = X_0 (torso to world) moving as dS_0c'/dq_c = S_0c x S_0c' for every pair. The
// chain to the quaternion coordinates is the caller's (tangent_of_quaternion below).
//
// Sign and frame conventions are RNEA's: tau's base part is the spatial force on the torso in
// torso coordinates. d tau / d a is M(q) (the CRBA). Everything is fixed-size; no call
// allocates. One instance per thread (it owns its workspace).
#pragma once

#include <array>

#include "hmpc/humanoid/dynamics.hpp"
#include "hmpc/humanoid/spatial.hpp"

namespace hmpc::humanoid {

template <int ArmJoints>
struct BasicInverseDynamicsDerivatives {
  BasicVelocity<ArmJoints> tau;           // RNEA(q, v, a), for checking against dynamics.hpp
  BasicMassMatrix<ArmJoints> dtau_dq;     // columns: the tangent directions above
  BasicMassMatrix<ArmJoints> dtau_dv;
};

// Forward dynamics a = M^-1 (tau - c) and its derivatives: from M a + c = tau,
// da/dx = -M^-1 d tau/dx at the solved a (x = q or v), and da/dtau = M^-1.
template <int ArmJoints>
struct BasicForwardDynamicsDerivatives {
  BasicVelocity<ArmJoints> a;
  BasicMassMatrix<ArmJoints> da_dq;  // tangent columns, as dtau_dq
  BasicMassMatrix<ArmJoints> da_dv;
  BasicMassMatrix<ArmJoints> da_dtau;  // M^-1
};

template <int ArmJoints>
class BasicDynamicsDerivatives {
 public:
  using Model = BasicModel<ArmJoints>;
  using Configuration = BasicConfiguration<ArmJoints>;
  using Velocity = BasicVelocity<ArmJoints>;
  using Derivatives = BasicInverseDynamicsDerivatives<ArmJoints>;
  static constexpr int kBodies = Dimensions<ArmJoints>::kBodies;
  static constexpr int kDofs = Dimensions<ArmJoints>::kDofs;

  explicit BasicDynamicsDerivatives(const Model& model = Model{});

  void inverse_dynamics_derivatives(const Configuration& q, const Velocity& v, const Velocity& a,
                                    Derivatives& out);
  void forward_dynamics_derivatives(const Configuration& q, const Velocity& v,
                                    const Velocity& tau,
                                    BasicForwardDynamicsDerivatives<ArmJoints>& out);

 private:
  // The world-frame RNEA at (q, v, a), kept for the derivative passes.
  void forward_pass(const Configuration& q, const Velocity& v, const Velocity& a);
  // One column's derivative of every body's force, over the column's subtree, then of tau.
  void configuration_column(int column, const Velocity& v, const Velocity& a, Velocity& dtau);
  void velocity_column(int column, const Velocity& v, Velocity& dtau);
  void backward_column(int column, Velocity& dtau);

  static constexpr int body_of(int column) {
    return column < kBaseDofs ? 0 : column - kBaseDofs + 1;
  }
  // Column range of body i: the base's six, or one joint's.
  static constexpr int first_column(int body) { return body == 0 ? 0 : kBaseDofs + body - 1; }
  static constexpr int column_count(int body) { return body == 0 ? kBaseDofs : 1; }

  Model model_;
  BasicDynamics<ArmJoints> dynamics_;  // M and its factorisation for the forward dynamics
  Eigen::LLT<BasicMassMatrix<ArmJoints>> cholesky_{BasicMassMatrix<ArmJoints>::Identity()};
  Derivatives inverse_;
  std::array<spatial::Matrix6, kBodies> body_inertia_;  // about the body origin, body coords
  std::array<bool, kBodies * kBodies> in_subtree_;       // [root * kBodies + i]: i below root
  // Workspace, world frame at the world origin.
  std::array<spatial::Matrix6, kBodies> inertia_;  // I_i
  std::array<spatial::Vector6, kBodies> velocity_, acceleration_, momentum_, force_, total_;
  std::array<spatial::Vector6, kDofs> subspace_, subspace_rate_;  // S_c, Sdot_c
  // One column's derivatives.
  std::array<spatial::Vector6, kBodies> d_velocity_, d_acceleration_, d_force_;
};

// The body-frame rotation increment of a change dquat of the quaternion coordinates (w x y z)
// of a unit quaternion: delta_theta = 2 Im(conj(quat) (x) dquat), a 3x4 matrix. The change's
// component along quat (which normalisation removes) maps to zero.
Eigen::Matrix<double, 3, 4> tangent_of_quaternion(const Eigen::Vector4d& quat);

using DynamicsDerivatives = BasicDynamicsDerivatives<0>;
using InverseDynamicsDerivatives = BasicInverseDynamicsDerivatives<0>;

}  // namespace hmpc::humanoid
