#include "hydraulic_humanoid.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "hmpc/humanoid/hydraulic_legs.hpp"
#include "simbody_tree.hpp"

namespace hmpc::hil {

using namespace hmpc::humanoid;
namespace hy = hmpc::hydraulic;

namespace {

using Tree = SimbodyTree<0>;
using Generalised = Eigen::Matrix<double, kDofs, 1>;
using Square = Eigen::Matrix<double, kDofs, kDofs>;

// The end caps: a stiff, damped contact at the stroke's ends (as the one-joint bench's stops,
// hil/joint_bench: 20 kN m/rad holds the largest torque a cylinder makes, 314 N m, within
// 16 mrad).
constexpr double kEndCapStiffness = 2e4;    // N m/rad
constexpr double kEndCapDissipation = 1.0;  // s/rad (Hunt-Crossley)
// Sole points farther above the ground than this carry no force worth an implicit slope
// (Simbody's smoothed Hertz force is below 0.1 N there).
constexpr double kSlopeClearance = 0.005;  // m
// step_reference()'s accuracy: relative, per step, as the twin's.
constexpr double kReferenceAccuracy = 1e-6;
// Implicit steps per plant step: two of 0.5 ms. The step is first order; at 1 ms the actuator
// torques strayed from Runge-Kutta-Merson's by 5-6 % of their range on a test motion (0.84 N m
// of 17 at the knee), at 0.5 ms by 1.7 % (hydraulic_humanoid_test).
constexpr int kSubsteps = 2;

void check_scale(const char* field, double value) {
  if (!(std::isfinite(value) && value >= 0.5 && value <= 2.0)) {
    throw std::invalid_argument(std::string("HumanoidMismatch::") + field +
                                " must be finite and in [0.5, 2], got " + std::to_string(value));
  }
}

Model plant_model(Parameters parameters, const HumanoidMismatch& m) {
  check_scale("mass_scale", m.mass_scale);
  check_scale("inertia_scale", m.inertia_scale);
  check_scale("joint_friction_scale", m.joint_friction_scale);
  check_scale("bulk_modulus_scale", m.bulk_modulus_scale);
  check_scale("valve_flow_gain_scale", m.valve_flow_gain_scale);
  parameters.armature.fill(0.0);
  parameters.arm_armature = 0.0;
  parameters.body_mass *= m.mass_scale;
  Model model(parameters);
  for (Body& b : model.bodies) b.inertia *= m.inertia_scale;
  return model;
}

SimbodyHydraulicHumanoid::Actuators mismatched_actuators(const Parameters& parameters,
                                                         const HumanoidMismatch& m) {
  SimbodyHydraulicHumanoid::Actuators a;
  for (int j = 0; j < kJoints; ++j) {
    hy::JointActuatorParameters<double> p = leg_actuator(parameters, LegJoint(j % kJointsPerLeg));
    p.bulk_modulus *= m.bulk_modulus_scale;
    p.valve_flow_gain *= m.valve_flow_gain_scale;
    p.coulomb_friction *= m.joint_friction_scale;
    p.viscous_friction *= m.joint_friction_scale;
    if (const char* invalid = hy::check(p)) {
      throw std::invalid_argument(std::string("SimbodyHydraulicHumanoid: ") + invalid);
    }
    a[std::size_t(j)] = p;
  }
  return a;
}

// The eight actuators as one Simbody force element: three continuous states per joint (spool,
// p_a, p_b) evolving by hydraulic::derivative, the valve commands a discrete variable held over
// a step, the torques hydraulic::joint_torque (the one source of the actuator's equations).
class HydraulicLegs : public SimTK::Force::Custom::Implementation {
 public:
  HydraulicLegs(const Tree& tree, const SimbodyHydraulicHumanoid::Actuators& actuators)
      : tree_(tree), actuators_(actuators) {}

