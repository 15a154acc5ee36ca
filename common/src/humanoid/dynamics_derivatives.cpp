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
  for (int i = 0; i < kBodies; ++i) {
    const Body& b = model_.bodies[i];
    body_inertia_[i] = spatial::spatial_inertia(b.mass, b.com, b.inertia);
  }
  // Parents precede their children (the RNEA's forward pass relies on it too), so a body's
  // subtree is found by walking each body's ancestors once.
  in_subtree_.fill(false);
  for (int i = 0; i < kBodies; ++i) {
    for (int k = i; k >= 0; k = model_.bodies[k].parent) in_subtree_[k * kBodies + i] = true;
  }
}

template <int A>
void BasicDynamicsDerivatives<A>::forward_pass(const Configuration& q, const Velocity& v,
                                               const Velocity& a) {
  // World poses: R_i body to world, p_i the body origin.
  std::array<Matrix3, kBodies> rotation;
  std::array<Vector3, kBodies> position;
  rotation[0] = Eigen::Quaterniond(q[3], q[4], q[5], q[6]).normalized().toRotationMatrix();
  position[0] = q.template head<3>();
  for (int i = 1; i < kBodies; ++i) {
    const Body& b = model_.bodies[i];
    rotation[i] =
        rotation[b.parent] * Eigen::AngleAxisd(q[7 + i - 1], b.axis).toRotationMatrix();
    position[i] = position[b.parent] + rotation[b.parent] * b.joint_origin;
  }
  // Gravity as a fictitious upward acceleration of the world, as in the RNEA.
  Vector6 gravity_acceleration;
  gravity_acceleration << Vector3::Zero(), -model_.gravity;
  for (int i = 0; i < kBodies; ++i) {
    // Body to world: motion X = [R 0; p^ R R], force X^-T = [R p^ R; 0 R] =: F, and the world
    // inertia I = F I_body F^T.
    const Matrix3& R = rotation[i];
    const Matrix3 pR = skew(position[i]) * R;
    Matrix6 F;
    F << R, pR, Matrix3::Zero(), R;
    inertia_[i] = F * body_inertia_[i] * F.transpose();
    if (i == 0) {
      for (int c = 0; c < 3; ++c) {  // the columns of X_0: rotations, then translations
        subspace_[c] << R.col(c), pR.col(c);
        subspace_[3 + c] << Vector3::Zero(), R.col(c);
      }
    } else {
      const Vector3 axis = R * model_.bodies[i].axis;
      subspace_[first_column(i)] << axis, position[i].cross(axis);
    }
    // v_i = v_parent + S_i qd_i; Sdot_i = v_i x S_i; a_i = a_parent + S_i qdd_i + Sdot_i qd_i.
    const int parent = model_.bodies[i].parent;
    Vector6 vi = i == 0 ? Vector6::Zero().eval() : velocity_[parent];
    Vector6 ai = i == 0 ? gravity_acceleration : acceleration_[parent];
    const int first = first_column(i), last = first + column_count(i);
    for (int c = first; c < last; ++c) vi += subspace_[c] * v[c];
    for (int c = first; c < last; ++c) {
      subspace_rate_[c] = cross_motion(vi, subspace_[c]);
      ai += subspace_[c] * a[c] + subspace_rate_[c] * v[c];
    }
    velocity_[i] = vi;
    acceleration_[i] = ai;
    // f_i = I_i a_i + v_i x* I_i v_i.
    momentum_[i] = inertia_[i] * vi;
    force_[i] = inertia_[i] * ai + cross_force(vi, momentum_[i]);
  }
  // F_i = f_i + the children's F.
  total_ = force_;
  for (int i = kBodies - 1; i > 0; --i) total_[model_.bodies[i].parent] += total_[i];
}

