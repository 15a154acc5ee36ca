#include "hmpc/humanoid/step.hpp"

#include <cmath>

namespace hmpc::humanoid {

JointStop joint_stop(double q, double v, double lower, double upper, const Parameters& parameters) {
  const double k = parameters.stop_stiffness, b = parameters.stop_damping,
               w = parameters.stop_width;
  // s(d) = w log(1 + exp(d / w)) and sigma(d / w) = s'(d), written to stay finite for any d.
  const auto softplus = [w](double d) {
    return d > 0.0 ? d + w * std::log1p(std::exp(-d / w)) : w * std::log1p(std::exp(d / w));
  };
  const auto logistic = [w](double d) {
    return d > 0.0 ? 1.0 / (1.0 + std::exp(-d / w)) : std::exp(d / w) / (1.0 + std::exp(d / w));
  };
  const double above = q - upper, below = lower - q;
  const double sigma_above = logistic(above), sigma_below = logistic(below);
  const double gate = sigma_above + sigma_below;
  // sigma(d / w)' = sigma (1 - sigma) / w, and below = -q.
  const double gate_slope =
      (sigma_above * (1.0 - sigma_above) - sigma_below * (1.0 - sigma_below)) / w;
  JointStop stop;
  stop.torque = -k * softplus(above) + k * softplus(below) - b * gate * v;
  stop.stiffness = k * gate;
  stop.damping = b * gate;
  stop.stiffness_slope = k * gate_slope;
  stop.damping_slope = b * gate_slope;
  return stop;
}

}  // namespace hmpc::humanoid
