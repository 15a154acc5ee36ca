// A hydraulic joint actuator: a servo valve driving a double-acting cylinder that turns the
// joint through a lever (the humanoid's legs, thesis Sec. 2.7: CB-i's joints are hydraulic).
// The structure is the classic valve-controlled cylinder (H. E. Merritt, Hydraulic Control
// Systems, 1967, ch. 5; the same model as in the torque control of the HyQ leg, Boaventura et
// al., ICRA 2012):
//
//   tau_v dxv/dt = u - xv                                      (valve spool, first order)
//   Q_a = K xv g(p_s - p_a),  Q_b = -K xv g(p_b - p_r)          (xv >= 0: supply into a)
//   Q_a = K xv g(p_a - p_r),  Q_b = -K xv g(p_s - p_b)          (xv < 0: supply into b)
//   dp_a/dt = beta / V_a(theta) (Q_a - A_a r theta')             (chamber a: piston side)
//   dp_b/dt = beta / V_b(theta) (Q_b + A_b r theta')             (chamber b: rod side)
//   tau = r (A_a p_a - A_b p_b) - r F_friction(r theta')        (joint torque)
//
// with x = r (theta - theta_m) the piston's travel from mid-stroke, theta_m the joint angle at
// mid-stroke, V_a = V_0 + A_a (s/2 + x) and
// V_b = V_0 + A_b (s/2 - x), g(dp) the orifice's signed square root, smoothed below a
// transition pressure so that the flow is differentiable through dp = 0 (there, flow through a
// real orifice turns laminar and linear in dp). The terms -A_a r theta' and +A_b r theta' are
// the load-velocity coupling: a joint that moves compresses one chamber and expands the other,
// so its torque falls as it speeds up even with the valve closed. A joint controller that
// ignores it sees a velocity-dependent torque error; load-velocity feedback compensates it.
//
// Units: SI (Pa, m^3, m, rad, N·m); the valve command u is normalised to [-1, 1] (the valve's
// rated current). Pressures are gauge pressures.
#pragma once

#include <cmath>

namespace hmpc::hydraulic {

// Every parameter of a joint's actuator in one place, with its reason. A HyQ-class leg joint:
// supply pressure, cylinder and valve from HyQ's published design (Semini et al., Proc. IMechE
// Part I 225(6), 2011: 16 MPa, Hoerbiger LB6 16/10 mm cylinders, Moog E024 valves), the
// lever from its knee; CB-i's joints are of the same size class (Sarcos valve-controlled
// cylinders driving a human-sized leg).
template <typename Scalar>
struct JointActuatorParameters {
  Scalar supply_pressure = Scalar(16e6);  // Pa, HyQ's nominal supply
  Scalar return_pressure = Scalar(0);     // Pa, gauge: tank at atmosphere
  // Effective bulk modulus: Merritt's design value (100 000 psi), lower than the oil's own
  // ~1.5 GPa because of entrained air and hose compliance.
  Scalar bulk_modulus = Scalar(6.9e8);  // Pa
  // 16 mm bore, 10 mm rod: A_a = pi 0.008^2, A_b = A_a - pi 0.005^2.
  Scalar area_a = Scalar(2.0106e-4);  // m^2, piston side
  Scalar area_b = Scalar(1.2252e-4);  // m^2, rod side
  Scalar stroke = Scalar(0.08);       // m
  // Oil between the valve and each chamber at the stroke's end (manifold-mounted valve).
  Scalar dead_volume = Scalar(2e-6);  // m^3
  // Lever arm of the cylinder about the joint, taken constant (the linkage's variation over
  // the joint's range is left out).
  Scalar lever = Scalar(0.035);  // m
  // The joint angle at mid-stroke: 0 puts the stroke's middle at the joint's zero; a joint whose
  // range is not centred on zero (a knee, 0 to 135 degrees) mounts its cylinder about the
  // middle of its range.
  Scalar mid_stroke_angle = Scalar(0);  // rad
  // E024: 2.5 l/min rated flow at 7 MPa valve drop, i.e. 3.5 MPa per land:
  // K = 2.5e-3 / 60 / sqrt(3.5e6).
  Scalar valve_flow_gain = Scalar(2.227e-8);  // m^3/s per sqrt(Pa) at full opening
  // E024's bandwidth is about 250 Hz (-3 dB): a first-order lag of 1 / (2 pi 250) s.
  Scalar valve_time_constant = Scalar(6.4e-4);  // s
  // Below this pressure drop the orifice's flow turns linear (smoothing of g); small against
  // the supply, so the turbulent law holds wherever the joint works.
  Scalar transition_pressure = Scalar(2e5);  // Pa
  // Cylinder seal friction (our choice until identified on a joint: typical of small servo
  // cylinders with low-friction seals), Coulomb smoothed over the velocity below.
  Scalar coulomb_friction = Scalar(20);           // N
  Scalar viscous_friction = Scalar(200);          // N·s/m
  Scalar coulomb_smoothing_speed = Scalar(1e-3);  // m/s

