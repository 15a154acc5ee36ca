#include "simbody_joint.hpp"

#include <Simbody.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hmpc::hil {

namespace {

using Actuator = hydraulic::JointActuatorParameters<double>;
using Load = hydraulic::PendulumLoad<double>;

// Runge-Kutta-Merson with error control, stepping to each 1 ms sample: the chambers' pressure
// dynamics (a hydraulic spring of some 100 rad/s on the leg, the valve's 0.64 ms lag) and the
// end stops need steps well below 1 ms, which error control finds by itself.
constexpr double kAccuracy = 1e-6;
// End stops: a stiff, damped contact (our choice: 20 kN·m/rad stops the leg within a few
// milliradians at the speeds a valve can give it).
constexpr double kStopStiffness = 2e4;    // N·m/rad
constexpr double kStopDissipation = 1.0;  // s/rad (Hunt-Crossley)

// The valve and the cylinder: spool opening and both chamber pressures are Simbody continuous
// state variables (z's of the force subsystem) evolving by hydraulic::derivative, the valve
// command a discrete variable held over the step; the torque is hydraulic::joint_torque, the
// one source of truth for the actuator, shared with the boards' tests and images.
class HydraulicActuator : public SimTK::Force::Custom::Implementation {
 public:
  HydraulicActuator(const SimTK::GeneralForceSubsystem& forces,
                    const SimTK::MobilizedBody::Pin& joint, const Actuator& actuator)
      : forces_(forces), joint_(joint), actuator_(actuator) {}

  void realizeTopology(SimTK::State& state) const override {
    z_ = forces_.allocateZ(state, SimTK::Vector(3, 0.0));
    command_ = forces_.allocateDiscreteVariable(state, SimTK::Stage::Dynamics,
                                                new SimTK::Value<double>(0.0));
  }
  hydraulic::JointActuatorState<double> actuator_state(const SimTK::State& state) const {
    const SimTK::Vector& z = forces_.getZ(state);
    return {z[z_], z[z_ + 1], z[z_ + 2]};
  }
  void set_actuator_state(SimTK::State& state,
                          const hydraulic::JointActuatorState<double>& a) const {
    SimTK::Vector& z = forces_.updZ(state);
    z[z_] = a.spool;
    z[z_ + 1] = a.pressure_a;
    z[z_ + 2] = a.pressure_b;
  }
  // Invalidates Stage::Dynamics and above: forces and derivatives get recomputed.
  void set_command(SimTK::State& state, double u) const {
    SimTK::Value<double>::updDowncast(forces_.updDiscreteVariable(state, command_)).upd() = u;
  }
  double command(const SimTK::State& state) const {
    return SimTK::Value<double>::downcast(forces_.getDiscreteVariable(state, command_)).get();
  }
  double torque(const SimTK::State& state) const {
    return hydraulic::joint_torque(actuator_, actuator_state(state), joint_.getRate(state));
  }
  void calcForce(const SimTK::State& state, SimTK::Vector_<SimTK::SpatialVec>&,
                 SimTK::Vector_<SimTK::Vec3>&, SimTK::Vector& mobility_forces) const override {
    joint_.applyOneMobilityForce(state, 0, torque(state), mobility_forces);
  }
  // Driven by the valve, not a conservative spring: no potential energy.
  SimTK::Real calcPotentialEnergy(const SimTK::State&) const override { return 0; }
  void realizeAcceleration(const SimTK::State& state) const override {
    const hydraulic::JointActuatorState<double> d =
        hydraulic::derivative(actuator_, actuator_state(state), joint_.getAngle(state),
                              joint_.getRate(state), command(state));
    SimTK::Vector& zdot = forces_.updZDot(state);
    zdot[z_] = d.spool;
    zdot[z_ + 1] = d.pressure_a;
    zdot[z_ + 2] = d.pressure_b;
  }

 private:
  const SimTK::GeneralForceSubsystem& forces_;
  SimTK::MobilizedBody::Pin joint_;
  Actuator actuator_;
  mutable SimTK::ZIndex z_;
  mutable SimTK::DiscreteVariableIndex command_;
};

// The link: its mass at com_distance along the body's -y axis (hanging at q = 0), a slender
// body whose moment about the joint's axis is the load's inertia. Simbody wants the inertia
// about the body origin, the joint, which lies at -com from the centre of mass.
SimTK::Body::Rigid link(const Load& load) {
  const SimTK::Vec3 com(0, -load.com_distance, 0);
  const double about_com = load.inertia - load.mass * load.com_distance * load.com_distance;
  if (!(about_com > 0)) {
    throw std::invalid_argument("PendulumLoad: inertia must exceed m l^2 (the point-mass value)");
  }
  const SimTK::Inertia central(about_com, 1e-3 * about_com, about_com);  // slender along y
  return SimTK::Body::Rigid(
      SimTK::MassProperties(load.mass, com, central.shiftFromMassCenter(-com, load.mass)));
}

void check_scale(const char* field, double value) {
  if (!(std::isfinite(value) && value >= 0.5 && value <= 2.0)) {
    throw std::invalid_argument(std::string("JointMismatch::") + field +
                                " must be finite and in [0.5, 2], got " + std::to_string(value));
  }
}

}  // namespace

