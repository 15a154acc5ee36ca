#include "hmpc/humanoid/problem.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "hmpc/humanoid/stance.hpp"
#include "hmpc/solver/finite_difference.hpp"

namespace hmpc::humanoid {
namespace {

// Angle of the torso-frame vector d (pointing down the leg) from the torso's -z axis towards
// its `axis` (0: x, sagittal plane; 1: y, frontal plane).
double leg_angle(const Vector3& d, int axis) { return std::atan2(d[axis], -d.z()); }

}  // namespace

template <int A>
BasicStateCost<A>::BasicStateCost(const Motion& motion, const State& initial,
                                  const ProblemConfig& config)
    : motion_(motion), base_point_(config.base_point), dynamics_(BasicModel<A>(config.parameters)) {
  if (motion.reach.active != (A == 1)) {
    throw std::invalid_argument(motion.reach.active
                                    ? "humanoid: a reaching motion needs the robot with an arm"
                                    : "humanoid: the robot with an arm runs reaching motions only");
  }
  const BasicContactModel<A> contact(dynamics_.model(), config.parameters, config.contact);
  for (int leg = 0; leg < 2; ++leg) {
    // ContactModel's sole corners: per foot two heel corners, then two toe corners.
    const auto corner = [&](int k) { return contact.point(leg * kFootPoints + k).local; };
    sole_points_[2 * leg] = 0.5 * (corner(0) + corner(1));
    sole_points_[2 * leg + 1] = 0.5 * (corner(2) + corner(3));
  }
  const BaseFeatures f = features(initial);
  beta_left_init_ = f.beta_left;
  beta_right_init_ = f.beta_right;
  position_init_ = f.position.head<2>();
}

template <int A>
void BasicStateCost<A>::set_motion(const Motion& motion) {
  if (motion.reach.active != motion_.reach.active || motion.chair != motion_.chair ||
      (motion.chair &&
       (motion.seat_height != motion_.seat_height || motion.seat_x_min != motion_.seat_x_min ||
        motion.seat_x_max != motion_.seat_x_max))) {
    throw std::invalid_argument("humanoid: a new motion for a cost must keep its chair and reach");
  }
  motion_ = motion;
}

template <int A>
BaseFeatures BasicStateCost<A>::features(const State& x) const {
  using Model = BasicModel<A>;
  BasicKinematics<A> kin;
  dynamics_.kinematics(x.q, x.v, kin);
  const Matrix3& R = kin.rotation[0];
  BaseFeatures f;
  f.quaternion = x.q.template segment<4>(3).normalized();
  f.position = kin.position[0] + R * base_point_;
  const Vector3 omega = x.v.template head<3>();
  f.velocity = R * (x.v.template segment<3>(3) + omega.cross(base_point_));
  f.angular_velocity = R * omega;
  const auto ankle = [&](int leg) {
    return Vector3(R.transpose() * (kin.position[Model::body_of(leg, kAnkle)] - f.position));
  };
  const Vector3 left = ankle(0), right = ankle(1);
  f.alpha_left = -leg_angle(left, 0);  // positive backward (see problem.hpp)
  f.alpha_right = leg_angle(right, 0);
  f.beta_left = leg_angle(left, 1);
  f.beta_right = leg_angle(right, 1);
  for (int k = 0; k < 4; ++k) {
    const int foot = Model::body_of(k / 2, kAnkle);
    f.sole_height[k] = (kin.position[foot] + kin.rotation[foot] * sole_points_[k]).z();
  }
  if constexpr (A == 1) f.hand = hand_position(dynamics_.model(), kin);
  return f;
}

template <int A>
typename BasicStateCost<A>::CostResidual BasicStateCost<A>::residual(const StateVector& x,
                                                                     double time) const {
  const BaseFeatures f = features(to_state<A>(x));
  const Phase& target = motion_.phase_at(time);
  const CostWeights& w = motion_.weights;
  CostResidual r;
  // Eq. 4.25; W_attitude = diag(w_q1, w_q2, w_q3, w_q4) on (x, y, z; w).
  const Eigen::Vector4d dq = f.quaternion - attitude_quaternion(target.attitude);
  r.template segment<3>(0) = w.attitude.head<3>().cwiseSqrt().cwiseProduct(dq.tail<3>());
  r[3] = std::sqrt(w.attitude[3]) * dq[0];
  r[4] = std::sqrt(w.height) * (f.position.z() - target.height_at(time));  // Eq. 4.26
  r.template segment<3>(5) =
      w.velocity.cwiseSqrt().cwiseProduct(f.velocity - target.velocity_at(time));  // Eq. 4.27
  r[8] = std::sqrt(w.alpha) * (f.alpha_right - f.alpha_left);                      // Eq. 4.28
  r[9] = std::sqrt(w.beta) * (f.beta_right - beta_right_init_);                    // Eq. 4.29
  r[10] = std::sqrt(w.beta) * (f.beta_left - beta_left_init_);
  r.template segment<3>(11) =
      w.angular_velocity.cwiseSqrt().cwiseProduct(f.angular_velocity);  // Eq. 4.30
  for (int k = 0; k < 4; ++k) {  // foot heights, heel and toe of each sole (Gait, motion.hpp)
    r[14 + k] = std::sqrt(w.foot) * (f.sole_height[k] - motion_.gait.foot_height(time, k / 2));
  }
  for (int j = 0; j < 2 * kJointsPerLeg; ++j) {  // joint tracking (CostWeights::joint)
    r[18 + j] = std::sqrt(w.joint) * (x[7 + j] - target.joints[j]);  // q = (p, quaternion, joints)
  }
  r.template segment<2>(26) =  // the initial hip position (Sec. 2.7.3)
      std::sqrt(w.position) * (f.position.template head<2>() - position_init_);
  r.template segment<2 * kJointsPerLeg>(28) =  // the joints' rates (Sec. 2.7.3)
      std::sqrt(w.joint_velocity) *
      x.template segment<2 * kJointsPerLeg>(Dimensions<A>::kConfigurationSize + kBaseDofs);
  if constexpr (A == 1) {  // Eq. 2.53, from the reach's start
    const Reach& reach = motion_.reach;
    const double weight = time >= reach.start ? reach.weight : 0.0;
    r.template tail<3>() = std::sqrt(weight) * (f.hand - reach.target);
  }
  return r;
}

template <int A>
void BasicStateCost<A>::residual_jacobian(const StateVector& x, double time,
                                          ResidualJacobian& J) const {
  // Central differences (finite_difference.hpp's step) in the entries r depends on: the base
  // height, quaternion and joint angles, and the torso's velocities. The horizontal base
  // position enters the held-position rows alone (it cancels from the leg angles), with the
  // base point moving as the torso origin does, and the leg joints' rates their own rows
  // alone: those columns are exact. The arm joint's rate does not enter.
  J.setZero();
  J(26, 0) = J(27, 1) = std::sqrt(motion_.weights.position);
  for (int j = 0; j < 2 * kJointsPerLeg; ++j) {
    J(28 + j, Dimensions<A>::kConfigurationSize + kBaseDofs + j) =
        std::sqrt(motion_.weights.joint_velocity);
  }
  StateVector xp = x;
  for (int i = 2; i < Dimensions<A>::kConfigurationSize + kBaseDofs; ++i) {
    const double h = detail::fd_step(x[i], 1.0 / 3.0);
    xp[i] = x[i] + h;
    const CostResidual plus = residual(xp, time);
    xp[i] = x[i] - h;
    const CostResidual minus = residual(xp, time);
    xp[i] = x[i];
    J.col(i) = (plus - minus) / (2.0 * h);
  }
}

template <int A>
void BasicStateCost<A>::derivatives(const StateVector& x, double time, StateVector& lx,
                                    StateMatrix& lxx) const {
  ResidualJacobian J;
  residual_jacobian(x, time, J);
  const CostResidual r = residual(x, time);
  lx.noalias() = 2.0 * J.transpose() * r;
  lxx.noalias() = 2.0 * J.transpose() * J;
}

template <int A>
BasicJointVector<A> BasicStateCost<A>::control_weights() const {
  JointVector w;
  for (int leg = 0; leg < 2; ++leg)
    for (int j = 0; j < kJointsPerLeg; ++j) w[leg * kJointsPerLeg + j] = motion_.weights.control[j];
  if constexpr (A == 1) w[Dimensions<A>::kArmJoint] = motion_.reach.control;
  return w;
}

template <int A>
double BasicStateCost<A>::control_cost(const JointVector& tau) const {
  return tau.cwiseAbs2().dot(control_weights());
}

ContactParameters contact_for(const Motion& motion, ContactParameters contact) {
  contact.chair = motion.chair;
  if (motion.chair) {
    contact.seat_height = motion.seat_height;
    contact.seat_x_min = motion.seat_x_min;
    contact.seat_x_max = motion.seat_x_max;
  }
  return contact;
}

ProblemConfig model_config(const Motion& motion, ProblemConfig config) {
  config.contact = contact_for(motion, config.contact);
  if (motion.model_substep > 0.0) config.max_substep = motion.model_substep;
  if (config.model_slip_velocity > 0.0) config.contact.slip_velocity = config.model_slip_velocity;
  return config;
}

template <int A>
BasicState<A> standing_state(const ProblemConfig& config, double height) {
  State biped = standing_stance(config.parameters, config.contact, config.base_point, height);
  if constexpr (A == 0) {
    return biped;
  } else {
    // The arm hangs: the biped's stance (model.hpp's arm is the biped's right arm on a joint).
    BasicState<A> x;
    x.q << biped.q, 0.0;
    x.v << biped.v, 0.0;
    return x;
  }
}

template State standing_state<0>(const ProblemConfig&, double);
template BasicState<1> standing_state<1>(const ProblemConfig&, double);

template class BasicStateCost<0>;
template class BasicStateCost<1>;

}  // namespace hmpc::humanoid
