// The one-joint HIL bench's plant in Simbody: a hydraulic joint actuator
// (common/include/hmpc/models/hydraulic_joint.hpp) swinging a rigid link that hangs under
// gravity (the load of models/hydraulic_pendulum.hpp), with mechanical end stops. Simbody
// supplies the multibody dynamics, the integration and the state, which holds the spool
// opening and both chamber pressures as continuous variables. Scale factors give plant-model
// mismatch.
//
// Simbody stays behind this interface (pimpl), so that only simbody_joint.cpp needs Simbody's
// headers and their -UNDEBUG (Debian 12's Simbody 3.7 crashes when code
// including its headers is built with NDEBUG and the library without it: their inline code
// then disagrees).
#pragma once

#include <cstdint>
#include <memory>

#include "hmpc/models/hydraulic_pendulum.hpp"

namespace hmpc::hil {

// Plant-model mismatch: the plant's load mass (and with it its inertia), the actuator's bulk
// modulus and valve flow gain, and its seal friction are the nominal ones times these factors,
// each finite and in [0.5, 2].
struct JointMismatch {
  double load_scale = 1, bulk_modulus_scale = 1, valve_flow_gain_scale = 1, friction_scale = 1;
};

class SimbodyHydraulicJoint {
 public:
  static constexpr double kStep = 0.001;  // s, one plant step
  // The end stops: just inside the cylinder's stroke (+-1.14 rad for the nominal actuator).
  static constexpr double kStopAngle = 1.1;  // rad

  // Throws std::invalid_argument naming the field if the mismatch is out of range or the
  // initial state is not finite, has a negative pressure or lies outside the stops.
  SimbodyHydraulicJoint(const hydraulic::JointActuatorParameters<double>& actuator,
                        const hydraulic::PendulumLoad<double>& load, const JointMismatch& mismatch,
                        const hydraulic::PendulumState<double>& initial);
  ~SimbodyHydraulicJoint();
  SimbodyHydraulicJoint(const SimbodyHydraulicJoint&) = delete;
  SimbodyHydraulicJoint& operator=(const SimbodyHydraulicJoint&) = delete;

  // Advances kStep with the valve command u held (clamped to [-1, 1]); a command that is not
  // finite centres the valve and is counted in rejected_commands().
  void step(double u);
  // An external torque on the link (a push), N·m, from now on until changed.
  void set_disturbance(double torque);

  hydraulic::PendulumState<double> state() const;
  double torque() const;  // N·m, the actuator's on the joint (what a load cell measures)
  double time() const;    // s since construction
  std::uint64_t rejected_commands() const;
  const hydraulic::JointActuatorParameters<double>& plant_actuator() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace hmpc::hil
