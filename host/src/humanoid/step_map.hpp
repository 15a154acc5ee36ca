// BasicStepMap's member definitions (step.hpp), shared by step_biped.cpp and step_arm.cpp,
// which instantiate it for the biped and for the robot with an arm: the two instantiations
// are the library's heaviest after the closed loop's, and compile in parallel.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "hmpc/humanoid/step.hpp"
#include "hmpc/solver/finite_difference.hpp"

namespace hmpc::humanoid {
namespace {

constexpr int kFirstJoint = 7;  // q index of the first joint angle

// (S2): q moved over h by the new velocity v.
template <class Configuration, class Velocity>
void move_configuration(Configuration& q, const Velocity& v, double h) {
  constexpr int kJoints = Velocity::RowsAtCompileTime - kBaseDofs;
  const Eigen::Quaterniond orientation(q[3], q[4], q[5], q[6]);
  q.template head<3>() +=
      h * (orientation.normalized().toRotationMatrix() * v.template segment<3>(3));
  // exp of the rotation vector theta = h omega: (cos(|theta|/2), sin(|theta|/2) theta/|theta|);
  // sin(a)/a by its Taylor series near 0, where the quotient loses all digits.
  const Vector3 theta = h * v.template head<3>();
  const double half_angle = 0.5 * theta.norm();
  const double sinc =
      half_angle < 1e-4 ? 1.0 - half_angle * half_angle / 6.0 : std::sin(half_angle) / half_angle;
  const Vector3 axis_part = 0.5 * sinc * theta;
  const Eigen::Quaterniond increment(std::cos(half_angle), axis_part.x(), axis_part.y(),
                                     axis_part.z());
  const Eigen::Quaterniond rotated = (orientation * increment).normalized();
  q[3] = rotated.w();
  q[4] = rotated.x();
  q[5] = rotated.y();
  q[6] = rotated.z();
  q.template tail<kJoints>() += h * v.template tail<kJoints>();
}

// The rotation guard's rate: the torso's |omega| or the fastest joint's.
template <class Velocity>
double guard_rate(const Velocity& v) {
  constexpr int kJoints = Velocity::RowsAtCompileTime - kBaseDofs;
  return std::max(v.template head<3>().norm(), v.template tail<kJoints>().cwiseAbs().maxCoeff());
}

// d guard_rate / dv (where one rate is the largest).
template <class Velocity>
Eigen::Matrix<double, 1, Velocity::RowsAtCompileTime> guard_rate_gradient(const Velocity& v) {
  constexpr int kDofs = Velocity::RowsAtCompileTime, kJoints = kDofs - kBaseDofs;
  Eigen::Matrix<double, 1, kDofs> gradient = Eigen::Matrix<double, 1, kDofs>::Zero();
  int joint = 0;
  const double joint_rate = v.template tail<kJoints>().cwiseAbs().maxCoeff(&joint);
  const double omega = v.template head<3>().norm();
  if (omega >= joint_rate) {
    gradient.template head<3>() = v.template head<3>().transpose() / omega;
  } else {
    gradient[kBaseDofs + joint] = v[kBaseDofs + joint] > 0.0 ? 1.0 : -1.0;
  }
  return gradient;
}

// The body whose joint entry i of q (v) moves: its own for a joint, the torso for the base.
int moved_body_of_configuration(int i) { return i < kFirstJoint ? 0 : i - kFirstJoint + 1; }
int moved_body_of_velocity(int i) { return i < kBaseDofs ? 0 : i - kBaseDofs + 1; }

// One point's term J^T (f + h D J a) of (L2)'s sum.
template <class PointJacobian, class Velocity>
Velocity contact_term(const PointJacobian& J, const Vector3& force, const Matrix3& dforce,
                      const Velocity& a, double h) {
  return J.transpose() * (force + h * dforce * (J * a));
}

// Forward-difference step for x_i: sqrt(eps), scaled like the reference's central one
// (finite_difference.hpp).
double forward_step(double xi) { return detail::fd_step(xi, 0.5); }

}  // namespace

template <int A>
BasicStepMap<A>::BasicStepMap(const Model& model, const Parameters& parameters,
                              const ContactParameters& contact, double max_substep,
                              ResidualJacobian residual)
    : dynamics_(model), contact_(model, parameters, contact), parameters_(parameters),
      joint_lower_(model.joint_lower), joint_upper_(model.joint_upper), max_substep_(max_substep),
      residual_(residual), derivatives_(model) {}

template <int A>
double BasicStepMap<A>::stop_term(int j, double q, double v, double a, double h) const {
  const JointStop stop = joint_stop(q, v, joint_lower_[j], joint_upper_[j], parameters_);
  return stop.torque - h * stop.stiffness * v - (h * stop.damping + h * h * stop.stiffness) * a;
}

template <int A>
const BasicContactState<A>& BasicStepMap<A>::evaluate_contact(const State& x) {
  dynamics_.set_configuration(x.q);
  dynamics_.kinematics(x.v, kinematics_);
  contact_.evaluate(kinematics_, x.v, contact_state_);
  return contact_state_;
}

template <int A>
template <class Substep>
BasicState<A> BasicStepMap<A>::advance(const State& x, double dt, const Substep& substep) const {
  const int substeps = std::max(1, static_cast<int>(std::ceil(dt / max_substep_ - 1e-9)));
  const double nominal = dt / substeps;
  State next = x;
  double remaining = dt;
  while (remaining > 0.0) {
    // The rotation guard (step.hpp): shorten the sub-step so no body turns more than
    // kMaxRotation relative to its parent or the world; a non-finite rate keeps `nominal`.
    const double rate = guard_rate(next.v);
    SubStep sub{nominal, SubStep::kFixed};
    if (rate * nominal > kMaxRotation) {
      const double guarded = kMaxRotation / rate, floor = nominal / kMaxRefinement;
      sub = guarded < floor ? SubStep{floor, SubStep::kFixed} : SubStep{guarded, SubStep::kGuarded};
    }
    // Finish dt exactly, without leaving a sliver for a last, tiny sub-step.
    if (remaining < 1.5 * sub.h) sub = SubStep{remaining, SubStep::kRemainder};
    substep(next, sub);
    remaining -= sub.h;
  }
  return next;
}

template <int A>
BasicState<A> BasicStepMap<A>::step(const State& x, const JointVector& tau, double dt,
                                    const Velocity& external) {
  return advance(x, dt,
                 [&](State& s, const SubStep& sub) { substep(s, tau, sub.h, external, false); });
}

template <int A>
BasicState<A> BasicStepMap<A>::step_joints(const State& x, const JointVector& tau, double dt) {
  return advance(
      x, dt, [&](State& s, const SubStep& sub) { substep(s, tau, sub.h, Velocity::Zero(), true); });
}

// The sub-step lengths' derivatives: zero for a fixed length, -h / rate d rate for the
// guard's kMaxRotation / rate, and for the remainder minus the derivative of the time
// elapsed before it. The rate's derivative reaches the chain through the last Rates rows of
// the Jacobians (the rates they carry: all of v, or the legs' with the base held).
template <int A>
template <int Rates, class Jacobian, class ControlJacobian, class Linearised>
BasicState<A> BasicStepMap<A>::linearise_chain(const State& x, double dt, Jacobian& fx,
                                               ControlJacobian& fu, const Linearised& linearised) {
  using Row = Eigen::Matrix<double, 1, Jacobian::ColsAtCompileTime>;
  fx.setIdentity();
  fu.setZero();
  Row elapsed_x = Row::Zero();
  ControlRow elapsed_u = ControlRow::Zero();
  return advance(x, dt, [&](State& s, const SubStep& sub) {
    Row dh_x = Row::Zero();
    ControlRow dh_u = ControlRow::Zero();
    if (sub.rule == SubStep::kGuarded) {
      const Eigen::Matrix<double, 1, Rates> drate =
          -sub.h / guard_rate(s.v) * guard_rate_gradient(s.v).template tail<Rates>();
      dh_x.noalias() = drate * fx.template bottomRows<Rates>();
      dh_u.noalias() = drate * fu.template bottomRows<Rates>();
    } else if (sub.rule == SubStep::kRemainder) {
      dh_x = -elapsed_x;
      dh_u = -elapsed_u;
    }
    linearised(s, sub.h, dh_x, dh_u);
    elapsed_x += dh_x;
    elapsed_u += dh_u;
  });
}

template <int A>
BasicState<A> BasicStepMap<A>::linearise(const State& x, const JointVector& tau, double dt,
                                         StepJacobian& fx, StepControlJacobian& fu) {
  return linearise_chain<kDofs>(
      x, dt, fx, fu, [&](State& s, double h, const StateRow& dh_x, const ControlRow& dh_u) {
        linearised_substep(s, tau, h, dh_x, dh_u, fx, fu);
      });
}

template <int A>
BasicState<A> BasicStepMap<A>::linearise_joints(const State& x, const JointVector& tau, double dt,
                                                JointStepJacobian& fz, JointControlJacobian& fu) {
  return linearise_chain<kJoints>(
      x, dt, fz, fu, [&](State& s, double h, const JointStateRow& dh_z, const ControlRow& dh_u) {
        linearised_joint_substep(s, tau, h, dh_z, dh_u, fz, fu);
      });
}

template <int A>
BasicVelocity<A> BasicStepMap<A>::acceleration(const State& x, const JointVector& tau, double h,
                                               const Velocity& external, bool base_held) {
  // evaluate_contact() also sets the dynamics' configuration for M and c.
  const ContactState& contact = evaluate_contact(x);
  Velocity rhs = external - dynamics_.inverse_dynamics(x.v, Velocity::Zero()) +
                 ContactModel::generalized_force(contact);
  rhs.template tail<kJoints>() += tau;
  iteration_matrix_ = dynamics_.mass_matrix();
  for (int i = 0; i < contact.count; ++i) {
    contact_.subtract_damping(i, contact, h, iteration_matrix_);
  }
  for (int j = 0; j < kJoints; ++j) {
    const double qdot = x.v[kBaseDofs + j];
    const JointStop stop =
        joint_stop(x.q[kFirstJoint + j], qdot, joint_lower_[j], joint_upper_[j], parameters_);
    rhs[kBaseDofs + j] += stop.torque - h * stop.stiffness * qdot;
    iteration_matrix_(kBaseDofs + j, kBaseDofs + j) += h * stop.damping + h * h * stop.stiffness;
  }
  Velocity a = Velocity::Zero();
  if (base_held) {
    joint_cholesky_.compute(iteration_matrix_.template bottomRightCorner<kJoints, kJoints>());
    a.template tail<kJoints>() = joint_cholesky_.solve(rhs.template tail<kJoints>());
  } else {
    cholesky_.compute(iteration_matrix_);
    a = cholesky_.solve(rhs);
  }
  return a;
}

template <int A>
void BasicStepMap<A>::substep(State& x, const JointVector& tau, double h, const Velocity& external,
                              bool base_held) {
  const Velocity a = acceleration(x, tau, h, external, base_held);
  if (base_held) {
    x.v.template tail<kJoints>() += h * a.template tail<kJoints>();
    x.q.template tail<kJoints>() += h * x.v.template tail<kJoints>();
    return;
  }
  x.v += h * a;
  move_configuration(x.q, x.v, h);
}

template <int A>
void BasicStepMap<A>::residual_jacobian(const State& x, const Velocity& a, double h, int first_q,
                                        int q_count, int first_v, int v_count) {
  if (residual_ == ResidualJacobian::kForwardDifferences) {
    differenced_residual_jacobian(x, a, h, first_q, q_count, first_v, v_count);
    return;
  }
  analytic_residual_jacobian(x, a, h);
  residual_jacobian_.leftCols(q_count) = analytic_jacobian_.middleCols(first_q, q_count);
  residual_jacobian_.middleCols(q_count, v_count) =
      analytic_jacobian_.middleCols(kConfigurationSize + first_v, v_count);
}

template <int A>
void BasicStepMap<A>::analytic_residual_jacobian(const State& x, const Velocity& a, double h) {
  // (L2)'s dynamics term -RNEA(q, v, a); kinematics_ is at x (acceleration()).
  derivatives_.inverse_dynamics_derivatives(kinematics_, x.v, a, inverse_);
  residual_by_tangent_ = -inverse_.dtau_dq;
  MassMatrix by_velocity = -inverse_.dtau_dv;
  // The contact terms J_i^T phi_i, phi_i = f_i + h D_i J_i a, and d(b - A a)/dh's
  // sum_i J_i^T D_i J_i a.
  damping_acceleration_.setZero();
  for (int k = 0; k < contact_state_.count; ++k) {
    const PointJacobian& J = contact_state_.jacobian[k];
    const Vector3 point_acceleration = J * a;
    damping_acceleration_.noalias() +=
        J.transpose() * (contact_state_.force_velocity[k] * point_acceleration);
    const PointForceSlopes slopes = contact_.force_slopes(
        k, contact_state_.position[k], contact_state_.velocity[k], point_acceleration, h);
    derivatives_.add_point_force_derivatives(contact_.point(k).body, contact_state_.position[k],
                                             slopes, residual_by_tangent_, by_velocity);
  }
  // The end stops' term T - h K v - (h B + h^2 K) a (stop_term), with T's slopes
  // dT/dq = -K - v dB/dq and dT/dv = -B; and their part of d(b - A a)/dh.
  for (int j = 0; j < kJoints; ++j) {
    const int i = kBaseDofs + j;
    const double v = x.v[i];
    const JointStop stop =
        joint_stop(x.q[kFirstJoint + j], v, joint_lower_[j], joint_upper_[j], parameters_);
    damping_acceleration_[i] -=
        (stop.damping + 2.0 * h * stop.stiffness) * a[i] + stop.stiffness * v;
    residual_by_tangent_(i, i) += -stop.stiffness - v * stop.damping_slope -
                                  h * v * stop.stiffness_slope -
                                  (h * stop.damping_slope + h * h * stop.stiffness_slope) * a[i];
    by_velocity(i, i) += -stop.damping - h * stop.stiffness;
  }
  // Tangent columns to q's: the world position p moves the torso by R^T dp in torso
  // coordinates; the quaternion by its body-frame rotation increment; joints are their own.
  const Eigen::Vector4d quaternion = x.q.template segment<4>(3);
  const Matrix3 rotation =
      Eigen::Quaterniond(quaternion[0], quaternion[1], quaternion[2], quaternion[3])
          .normalized()
          .toRotationMatrix();
  analytic_jacobian_.template leftCols<3>().noalias() =
      residual_by_tangent_.template middleCols<3>(3) * rotation.transpose();
  analytic_jacobian_.template middleCols<4>(3).noalias() =
      residual_by_tangent_.template leftCols<3>() * tangent_of_quaternion(quaternion);
  analytic_jacobian_.template middleCols<kJoints>(kFirstJoint) =
      residual_by_tangent_.template rightCols<kJoints>();
  analytic_jacobian_.template rightCols<kDofs>() = by_velocity;
}

template <int A>
void BasicStepMap<A>::differenced_residual_jacobian(const State& x, const Velocity& a, double h,
                                                    int first_q, int q_count, int first_v,
                                                    int v_count) {
  const int points = contact_state_.count;
  damping_acceleration_.setZero();
  for (int k = 0; k < points; ++k) {
    const PointJacobian& J = contact_state_.jacobian[k];
    damping_acceleration_.noalias() += J.transpose() * (contact_state_.force_velocity[k] * (J * a));
    contact_terms_[k] =
        contact_term(J, contact_state_.force[k], contact_state_.force_velocity[k], a, h);
  }
  // The end stops' d(b - A a)/dh: -(B + 2 h K) a - K qdot per joint; and their nominal part
  // of r, which every joint column below differences against.
  JointVector nominal_stop;
  for (int j = 0; j < kJoints; ++j) {
    const int i = kBaseDofs + j;
    const JointStop stop =
        joint_stop(x.q[kFirstJoint + j], x.v[i], joint_lower_[j], joint_upper_[j], parameters_);
    damping_acceleration_[i] -=
        (stop.damping + 2.0 * h * stop.stiffness) * a[i] + stop.stiffness * x.v[i];
    nominal_stop[j] = stop_term(j, x.q[kFirstJoint + j], x.v[i], a[i], h);
  }
  const Velocity dynamics_term = dynamics_.inverse_dynamics(x.v, a, nominal_passes_);

  // Columns by forward differences, r(x + d e_i) - r(x) over d. First v's, while
  // contact_state_ and the dynamics are at x's q: J is kept, and only the points carried by
  // the entry's joint change velocity; the RNEA is redone on that joint's subtree (all of it
  // for the base).
  for (int j = 0; j < v_count; ++j) {
    const int i = first_v + j;
    const double d = forward_step(x.v[i]);
    Velocity v = x.v;
    v[i] += d;
    const int moved = moved_body_of_velocity(i);
    Velocity change =
        dynamics_term - dynamics_.inverse_dynamics_in_subtree(moved, v, a, nominal_passes_);
    for (int k = 0; k < points; ++k) {
      if (!contact_.moves_with(k, moved)) continue;
      const PointJacobian& J = contact_state_.jacobian[k];
      Matrix3 dforce;
      const Vector3 force = contact_.force_moving(k, contact_state_, J * v, dforce);
      change += contact_term(J, force, dforce, a, h) - contact_terms_[k];
    }
    if (i >= kBaseDofs) {
      const int joint = i - kBaseDofs;
      change[i] += stop_term(joint, x.q[kFirstJoint + joint], v[i], a[i], h) - nominal_stop[joint];
    }
    residual_jacobian_.col(q_count + j) = change / d;
  }
  // Then q's. A base translation (q's first three entries) moves every point by the same
  // offset and changes neither M, c (gravity is uniform) nor J; it changes the forces that
  // read the coordinate moved only (the others' terms are exactly as at x: their change is 0).
  // A joint angle moves its subtree: its transform, the kinematics and the RNEA are redone
  // there, and the points it carries evaluated anew (into contact_state_, so after the
  // translations), then the angle is put back. The quaternion's entries come last: they move
  // everything (from the base's pose set anew, which they leave moved).
  const auto column = [&](int j) {
    const int i = first_q + j;
    const double d = forward_step(x.q[i]);
    Velocity change = Velocity::Zero();
    if (i < 3) {
      for (int k = 0; k < points; ++k) {
        if (!ContactModel::force_reads_position(k, i)) continue;
        Matrix3 dforce;
        const Vector3 force =
            contact_.force_at(k, contact_state_.position[k] + d * Vector3::Unit(i),
                              contact_state_.velocity[k], dforce);
        change += contact_term(contact_state_.jacobian[k], force, dforce, a, h) - contact_terms_[k];
      }
      residual_jacobian_.col(j) = change / d;
      return;
    }
    const int moved = moved_body_of_configuration(i);
    const BasicKinematics<A>* kinematics = &kinematics_;
    if (i >= kFirstJoint) {
      dynamics_.set_joint_angle(moved, x.q[i] + d);
      moved_kinematics_ = kinematics_;
      dynamics_.kinematics_in_subtree(moved, x.v, moved_kinematics_);
      kinematics = &moved_kinematics_;
      change =
          dynamics_term - dynamics_.inverse_dynamics_in_subtree(moved, x.v, a, nominal_passes_);
    } else {
      Configuration q = x.q;
      q[i] += d;
      dynamics_.set_base_pose(q);
      dynamics_.kinematics(x.v, kinematics_);
      change = dynamics_term - dynamics_.inverse_dynamics(x.v, a);
    }
    for (int k = 0; k < points; ++k) {
      if (!contact_.moves_with(k, moved)) continue;
      contact_.evaluate_point(k, *kinematics, x.v, contact_state_);
      change += contact_term(contact_state_.jacobian[k], contact_state_.force[k],
                             contact_state_.force_velocity[k], a, h) -
                contact_terms_[k];
    }
    if (i >= kFirstJoint) {
      const int joint = i - kFirstJoint, row = kBaseDofs + joint;
      change[row] += stop_term(joint, x.q[i] + d, x.v[row], a[row], h) - nominal_stop[joint];
      dynamics_.set_joint_angle(moved, x.q[i]);
    }
    residual_jacobian_.col(j) = change / d;
  };
  for (int j = 0; j < q_count; ++j) {
    if (first_q + j < 3 || first_q + j >= kFirstJoint) column(j);
  }
  for (int j = 0; j < q_count; ++j) {
    if (first_q + j >= 3 && first_q + j < kFirstJoint) column(j);
  }
}

template <int A>
void BasicStepMap<A>::linearised_substep(State& x, const JointVector& tau, double h,
                                         const StateRow& dh_x, const ControlRow& dh_u,
                                         StepJacobian& fx, StepControlJacobian& fu) {
  const Velocity a = acceleration(x, tau, h, Velocity::Zero(), false);
  residual_jacobian(x, a, h, 0, kConfigurationSize, 0, kDofs);
  // (L1) and the derivative of v+ = v + h a with A = M - h sum J^T D J in h:
  // [dv+/dx, dv+/dtau, dv+/dh] = h A^-1 [dr/dx, S^T, sum J^T D J a] + [(0 1), 0, a].
  constexpr int kColumns = kStateSize + kJoints + 1;
  Eigen::Matrix<double, kDofs, kColumns> velocity;
  velocity.template leftCols<kStateSize>() = residual_jacobian_;
  velocity.template middleCols<kJoints>(kStateSize).setZero();
  velocity.template block<kJoints, kJoints>(kBaseDofs, kStateSize).setIdentity();
  velocity.col(kColumns - 1) = damping_acceleration_;
  cholesky_.solveInPlace(velocity);
  velocity *= h;
  velocity.template middleCols<kDofs>(kConfigurationSize) += MassMatrix::Identity();
  velocity.col(kColumns - 1) += a;

  const Configuration q = x.q;
  x.v += h * a;
  move_configuration(x.q, x.v, h);
  // (S2)'s derivatives: q+ = q + G (dq, dv+, dh) with G the identity in p and the joints plus
  // dp+/dquaternion and dquaternion+/dquaternion (rows of p and the quaternion), h R on v_o+,
  // dquaternion+/domega+ and h on the joint rates. The quaternion's and omega+'s by central
  // differences of (S2) alone; (S2) depends on h and v+ through h v+ only, so at fixed v+
  // dq+/dh = (dq+/dv+) v+ / h.
  Eigen::Matrix<double, 7, 4> by_quaternion;  // d(p+, quaternion+)/dquaternion - identity
  for (int k = 0; k < 4; ++k) {
    const double d = detail::fd_step(q[3 + k], 1.0 / 3.0);
    Configuration plus = q, minus = q;
    plus[3 + k] += d;
    minus[3 + k] -= d;
    move_configuration(plus, x.v, h);
    move_configuration(minus, x.v, h);
    by_quaternion.col(k) = (plus - minus).template head<7>() / (2.0 * d);
  }
  by_quaternion.template bottomRows<4>() -= Eigen::Matrix4d::Identity();
  Eigen::Matrix<double, 4, 3> by_omega;  // dquaternion+/domega+
  for (int k = 0; k < 3; ++k) {
    const double d = detail::fd_step(x.v[k], 1.0 / 3.0);
    Velocity v_plus = x.v, v_minus = x.v;
    v_plus[k] += d;
    v_minus[k] -= d;
    Configuration plus = q, minus = q;
    move_configuration(plus, v_plus, h);
    move_configuration(minus, v_minus, h);
    by_omega.col(k) = (plus - minus).template segment<4>(3) / (2.0 * d);
  }
  const Eigen::Quaterniond orientation(q[3], q[4], q[5], q[6]);
  const Matrix3 by_velocity = h * orientation.normalized().toRotationMatrix();  // dp+/dv_o+
  Configuration by_length;  // dq+/dh at fixed v+
  by_length.template head<3>() = by_velocity * x.v.template segment<3>(3) / h;
  by_length.template segment<4>(3) = by_omega * x.v.template head<3>() / h;
  by_length.template tail<kJoints>() = x.v.template tail<kJoints>();

  // The chain rule, F <- dx+/dx F + dx+/dh dh (+ dx+/dtau for fu), with F the derivative of
  // the sub-step's start x in the step's start (fx) or torques (fu): v+'s rows by (L1) first,
  // then q+'s from them by (S2)'s sparse G.
  Eigen::Matrix<double, kDofs, kJoints> fu_velocity =
      velocity.template middleCols<kJoints>(kStateSize);
  fu_velocity.noalias() += velocity.template leftCols<kStateSize>() * fu;
  fu_velocity.noalias() += velocity.col(kColumns - 1) * dh_u;
  Eigen::Matrix<double, kDofs, kStateSize> fx_velocity;
  fx_velocity.noalias() = velocity.template leftCols<kStateSize>() * fx;
  fx_velocity.noalias() += velocity.col(kColumns - 1) * dh_x;
  const auto chain = [&](auto& F, const auto& velocity_rows, const auto& dh) {
    F.template topRows<7>() += (by_quaternion * F.template middleRows<4>(3)).eval();
    F.template bottomRows<kDofs>() = velocity_rows;
    F.template topRows<3>().noalias() += by_velocity * velocity_rows.template middleRows<3>(3);
    F.template middleRows<4>(3).noalias() += by_omega * velocity_rows.template topRows<3>();
    F.template middleRows<kJoints>(kFirstJoint) += h * velocity_rows.template bottomRows<kJoints>();
    F.template topRows<kConfigurationSize>().noalias() += by_length * dh;
  };
  chain(fu, fu_velocity, dh_u);
  chain(fx, fx_velocity, dh_x);
}

template <int A>
void BasicStepMap<A>::linearised_joint_substep(State& x, const JointVector& tau, double h,
                                               const JointStateRow& dh_z, const ControlRow& dh_u,
                                               JointStepJacobian& fz, JointControlJacobian& fu) {
  const Velocity a = acceleration(x, tau, h, Velocity::Zero(), true);
  residual_jacobian(x, a, h, kFirstJoint, kJoints, kBaseDofs, kJoints);
  // (L1) on the leg rows, as in linearised_substep with A22 for A.
  using LegMatrix = Eigen::Matrix<double, kJoints, kJoints>;
  constexpr int kColumns = kJointStateSize + kJoints + 1;
  Eigen::Matrix<double, kJoints, kColumns> velocity;
  velocity.template leftCols<kJointStateSize>() =
      residual_jacobian_.template bottomLeftCorner<kJoints, kJointStateSize>();
  velocity.template middleCols<kJoints>(kJointStateSize).setIdentity();
  velocity.col(kColumns - 1) = damping_acceleration_.template tail<kJoints>();
  joint_cholesky_.solveInPlace(velocity);
  velocity *= h;
  velocity.template middleCols<kJoints>(kJoints) += LegMatrix::Identity();
  velocity.col(kColumns - 1) += a.template tail<kJoints>();

  x.v.template tail<kJoints>() += h * a.template tail<kJoints>();
  x.q.template tail<kJoints>() += h * x.v.template tail<kJoints>();
  // z+ = (q_leg + h v_leg+, v_leg+).
  JointStepJacobian phi;
  phi.template topRows<kJoints>() = h * velocity.template leftCols<kJointStateSize>();
  phi.template topLeftCorner<kJoints, kJoints>() += LegMatrix::Identity();
  phi.template bottomRows<kJoints>() = velocity.template leftCols<kJointStateSize>();
  JointControlJacobian phi_u;
  phi_u.template topRows<kJoints>() = h * velocity.template middleCols<kJoints>(kJointStateSize);
  phi_u.template bottomRows<kJoints>() = velocity.template middleCols<kJoints>(kJointStateSize);
  Eigen::Matrix<double, kJointStateSize, 1> dz_dh;
  dz_dh.template head<kJoints>() = x.v.template tail<kJoints>() + h * velocity.col(kColumns - 1);
  dz_dh.template tail<kJoints>() = velocity.col(kColumns - 1);
  fu = phi * fu + phi_u + dz_dh * dh_u;
  fz = phi * fz + dz_dh * dh_z;
}

}  // namespace hmpc::humanoid
