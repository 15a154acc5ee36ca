// The forearm's optimal control problems for the iLQR core (thesis Ch. 3):
//   ForearmProblem       - Eq. 3.1 discretised with step h, cost Eq. 3.3; the Fine and Coarse
//                          strategies and the first stage of the Two-stage MPC.
//   ForearmFastSubsystem - Eq. 3.2: P frozen at the coarse plan, deviations of theta and
//                          theta' as state, only the motor deviation nu acts; the second stage.
//
// Discretisation: semi-implicit (symplectic) Euler, theta'_{k+1} = theta'_k + h theta''_k,
// theta_{k+1} = theta_k + h theta'_{k+1}. Unlike the explicit Euler of Eq. 2.1 it stays stable
// for the PAM's joint stiffness at the 40 ms coarse step (omega h ~ 0.6), and its Jacobians
// are still closed-form.
#pragma once

#include <array>

#include "hmpc/models/forearm.hpp"
#include "hmpc/models/forearm_target.hpp"
#include "hmpc/solver/problem.hpp"

namespace hmpc::forearm {

// Immediate cost of Eq. 3.3a without its voltage term (which differs between the stages),
// with gradient and Hessian in (theta, P) and the motor torque's part in v_m.
template <typename Scalar>
struct TrackingCost {
  Scalar value = 0;
  Scalar d_theta = 0, d_pressure = 0, d_v_m = 0;
  Scalar d_theta_theta = 0, d_theta_pressure = 0, d_pressure_pressure = 0, d_v_m_v_m = 0;
};

// Offset-free control (our addition to the thesis's method): the MPC's model carries the
// disturbance torque d its board estimates (forearm_disturbance.hpp), and Eq. 3.3a's PAM torque
// penalty counts only the torque beyond what holds the arm at rest at theta against gravity and
// d. With the thesis's w_tau tau_p^2, resting on a target costs w_tau tau_hold^2, whose slope
// in theta the optimum trades against w_theta's: the arm settles short of (or past) its target,
// about w_tau tau_hold tau_hold' / w_theta, 0.9 deg at 30 deg with Sec. 3.3's weights. Off: the
// thesis's Eq. 3.3 and Eq. 3.1 exactly.
template <typename Scalar>
struct OffsetFree {
  bool enabled = false;
  Scalar disturbance = 0;  // N·m, the estimate, held over the horizon
};

// w_theta (theta - theta_d)^2 + w_P smin(P - P0, 0)^2 [+ w_tau (r_p^2 + tau_m^2)], with
// r_p = tau_p (the thesis) or, offset-free, tau_p - tau_hold(theta, d).
// The torque term's Hessian keeps only its Gauss-Newton part 2 w_tau grad(r) grad(r)', which
// stays positive semi-definite (the r * Hessian(r) part is indefinite in theta, P).
template <typename Scalar>
TrackingCost<Scalar> tracking_cost(const Parameters<Scalar>& p, const CostWeights<Scalar>& w,
                                   Scalar theta, Scalar theta_d, Scalar pressure, Scalar v_m,
                                   bool with_torque,
                                   const OffsetFree<Scalar>& offset_free = OffsetFree<Scalar>{}) {
  TrackingCost<Scalar> c;
  const Scalar e = theta - theta_d;
  const SmoothMin<Scalar> s = smin_zero(pressure - w.P0, w.gamma);
  c.value = w.w_theta * e * e + w.w_P * s.value * s.value;
  c.d_theta = Scalar(2) * w.w_theta * e;
  c.d_theta_theta = Scalar(2) * w.w_theta;
  c.d_pressure = Scalar(2) * w.w_P * s.value * s.d;
  c.d_pressure_pressure = Scalar(2) * w.w_P * (s.d * s.d + s.value * s.dd);
  if (with_torque) {
    const PamTorque<Scalar> tp = pam_torque(p, pressure, theta);
    Scalar r = tp.tau, r_theta = tp.d_theta;
    if (offset_free.enabled) {
      const HoldingTorque<Scalar> hold = holding_torque(p, theta, offset_free.disturbance);
      r -= hold.tau;
      r_theta -= hold.d_theta;
    }
    const Scalar tm = p.motor_gain * v_m;
    c.value += w.w_tau * (r * r + tm * tm);
    c.d_theta += Scalar(2) * w.w_tau * r * r_theta;
    c.d_pressure += Scalar(2) * w.w_tau * r * tp.d_pressure;
    c.d_v_m = Scalar(2) * w.w_tau * tm * p.motor_gain;
    c.d_theta_theta += Scalar(2) * w.w_tau * r_theta * r_theta;
    c.d_theta_pressure = Scalar(2) * w.w_tau * r_theta * tp.d_pressure;
    c.d_pressure_pressure += Scalar(2) * w.w_tau * tp.d_pressure * tp.d_pressure;
    c.d_v_m_v_m = Scalar(2) * w.w_tau * p.motor_gain * p.motor_gain;
  }
  return c;
}

// Terminal rate term (our addition, off by default): w_theta T_v^2 (theta'_N - theta_d'(t_N))^2
// beside Eq. 3.3b. Eq. 3.3b prices the angle at the horizon's end but not the rate: a plan may
// end on target while moving away from it, an error that grows as (theta' - theta_d') T_v over
// the next T_v seconds, past the horizon. The term prices that error as w_theta prices an angle
// error. T_v = 0 is the thesis's cost.
template <typename Scalar>
struct TerminalRateTerm {
  Scalar value = 0, d_rate = 0, d_rate_rate = 0;
};

template <typename Scalar>
TerminalRateTerm<Scalar> terminal_rate_term(const CostWeights<Scalar>& w, Scalar t_v,
                                            Scalar theta_dot, Scalar theta_d_dot) {
  const Scalar weight = w.w_theta * t_v * t_v;
  const Scalar e = theta_dot - theta_d_dot;
  return {weight * e * e, Scalar(2) * weight * e, Scalar(2) * weight};
}

// One symplectic Euler step of the joint with its Jacobian in (theta, theta', P, v_m).
template <typename Scalar>
struct JointStep {
  Scalar theta, theta_dot;
  Eigen::Matrix<Scalar, 2, 4> jacobian;  // rows (theta+, theta'+), cols (theta, theta', P, v_m)
};

template <typename Scalar>
JointStep<Scalar> joint_step(const Parameters<Scalar>& p, Scalar h, Scalar theta, Scalar theta_dot,
                             Scalar pressure, Scalar v_m, Scalar disturbance = Scalar(0)) {
  const JointAcceleration<Scalar> a =
      joint_acceleration(p, theta, theta_dot, pressure, v_m, disturbance);
  JointStep<Scalar> s;
  s.theta_dot = theta_dot + h * a.value;
  s.theta = theta + h * s.theta_dot;
  const Eigen::Matrix<Scalar, 1, 4> dvel(h * a.d_theta, Scalar(1) + h * a.d_theta_dot,
                                         h * a.d_pressure, h * a.d_v_m);
  s.jacobian.row(1) = dvel;
  s.jacobian.row(0) = h * dvel;
  s.jacobian(0, 0) += Scalar(1);
  return s;
}

// Full model: x = [theta, theta', P], u = [v_m, v_p], step h, horizon starting at start_time.
template <typename Scalar>
class ForearmProblem : public ProblemBase<ForearmProblem<Scalar>, Scalar, 3, 2> {
  using Base = ProblemBase<ForearmProblem<Scalar>, Scalar, 3, 2>;

