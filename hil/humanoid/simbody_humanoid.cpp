#include "simbody_humanoid.hpp"

#include <Simbody.h>

#include <Eigen/Geometry>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace hmpc::hil {
namespace {

using namespace hmpc::humanoid;

SimTK::Vec3 vec3(const Vector3& x) { return SimTK::Vec3(x.x(), x.y(), x.z()); }

SimTK::Body::Rigid rigid_body(const Body& b) {
  SimTK::Mat33 central;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) central(r, c) = b.inertia(r, c);
  }
  // Simbody wants the inertia about the body origin, which lies at -com from the CoM.
  const SimTK::Inertia about_origin =
      SimTK::Inertia(central).shiftFromMassCenter(-vec3(b.com), b.mass);
  return SimTK::Body::Rigid(SimTK::MassProperties(b.mass, vec3(b.com), about_origin));
}

// SmoothSphereHalfSpaceForce's smoothing constants, at Simbody's defaults (its header): they
// shape the force within ~3 mm of touching (cf the floor sqrt(cf) of the Hertz penetration
// and of the slip speed, bd the tanh of the Hertz force, bv that of the Hunt-Crossley clamp),
// as our softplus length s = 1 mm does. Their effect at the standing sink is calibrated away
// in hertz_modulus().
constexpr double kSmoothingConstant = 1e-5;  // cf [m^2]
constexpr double kHertzSmoothing = 300.0;    // bd [1/m]
constexpr double kClampSmoothing = 50.0;     // bv [s/m]
// Sphere radius (choice): small against the 17 x 8.7 cm sole, so a sphere's lowest point
// stays within R sin(10 deg) = 1.7 mm of our sole point for a foot tilted by 10 degrees.
constexpr double kSphereRadius = 0.01;  // [m]
// Integrator accuracy: relative, per step, as the forearm plant's (simbody_forearm.cpp). The
// stiff sole friction (mu F_n / v_s = 4.6e3 N s/m per standing point) keeps Runge-Kutta-Merson
// at 8-12 steps per 1 ms when standing (humanoid_contact_simbody_test prints the count).
constexpr double kAccuracy = 1e-6;

// Simbody's smoothed Hertz force of a sphere of radius R at penetration delta (its header):
//   F = (4/3) kappa sqrt(R kappa) (delta^2 + cf)^(3/4) (1 + tanh(bd delta)) / 2,
//   kappa = E^(2/3) / 2.
// The plane-strain modulus E that gives F = W / 8 at our standing sink delta = W / (8 k).
double hertz_modulus(double weight, const humanoid::ContactParameters& ours) {
  const double load = weight / humanoid::kSolePoints;
  const double sink = load / ours.stiffness;
  const double shape = 4.0 / 3.0 * std::sqrt(kSphereRadius) *
                       std::pow(sink * sink + kSmoothingConstant, 0.75) * 0.5 *
                       (1.0 + std::tanh(kHertzSmoothing * sink));
  const double kappa = std::pow(load / shape, 2.0 / 3.0);
  return std::pow(2.0 * kappa, 1.5);
}

// The model, if the twin can mirror it (no armature, see simbody_humanoid.hpp).
template <class Model>
const Model& require_rigid(const Model& model) {
  if (!model.armature.isZero(0.0)) {
    throw std::invalid_argument(
        "SimbodyHumanoid: the model has joint armature, which Simbody cannot mirror; build it "
        "from SimbodyHumanoid::rigid_parameters()");
  }
  return model;
}

}  // namespace

