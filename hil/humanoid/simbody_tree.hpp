// The humanoid's bodies, joints and sole contact in Simbody, and the mapping of its coordinates
// to ours: what the twin (simbody_humanoid.hpp) and the HIL plant (hydraulic_humanoid.hpp) both
// build. Internal to hil/humanoid: it includes Simbody, so only .cpp files built with -UNDEBUG
// include it (simbody_humanoid.hpp says why).
//
// Coordinate mapping, ours -> Simbody:
//  - Torso: MobilizedBody::Free, q = (quaternion w x y z, p) and u = (omega, v_origin), both
//    expressed in the ground frame. Ours: q = (p, quaternion w x y z), v = (omega, v_origin) in
//    torso coordinates. So u_base = R v_base (R torso-to-world, block-diagonal on both halves).
//  - Hip: MobilizedBody::Universal (first about the abduction axis, then about the rotated
//    flexion axis) replaces our massless hip link and its two revolute joints.
//  - Knee and ankle, and the reaching variant's shoulder: MobilizedBody::Pin with its z axis
//    along our joint axis.
//  - Joint coordinates are the same angles; Simbody orders q and u by tree level, so the index
//    of each is looked up once (index()).
//
// Ground contact: the 8 sole points of our ContactModel (contact.hpp, the one source of their
// positions), each a small sphere against the ground half space z < 0 in Simbody's own smooth
// Hunt-Crossley element SmoothSphereHalfSpaceForce (in Simbody 3.7, by G. Serrancoli and
// A. Falisse). The laws differ in form:
//   ours (C2)  F = k delta (1 + c delta_dot)                linear spring
//   Simbody    F = K delta^(3/2) (1 + (3/2) c_S delta_dot)   Hertz sphere, K from E and R
// so their parameters are mapped to agree where standing puts them (sole_contact_law()):
//  - stiffness: the modulus E that sinks a point by our W / (8 k) under the standing load
//    W / 8 (Simbody's smoothing factors included), so the static pose is the same; Hertz is
//    then about 3/2 as stiff as ours for small motions about it (dF/ddelta = 1.5 F / delta);
//  - dissipation: c_S = c / 1.5, the same damping k delta c per point at the same load;
//  - friction: static = dynamic = mu, transition velocity = v_s: the same Coulomb limit and
//    the same viscous slope mu F_n / v_s below it (Simbody's friction is linear up to v_s and
//    flat beyond it, ours saturates smoothly).
// Simbody applies a point's force at the sphere's lowest point raised by half the penetration
// (its source, after Sherman et al. 2011), ours at the sole point itself: 5 mm higher at the
// standing sink, which only moves where friction acts. The chair (motion IV) is not mirrored.
#pragma once

#include <Simbody.h>

#include <array>
#include <vector>

#include "hmpc/humanoid/contact.hpp"
#include "hmpc/humanoid/model.hpp"

namespace hmpc::hil {

// SmoothSphereHalfSpaceForce's parameters for our contact, and its sphere's radius.
struct SoleContactLaw {
  // Its smoothing constants at Simbody's defaults (its header): they shape the force within
  // ~3 mm of touching (cf the floor sqrt(cf) of the Hertz penetration and of the slip speed,
  // bd the tanh of the Hertz force, bv that of the Hunt-Crossley clamp), as our softplus length
  // s = 1 mm does. Their effect at the standing sink is calibrated away in the modulus.
  static constexpr double kSmoothingConstant = 1e-5;  // cf [m^2]
  static constexpr double kHertzSmoothing = 300.0;    // bd [1/m]
  static constexpr double kClampSmoothing = 50.0;     // bv [s/m]
  // Sphere radius (choice): small against the 17 x 8.7 cm sole, so a sphere's lowest point
  // stays within R sin(10 deg) = 1.7 mm of our sole point for a foot tilted by 10 degrees.
  static constexpr double kSphereRadius = 0.01;  // [m]

  double modulus = 0.0;              // E, plane strain [Pa]
  double dissipation = 0.0;          // c_S [s/m]
  double friction = 0.0;             // mu, static and dynamic
  double transition_velocity = 0.0;  // v_t [m/s]
};
// The law that agrees with `ours` under the standing load `weight` [N] (see the top).
SoleContactLaw sole_contact_law(double weight, const humanoid::ContactParameters& ours);

template <int ArmJoints>
struct SimbodyTree {
  using Model = humanoid::BasicModel<ArmJoints>;
  using ContactModel = humanoid::BasicContactModel<ArmJoints>;
  using Configuration = humanoid::BasicConfiguration<ArmJoints>;
  using Velocity = humanoid::BasicVelocity<ArmJoints>;
  using D = humanoid::Dimensions<ArmJoints>;
  static constexpr int kJoints = D::kJoints;
  static constexpr int kDofs = D::kDofs;

  SimTK::MultibodySystem system;
  SimTK::SimbodyMatterSubsystem matter{system};
  SimTK::GeneralForceSubsystem forces{system};
  SimTK::Force::Gravity gravity;
  SimTK::MobilizedBody::Free torso;
  std::array<SimTK::MobilizedBody, D::kBodies> body;  // ours -> Simbody's; none for the hip links
  std::array<SimTK::MobilizedBody, kJoints> joint;    // the mobilizer of each of our joints
  // Which of its mobilizer's coordinates each joint is (the Universal's second is hip flexion).
  std::array<int, kJoints> joint_coordinate{};
  std::vector<SimTK::SmoothSphereHalfSpaceForce>
      soles;  // the contact elements, ContactModel's order
  std::vector<SimTK::MobilizedBodyIndex> sole_body;
  // Simbody's index of each joint's q and u, and of the torso's first (after index()).
  std::array<int, kJoints> joint_q{}, joint_u{};
  int base_q = 0, base_u = 0;

  explicit SimbodyTree(const Model& model);
  SimbodyTree(const SimbodyTree&) = delete;
  SimbodyTree& operator=(const SimbodyTree&) = delete;

  // One SmoothSphereHalfSpaceForce per sole point (see the top). Before realizeTopology().
  void add_ground_contact(const Model& model, const ContactModel& contact);
  // After realizeTopology(): looks up the coordinates' indices; throws std::logic_error if the
  // system's coordinates are not the model's.
  void index(const SimTK::State& state);

  // Our q and v into `state`'s Q and U (the quaternion normalised), and back.
  void set(SimTK::State& state, const Configuration& q, const Velocity& v) const;
  Configuration configuration(const SimTK::State& state) const;
  Velocity velocity(const SimTK::State& state) const;
  // R of the torso (torso to world) at `state`'s Q.
  humanoid::Matrix3 torso_rotation(const SimTK::State& state) const;
};

}  // namespace hmpc::hil