 public:
  using typename Base::Control;
  using typename Base::ControlJacobian;
  using typename Base::RunningDerivatives;
  using typename Base::State;
  using typename Base::StateJacobian;
  using typename Base::TerminalDerivatives;

  ForearmProblem(const Parameters<Scalar>& parameters, const CostWeights<Scalar>& weights,
                 Scalar step, const TargetTrajectory<Scalar>* target)
      : p_(parameters), w_(weights), h_(step), target_(target) {}

  Scalar step() const { return h_; }
  void set_start_time(Scalar t) { start_time_ = t; }
  Scalar start_time() const { return start_time_; }
  void set_target(const TargetTrajectory<Scalar>* target) { target_ = target; }
  // PAM-only control (Fig. 3.8b): the motor input is held at zero.
  void set_motor_enabled(bool enabled) { motor_enabled_ = enabled; }
  void set_weights(const CostWeights<Scalar>& w) { w_ = w; }
  const CostWeights<Scalar>& weights() const { return w_; }
  const Parameters<Scalar>& parameters() const { return p_; }
  void set_offset_free(const OffsetFree<Scalar>& o) { offset_free_ = o; }
  const OffsetFree<Scalar>& offset_free() const { return offset_free_; }
  void set_terminal_rate_time(Scalar t_v) { terminal_rate_time_ = t_v; }
  Scalar target_angle(int k) const { return target_->angle(time(k)); }

