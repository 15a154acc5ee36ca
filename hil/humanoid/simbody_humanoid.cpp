#include "simbody_humanoid.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "simbody_tree.hpp"

namespace hmpc::hil {
namespace {

using namespace hmpc::humanoid;

// Integrator accuracy: relative, per step, as the forearm plant's (simbody_forearm.cpp). The
// stiff sole friction (mu F_n / v_s = 4.6e3 N s/m per standing point) keeps Runge-Kutta-Merson
// at 8-12 steps per 1 ms when standing (humanoid_contact_simbody_test prints the count).
constexpr double kAccuracy = 1e-6;

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
  SimbodyTree<ArmJoints> tree;
  SimTK::Force::DiscreteForces applied{tree.forces, tree.matter};
  SimTK::State state;
  std::unique_ptr<SimTK::RungeKuttaMersonIntegrator> integrator;  // made by the first step()
  bool restart = true;    // the integrator must start from `state` (set_state() changed it)
  MassMatrix to_simbody;  // T: u = T v
  Eigen::Matrix<double, kDofs, 1> udot_offset;  // d: udot = T a + d

  Impl(const Model& model, const ContactModel* contact) : tree(require_rigid(model)) {
    if (contact != nullptr) tree.add_ground_contact(model, *contact);
    state = tree.system.realizeTopology();
    tree.index(state);
    to_simbody.setZero();
    for (int j = 0; j < kJoints; ++j) to_simbody(tree.joint_u[j], kBaseDofs + j) = 1.0;
    udot_offset.setZero();
  }

  // After `state` changed: T and d for its orientation and velocity.
  void update_mapping() {
    const Matrix3 R = tree.torso_rotation(state);
    to_simbody.template block<3, 3>(tree.base_u, 0) = R;
    to_simbody.template block<3, 3>(tree.base_u + 3, 3) = R;
    const Velocity v = tree.velocity(state);
    udot_offset.template segment<3>(tree.base_u + 3) =
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
  s.tree.set(s.state, q, v);
  s.update_mapping();
  s.restart = true;
}

template <int A>
BasicState<A> BasicSimbodyHumanoid<A>::state() {
  Impl& s = *impl_;
  State x;
  x.q = s.tree.configuration(s.state);
  x.v = s.tree.velocity(s.state);
  return x;
}

template <int A>
BasicMassMatrix<A> BasicSimbodyHumanoid<A>::mass_matrix() {
  Impl& s = *impl_;
  s.tree.system.realize(s.state, SimTK::Stage::Position);
  SimTK::Matrix M;
  s.tree.matter.calcM(s.state, M);
  MassMatrix M_s;
  for (int r = 0; r < kDofs; ++r) {
    for (int c = 0; c < kDofs; ++c) M_s(r, c) = M(r, c);
  }
  return s.to_simbody.transpose() * M_s * s.to_simbody;
}

template <int A>
BasicVelocity<A> BasicSimbodyHumanoid<A>::bias_forces() {
  Impl& s = *impl_;
  s.tree.system.realize(s.state, SimTK::Stage::Velocity);
  const SimTK::Vector zero(kDofs, 0.0);
  SimTK::Vector residual;
  s.tree.matter.calcResidualForceIgnoringConstraints(
      s.state, zero, s.tree.gravity.getBodyForces(s.state), zero, residual);
  // Ours also carries the velocity-dependent part of Simbody's udot for the same a: M_S d.
  SimTK::Vector d(kDofs), M_d;
  for (int k = 0; k < kDofs; ++k) d[k] = s.udot_offset[k];
  s.tree.matter.multiplyByM(s.state, d, M_d);
  return s.to_simbody.transpose() * (s.map(residual) + s.map(M_d));
}

template <int A>
BasicVelocity<A> BasicSimbodyHumanoid<A>::forward_dynamics(const Velocity& tau) {
  Impl& s = *impl_;
  const Eigen::Matrix<double, kDofs, 1> tau_s = s.to_simbody * tau;
  SimTK::Vector mobility_forces(kDofs);
  for (int k = 0; k < kDofs; ++k) mobility_forces[k] = tau_s[k];
  s.applied.setAllMobilityForces(s.state, mobility_forces);
  s.tree.system.realize(s.state, SimTK::Stage::Acceleration);
  return s.to_simbody.transpose() * (s.map(s.state.getUDot()) - s.udot_offset);
}

template <int A>
double BasicSimbodyHumanoid<A>::kinetic_energy() {
  Impl& s = *impl_;
  s.tree.system.realize(s.state, SimTK::Stage::Velocity);
  return s.tree.matter.calcKineticEnergy(s.state);
}

template <int A>
void BasicSimbodyHumanoid<A>::step(const JointVector& tau, double dt) {
  Impl& s = *impl_;
  SimTK::Vector mobility_forces(kDofs, 0.0);
  for (int j = 0; j < kJoints; ++j) mobility_forces[s.tree.joint_u[j]] = tau[j];
  if (!s.integrator) {
    s.integrator = std::make_unique<SimTK::RungeKuttaMersonIntegrator>(s.tree.system);
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
  if (s.tree.soles.empty()) return out;
  s.tree.system.realize(s.state, SimTK::Stage::Velocity);
  SimTK::Vector_<SimTK::SpatialVec> body_forces;
  SimTK::Vector_<SimTK::Vec3> particle_forces;
  SimTK::Vector mobility_forces;
  for (int i = 0; i < kSolePoints; ++i) {
    s.tree.soles[i].calcForceContribution(s.state, body_forces, particle_forces, mobility_forces);
    const SimTK::Vec3& f = body_forces[s.tree.sole_body[i]][1];  // on the foot, world
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