template <int A>
void BasicDynamicsDerivatives<A>::configuration_column(int column, const Velocity& v,
                                                       const Velocity& a, Velocity& dtau) {
  const int root = body_of(column);
  const Vector6& S = subspace_[column];
  for (int i = root; i < kBodies; ++i) {
    if (!in_subtree_[root * kBodies + i]) continue;
    const int parent = model_.bodies[i].parent;
    // The subtree's root keeps its parent's motion; below it the parent's derivative carries.
    Vector6 dv = i == root ? Vector6::Zero().eval() : d_velocity_[parent];
    Vector6 da = i == root ? Vector6::Zero().eval() : d_acceleration_[parent];
    const int first = first_column(i), last = first + column_count(i);
    // dS_c = S x S_c; dv_i = dv_parent + dS_c qd_c.
    for (int c = first; c < last; ++c) dv += cross_motion(S, subspace_[c]) * v[c];
    // dSdot_c = dv_i x S_c + v_i x dS_c; da_i = da_parent + dS_c qdd_c + dSdot_c qd_c.
    for (int c = first; c < last; ++c) {
      const Vector6 dS = cross_motion(S, subspace_[c]);
      da += dS * a[c] +
            (cross_motion(dv, subspace_[c]) + cross_motion(velocity_[i], dS)) * v[c];
    }
    d_velocity_[i] = dv;
    d_acceleration_[i] = da;
    // dI x = S x* (I x) - I (S x x), and
    // df_i = dI a_i + I da_i + dv_i x* (I v_i) + v_i x* (dI v_i + I dv_i).
    const Matrix6& I = inertia_[i];
    const Vector6 dI_a =
        cross_force(S, force_[i] - cross_force(velocity_[i], momentum_[i])) -
        I * cross_motion(S, acceleration_[i]);
    const Vector6 dI_v = cross_force(S, momentum_[i]) - I * cross_motion(S, velocity_[i]);
    d_force_[i] = dI_a + I * da + cross_force(dv, momentum_[i]) +
                  cross_force(velocity_[i], dI_v + I * dv);
  }
  backward_column(column, dtau);
  // The subspaces below the root moved too: tau_c = S_c^T F_c gains dS_c^T F_c.
  for (int c = 0; c < kDofs; ++c) {
    const int body = body_of(c);
    if (in_subtree_[root * kBodies + body]) {
      dtau[c] += cross_motion(S, subspace_[c]).dot(total_[body]);
    }
  }
}

template <int A>
void BasicDynamicsDerivatives<A>::velocity_column(int column, const Velocity& v, Velocity& dtau) {
  const int root = body_of(column);
  const Vector6& S = subspace_[column];
  for (int i = root; i < kBodies; ++i) {
    if (!in_subtree_[root * kBodies + i]) continue;
    const int parent = model_.bodies[i].parent;
    // dv_i = S for the whole subtree; da_i = da_parent + (dv_i x S_c) qd_c (+ Sdot_column).
    Vector6 da = i == root ? Vector6::Zero().eval() : d_acceleration_[parent];
    const int first = first_column(i), last = first + column_count(i);
    for (int c = first; c < last; ++c) {
      da += cross_motion(S, subspace_[c]) * v[c];
      if (c == column) da += subspace_rate_[c];
    }
    d_acceleration_[i] = da;
    // df_i = I da_i + dv_i x* (I v_i) + v_i x* (I dv_i).
    const Matrix6& I = inertia_[i];
    d_force_[i] =
        I * da + cross_force(S, momentum_[i]) + cross_force(velocity_[i], I * S);
  }
  backward_column(column, dtau);
}

template <int A>
void BasicDynamicsDerivatives<A>::backward_column(int column, Velocity& dtau) {
  const int root = body_of(column);
  // dF_i = df_i + the children's dF, over the subtree; the root's dF reaches every ancestor
  // unchanged (nothing else moves).
  for (int i = kBodies - 1; i > root; --i) {
    if (in_subtree_[root * kBodies + i]) d_force_[model_.bodies[i].parent] += d_force_[i];
  }
  for (int c = 0; c < kDofs; ++c) {
    const int body = body_of(c);
    if (in_subtree_[root * kBodies + body]) {
      dtau[c] = subspace_[c].dot(d_force_[body]);
    } else if (in_subtree_[body * kBodies + root]) {
      dtau[c] = subspace_[c].dot(d_force_[root]);
    } else {
      dtau[c] = 0.0;
    }
  }
}

template <int A>
void BasicDynamicsDerivatives<A>::inverse_dynamics_derivatives(const Configuration& q,
                                                               const Velocity& v,
                                                               const Velocity& a,
                                                               Derivatives& out) {
  forward_pass(q, v, a);
  for (int c = 0; c < kDofs; ++c) out.tau[c] = subspace_[c].dot(total_[body_of(c)]);
  out.tau.template tail<Dimensions<A>::kJoints>() +=
      model_.armature.cwiseProduct(a.template tail<Dimensions<A>::kJoints>());
  Velocity column;
  for (int c = 0; c < kDofs; ++c) {
    configuration_column(c, v, a, column);
    out.dtau_dq.col(c) = column;
    velocity_column(c, v, column);
    out.dtau_dv.col(c) = column;
  }
}

template <int A>
void BasicDynamicsDerivatives<A>::forward_dynamics_derivatives(
    const Configuration& q, const Velocity& v, const Velocity& tau,
    BasicForwardDynamicsDerivatives<A>& out) {
  // a = M^-1 (tau - c), c the RNEA at a = 0 (one pass sets the configuration for M too).
  const Velocity c = dynamics_.inverse_dynamics(q, v, Velocity::Zero());
  cholesky_.compute(dynamics_.mass_matrix());
  out.a = cholesky_.solve(tau - c);
  inverse_dynamics_derivatives(q, v, out.a, inverse_);
  out.da_dtau.setIdentity();
  cholesky_.solveInPlace(out.da_dtau);
  out.da_dq.noalias() = -out.da_dtau * inverse_.dtau_dq;
  out.da_dv.noalias() = -out.da_dtau * inverse_.dtau_dv;
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
