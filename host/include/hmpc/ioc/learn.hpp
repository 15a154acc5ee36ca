// Learning the weights (thesis Sec. 4.2.2): maximise log p(D | w) of local_ioc.hpp by L-BFGS
// over theta = log w, so that every weight stays positive and H positive definite (our
// replacement for the thesis's augmented Lagrangian, see local_ioc.hpp).
#pragma once

#include <functional>

#include "hmpc/ioc/lbfgs.hpp"
#include "hmpc/ioc/local_ioc.hpp"

namespace hmpc::ioc {

enum class Estimator {
  // Eq. 4.10's maximum over all 13 weights, as the thesis learns.
  kMaximumLikelihood,
  // Eq. 4.10's low-temperature limit: the weights' common scale from Eq. 4.10's maximum, their
  // ratios from the demonstrations' least excess cost (LocalIoc::excess_cost) at that scale.
  kLeastExcessCost,
};

struct LearnConfig {
  Weights initial = initial_weights();  // Sec. 4.3.1
  Estimator estimator = Estimator::kMaximumLikelihood;
  LbfgsConfig lbfgs{};
};

struct LearnResult {
  Weights weights;
  double log_likelihood = 0.0, initial_log_likelihood = 0.0;
  int iterations = 0, evaluations = 0;
  bool converged = false;
  std::string stop;
};

// Called after each L-BFGS iteration with its number, the weights and log p(D | w).
using LearnProgress = std::function<void(int iteration, const Weights& w, double log_likelihood)>;

// Throws std::invalid_argument if `ioc` has no window or an initial weight is not positive.
LearnResult learn_weights(const LocalIoc& ioc, const LearnConfig& config = LearnConfig{},
                          const LearnProgress& progress = nullptr);

}  // namespace hmpc::ioc
