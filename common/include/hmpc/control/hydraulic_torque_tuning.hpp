// One tuning procedure for a hydraulic joint's torque loop (LoadVelocityFeedbackPid on the
// torque, output the valve command), from the actuator's linearised torque rate
//   d tau / dt = k_q u - k_v theta'                                (models/hydraulic_joint.hpp)
// at the valve's no-load operating point. The loop without the velocity term is an integrator
// of gain k_q behind a delay D: half the control period T (the zero-order hold), the board's
// 1 ms I/O tick from the sensor sample to the valve drive, and the valve's own lag tau_v.
// Proportional gain puts the crossover at omega_c = kp k_q; a 30 degree phase loss to the
// delay at crossover leaves a 60 degree margin:
//   D = T / 2 + 1 ms + tau_v,  omega_c = (pi / 6) / D,
//   kp = omega_c / k_q,  ki = kp omega_c / 5,  k_lv = 0.9 k_v / k_q.
// The integral's corner a fifth of the crossover costs about 11 degrees more (our choice: it
// removes the friction's steady error within a few crossover periods). k_lv cancels the
// load-velocity coupling (thesis Sec. 2.7.3); the same kp and ki serve a PID without it, so the
// two differ only in that term. The coupling is derated to 0.9 of the believed one because
// its two errors are not alike: too little leaves some coupling, too much is positive feedback
// of the load's velocity, which pumps energy into a swinging load. With the actuator constants
// up to 20 % below the plant's (k_lv 25 % high) the derated term over-compensates by at most
// 12.5 %; on the one-joint bench the full term over-compensating by 25 % lost a third of its
// benefit, the derated one kept it within 20 % either way (README, joint board).
//
// k_v / k_q moves with the operating point (the chamber volumes with the angle, the valve's
// pressure drops with the load), which the board measures: load_velocity_schedule() gives the
// factor by which the gain at the present point exceeds the no-load one, from the same model.
#pragma once

#include <cmath>

#include "hmpc/models/hydraulic_joint.hpp"

namespace hmpc::hydraulic {

// The share of the believed load-velocity coupling the torque loop cancels (see above).
inline constexpr double kLoadVelocityDerating = 0.9;

template <typename Scalar>
struct TorqueLoopGains {
  Scalar kp = Scalar(0);    // 1/(N·m)
  Scalar ki = Scalar(0);    // 1/(N·m·s)
  Scalar k_lv = Scalar(0);  // s/rad
};

// The chambers' pressures at the valve's null with no load and the joint centred, for a
// spool just opened: equal flow per piston area through both lands and no net force give
// p_a = p_s / (1 + (A_a / A_b)^3), p_b = p_a A_a / A_b (return at gauge zero).
template <typename Scalar>
JointActuatorState<Scalar> no_load_operating_point(const JointActuatorParameters<Scalar>& p) {
  const Scalar ratio = p.area_a / p.area_b;
  JointActuatorState<Scalar> s;
  s.pressure_a = p.return_pressure +
                 (p.supply_pressure - p.return_pressure) / (Scalar(1) + ratio * ratio * ratio);
  s.pressure_b = s.pressure_a * ratio;
  return s;
}

// The board's I/O tick: a sensor sample reaches the valve drive within it.
inline constexpr double kIoTickSeconds = 0.001;

// The procedure above for control period T (s), from the actuator constants the controller
// believes (which may differ from the plant's).
template <typename Scalar>
TorqueLoopGains<Scalar> tune_torque_loop(const JointActuatorParameters<Scalar>& believed,
                                         Scalar period) {
  const TorqueRateGains<Scalar> k =
      torque_rate_gains(believed, no_load_operating_point(believed), believed.mid_stroke_angle);
  const Scalar pi = Scalar(3.14159265358979323846);
  const Scalar delay = period / Scalar(2) + Scalar(kIoTickSeconds) + believed.valve_time_constant;
  const Scalar crossover = (pi / Scalar(6)) / delay;
  TorqueLoopGains<Scalar> gains;
  gains.kp = crossover / k.valve;
  gains.ki = gains.kp * crossover / Scalar(5);
  gains.k_lv = Scalar(kLoadVelocityDerating) * k.load_velocity / k.valve;
  return gains;
}

// k_v / k_q at the no-load operating point: what load_velocity_schedule() divides by, fixed for
// a given actuator, so a controller computes it once.
template <typename Scalar>
Scalar no_load_velocity_ratio(const JointActuatorParameters<Scalar>& believed) {
  const TorqueRateGains<Scalar> k =
      torque_rate_gains(believed, no_load_operating_point(believed), believed.mid_stroke_angle);
  return k.load_velocity / k.valve;
}

// The factor k_lv(x) / k_lv(no load) of the load-velocity gain at the measured operating point
// (chamber pressures, joint angle, the side of the valve's last command), from the believed
// constants and their no_load_velocity_ratio(); bounded to [0, 2] so that a pressure at the
// supply's (where the open land's flow, and k_q with it, vanishes) cannot make the gain
// unbounded.
template <typename Scalar>
Scalar load_velocity_schedule(const JointActuatorParameters<Scalar>& believed, Scalar no_load_ratio,
                              const JointActuatorState<Scalar>& measured, Scalar theta) {
  const TorqueRateGains<Scalar> here = torque_rate_gains(believed, measured, theta);
  if (!(here.valve > Scalar(0))) return Scalar(2);
  const Scalar factor = (here.load_velocity / here.valve) / no_load_ratio;
  return factor < Scalar(0) ? Scalar(0) : (factor > Scalar(2) ? Scalar(2) : factor);
}

}  // namespace hmpc::hydraulic
