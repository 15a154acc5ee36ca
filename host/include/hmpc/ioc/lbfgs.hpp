// Limited-memory BFGS (Nocedal & Wright, Numerical Optimization, Alg. 7.4 and 7.5) for
// IOC's likelihood (thesis Sec. 4.2.2: "a gradient-based optimization approach (LBFGS)").
// Our own, small: the two-loop recursion, a backtracking line search on the Armijo condition,
// and a pair (s, y) kept only where the curvature s'y is positive, so the implied Hessian
// stays positive definite without a Wolfe line search.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <string>

namespace hmpc::ioc {

struct LbfgsConfig {
  int memory = 8;  // pairs (s, y) kept; 3-20 is the usual range (Nocedal & Wright)
  int max_iterations = 100;
  // Converged when |grad f|_inf <= gradient_tolerance * max(1, |f|), or when an iteration
  // lowers f by less than value_tolerance * max(1, |f|).
  double gradient_tolerance = 1e-6;
  double value_tolerance = 1e-10;
};

struct LbfgsResult {
  Eigen::VectorXd x;
  double value = 0.0;
  int iterations = 0, evaluations = 0;
  bool converged = false;
  std::string stop;  // why it stopped, for logs
};

// f(x, gradient) returns f(x) and writes its gradient.
using Objective = std::function<double(const Eigen::VectorXd& x, Eigen::VectorXd& gradient)>;
// Called after each iteration with its number (from 1), x and f(x).
using IterationReport = std::function<void(int iteration, const Eigen::VectorXd& x, double value)>;

// Minimises f from x0. A non-finite f or gradient at x0 throws std::invalid_argument; a
// non-finite value during a line search counts as no decrease.
LbfgsResult minimize_lbfgs(const Objective& f, const Eigen::VectorXd& x0, const LbfgsConfig& config,
                           const IterationReport& report = nullptr);

}  // namespace hmpc::ioc
