// The humanoid of host/humanoid (same bodies, masses, centres of mass, inertias, joint axes
// and gravity) built in Simbody: the reference our own dynamics is validated against, and
// later the HIL plant. Simbody stays behind this interface (pimpl) so that only
// simbody_humanoid.cpp needs Simbody's headers and their -UNDEBUG (DESIGN.md §5).
//
// Coordinate mapping, ours -> Simbody (all conversions happen here; callers use ours):
//  - Torso: MobilizedBody::Free, q = (quaternion w x y z, p) and u = (omega, v_origin), both
//    expressed in the ground frame. Ours: q = (p, quaternion w x y z), v = (omega, v_origin) in
//    torso coordinates. So u_base = R v_base (R torso-to-world, block-diagonal on both
//    halves), and Simbody's udot = d/dt(R v_base) = R (a_base + (0, omega x v_o)).
//  - Hip: MobilizedBody::Universal (first about the abduction axis, then about the rotated
//    flexion axis) replaces our massless hip link and its two revolute joints.
//  - Knee and ankle: MobilizedBody::Pin with its z axis along our joint axis.
//  - Joint coordinates are the same angles; Simbody orders q and u by tree level, so the
//    index of each is looked up once.
// With T the orthogonal matrix u = T v: M = T^T M_S T, c = T^T (c_S + M_S d), tau_S = T tau,
// a = T^T (udot - d), d = (0, 0, 0, R (omega x v_o), 0...).
#pragma once

#include <memory>

#include "hmpc/humanoid/model.hpp"

namespace hmpc::hil {

class SimbodyHumanoid {
 public:
  explicit SimbodyHumanoid(const humanoid::Model& model = humanoid::Model{});
  ~SimbodyHumanoid();
  SimbodyHumanoid(const SimbodyHumanoid&) = delete;
  SimbodyHumanoid& operator=(const SimbodyHumanoid&) = delete;

  // Our q and v (model.hpp); the quaternion is normalised.
  void set_state(const humanoid::Configuration& q, const humanoid::Velocity& v);

  // In our coordinates, from Simbody's calcM, calcResidualForceIgnoringConstraints (zero udot,
  // gravity applied) and realize(Acceleration) with tau as applied mobility forces.
  humanoid::MassMatrix mass_matrix();
  humanoid::Velocity bias_forces();
  humanoid::Velocity forward_dynamics(const humanoid::Velocity& tau);
  double kinetic_energy();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace hmpc::hil
