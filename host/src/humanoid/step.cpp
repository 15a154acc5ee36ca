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
  const double gate = logistic(above) + logistic(below);
  JointStop stop;
  stop.torque = -k * softplus(above) + k * softplus(below) - b * gate * v;
  stop.stiffness = k * gate;
  stop.damping = b * gate;
  return stop;
}

}  // namespace hmpc::humanoid