  void realizeTopology(SimTK::State& state) const override {
    z_ = tree_.forces.allocateZ(state, SimTK::Vector(3 * kJoints, 0.0));
    command_ = tree_.forces.allocateDiscreteVariable(
        state, SimTK::Stage::Dynamics, new SimTK::Value<JointVector>(JointVector::Zero()));
  }
  hy::JointActuatorState<double> actuator(const SimTK::State& state, int j) const {
    const SimTK::Vector& z = tree_.forces.getZ(state);
    return {z[z_ + 3 * j], z[z_ + 3 * j + 1], z[z_ + 3 * j + 2]};
  }
  void set_actuator(SimTK::State& state, int j, const hy::JointActuatorState<double>& a) const {
    SimTK::Vector& z = tree_.forces.updZ(state);
    z[z_ + 3 * j] = a.spool;
    z[z_ + 3 * j + 1] = a.pressure_a;
    z[z_ + 3 * j + 2] = a.pressure_b;
  }
  void set_commands(SimTK::State& state, const JointVector& u) const {
    SimTK::Value<JointVector>::updDowncast(tree_.forces.updDiscreteVariable(state, command_))
        .upd() = u;
  }
  const JointVector& commands(const SimTK::State& state) const {
    return SimTK::Value<JointVector>::downcast(tree_.forces.getDiscreteVariable(state, command_))
        .get();
  }
  double rate(const SimTK::State& state, int j) const { return state.getU()[tree_.joint_u[j]]; }
  double angle(const SimTK::State& state, int j) const { return state.getQ()[tree_.joint_q[j]]; }
  double torque(const SimTK::State& state, int j) const {
    return hy::joint_torque(actuators_[std::size_t(j)], actuator(state, j), rate(state, j));
  }

  void calcForce(const SimTK::State& state, SimTK::Vector_<SimTK::SpatialVec>&,
                 SimTK::Vector_<SimTK::Vec3>&, SimTK::Vector& mobility_forces) const override {
    for (int j = 0; j < kJoints; ++j) mobility_forces[tree_.joint_u[j]] += torque(state, j);
  }
  // Driven by the valves, not a conservative spring: no potential energy.
  SimTK::Real calcPotentialEnergy(const SimTK::State&) const override { return 0; }
  void realizeAcceleration(const SimTK::State& state) const override {
    SimTK::Vector& zdot = tree_.forces.updZDot(state);
    const JointVector& u = commands(state);
    for (int j = 0; j < kJoints; ++j) {
      const hy::JointActuatorState<double> d = hy::derivative(
          actuators_[std::size_t(j)], actuator(state, j), angle(state, j), rate(state, j), u[j]);
      zdot[z_ + 3 * j] = d.spool;
      zdot[z_ + 3 * j + 1] = d.pressure_a;
      zdot[z_ + 3 * j + 2] = d.pressure_b;
    }
  }

 private:
  const Tree& tree_;
  SimbodyHydraulicHumanoid::Actuators actuators_;
  mutable SimTK::ZIndex z_;
  mutable SimTK::DiscreteVariableIndex command_;
};

// One chamber's pressure after h with its inflow q(p) and piston term: dp/dt = beta / V (q(p) -
// displacement), stepped implicitly in p through q's slope (the orifice is stiff near a closed
// land: beta / V K g' reaches 1e4 /s at the dead volume).
double step_pressure(double p, double rate, double rate_slope, double h) {
  return p + h * rate / (1.0 - h * std::min(rate_slope, 0.0));
}

}  // namespace

struct SimbodyHydraulicHumanoid::Impl {
  Model model;
  ContactModel contact;
  Actuators actuators;
  Tree tree;
  HydraulicLegs* legs = nullptr;  // owned by legs_force
  SimTK::Force::Custom legs_force;
  SimTK::Force::DiscreteForces pushes{tree.forces, tree.matter};
  std::vector<SimTK::Force::MobilityLinearStop> end_caps;
  SimTK::State state;
  std::vector<Push> active;
  Velocity acceleration = Velocity::Zero();
  std::uint64_t rejected = 0;
  SoleContactLaw law;
  // Work space of step(), sized once.
  SimTK::Matrix mass;
  SimTK::RowVector_<SimTK::SpatialVec> frame_jacobian;  // of one foot
  SimTK::Array_<SimTK::MobilizedBodyIndex> sole_bodies;
  SimTK::Array_<SimTK::Vec3> sole_stations;
  SimTK::Vector qdot, speeds;

