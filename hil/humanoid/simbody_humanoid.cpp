#include "simbody_humanoid.hpp"

#include <Eigen/Geometry>
#include <Simbody.h>
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

struct SimbodyHumanoid::Impl {
  SimTK::MultibodySystem system;
  SimTK::SimbodyMatterSubsystem matter{system};
  SimTK::GeneralForceSubsystem forces{system};
  SimTK::Force::Gravity gravity;
  SimTK::Force::DiscreteForces applied{forces, matter};
  SimTK::MobilizedBody::Free torso;
  SimTK::State state;
  std::array<int, kJoints> joint_q{}, joint_u{};  // Simbody index of each of our joints
  int base_q = 0, base_u = 0;
  MassMatrix to_simbody;                          // T: u = T v
  Eigen::Matrix<double, kDofs, 1> udot_offset;    // d: udot = T a + d

  explicit Impl(const Model& model)
      : gravity(forces, matter, vec3(model.gravity)),
        torso(matter.Ground(), SimTK::Transform(), rigid_body(model.bodies[0]), SimTK::Transform()) {
    std::array<SimTK::MobilizedBody, 2 * kJointsPerLeg> leg;
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
      leg[side * kJointsPerLeg + 0] = thigh_body;
      leg[side * kJointsPerLeg + 2] = shank_body;
      leg[side * kJointsPerLeg + 3] = foot_body;
    }
    state = system.realizeTopology();
    if (state.getNQ() != kConfigurationSize || state.getNU() != kDofs) {
      throw std::logic_error("SimbodyHumanoid: unexpected number of coordinates");
    }
    base_q = torso.getFirstQIndex(state);
    base_u = torso.getFirstUIndex(state);
    for (int side = 0; side < 2; ++side) {
      for (int j : {kHipAbduction, kKnee, kAnkle}) {
        const int ours = side * kJointsPerLeg + j;
        joint_q[ours] = leg[ours].getFirstQIndex(state);
        joint_u[ours] = leg[ours].getFirstUIndex(state);
      }
      // The Universal's second coordinate is hip flexion.
      const int abduction = side * kJointsPerLeg + kHipAbduction;
      joint_q[abduction + 1] = joint_q[abduction] + 1;
      joint_u[abduction + 1] = joint_u[abduction] + 1;
    }
    to_simbody.setZero();
    for (int j = 0; j < kJoints; ++j) to_simbody(joint_u[j], kBaseDofs + j) = 1.0;
    udot_offset.setZero();
  }

  Eigen::Map<const Eigen::Matrix<double, kDofs, 1>> map(const SimTK::Vector& x) const {
    return Eigen::Map<const Eigen::Matrix<double, kDofs, 1>>(&x[0]);
  }
};

SimbodyHumanoid::SimbodyHumanoid(const Model& model) : impl_(std::make_unique<Impl>(model)) {}
SimbodyHumanoid::~SimbodyHumanoid() = default;

void SimbodyHumanoid::set_state(const Configuration& q, const Velocity& v) {
  Impl& s = *impl_;
  const Eigen::Quaterniond orientation =
      Eigen::Quaterniond(q[3], q[4], q[5], q[6]).normalized();
  const Matrix3 R = orientation.toRotationMatrix();
  SimTK::Vector& sq = s.state.updQ();
  sq[s.base_q + 0] = orientation.w();
  sq[s.base_q + 1] = orientation.x();
  sq[s.base_q + 2] = orientation.y();
  sq[s.base_q + 3] = orientation.z();
  for (int k = 0; k < 3; ++k) sq[s.base_q + 4 + k] = q[k];
  for (int j = 0; j < kJoints; ++j) sq[s.joint_q[j]] = q[7 + j];

  s.to_simbody.block<3, 3>(s.base_u, 0) = R;
  s.to_simbody.block<3, 3>(s.base_u + 3, 3) = R;
  const Eigen::Matrix<double, kDofs, 1> u = s.to_simbody * v;
  SimTK::Vector& su = s.state.updU();
  for (int k = 0; k < kDofs; ++k) su[k] = u[k];
  s.udot_offset.segment<3>(s.base_u + 3) = R * v.head<3>().cross(v.segment<3>(3));
}

MassMatrix SimbodyHumanoid::mass_matrix() {
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

Velocity SimbodyHumanoid::bias_forces() {
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

Velocity SimbodyHumanoid::forward_dynamics(const Velocity& tau) {
  Impl& s = *impl_;
  const Eigen::Matrix<double, kDofs, 1> tau_s = s.to_simbody * tau;
  SimTK::Vector mobility_forces(kDofs);
  for (int k = 0; k < kDofs; ++k) mobility_forces[k] = tau_s[k];
  s.applied.setAllMobilityForces(s.state, mobility_forces);
  s.system.realize(s.state, SimTK::Stage::Acceleration);
  return s.to_simbody.transpose() * (s.map(s.state.getUDot()) - s.udot_offset);
}

double SimbodyHumanoid::kinetic_energy() {
  Impl& s = *impl_;
  s.system.realize(s.state, SimTK::Stage::Velocity);
  return s.matter.calcKineticEnergy(s.state);
}

}  // namespace hmpc::hil
