#include "hmpc/humanoid/step.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace hmpc::humanoid {

StepMap::StepMap(const Model& model, const Parameters& parameters, const ContactParameters& contact,
                 double max_substep)
    : dynamics_(model), contact_(model, parameters, contact), max_substep_(max_substep) {}

const ContactState& StepMap::evaluate_contact(const State& x) {
  dynamics_.kinematics(x.q, x.v, kinematics_);
  contact_.evaluate(kinematics_, x.v, contact_state_);
  return contact_state_;
}

State StepMap::step(const State& x, const JointVector& tau, double dt, const Velocity& external) {
  return advance(x, tau, dt, external, false);
}

State StepMap::step_legs(const State& x, const JointVector& tau, double dt) {
  return advance(x, tau, dt, Velocity::Zero(), true);
}

State StepMap::advance(const State& x, const JointVector& tau, double dt, const Velocity& external,
                       bool base_held) {
  const int substeps = std::max(1, static_cast<int>(std::ceil(dt / max_substep_ - 1e-9)));
  const double nominal = dt / substeps;
  State next = x;
  double remaining = dt;
  while (remaining > 0.0) {
    // The rotation guard (step.hpp): shorten the sub-step so no body turns more than
    // kMaxRotation relative to its parent or the world; a non-finite rate keeps `nominal`.
    const double rate = std::max(next.v.head<3>().norm(), next.v.tail<kJoints>().cwiseAbs().maxCoeff());
    double h = nominal;
    if (rate * h > kMaxRotation) h = std::max(kMaxRotation / rate, nominal / kMaxRefinement);
    // Finish dt exactly, without leaving a sliver for a last, tiny sub-step.
    if (remaining < 1.5 * h) h = remaining;
    substep(next, tau, h, external, base_held);
    remaining -= h;
  }
  return next;
}

void StepMap::substep(State& x, const JointVector& tau, double h, const Velocity& external,
                      bool base_held) {
  const ContactState& contact = evaluate_contact(x);
  // (S1). bias_forces and mass_matrix both refresh the dynamics' transforms from q.
  Velocity rhs = external - dynamics_.bias_forces(x.q, x.v) + ContactModel::generalized_force(contact);
  rhs.tail<kJoints>() += tau;
  iteration_matrix_ = dynamics_.mass_matrix(x.q);
  for (int i = 0; i < contact.count; ++i) {
    iteration_matrix_.noalias() -=
        h * contact.jacobian[i].transpose() * contact.force_velocity[i] * contact.jacobian[i];
  }
  if (base_held) {
    leg_cholesky_.compute(iteration_matrix_.bottomRightCorner<kJoints, kJoints>());
    x.v.tail<kJoints>() += h * leg_cholesky_.solve(rhs.tail<kJoints>());
    x.q.tail<kJoints>() += h * x.v.tail<kJoints>();
    return;
  }
  cholesky_.compute(iteration_matrix_);
  x.v += h * cholesky_.solve(rhs);

  // (S2).
  const Eigen::Quaterniond orientation(x.q[3], x.q[4], x.q[5], x.q[6]);
  x.q.head<3>() += h * (orientation.normalized().toRotationMatrix() * x.v.segment<3>(3));
  // exp of the rotation vector theta = h omega: (cos(|theta|/2), sin(|theta|/2) theta/|theta|);
  // sin(a)/a by its Taylor series near 0, where the quotient loses all digits.
  const Vector3 theta = h * x.v.head<3>();
  const double half_angle = 0.5 * theta.norm();
  const double sinc = half_angle < 1e-4 ? 1.0 - half_angle * half_angle / 6.0
                                        : std::sin(half_angle) / half_angle;
  const Vector3 axis_part = 0.5 * sinc * theta;
  const Eigen::Quaterniond increment(std::cos(half_angle), axis_part.x(), axis_part.y(), axis_part.z());
  const Eigen::Quaterniond rotated = (orientation * increment).normalized();
  x.q[3] = rotated.w();
  x.q[4] = rotated.x();
  x.q[5] = rotated.y();
  x.q[6] = rotated.z();
  x.q.tail<kJoints>() += h * x.v.tail<kJoints>();
}

}  // namespace hmpc::humanoid
