// The forearm plant in Simbody (hil/forearm) against the controller's model of Eq. 3.1, and as a
// physical plant: pressure as a Simbody state, end stops, actuator limits, bad commands, heap
// use in the step. Its speed is tests/bench/hil_plant_bench's.
#include "simbody_forearm.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>

#include "hmpc/constants.hpp"
#include "hmpc/models/forearm.hpp"
#include "hmpc/platform/linux/heap_monitor.hpp"

namespace {

using hmpc::hil::ForearmMismatch;
using hmpc::hil::ForearmPlantState;
using hmpc::hil::SimbodyForearm;
using Parameters = hmpc::forearm::Parameters<double>;
namespace heap_monitor = hmpc::platform::heap_monitor;

constexpr double kDt = SimbodyForearm::kStep;
constexpr double kTwoPi = 2 * hmpc::kPi<double>;

int steps_for(double seconds) { return static_cast<int>(std::lround(seconds / kDt)); }

std::string text(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", value);
  return buffer;
}

// Mechanical energy of the plant: link kinetic energy, gravity (centre of mass d sin(theta)
// above the elbow) and the stop springs. Friction, stop damping and a vented PAM only remove
// energy from it.
double mechanical_energy(const Parameters& p, const ForearmPlantState& x) {
  const double penetration =
      std::max(0.0, p.stop_lower - x.theta) + std::max(0.0, x.theta - p.stop_upper);
  return 0.5 * p.inertia() * x.theta_dot * x.theta_dot +
         p.mass * p.gravity * p.com_distance * std::sin(x.theta) +
         0.5 * p.stop_stiffness * penetration * penetration;
}

// 1. Same arm, same inputs: Simbody's pin joint, gravity, friction and pressure state against
// forearm::integrate (RK4 of Eq. 3.1 at 1 ms) over 2 s of open-loop input from an equilibrium.
// Both integrate the same ODE with 4th-order methods at 1 ms, so they differ only by their
// truncation errors: measured 8e-11 rad, 5e-10 rad/s, 3e-12 bar. The bounds are 100x that.
// A physical difference is far larger: a plant 1 % heavier than the model (the negative control
// below) is off by more than 1e-4 rad.
struct Agreement {
  double theta = 0, theta_dot = 0, pressure = 0;  // worst absolute differences
  double theta_span = 0;                          // how far the arm swung
};

Agreement compare_with_model(const ForearmMismatch& mismatch) {
  Parameters model;
  model.stop_lower = -3.0;  // stops far from the motion: Eq. 3.1 has none
  model.stop_upper = 3.0;
  const double theta0 = 0.0;
  const double p0 = hmpc::forearm::equilibrium_pressure(model, theta0);
  SimbodyForearm plant(model, mismatch, ForearmPlantState{theta0, 0.0, p0});
  Eigen::Vector3d x(theta0, 0.0, p0);
  Agreement worst;
  double theta_min = theta0, theta_max = theta0;
  for (int k = 0; k < steps_for(2.0); ++k) {
    const double t = k * kDt;
    // A slow valve ramp down with a 1 Hz sine on it, and a 3 Hz motor sine: inside the limits.
    const double v_p = model.k_vp * p0 - 0.2 * t + 0.3 * std::sin(kTwoPi * 1.0 * t);
    const double v_m = 3.0 * std::sin(kTwoPi * 3.0 * t);
    plant.step(v_p, v_m);
    x = hmpc::forearm::integrate(model, x, Eigen::Vector2d(v_m, v_p), kDt);
    EXPECT_DOUBLE_EQ(plant.applied_v_p(), v_p);
    EXPECT_DOUBLE_EQ(plant.applied_v_m(), v_m);
    const ForearmPlantState s = plant.state();
    worst.theta = std::max(worst.theta, std::abs(s.theta - x(0)));
    worst.theta_dot = std::max(worst.theta_dot, std::abs(s.theta_dot - x(1)));
    worst.pressure = std::max(worst.pressure, std::abs(s.pressure_bar - x(2)));
    theta_min = std::min(theta_min, s.theta);
    theta_max = std::max(theta_max, s.theta);
  }
  EXPECT_NEAR(plant.time(), 2.0, 1e-12);
  worst.theta_span = theta_max - theta_min;
  return worst;
}

TEST(SimbodyForearm, AgreesWithTheControllersModel) {
  const Agreement worst = compare_with_model(ForearmMismatch{});
  // The input really swung the arm (else agreement would prove little).
  EXPECT_GT(worst.theta_span, 0.5);
  RecordProperty("max_error_theta", text(worst.theta));
  RecordProperty("max_error_theta_dot", text(worst.theta_dot));
  RecordProperty("max_error_pressure", text(worst.pressure));
  EXPECT_LT(worst.theta, 1e-8);
  EXPECT_LT(worst.theta_dot, 1e-7);
  EXPECT_LT(worst.pressure, 1e-9);
}

TEST(SimbodyForearm, AgreementTestSeesAOnePercentMassError) {
  EXPECT_GT(compare_with_model(ForearmMismatch{1.01, 1, 1}).theta, 1e-4);
}

// 2. The PAM pressure is a Simbody state with the first-order valve response of Eq. 3.1:
// after a step in v_p, P = (v_p / k_vp)(1 - exp(-t / tau)), tau = T_p / k_vp, so 63.2 % at tau;
// a T_p mismatch of 2 doubles tau.
TEST(SimbodyForearm, PressureStepIsFirstOrderWithTimeConstantTpOverKvp) {
  const Parameters model;
  const double v_p = 4.0;
  for (const double scale : {1.0, 2.0}) {
    ForearmMismatch mismatch;
    mismatch.pam_time_constant_scale = scale;
    SimbodyForearm plant(model, mismatch, ForearmPlantState{0.0, 0.0, 0.0});
    ASSERT_DOUBLE_EQ(plant.plant_parameters().T_p, scale * model.T_p);
    const double tau = scale * model.T_p / model.k_vp;
    const double final_pressure = v_p / model.k_vp;
    double worst = 0;
    for (int k = 1; k <= steps_for(tau); ++k) {
      plant.step(v_p, 0.0);
      const double expected = final_pressure * (1.0 - std::exp(-k * kDt / tau));
      worst = std::max(worst, std::abs(plant.state().pressure_bar - expected));
    }
    EXPECT_LT(worst, 1e-6) << "scale " << scale;
    EXPECT_NEAR(plant.state().pressure_bar / final_pressure, 1.0 - std::exp(-1.0), 1e-6)
        << "scale " << scale;
  }
}

// 3. Valve vented, motor off, from 0.5 rad at rest with an empty muscle: the arm falls onto the
// lower stop and comes to rest on it. Energy bound on the penetration x: the fall releases at
// most dV = m g d (sin(theta0) - sin(stop)), gravity adds at most m g d per radian beyond the
// stop, and the stop stores k x^2 / 2, so k x^2 / 2 <= dV + m g d x. At rest the stop carries
// the arm's weight: k x = m g d cos(stop). Mechanical energy never grows.
TEST(SimbodyForearm, VentedArmFallsOntoTheLowerStopAndRests) {
  const Parameters model;
  const double theta0 = 0.5;
  SimbodyForearm plant(model, ForearmMismatch{}, ForearmPlantState{theta0, 0.0, 0.0});
  const Parameters& p = plant.plant_parameters();
  const double weight_torque = p.mass * p.gravity * p.com_distance;
  const double released = weight_torque * (std::sin(theta0) - std::sin(p.stop_lower));
  const double max_penetration =
      (weight_torque + std::sqrt(weight_torque * weight_torque + 2 * p.stop_stiffness * released)) /
      p.stop_stiffness;

  double energy = mechanical_energy(p, plant.state());
  const double initial_energy = energy;
  double worst_increase = 0, theta_min = theta0;
  for (int k = 0; k < steps_for(3.0); ++k) {
    plant.step(0.0, 0.0);
    const ForearmPlantState s = plant.state();
    const double e = mechanical_energy(p, s);
    worst_increase = std::max(worst_increase, e - energy);
    energy = e;
    theta_min = std::min(theta_min, s.theta);
    ASSERT_EQ(s.pressure_bar, 0.0);
  }
  const ForearmPlantState rest = plant.state();
  RecordProperty("max_penetration_rad", text(p.stop_lower - theta_min));
  // It hit the stop, and the stop held within the bound.
  EXPECT_LT(theta_min, p.stop_lower);
  EXPECT_GT(theta_min, p.stop_lower - max_penetration);
  // At rest on the stop, compressed by the arm's weight.
  EXPECT_NEAR(rest.theta, p.stop_lower - weight_torque * std::cos(p.stop_lower) / p.stop_stiffness,
              1e-6);
  EXPECT_LT(std::abs(rest.theta_dot), 1e-4);
  // Energy: never up by more than integration error, and most of it gone.
  EXPECT_LT(worst_increase, 1e-7);
  EXPECT_LT(energy, initial_energy);
}

// Full valve and motor from the horizontal: the arm is driven onto the upper stop and held
// there, the stop compressed by PAM (at the full 5 bar) plus motor plus gravity torque.
TEST(SimbodyForearm, FullDriveHoldsTheArmAgainstTheUpperStop) {
  const Parameters model;
  const double p0 = hmpc::forearm::equilibrium_pressure(model, 0.0);
  SimbodyForearm plant(model, ForearmMismatch{}, ForearmPlantState{0.0, 0.0, p0});
  const Parameters& p = plant.plant_parameters();
  double theta_max = 0;
  for (int k = 0; k < steps_for(3.0); ++k) {
    plant.step(p.v_p_max, p.v_m_max);
    theta_max = std::max(theta_max, plant.state().theta);
  }
  const ForearmPlantState rest = plant.state();
  EXPECT_NEAR(rest.pressure_bar, p.v_p_max / p.k_vp, 1e-6);
  EXPECT_GT(theta_max, p.stop_upper);
  EXPECT_LT(theta_max - p.stop_upper, 0.05);  // the stop holds within 3 degrees
  const double pushing = hmpc::forearm::pam_torque(p, rest.pressure_bar, rest.theta).tau +
                         p.motor_gain * p.v_m_max -
                         p.mass * p.gravity * p.com_distance * std::cos(rest.theta);
  EXPECT_GT(pushing, 0.0);
  EXPECT_NEAR(rest.theta, p.stop_upper + pushing / p.stop_stiffness, 1e-6);
  EXPECT_NEAR(plant.pam_torque(), hmpc::forearm::pam_torque(p, rest.pressure_bar, rest.theta).tau,
              1e-12);
  EXPECT_DOUBLE_EQ(plant.motor_torque(), p.motor_gain * p.v_m_max);
  EXPECT_LT(std::abs(rest.theta_dot), 1e-4);
}

// A heavier plant than the model sags from the model's equilibrium, a lighter one rises; the
// scales reach the plant's parameters.
TEST(SimbodyForearm, MismatchChangesThePlant) {
  const Parameters model;
  const double p0 = hmpc::forearm::equilibrium_pressure(model, 0.0);
  const auto theta_after_half_second = [&](const ForearmMismatch& m) {
    SimbodyForearm plant(model, m, ForearmPlantState{0.0, 0.0, p0});
    for (int k = 0; k < steps_for(0.5); ++k) plant.step(model.k_vp * p0, 0.0);
    return plant.state().theta;
  };
  EXPECT_NEAR(theta_after_half_second(ForearmMismatch{}), 0.0, 1e-9);
  EXPECT_LT(theta_after_half_second(ForearmMismatch{1.5, 1, 1}), -0.1);
  EXPECT_GT(theta_after_half_second(ForearmMismatch{0.75, 1, 1}), 0.1);

  SimbodyForearm plant(model, ForearmMismatch{1.5, 2.0, 0.5}, ForearmPlantState{});
  const Parameters& p = plant.plant_parameters();
  EXPECT_DOUBLE_EQ(p.mass, 1.5 * model.mass);
  EXPECT_DOUBLE_EQ(p.viscous_friction, 2.0 * model.viscous_friction);
  EXPECT_DOUBLE_EQ(p.coulomb_friction, 2.0 * model.coulomb_friction);
  EXPECT_DOUBLE_EQ(p.T_p, 0.5 * model.T_p);
  EXPECT_DOUBLE_EQ(p.com_distance, model.com_distance);
}

// 4. Bad commands: non-finite -> safe outputs (0, 0), counted; out of range -> clamped.
TEST(SimbodyForearm, NonFiniteCommandsGiveSafeOutputsAndOutOfRangeIsClamped) {
  const Parameters model;
  const double p0 = hmpc::forearm::equilibrium_pressure(model, 0.3);
  SimbodyForearm plant(model, ForearmMismatch{}, ForearmPlantState{0.3, 0.0, p0});
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();

  plant.step(nan, 2.0);
  EXPECT_EQ(plant.applied_v_p(), 0.0);
  EXPECT_EQ(plant.applied_v_m(), 0.0);
  EXPECT_EQ(plant.motor_torque(), 0.0);
  EXPECT_EQ(plant.rejected_commands(), 1u);
  plant.step(3.0, -inf);
  plant.step(inf, nan);
  EXPECT_EQ(plant.applied_v_p(), 0.0);
  EXPECT_EQ(plant.applied_v_m(), 0.0);
  EXPECT_EQ(plant.rejected_commands(), 3u);
  // Vented: the pressure falls from p0 as exp(-t / tau) over the three steps.
  EXPECT_NEAR(plant.state().pressure_bar, p0 * std::exp(-3 * kDt * model.k_vp / model.T_p), 1e-9);

  plant.step(7.5, -9.0);
  EXPECT_EQ(plant.applied_v_p(), model.v_p_max);
  EXPECT_EQ(plant.applied_v_m(), model.v_m_min);
  EXPECT_DOUBLE_EQ(plant.motor_torque(), model.motor_gain * model.v_m_min);
  plant.step(-1.0, 12.0);
  EXPECT_EQ(plant.applied_v_p(), model.v_p_min);
  EXPECT_EQ(plant.applied_v_m(), model.v_m_max);
  EXPECT_EQ(plant.rejected_commands(), 3u);  // clamping is not rejection
  const ForearmPlantState s = plant.state();
  EXPECT_TRUE(std::isfinite(s.theta));
  EXPECT_TRUE(std::isfinite(s.theta_dot));
  EXPECT_TRUE(std::isfinite(s.pressure_bar));
  EXPECT_NEAR(plant.time(), 5 * kDt, 1e-15);
}

std::string construction_error(const ForearmMismatch& m, const ForearmPlantState& x = {}) {
  try {
    SimbodyForearm plant(Parameters{}, m, x);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(SimbodyForearm, InvalidMismatchOrInitialStateThrowsNamingTheField) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (const double bad : {nan, inf, -1.0, 0.0, 0.49, 2.01}) {
    ForearmMismatch m;
    m.mass_scale = bad;
    EXPECT_NE(construction_error(m).find("mass_scale"), std::string::npos) << bad;
    m = ForearmMismatch{};
    m.friction_scale = bad;
    EXPECT_NE(construction_error(m).find("friction_scale"), std::string::npos) << bad;
    m = ForearmMismatch{};
    m.pam_time_constant_scale = bad;
    EXPECT_NE(construction_error(m).find("pam_time_constant_scale"), std::string::npos) << bad;
  }
  EXPECT_EQ(construction_error(ForearmMismatch{0.5, 2.0, 1.0}), "");  // the range's ends are valid
  EXPECT_NE(construction_error({}, {nan, 0, 0}).find("finite"), std::string::npos);
  EXPECT_NE(construction_error({}, {0, 0, -0.1}).find("pressure"), std::string::npos);
  EXPECT_NE(construction_error({}, {2.0, 0, 0}).find("stops"), std::string::npos);
}

// 5. Heap use in the 1 kHz loop. Simbody 3.7 allocates inside every integrator step (its vector
// arithmetic, error norm, saved previous state and projection build vector temporaries and
// views, and so does the forward dynamics), so step() cannot be allocation-free with Simbody's
// integrators: measured 146 per plain 1 ms step, all inside Simbody (none in our forces). The
// bound is about twice that, so a regression (per-step set-up, growth over time) fails.
// Reading the plant allocates nothing.
TEST(SimbodyForearm, HeapUseIsSimbodysOwnAndBounded) {
  constexpr double kMaxAllocationsPerStep = 300;
  const Parameters model;
  SimbodyForearm plant(model, ForearmMismatch{}, ForearmPlantState{0.5, 0.0, 0.0});
  plant.step(1.0, 0.0);  // first step outside the count: lets Simbody size its caches
  const int steps = 2000;
  auto before = heap_monitor::allocations();
  heap_monitor::arm();
  // Changing inputs, a fall onto the lower stop, and bad commands.
  for (int k = 0; k < steps; ++k) {
    const double v_p =
        (k % 500 == 7) ? std::numeric_limits<double>::quiet_NaN() : 0.5 + 0.5 * std::sin(0.01 * k);
    plant.step(v_p, 4.0 * std::sin(0.02 * k));
  }
  heap_monitor::disarm();
  const double per_step = static_cast<double>(heap_monitor::allocations() - before) / steps;
  RecordProperty("allocations_per_step", text(per_step));
  std::printf("SimbodyForearm: %.1f heap allocations per step (inside Simbody)\n", per_step);
  EXPECT_LE(per_step, kMaxAllocationsPerStep);

  before = heap_monitor::allocations();
  heap_monitor::arm();
  double sum = 0;
  for (int k = 0; k < 1000; ++k) {
    const ForearmPlantState s = plant.state();
    sum += s.theta + s.theta_dot + s.pressure_bar + plant.time() + plant.pam_torque() +
           plant.motor_torque() + plant.applied_v_p() + plant.applied_v_m() +
           static_cast<double>(plant.rejected_commands()) + plant.plant_parameters().mass;
  }
  heap_monitor::disarm();
  EXPECT_EQ(heap_monitor::allocations() - before, 0u);
  EXPECT_TRUE(std::isfinite(sum));
}

}  // namespace
