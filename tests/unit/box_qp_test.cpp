// The box QP of box-DDP against brute-force enumeration of active sets.
#include "hmpc/solver/box_qp.hpp"

#include <gtest/gtest.h>

#include <random>

namespace {

using V3 = Eigen::Matrix<double, 3, 1>;
using M3 = Eigen::Matrix<double, 3, 3>;

double objective(const M3& H, const V3& g, const V3& x) { return g.dot(x) + 0.5 * x.dot(H * x); }

// Every assignment of each variable to {free, lower, upper}; the free block solved exactly.
V3 brute_force(const M3& H, const V3& g, const V3& lo, const V3& hi) {
  double best = std::numeric_limits<double>::infinity();
  V3 best_x = V3::Zero();
  for (int code = 0; code < 27; ++code) {
    int c = code;
    V3 x;
    std::array<int, 3> state{};
    for (int i = 0; i < 3; ++i, c /= 3) state[i] = c % 3;
    std::vector<int> free;
    for (int i = 0; i < 3; ++i) {
      if (state[i] == 1) x(i) = lo(i);
      if (state[i] == 2) x(i) = hi(i);
      if (state[i] == 0) free.push_back(i);
    }
    if (!free.empty()) {
      Eigen::MatrixXd Hff(free.size(), free.size());
      Eigen::VectorXd rhs(free.size());
      for (size_t a = 0; a < free.size(); ++a) {
        rhs(a) = -g(free[a]);
        for (int j = 0; j < 3; ++j)
          if (state[j] != 0) rhs(a) -= H(free[a], j) * x(j);
        for (size_t b = 0; b < free.size(); ++b) Hff(a, b) = H(free[a], free[b]);
      }
      const Eigen::VectorXd xf = Hff.ldlt().solve(rhs);
      for (size_t a = 0; a < free.size(); ++a) x(free[a]) = xf(a);
    }
    if ((x.array() < lo.array() - 1e-12).any() || (x.array() > hi.array() + 1e-12).any()) continue;
    const double f = objective(H, g, x);
    if (f < best) {
      best = f;
      best_x = x;
    }
  }
  return best_x;
}

TEST(BoxQp, MatchesBruteForceOnRandomProblems) {
  std::mt19937 rng(42);
  std::normal_distribution<double> n(0, 1);
  for (int trial = 0; trial < 200; ++trial) {
    M3 L;
    for (int i = 0; i < 9; ++i) L(i) = n(rng);
    const M3 H = L * L.transpose() + 0.1 * M3::Identity();
    const V3 g(3 * n(rng), 3 * n(rng), 3 * n(rng));
    const V3 lo(-std::abs(n(rng)), -std::abs(n(rng)), -std::abs(n(rng)));
    const V3 hi(std::abs(n(rng)), std::abs(n(rng)), std::abs(n(rng)));
    hmpc::BoxQpSolution<double, 3> sol;
    hmpc::solve_box_qp<double, 3>(H, g, lo, hi, V3::Zero(), sol);
    ASSERT_TRUE(sol.usable());
    const V3 ref = brute_force(H, g, lo, hi);
    EXPECT_NEAR(objective(H, g, sol.x), objective(H, g, ref), 1e-9) << "trial " << trial;
    EXPECT_LT((sol.x - ref).norm(), 1e-6) << "trial " << trial;
    EXPECT_TRUE((sol.x.array() >= lo.array()).all() && (sol.x.array() <= hi.array()).all());
  }
}

TEST(BoxQp, ReportsIndefiniteHessian) {
  M3 H = M3::Identity();
  H(1, 1) = -1;
  hmpc::BoxQpSolution<double, 3> sol;
  hmpc::solve_box_qp<double, 3>(H, V3(1, 1, 1), V3::Constant(-1e9), V3::Constant(1e9), V3::Zero(),
                                sol);
  EXPECT_EQ(sol.status, hmpc::BoxQpStatus::kNotPositiveDefinite);
  EXPECT_FALSE(sol.usable());
}

}  // namespace
