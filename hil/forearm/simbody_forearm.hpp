// The forearm of Eq. 3.1 (common/include/hmpc/models/forearm.hpp) built in Simbody: the plant
// the HIL harness runs the forearm board against. Same physical parameters as the controller's
// model, but none of its joint equation: Simbody supplies the multibody dynamics (a pin joint,
// a rigid link, gravity), the integration and the state, which holds the PAM pressure as a
// continuous variable. On top of Eq. 3.1 the plant has mechanical end stops, actuator limits,
// and scale factors for plant-model mismatch.
//
// Simbody stays behind this interface (pimpl), so that only simbody_forearm.cpp needs Simbody's
// headers and their -UNDEBUG (Debian 12's Simbody 3.7 crashes when code
// including its headers is built with NDEBUG and the library without it: their inline code
// then disagrees).
#pragma once

#include <cstdint>
#include <memory>

#include "hmpc/models/forearm.hpp"

namespace hmpc::hil {

// Plant-model mismatch for robustness studies: the plant's mass, friction (viscous and Coulomb
// alike) and valve time constant T_p are the model's times these factors. Each must be finite
// and in [0.5, 2].
struct ForearmMismatch {
  double mass_scale = 1, friction_scale = 1, pam_time_constant_scale = 1;
};

// The HIL demo's default: a modest mismatch, as a real arm has: a heavier forearm (a hand-held
// load of ~5 % of its mass), more friction (a worn bearing), a slower valve.
constexpr ForearmMismatch kDemoMismatch{1.05, 1.2, 1.1};

// The plant's parameters: the model's with the mismatch applied. Throws std::invalid_argument
// naming the field if a factor is out of range or the model's end stops are malformed.
forearm::Parameters<double> with_mismatch(const forearm::Parameters<double>& model,
                                          const ForearmMismatch& mismatch);

// theta (rad, from the horizontal, flexion positive), theta' (rad/s), PAM pressure (bar).
struct ForearmPlantState {
  double theta = 0, theta_dot = 0, pressure_bar = 0;
};

class SimbodyForearm {
 public:
  static constexpr double kStep = 0.001;  // s, one plant step

  // Throws std::invalid_argument naming the field if the mismatch is out of range or the
  // initial state is not finite, has a negative pressure or lies outside the stops.
  SimbodyForearm(const forearm::Parameters<double>& model, const ForearmMismatch& mismatch,
                 const ForearmPlantState& initial);
  ~SimbodyForearm();
  SimbodyForearm(const SimbodyForearm&) = delete;
  SimbodyForearm& operator=(const SimbodyForearm&) = delete;

  // Advances kStep with these voltages held (zero-order hold). Voltages are clamped to the
  // model's v_p / v_m ranges; if either is not finite, the safe outputs (0, 0) are applied and
  // the command is counted in rejected_commands(). Not allocation-free: Simbody 3.7's
  // integrator allocates ~150 times per step internally (tests/hil/simbody_forearm_test.cpp).
  void step(double v_p, double v_m);

  ForearmPlantState state() const;
  double time() const;          // s since construction
  double pam_torque() const;    // N·m at the current state
  double motor_torque() const;  // N·m applied during the last step
  double applied_v_p() const;   // V, after clamping
  double applied_v_m() const;   // V, after clamping
  std::uint64_t rejected_commands() const;
  const forearm::Parameters<double>& plant_parameters() const;  // model with the mismatch applied

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace hmpc::hil
