#include "hmpc/ioc/learn.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace hmpc::ioc {

namespace {

// theta = log w as the optimiser's vector, and back.
Eigen::VectorXd log_of(const Weights& w) { return w.array().log().matrix(); }
Weights exp_of(const Eigen::VectorXd& theta) { return theta.array().exp().matrix(); }
bool usable(const Weights& w) { return w.allFinite() && (w.array() > 0.0).all(); }

}  // namespace

LearnResult learn_weights(const LocalIoc& ioc, const LearnConfig& config,
                          const LearnProgress& progress) {
  if (ioc.window_count() == 0)
    throw std::invalid_argument("IOC: no demonstration is a whole window long");
  if (!usable(config.initial)) {
    throw std::invalid_argument("IOC: every initial weight must be positive and finite");
  }
  // f(theta) = -log p(D | exp(theta)); df/dtheta_k = -w_k d log p / d w_k.
  const Objective likelihood = [&ioc](const Eigen::VectorXd& theta, Eigen::VectorXd& gradient) {
    const Weights w = exp_of(theta);
    if (!usable(w)) return std::numeric_limits<double>::infinity();
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
    if (progress) progress(iteration, exp_of(theta), -value);
  };
  LbfgsResult fit = minimize_lbfgs(likelihood, log_of(config.initial), config.lbfgs, report);
  result.iterations = fit.iterations;
  result.evaluations = fit.evaluations;

  if (config.estimator == Estimator::kLeastExcessCost) {
    // The ratios: the excess cost's minimum with the weights' geometric mean held at the
    // likelihood's (theta's mean fixed; the optimiser moves the centred part only).
    const Eigen::VectorXd centre = fit.x;
    const auto weights = [&centre](const Eigen::VectorXd& step) {
      return exp_of(centre + (step.array() - step.mean()).matrix());
    };
    const Objective excess = [&](const Eigen::VectorXd& step, Eigen::VectorXd& gradient) {
      const Weights w = weights(step);
      if (!usable(w)) return std::numeric_limits<double>::infinity();
      Weights dw;
      const double value = ioc.excess_cost(w, &dw);
      const Eigen::VectorXd g = w.cwiseProduct(dw);
      gradient = (g.array() - g.mean()).matrix();
      return value;
    };
    const LbfgsResult ratios =
        minimize_lbfgs(excess, Eigen::VectorXd::Zero(kWeightCount), config.lbfgs);
    fit.x = log_of(weights(ratios.x));
    fit.value = -ioc.log_likelihood(exp_of(fit.x));
    fit.converged = fit.converged && ratios.converged;
    fit.stop += "; excess cost: " + ratios.stop;
    result.iterations += ratios.iterations;
    result.evaluations += ratios.evaluations;
  }
  result.weights = exp_of(fit.x);
  result.log_likelihood = -fit.value;
  result.converged = fit.converged;
  result.stop = fit.stop;
  return result;
}

}  // namespace hmpc::ioc
