#include "simbody_forearm.hpp"

#include <Simbody.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hmpc::hil {
namespace {

using Parameters = forearm::Parameters<double>;

// Simbody's integrator: Runge-Kutta-Merson (4th order, error controlled), stepping to each 1 ms
// sample without interpolation, so a sample is one step or a few. Error control rather than a
// fixed step because the end stops are stiff: the integrator shortens its steps through an
// impact and stays stable, where a fixed 1 ms step goes unstable once the stop's damping k d x
// exceeds ~2.8 I / h (a penetration of ~0.04 rad). Accuracy 1e-6 (relative, per step): away
// from impacts every sample is one 1 ms step with an error far below it (the plant matches the
// model's RK4 to 1e-10 rad, see the test). 1e-8 gave the same trajectories to 1e-9 but 10-40 %
// more steps (friction zero crossings, impacts), and Debian's Simbody 3.7 spends ~8 us on each
// evaluation of the dynamics (five per step): the 20x real time the HIL needs is tight.
constexpr double kAccuracy = 1e-6;

// The valve and the muscle: PAM pressure P is a Simbody continuous state variable (a z of the
// force subsystem) with T_p dP/dt = -k_vp P + v_p (Eq. 3.1, first row), the valve voltage v_p
// a discrete state variable held over the step. The muscle pulls through the pulley with the
// torque tau_p(P, theta) of forearm::pam_torque: the one source of truth for the constitutive
// PAM law (Chou-Hannaford), shared with the controller's model. Simbody does the rest.
class PamActuator : public SimTK::Force::Custom::Implementation {
 public:
  PamActuator(const SimTK::GeneralForceSubsystem& forces, const SimTK::MobilizedBody::Pin& elbow,
              const Parameters& plant)
      : forces_(forces), elbow_(elbow), plant_(plant) {}

  void realizeTopology(SimTK::State& state) const override {
    pressure_ = forces_.allocateZ(state, SimTK::Vector(1, 0.0));
    valve_voltage_ = forces_.allocateDiscreteVariable(state, SimTK::Stage::Dynamics,
                                                      new SimTK::Value<double>(0.0));
  }

  double pressure(const SimTK::State& state) const { return forces_.getZ(state)[pressure_]; }
  void set_pressure(SimTK::State& state, double bar) const { forces_.updZ(state)[pressure_] = bar; }
  double valve_voltage(const SimTK::State& state) const {
    return SimTK::Value<double>::downcast(forces_.getDiscreteVariable(state, valve_voltage_)).get();
  }
  // Invalidates Stage::Dynamics and above of the state: forces and derivatives get recomputed.
  void set_valve_voltage(SimTK::State& state, double volts) const {
    SimTK::Value<double>::updDowncast(forces_.updDiscreteVariable(state, valve_voltage_)).upd() =
        volts;
  }
  double torque(const SimTK::State& state) const {
    return forearm::pam_torque(plant_, pressure(state), elbow_.getAngle(state)).tau;
  }

  void calcForce(const SimTK::State& state, SimTK::Vector_<SimTK::SpatialVec>&,
                 SimTK::Vector_<SimTK::Vec3>&, SimTK::Vector& mobility_forces) const override {
    elbow_.applyOneMobilityForce(state, 0, torque(state), mobility_forces);
  }
  // The muscle is driven by the valve, not a conservative spring: no potential energy.
  SimTK::Real calcPotentialEnergy(const SimTK::State&) const override { return 0; }

  void realizeAcceleration(const SimTK::State& state) const override {
    forces_.updZDot(state)[pressure_] =
        (-plant_.k_vp * pressure(state) + valve_voltage(state)) / plant_.T_p;
  }

 private:
  const SimTK::GeneralForceSubsystem& forces_;
  SimTK::MobilizedBody::Pin elbow_;
  Parameters plant_;
  // Indices into the state, assigned when Simbody realizes the topology.
  mutable SimTK::ZIndex pressure_;
  mutable SimTK::DiscreteVariableIndex valve_voltage_;
};

// Smooth friction of the elbow (the model's ref. [82]): viscous plus tanh-smoothed Coulomb.
class JointFriction : public SimTK::Force::Custom::Implementation {
 public:
  JointFriction(const SimTK::MobilizedBody::Pin& elbow, const Parameters& plant)
      : elbow_(elbow), plant_(plant) {}