  Impl(const Parameters& parameters, const ContactParameters& contact_parameters,
       const HumanoidMismatch& mismatch)
      : model(plant_model(parameters, mismatch)), contact(model, parameters, contact_parameters),
        actuators(mismatched_actuators(parameters, mismatch)), tree(model),
        legs(new HydraulicLegs(tree, actuators)), legs_force(tree.forces, legs) {
    tree.add_ground_contact(model, contact);
    for (int j = 0; j < kJoints; ++j) {
      const hy::JointActuatorParameters<double>& a = actuators[std::size_t(j)];
      end_caps.emplace_back(tree.forces, tree.joint[j],
                            SimTK::MobilizerQIndex(tree.joint_coordinate[j]), kEndCapStiffness,
                            kEndCapDissipation, a.mid_stroke_angle - a.theta_limit(),
                            a.mid_stroke_angle + a.theta_limit());
    }
    state = tree.system.realizeTopology();
    tree.index(state);
    law = sole_contact_law(model.total_mass() * -model.gravity.z(), contact.parameters());
    for (int i = 0; i < kSolePoints; ++i) {
      sole_bodies.push_back(tree.sole_body[std::size_t(i)]);
      const Vector3& local = contact.point(i).local;
      sole_stations.push_back(SimTK::Vec3(local.x(), local.y(), local.z() + law.kSphereRadius));
    }
  }

  // The Simbody system holds references into itself: not to be copied.
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  Velocity velocity() const { return tree.velocity(state); }

  // The sole points' contribution to D and K (generalised speeds): each sphere's Hertz
  // stiffness and Hunt-Crossley damping along z, its friction's slope along x and y, through
  // the Jacobian of its centre (the contact point is within a radius of it).
  void add_contact_slopes(Square& damping, Square& stiffness) {
    using L = SoleContactLaw;
    const double kappa = 0.5 * std::pow(law.modulus, 2.0 / 3.0);
    const double scale = 4.0 / 3.0 * kappa * std::sqrt(L::kSphereRadius * kappa);
    // The foot's spatial Jacobian (about its origin), taken once for its four points: a point
    // at r from the origin moves at v_o + omega x r.
    int foot_of_jacobian = -1;
    for (int i = 0; i < kSolePoints; ++i) {
      const SimTK::MobilizedBody& foot = tree.matter.getMobilizedBody(sole_bodies[unsigned(i)]);
      const SimTK::Vec3& station = sole_stations[unsigned(i)];
      const SimTK::Vec3 centre = foot.findStationLocationInGround(state, station);
      const double depth = L::kSphereRadius - centre[2];
      if (depth < -kSlopeClearance) continue;
      const SimTK::Vec3 velocity = foot.findStationVelocityInGround(state, station);
      const double base = depth * depth + L::kSmoothingConstant;
      const double on = 0.5 * (1.0 + std::tanh(L::kHertzSmoothing * depth));
      const double hertz = scale * std::pow(base, 0.75) * on;
      const double hertz_slope = scale * (1.5 * depth * std::pow(base, -0.25) * on +
                                          std::pow(base, 0.75) * 0.5 * L::kHertzSmoothing *
                                              (1.0 - (2.0 * on - 1.0) * (2.0 * on - 1.0)));
      const double depth_rate = -velocity[2];
      const double dissipation = std::max(0.0, 1.0 + 1.5 * law.dissipation * depth_rate);
      const double normal = hertz * dissipation;
      const double slip = std::sqrt(velocity[0] * velocity[0] + velocity[1] * velocity[1]);
      // Per unit of the point's motion (world): z up lowers the depth.
      const double k_z = -hertz_slope * dissipation;
      const double d_z = -1.5 * law.dissipation * hertz;
      const double d_t = -law.friction * normal / std::max(slip, law.transition_velocity);
      if (foot_of_jacobian != int(sole_bodies[unsigned(i)])) {
        foot_of_jacobian = int(sole_bodies[unsigned(i)]);
        tree.matter.calcFrameJacobian(state, sole_bodies[unsigned(i)], SimTK::Vec3(0),
                                      frame_jacobian);
      }
      const SimTK::Vec3 r = centre - foot.getBodyOriginLocation(state);
      Eigen::Matrix<double, 3, kDofs> J;
      for (int c = 0; c < kDofs; ++c) {
        const SimTK::SpatialVec& column = frame_jacobian[c];
        const SimTK::Vec3 moved = column[1] + column[0] % r;
        J.col(c) << moved[0], moved[1], moved[2];
      }
      const Eigen::Vector3d d(d_t, d_t, d_z);
      damping.noalias() += J.transpose() * d.asDiagonal() * J;
      stiffness.noalias() += k_z * J.row(2).transpose() * J.row(2);
    }
  }

