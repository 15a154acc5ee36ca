// Humanoid MPC figures (DESIGN.md §6), measured side by side in one run:
//   - the iLQR's linearisation of all N steps of the coarse problem (30 ms, N = 10, Table 2.4):
//     central-difference dynamics Jacobians and Gauss-Newton cost derivatives, serial and on a
//     ThreadPool of 2 (thesis Sec. 2.6.2 used 10 OpenMP threads);
//   - with --closed-loop [--threads T]: motion I (standing) for its file's duration under the
//     Coarse-Fast MPC of Table 2.4 on the 1 ms simulator, reporting the base height and the
//     solve times (T threads, default 2).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "hmpc/humanoid/coarse_fast.hpp"

namespace {

using namespace hmpc::humanoid;

Motion standing_motion() {
  return load_motion(std::string(HMPC_HUMANOID_MOTIONS) + "/I-standing.motion");
}

std::map<int, double>& seconds_per_linearisation() {
  static std::map<int, double> s;
  return s;
}

void BM_Linearise(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  using Problem = HumanoidProblem<kCoarseHorizon>;
  using Solver = hmpc::Ilqr<Problem, kCoarseHorizon>;
  const Motion motion = standing_motion();
  ProblemConfig config;
  config.step = kCoarseStep;
  const State x0 = standing_state(config, motion.phases[0].height);
  ThreadPool pool(threads);
  const auto problem = std::make_unique<Problem>(motion, x0, config, threads > 1 ? &pool : nullptr);
  // A realistic nominal trajectory: the offline-optimised standing plan.
  const auto solver = std::make_unique<Solver>(
      hmpc::IlqrConfig<double>::with_cap_and_tolerance(kOfflineIterations, kTolerance));
  solver->solve(*problem, to_vector(x0));
  std::array<Problem::StateJacobian, kCoarseHorizon> fx;
  std::array<Problem::ControlJacobian, kCoarseHorizon> fu;
  std::array<Problem::RunningDerivatives, kCoarseHorizon> l;
  // The same work as Ilqr's derivative pass, through the same hook.
  for (auto _ : state) {
    problem->for_each_step(kCoarseHorizon, [&](int t) {
      problem->dynamics_derivatives(solver->states()[t], solver->controls()[t], t, fx[t], fu[t]);
      problem->running_cost_derivatives(solver->states()[t], solver->controls()[t], t, l[t]);
    });
    benchmark::DoNotOptimize(fx[0](0, 0));
  }
  state.SetLabel(std::to_string(threads) + (threads == 1 ? " thread" : " threads"));
}

// Google Benchmark's console output plus a record of each run's real time per iteration.
class Recorder : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& run : runs) {
      const double seconds = run.GetAdjustedRealTime() / benchmark::GetTimeUnitMultiplier(run.time_unit);
      seconds_per_linearisation()[std::atoi(run.run_name.args.c_str())] = seconds;  // Arg = threads
    }
    ConsoleReporter::ReportRuns(runs);
  }
};

void closed_loop(int threads) {
  ThreadPool pool(threads);
  const Motion motion = standing_motion();
  const std::vector<ClosedLoopSample> samples =
      run_coarse_fast(motion, motion.duration, threads > 1 ? &pool : nullptr);
  std::vector<double> solve;
  double low = 1e9, high = -1e9;
  int unusable = 0;
  for (const ClosedLoopSample& s : samples) {
    solve.push_back(s.solve_seconds);
    low = std::min(low, s.base.position.z());
    high = std::max(high, s.base.position.z());
    unusable += s.plan_usable ? 0 : 1;
  }
  std::sort(solve.begin(), solve.end());
  const ClosedLoopSample& last = samples.back();
  std::printf("\nMotion I (standing, target 0.85 m), Coarse-Fast MPC (Table 2.4), %.2f s, %d thread%s\n",
              last.time, threads, threads == 1 ? "" : "s");
  std::printf("base height: min %.4f m, max %.4f m, final %.4f m; final |v| %.3f m/s, tilt %.4f\n",
              low, high, last.base.position.z(), last.base.velocity.norm(),
              last.base.quaternion.tail<3>().norm());
  std::printf("solve per 30 ms sample: max %.1f ms, median %.1f ms; unusable plans %d of %zu\n",
              solve.back() * 1e3, solve[solve.size() / 2] * 1e3, unusable, samples.size());
}

}  // namespace

BENCHMARK(BM_Linearise)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(1.0);

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  bool run_closed_loop = false;
  int threads = 2;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--closed-loop") {
      run_closed_loop = true;
    } else if (arg == "--threads" && i + 1 < argc) {
      char* end = nullptr;
      const long value = std::strtol(argv[++i], &end, 10);
      if (*end != '\0' || value < 1 || value > 64) {
        std::fprintf(stderr, "--threads needs an integer in 1..64, got '%s'\n", argv[i]);
        return 2;
      }
      threads = static_cast<int>(value);
    } else {
      std::fprintf(stderr, "unknown argument '%s' (expected --closed-loop, --threads T)\n",
                   arg.c_str());
      return 2;
    }
  }
  Recorder recorder;
  benchmark::RunSpecifiedBenchmarks(&recorder);
  benchmark::Shutdown();
  const auto& s = seconds_per_linearisation();
  if (s.count(1) != 0 && s.count(2) != 0 && s.at(2) > 0.0)
    std::printf("linearisation of N = %d coarse steps: 1 thread %.1f ms, 2 threads %.1f ms: speed-up %.2fx\n",
                kCoarseHorizon, s.at(1) * 1e3, s.at(2) * 1e3, s.at(1) / s.at(2));
  if (run_closed_loop) closed_loop(threads);
  return 0;
}