template <int ArmJoints>
struct BasicSimbodyHumanoid<ArmJoints>::Impl {
  using D = Dimensions<ArmJoints>;
  SimTK::MultibodySystem system;
  SimTK::SimbodyMatterSubsystem matter{system};
  SimTK::GeneralForceSubsystem forces{system};
  SimTK::Force::Gravity gravity;
  SimTK::Force::DiscreteForces applied{forces, matter};
  SimTK::MobilizedBody::Free torso;
  std::array<SimTK::MobilizedBody, D::kBodies> body;  // ours -> Simbody's; none for the hip links
  std::vector<SimTK::Force> soles;                    // the contact elements, ContactModel's order
  std::vector<SimTK::MobilizedBodyIndex> sole_body;
  SimTK::State state;
  std::unique_ptr<SimTK::RungeKuttaMersonIntegrator> integrator;  // made by the first step()
  bool restart = true;  // the integrator must start from `state` (set_state() changed it)
  std::array<SimTK::MobilizedBody, kJoints> joint;  // the mobilizer of each of our joints
  std::array<int, kJoints> joint_q{}, joint_u{};    // Simbody index of each of our joints
  int base_q = 0, base_u = 0;
  MassMatrix to_simbody;                        // T: u = T v
  Eigen::Matrix<double, kDofs, 1> udot_offset;  // d: udot = T a + d

  Impl(const Model& model, const ContactModel* contact)
      : gravity(forces, matter, vec3(require_rigid(model).gravity)),
        torso(matter.Ground(), SimTK::Transform(), rigid_body(model.bodies[0]),
              SimTK::Transform()) {
    for (int side = 0; side < 2; ++side) {
      const Body& hip = model.bodies[Model::body_of(side, kHipAbduction)];
      const Body& thigh = model.bodies[Model::body_of(side, kHipFlexion)];
      const Body& shank = model.bodies[Model::body_of(side, kKnee)];
      const Body& foot = model.bodies[Model::body_of(side, kAnkle)];
      // Universal: x of its frames along the abduction axis, y along the flexion axis.
      const SimTK::Rotation hip_frame(SimTK::UnitVec3(vec3(hip.axis)), SimTK::XAxis,
                                      vec3(thigh.axis), SimTK::YAxis);
      SimTK::MobilizedBody::Universal thigh_body(
          torso, SimTK::Transform(hip_frame, vec3(hip.joint_origin)), rigid_body(thigh),
          SimTK::Transform(hip_frame, vec3(thigh.joint_origin)));
      // Pin: z of its frames along the joint axis.
      const SimTK::Rotation knee_frame(SimTK::UnitVec3(vec3(shank.axis)), SimTK::ZAxis);
      SimTK::MobilizedBody::Pin shank_body(
          thigh_body, SimTK::Transform(knee_frame, vec3(shank.joint_origin)), rigid_body(shank),
          SimTK::Transform(knee_frame, SimTK::Vec3(0)));
      const SimTK::Rotation ankle_frame(SimTK::UnitVec3(vec3(foot.axis)), SimTK::ZAxis);
      SimTK::MobilizedBody::Pin foot_body(
          shank_body, SimTK::Transform(ankle_frame, vec3(foot.joint_origin)), rigid_body(foot),
          SimTK::Transform(ankle_frame, SimTK::Vec3(0)));
      joint[side * kJointsPerLeg + kHipAbduction] = thigh_body;
      joint[side * kJointsPerLeg + kKnee] = shank_body;
      joint[side * kJointsPerLeg + kAnkle] = foot_body;
      body[Model::body_of(side, kHipFlexion)] = thigh_body;
      body[Model::body_of(side, kKnee)] = shank_body;
      body[Model::body_of(side, kAnkle)] = foot_body;
    }
    if constexpr (ArmJoints == 1) {
      const Body& arm = model.bodies[D::kArmBody];
      const SimTK::Rotation shoulder_frame(SimTK::UnitVec3(vec3(arm.axis)), SimTK::ZAxis);
      SimTK::MobilizedBody::Pin arm_body(
          torso, SimTK::Transform(shoulder_frame, vec3(arm.joint_origin)), rigid_body(arm),
          SimTK::Transform(shoulder_frame, SimTK::Vec3(0)));
      joint[D::kArmJoint] = arm_body;
      body[D::kArmBody] = arm_body;
    }
    body[0] = torso;
    if (contact != nullptr) add_ground_contact(model, *contact);
    state = system.realizeTopology();
    if (state.getNQ() != D::kConfigurationSize || state.getNU() != kDofs) {
      throw std::logic_error("SimbodyHumanoid: unexpected number of coordinates");
    }
    base_q = torso.getFirstQIndex(state);
    base_u = torso.getFirstUIndex(state);
    for (int j = 0; j < kJoints; ++j) {
      if (joint[j].isEmptyHandle()) continue;
      joint_q[j] = joint[j].getFirstQIndex(state);
      joint_u[j] = joint[j].getFirstUIndex(state);
    }
    // The Universal's second coordinate is hip flexion.
    for (int side = 0; side < 2; ++side) {
      const int abduction = side * kJointsPerLeg + kHipAbduction;
      joint_q[abduction + 1] = joint_q[abduction] + 1;
      joint_u[abduction + 1] = joint_u[abduction] + 1;
    }
    to_simbody.setZero();
    for (int j = 0; j < kJoints; ++j) to_simbody(joint_u[j], kBaseDofs + j) = 1.0;
    udot_offset.setZero();
  }

