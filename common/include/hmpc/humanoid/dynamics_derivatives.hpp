// Analytic derivatives of the humanoid's inverse dynamics tau = RNEA(q, v, a) (dynamics.hpp)
// with respect to the configuration and the velocity, after Carpentier and Mansard ("Analytical
// Derivatives of Rigid Body Dynamics Algorithms", RSS 2018), derived here in our conventions.
// Everything is in the world frame at the world origin, where a joint's motion subspace S_j is
// the only thing its angle moves:
//   dS_k/dq_j = S_j x S_k  (k in j's subtree),   dI_i/dq_j = S_j x* I_i - I_i S_j x.
// RNEA there: v_i = v_parent + S_i qd_i, a_i = a_parent + S_i qdd_i + (v_i x S_i) qd_i (a_world =
// gravity's fictitious upward acceleration), f_i = I_i a_i + v_i x* I_i v_i, F_i = f_i + the
// children's F, tau_c = S_c^T F_body(c). Moving q_j turns j's subtree rigidly about S_j, under
// which f is covariant (df = S_j x* f) except where the subtree meets its parent p: with
//   w_j = S_j x v_p,  u_j = S_j x a_p - w_j x v_p,  z_j = S_j x (v_p + v_body(j)),
// and B_i = (v_i x*) I_i - I_i (v_i x) + (h_i x-bar*) (h_i = I_i v_i; (h x-bar*) w = w x* h),
// summing over the subtree (Ic, Bc: composite inertia and B; F the composite force):
// - column c at or below j (Ic, Bc of c's body; the S_j x* F term cancels against dS_c^T F):
//     d tau_c/dq_j = -S_c^T (Ic u_j + Bc w_j),     d tau_c/dv_j = S_c^T (Bc S_j - Ic z_j);
// - column c above j (Ic, Bc and F of j's body):
//     d tau_c/dq_j = S_c^T (S_j x* F - Ic u_j - Bc w_j),  d tau_c/dv_j = S_c^T (Bc S_j - Ic z_j);
// - 0 elsewhere. One forward pass, one backward pass of 6x6 sums, then 6-vector dot products.
//
// The configuration derivative is taken in the tangent space: a joint's column is d/dq_j; a
// base column c is the right perturbation of the torso's pose by the unit twist e_c in torso
// coordinates (rotation R exp(eps e_c^), or origin p + eps R e_c), the base's 6 motion subspace
// columns being S_0 = X_0 (torso to world), with the world (v_p = 0, a_p = gravity's) as their
// parent. The chain to the quaternion coordinates is the caller's (tangent_of_quaternion).
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
  BasicVelocity<ArmJoints> tau;        // RNEA(q, v, a), for checking against dynamics.hpp
  BasicMassMatrix<ArmJoints> dtau_dq;  // columns: the tangent directions above
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

// A world force phi(p, p_dot, p_acc) on a point, with p its world position, p_dot = J v its
// velocity and p_acc = J a the point's part of J a (the step map's implicit contact term
// h D J a), and phi's slopes in each.
struct PointForceSlopes {
  Vector3 force = Vector3::Zero();
  Matrix3 by_position = Matrix3::Zero(), by_velocity = Matrix3::Zero(),
          by_acceleration = Matrix3::Zero();
};

template <int ArmJoints>
class BasicDynamicsDerivatives {
 public:
  using Model = BasicModel<ArmJoints>;
  using Configuration = BasicConfiguration<ArmJoints>;
  using Velocity = BasicVelocity<ArmJoints>;
  using Derivatives = BasicInverseDynamicsDerivatives<ArmJoints>;
  using MassMatrix = BasicMassMatrix<ArmJoints>;
  static constexpr int kBodies = Dimensions<ArmJoints>::kBodies;
  static constexpr int kDofs = Dimensions<ArmJoints>::kDofs;

  explicit BasicDynamicsDerivatives(const Model& model = Model{});

  void inverse_dynamics_derivatives(const Configuration& q, const Velocity& v, const Velocity& a,
                                    Derivatives& out);
  // The same from the bodies' poses at q (dynamics.hpp's kinematics), for a caller that has
  // them already.
  void inverse_dynamics_derivatives(const BasicKinematics<ArmJoints>& kinematics, const Velocity& v,
                                    const Velocity& a, Derivatives& out);
  void forward_dynamics_derivatives(const Configuration& q, const Velocity& v, const Velocity& tau,
                                    BasicForwardDynamicsDerivatives<ArmJoints>& out);

