#include "simbody_tree.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <stdexcept>

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

}  // namespace

// Simbody's smoothed Hertz force of a sphere of radius R at penetration delta (its header):
//   F = (4/3) kappa sqrt(R kappa) (delta^2 + cf)^(3/4) (1 + tanh(bd delta)) / 2,
//   kappa = E^(2/3) / 2.
// The plane-strain modulus E that gives F = W / 8 at our standing sink delta = W / (8 k).
SoleContactLaw sole_contact_law(double weight, const ContactParameters& ours) {
  using L = SoleContactLaw;
  const double load = weight / kSolePoints;
  const double sink = load / ours.stiffness;
  const double shape = 4.0 / 3.0 * std::sqrt(L::kSphereRadius) *
                       std::pow(sink * sink + L::kSmoothingConstant, 0.75) * 0.5 *
                       (1.0 + std::tanh(L::kHertzSmoothing * sink));
  const double kappa = std::pow(load / shape, 2.0 / 3.0);
  SoleContactLaw law;
  law.modulus = std::pow(2.0 * kappa, 1.5);
  // Its damping term is (3/2) c_S delta_dot where ours is c delta_dot.
  law.dissipation = ours.damping / 1.5;
  law.friction = ours.friction;
  law.transition_velocity = ours.slip_velocity;
  return law;
}

template <int A>
SimbodyTree<A>::SimbodyTree(const Model& model)
    : gravity(forces, matter, vec3(model.gravity)),
      torso(matter.Ground(), SimTK::Transform(), rigid_body(model.bodies[0]), SimTK::Transform()) {
  for (int side = 0; side < 2; ++side) {
    const Body& hip = model.bodies[Model::body_of(side, kHipAbduction)];
    const Body& thigh = model.bodies[Model::body_of(side, kHipFlexion)];
    const Body& shank = model.bodies[Model::body_of(side, kKnee)];
    const Body& foot = model.bodies[Model::body_of(side, kAnkle)];
    // Universal: x of its frames along the abduction axis, y along the flexion axis.
    const SimTK::Rotation hip_frame(SimTK::UnitVec3(vec3(hip.axis)), SimTK::XAxis, vec3(thigh.axis),
                                    SimTK::YAxis);
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
    const int first = side * kJointsPerLeg;
    joint[first + kHipAbduction] = thigh_body;
    joint[first + kHipFlexion] = thigh_body;
    joint_coordinate[first + kHipFlexion] = 1;
    joint[first + kKnee] = shank_body;
    joint[first + kAnkle] = foot_body;
    body[Model::body_of(side, kHipFlexion)] = thigh_body;
    body[Model::body_of(side, kKnee)] = shank_body;
    body[Model::body_of(side, kAnkle)] = foot_body;
  }
  if constexpr (A == 1) {
    const Body& arm = model.bodies[D::kArmBody];
    const SimTK::Rotation shoulder_frame(SimTK::UnitVec3(vec3(arm.axis)), SimTK::ZAxis);
    SimTK::MobilizedBody::Pin arm_body(
        torso, SimTK::Transform(shoulder_frame, vec3(arm.joint_origin)), rigid_body(arm),
        SimTK::Transform(shoulder_frame, SimTK::Vec3(0)));
    joint[D::kArmJoint] = arm_body;
    body[D::kArmBody] = arm_body;
  }
  body[0] = torso;
}

// One sphere per sole point, its lowest point at the point (Simbody's body frames are ours: the
// mobilizers' frames only rotate the joint axes), against the ground's half space, whose frame
// x axis is the inward normal, world -z.
template <int A>
void SimbodyTree<A>::add_ground_contact(const Model& model, const ContactModel& contact) {
  using L = SoleContactLaw;
  const SoleContactLaw law =
      sole_contact_law(model.total_mass() * -model.gravity.z(), contact.parameters());
  const SimTK::Transform ground_half_space(
      SimTK::Rotation(SimTK::UnitVec3(0.0, 0.0, -1.0), SimTK::XAxis), SimTK::Vec3(0));
  for (int i = 0; i < kSolePoints; ++i) {
    const ContactPoint& point = contact.point(i);
    if (body[point.body].isEmptyHandle()) {
      throw std::invalid_argument("SimbodyHumanoid: a sole point on a massless hip link");
    }
    SimTK::SmoothSphereHalfSpaceForce sphere(forces);
    sphere.setParameters(law.modulus, law.dissipation, law.friction, law.friction, 0.0,
                         law.transition_velocity, L::kSmoothingConstant, L::kHertzSmoothing,
                         L::kClampSmoothing);
    sphere.setContactSphereBody(body[point.body]);
    sphere.setContactSphereLocationInBody(vec3(point.local) + SimTK::Vec3(0, 0, L::kSphereRadius));
    sphere.setContactSphereRadius(L::kSphereRadius);
    sphere.setContactHalfSpaceBody(matter.Ground());
    sphere.setContactHalfSpaceFrame(ground_half_space);
    soles.push_back(sphere);
    sole_body.push_back(body[point.body].getMobilizedBodyIndex());
  }
}

