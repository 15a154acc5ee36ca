#include "hmpc/ioc/lbfgs.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <stdexcept>
#include <vector>

namespace hmpc::ioc {

namespace {

struct Pair {
  Eigen::VectorXd s, y;
  double rho;  // 1 / (y's)
};

// The two-loop recursion (Nocedal & Wright Alg. 7.4): -H g, H the L-BFGS inverse Hessian with
// H_0 = gamma I, gamma = s'y / y'y of the newest pair (Eq. 7.20).
Eigen::VectorXd descent_direction(const std::deque<Pair>& pairs, const Eigen::VectorXd& g) {
  Eigen::VectorXd q = g;
  std::vector<double> alpha(pairs.size());
  for (int i = static_cast<int>(pairs.size()) - 1; i >= 0; --i) {
    alpha[i] = pairs[i].rho * pairs[i].s.dot(q);
    q -= alpha[i] * pairs[i].y;
  }
  if (!pairs.empty()) q *= 1.0 / (pairs.back().rho * pairs.back().y.squaredNorm());
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const double beta = pairs[i].rho * pairs[i].y.dot(q);
    q += (alpha[i] - beta) * pairs[i].s;
  }
  return -q;
}

}  // namespace

LbfgsResult minimize_lbfgs(const Objective& f, const Eigen::VectorXd& x0, const LbfgsConfig& config,
                           const IterationReport& report) {
  if (config.memory < 1 || config.max_iterations < 0) {
    throw std::invalid_argument("L-BFGS: memory must be >= 1 and max_iterations >= 0");
  }
  LbfgsResult result;
  result.x = x0;
  Eigen::VectorXd g(x0.size()), g_new(x0.size());
  result.value = f(result.x, g);
  result.evaluations = 1;
  if (!std::isfinite(result.value) || !g.allFinite()) {
    throw std::invalid_argument("L-BFGS: the objective or its gradient is not finite at the start");
  }
  std::deque<Pair> pairs;
  constexpr double kArmijo = 1e-4;    // sufficient decrease c_1 (Nocedal & Wright Sec. 3.1)
  constexpr int kMaxBacktracks = 40;  // step halved at most this often (2^-40 ~ 1e-12)
  for (result.iterations = 0; result.iterations < config.max_iterations;) {
    const double scale = std::max(1.0, std::abs(result.value));
    if (g.lpNorm<Eigen::Infinity>() <= config.gradient_tolerance * scale) {
      result.converged = true;
      result.stop = "gradient below tolerance";
      return result;
    }
    Eigen::VectorXd d = descent_direction(pairs, g);
    double slope = g.dot(d);
    if (!(slope < 0.0)) {  // lost descent (round-off): restart from steepest descent
      pairs.clear();
      d = -g;
      slope = -g.squaredNorm();
    }
    // First step without curvature pairs: length 1 in the largest coordinate.
    double step = pairs.empty() ? 1.0 / std::max(1.0, d.lpNorm<Eigen::Infinity>()) : 1.0;
    Eigen::VectorXd x_new;
    double value_new = 0.0;
    bool decreased = false;
    for (int k = 0; k < kMaxBacktracks; ++k, step *= 0.5) {
      x_new = result.x + step * d;
      value_new = f(x_new, g_new);
      ++result.evaluations;
      if (std::isfinite(value_new) && g_new.allFinite() &&
          value_new <= result.value + kArmijo * step * slope) {
        decreased = true;
        break;
      }
    }
    if (!decreased) {
      result.stop = "line search found no decrease";
      return result;
    }
    ++result.iterations;
    Pair pair{x_new - result.x, g_new - g, 0.0};
    const double curvature = pair.s.dot(pair.y);
    if (curvature > 1e-12 * pair.s.norm() * pair.y.norm()) {
      pair.rho = 1.0 / curvature;
      pairs.push_back(std::move(pair));
      if (static_cast<int>(pairs.size()) > config.memory) pairs.pop_front();
    }
    const double decrease = result.value - value_new;
    result.x = x_new;
    result.value = value_new;
    g = g_new;
    if (report) report(result.iterations, result.x, result.value);
    if (decrease <= config.value_tolerance * scale) {
      result.converged = true;
      result.stop = "decrease below tolerance";
      return result;
    }
  }
  result.stop = "iteration limit";
  return result;
}

}  // namespace hmpc::ioc
