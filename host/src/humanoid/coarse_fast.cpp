#include "hmpc/humanoid/coarse_fast.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace hmpc::humanoid {

int CoarseFastTiming::fine_steps_per_upper_step() const {
  return static_cast<int>(std::lround(upper_step / fast_step));
}

bool CoarseFastTiming::valid() const {
  // Whole multiples to within a microsecond: the steps are given in milliseconds.
  const auto multiple = [](double of, double unit) {
    return unit > 0.0 && of >= unit && std::abs(of / unit - std::round(of / unit)) * unit < 1e-6;
  };
  return std::isfinite(upper_step) && std::isfinite(fast_step) && upper_step <= 1.0 &&
         multiple(upper_step, fast_step) && multiple(fast_step, kSimulatorStep);
}

void CoarseFastTiming::check(const char* who) const {
  if (!valid()) {
    throw std::invalid_argument(std::string(who) +
                                ": the sampling period must be a whole number of lower-layer "
                                "steps, each a whole number of 1 ms simulator steps, at most 1 s");
  }
}

IlqrConfig<double> layer_solver(const Motion& motion) {
  return motion.reach.active
             ? IlqrConfig<double>::with_cap_and_tolerance(kReachingIterationCap, kReachingTolerance)
             : IlqrConfig<double>::with_cap_and_tolerance(kIterationCap, kTolerance);
}

template <int A>
std::unique_ptr<BasicCoarseFast<A>> make_coarse_fast(const Motion& motion,
                                                     const BasicState<A>& initial, ThreadPool* pool,
                                                     ProblemConfig config, int iteration_cap,
                                                     const CoarseFastTiming& timing) {
  using CoarseFast = BasicCoarseFast<A>;
  timing.check("Coarse-Fast");
  config = model_config(motion, config);
  ProblemConfig coarse = config, fast = config;
  coarse.step = timing.upper_step;
  fast.step = timing.fast_step;
  typename CoarseFast::Config mpc;
  mpc.fine_steps_per_upper_step = timing.fine_steps_per_upper_step();
  mpc.samples_per_upper_step = 1;  // sampling period = Delta t_c
  mpc.state_hold = CoarseFast::Config::StateHold::kLinear;
  mpc.upper = layer_solver(motion);
  if (iteration_cap > 0) mpc.upper.max_iterations = iteration_cap;
  mpc.fast = mpc.upper;
  return std::make_unique<CoarseFast>(
      HumanoidProblem<kCoarseHorizon, A>(motion, initial, coarse, pool),
      FastSubsystem<kFastHorizon, A>(motion.weights, fast, pool), mpc);
}

template std::unique_ptr<BasicCoarseFast<0>> make_coarse_fast(const Motion&, const BasicState<0>&,
                                                              ThreadPool*, ProblemConfig, int,
                                                              const CoarseFastTiming&);
template std::unique_ptr<BasicCoarseFast<1>> make_coarse_fast(const Motion&, const BasicState<1>&,
                                                              ThreadPool*, ProblemConfig, int,
                                                              const CoarseFastTiming&);

}  // namespace hmpc::humanoid
