// The disturbance torque on the forearm's joint that Eq. 3.1 does not model, estimated on the
// board for offset-free MPC: a generalised-momentum observer (De Luca and Mattone, ICRA 2003)
// on the joint,
//
//   r(t) = K ( I theta'(t) - I theta'(0) - integral_0^t ( c + tau_p + tau_m + r ) ds ),
//
// whose estimate r follows the true disturbance d through a first-order lag, r' = K (d - r),
// from the measured angle, rate and pressure and the applied motor voltage, without
// differentiating the rate. A constant d (a payload, a worn bearing at rest, a valve whose
// steady gain differs) is estimated exactly in steady state; the MPC's model then carries it
// (forearm_problems.hpp OffsetFree). Allocation-free: a Config and a State, a pure update.
#pragma once

#include <cmath>

#include "hmpc/models/forearm.hpp"

namespace hmpc::forearm {

template <typename Scalar>
struct DisturbanceObserver {
  struct Config {
    // K, rad/s: the estimate's bandwidth. 10 rad/s (a 100 ms time constant) settles within the
    // MPC's 200 ms horizon (Table 3.1) twice over per second of target, while the rate sensor's
    // noise (0.01 rad/s in the HIL plant) reaches the estimate as about K I 0.01 = 7 mN·m, 0.2 %
    // of the gravity torque.
    Scalar bandwidth = Scalar(10);
    // |r| <= limit, N·m: the estimate never asks the model for more than the actuators can
    // balance (the PAM's ~11 N·m at 5 bar, less the arm's 3.4 N·m of gravity), so a glitch
    // cannot drive the MPC to garbage.
    Scalar limit = Scalar(5);
  };

  struct State {
    Scalar momentum_at_start = 0;  // I theta'(0)
    Scalar integral = 0;           // of c + tau_p + tau_m + r
    Scalar estimate = 0;           // r, N·m
    bool started = false;
  };

  static void reset(State& s) { s = State{}; }

  // One sample h after the last, at the measured state and the motor voltage applied since the
  // last sample. Returns the estimate.
  static Scalar update(const Parameters<Scalar>& p, const Config& c, State& s, Scalar theta,
                       Scalar theta_dot, Scalar pressure_bar, Scalar v_m, Scalar h) {
    const Scalar momentum = p.inertia() * theta_dot;
    if (!s.started) {
      s = State{momentum, Scalar(0), Scalar(0), true};
      return s.estimate;
    }
    // I theta'' = model torque + d, the model's part at this sample.
    const Scalar model_torque =
        p.inertia() * joint_acceleration(p, theta, theta_dot, pressure_bar, v_m).value;
    s.integral += h * (model_torque + s.estimate);
    const Scalar r = c.bandwidth * (momentum - s.momentum_at_start - s.integral);
    s.estimate = r > c.limit ? c.limit : (r < -c.limit ? -c.limit : r);
    return s.estimate;
  }
};

}  // namespace hmpc::forearm