  // One sphere per sole point, its lowest point at the point (Simbody's body frames are ours:
  // the mobilizers' frames only rotate the joint axes), against the ground's half space,
  // whose frame x axis is the inward normal, world -z.
  void add_ground_contact(const Model& model, const ContactModel& contact) {
    const ContactParameters& ours = contact.parameters();
    const double modulus = hertz_modulus(model.total_mass() * -model.gravity.z(), ours);
    const SimTK::Transform ground_half_space(
        SimTK::Rotation(SimTK::UnitVec3(0.0, 0.0, -1.0), SimTK::XAxis), SimTK::Vec3(0));
    for (int i = 0; i < kSolePoints; ++i) {
      const ContactPoint& point = contact.point(i);
      if (body[point.body].isEmptyHandle()) {
        throw std::invalid_argument("SimbodyHumanoid: a sole point on a massless hip link");
      }
      SimTK::SmoothSphereHalfSpaceForce sphere(forces);
      // Its damping term is (3/2) c_S delta_dot where ours is c delta_dot.
      sphere.setParameters(modulus, ours.damping / 1.5, ours.friction, ours.friction, 0.0,
                           ours.slip_velocity, kSmoothingConstant, kHertzSmoothing,
                           kClampSmoothing);
      sphere.setContactSphereBody(body[point.body]);
      sphere.setContactSphereLocationInBody(vec3(point.local) + SimTK::Vec3(0, 0, kSphereRadius));
      sphere.setContactSphereRadius(kSphereRadius);
      sphere.setContactHalfSpaceBody(matter.Ground());
      sphere.setContactHalfSpaceFrame(ground_half_space);
      soles.push_back(sphere);
      sole_body.push_back(body[point.body].getMobilizedBodyIndex());
    }
  }

  // After `state` changed: T and d for its orientation and velocity.
  void update_mapping() {
    const SimTK::Vector& sq = state.getQ();
    const Matrix3 R = Eigen::Quaterniond(sq[base_q], sq[base_q + 1], sq[base_q + 2], sq[base_q + 3])
                          .normalized()
                          .toRotationMatrix();
    to_simbody.template block<3, 3>(base_u, 0) = R;
    to_simbody.template block<3, 3>(base_u + 3, 3) = R;
    const Velocity v = to_simbody.transpose() * map(state.getU());
    udot_offset.template segment<3>(base_u + 3) =
        R * v.template head<3>().cross(v.template segment<3>(3));
  }

  Eigen::Map<const Eigen::Matrix<double, kDofs, 1>> map(const SimTK::Vector& x) const {
    return Eigen::Map<const Eigen::Matrix<double, kDofs, 1>>(&x[0]);
  }
};

