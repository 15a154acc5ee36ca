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

template <class Mpc>
void record_layers(const Mpc& mpc, StepRecord& step) {
  if constexpr (std::is_same_v<Mpc, M::Fine> || std::is_same_v<Mpc, M::Coarse>) {
    step.upper_iterations = mpc.last_result().iterations;
    step.upper_status = mpc.last_result().status;
  } else {
    step.upper_iterations = mpc.last_upper_result().iterations;
    step.upper_status = mpc.last_upper_result().status;
    step.fast_iterations = mpc.last_fast_result().iterations;
    step.fast_status = mpc.last_fast_result().status;
  }
}

template <class Mpc>
RunResult run_loop(Mpc& mpc, Method method, const RunOptions& options) {
  const Parameters<double> p;
  RunResult result;
  result.method = method;
  result.steps.reserve(static_cast<std::size_t>(options.samples));

  Vector2<double> x = initial_state<double>();
  mpc.initialize(x, kOfflineIterations);
  for (int k = 0; k < options.samples; ++k) {
    const auto t0 = Clock::now();
    const Vector2<double> u = mpc.update(x);
    const auto t1 = Clock::now();

    StepRecord step;
    step.time = k * kSamplingPeriod;
    step.y = x(0);
    step.z = x(1);
    step.u1 = u(0);
    step.u2 = u(1);
    step.solve_seconds = std::chrono::duration<double>(t1 - t0).count();
    record_layers(mpc, step);
    if (!plan_is_usable(step.upper_status) || !plan_is_usable(step.fast_status))
      ++result.unusable_solves;
    result.steps.push_back(step);

    result.accumulated_cost += regulator_cost(p, x, u) * kSamplingPeriod;
    x = integrate_plant(p, x, u, kSamplingPeriod);
  }
  result.final_y = x(0);
  result.final_z = x(1);

  std::vector<double> times;
  times.reserve(result.steps.size());
  for (const auto& s : result.steps) times.push_back(s.solve_seconds);
  if (!times.empty()) {
    result.max_solve_seconds = *std::max_element(times.begin(), times.end());
    std::nth_element(times.begin(), times.begin() + times.size() / 2, times.end());
    result.median_solve_seconds = times[times.size() / 2];
  }
  return result;
}

template <class Mpc>
RunResult run_owned(std::unique_ptr<Mpc> mpc, Method method, const RunOptions& options) {
  return run_loop(*mpc, method, options);
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
  out << "method,time,y,z,u1,u2,solve_ms,upper_iterations,fast_iterations\n";
  out.precision(10);
  for (const auto& run : runs)
    for (const auto& s : run.steps)
      out << to_string(run.method) << ',' << s.time << ',' << s.y << ',' << s.z << ',' << s.u1
          << ',' << s.u2 << ',' << s.solve_seconds * 1e3 << ',' << s.upper_iterations << ','
          << s.fast_iterations << '\n';
  if (!out) throw std::runtime_error("error while writing " + path);
}

}  // namespace hmpc::sec24
