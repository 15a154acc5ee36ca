#include "hmpc/humanoid/dynamics.hpp"

#include <Eigen/Geometry>

#include "hmpc/humanoid/spatial.hpp"
#include "joint_transform.hpp"

namespace hmpc::humanoid {
namespace {

using spatial::cross_force;
using spatial::cross_motion;
using spatial::motion_transform;
using spatial::spatial_inertia;

constexpr int dof_of(int body) { return kBaseDofs + body - 1; }

// Body i's pose and velocity in the forward pass of kinematics(), from its parent's and its
// rotation relative to the parent.
template <int A>
EIGEN_ALWAYS_INLINE void body_kinematics(const BasicModel<A>& model, int i,
                                         const Matrix3& joint_rotation, const BasicVelocity<A>& v,
                                         BasicKinematics<A>& out) {
  const Body& b = model.bodies[i];
  out.rotation[i] = out.rotation[b.parent] * joint_rotation;
  out.position[i] = out.position[b.parent] + out.rotation[b.parent] * b.joint_origin;
  // Body velocity: the parent's velocity moved to the joint, rotated into the body frame, plus
  // the joint rate about the axis.
  const Vector3 omega = out.velocity[b.parent].template head<3>();
  const Vector3 v_joint = out.velocity[b.parent].template tail<3>() + omega.cross(b.joint_origin);
  out.velocity[i].template head<3>() = joint_rotation.transpose() * omega + b.axis * v[dof_of(i)];
  out.velocity[i].template tail<3>() = joint_rotation.transpose() * v_joint;
}

// The forward pass of kinematics() given each body's rotation relative to its parent (to the
// world for the torso).
template <int A>
void kinematics_from_rotations(const BasicModel<A>& model,
                               const std::array<Matrix3, Dimensions<A>::kBodies>& rotation,
                               const Vector3& base_position, const BasicVelocity<A>& v,
                               BasicKinematics<A>& out) {
  out.rotation[0] = rotation[0];
  out.position[0] = base_position;
  out.velocity[0] = v.template head<6>();
  for (int i = 1; i < Dimensions<A>::kBodies; ++i) body_kinematics(model, i, rotation[i], v, out);
}

}  // namespace

template <int A>
BasicDynamics<A>::BasicDynamics(const Model& model) : model_(model) {
  for (int i = 0; i < kBodies; ++i) {
    const Body& b = model_.bodies[i];
    inertia_[i] = spatial_inertia(b.mass, b.com, b.inertia);
    subspace_[i] << b.axis, Vector3::Zero();
    transform_pattern_[i] =
        joint_transform::index_of(joint_transform::pattern_of(b.axis, b.joint_origin));
  }
  // Children have larger indices than their parents (Body), so leaves to root is i descending.
  for (int i = kBodies - 1; i > 0; --i) {
    subtree_dof_[i][subtree_size_[i]++] = dof_of(i);
    const int parent = model_.bodies[i].parent;
    offset_in_parent_[i] = subtree_size_[parent];
    first_into_parent_[i] = !has_children_[parent];
    has_children_[parent] = true;
    for (int c = 0; c < subtree_size_[i]; ++c) {
      subtree_dof_[parent][subtree_size_[parent]++] = subtree_dof_[i][c];
    }
  }
  in_subtree_[0][0] = true;
  for (int i = 1; i < kBodies; ++i) {
    for (int b = 0; b < kBodies; ++b)
      in_subtree_[b][i] = in_subtree_[b][model_.bodies[i].parent] || b == i;
  }
  // mass_matrix() writes the entries of each joint and its ancestors; the rest, joints on
  // different legs, never couple.
  mass_matrix_.setZero();
}

template <int A>
void BasicDynamics<A>::set_configuration(const Configuration& q) {
  set_base_pose(q);
  for (int i = 1; i < kBodies; ++i) set_joint_angle(i, q[7 + i - 1]);
}

template <int A>
void BasicDynamics<A>::set_base_pose(const Configuration& q) {
  configuration_.template head<7>() = q.template head<7>();
  // Floating base: q = (p, quaternion w x y z); the world-to-torso transform has E = R^T.
  const Eigen::Quaterniond orientation(q[3], q[4], q[5], q[6]);
  transform_[0] = motion_transform(orientation.normalized().toRotationMatrix().transpose(),
                                   q.template head<3>());
}

template <int A>
void BasicDynamics<A>::set_joint_angle(int body, double angle) {
  configuration_[7 + body - 1] = angle;
  const Body& b = model_.bodies[body];
  // X = X_J(q) X_T: translate to the joint, then rotate about its axis.
  const Matrix3 E = Eigen::AngleAxisd(angle, b.axis).toRotationMatrix().transpose();
  transform_[body] = motion_transform(E, b.joint_origin);
}

template <int A>
const BasicMassMatrix<A>& BasicDynamics<A>::mass_matrix(const Configuration& q) {
  set_configuration(q);
  return mass_matrix();
}

template <int A>
const BasicMassMatrix<A>& BasicDynamics<A>::mass_matrix() {
  // Composite inertias, leaves to root (Table 6.2): I^c_parent += X^T I^c X, starting from the
  // parent's own inertia. Body i's children come first, so I^c_i is complete when i is reached;
  // a body without children is its own composite.
  const auto composite = [&](int i) -> const Matrix6& {
    return has_children_[i] ? composite_[i] : inertia_[i];
  };
  for (int i = kBodies - 1; i > 0; --i) {
    // F = I^c_i S_i is the spatial force that accelerates the composite body i at unit rate;
    // carried to each ancestor j it gives M_ji = S_j^T F (the base: M_0i = F).
    // About a coordinate axis a (the pattern's), S = +-e_a: I^c S and S^T F are +-(column a) and
    // +-F_a, the same numbers as the products, whose other terms are exact zeros. (The forces are
    // stored by rows; a column is copied out so that its dot product adds in the packets' order.)
    const int a = joint_transform::pattern_at(transform_pattern_[i]).axis;
    const int count = subtree_size_[i];
    if (a >= 0) {
      subtree_force_[i].col(count - 1) = composite(i).col(a) * subspace_[i][a];
    } else {
      subtree_force_[i].col(count - 1) = composite(i) * subspace_[i];
    }
    for (int c = 0; c < count; ++c) {
      const int k = subtree_dof_[i][c];
      const double m = a >= 0 ? subspace_[i][a] * subtree_force_[i](a, c)
                              : subspace_[i].dot(Vector6(subtree_force_[i].col(c)));
      mass_matrix_(dof_of(i), k) = m;
      mass_matrix_(k, dof_of(i)) = m;
    }
    mass_matrix_(dof_of(i), dof_of(i)) += model_.armature[i - 1];
    const int parent = model_.bodies[i].parent;
    const auto carry = joint_transform::carry_for<kBodies>(transform_pattern_[i]);
    carry(composite_[parent], first_into_parent_[i] ? inertia_[parent] : composite_[parent],
          transform_[i], composite(i), subtree_force_[i], count, subtree_force_[parent],
          offset_in_parent_[i]);
  }
  // Base block: S_0 = identity, so M_00 = I^c_0 and M_0k = F.
  mass_matrix_.template topLeftCorner<6, 6>() = composite(0);
  for (int c = 0; c < subtree_size_[0]; ++c) {
    const int k = subtree_dof_[0][c];
    mass_matrix_.template block<6, 1>(0, k) = subtree_force_[0].col(c);
    mass_matrix_.template block<1, 6>(k, 0) = subtree_force_[0].col(c).transpose();
  }
  return mass_matrix_;
}

template <int A>
BasicVelocity<A> BasicDynamics<A>::inverse_dynamics(const Configuration& q, const Velocity& v,
                                                    const Velocity& a) {
  set_configuration(q);
  return inverse_dynamics(v, a);
}

template <int A>
EIGEN_ALWAYS_INLINE void BasicDynamics<A>::forward_pass(int i, const InverseDynamicsPasses& from,
                                                        InverseDynamicsPasses& to,
                                                        const Velocity& v,
                                                        const Velocity& a) const {
  const int parent = model_.bodies[i].parent;
  const Vector6 joint_velocity = subspace_[i] * v[dof_of(i)];
  to.velocity[i] = transform_[i] * from.velocity[parent] + joint_velocity;
  to.acceleration[i] = transform_[i] * from.acceleration[parent] + subspace_[i] * a[dof_of(i)] +
                       cross_motion(to.velocity[i], joint_velocity);
}

template <int A>
EIGEN_ALWAYS_INLINE void BasicDynamics<A>::own_force(int i, InverseDynamicsPasses& passes) const {
  passes.own_force[i] = inertia_[i] * passes.acceleration[i] +
                        cross_force(passes.velocity[i], inertia_[i] * passes.velocity[i]);
  passes.force[i] = passes.own_force[i];
}

template <int A>
EIGEN_ALWAYS_INLINE void BasicDynamics<A>::backward_pass(int i, InverseDynamicsPasses& passes,
                                                         const Velocity& a) const {
  passes.tau[dof_of(i)] = subspace_[i].dot(passes.force[i]) + model_.armature[i - 1] * a[dof_of(i)];
  passes.carried[i] = transform_[i].transpose() * passes.force[i];
  passes.force[model_.bodies[i].parent] += passes.carried[i];
}

template <int A>
BasicVelocity<A> BasicDynamics<A>::inverse_dynamics(const Velocity& v, const Velocity& a) {
  return inverse_dynamics(v, a, passes_);
}

template <int A>
BasicVelocity<A> BasicDynamics<A>::inverse_dynamics(const Velocity& v, const Velocity& a,
                                                    InverseDynamicsPasses& passes) {
  // Gravity as a fictitious upward acceleration of the world: a_world = -(0, g).
  Vector6 world_acceleration;
  world_acceleration << Vector3::Zero(), -model_.gravity;
  // Forward pass (Table 5.1): v_i = X_i v_parent + S_i qd_i,
  // a_i = X_i a_parent + S_i qdd_i + v_i x S_i qd_i; f_i = I_i a_i + v_i x* I_i v_i.
  // The base joint has S = 1: v_0 and a_0 are v and a's first six entries.
  passes.velocity[0] = v.template head<6>();
  passes.acceleration[0] = transform_[0] * world_acceleration + a.template head<6>();
  for (int i = 1; i < kBodies; ++i) forward_pass(i, passes, passes, v, a);
  for (int i = 0; i < kBodies; ++i) own_force(i, passes);
  // Backward pass: tau_i = S_i^T f_i, f_parent += X_i^T f_i.
  for (int i = kBodies - 1; i > 0; --i) backward_pass(i, passes, a);
  passes.tau.template head<6>() = passes.force[0];
  return passes.tau;
}

template <int A>
BasicVelocity<A> BasicDynamics<A>::inverse_dynamics_in_subtree(
    int body, const Velocity& v, const Velocity& a, const InverseDynamicsPasses& passes) {
  if (body == 0) return inverse_dynamics(v, a);
  // The subtree's forward pass from the parent's kept velocity and acceleration. Children have
  // larger indices than their parents (Body), so the subtree is among the bodies after body.
  const std::array<bool, kBodies>& in_subtree = in_subtree_[body];
  forward_pass(body, passes, passes_, v, a);
  own_force(body, passes_);
  for (int i = body + 1; i < kBodies; ++i) {
    if (!in_subtree[i]) continue;
    forward_pass(i, passes_, passes_, v, a);
    own_force(i, passes_);
  }
  // The path to the root starts again from its own forces; its other children's are added as
  // they were, in the same order (descending index), so every sum has its full pass's bits.
  std::array<bool, kBodies> on_path{};
  for (int j = model_.bodies[body].parent;; j = model_.bodies[j].parent) {
    on_path[j] = true;
    passes_.force[j] = passes.own_force[j];
    if (j == 0) break;
  }
  passes_.tau = passes.tau;
  for (int i = kBodies - 1; i > 0; --i) {
    if (in_subtree[i] || on_path[i]) {
      backward_pass(i, passes_, a);
    } else if (on_path[model_.bodies[i].parent]) {
      passes_.force[model_.bodies[i].parent] += passes.carried[i];
    }
  }
  passes_.tau.template head<6>() = passes_.force[0];
  return passes_.tau;
}

template <int A>
BasicVelocity<A> BasicDynamics<A>::bias_forces(const Configuration& q, const Velocity& v) {
  return inverse_dynamics(q, v, Velocity::Zero());
}

template <int A>
BasicVelocity<A> BasicDynamics<A>::forward_dynamics(const Configuration& q, const Velocity& v,
                                                    const Velocity& tau) {
  const Velocity c = bias_forces(q, v);
  cholesky_.compute(mass_matrix(q));
  return cholesky_.solve(tau - c);
}

template <int A>
void BasicDynamics<A>::kinematics(const Configuration& q, const Velocity& v,
                                  Kinematics& out) const {
  std::array<Matrix3, kBodies> rotation;
  rotation[0] = Eigen::Quaterniond(q[3], q[4], q[5], q[6]).normalized().toRotationMatrix();
  for (int i = 1; i < kBodies; ++i)
    rotation[i] = Eigen::AngleAxisd(q[7 + i - 1], model_.bodies[i].axis).toRotationMatrix();
  kinematics_from_rotations(model_, rotation, q.template head<3>(), v, out);
}

template <int A>
void BasicDynamics<A>::kinematics(const Velocity& v, Kinematics& out) const {
  // The transforms hold E = the transposed rotations (set_configuration()).
  std::array<Matrix3, kBodies> rotation;
  for (int i = 0; i < kBodies; ++i)
    rotation[i] = transform_[i].template topLeftCorner<3, 3>().transpose();
  kinematics_from_rotations(model_, rotation, configuration_.template head<3>(), v, out);
}

template <int A>
void BasicDynamics<A>::kinematics_in_subtree(int body, const Velocity& v, Kinematics& out) const {
  for (int i = body; i < kBodies; ++i) {
    if (in_subtree_[body][i]) {
      body_kinematics(model_, i, transform_[i].template topLeftCorner<3, 3>().transpose(), v, out);
    }
  }
}

template class BasicDynamics<0>;
template class BasicDynamics<1>;

}  // namespace hmpc::humanoid