template <int A>
Parameters BasicSimbodyHumanoid<A>::rigid_parameters(Parameters parameters) {
  parameters.armature.fill(0.0);
  parameters.arm_armature = 0.0;
  return parameters;
}

template <int A>
BasicSimbodyHumanoid<A>::BasicSimbodyHumanoid(const Model& model)
    : impl_(std::make_unique<Impl>(model, nullptr)) {}
template <int A>
BasicSimbodyHumanoid<A>::BasicSimbodyHumanoid(const Model& model, const ContactModel& contact)
    : impl_(std::make_unique<Impl>(model, &contact)) {}
template <int A>
BasicSimbodyHumanoid<A>::~BasicSimbodyHumanoid() = default;

template <int A>
void BasicSimbodyHumanoid<A>::set_state(const Configuration& q, const Velocity& v) {
  Impl& s = *impl_;
  const Eigen::Quaterniond orientation = Eigen::Quaterniond(q[3], q[4], q[5], q[6]).normalized();
  const Matrix3 R = orientation.toRotationMatrix();
  SimTK::Vector& sq = s.state.updQ();
  sq[s.base_q + 0] = orientation.w();
  sq[s.base_q + 1] = orientation.x();
  sq[s.base_q + 2] = orientation.y();
  sq[s.base_q + 3] = orientation.z();
  for (int k = 0; k < 3; ++k) sq[s.base_q + 4 + k] = q[k];
  for (int j = 0; j < kJoints; ++j) sq[s.joint_q[j]] = q[7 + j];

  s.to_simbody.template block<3, 3>(s.base_u, 0) = R;
  s.to_simbody.template block<3, 3>(s.base_u + 3, 3) = R;
  const Eigen::Matrix<double, kDofs, 1> u = s.to_simbody * v;
  SimTK::Vector& su = s.state.updU();
  for (int k = 0; k < kDofs; ++k) su[k] = u[k];
  s.udot_offset.template segment<3>(s.base_u + 3) =
      R * v.template head<3>().cross(v.template segment<3>(3));
  s.restart = true;
}

template <int A>
BasicState<A> BasicSimbodyHumanoid<A>::state() {
  Impl& s = *impl_;
  const SimTK::Vector& sq = s.state.getQ();
  State x;
  const Eigen::Quaterniond orientation =
      Eigen::Quaterniond(sq[s.base_q], sq[s.base_q + 1], sq[s.base_q + 2], sq[s.base_q + 3])
          .normalized();
  for (int k = 0; k < 3; ++k) x.q[k] = sq[s.base_q + 4 + k];
  x.q.template segment<4>(3) << orientation.w(), orientation.x(), orientation.y(), orientation.z();
  for (int j = 0; j < kJoints; ++j) x.q[7 + j] = sq[s.joint_q[j]];
  x.v = s.to_simbody.transpose() * s.map(s.state.getU());
  return x;
}

template <int A>
BasicMassMatrix<A> BasicSimbodyHumanoid<A>::mass_matrix() {
  Impl& s = *impl_;
  s.system.realize(s.state, SimTK::Stage::Position);
  SimTK::Matrix M;
  s.matter.calcM(s.state, M);
  MassMatrix M_s;
  for (int r = 0; r < kDofs; ++r) {
    for (int c = 0; c < kDofs; ++c) M_s(r, c) = M(r, c);
  }
  return s.to_simbody.transpose() * M_s * s.to_simbody;
}

