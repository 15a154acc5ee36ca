// Central finite differences on fixed-size Eigen vectors, allocation-free.
// Step sizes follow the usual truncation/round-off balance: h ~ eps^(1/3) for first
// derivatives and eps^(1/4) for second derivatives, scaled by max(1, |x_i|).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <limits>

namespace hmpc {

namespace detail {
template <typename Scalar>
Scalar fd_step(Scalar xi, Scalar power) {
  using std::abs;
  using std::pow;
  const Scalar base = pow(std::numeric_limits<Scalar>::epsilon(), power);
  return base * (abs(xi) > Scalar(1) ? abs(xi) : Scalar(1));
}
}  // namespace detail

// J = d f / d x, with f returning a fixed-size vector of J.rows() entries.
template <class Function, class Vector, class Jacobian>
void central_difference_jacobian(const Function& f, const Vector& x, Jacobian& jacobian) {
  using Scalar = typename Vector::Scalar;
  Vector xp = x;
  for (int i = 0; i < x.size(); ++i) {
    const Scalar h = detail::fd_step(x(i), Scalar(1) / Scalar(3));
    xp(i) = x(i) + h;
    const auto f_plus = f(xp);
    xp(i) = x(i) - h;
    const auto f_minus = f(xp);
    xp(i) = x(i);
    jacobian.col(i) = (f_plus - f_minus) / (Scalar(2) * h);
  }
}

// Gradient and Hessian of a scalar function by central differences (Hessian symmetrised).
template <class Function, class Vector, class Gradient, class Hessian>
void central_difference_gradient_hessian(const Function& f, const Vector& x, Gradient& gradient,
                                         Hessian& hessian) {
  using Scalar = typename Vector::Scalar;
  constexpr int n = Vector::RowsAtCompileTime;
  Vector h;
  for (int i = 0; i < n; ++i) h(i) = detail::fd_step(x(i), Scalar(1) / Scalar(4));
  const Scalar f0 = f(x);
  Vector xp = x;
  for (int i = 0; i < n; ++i) {
    xp(i) = x(i) + h(i);
    const Scalar fp = f(xp);
    xp(i) = x(i) - h(i);
    const Scalar fm = f(xp);
    xp(i) = x(i);
    gradient(i) = (fp - fm) / (Scalar(2) * h(i));
    hessian(i, i) = (fp - Scalar(2) * f0 + fm) / (h(i) * h(i));
    for (int j = 0; j < i; ++j) {
      xp(i) = x(i) + h(i);
      xp(j) = x(j) + h(j);
      const Scalar fpp = f(xp);
      xp(j) = x(j) - h(j);
      const Scalar fpm = f(xp);
      xp(i) = x(i) - h(i);
      const Scalar fmm = f(xp);
      xp(j) = x(j) + h(j);
      const Scalar fmp = f(xp);
      xp(i) = x(i);
      xp(j) = x(j);
      hessian(i, j) = hessian(j, i) = (fpp - fpm - fmp + fmm) / (Scalar(4) * h(i) * h(j));
    }
  }
}

}  // namespace hmpc
