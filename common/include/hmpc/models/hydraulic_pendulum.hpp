// A hydraulic joint actuator (hydraulic_joint.hpp) swinging a rigid link that hangs under
// gravity: the one-joint test load of the joint boards, integrated here by RK4 for the tests
// and firmware images that run a plant in-process (the HIL bench's plant node has Simbody
// integrate the link instead, with the same actuator and load parameters).
//
//   I theta'' = tau(actuator) - m g l sin(theta),  theta = 0 hanging
//
// Header-only, allocation-free: it runs inside the Cortex-M images (Scalar float on an M4).
#pragma once

#include <cmath>

#include "hmpc/models/hydraulic_joint.hpp"

namespace hmpc::hydraulic {

template <typename Scalar>
struct PendulumLoad {
  Scalar mass = Scalar(3);            // kg
  Scalar com_distance = Scalar(0.2);  // m, joint to the centre of mass
  Scalar inertia = Scalar(0.4);       // kg·m^2 about the joint
  Scalar gravity = Scalar(9.81);      // m/s^2

  Scalar gravity_torque(Scalar theta) const {
    return mass * gravity * com_distance * std::sin(theta);
  }

  // A shank-sized link (3 kg at 0.2 m, 0.4 kg m^2 with its own inertia and the rotor's).
  static PendulumLoad shank() { return {}; }
  // A whole human-size leg swung about the hip, the humanoid's heaviest joint load: 16 kg
  // (16 % of a 1.6 m, 92 kg humanoid such as CB-i, the leg's share in anthropometric tables)
  // with its centre of mass 0.4 m below the hip and a 0.5 m radius of gyration.
  static PendulumLoad leg() { return {Scalar(16), Scalar(0.4), Scalar(4.0), Scalar(9.81)}; }
};

template <typename Scalar>
struct PendulumState {
  JointActuatorState<Scalar> actuator{};
  Scalar theta = Scalar(0);  // rad, 0 hanging
  Scalar omega = Scalar(0);  // rad/s
};

// At rest, hanging, torque-free, with the rod-side chamber at rod_pressure (Pa): the piston
// side at A_b / A_a of it.
template <typename Scalar>
PendulumState<Scalar> torque_free_rest(const JointActuatorParameters<Scalar>& actuator,
                                       Scalar rod_pressure = Scalar(6e6)) {
  PendulumState<Scalar> s;
  s.actuator.pressure_b = rod_pressure;
  s.actuator.pressure_a = rod_pressure * actuator.area_b / actuator.area_a;
  return s;
}

// Advances the actuator and link by dt under valve command u, in `substeps` RK4 steps (the
// chambers' pressure dynamics are stiff: steps of 20 to 50 us). A clamped link (a torque test
// stand) does not move; its actuator still does.
template <typename Scalar>
void step_pendulum(const JointActuatorParameters<Scalar>& actuator,
                   const PendulumLoad<Scalar>& load, PendulumState<Scalar>& x, Scalar u, Scalar dt,
                   int substeps, bool clamped = false) {
  struct Rate {
    JointActuatorState<Scalar> a;
    Scalar theta, omega;
  };
  const auto rate = [&](const JointActuatorState<Scalar>& s, Scalar th, Scalar om) {
    if (clamped) return Rate{derivative(actuator, s, th, Scalar(0), u), Scalar(0), Scalar(0)};
    const Scalar tau = joint_torque(actuator, s, om);
    return Rate{derivative(actuator, s, th, om, u), om,
                (tau - load.gravity_torque(th)) / load.inertia};
  };
  const auto moved = [](const JointActuatorState<Scalar>& s, const Rate& k, Scalar h) {
    return JointActuatorState<Scalar>{s.spool + h * k.a.spool, s.pressure_a + h * k.a.pressure_a,
                                      s.pressure_b + h * k.a.pressure_b};
  };
  const Scalar h = dt / Scalar(substeps);
  for (int i = 0; i < substeps; ++i) {
    const Rate k1 = rate(x.actuator, x.theta, x.omega);
    const Rate k2 =
        rate(moved(x.actuator, k1, h / 2), x.theta + h / 2 * k1.theta, x.omega + h / 2 * k1.omega);
    const Rate k3 =
        rate(moved(x.actuator, k2, h / 2), x.theta + h / 2 * k2.theta, x.omega + h / 2 * k2.omega);
    const Rate k4 = rate(moved(x.actuator, k3, h), x.theta + h * k3.theta, x.omega + h * k3.omega);
    const auto mix = [h](Scalar a, Scalar b, Scalar c, Scalar d) {
      return h / Scalar(6) * (a + Scalar(2) * b + Scalar(2) * c + d);
    };
    x.actuator.spool += mix(k1.a.spool, k2.a.spool, k3.a.spool, k4.a.spool);
    x.actuator.pressure_a +=
        mix(k1.a.pressure_a, k2.a.pressure_a, k3.a.pressure_a, k4.a.pressure_a);
    x.actuator.pressure_b +=
        mix(k1.a.pressure_b, k2.a.pressure_b, k3.a.pressure_b, k4.a.pressure_b);
    x.theta += mix(k1.theta, k2.theta, k3.theta, k4.theta);
    x.omega += mix(k1.omega, k2.omega, k3.omega, k4.omega);
  }
}

}  // namespace hmpc::hydraulic