  State dynamics(const State& x, const Control& u, int) const {
    const JointStep<Scalar> s = joint_step(p_, h_, x(0), x(1), x(2), u(0), disturbance());
    return State(s.theta, s.theta_dot, x(2) + h_ * pressure_rate(p_, x(2), u(1)));
  }

  void dynamics_derivatives(const State& x, const Control& u, int, StateJacobian& fx,
                            ControlJacobian& fu) const {
    const JointStep<Scalar> s = joint_step(p_, h_, x(0), x(1), x(2), u(0), disturbance());
    fx.template topRows<2>() = s.jacobian.template leftCols<3>();
    fx.row(2) << Scalar(0), Scalar(0), Scalar(1) - h_ * p_.k_vp / p_.T_p;
    fu.template topRows<2>() << s.jacobian.col(3), Eigen::Matrix<Scalar, 2, 1>::Zero();
    fu.row(2) << Scalar(0), h_ / p_.T_p;
  }

  // Eq. 3.3a.
  Scalar running_cost(const State& x, const Control& u, int k) const {
    return tracking_cost(p_, w_, x(0), target_angle(k), x(2), u(0), true, offset_free_).value +
           w_.w_v * u.squaredNorm();
  }
  // Eq. 3.3b, at the end of the horizon (k = N), with the terminal rate term when enabled.
  Scalar terminal_cost(const State& x, int k) const {
    return tracking_cost(p_, w_, x(0), target_angle(k), x(2), Scalar(0), false).value +
           rate_term(x, k).value;
  }

  void running_cost_derivatives(const State& x, const Control& u, int k,
                                RunningDerivatives& d) const {
    const TrackingCost<Scalar> c =
        tracking_cost(p_, w_, x(0), target_angle(k), x(2), u(0), true, offset_free_);
    d.lx << c.d_theta, Scalar(0), c.d_pressure;
    d.lxx << c.d_theta_theta, Scalar(0), c.d_theta_pressure, Scalar(0), Scalar(0), Scalar(0),
        c.d_theta_pressure, Scalar(0), c.d_pressure_pressure;
    d.lu << c.d_v_m + Scalar(2) * w_.w_v * u(0), Scalar(2) * w_.w_v * u(1);
    d.luu << c.d_v_m_v_m + Scalar(2) * w_.w_v, Scalar(0), Scalar(0), Scalar(2) * w_.w_v;
    d.lux.setZero();
  }
  void terminal_cost_derivatives(const State& x, int k, TerminalDerivatives& d) const {
    const TrackingCost<Scalar> c =
        tracking_cost(p_, w_, x(0), target_angle(k), x(2), Scalar(0), false);
    const TerminalRateTerm<Scalar> r = rate_term(x, k);
    d.lx << c.d_theta, r.d_rate, c.d_pressure;
    d.lxx << c.d_theta_theta, Scalar(0), c.d_theta_pressure, Scalar(0), r.d_rate_rate, Scalar(0),
        c.d_theta_pressure, Scalar(0), c.d_pressure_pressure;
  }

