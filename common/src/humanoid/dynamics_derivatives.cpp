#include "hmpc/humanoid/dynamics_derivatives.hpp"

#include <Eigen/Geometry>

#include "hmpc/humanoid/spatial.hpp"

namespace hmpc::humanoid {

using spatial::cross_force;
using spatial::cross_motion;
using spatial::Matrix6;
using spatial::skew;
using spatial::Vector6;

template <int A>
BasicDynamicsDerivatives<A>::BasicDynamicsDerivatives(const Model& model)
    : model_(model), dynamics_(model) {
  // Joints on different legs never couple: the CRBA leaves their entries zero.
  mass_matrix_.setZero();
  // Parents precede their children (the RNEA's forward pass relies on it too), so a body's
  // subtree is found by walking each body's ancestors once.
  in_subtree_.fill(false);
  for (int i = 0; i < kBodies; ++i) {
    for (int k = i; k >= 0; k = model_.bodies[k].parent) in_subtree_[k * kBodies + i] = true;
  }
}

namespace {

// B = (v x*) I - I (v x) + (h x-bar*) for a symmetric I: with P = (v x)^T I, (v x*) I = -P and
// I (v x) = P^T, so B = -(P + P^T) + (h x-bar*), where (h x-bar*) w = w x* h is
// [-n^ -f^; -f^ 0] for h = (n, f).
Matrix6 coriolis_matrix(const Vector6& v, const Matrix6& I, const Vector6& h) {
  // (v x) = [w^ 0; u^ w^] for v = (w, u), so P = [w^T I_top + u^T I_bottom; w^T I_bottom].
  const Matrix3 wT = skew(v.head<3>()).transpose(), uT = skew(v.tail<3>()).transpose();
  Matrix6 P;
  P.topRows<3>().noalias() = wT * I.topRows<3>() + uT * I.bottomRows<3>();
  P.bottomRows<3>().noalias() = wT * I.bottomRows<3>();
  Matrix6 B = -(P + P.transpose());
  const Matrix3 n = skew(h.head<3>()), f = skew(h.tail<3>());
  B.topLeftCorner<3, 3>() -= n;
  B.topRightCorner<3, 3>() -= f;
  B.bottomLeftCorner<3, 3>() -= f;
  return B;
}

}  // namespace

template <int A>
void BasicDynamicsDerivatives<A>::velocity_pass(const BasicKinematics<A>& kinematics,
                                                const Velocity& v) {
  // World poses: R_i body to world, p_i the body origin.
  const auto& rotation = kinematics.rotation;
  const auto& position = kinematics.position;
  for (int i = 0; i < kBodies; ++i) {
    // The world inertia about the world origin: the body's mass at its CoM in world
    // coordinates, its central inertia rotated into the world. Body to world motion transform
    // X = [R 0; p^ R R], whose columns are the base's subspace.
    const Matrix3& R = rotation[i];
    const Matrix3 pR = skew(position[i]) * R;
    const Body& body = model_.bodies[i];
    body_inertia_[i] = spatial::spatial_inertia(body.mass, position[i] + R * body.com,
                                                R * body.inertia * R.transpose());
    if (i == 0) {
      for (int c = 0; c < 3; ++c) {  // the columns of X_0: rotations, then translations
        subspace_[c] << R.col(c), pR.col(c);
        subspace_[3 + c] << Vector3::Zero(), R.col(c);
      }
    } else {
      const Vector3 axis = R * model_.bodies[i].axis;
      subspace_[first_column(i)] << axis, position[i].cross(axis);
    }
    // v_i = v_parent + S_i qd_i; the bias acceleration (a = 0):
    // a0_i = a0_parent + (v_i x S_i) qd_i.
    const int parent = model_.bodies[i].parent;
    Vector6 vi = i == 0 ? Vector6::Zero().eval() : velocity_[parent];
    Vector6 ai = i == 0 ? gravity_acceleration() : bias_acceleration_[parent];
    const int first = first_column(i), last = first + column_count(i);
    for (int c = first; c < last; ++c) vi += subspace_[c] * v[c];
    for (int c = first; c < last; ++c) ai += cross_motion(vi, subspace_[c]) * v[c];
    velocity_[i] = vi;
    bias_acceleration_[i] = ai;
    // f0_i = I_i a0_i + v_i x* h_i, B_i = (v_i x*) I_i - I_i (v_i x) + (h_i x-bar*).
    const Vector6 h = body_inertia_[i] * vi;
    bias_force_[i] = body_inertia_[i] * ai + cross_force(vi, h);
    coriolis_[i] = coriolis_matrix(vi, body_inertia_[i], h);
  }
  // Composites, leaves to root: all in world coordinates, so plain sums.
  inertia_ = body_inertia_;
  for (int i = kBodies - 1; i > 0; --i) {
    const int parent = model_.bodies[i].parent;
    inertia_[parent] += inertia_[i];
    coriolis_[parent] += coriolis_[i];
    bias_force_[parent] += bias_force_[i];
  }
  // Ic S_c of each column's body: the CRBA's columns (M_c'c = S_c'^T Ic S_c for c' at or above
  // c) and what the derivatives of the columns at or below c dot with.
  for (int c = 0; c < kDofs; ++c) inertia_s_[c] = inertia_[body_of(c)] * subspace_[c];
}

template <int A>
void BasicDynamicsDerivatives<A>::acceleration_pass(const Velocity& a) {
  // The joint accelerations' part: alpha_i = alpha_parent + S_i qdd_i, f_i = f0_i + I_i alpha_i.
  std::array<Vector6, kBodies>& alpha = joint_acceleration_;
  for (int i = 0; i < kBodies; ++i) {
    const int parent = model_.bodies[i].parent;
    alpha[i] = i == 0 ? Vector6::Zero().eval() : alpha[parent];
    const int first = first_column(i), last = first + column_count(i);
    for (int c = first; c < last; ++c) alpha[i] += subspace_[c] * a[c];
    acceleration_[i] = bias_acceleration_[i] + alpha[i];
    force_[i] = body_inertia_[i] * alpha[i];
  }
  for (int i = kBodies - 1; i > 0; --i) force_[model_.bodies[i].parent] += force_[i];
  for (int i = 0; i < kBodies; ++i) force_[i] += bias_force_[i];
}

template <int A>
void BasicDynamicsDerivatives<A>::derivative_columns(const Velocity& a, Derivatives& out) {
  constexpr int kJoints = Dimensions<A>::kJoints;
  for (int c = 0; c < kDofs; ++c) {
    const int body = body_of(c);
    const Vector6& S = subspace_[c];
    out.tau[c] = S.dot(force_[body]);
    coriolis_s_[c] = coriolis_[body].transpose() * S;
    // Where c's subtree meets its parent p (the world for the base: at rest, gravity's
    // acceleration): w = S x v_p, u = S x a_p - w x v_p, z = S x (v_p + v_body).
    const int parent = model_.bodies[body].parent;
    const Vector6 vp = body == 0 ? Vector6::Zero().eval() : velocity_[parent];
    const Vector6 ap = body == 0 ? gravity_acceleration() : acceleration_[parent];
    w_[c] = cross_motion(S, vp);
    u_[c] = cross_motion(S, ap) - cross_motion(w_[c], vp);
    z_[c] = cross_motion(S, vp + velocity_[body]);
    // What the columns above c dot with.
    above_q_[c] = cross_force(S, force_[body]) - inertia_[body] * u_[c] - coriolis_[body] * w_[c];
    above_v_[c] = coriolis_[body] * S - inertia_[body] * z_[c];
  }
  out.tau.template tail<kJoints>() += model_.armature.cwiseProduct(a.template tail<kJoints>());
  for (int j = 0; j < kDofs; ++j) {
    const int root = body_of(j);
    for (int c = 0; c < kDofs; ++c) {
      const int body = body_of(c);
      if (in_subtree_[root * kBodies + body]) {  // c at or below j
        out.dtau_dq(c, j) = -(inertia_s_[c].dot(u_[j]) + coriolis_s_[c].dot(w_[j]));
        out.dtau_dv(c, j) = coriolis_s_[c].dot(subspace_[j]) - inertia_s_[c].dot(z_[j]);
      } else if (in_subtree_[body * kBodies + root]) {  // c above j
        out.dtau_dq(c, j) = subspace_[c].dot(above_q_[j]);
        out.dtau_dv(c, j) = subspace_[c].dot(above_v_[j]);
      } else {
        out.dtau_dq(c, j) = 0.0;
        out.dtau_dv(c, j) = 0.0;
      }
    }
  }
}

template <int A>
void BasicDynamicsDerivatives<A>::inverse_dynamics_derivatives(const Configuration& q,
                                                               const Velocity& v, const Velocity& a,
                                                               Derivatives& out) {
  dynamics_.kinematics(q, v, kinematics_);
  inverse_dynamics_derivatives(kinematics_, v, a, out);
}

template <int A>
void BasicDynamicsDerivatives<A>::inverse_dynamics_derivatives(const BasicKinematics<A>& kinematics,
                                                               const Velocity& v, const Velocity& a,
                                                               Derivatives& out) {
  velocity_pass(kinematics, v);
  acceleration_pass(a);
  derivative_columns(a, out);
}

template <int A>
void BasicDynamicsDerivatives<A>::forward_dynamics_derivatives(
    const Configuration& q, const Velocity& v, const Velocity& tau,
    BasicForwardDynamicsDerivatives<A>& out) {
  // The velocity pass gives the bias forces c_c = S_c^T F0 and, from the composite inertias,
  // M (the CRBA in world coordinates): M_c'c = S_c'^T Ic S_c for c' at or above c.
  dynamics_.kinematics(q, v, kinematics_);
  velocity_pass(kinematics_, v);
  Velocity bias;
  for (int c = 0; c < kDofs; ++c) {
    const int body = body_of(c);
    bias[c] = subspace_[c].dot(bias_force_[body]);
    for (int k = c; k >= 0; --k) {
      if (!in_subtree_[body_of(k) * kBodies + body]) continue;
      const double m = subspace_[k].dot(inertia_s_[c]);
      mass_matrix_(k, c) = m;
      mass_matrix_(c, k) = m;
    }
  }
  mass_matrix_.diagonal().template tail<Dimensions<A>::kJoints>() += model_.armature;
  // M^-1 = L^-T L^-1 from M = L L^T. L^-1 by forward substitution a row at a time, row i being
  // (e_i - sum over k < i of L_ik row k) / L_ii: kept as the columns of L^-T, each row is one
  // vectorised column update, and the rows' entries do not wait on each other.
  cholesky_.compute(mass_matrix_);
  const MassMatrix& L = cholesky_.matrixLLT();  // lower triangle: L
  const Velocity reciprocal = L.diagonal().cwiseInverse();
  MassMatrix inverse_l_transposed;
  for (int i = 0; i < kDofs; ++i) {
    Velocity row = Velocity::Unit(i);
    for (int k = 0; k < i; ++k) row -= L(i, k) * inverse_l_transposed.col(k);
    inverse_l_transposed.col(i) = row * reciprocal[i];
  }
  const MassMatrix inverse_l = inverse_l_transposed.transpose();
  // M^-1 is symmetric and L^-1 lower triangular: (M^-1)_ij = sum over k >= i of
  // (L^-1)_ki (L^-1)_kj for i >= j, a sixth of the dense product's multiplications.
  for (int j = 0; j < kDofs; ++j) {
    for (int i = j; i < kDofs; ++i) {
      const double m = inverse_l.col(i).tail(kDofs - i).dot(inverse_l.col(j).tail(kDofs - i));
      out.da_dtau(i, j) = m;
      out.da_dtau(j, i) = m;
    }
  }
  // a = M^-1 (tau - c), then the derivatives at it: da/dx = -M^-1 d tau/dx, da/dtau = M^-1.
  out.a.noalias() = out.da_dtau * (tau - bias);
  acceleration_pass(out.a);
  derivative_columns(out.a, inverse_);
  out.da_dq.noalias() = -out.da_dtau.lazyProduct(inverse_.dtau_dq);
  out.da_dv.noalias() = -out.da_dtau.lazyProduct(inverse_.dtau_dv);
}

template <int A>
void BasicDynamicsDerivatives<A>::add_point_force_derivatives(int body, const Vector3& p,
                                                              const PointForceSlopes& slopes,
                                                              MassMatrix& dq,
                                                              MassMatrix& dv) const {
  // The point's chain of columns, from its body's to the root's, and there J_c = P(p) S_c
  // and w_c (the other columns of J are zero).
  const auto point_velocity = [&p](const Vector3& angular, const Vector3& linear) -> Vector3 {
    return linear + angular.cross(p);
  };
  std::array<int, kDofs> chain;
  std::array<Vector3, kDofs> J, w;
  int length = 0;
  for (int b = body; b >= 0; b = model_.bodies[b].parent) {
    for (int c = first_column(b) + column_count(b) - 1; c >= first_column(b); --c) {
      chain[length] = c;
      w[length] = subspace_[c].template head<3>();
      J[length] = point_velocity(w[length], subspace_[c].template tail<3>());
      ++length;
    }
  }
  const Vector3& phi = slopes.force;
  const Vector3 omega = velocity_[body].template head<3>(),
                alpha = joint_acceleration_[body].template head<3>();
  for (int n = 0; n < length; ++n) {
    const int j = chain[n], root = body_of(j);
    const Vector3& dp = J[n];
    // S_j x (v_body - v_p), and the same for alpha (v_p = 0 for the base).
    Vector6 dv_rel = velocity_[body], da_rel = joint_acceleration_[body];
    if (root != 0) {
      dv_rel -= velocity_[model_.bodies[root].parent];
      da_rel -= joint_acceleration_[model_.bodies[root].parent];
    }
    const Vector6 turned_velocity = cross_motion(subspace_[j], dv_rel),
                  turned_acceleration = cross_motion(subspace_[j], da_rel);
    const Vector3 dvelocity = omega.cross(dp) + point_velocity(turned_velocity.template head<3>(),
                                                               turned_velocity.template tail<3>());
    const Vector3 dacceleration =
        alpha.cross(dp) + point_velocity(turned_acceleration.template head<3>(),
                                         turned_acceleration.template tail<3>());
    const Vector3 chi = slopes.by_position * dp + slopes.by_velocity * dvelocity +
                        slopes.by_acceleration * dacceleration;
    const Vector3 turned = chi + phi.cross(w[n]), moment = dp.cross(phi);
    const Vector3 phi_v = slopes.by_velocity * dp;  // phi_v J_j
    // The chain's columns at or below j: those before it, or all of it for a base column.
    const int below = root == 0 ? length : n + 1;
    for (int m = 0; m < below; ++m) dq(chain[m], j) += J[m].dot(turned);
    for (int m = below; m < length; ++m) dq(chain[m], j) += J[m].dot(chi) + w[m].dot(moment);
    for (int m = 0; m < length; ++m) dv(chain[m], j) += J[m].dot(phi_v);
  }
}

Eigen::Matrix<double, 3, 4> tangent_of_quaternion(const Eigen::Vector4d& quat) {
  // 2 Im(conj(q) (x) dq) = 2 (w dv - dw u - u x dv), u = (x, y, z).
  const double w = quat[0];
  const Vector3 u = quat.tail<3>();
  Eigen::Matrix<double, 3, 4> G;
  G.col(0) = -2.0 * u;
  G.rightCols<3>() = 2.0 * (w * Matrix3::Identity() - skew(u));
  return G;
}

template class BasicDynamicsDerivatives<0>;
template class BasicDynamicsDerivatives<1>;

}  // namespace hmpc::humanoid
