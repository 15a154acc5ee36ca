// Joint-level PID with load-velocity feedback for valve-driven actuators (thesis Sec. 2.7.3,
// "a PID controller with load velocity feedback to compute the valve commands while
// compensating the actuator dynamics", refs. [69, 70]: hydraulic joint torque control).
//
// Why the velocity term: for a valve-controlled actuator the linearised torque (pressure) rate
//   d tau / dt = k_q u - k_v omega - tau / T
// is the flow k_q u through the valve, minus the flow the moving load takes by expanding the
// chamber (k_v omega), minus leakage. The load's motion thus enters the torque as a
// disturbance. Adding (k_v / k_q) omega to the valve command u cancels it: the PID part u_pid
// then sees d tau / dt = k_q u_pid - tau / T, however the load moves.
//
// Sign convention: positive output raises the actuator's torque (pressure), positive
// load_velocity is motion in the direction of positive torque (the driven chamber expands), so
// load_velocity_gain = k_v / k_q is positive.
//
// Control law, per update with error e = setpoint - measurement:
//   output = clamp(feedforward_gain * setpoint + kp e + I - kd d_f + load_velocity_gain * omega)
// with I = ki * integral of e (held in output units so gain changes do not bump the output) and
// d_f the first-order-filtered derivative of the measurement (derivative on measurement, so
// setpoint steps give no derivative kick).
//
// Anti-windup: conditional integration (clamping). While the output is saturated in the
// direction the integral is moving (the sign of ki * e), the integral stops; on the step that
// reaches the limit it advances only as far as brings the output onto the limit. It also stays
// within +-integral_limit. Chosen over back-calculation because it needs no extra tuning gain
// and the integral never holds more than the output limits can use, so it leaves saturation
// on the first step after the error changes sign.
//
// Header-only, allocation-free, no exceptions, no virtual calls: it runs on the joint boards
// (Cortex-M, Scalar = float) and on the host.
#pragma once

#include <cmath>
#include <cstdint>

namespace hmpc {

template <typename Scalar>
class LoadVelocityFeedbackPid {
 public:
  struct Config {
    Scalar kp = Scalar(0);  // output per unit error
    Scalar ki = Scalar(0);  // output per (unit error * s)
    Scalar kd = Scalar(0);  // output per (unit measurement / s)
    // Time constant T_f of the first-order filter on the measurement derivative, s:
    // D(s) = s / (T_f s + 1), discretised by backward Euler so it is stable for any dt.
    // 0: plain backward difference. A cutoff f_c corresponds to T_f = 1 / (2 pi f_c).
    Scalar derivative_time_constant = Scalar(0);
    Scalar integral_limit = Scalar(0);  // |I| bound, output units; 0 disables the integral
    Scalar output_min = Scalar(-1);
    Scalar output_max = Scalar(1);
    Scalar load_velocity_gain = Scalar(0);  // k_lvf = k_v / k_q of the actuator
    Scalar feedforward_gain = Scalar(0);    // output per unit setpoint, e.g. 1 / (k_q T) for torque
    // Output on a rejected update (non-finite input, dt <= 0, invalid config): e.g. the valve
    // command that vents the actuator or holds it at a safe pressure.
    Scalar safe_output = Scalar(0);
  };

  enum class Fault : std::uint8_t {
    kNone = 0,
    kNonFiniteInput,  // setpoint, measurement, load velocity or dt is NaN or infinite
    kNonPositiveTimeStep,
    kInvalidConfig,    // see config_valid()
    kNonFiniteResult,  // finite but extreme inputs overflowed the arithmetic
  };

  struct State {
    Scalar integral = Scalar(0);             // I, output units
    Scalar filtered_derivative = Scalar(0);  // d_f, measurement units per second
    // Derivative on measurement: the previous measurement, not the previous error, is kept.
    Scalar previous_measurement = Scalar(0);
    bool has_previous_measurement = false;
    Scalar output = Scalar(0);  // last output
    bool saturated = false;     // last output was clamped to a limit
    // Sticky: the latest reason an update was rejected, until reset(). Updates after a fault
    // run normally; the board's state machine decides whether to leave closed-loop control.
    Fault fault = Fault::kNone;
    std::uint32_t rejected_updates = 0;
  };

