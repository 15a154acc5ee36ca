// Forearm with a pneumatic-electric hybrid actuator (thesis Ch. 3, Eq. 3.1):
//
//   T_p dP/dt   = -k_vp P + v_p                                  (valve + PAM pressure)
//   I theta''   = c(theta, theta') + tau_p(P, theta) + tau_m(v_m)  (joint)
//
// theta is the elbow angle from the horizontal, flexion positive; the PAM acts as a flexor
// against gravity through a pulley, the motor drives the joint directly. State
// x = [theta, theta', P], input u = [v_m, v_p] as in the thesis (Sec. 3.2.1).
//
// Units: rad, rad/s, bar (pressure; 1 bar = 0.1 MPa), V, N·m. Pressure is kept in bar so that
// the thesis's weights (w_P on the pressure penalty, k_vp as a pressure-to-voltage factor)
// act on numbers of order one, as on the original robot.
#pragma once

#include <Eigen/Core>
#include <cmath>

#include "hmpc/constants.hpp"

namespace hmpc::forearm {

// Every physical parameter of the forearm in one place, with where its value comes from.
template <typename Scalar>
struct Parameters {
  // Link. Mass from the thesis (Sec. 3.3: "The forearm robot weighed 2.7 kg"). Length, centre
  // of mass and radius of gyration are our choice for a forearm-and-hand link of an adult-size
  // arm: 0.30 m long, centre of mass at 0.13 m, gyration about the centre of mass as a
  // uniform rod of that length (L / sqrt(12)).
  Scalar mass = Scalar(2.7);                // kg (thesis)
  Scalar com_distance = Scalar(0.13);       // m, elbow to centre of mass
  Scalar gyration_radius = Scalar(0.0866);  // m, about the centre of mass
  Scalar gravity = Scalar(9.81);            // m/s^2

  // Smooth friction, as the thesis uses (its ref. [82], Makkar et al.): viscous plus a
  // tanh-smoothed Coulomb term. Values: a light plain-bearing elbow; the smoothing velocity is
  // wide enough that the 40 ms coarse model stays stable (h * F_c / (I v_s) < 1).
  Scalar viscous_friction = Scalar(0.05);  // N·m·s/rad
  Scalar coulomb_friction = Scalar(0.10);  // N·m
  Scalar friction_velocity = Scalar(0.2);  // rad/s, tanh smoothing

  // Pneumatic artificial muscle, Chou & Hannaford (1996) static model
  //   F = p (pi D0^2 / 4) (3 (1 - e)^2 / tan^2 a0 - 1 / sin^2 a0),
  // contraction e = e0 + r theta / L0 through a pulley of radius r. A 16 mm McKibben muscle
  // with a 25 degree braid, 0.25 m long, 10 % pre-contracted at theta = 0, on a 20 mm pulley:
  // it holds the arm horizontal at about 1.5 bar, mid-range of the valve, and gives ~11 N·m
  // at 5 bar: the "strong" actuator, ten times the motor.
  Scalar pam_diameter = Scalar(0.016);       // m, D0
  Scalar pam_braid_angle = Scalar(0.4363);   // rad, a0 = 25 deg
  Scalar pam_rest_length = Scalar(0.25);     // m, L0
  Scalar pam_precontraction = Scalar(0.10);  // e0 at theta = 0
  Scalar pulley_radius = Scalar(0.020);      // m, r

  // Valve and muscle volume: first-order pressure response with time constant T_p / k_vp.
  // 5 V commands 5 bar (k_vp = 1 V/bar); 150 ms time constant, typical of a proportional
  // valve filling a McKibben muscle through a hose: the "slow" actuator.
  Scalar k_vp = Scalar(1.0);  // V/bar
  Scalar T_p = Scalar(0.15);  // V·s/bar

  // Electric motor with driver in torque mode: tau_m = k_m v_m, 0.3 N·m at 5 V, a small
  // lightweight assist motor (the thesis: its torque is "much smaller than that of PAM",
  // Sec. 3.4.3): the weak but fast actuator, electrical dynamics neglected.
  Scalar motor_gain = Scalar(0.06);  // N·m/V

  // Input limits (thesis Sec. 3.3): 0 <= v_p <= 5 V, -5 <= v_m <= 5 V.
  Scalar v_p_min = Scalar(0), v_p_max = Scalar(5);
  Scalar v_m_min = Scalar(-5), v_m_max = Scalar(5);

