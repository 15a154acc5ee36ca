// Humanoid MPC figures (DESIGN.md §6), measured side by side in one run:
//   - the iLQR's linearisation of all N steps of the coarse problem (30 ms, N = 10, Table 2.4):
//     dynamics Jacobians and Gauss-Newton cost derivatives, serial and on a ThreadPool of 2
//     (thesis Sec. 2.6.2 used 10 OpenMP threads), with the step map's linearisation (sub-step
//     chain rule, step.hpp) and with the reference (central differences of whole steps);
//   - with --closed-loop [--threads T] [--linearisation chain-rule|reference]: motion I
//     (standing) for its file's duration under the Coarse-Fast MPC of Table 2.4 on the 1 ms
//     simulator, reporting the base height and the solve times (T threads, default 2; the
//     step map's linearisation by default).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "hmpc/humanoid/coarse_fast.hpp"

namespace {

using namespace hmpc::humanoid;

Motion standing_motion() {
  return load_motion(std::string(HMPC_HUMANOID_MOTIONS) + "/I-standing.motion");
}

const char* name_of(Linearisation linearisation) {
  return linearisation == Linearisation::kSubStepChainRule ? "chain-rule" : "reference";
}

// Seconds per linearisation by (Linearisation, threads).
std::map<std::pair<int, int>, double>& seconds_per_linearisation() {
  static std::map<std::pair<int, int>, double> s;
  return s;
}

// Args: Linearisation, threads.
void BM_Linearise(benchmark::State& state) {
  const auto linearisation = static_cast<Linearisation>(state.range(0));
  const int threads = static_cast<int>(state.range(1));
  using Problem = HumanoidProblem<kCoarseHorizon>;
  using Solver = hmpc::Ilqr<Problem, kCoarseHorizon>;
  const Motion motion = standing_motion();
  ProblemConfig config;
  config.step = kCoarseStep;
  config.linearisation = linearisation;
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
  state.SetLabel(std::string(name_of(linearisation)) + ", " + std::to_string(threads) +
                 (threads == 1 ? " thread" : " threads"));
}

// Google Benchmark's console output plus a record of each run's real time per iteration.
class Recorder : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& run : runs) {
      const double seconds = run.GetAdjustedRealTime() / benchmark::GetTimeUnitMultiplier(run.time_unit);
      // run_name.args is "linearisation/threads".
      const std::string& args = run.run_name.args;
      const std::size_t slash = args.find('/');
      seconds_per_linearisation()[{std::atoi(args.c_str()), std::atoi(args.c_str() + slash + 1)}] =
          seconds;
    }
    ConsoleReporter::ReportRuns(runs);
  }
};

void closed_loop(int threads, Linearisation linearisation) {
  ThreadPool pool(threads);
  const Motion motion = standing_motion();
  ProblemConfig config;
  config.linearisation = linearisation;
  const std::vector<ClosedLoopSample> samples =
      run_coarse_fast(motion, motion.duration, threads > 1 ? &pool : nullptr, config);
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
  std::printf("\nMotion I (standing, target 0.85 m), Coarse-Fast MPC (Table 2.4), %.2f s, %d thread%s, "
              "%s linearisation\n",
              last.time, threads, threads == 1 ? "" : "s", name_of(linearisation));
  std::printf("base height: min %.4f m, max %.4f m, final %.4f m; final |v| %.3f m/s, tilt %.4f\n",
              low, high, last.base.position.z(), last.base.velocity.norm(),
              last.base.quaternion.tail<3>().norm());
  std::printf("solve per 30 ms sample: max %.1f ms, median %.1f ms; unusable plans %d of %zu\n",
              solve.back() * 1e3, solve[solve.size() / 2] * 1e3, unusable, samples.size());
}

}  // namespace

BENCHMARK(BM_Linearise)
    ->ArgsProduct({{static_cast<int>(Linearisation::kWholeStepDifferences),
                    static_cast<int>(Linearisation::kSubStepChainRule)},
                   {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(1.0);

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  bool run_closed_loop = false;
  int threads = 2;
  Linearisation linearisation = Linearisation::kSubStepChainRule;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--closed-loop") {
      run_closed_loop = true;
    } else if (arg == "--linearisation" && i + 1 < argc) {
      const std::string value = argv[++i];
      if (value == name_of(Linearisation::kSubStepChainRule)) {
        linearisation = Linearisation::kSubStepChainRule;
      } else if (value == name_of(Linearisation::kWholeStepDifferences)) {
        linearisation = Linearisation::kWholeStepDifferences;
      } else {
        std::fprintf(stderr, "--linearisation needs chain-rule or reference, got '%s'\n", value.c_str());
        return 2;
      }
    } else if (arg == "--threads" && i + 1 < argc) {
      char* end = nullptr;
      const long value = std::strtol(argv[++i], &end, 10);
      if (*end != '\0' || value < 1 || value > 64) {
        std::fprintf(stderr, "--threads needs an integer in 1..64, got '%s'\n", argv[i]);
        return 2;
      }
      threads = static_cast<int>(value);
    } else {
      std::fprintf(stderr,
                   "unknown argument '%s' (expected --closed-loop, --threads T, "
                   "--linearisation chain-rule|reference)\n",
                   arg.c_str());
      return 2;
    }
  }
  Recorder recorder;
  benchmark::RunSpecifiedBenchmarks(&recorder);
  benchmark::Shutdown();
  const auto& s = seconds_per_linearisation();
  const int reference = static_cast<int>(Linearisation::kWholeStepDifferences);
  const int chain_rule = static_cast<int>(Linearisation::kSubStepChainRule);
  if (s.size() == 4) {
    std::printf("\nlinearisation of N = %d coarse steps     1 thread   2 threads\n", kCoarseHorizon);
    std::printf("  reference (whole-step differences) %8.2f ms %8.2f ms\n", s.at({reference, 1}) * 1e3,
                s.at({reference, 2}) * 1e3);
    std::printf("  sub-step chain rule                %8.2f ms %8.2f ms\n", s.at({chain_rule, 1}) * 1e3,
                s.at({chain_rule, 2}) * 1e3);
    std::printf("  speed-up of the chain rule         %8.1fx    %8.1fx\n",
                s.at({reference, 1}) / s.at({chain_rule, 1}), s.at({reference, 2}) / s.at({chain_rule, 2}));
    std::printf("linearisation of N = %d coarse steps (chain rule): 1 thread %.2f ms, 2 threads %.2f ms: "
                "speed-up %.2fx\n",
                kCoarseHorizon, s.at({chain_rule, 1}) * 1e3, s.at({chain_rule, 2}) * 1e3,
                s.at({chain_rule, 1}) / s.at({chain_rule, 2}));
  }
  if (run_closed_loop) closed_loop(threads, linearisation);
  return 0;
}
