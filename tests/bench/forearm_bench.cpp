// Forearm strategies (Table 3.1) side by side in one run: host solve time per 4 ms control
// step (max and median; Fig. 3.3a analogue), and the Cortex-M7 instructions per step that the
// QEMU-fitted compute model predicts from the same solves (the forearm_mpc_on_qemu test
// prints the measured ones). Each benchmark iteration is 10 s of 1 Hz, +-30 deg tracking.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <memory>
#include <vector>

#include "hmpc/models/forearm_mpc.hpp"
#include "hmpc/models/forearm_solvers.hpp"

namespace {

using namespace hmpc::forearm;
using S = Strategies<double>;
using Clock = std::chrono::steady_clock;
constexpr int kSamples = 2500;

struct Row {
  std::vector<double> host_ms, m7_instructions;
  double cost = 0, rms = 0;
};
std::map<Strategy, Row>& rows() {
  static std::map<Strategy, Row> r;
  return r;
}

struct Timing {
  Row& row;
  Clock::time_point start{};
  void before_update(int) { start = Clock::now(); }
  template <class X, class U, class M>
  void after_update(int, const X&, const U&, const M& mpc) {
    row.host_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - start).count());
    row.m7_instructions.push_back(kCortexM7ComputeModel.instructions(mpc.last_work()));
  }
};

template <class Mpc, class Factory>
void track(benchmark::State& state, Strategy strategy, Factory make) {
  Row& row = rows()[strategy];
  row.host_ms.reserve(kSamples * 5);
  row.m7_instructions.reserve(kSamples * 5);
  TargetTrajectory<double> target;
  target.set_sinusoid(30 * M_PI / 180, 1.0, 0, 0);
  S::Setup setup;
  setup.target = &target;
  const Parameters<double> p;
  for (auto _ : state) {
    auto mpc = std::make_unique<Mpc>(make(setup));
    Timing timing{row};
    const auto out = simulate_tracking<double>(*mpc, p, CostWeights<double>{}, target,
                                               Eigen::Vector3d(0, 0, equilibrium_pressure(p, 0.0)),
                                               kSamples, NoComputeDelay{}, timing);
    row.cost = out.accumulated_cost;
    row.rms = out.rms_error;
  }
}

double percentile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(q * (v.size() - 1))];
}

}  // namespace

#define HMPC_FOREARM_BENCH(name, type, factory, strategy)                            \
  static void name(benchmark::State& s) { track<S::type>(s, strategy, S::factory); } \
  BENCHMARK(name)->Iterations(3)->Unit(benchmark::kMillisecond)
HMPC_FOREARM_BENCH(BM_Fine4ms, Fine4, fine4, Strategy::kFine4);
HMPC_FOREARM_BENCH(BM_Fine8ms, Fine8, fine8, Strategy::kFine8);
HMPC_FOREARM_BENCH(BM_Coarse20ms, Coarse20, coarse20, Strategy::kCoarse20);
HMPC_FOREARM_BENCH(BM_Coarse40ms, Coarse40, coarse40, Strategy::kCoarse40);
HMPC_FOREARM_BENCH(BM_TwoStage, TwoStage, two_stage, Strategy::kTwoStage);
HMPC_FOREARM_BENCH(BM_PamOnly, PamOnly, pam_only, Strategy::kPamOnly);

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  if (rows().count(Strategy::kTwoStage) == 0 || rows().count(Strategy::kFine4) == 0) return 0;

  std::printf("\nForearm, 1 Hz +-30 deg, 10 s, 4 ms control period (every update of 3 runs)\n");
  std::printf("%-12s %12s %12s %14s %14s %10s %10s\n", "strategy", "host max ms", "host med ms",
              "M7 max instr", "M7 med instr", "cost", "rms rad");
  for (const auto& [strategy, r] : rows())
    std::printf("%-12s %12.3f %12.4f %14.0f %14.0f %10.1f %10.4f\n", to_string(strategy),
                percentile(r.host_ms, 1.0), percentile(r.host_ms, 0.5),
                percentile(r.m7_instructions, 1.0), percentile(r.m7_instructions, 0.5), r.cost,
                r.rms);
  const Row& two = rows().at(Strategy::kTwoStage);
  for (Strategy other : {Strategy::kFine4, Strategy::kCoarse20}) {
    const Row& o = rows().at(other);
    std::printf("two-stage / %s: host max %.2fx, host median %.2fx, M7 median %.2fx\n",
                to_string(other), percentile(two.host_ms, 1.0) / percentile(o.host_ms, 1.0),
                percentile(two.host_ms, 0.5) / percentile(o.host_ms, 0.5),
                percentile(two.m7_instructions, 0.5) / percentile(o.m7_instructions, 0.5));
  }
  std::printf("M7 at 400 MHz, 1 cycle/instruction (an assumption): 4 ms = 1.6 M instructions\n");
  return 0;
}