  // Software joint limits: beyond them the board faults into its safe state, and the host and
  // the DDS bridge refuse targets outside them. Inside the mechanical stops below, so a
  // working controller never reaches the stops.
  Scalar soft_limit_lower = Scalar(-1.2);  // rad
  Scalar soft_limit_upper = Scalar(1.6);   // rad

  // Mechanical end stops of the elbow: only the HIL plant (hil/forearm) has them; Eq. 3.1 and
  // the controllers ignore these fields. The arm rests on the lower stop when the valve is
  // vented. A stiff rubber bumper (our choice): at
  // 1e4 N·m/rad the arm's own weight compresses the lower stop by 0.04 mrad. Hunt-Crossley
  // dissipation: the stop torque is k x (1 + d x'), x the penetration and x' its rate, never
  // pulling, so it adds nothing at first touch and damps in proportion to impact speed. With
  // d = 0.5 s/rad the vented arm falling from the horizontal (~10 rad/s at impact) compresses
  // the stop by 0.012 rad and keeps ~3 % of its energy (rebounds 0.15 rad).
  Scalar stop_lower = Scalar(-1.45);      // rad
  Scalar stop_upper = Scalar(1.75);       // rad
  Scalar stop_stiffness = Scalar(1e4);    // N·m/rad
  Scalar stop_dissipation = Scalar(0.5);  // s/rad

