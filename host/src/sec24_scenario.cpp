#include "hmpc/host/sec24_scenario.hpp"

#include <algorithm>
#include <chrono>
#include <fstream>
#include <memory>
#include <stdexcept>

#include "hmpc/models/singularly_perturbed_example_mpc.hpp"

namespace hmpc::sec24 {

const char* to_string(Method method) {
  switch (method) {
    case Method::kFine: return "fine";
    case Method::kCoarse: return "coarse";
    case Method::kSlowFast: return "slow-fast";
    case Method::kCoarseFast: return "coarse-fast";
  }
  return "unknown";
}

namespace {

using Clock = std::chrono::steady_clock;
using M = Mpcs<double>;

// Times every update and appends to a log reserved in advance (no allocation in the loop).
struct Recorder {
  RunResult& result;
  Clock::time_point start{};

  void before_update(int) { start = Clock::now(); }

  template <class Mpc>
  void after_update(int k, const Vector2<double>& x, const Vector2<double>& u, const Mpc& mpc) {
    const auto end = Clock::now();
    StepRecord step;
    step.time = k * kSamplingPeriod;
    step.y = x(0);
    step.z = x(1);
    step.u1 = u(0);
    step.u2 = u(1);
    step.solve_seconds = std::chrono::duration<double>(end - start).count();
    step.iterations = mpc.last_iterations();
    step.plan_usable = mpc.last_plan_usable();
    result.unusable_solves += step.plan_usable ? 0 : 1;
    result.steps.push_back(step);
  }
};

template <class Mpc>
RunResult run_owned(std::unique_ptr<Mpc> mpc, Method method, const RunOptions& options) {
  RunResult result;
  result.method = method;
  result.steps.reserve(static_cast<std::size_t>(options.samples));
  Recorder recorder{result};
  const auto outcome = simulate_closed_loop<double>(*mpc, options.samples, recorder);
  result.final_y = outcome.final_state(0);
  result.final_z = outcome.final_state(1);
  result.accumulated_cost = outcome.accumulated_cost;

  std::vector<double> times;
  times.reserve(result.steps.size());
  for (const auto& s : result.steps) times.push_back(s.solve_seconds);
  result.max_solve_seconds = *std::max_element(times.begin(), times.end());
  std::nth_element(times.begin(), times.begin() + times.size() / 2, times.end());
  result.median_solve_seconds = times[times.size() / 2];
  return result;
}

}  // namespace

RunResult run(Method method, const RunOptions& options) {
  if (options.samples <= 0) throw std::invalid_argument("samples must be positive");
  // The MPC objects hold their whole workspace inline (hundreds of kB for the Fine MPC):
  // allocate them once here, never on the control loop's path.
  switch (method) {
    case Method::kFine: return run_owned(std::make_unique<M::Fine>(M::fine()), method, options);
    case Method::kCoarse:
      return run_owned(std::make_unique<M::Coarse>(M::coarse()), method, options);
    case Method::kSlowFast:
      return run_owned(std::make_unique<M::SlowFast>(M::slow_fast()), method, options);
    case Method::kCoarseFast:
      return run_owned(std::make_unique<M::CoarseFast>(M::coarse_fast()), method, options);
  }
  throw std::invalid_argument("unknown method");
}

void write_trajectories_csv(const std::vector<RunResult>& runs, const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  out << "method,time,y,z,u1,u2,solve_ms,iterations\n";
  out.precision(10);
  for (const auto& run : runs)
    for (const auto& s : run.steps)
      out << to_string(run.method) << ',' << s.time << ',' << s.y << ',' << s.z << ',' << s.u1
          << ',' << s.u2 << ',' << s.solve_seconds * 1e3 << ',' << s.iterations << '\n';
  if (!out) throw std::runtime_error("error while writing " + path);
}

}  // namespace hmpc::sec24