  // Each joint's torque slope in its own rate over a step of h: the seal friction's, and the
  // oil spring's h k_v (the chambers' pressures follow the joint's new rate); an engaged end
  // cap's stiffness.
  void add_joint_slopes(double h, Square& damping, Square& stiffness) const {
    for (int j = 0; j < kJoints; ++j) {
      const hy::JointActuatorParameters<double>& a = actuators[std::size_t(j)];
      const int u = tree.joint_u[j];
      const double theta = legs->angle(state, j), rate = legs->rate(state, j);
      const double piston = a.lever * rate;
      const double friction_slope = hy::piston_friction_slope(a, piston);
      damping(u, u) +=
          -a.lever * a.lever * friction_slope + h * hy::load_velocity_coupling(a, theta);
      const double beyond = std::max(theta - (a.mid_stroke_angle + a.theta_limit()),
                                     (a.mid_stroke_angle - a.theta_limit()) - theta);
      if (beyond > 0.0) stiffness(u, u) += -kEndCapStiffness;
    }
  }

  // The actuators over h, with the joints' rates at the step's end: the spool's lag exactly,
  // the pressures implicitly in their orifices' flows.
  void step_actuators(const JointVector& commands, double h) {
    for (int j = 0; j < kJoints; ++j) {
      const hy::JointActuatorParameters<double>& a = actuators[std::size_t(j)];
      hy::JointActuatorState<double> x = legs->actuator(state, j);
      x.spool = commands[j] + (x.spool - commands[j]) * std::exp(-h / a.valve_time_constant);
      const double theta = legs->angle(state, j), rate = legs->rate(state, j);
      const hy::JointActuatorState<double> d = hy::derivative(a, x, theta, rate, commands[j]);
      const double k = a.valve_flow_gain * x.spool, pt = a.transition_pressure;
      // d(flow into a)/dp_a and d(flow into b)/dp_b, on the side of the spool's opening.
      const double slope_a = x.spool >= 0
                                 ? -k * hy::orifice_root_slope(a.supply_pressure - x.pressure_a, pt)
                                 : k * hy::orifice_root_slope(x.pressure_a - a.return_pressure, pt);
      const double slope_b = x.spool >= 0
                                 ? -k * hy::orifice_root_slope(x.pressure_b - a.return_pressure, pt)
                                 : k * hy::orifice_root_slope(a.supply_pressure - x.pressure_b, pt);
      x.pressure_a = step_pressure(x.pressure_a, d.pressure_a,
                                   a.bulk_modulus / hy::chamber_volume_a(a, theta) * slope_a, h);
      x.pressure_b = step_pressure(x.pressure_b, d.pressure_b,
                                   a.bulk_modulus / hy::chamber_volume_b(a, theta) * slope_b, h);
      legs->set_actuator(state, j, x);
    }
  }