  void calcForce(const SimTK::State& state, SimTK::Vector_<SimTK::SpatialVec>&,
                 SimTK::Vector_<SimTK::Vec3>&, SimTK::Vector& mobility_forces) const override {
    const double rate = elbow_.getRate(state);
    const double torque = -plant_.viscous_friction * rate -
                          plant_.coulomb_friction * std::tanh(rate / plant_.friction_velocity);
    elbow_.applyOneMobilityForce(state, 0, torque, mobility_forces);
  }
  SimTK::Real calcPotentialEnergy(const SimTK::State&) const override { return 0; }

 private:
  SimTK::MobilizedBody::Pin elbow_;
  Parameters plant_;
};

// The link: mass at com_distance along the body's x axis, gyration radius about the centre of
// mass (only the moment about the pin's z axis matters). Simbody wants the inertia about the
// body origin, the elbow, which lies at -com from the centre of mass.
SimTK::Body::Rigid link(const Parameters& p) {
  const SimTK::Vec3 com(p.com_distance, 0, 0);
  const SimTK::Inertia about_elbow = SimTK::Inertia(p.mass * p.gyration_radius * p.gyration_radius)
                                         .shiftFromMassCenter(-com, p.mass);
  return SimTK::Body::Rigid(SimTK::MassProperties(p.mass, com, about_elbow));
}

void check_scale(const char* field, double value) {
  if (!(std::isfinite(value) && value >= 0.5 && value <= 2.0)) {
    throw std::invalid_argument(std::string("ForearmMismatch::") + field +
                                " must be finite and in [0.5, 2], got " + std::to_string(value));
  }
}

void check_initial(const Parameters& p, const ForearmPlantState& x) {
  if (!std::isfinite(x.theta) || !std::isfinite(x.theta_dot) || !std::isfinite(x.pressure_bar)) {
    throw std::invalid_argument("SimbodyForearm: initial state must be finite");
  }
  if (x.theta < p.stop_lower || x.theta > p.stop_upper) {
    throw std::invalid_argument("SimbodyForearm: initial theta " + std::to_string(x.theta) +
                                " rad lies outside the stops [" + std::to_string(p.stop_lower) +
                                ", " + std::to_string(p.stop_upper) + "]");
  }
  if (x.pressure_bar < 0) {
    throw std::invalid_argument("SimbodyForearm: initial pressure_bar must be >= 0, got " +
                                std::to_string(x.pressure_bar));
  }
}

}  // namespace

Parameters with_mismatch(const Parameters& model, const ForearmMismatch& m) {
  check_scale("mass_scale", m.mass_scale);
  check_scale("friction_scale", m.friction_scale);
  check_scale("pam_time_constant_scale", m.pam_time_constant_scale);
  if (!(model.stop_lower < model.stop_upper) || !(model.stop_stiffness >= 0) ||
      !(model.stop_dissipation >= 0)) {
    throw std::invalid_argument(
        "SimbodyForearm: forearm::Parameters needs stop_lower < stop_upper and a non-negative "
        "stop_stiffness and stop_dissipation");
  }
  Parameters plant = model;
  plant.mass *= m.mass_scale;
  plant.viscous_friction *= m.friction_scale;
  plant.coulomb_friction *= m.friction_scale;
  plant.T_p *= m.pam_time_constant_scale;
  return plant;
}