template <int A>
BasicVelocity<A> BasicSimbodyHumanoid<A>::bias_forces() {
  Impl& s = *impl_;
  s.system.realize(s.state, SimTK::Stage::Velocity);
  const SimTK::Vector zero(kDofs, 0.0);
  SimTK::Vector residual;
  s.matter.calcResidualForceIgnoringConstraints(s.state, zero, s.gravity.getBodyForces(s.state),
                                                zero, residual);
  // Ours also carries the velocity-dependent part of Simbody's udot for the same a: M_S d.
  SimTK::Vector d(kDofs), M_d;
  for (int k = 0; k < kDofs; ++k) d[k] = s.udot_offset[k];
  s.matter.multiplyByM(s.state, d, M_d);
  return s.to_simbody.transpose() * (s.map(residual) + s.map(M_d));
}

template <int A>
BasicVelocity<A> BasicSimbodyHumanoid<A>::forward_dynamics(const Velocity& tau) {
  Impl& s = *impl_;
  const Eigen::Matrix<double, kDofs, 1> tau_s = s.to_simbody * tau;
  SimTK::Vector mobility_forces(kDofs);
  for (int k = 0; k < kDofs; ++k) mobility_forces[k] = tau_s[k];
  s.applied.setAllMobilityForces(s.state, mobility_forces);
  s.system.realize(s.state, SimTK::Stage::Acceleration);
  return s.to_simbody.transpose() * (s.map(s.state.getUDot()) - s.udot_offset);
}

template <int A>
double BasicSimbodyHumanoid<A>::kinetic_energy() {
  Impl& s = *impl_;
  s.system.realize(s.state, SimTK::Stage::Velocity);
  return s.matter.calcKineticEnergy(s.state);
}

template <int A>
void BasicSimbodyHumanoid<A>::step(const JointVector& tau, double dt) {
  Impl& s = *impl_;
  SimTK::Vector mobility_forces(kDofs, 0.0);
  for (int j = 0; j < kJoints; ++j) mobility_forces[s.joint_u[j]] = tau[j];
  if (!s.integrator) {
    s.integrator = std::make_unique<SimTK::RungeKuttaMersonIntegrator>(s.system);
    s.integrator->setAccuracy(kAccuracy);
    // Each step() ends on a step boundary, where the held torques may change.
    s.integrator->setAllowInterpolation(false);
  }
  if (s.restart) {
    s.applied.setAllMobilityForces(s.state, mobility_forces);
    s.integrator->initialize(s.state);
    s.restart = false;
  } else {
    s.applied.setAllMobilityForces(s.integrator->updAdvancedState(), mobility_forces);
    // A changed input starts a new continuous interval.
    s.integrator->reinitialize(SimTK::Stage::Dynamics, false);
  }
  // The first stepTo() after (re)initialising may only report the state, not advance it
  // (Debian 12's Simbody 3.7), hence the loop.
  const double target = s.integrator->getTime() + dt;
  while (s.integrator->getTime() < target) s.integrator->stepTo(target);
  s.state = s.integrator->getState();
  s.update_mapping();
}

template <int A>
std::array<Vector3, kSolePoints> BasicSimbodyHumanoid<A>::sole_forces() {
  Impl& s = *impl_;
  std::array<Vector3, kSolePoints> out;
  for (Vector3& f : out) f.setZero();
  if (s.soles.empty()) return out;
  s.system.realize(s.state, SimTK::Stage::Velocity);
  SimTK::Vector_<SimTK::SpatialVec> body_forces;
  SimTK::Vector_<SimTK::Vec3> particle_forces;
  SimTK::Vector mobility_forces;
  for (int i = 0; i < kSolePoints; ++i) {
    s.soles[i].calcForceContribution(s.state, body_forces, particle_forces, mobility_forces);
    const SimTK::Vec3& f = body_forces[s.sole_body[i]][1];  // on the foot, world
    out[i] = Vector3(f[0], f[1], f[2]);
  }
  return out;
}

template <int A>
int BasicSimbodyHumanoid<A>::integrator_steps() const {
  return impl_->integrator ? impl_->integrator->getNumStepsTaken() : 0;
}

template class BasicSimbodyHumanoid<0>;
template class BasicSimbodyHumanoid<1>;

}  // namespace hmpc::hil