  // One linearly implicit Euler step of h (see the header).
  void substep(const JointVector& u, double h) {
    // f / M: Simbody's accelerations under every element at the step's start.
    tree.system.realize(state, SimTK::Stage::Acceleration);
    Eigen::Map<const Generalised> udot(&state.getUDot()[0]);
    const Generalised start = Eigen::Map<const Generalised>(&state.getU()[0]);
    tree.matter.calcM(state, mass);
    Square M;
    if (mass.hasContiguousData()) {
      M = Eigen::Map<const Square>(mass.getContiguousScalarData());
    } else {
      for (int r = 0; r < kDofs; ++r) {
        for (int c = 0; c < kDofs; ++c) M(r, c) = mass(r, c);
      }
    }
    Square damping = Square::Zero(), stiffness = Square::Zero();
    add_contact_slopes(damping, stiffness);
    add_joint_slopes(h, damping, stiffness);

    // (M - h D - h^2 K) du = h M udot + h^2 K u
    const Square A = M - h * damping - h * h * stiffness;
    const Generalised rhs = h * (M * udot) + h * h * (stiffness * start);
    const Generalised next = start + A.llt().solve(rhs);

    for (int k = 0; k < kDofs; ++k) speeds[k] = next[k];
    state.updU() = speeds;
    step_actuators(u, h);
    // q+ = q + h N(q) u+, at the step's start configuration; the quaternion renormalised.
    tree.matter.multiplyByN(state, false, speeds, qdot);
    SimTK::Vector& q = state.updQ();
    for (int k = 0; k < kConfigurationSize; ++k) q[k] += h * qdot[k];
    double norm = 0.0;
    for (int k = 0; k < 4; ++k) norm += q[tree.base_q + k] * q[tree.base_q + k];
    norm = std::sqrt(norm);
    for (int k = 0; k < 4; ++k) q[tree.base_q + k] /= norm;
    state.updTime() += h;
  }

