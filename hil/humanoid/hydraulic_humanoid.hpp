// The humanoid HIL plant: the biped in Simbody (simbody_tree.hpp: the twin's bodies, joints and
// sole contact) with its eight leg joints driven by hydraulic actuators
// (hmpc/models/hydraulic_joint.hpp, sized per joint in hmpc/humanoid/hydraulic_legs.hpp), end
// caps at the cylinders' strokes, and pushes. Each actuator's spool opening and chamber
// pressures are Simbody continuous states, its valve command a discrete one held over a step.
//
// Stepping. The sole friction (its slope mu F_n / v_t, 4.6e3 N s/m per standing point, on a
// 0.6 kg foot), the cylinders' seal friction, their oil springs and the orifices' flows are
// stiff: Simbody's error-controlled Runge-Kutta-Merson takes about 9 thousand steps per
// simulated second on the rigid robot alone (the twin's test), about the real time natively and
// 50 times slower in the QEMU guest where the HIL's vcan runs. So the plant steps 1 ms at a
// time by a linearly implicit Euler step on Simbody's own equations:
//   (M - h D - h^2 K) (u+ - u) = h f(q, u, z) + h^2 K u,   q+ = q + h N(q) u+
// with f the generalised forces of every element Simbody evaluates (gravity, Coriolis, the sole
// contact elements, the actuators' torques, the end caps, the pushes), M Simbody's mass matrix,
// and D, K the stiff elements' slopes in the generalised speeds (the sole points' friction,
// damping and Hertz stiffness through their station Jacobians; each actuator's seal friction
// and its oil spring over the step, h k_v, hydraulic_joint.hpp; an engaged end cap). The spool
// follows its first-order lag exactly; each chamber's pressure is stepped implicitly in its own
// orifice flow with the joint's new velocity. The slopes only set the step's stability: the
// forces are Simbody's. step_reference() integrates the same system with Runge-Kutta-Merson,
// the check of the implicit step (hydraulic_humanoid_test).
//
// Simbody stays behind this interface (pimpl), as in simbody_humanoid.hpp.
#pragma once

#include <array>
#include <cstdint>
#include <memory>

#include "hmpc/humanoid/contact.hpp"
#include "hmpc/humanoid/model.hpp"
#include "hmpc/models/hydraulic_joint.hpp"

namespace hmpc::hil {

// Plant-model mismatch, each a factor on the nominal robot in [0.5, 2]: every body's mass (and
// with it its inertia), every body's inertia on top of that, the cylinders' seal friction, and
// the actuators' bulk modulus and valve flow gain.
struct HumanoidMismatch {
  double mass_scale = 1, inertia_scale = 1, joint_friction_scale = 1;
  double bulk_modulus_scale = 1, valve_flow_gain_scale = 1;
};

// A push: `force` [N, world] on `body`'s centre of mass (model.hpp's body index) from `start`
// for `duration` seconds of plant time.
struct Push {
  int body = 0;
  humanoid::Vector3 force = humanoid::Vector3::Zero();
  double start = 0.0, duration = 0.0;
};

class SimbodyHydraulicHumanoid {
 public:
  static constexpr double kStep = 0.001;  // s, one plant step
  using ActuatorStates = std::array<hydraulic::JointActuatorState<double>, humanoid::kJoints>;
  using Actuators = std::array<hydraulic::JointActuatorParameters<double>, humanoid::kJoints>;

  // The nominal robot `parameters` (its armature is left out: a hydraulic joint has no geared
  // rotor) on the ground of `contact`, mismatched, at rest or moving at `initial`, the valves
  // centred and each actuator torque-free (both chambers balanced at half the supply on the rod
  // side). Throws std::invalid_argument naming what is wrong: a factor out of range, an initial
  // state that is not finite or has a joint beyond its end caps.
  SimbodyHydraulicHumanoid(const humanoid::Parameters& parameters,
                           const humanoid::ContactParameters& contact,
                           const HumanoidMismatch& mismatch,
                           const humanoid::BasicState<0>& initial);
  ~SimbodyHydraulicHumanoid();
  SimbodyHydraulicHumanoid(const SimbodyHydraulicHumanoid&) = delete;
  SimbodyHydraulicHumanoid& operator=(const SimbodyHydraulicHumanoid&) = delete;

  // Advances kStep with the valve commands held (each clamped to [-1, 1]); a command that is
  // not finite centres its valve and is counted in rejected_commands().
  void step(const humanoid::JointVector& valve_commands);
  // The same system over `duration` by Simbody's error-controlled Runge-Kutta-Merson (accuracy
  // 1e-6): the reference the implicit step is checked against.
  void step_reference(const humanoid::JointVector& valve_commands, double duration);

  // Adds a push to those acting (pushes add up while they overlap).
  void push(const Push& push);

  humanoid::BasicState<0> state() const;  // ours (model.hpp)
  // (v_end - v_start) / kStep of the last step(), ours: the IMU's acceleration.
  const humanoid::Velocity& acceleration() const;
  // The actuators' torques on the joints [N m]: what a load cell in each linkage reads.
  humanoid::JointVector joint_torques() const;
  ActuatorStates actuators() const;
  // The plant's own actuators (the mismatch applied), joint order.
  const Actuators& plant_actuators() const;
  // Ground force on each sole point (world), ContactModel's order.
  std::array<humanoid::Vector3, humanoid::kSolePoints> sole_forces() const;
  double time() const;  // s since construction
  std::uint64_t rejected_commands() const;
  // The plant's model: the nominal parameters mismatched, without armature.
  const humanoid::Model& model() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace hmpc::hil