  Control control_lower_bound(int) const {
    return Control(motor_enabled_ ? p_.v_m_min : Scalar(0), p_.v_p_min);
  }
  Control control_upper_bound(int) const {
    return Control(motor_enabled_ ? p_.v_m_max : Scalar(0), p_.v_p_max);
  }

 private:
  Scalar disturbance() const { return offset_free_.enabled ? offset_free_.disturbance : Scalar(0); }
  Scalar time(int k) const { return start_time_ + Scalar(k) * h_; }
  TerminalRateTerm<Scalar> rate_term(const State& x, int k) const {
    return terminal_rate_term(w_, terminal_rate_time_, x(1), target_->rate(time(k)));
  }

  Parameters<Scalar> p_;
  CostWeights<Scalar> w_;
  Scalar h_;
  const TargetTrajectory<Scalar>* target_;
  Scalar start_time_ = 0;
  bool motor_enabled_ = true;
  OffsetFree<Scalar> offset_free_{};
  Scalar terminal_rate_time_ = 0;
};

// Fast subsystem of Eq. 3.2 for the second stage, horizon NFast: P frozen at the coarse plan's
// P~*, state zeta = [theta - theta~*, theta' - theta'~*], input nu = v_m - v~_m*. The coarse
// plan arrives held on the fine grid (Eq. 2.35); zeta is re-referenced where the held plan
// steps, so the underlying joint evolves continuously. The cost is Eq. 3.3 with the voltage
// term replaced by w_v nu^2 (Sec. 3.3: "the deviation of the fast control input").
// Its terminal cost may carry the terminal rate term, which matters most here: the second
// stage looks only 80 ms ahead.
template <typename Scalar, int NFast>
class ForearmFastSubsystem : public ProblemBase<ForearmFastSubsystem<Scalar, NFast>, Scalar, 2, 1> {
  using Base = ProblemBase<ForearmFastSubsystem<Scalar, NFast>, Scalar, 2, 1>;

 public:
  using typename Base::Control;
  using typename Base::ControlJacobian;
  using typename Base::RunningDerivatives;
  using typename Base::State;
  using typename Base::StateJacobian;
  using typename Base::TerminalDerivatives;
  using FullState = Eigen::Matrix<Scalar, 3, 1>;
  using FullControl = Eigen::Matrix<Scalar, 2, 1>;

  ForearmFastSubsystem(const Parameters<Scalar>& parameters, const CostWeights<Scalar>& weights,
                       Scalar fine_step, const TargetTrajectory<Scalar>* target)
      : p_(parameters), w_(weights), h_(fine_step), target_(target) {}

  void set_start_time(Scalar t) { start_time_ = t; }
  void set_target(const TargetTrajectory<Scalar>* target) { target_ = target; }
  void set_weights(const CostWeights<Scalar>& w) { w_ = w; }
  const CostWeights<Scalar>& weights() const { return w_; }
  void set_offset_free(const OffsetFree<Scalar>& o) { offset_free_ = o; }
  void set_terminal_rate_time(Scalar t_v) { terminal_rate_time_ = t_v; }
  Scalar terminal_rate_time() const { return terminal_rate_time_; }

  void set_reference(int j, const FullState& x_hat, const FullControl& u_hat) {
    theta_hat_[j] = x_hat(0);
    theta_dot_hat_[j] = x_hat(1);
    pressure_hat_[j] = x_hat(2);
    v_m_hat_[j] = u_hat(0);
  }
  State deviation(const FullState& x) const {
    return State(x(0) - theta_hat_[0], x(1) - theta_dot_hat_[0]);
  }
  // Eq. 2.36 for the forearm: only the motor input is refined.
  FullControl compose(const FullControl& u_hat, const Control& nu) const {
    return FullControl(u_hat(0) + nu(0), u_hat(1));
  }