  // The pushes acting at plant time t, as body forces at their bodies' centres of mass.
  void apply_pushes(double t) {
    pushes.clearAllBodyForces(state);
    tree.system.realize(state, SimTK::Stage::Position);  // a body point's force needs its pose
    for (const Push& p : active) {
      if (t < p.start || t >= p.start + p.duration) continue;
      const Vector3& com = model.bodies[std::size_t(p.body)].com;  // body frame
      pushes.addForceToBodyPoint(state, tree.body[std::size_t(p.body)],
                                 SimTK::Vec3(com.x(), com.y(), com.z()),
                                 SimTK::Vec3(p.force.x(), p.force.y(), p.force.z()));
    }
  }
};

SimbodyHydraulicHumanoid::SimbodyHydraulicHumanoid(const Parameters& parameters,
                                                   const ContactParameters& contact,
                                                   const HumanoidMismatch& mismatch,
                                                   const BasicState<0>& initial)
    : impl_(std::make_unique<Impl>(parameters, contact, mismatch)) {
  Impl& s = *impl_;
  if (!initial.q.allFinite() || !initial.v.allFinite() || !(initial.q.segment<4>(3).norm() > 0.5)) {
    throw std::invalid_argument(
        "SimbodyHydraulicHumanoid: the initial state must be finite with a unit quaternion");
  }
  for (int j = 0; j < kJoints; ++j) {
    const hy::JointActuatorParameters<double>& a = s.actuators[std::size_t(j)];
    if (std::abs(initial.q[7 + j] - a.mid_stroke_angle) > a.theta_limit()) {
      throw std::invalid_argument("SimbodyHydraulicHumanoid: joint " + std::to_string(j) +
                                  " starts at " + std::to_string(initial.q[7 + j]) +
                                  " rad, beyond its end caps");
    }
  }
  s.tree.set(s.state, initial.q, initial.v);
  for (int j = 0; j < kJoints; ++j) {
    const hy::JointActuatorParameters<double>& a = s.actuators[std::size_t(j)];
    hy::JointActuatorState<double> x;
    x.pressure_b = 0.5 * a.supply_pressure;
    x.pressure_a = x.pressure_b * a.area_b / a.area_a;
    s.legs->set_actuator(s.state, j, x);
  }
  s.legs->set_commands(s.state, JointVector::Zero());
  s.mass.resize(kDofs, kDofs);
  s.qdot.resize(kConfigurationSize);
  s.speeds.resize(kDofs);
}

SimbodyHydraulicHumanoid::~SimbodyHydraulicHumanoid() = default;

namespace {
JointVector screened(const JointVector& commands, std::uint64_t& rejected) {
  JointVector u;
  for (int j = 0; j < kJoints; ++j) {
    if (std::isfinite(commands[j])) {
      u[j] = std::clamp(commands[j], -1.0, 1.0);
    } else {
      u[j] = 0.0;  // the valve centred
      ++rejected;
    }
  }
  return u;
}
}  // namespace

void SimbodyHydraulicHumanoid::step(const JointVector& valve_commands) {
  Impl& s = *impl_;
  const double h = kStep;
  const JointVector u = screened(valve_commands, s.rejected);
  s.legs->set_commands(s.state, u);
  s.apply_pushes(s.state.getTime());
  const Velocity v_start = s.velocity();

  for (int i = 0; i < kSubsteps; ++i) s.substep(u, h / kSubsteps);
  s.acceleration = (s.velocity() - v_start) / h;
}

void SimbodyHydraulicHumanoid::step_reference(const JointVector& valve_commands, double duration) {
  Impl& s = *impl_;
  const Velocity v_start = s.velocity();
  const double start = s.state.getTime();
  s.legs->set_commands(s.state, screened(valve_commands, s.rejected));
  s.apply_pushes(start);
  SimTK::RungeKuttaMersonIntegrator integrator(s.tree.system);
  integrator.setAccuracy(kReferenceAccuracy);
  integrator.setAllowInterpolation(false);
  integrator.initialize(s.state);
  // The first stepTo() after initialising may only report the state (Debian 12's Simbody 3.7).
  while (integrator.getTime() < start + duration) integrator.stepTo(start + duration);
  s.state = integrator.getState();
  s.acceleration = (s.velocity() - v_start) / duration;
}

void SimbodyHydraulicHumanoid::push(const Push& push) {
  if (push.body < 0 || push.body >= kBodies || !push.force.allFinite() ||
      !std::isfinite(push.start) || !(push.duration >= 0.0)) {
    throw std::invalid_argument(
        "SimbodyHydraulicHumanoid: a push needs a body of the model, a finite force and start, "
        "and a duration >= 0");
  }
  if (impl_->tree.body[std::size_t(push.body)].isEmptyHandle()) {
    throw std::invalid_argument("SimbodyHydraulicHumanoid: a push on a massless hip link");
  }
  impl_->active.push_back(push);
}

BasicState<0> SimbodyHydraulicHumanoid::state() const {
  BasicState<0> x;
  x.q = impl_->tree.configuration(impl_->state);
  x.v = impl_->tree.velocity(impl_->state);
  return x;
}

const Velocity& SimbodyHydraulicHumanoid::acceleration() const { return impl_->acceleration; }

JointVector SimbodyHydraulicHumanoid::joint_torques() const {
  JointVector tau;
  for (int j = 0; j < kJoints; ++j) tau[j] = impl_->legs->torque(impl_->state, j);
  return tau;
}

SimbodyHydraulicHumanoid::ActuatorStates SimbodyHydraulicHumanoid::actuators() const {
  ActuatorStates out;
  for (int j = 0; j < kJoints; ++j) out[std::size_t(j)] = impl_->legs->actuator(impl_->state, j);
  return out;
}

const SimbodyHydraulicHumanoid::Actuators& SimbodyHydraulicHumanoid::plant_actuators() const {
  return impl_->actuators;
}

std::array<Vector3, kSolePoints> SimbodyHydraulicHumanoid::sole_forces() const {
  Impl& s = *impl_;
  s.tree.system.realize(s.state, SimTK::Stage::Velocity);
  std::array<Vector3, kSolePoints> out;
  for (int i = 0; i < kSolePoints; ++i) {
    SimTK::Vector_<SimTK::SpatialVec> body_forces;
    SimTK::Vector_<SimTK::Vec3> particle_forces;
    SimTK::Vector mobility_forces;
    s.tree.soles[std::size_t(i)].calcForceContribution(s.state, body_forces, particle_forces,
                                                       mobility_forces);
    const SimTK::Vec3& f = body_forces[s.tree.sole_body[std::size_t(i)]][1];  // on the foot, world
    out[std::size_t(i)] = Vector3(f[0], f[1], f[2]);
  }
  return out;
}

double SimbodyHydraulicHumanoid::time() const { return impl_->state.getTime(); }
std::uint64_t SimbodyHydraulicHumanoid::rejected_commands() const { return impl_->rejected; }
const Model& SimbodyHydraulicHumanoid::model() const { return impl_->model; }

}  // namespace hmpc::hil
