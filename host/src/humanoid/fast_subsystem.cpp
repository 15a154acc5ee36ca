#include "hmpc/humanoid/fast_subsystem.hpp"

#include <cmath>

namespace hmpc::humanoid {

double perturbation_parameter(const MassMatrix& M) {
  const double base = M.topLeftCorner<kBaseDofs, kBaseDofs>().norm();
  // ||M_leg||^2 = ||M||^2 - ||M11||^2 (Frobenius norms add over disjoint blocks).
  return std::sqrt(M.squaredNorm() - base * base) / base;
}

}  // namespace hmpc::humanoid