struct SimbodyHydraulicJoint::Impl {
  Actuator actuator;
  Load load;
  SimTK::MultibodySystem system;
  SimTK::SimbodyMatterSubsystem matter{system};
  SimTK::GeneralForceSubsystem forces{system};
  // Pin about the ground's z axis; gravity along -y pulls the link, hanging along -y, back to
  // q = 0 with the torque -m g l sin(q).
  SimTK::MobilizedBody::Pin joint{matter.Ground(), SimTK::Transform(), link(load),
                                  SimTK::Transform()};
  SimTK::Force::Gravity gravity{forces, matter, -SimTK::YAxis, load.gravity};
  HydraulicActuator* cylinder = new HydraulicActuator(forces, joint, actuator);  // owned below
  SimTK::Force::Custom cylinder_force{forces, cylinder};
  SimTK::Force::MobilityConstantForce disturbance{forces, joint, SimTK::MobilizerUIndex(0), 0.0};
  SimTK::Force::MobilityLinearStop stops{
      forces,      joint,     SimTK::MobilizerQIndex(0), kStopStiffness, kStopDissipation,
      -kStopAngle, kStopAngle};
  SimTK::RungeKuttaMersonIntegrator integrator{system};
  std::uint64_t rejected = 0, steps = 0;

  Impl(const Actuator& a, const Load& l, const hydraulic::PendulumState<double>& initial)
      : actuator(a), load(l) {
    SimTK::State state = system.realizeTopology();
    joint.setAngle(state, initial.theta);
    joint.setRate(state, initial.omega);
    cylinder->set_actuator_state(state, initial.actuator);
    integrator.setAccuracy(kAccuracy);
    integrator.setAllowInterpolation(false);  // each sample a step boundary: u may change there
    integrator.initialize(state);
  }
};

SimbodyHydraulicJoint::SimbodyHydraulicJoint(
    const hydraulic::JointActuatorParameters<double>& actuator,
    const hydraulic::PendulumLoad<double>& load, const JointMismatch& mismatch,
    const hydraulic::PendulumState<double>& initial) {
  check_scale("load_scale", mismatch.load_scale);
  check_scale("bulk_modulus_scale", mismatch.bulk_modulus_scale);
  check_scale("valve_flow_gain_scale", mismatch.valve_flow_gain_scale);
  check_scale("friction_scale", mismatch.friction_scale);
  Actuator plant = actuator;
  plant.bulk_modulus *= mismatch.bulk_modulus_scale;
  plant.valve_flow_gain *= mismatch.valve_flow_gain_scale;
  plant.coulomb_friction *= mismatch.friction_scale;
  plant.viscous_friction *= mismatch.friction_scale;
  if (const char* invalid = hydraulic::check(plant)) {
    throw std::invalid_argument(std::string("SimbodyHydraulicJoint: ") + invalid);
  }
  Load plant_load = load;
  plant_load.mass *= mismatch.load_scale;
  plant_load.inertia *= mismatch.load_scale;
  const auto finite = [](double v) { return std::isfinite(v); };
  if (!finite(initial.theta) || !finite(initial.omega) || !finite(initial.actuator.spool) ||
      !finite(initial.actuator.pressure_a) || !finite(initial.actuator.pressure_b)) {
    throw std::invalid_argument("SimbodyHydraulicJoint: initial state must be finite");
  }
  if (std::abs(initial.theta) > kStopAngle) {
    throw std::invalid_argument("SimbodyHydraulicJoint: initial theta " +
                                std::to_string(initial.theta) + " rad lies outside the stops");
  }
  if (initial.actuator.pressure_a < 0 || initial.actuator.pressure_b < 0) {
    throw std::invalid_argument("SimbodyHydraulicJoint: initial pressures must be >= 0");
  }
  impl_ = std::make_unique<Impl>(plant, plant_load, initial);
}

SimbodyHydraulicJoint::~SimbodyHydraulicJoint() = default;

void SimbodyHydraulicJoint::step(double u) {
  Impl& s = *impl_;
  if (!std::isfinite(u)) {
    u = 0;  // the valve centred
    ++s.rejected;
  }
  SimTK::State& state = s.integrator.updAdvancedState();
  s.cylinder->set_command(state, std::clamp(u, -1.0, 1.0));
  // A changed input starts a new continuous interval; the first stepTo() after this only
  // reports the current state (Debian 12's Simbody 3.7), hence the loop.
  s.integrator.reinitialize(SimTK::Stage::Dynamics, false);
  ++s.steps;
  const double target = static_cast<double>(s.steps) * kStep;
  while (s.integrator.getTime() < target) s.integrator.stepTo(target);
}

void SimbodyHydraulicJoint::set_disturbance(double torque) {
  SimTK::State& state = impl_->integrator.updAdvancedState();
  impl_->disturbance.setForce(state, std::isfinite(torque) ? torque : 0.0);
  impl_->integrator.reinitialize(SimTK::Stage::Dynamics, false);
}

hydraulic::PendulumState<double> SimbodyHydraulicJoint::state() const {
  const SimTK::State& state = impl_->integrator.getState();
  hydraulic::PendulumState<double> x;
  x.actuator = impl_->cylinder->actuator_state(state);
  x.theta = impl_->joint.getAngle(state);
  x.omega = impl_->joint.getRate(state);
  return x;
}

double SimbodyHydraulicJoint::torque() const {
  return impl_->cylinder->torque(impl_->integrator.getState());
}
double SimbodyHydraulicJoint::time() const { return impl_->integrator.getTime(); }
std::uint64_t SimbodyHydraulicJoint::rejected_commands() const { return impl_->rejected; }
const hydraulic::JointActuatorParameters<double>& SimbodyHydraulicJoint::plant_actuator() const {
  return impl_->actuator;
}

}  // namespace hmpc::hil