  // At the (q, v, a) of the last inverse_dynamics_derivatives call: the derivatives of the
  // generalized force J^T phi of a force on a point fixed on `body`, at world position p, added
  // to dq (tangent columns, as dtau_dq) and dv. Moving q_j moves the point by dp_j = J_j (the
  // point's part of S_j), its velocity J v by w_b x dp_j + P (S_j x (v_b - v_p)) and J a
  // likewise with alpha = sum S_c a_c for v (P(p) (w, u) = u + w x p, the point's linear
  // velocity of a twist; p's parent the world for the base); and J_c turns with S_j for c at
  // or below j, giving J_c . (phi x w_j), and moves with p for c above it, giving
  // w_c . (dp_j x phi). So, with chi_j = phi_p dp_j + phi_v d(J v)_j + phi_a d(J a)_j:
  //   d(J^T phi)_c/dq_j = J_c . (chi_j + phi x w_j) (c at or below j),
  //                       J_c . chi_j + w_c . (dp_j x phi) (c above j);
  //   d(J^T phi)/dv = J^T phi_v J.
  void add_point_force_derivatives(int body, const Vector3& p, const PointForceSlopes& slopes,
                                   MassMatrix& dq, MassMatrix& dv) const;

 private:
  // The world-frame RNEA in two parts, kept for the derivatives: what q and v give (poses,
  // subspaces, velocities, the bias accelerations and forces at a = 0, B, the composite
  // inertias), then what the accelerations add (a_i, the composite forces F).
  void velocity_pass(const BasicKinematics<ArmJoints>& kinematics, const Velocity& v);
  void acceleration_pass(const Velocity& a);
  void derivative_columns(const Velocity& a, Derivatives& out);

  // Gravity as a fictitious upward acceleration of the world, as in the RNEA.
  spatial::Vector6 gravity_acceleration() const {
    spatial::Vector6 a;
    a << spatial::Vector3::Zero(), -model_.gravity;
    return a;
  }
  static constexpr int body_of(int column) {
    return column < kBaseDofs ? 0 : column - kBaseDofs + 1;
  }
  // Column range of body i: the base's six, or one joint's.
  static constexpr int first_column(int body) { return body == 0 ? 0 : kBaseDofs + body - 1; }
  static constexpr int column_count(int body) { return body == 0 ? kBaseDofs : 1; }

  Model model_;
  BasicDynamics<ArmJoints> dynamics_;       // its kinematics: the bodies' world poses
  BasicKinematics<ArmJoints> kinematics_;   // for the calls given q
  BasicMassMatrix<ArmJoints> mass_matrix_;  // M and its factorisation, for forward dynamics
  Eigen::LLT<BasicMassMatrix<ArmJoints>> cholesky_{BasicMassMatrix<ArmJoints>::Identity()};
  Derivatives inverse_;
  std::array<bool, kBodies * kBodies> in_subtree_;  // [root * kBodies + i]: i below root
  // Workspace, world frame at the world origin.
  std::array<spatial::Matrix6, kBodies> body_inertia_;        // I_i
  std::array<spatial::Matrix6, kBodies> inertia_, coriolis_;  // Ic, and B_i then Bc
  std::array<spatial::Vector6, kBodies> velocity_, bias_acceleration_, acceleration_;
  std::array<spatial::Vector6, kBodies> joint_acceleration_;  // alpha_i = sum of S_c a_c
  std::array<spatial::Vector6, kBodies> bias_force_, force_;  // composite F at a = 0, and F
  std::array<spatial::Vector6, kDofs> subspace_;              // S_c
  // Per column j: u_j, w_j, z_j; the vectors its ancestors' columns dot with; and per column c
  // the products Ic S_c and Bc^T S_c of its own body.
  std::array<spatial::Vector6, kDofs> u_, w_, z_, above_q_, above_v_, inertia_s_, coriolis_s_;
};

// The body-frame rotation increment of a change dquat of the quaternion coordinates (w x y z)
// of a unit quaternion: delta_theta = 2 Im(conj(quat) (x) dquat), a 3x4 matrix. The change's
// component along quat (which normalisation removes) maps to zero.
Eigen::Matrix<double, 3, 4> tangent_of_quaternion(const Eigen::Vector4d& quat);

using DynamicsDerivatives = BasicDynamicsDerivatives<0>;
using InverseDynamicsDerivatives = BasicInverseDynamicsDerivatives<0>;

}  // namespace hmpc::humanoid
