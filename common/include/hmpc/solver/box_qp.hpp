// Box-constrained quadratic program of box-DDP (Tassa, Mansard & Todorov, ICRA 2014):
//   min_x 0.5 x'Hx + g'x   s.t.  lower <= x <= upper,
// solved by projected Newton with an Armijo line search along the projected arc.
// Fixed-size and allocation-free: the Newton system on the free set is solved with the
// clamped rows and columns of H replaced by the identity, so no dynamic sub-matrices arise.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>

namespace hmpc {

enum class BoxQpStatus {
  kConverged,         // projected gradient on the free set below tolerance
  kAllClamped,        // every variable sits on a bound with the gradient pushing outward
  kSmallImprovement,  // relative improvement below tolerance
  kMaxIterations,
  kLineSearchFailed,
  kNotPositiveDefinite,  // H restricted to the free set is not positive definite
};

template <typename Scalar>
struct BoxQpConfig {
  int max_iterations = 100;
  Scalar min_gradient = Scalar(1e-8);
  Scalar min_relative_improvement = Scalar(1e-8);
  Scalar step_decrease = Scalar(0.6);
  Scalar min_step = Scalar(1e-22);
  Scalar armijo = Scalar(0.1);
};

template <typename Scalar, int N>
struct BoxQpSolution {
  using Vector = Eigen::Matrix<Scalar, N, 1>;
  using Matrix = Eigen::Matrix<Scalar, N, N>;
  Vector x;
  Vector free_mask;  // 1 where x is free, 0 where it is clamped at an active bound
  // Cholesky of H with clamped rows/columns replaced by the identity: solving with it gives
  // -H_ff^{-1} on the free block and zero on the clamped one (needed for the feedback gain).
  Eigen::LLT<Matrix> free_factor;
  BoxQpStatus status = BoxQpStatus::kMaxIterations;
  int iterations = 0;

  bool usable() const { return status != BoxQpStatus::kNotPositiveDefinite; }
};

namespace detail {
template <typename Scalar, int N>
Eigen::Matrix<Scalar, N, N> mask_clamped(const Eigen::Matrix<Scalar, N, N>& H,
                                         const Eigen::Matrix<Scalar, N, 1>& free_mask) {
  Eigen::Matrix<Scalar, N, N> masked = H;
  for (int i = 0; i < N; ++i) {
    if (free_mask(i) == Scalar(0)) {
      masked.row(i).setZero();
      masked.col(i).setZero();
      masked(i, i) = Scalar(1);
    }
  }
  return masked;
}
}  // namespace detail

template <typename Scalar, int N>
void solve_box_qp(const Eigen::Matrix<Scalar, N, N>& H, const Eigen::Matrix<Scalar, N, 1>& g,
                  const Eigen::Matrix<Scalar, N, 1>& lower,
                  const Eigen::Matrix<Scalar, N, 1>& upper,
                  const Eigen::Matrix<Scalar, N, 1>& initial_guess, BoxQpSolution<Scalar, N>& out,
                  const BoxQpConfig<Scalar>& config = {}) {
  using Vector = Eigen::Matrix<Scalar, N, 1>;
  const auto objective = [&](const Vector& x) { return x.dot(g) + Scalar(0.5) * x.dot(H * x); };

  Vector& x = out.x;
  x = initial_guess.cwiseMax(lower).cwiseMin(upper);
  Scalar value = objective(x);
  Scalar previous_value = value;
  Vector previous_free = Vector::Constant(Scalar(-1));
  out.status = BoxQpStatus::kMaxIterations;

  int iteration = 0;
  for (; iteration < config.max_iterations; ++iteration) {
    if (iteration > 0 &&
        (previous_value - value) < config.min_relative_improvement *
                                       (previous_value < 0 ? -previous_value : previous_value)) {
      out.status = BoxQpStatus::kSmallImprovement;
      break;
    }
    previous_value = value;

    const Vector gradient = g + H * x;
    for (int i = 0; i < N; ++i) {
      const bool clamped = (x(i) == lower(i) && gradient(i) > Scalar(0)) ||
                           (x(i) == upper(i) && gradient(i) < Scalar(0));
      out.free_mask(i) = clamped ? Scalar(0) : Scalar(1);
    }
    if (out.free_mask.isZero()) {
      out.free_factor.compute(Eigen::Matrix<Scalar, N, N>::Identity());  // keeps the invariant
      out.status = BoxQpStatus::kAllClamped;
      break;
    }
    if (out.free_mask != previous_free) {
      out.free_factor.compute(detail::mask_clamped(H, out.free_mask));
      if (out.free_factor.info() != Eigen::Success) {
        out.status = BoxQpStatus::kNotPositiveDefinite;
        break;
      }
      previous_free = out.free_mask;
    }
    if (gradient.cwiseProduct(out.free_mask).norm() < config.min_gradient) {
      out.status = BoxQpStatus::kConverged;
      break;
    }

    // Newton step on the free set with clamped variables held: H_ff x_f = -(g_f + H_fc x_c).
    const Vector x_clamped = x.cwiseProduct(Vector::Ones() - out.free_mask);
    const Vector rhs = (g + H * x_clamped).cwiseProduct(out.free_mask);
    const Vector newton_target = -out.free_factor.solve(rhs);
    const Vector search = (newton_target - x).cwiseProduct(out.free_mask);
    const Scalar slope = search.dot(gradient);
    if (slope >= Scalar(0)) {  // no descent left at machine precision
      out.status = BoxQpStatus::kConverged;
      break;
    }

    Scalar step = Scalar(1);
    Vector candidate = (x + step * search).cwiseMax(lower).cwiseMin(upper);
    Scalar candidate_value = objective(candidate);
    while ((candidate_value - value) / (step * slope) < config.armijo) {
      step *= config.step_decrease;
      if (step < config.min_step) break;
      candidate = (x + step * search).cwiseMax(lower).cwiseMin(upper);
      candidate_value = objective(candidate);
    }
    if (step < config.min_step) {
      out.status = BoxQpStatus::kLineSearchFailed;
      break;
    }
    x = candidate;
    value = candidate_value;
  }
  out.iterations = iteration;
}

}  // namespace hmpc