  static bool config_valid(const Config& c) {
    using std::isfinite;
    return isfinite(c.kp) && isfinite(c.ki) && isfinite(c.kd) &&
           isfinite(c.derivative_time_constant) && c.derivative_time_constant >= Scalar(0) &&
           isfinite(c.integral_limit) && c.integral_limit >= Scalar(0) && isfinite(c.output_min) &&
           isfinite(c.output_max) && c.output_min <= c.output_max &&
           isfinite(c.load_velocity_gain) && isfinite(c.feedforward_gain) &&
           isfinite(c.safe_output);
  }

  static void reset(State& state) { state = State{}; }

  // One control step; dt is the time since the previous update, s. Never returns NaN.
  static Scalar update(const Config& config, State& state, Scalar setpoint, Scalar measurement,
                       Scalar load_velocity, Scalar dt) {
    using std::isfinite;
    if (!config_valid(config)) return reject(config, state, Fault::kInvalidConfig);
    if (!isfinite(setpoint) || !isfinite(measurement) || !isfinite(load_velocity) ||
        !isfinite(dt)) {
      return reject(config, state, Fault::kNonFiniteInput);
    }
    if (dt <= Scalar(0)) return reject(config, state, Fault::kNonPositiveTimeStep);

    const Scalar error = setpoint - measurement;

    // Backward-Euler discretisation of s / (T_f s + 1) applied to the measurement:
    //   (T_f + dt) d_k = T_f d_{k-1} + (y_k - y_{k-1}).
    // The first sample after reset (or a rejected update) has no predecessor: d_f starts at 0.
    Scalar derivative = Scalar(0);
    if (state.has_previous_measurement) {
      const Scalar t_f = config.derivative_time_constant;
      derivative = (t_f * state.filtered_derivative + (measurement - state.previous_measurement)) /
                   (t_f + dt);
    }

    const Scalar without_integral = config.feedforward_gain * setpoint + config.kp * error -
                                    config.kd * derivative +
                                    config.load_velocity_gain * load_velocity;

    // Conditional integration: I moves towards a limit only until the output reaches it.
    // Capping at the exact landing value (rather than skipping the whole step) lets the output
    // sit on the limit instead of one increment short of it.
    const Scalar increment = config.ki * error * dt;
    Scalar integral = state.integral + increment;
    if (increment > Scalar(0)) {
      integral = min(integral, max(state.integral, config.output_max - without_integral));
    } else if (increment < Scalar(0)) {
      integral = max(integral, min(state.integral, config.output_min - without_integral));
    }
    integral = clamp(integral, -config.integral_limit, config.integral_limit);

    const Scalar unclamped = without_integral + integral;
    if (!isfinite(derivative) || !isfinite(unclamped)) {
      return reject(config, state, Fault::kNonFiniteResult);
    }
    const Scalar output = clamp(unclamped, config.output_min, config.output_max);

    state.integral = integral;
    state.filtered_derivative = derivative;
    state.previous_measurement = measurement;
    state.has_previous_measurement = true;
    state.output = output;
    state.saturated = output != unclamped;
    return output;
  }

 private:
  static Scalar min(Scalar a, Scalar b) { return b < a ? b : a; }
  static Scalar max(Scalar a, Scalar b) { return a < b ? b : a; }
  static Scalar clamp(Scalar value, Scalar low, Scalar high) { return max(low, min(value, high)); }

  // The integral is kept (the fault may be one bad sample); the derivative restarts, since the
  // skipped sample would otherwise make the next difference span an unknown interval.
  static Scalar reject(const Config& config, State& state, Fault fault) {
    using std::isfinite;
    state.fault = fault;
    ++state.rejected_updates;
    state.has_previous_measurement = false;
    state.filtered_derivative = Scalar(0);
    state.saturated = false;
    state.output = isfinite(config.safe_output) ? config.safe_output : Scalar(0);
    return state.output;
  }
};

}  // namespace hmpc
