// How large a sinusoid the forearm's actuators can make the joint follow: a first-harmonic
// (describing-function) bound on Eq. 3.1, linearised about the sinusoid's centre with the PAM
// holding the arm there. Every signal is reduced to its fundamental at the target's frequency:
//
//   needed   I theta'' = K theta - b theta' - F_c sign(theta') + tau_P dP + k_m v_m
//            for theta = A sin(w t):  U = (-(I w^2 + K) + j w b) A + j (4 / pi) F_c
//   valve    the largest fundamental of a voltage inside [v_min, v_max] with mean V_h (the
//            holding voltage) is a rectangle's: (2 (v_max - v_min) / pi) sin(pi d),
//            d = (V_h - v_min) / (v_max - v_min)
//   pressure T_p dP/dt = -k_vp P + v_p (Eq. 3.1):  |dP| = |dv_p| / sqrt(k_vp^2 + (w T_p)^2)
//   motor    the same rectangle bound on v_m about 0, times k_m
//
// The largest trackable amplitude A_max solves |U(A)| = PAM + motor bound (the two can be put
// in phase). A controller can do no better than an output of A_max in phase with the target,
// so a larger target leaves an RMS error of at least (A - A_max) / sqrt 2. It is an estimate,
// not a proof: the muscle's force is nonlinear in pressure and angle over a large swing, and a
// controller may shift the mean pressure; the runner prints it beside the measured errors.
#pragma once

#include <algorithm>
#include <cmath>

#include "hmpc/constants.hpp"
#include "hmpc/models/forearm.hpp"

namespace hmpc::forearm {

struct TrackingLimit {
  double pam_torque;       // N·m, the largest fundamental PAM torque at this frequency
  double motor_torque;     // N·m, the motor's
  double max_amplitude;    // rad, A_max
  double rms_error_floor;  // rad, (A - A_max) / sqrt 2 for the asked amplitude A, or 0
};

// Largest fundamental amplitude of a signal inside [lower, upper] whose mean is `mean`.
inline double largest_fundamental(double lower, double upper, double mean) {
  const double span = upper - lower;
  const double duty = std::clamp((mean - lower) / span, 0.0, 1.0);
  return 2 * span / kPi<double> * std::sin(kPi<double> * duty);
}

inline TrackingLimit tracking_limit(const Parameters<double>& p, double frequency_hz,
                                    double amplitude, double offset) {
  const double w = 2 * kPi<double> * frequency_hz;
  const double hold_pressure = equilibrium_pressure(p, offset);
  const PamTorque<double> pam = pam_torque(p, hold_pressure, offset);
  // K: the slope in theta of gravity's and the muscle's torque at the centre, holding pressure
  // (negative where they pull the arm back, as the muscle's shortening does).
  const double stiffness = p.mass * p.gravity * p.com_distance * std::sin(offset) + pam.d_theta;
  const double in_phase = p.inertia() * w * w + stiffness;  // N·m/rad
  const double quadrature = w * p.viscous_friction;         // N·m/rad
  const double coulomb = 4 / kPi<double> * p.coulomb_friction;

  TrackingLimit l{};
  const double valve = largest_fundamental(p.v_p_min, p.v_p_max, p.k_vp * hold_pressure);
  l.pam_torque = pam.d_pressure * valve / std::hypot(p.k_vp, w * p.T_p);
  l.motor_torque = p.motor_gain * largest_fundamental(p.v_m_min, p.v_m_max, 0.0);
  // |U(A)|^2 = (in_phase A)^2 + (quadrature A + coulomb)^2 = available^2, the positive root.
  const double available = l.pam_torque + l.motor_torque;
  const double a = in_phase * in_phase + quadrature * quadrature;
  const double b = 2 * quadrature * coulomb;
  const double c = coulomb * coulomb - available * available;
  l.max_amplitude = c >= 0 ? 0.0 : (-b + std::sqrt(b * b - 4 * a * c)) / (2 * a);
  l.rms_error_floor = std::max(0.0, amplitude - l.max_amplitude) / std::sqrt(2.0);
  return l;
}

}  // namespace hmpc::forearm