struct SimbodyForearm::Impl {
  Parameters plant;
  SimTK::MultibodySystem system;
  SimTK::SimbodyMatterSubsystem matter{system};
  SimTK::GeneralForceSubsystem forces{system};
  // Pin about the ground's z axis, the link along the body's x axis: at q = theta = 0 the arm
  // is horizontal, flexion (q > 0) lifts the centre of mass against gravity along -y, whose
  // torque is then -m g d cos(theta).
  SimTK::MobilizedBody::Pin elbow{matter.Ground(), SimTK::Transform(), link(plant),
                                  SimTK::Transform()};
  SimTK::Force::Gravity gravity{forces, matter, -SimTK::YAxis, plant.gravity};
  PamActuator* pam = new PamActuator(forces, elbow, plant);  // owned by pam_force
  SimTK::Force::Custom pam_force{forces, pam};
  SimTK::Force::Custom friction{forces, new JointFriction(elbow, plant)};
  // The motor driver in torque mode: tau_m = k_m v_m, set for each step.
  SimTK::Force::MobilityConstantForce motor{forces, elbow, SimTK::MobilizerUIndex(0), 0.0};
  // One element holds both stops.
  SimTK::Force::MobilityLinearStop stops{forces,
                                         elbow,
                                         SimTK::MobilizerQIndex(0),
                                         plant.stop_stiffness,
                                         plant.stop_dissipation,
                                         plant.stop_lower,
                                         plant.stop_upper};
  SimTK::RungeKuttaMersonIntegrator integrator{system};

  double v_p = 0, v_m = 0;
  std::uint64_t rejected = 0, steps = 0;

  Impl(const Parameters& plant_parameters, const ForearmPlantState& initial)
      : plant(plant_parameters) {
    SimTK::State state = system.realizeTopology();
    elbow.setAngle(state, initial.theta);
    elbow.setRate(state, initial.theta_dot);
    pam->set_pressure(state, initial.pressure_bar);
    integrator.setAccuracy(kAccuracy);
    // Each sample is a step boundary, where the held voltages may change.
    integrator.setAllowInterpolation(false);
    integrator.initialize(state);
  }
};

SimbodyForearm::SimbodyForearm(const forearm::Parameters<double>& model,
                               const ForearmMismatch& mismatch, const ForearmPlantState& initial) {
  const Parameters plant = with_mismatch(model, mismatch);
  check_initial(plant, initial);
  impl_ = std::make_unique<Impl>(plant, initial);
}

SimbodyForearm::~SimbodyForearm() = default;

void SimbodyForearm::step(double v_p, double v_m) {
  Impl& s = *impl_;
  if (!std::isfinite(v_p) || !std::isfinite(v_m)) {
    v_p = 0;  // safe outputs: valve vented, motor off
    v_m = 0;
    ++s.rejected;
  }
  s.v_p = std::clamp(v_p, s.plant.v_p_min, s.plant.v_p_max);
  s.v_m = std::clamp(v_m, s.plant.v_m_min, s.plant.v_m_max);

  SimTK::State& state = s.integrator.updAdvancedState();
  s.pam->set_valve_voltage(state, s.v_p);
  s.motor.setForce(state, s.plant.motor_gain * s.v_m);
  // A changed input starts a new continuous interval; the first stepTo() after this only
  // reports the current state (Debian 12's Simbody 3.7), hence the loop.
  s.integrator.reinitialize(SimTK::Stage::Dynamics, false);
  ++s.steps;
  const double target = static_cast<double>(s.steps) * kStep;  // no drift from summing kStep
  while (s.integrator.getTime() < target) s.integrator.stepTo(target);
}

ForearmPlantState SimbodyForearm::state() const {
  const SimTK::State& state = impl_->integrator.getState();
  return {impl_->elbow.getAngle(state), impl_->elbow.getRate(state), impl_->pam->pressure(state)};
}

double SimbodyForearm::time() const { return impl_->integrator.getTime(); }
double SimbodyForearm::pam_torque() const {
  return impl_->pam->torque(impl_->integrator.getState());
}
double SimbodyForearm::motor_torque() const { return impl_->plant.motor_gain * impl_->v_m; }
double SimbodyForearm::applied_v_p() const { return impl_->v_p; }
double SimbodyForearm::applied_v_m() const { return impl_->v_m; }
std::uint64_t SimbodyForearm::rejected_commands() const { return impl_->rejected; }
const forearm::Parameters<double>& SimbodyForearm::plant_parameters() const { return impl_->plant; }

}  // namespace hmpc::hil