  // Joint range over which the piston stays inside its stroke: mid_stroke_angle +- this.
  Scalar theta_limit() const { return stroke / (Scalar(2) * lever); }
  // Largest torque the actuator can push at stall: supply on the piston side, return on the
  // rod side (and the mirror image for the other direction, on the smaller rod-side area).
  Scalar stall_torque_positive() const {
    return lever * (area_a * supply_pressure - area_b * return_pressure);
  }
  Scalar stall_torque_negative() const {
    return lever * (area_a * return_pressure - area_b * supply_pressure);
  }
};

// Empty (nullptr) when the parameters make a physical actuator, otherwise what is wrong.
template <typename Scalar>
const char* check(const JointActuatorParameters<Scalar>& p) {
  const auto positive = [](Scalar v) { return std::isfinite(v) && v > Scalar(0); };
  if (!positive(p.supply_pressure)) return "supply pressure must be positive";
  if (!std::isfinite(p.return_pressure) || p.return_pressure < Scalar(0) ||
      p.return_pressure >= p.supply_pressure) {
    return "return pressure must be in [0, supply pressure)";
  }
  if (!positive(p.bulk_modulus)) return "bulk modulus must be positive";
  if (!positive(p.area_a) || !positive(p.area_b) || p.area_b > p.area_a) {
    return "cylinder areas must be positive, the rod side's at most the piston side's";
  }
  if (!positive(p.stroke) || !positive(p.dead_volume) || !positive(p.lever)) {
    return "stroke, dead volume and lever must be positive";
  }
  if (!std::isfinite(p.mid_stroke_angle)) return "mid-stroke angle must be finite";
  if (!positive(p.valve_flow_gain) || !positive(p.valve_time_constant) ||
      !positive(p.transition_pressure)) {
    return "valve flow gain, time constant and transition pressure must be positive";
  }
  if (!std::isfinite(p.coulomb_friction) || p.coulomb_friction < Scalar(0) ||
      !std::isfinite(p.viscous_friction) || p.viscous_friction < Scalar(0) ||
      !positive(p.coulomb_smoothing_speed)) {
    return "friction must be finite and non-negative, its smoothing speed positive";
  }
  return nullptr;
}

// The actuator's own state; the joint's angle and velocity belong to the mechanism it drives.
template <typename Scalar>
struct JointActuatorState {
  Scalar spool = Scalar(0);       // valve opening, [-1, 1]
  Scalar pressure_a = Scalar(0);  // Pa, piston side
  Scalar pressure_b = Scalar(0);  // Pa, rod side
};

// The orifice's signed square root, g(dp) = dp / (dp^2 + p_t^2)^(1/4): sign(dp) sqrt(|dp|)
// for |dp| >> p_t, linear (dp / sqrt(p_t)) around zero.
template <typename Scalar>
Scalar orifice_root(Scalar dp, Scalar transition_pressure) {
  return dp / std::sqrt(std::sqrt(dp * dp + transition_pressure * transition_pressure));
}

// d g / d dp of orifice_root: (dp^2 / 2 + p_t^2) / (dp^2 + p_t^2)^(5/4).
template <typename Scalar>
Scalar orifice_root_slope(Scalar dp, Scalar transition_pressure) {
  const Scalar s = dp * dp + transition_pressure * transition_pressure;
  return (Scalar(0.5) * dp * dp + transition_pressure * transition_pressure) /
         std::pow(s, Scalar(1.25));
}

// Chamber volumes at the joint angle theta (piston at mid-stroke for theta = mid_stroke_angle),
// never below the dead volume: beyond the stroke the piston sits on its end cap.
template <typename Scalar>
Scalar chamber_volume_a(const JointActuatorParameters<Scalar>& p, Scalar theta) {
  const Scalar travel = p.stroke / Scalar(2) + p.lever * (theta - p.mid_stroke_angle);
  return p.dead_volume + p.area_a * std::fmax(travel, Scalar(0));
}
template <typename Scalar>
Scalar chamber_volume_b(const JointActuatorParameters<Scalar>& p, Scalar theta) {
  const Scalar travel = p.stroke / Scalar(2) - p.lever * (theta - p.mid_stroke_angle);
  return p.dead_volume + p.area_b * std::fmax(travel, Scalar(0));
}

// Flows into chambers a and b (m^3/s) through the valve at its opening.
template <typename Scalar>
struct ValveFlows {
  Scalar into_a = Scalar(0);
  Scalar into_b = Scalar(0);
};
template <typename Scalar>
ValveFlows<Scalar> valve_flows(const JointActuatorParameters<Scalar>& p,
                               const JointActuatorState<Scalar>& s) {
  const Scalar k = p.valve_flow_gain * s.spool;
  const Scalar pt = p.transition_pressure;
  if (s.spool >= Scalar(0)) {
    return {k * orifice_root(p.supply_pressure - s.pressure_a, pt),
            -k * orifice_root(s.pressure_b - p.return_pressure, pt)};
  }
  return {k * orifice_root(s.pressure_a - p.return_pressure, pt),
          -k * orifice_root(p.supply_pressure - s.pressure_b, pt)};
}

// Friction force on the piston opposing its speed v (m/s): smoothed Coulomb plus viscous.
template <typename Scalar>
Scalar piston_friction(const JointActuatorParameters<Scalar>& p, Scalar v) {
  return p.coulomb_friction * std::tanh(v / p.coulomb_smoothing_speed) + p.viscous_friction * v;
}

// d F_friction / dv of piston_friction at piston speed v (N·s/m).
template <typename Scalar>
Scalar piston_friction_slope(const JointActuatorParameters<Scalar>& p, Scalar v) {
  const Scalar sech = Scalar(1) / std::cosh(v / p.coulomb_smoothing_speed);
  return p.coulomb_friction / p.coulomb_smoothing_speed * sech * sech + p.viscous_friction;
}

// Joint torque (N·m) the actuator applies at joint velocity theta_dot.
template <typename Scalar>
Scalar joint_torque(const JointActuatorParameters<Scalar>& p, const JointActuatorState<Scalar>& s,
                    Scalar theta_dot) {
  const Scalar pressure_force = p.area_a * s.pressure_a - p.area_b * s.pressure_b;
  return p.lever * (pressure_force - piston_friction(p, p.lever * theta_dot));
}

// The state's time derivative for valve command u (clamped to [-1, 1]) with the joint at
// theta, theta_dot: the equations at the top of this file.
template <typename Scalar>
JointActuatorState<Scalar> derivative(const JointActuatorParameters<Scalar>& p,
                                      const JointActuatorState<Scalar>& s, Scalar theta,
                                      Scalar theta_dot, Scalar u) {
  const Scalar command = std::fmin(std::fmax(u, Scalar(-1)), Scalar(1));
  const ValveFlows<Scalar> q = valve_flows(p, s);
  const Scalar piston_speed = p.lever * theta_dot;
  JointActuatorState<Scalar> d;
  d.spool = (command - s.spool) / p.valve_time_constant;
  d.pressure_a = p.bulk_modulus / chamber_volume_a(p, theta) * (q.into_a - p.area_a * piston_speed);
  d.pressure_b = p.bulk_modulus / chamber_volume_b(p, theta) * (q.into_b + p.area_b * piston_speed);
  return d;
}

// The load-velocity coupling: with the valve closed, the rate of change of the pressure torque
// per unit joint velocity, -r^2 beta (A_a^2 / V_a + A_b^2 / V_b) (N·m/s per rad/s). Negative:
// the hydraulic spring resists the motion.
template <typename Scalar>
Scalar load_velocity_coupling(const JointActuatorParameters<Scalar>& p, Scalar theta) {
  return -p.lever * p.lever * p.bulk_modulus *
         (p.area_a * p.area_a / chamber_volume_a(p, theta) +
          p.area_b * p.area_b / chamber_volume_b(p, theta));
}

// The torque's rate, linearised about an operating point (pressures p_a, p_b, joint at theta):
//   d tau / dt = k_q xv - k_v theta'
// from the equations above with the chambers' flows linear in the spool opening xv on each side
// of the valve's centre (the side of the state's spool; xv >= 0 when it is 0):
//   k_q = r beta K (A_a g_a / V_a + A_b g_b / V_b),  k_v = r^2 beta (A_a^2 / V_a + A_b^2 / V_b)
// with g_a, g_b the orifice roots across the two open lands. k_v / k_q is the load-velocity
// gain that cancels the joint's motion from the torque (LoadVelocityFeedbackPid).
template <typename Scalar>
struct TorqueRateGains {
  Scalar valve = Scalar(0);          // k_q, N·m/s per unit spool opening
  Scalar load_velocity = Scalar(0);  // k_v, N·m/s per rad/s
};
template <typename Scalar>
TorqueRateGains<Scalar> torque_rate_gains(const JointActuatorParameters<Scalar>& p,
                                          const JointActuatorState<Scalar>& s, Scalar theta) {
  const Scalar pt = p.transition_pressure;
  const bool positive_side = s.spool >= Scalar(0);
  const Scalar g_a = positive_side ? orifice_root(p.supply_pressure - s.pressure_a, pt)
                                   : orifice_root(s.pressure_a - p.return_pressure, pt);
  const Scalar g_b = positive_side ? orifice_root(s.pressure_b - p.return_pressure, pt)
                                   : orifice_root(p.supply_pressure - s.pressure_b, pt);
  const Scalar va = chamber_volume_a(p, theta), vb = chamber_volume_b(p, theta);
  TorqueRateGains<Scalar> gains;
  gains.valve =
      p.lever * p.bulk_modulus * p.valve_flow_gain * (p.area_a * g_a / va + p.area_b * g_b / vb);
  gains.load_velocity = -load_velocity_coupling(p, theta);
  return gains;
}

}  // namespace hmpc::hydraulic