  // Eq. 3.2b with the frozen pressure of Eq. 3.2a, one symplectic Euler step.
  State dynamics(const State& zeta, const Control& nu, int j) const {
    const JointStep<Scalar> s = step(zeta, nu, j);
    return State(s.theta - theta_hat_[j + 1], s.theta_dot - theta_dot_hat_[j + 1]);
  }
  void dynamics_derivatives(const State& zeta, const Control& nu, int j, StateJacobian& fx,
                            ControlJacobian& fu) const {
    const JointStep<Scalar> s = step(zeta, nu, j);
    fx = s.jacobian.template leftCols<2>();
    fu = s.jacobian.col(3);
  }

  Scalar running_cost(const State& zeta, const Control& nu, int j) const {
    return cost(zeta, nu, j, true).value + w_.w_v * nu(0) * nu(0);
  }
  Scalar terminal_cost(const State& zeta, int j) const {
    return cost(zeta, Control::Zero(), j, false).value + rate_term(zeta, j).value;
  }
  void running_cost_derivatives(const State& zeta, const Control& nu, int j,
                                RunningDerivatives& d) const {
    const TrackingCost<Scalar> c = cost(zeta, nu, j, true);
    d.lx << c.d_theta, Scalar(0);
    d.lxx << c.d_theta_theta, Scalar(0), Scalar(0), Scalar(0);
    d.lu << c.d_v_m + Scalar(2) * w_.w_v * nu(0);
    d.luu << c.d_v_m_v_m + Scalar(2) * w_.w_v;
    d.lux.setZero();
  }
  void terminal_cost_derivatives(const State& zeta, int j, TerminalDerivatives& d) const {
    const TrackingCost<Scalar> c = cost(zeta, Control::Zero(), j, false);
    const TerminalRateTerm<Scalar> r = rate_term(zeta, j);
    d.lx << c.d_theta, r.d_rate;
    d.lxx << c.d_theta_theta, Scalar(0), Scalar(0), r.d_rate_rate;
  }

  // The composed motor input stays within -5..5 V.
  Control control_lower_bound(int j) const { return Control(p_.v_m_min - v_m_hat_[j]); }
  Control control_upper_bound(int j) const { return Control(p_.v_m_max - v_m_hat_[j]); }

 private:
  JointStep<Scalar> step(const State& zeta, const Control& nu, int j) const {
    return joint_step(p_, h_, zeta(0) + theta_hat_[j], zeta(1) + theta_dot_hat_[j],
                      pressure_hat_[j], v_m_hat_[j] + nu(0),
                      offset_free_.enabled ? offset_free_.disturbance : Scalar(0));
  }
  Scalar time(int j) const { return start_time_ + Scalar(j) * h_; }
  TerminalRateTerm<Scalar> rate_term(const State& zeta, int j) const {
    return terminal_rate_term(w_, terminal_rate_time_, zeta(1) + theta_dot_hat_[j],
                              target_->rate(time(j)));
  }
  TrackingCost<Scalar> cost(const State& zeta, const Control& nu, int j, bool running) const {
    const Scalar theta_d = target_->angle(time(j));
    return tracking_cost(p_, w_, zeta(0) + theta_hat_[j], theta_d, pressure_hat_[j],
                         v_m_hat_[j] + nu(0), running, offset_free_);
  }

  Parameters<Scalar> p_;
  CostWeights<Scalar> w_;
  Scalar h_;
  const TargetTrajectory<Scalar>* target_;
  Scalar start_time_ = 0;
  OffsetFree<Scalar> offset_free_{};
  Scalar terminal_rate_time_ = 0;
  std::array<Scalar, NFast + 1> theta_hat_{};
  std::array<Scalar, NFast + 1> theta_dot_hat_{};
  std::array<Scalar, NFast + 1> pressure_hat_{};
  std::array<Scalar, NFast + 1> v_m_hat_{};
};

}  // namespace hmpc::forearm