template <int A>
void SimbodyTree<A>::index(const SimTK::State& state) {
  if (state.getNQ() != D::kConfigurationSize || state.getNU() != kDofs) {
    throw std::logic_error("SimbodyHumanoid: unexpected number of coordinates");
  }
  base_q = torso.getFirstQIndex(state);
  base_u = torso.getFirstUIndex(state);
  for (int j = 0; j < kJoints; ++j) {
    joint_q[j] = joint[j].getFirstQIndex(state) + joint_coordinate[j];
    joint_u[j] = joint[j].getFirstUIndex(state) + joint_coordinate[j];
  }
}

template <int A>
void SimbodyTree<A>::set(SimTK::State& state, const Configuration& q, const Velocity& v) const {
  const Eigen::Quaterniond orientation = Eigen::Quaterniond(q[3], q[4], q[5], q[6]).normalized();
  const Matrix3 R = orientation.toRotationMatrix();
  SimTK::Vector& sq = state.updQ();
  sq[base_q + 0] = orientation.w();
  sq[base_q + 1] = orientation.x();
  sq[base_q + 2] = orientation.y();
  sq[base_q + 3] = orientation.z();
  for (int k = 0; k < 3; ++k) sq[base_q + 4 + k] = q[k];
  for (int j = 0; j < kJoints; ++j) sq[joint_q[j]] = q[7 + j];
  SimTK::Vector& su = state.updU();
  const Vector3 omega = R * v.template head<3>(), velocity = R * v.template segment<3>(3);
  for (int k = 0; k < 3; ++k) {
    su[base_u + k] = omega[k];
    su[base_u + 3 + k] = velocity[k];
  }
  for (int j = 0; j < kJoints; ++j) su[joint_u[j]] = v[6 + j];
}

template <int A>
Matrix3 SimbodyTree<A>::torso_rotation(const SimTK::State& state) const {
  const SimTK::Vector& sq = state.getQ();
  return Eigen::Quaterniond(sq[base_q], sq[base_q + 1], sq[base_q + 2], sq[base_q + 3])
      .normalized()
      .toRotationMatrix();
}

template <int A>
BasicConfiguration<A> SimbodyTree<A>::configuration(const SimTK::State& state) const {
  const SimTK::Vector& sq = state.getQ();
  const Eigen::Quaterniond orientation =
      Eigen::Quaterniond(sq[base_q], sq[base_q + 1], sq[base_q + 2], sq[base_q + 3]).normalized();
  Configuration q;
  for (int k = 0; k < 3; ++k) q[k] = sq[base_q + 4 + k];
  q.template segment<4>(3) << orientation.w(), orientation.x(), orientation.y(), orientation.z();
  for (int j = 0; j < kJoints; ++j) q[7 + j] = sq[joint_q[j]];
  return q;
}

template <int A>
BasicVelocity<A> SimbodyTree<A>::velocity(const SimTK::State& state) const {
  const Matrix3 R = torso_rotation(state);
  const SimTK::Vector& su = state.getU();
  Velocity v;
  const Vector3 omega(su[base_u], su[base_u + 1], su[base_u + 2]);
  const Vector3 velocity(su[base_u + 3], su[base_u + 4], su[base_u + 5]);
  v.template head<3>() = R.transpose() * omega;
  v.template segment<3>(3) = R.transpose() * velocity;
  for (int j = 0; j < kJoints; ++j) v[6 + j] = su[joint_u[j]];
  return v;
}

template struct SimbodyTree<0>;
template struct SimbodyTree<1>;

}  // namespace hmpc::hil
