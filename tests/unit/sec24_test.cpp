// Thesis Sec. 2.4 reproduced closed loop: the qualitative results of Figs. 2.3 and 2.4.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "hmpc/host/sec24_scenario.hpp"
#include "hmpc/models/singularly_perturbed_example.hpp"

namespace {

using namespace hmpc::sec24;

const std::map<Method, RunResult>& runs() {
  static const std::map<Method, RunResult> all = [] {
    std::map<Method, RunResult> m;
    for (Method method : kAllMethods) m.emplace(method, run(method));
    return m;
  }();
  return all;
}

// RMS over the run of the difference to the Fine MPC's trajectory (the original problem).
double rms_to_fine(Method method, bool fast_state) {
  const auto& a = runs().at(method).steps;
  const auto& f = runs().at(Method::kFine).steps;
  double sum = 0;
  for (size_t k = 0; k < f.size(); ++k) {
    const double d = fast_state ? a[k].z - f[k].z : a[k].y - f[k].y;
    sum += d * d;
  }
  return std::sqrt(sum / static_cast<double>(f.size()));
}

TEST(Sec24, EveryMethodRunsTheFullHorizonWithUsablePlans) {
  for (Method method : kAllMethods) {
    const RunResult& r = runs().at(method);
    EXPECT_EQ(r.steps.size(), 400u) << to_string(method);
    EXPECT_EQ(r.unusable_solves, 0) << to_string(method);
    EXPECT_TRUE(std::isfinite(r.accumulated_cost)) << to_string(method);
    const int layers = (method == Method::kFine || method == Method::kCoarse) ? 1 : 2;
    for (const auto& s : r.steps) EXPECT_LE(s.iterations, 50 * layers) << to_string(method);
  }
}

TEST(Sec24, FineMpcRegulatesToTheTarget) {
  // 0.4 s is about three time constants of the closed slow loop: y within 2 % of y_d.
  const RunResult& fine = runs().at(Method::kFine);
  EXPECT_NEAR(fine.final_y, 1.0, 0.02);
  EXPECT_NEAR(fine.final_z, 2.0, 0.02);
}

TEST(Sec24, SlowFastDoesNotBringYToItsTarget) {
  // Fig. 2.3: the slow subsystem mispredicts y where Eq. 2.25 has no unique root.
  const RunResult& slow_fast = runs().at(Method::kSlowFast);
  const RunResult& fine = runs().at(Method::kFine);
  EXPECT_GT(std::abs(slow_fast.final_y - 1.0), 0.1);
  EXPECT_GT(std::abs(slow_fast.final_y - 1.0), 5 * std::abs(fine.final_y - 1.0));
  EXPECT_GT(rms_to_fine(Method::kSlowFast, false), 0.2);
  EXPECT_GT(slow_fast.accumulated_cost, 1.5 * fine.accumulated_cost);
}

TEST(Sec24, SlowModelHasNoRootWhereTheThesisSaysSo) {
  // At y = 0, Eq. 2.25 reads cos z = u2 - u1: no root when |u2 - u1| > 1, so the Newton
  // "root" the slow subsystem uses does not satisfy g = 0.
  const Parameters<double> p;
  const SlowSubsystem<double> slow(p, 0.01);
  const Vector2<double> u(0.0, 1.5);
  const double z_hat = slow.fast_equilibrium(0.0, u);
  EXPECT_GT(std::abs(fast_rate(0.0, z_hat, u)), 0.1);
  // Where a root exists (y = 1, u = 0) Newton finds it.
  const Vector2<double> zero = Vector2<double>::Zero();
  EXPECT_LT(std::abs(fast_rate(1.0, slow.fast_equilibrium(1.0, zero), zero)), 1e-9);
}

TEST(Sec24, CoarseFastEndsNearTheFineResultOnBothStates) {
  const RunResult& cf = runs().at(Method::kCoarseFast);
  const RunResult& fine = runs().at(Method::kFine);
  EXPECT_NEAR(cf.final_y, fine.final_y, 0.01);
  EXPECT_NEAR(cf.final_z, fine.final_z, 0.01);
  EXPECT_LT(rms_to_fine(Method::kCoarseFast, false), 0.03);
  EXPECT_LT(rms_to_fine(Method::kCoarseFast, true), 0.03);
  EXPECT_LT(cf.accumulated_cost, 1.02 * fine.accumulated_cost);
}

TEST(Sec24, CoarseAloneIsWorseThanCoarseFastOnTheFastState) {
  // Fig. 2.4: with only the 10 ms step the fast transient is not optimised.
  const double coarse = rms_to_fine(Method::kCoarse, true);
  const double coarse_fast = rms_to_fine(Method::kCoarseFast, true);
  EXPECT_GT(coarse, 3 * coarse_fast) << "coarse " << coarse << " coarse-fast " << coarse_fast;
  EXPECT_GT(runs().at(Method::kCoarse).accumulated_cost,
            runs().at(Method::kCoarseFast).accumulated_cost);
}

TEST(Sec24, CoarseFastReoptimisesLessThanFine) {
  // Machine-independent proxy of Fig. 2.5: decision variables times iterations per step.
  // Both layers' horizons together (40 + 30 steps) are bounded by 70 per iteration.
  double fine_work = 0, cf_work = 0;
  for (const auto& s : runs().at(Method::kFine).steps) fine_work += 400.0 * s.iterations;
  for (const auto& s : runs().at(Method::kCoarseFast).steps) cf_work += 70.0 * s.iterations;
  EXPECT_LT(cf_work, 0.5 * fine_work);
}

TEST(Sec24, RejectsNonPositiveSampleCounts) {
  RunOptions options;
  options.samples = 0;
  EXPECT_THROW(run(Method::kFine, options), std::invalid_argument);
}

}  // namespace
