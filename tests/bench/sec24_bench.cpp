// Fig. 2.5 analogue: per-step solve time of the four Sec. 2.4 MPCs, measured side by side in
// one run. Each benchmark iteration is one full 0.4 s closed-loop simulation (400 solves);
// the thesis averages the maximum over five simulations, so do we (--benchmark_repetitions
// is not needed: the iteration count is fixed at 5).
#include <benchmark/benchmark.h>

#include <cstdio>
#include <map>
#include <vector>

#include "hmpc/host/sec24_scenario.hpp"

namespace {

using namespace hmpc::sec24;

struct Summary {
  std::vector<double> max_ms, median_ms;
  double cost = 0;
  double final_y = 0, final_z = 0;
};
std::map<Method, Summary>& summaries() {
  static std::map<Method, Summary> s;
  return s;
}

void BM_ClosedLoop(benchmark::State& state, Method method) {
  Summary& summary = summaries()[method];
  for (auto _ : state) {
    const RunResult r = run(method);
    summary.max_ms.push_back(r.max_solve_seconds * 1e3);
    summary.median_ms.push_back(r.median_solve_seconds * 1e3);
    summary.cost = r.accumulated_cost;
    summary.final_y = r.final_y;
    summary.final_z = r.final_z;
    benchmark::DoNotOptimize(r.final_y);
  }
  double mean_max = 0, mean_median = 0;
  for (double v : summary.max_ms) mean_max += v;
  for (double v : summary.median_ms) mean_median += v;
  state.counters["max_solve_ms"] = mean_max / static_cast<double>(summary.max_ms.size());
  state.counters["median_solve_ms"] = mean_median / static_cast<double>(summary.median_ms.size());
  state.counters["accumulated_cost"] = summary.cost;
}

double mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? 0 : s / static_cast<double>(v.size());
}

}  // namespace

BENCHMARK_CAPTURE(BM_ClosedLoop, fine, Method::kFine)->Iterations(5)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ClosedLoop, coarse, Method::kCoarse)
    ->Iterations(5)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ClosedLoop, slow_fast, Method::kSlowFast)
    ->Iterations(5)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ClosedLoop, coarse_fast, Method::kCoarseFast)
    ->Iterations(5)
    ->Unit(benchmark::kMillisecond);

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();

  const auto& s = summaries();
  if (s.count(Method::kFine) == 0 || s.count(Method::kCoarseFast) == 0) return 0;
  const Summary& fine = s.at(Method::kFine);
  std::printf("\nSec. 2.4 side by side (mean over 5 closed-loop runs; sampling time 1 ms)\n");
  std::printf("%-12s %14s %14s %12s %10s %10s %16s\n", "method", "max solve ms", "median ms",
              "accum. cost", "final y", "final z", "max vs Fine");
  for (const auto& [method, summary] : s)
    std::printf("%-12s %14.4f %14.4f %12.5f %10.4f %10.4f %15.2fx\n", to_string(method),
                mean(summary.max_ms), mean(summary.median_ms), summary.cost, summary.final_y,
                summary.final_z, mean(summary.max_ms) / mean(fine.max_ms));
  const Summary& cf = s.at(Method::kCoarseFast);
  std::printf("Coarse-Fast / Fine: max solve %.2fx, median solve %.2fx, cost %.4fx\n",
              mean(cf.max_ms) / mean(fine.max_ms), mean(cf.median_ms) / mean(fine.median_ms),
              cf.cost / fine.cost);
  return 0;
}