  Scalar inertia() const {
    return mass * (com_distance * com_distance + gyration_radius * gyration_radius);
  }
};

// Cost weights of Eq. 3.3-3.4 (thesis Sec. 3.3) and the pressure threshold P0.
template <typename Scalar>
struct CostWeights {
  Scalar w_theta = Scalar(40);
  Scalar w_P = Scalar(30);
  Scalar w_tau = Scalar(0.1);
  Scalar w_v = Scalar(0.002);
  Scalar gamma = Scalar(0.1);  // smoothness of smin, Eq. 3.4
  // Below P0 the cable to the muscle goes slack (Sec. 3.3). The thesis gives no value; 0.5
  // bar is where a McKibben muscle of this size just takes up its own braid slack.
  Scalar P0 = Scalar(0.5);  // bar
};

// PAM torque tau_p(P, theta) and its partial derivatives.
template <typename Scalar>
struct PamTorque {
  Scalar tau, d_theta, d_pressure, d_theta_theta, d_theta_pressure;
};

template <typename Scalar>
PamTorque<Scalar> pam_torque(const Parameters<Scalar>& p, Scalar pressure_bar, Scalar theta) {
  using std::sin;
  using std::tan;
  const Scalar area = kPi<Scalar> * p.pam_diameter * p.pam_diameter / Scalar(4);
  const Scalar a = Scalar(3) / (tan(p.pam_braid_angle) * tan(p.pam_braid_angle));
  const Scalar b = Scalar(1) / (sin(p.pam_braid_angle) * sin(p.pam_braid_angle));
  const Scalar r = p.pulley_radius;
  const Scalar de = r / p.pam_rest_length;  // d contraction / d theta
  const Scalar stretch = Scalar(1) - (p.pam_precontraction + de * theta);  // 1 - e
  const Scalar pa_area = Scalar(1e5) * area;                               // N per bar
  const Scalar shape = a * stretch * stretch - b;
  PamTorque<Scalar> t;
  t.tau = r * pa_area * pressure_bar * shape;
  t.d_pressure = r * pa_area * shape;
  t.d_theta = -Scalar(2) * r * pa_area * pressure_bar * a * stretch * de;
  t.d_theta_theta = Scalar(2) * r * pa_area * pressure_bar * a * de * de;
  t.d_theta_pressure = -Scalar(2) * r * pa_area * a * stretch * de;
  return t;
}

// Joint acceleration theta'' of Eq. 3.1 and its partial derivatives. `disturbance` is a torque
// on the joint that Eq. 3.1 does not model (a payload, more friction, a valve slower than the
// model's, as its effect on the joint), estimated for offset-free control
// (forearm_disturbance.hpp); 0 is Eq. 3.1 itself.
template <typename Scalar>
struct JointAcceleration {
  Scalar value, d_theta, d_theta_dot, d_pressure, d_v_m;
};

template <typename Scalar>
JointAcceleration<Scalar> joint_acceleration(const Parameters<Scalar>& p, Scalar theta,
                                             Scalar theta_dot, Scalar pressure_bar, Scalar v_m,
                                             Scalar disturbance = Scalar(0)) {
  using std::cos;
  using std::sin;
  using std::tanh;
  const Scalar inv_inertia = Scalar(1) / p.inertia();
  const Scalar gravity_arm = p.mass * p.gravity * p.com_distance;
  const Scalar smooth_sign = tanh(theta_dot / p.friction_velocity);
  // c(theta, theta'): gravity and smooth friction.
  const Scalar c =
      -gravity_arm * cos(theta) - p.viscous_friction * theta_dot - p.coulomb_friction * smooth_sign;
  const PamTorque<Scalar> pam = pam_torque(p, pressure_bar, theta);
  JointAcceleration<Scalar> a;
  a.value = inv_inertia * (c + pam.tau + p.motor_gain * v_m + disturbance);
  a.d_theta = inv_inertia * (gravity_arm * sin(theta) + pam.d_theta);
  a.d_theta_dot = -inv_inertia * (p.viscous_friction + p.coulomb_friction *
                                                           (Scalar(1) - smooth_sign * smooth_sign) /
                                                           p.friction_velocity);
  a.d_pressure = inv_inertia * pam.d_pressure;
  a.d_v_m = inv_inertia * p.motor_gain;
  return a;
}

// dP/dt of Eq. 3.1.
template <typename Scalar>
Scalar pressure_rate(const Parameters<Scalar>& p, Scalar pressure_bar, Scalar v_p) {
  return (-p.k_vp * pressure_bar + v_p) / p.T_p;
}

// The plant's continuous right-hand side, for integrators (state [theta, theta', P],
// input [v_m, v_p]).
template <typename Scalar>
Eigen::Matrix<Scalar, 3, 1> state_derivative(const Parameters<Scalar>& p,
                                             const Eigen::Matrix<Scalar, 3, 1>& x,
                                             const Eigen::Matrix<Scalar, 2, 1>& u) {
  return Eigen::Matrix<Scalar, 3, 1>(x(1), joint_acceleration(p, x(0), x(1), x(2), u(0)).value,
                                     pressure_rate(p, x(2), u(1)));
}

// Eq. 3.1 integrated over dt with classical RK4, input held: the reference plant for tests
// and simulations on our own integrator.
template <typename Scalar>
Eigen::Matrix<Scalar, 3, 1> integrate(const Parameters<Scalar>& p,
                                      const Eigen::Matrix<Scalar, 3, 1>& x,
                                      const Eigen::Matrix<Scalar, 2, 1>& u, Scalar dt) {
  using V = Eigen::Matrix<Scalar, 3, 1>;
  const V k1 = state_derivative(p, x, u);
  const V k2 = state_derivative(p, V(x + Scalar(0.5) * dt * k1), u);
  const V k3 = state_derivative(p, V(x + Scalar(0.5) * dt * k2), u);
  const V k4 = state_derivative(p, V(x + dt * k3), u);
  return x + dt / Scalar(6) * (k1 + Scalar(2) * k2 + Scalar(2) * k3 + k4);
}

// The torque the actuators must supply to hold the arm still at theta against gravity and a
// disturbance torque (friction is zero at rest), and its slope in theta.
template <typename Scalar>
struct HoldingTorque {
  Scalar tau, d_theta;
};
template <typename Scalar>
HoldingTorque<Scalar> holding_torque(const Parameters<Scalar>& p, Scalar theta,
                                     Scalar disturbance) {
  using std::cos;
  using std::sin;
  const Scalar gravity_arm = p.mass * p.gravity * p.com_distance;
  return {gravity_arm * cos(theta) - disturbance, -gravity_arm * sin(theta)};
}

// Pressure at which the PAM alone holds the arm still at theta (gravity balance, friction
// aside): the natural initial state and hold point.
template <typename Scalar>
Scalar equilibrium_pressure(const Parameters<Scalar>& p, Scalar theta) {
  using std::cos;
  const Scalar per_bar = pam_torque(p, Scalar(1), theta).tau;
  return p.mass * p.gravity * p.com_distance * cos(theta) / per_bar;
}

// Smooth minimum of Eq. 3.4 against 0 and its first two derivatives in a.
template <typename Scalar>
struct SmoothMin {
  Scalar value, d, dd;
};
template <typename Scalar>
SmoothMin<Scalar> smin_zero(Scalar a, Scalar gamma) {
  using std::sqrt;
  const Scalar root = sqrt(a * a + gamma * gamma);
  return {-(root - a) / Scalar(2), (Scalar(1) - a / root) / Scalar(2),
          -gamma * gamma / (Scalar(2) * root * root * root)};
}

}  // namespace hmpc::forearm
