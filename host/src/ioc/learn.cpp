#include "hmpc/ioc/learn.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace hmpc::ioc {

LearnResult learn_weights(const LocalIoc& ioc, const LearnConfig& config,
                          const LearnProgress& progress) {
  if (ioc.window_count() == 0)
    throw std::invalid_argument("IOC: no demonstration is a whole window long");
  if (!(config.initial.array() > 0.0).all() || !config.initial.allFinite()) {
    throw std::invalid_argument("IOC: every initial weight must be positive and finite");
  }
  // f(theta) = -log p(D | exp(theta)); df/dtheta_k = -w_k d log p / d w_k.
  const Objective objective = [&ioc](const Eigen::VectorXd& theta, Eigen::VectorXd& gradient) {
    const Weights w = theta.array().exp().matrix();
    if (!w.allFinite() || !(w.array() > 0.0).all()) return std::numeric_limits<double>::infinity();
    Weights dw;
    const double value = ioc.log_likelihood(w, &dw);
    gradient = -w.cwiseProduct(dw);
    return -value;
  };
  LearnResult result;
  result.initial_log_likelihood = ioc.log_likelihood(config.initial);
  if (!std::isfinite(result.initial_log_likelihood)) {
    throw std::invalid_argument("IOC: the likelihood is not finite at the initial weights");
  }
  const IterationReport report = [&progress](int iteration, const Eigen::VectorXd& theta,
                                             double value) {
    if (progress) progress(iteration, theta.array().exp().matrix(), -value);
  };
  const LbfgsResult fit =
      minimize_lbfgs(objective, config.initial.array().log().matrix(), config.lbfgs, report);
  result.weights = fit.x.array().exp().matrix();
  result.log_likelihood = -fit.value;
  result.iterations = fit.iterations;
  result.evaluations = fit.evaluations;
  result.converged = fit.converged;
  result.stop = fit.stop;
  return result;
}

}  // namespace hmpc::ioc
