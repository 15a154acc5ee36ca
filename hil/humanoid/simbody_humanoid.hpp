// The humanoid of common/include/hmpc/humanoid (same bodies, masses, centres of mass, inertias,
// joint axes and gravity) built in Simbody: the reference our own dynamics is validated against,
// and, on the same tree (simbody_tree.hpp), the HIL plant (hydraulic_humanoid.hpp). Simbody stays
// behind this interface (pimpl) so that only simbody_humanoid.cpp needs Simbody's headers and their
// -UNDEBUG (Debian 12's Simbody 3.7 crashes when code including its headers is built with NDEBUG
// and the library without it: their inline code then disagrees).
//
// The bodies, joints, sole contact and the mapping of coordinates are simbody_tree.hpp's. With
// T the orthogonal matrix u = T v (u_base = R v_base, R torso to world, on both halves) and
// Simbody's udot = d/dt(R v_base) = R (a_base + (0, omega x v_o)):
// M = T^T M_S T, c = T^T (c_S + M_S d), tau_S = T tau, a = T^T (udot - d),
// d = (0, 0, 0, R (omega x v_o), 0...).
//
// Reflected actuator inertia (Model::armature): Simbody has no such element, so the twin
// mirrors the rigid bodies only and refuses a model with armature; it and whatever is compared
// with it are built from rigid_parameters(). Our armature term is exact by construction (a
// constant on M's diagonal, dynamics.hpp) and tested on its own.

#pragma once

#include <array>
#include <memory>

#include "hmpc/humanoid/contact.hpp"
#include "hmpc/humanoid/model.hpp"

namespace hmpc::hil {

// The twin of BasicModel<ArmJoints> (model.hpp): the biped or the reaching robot.
template <int ArmJoints>
class BasicSimbodyHumanoid {
 public:
  using Model = humanoid::BasicModel<ArmJoints>;
  using ContactModel = humanoid::BasicContactModel<ArmJoints>;
  using Configuration = humanoid::BasicConfiguration<ArmJoints>;
  using Velocity = humanoid::BasicVelocity<ArmJoints>;
  using JointVector = humanoid::BasicJointVector<ArmJoints>;
  using MassMatrix = humanoid::BasicMassMatrix<ArmJoints>;
  using State = humanoid::BasicState<ArmJoints>;

  // `parameters` without armature: what the twin can mirror.
  static humanoid::Parameters rigid_parameters(
      humanoid::Parameters parameters = humanoid::Parameters{});

  // Throws std::invalid_argument if the model has armature.
  explicit BasicSimbodyHumanoid(const Model& model = Model(rigid_parameters()));
  // With ground contact at `contact`'s sole points, its parameters mapped as above.
  BasicSimbodyHumanoid(const Model& model, const ContactModel& contact);
  ~BasicSimbodyHumanoid();
  BasicSimbodyHumanoid(const BasicSimbodyHumanoid&) = delete;
  BasicSimbodyHumanoid& operator=(const BasicSimbodyHumanoid&) = delete;

  // Our q and v (model.hpp); the quaternion is normalised.
  void set_state(const Configuration& q, const Velocity& v);

  // Our q and v at the current state.
  State state();

  // In our coordinates, from Simbody's calcM, calcResidualForceIgnoringConstraints (zero udot,
  // gravity applied) and realize(Acceleration) with tau as applied mobility forces (and the
  // contact forces, if any).
  MassMatrix mass_matrix();
  Velocity bias_forces();
  Velocity forward_dynamics(const Velocity& tau);
  double kinetic_energy();

  // Advances the state by dt under gravity, the contact and the joint torques tau held over dt
  // (zero-order hold, as the host MPC's step map), with Simbody's error-controlled
  // Runge-Kutta-Merson.
  void step(const JointVector& tau, double dt);
  // Ground force on each sole point at the current state (world), indexed as ContactModel's
  // points (0-3 left foot, 4-7 right); zero without contact.
  std::array<humanoid::Vector3, humanoid::kSolePoints> sole_forces();
  // Integrator steps taken by step() so far.
  int integrator_steps() const;

 private:
  static constexpr int kJoints = humanoid::Dimensions<ArmJoints>::kJoints;
  static constexpr int kDofs = humanoid::Dimensions<ArmJoints>::kDofs;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

using SimbodyHumanoid = BasicSimbodyHumanoid<0>;
using SimbodyArmHumanoid = BasicSimbodyHumanoid<1>;

}  // namespace hmpc::hil
