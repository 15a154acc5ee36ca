#include "hmpc/humanoid/coarse_fast.hpp"

namespace hmpc::humanoid {

IlqrConfig<double> layer_solver(const Motion& motion) {
  return motion.reach.active
             ? IlqrConfig<double>::with_cap_and_tolerance(kReachingIterationCap, kReachingTolerance)
             : IlqrConfig<double>::with_cap_and_tolerance(kIterationCap, kTolerance);
}

template <int A>
std::unique_ptr<BasicCoarseFast<A>> make_coarse_fast(const Motion& motion,
                                                     const BasicState<A>& initial, ThreadPool* pool,
                                                     ProblemConfig config, int iteration_cap) {
  using CoarseFast = BasicCoarseFast<A>;
  config = model_config(motion, config);
  ProblemConfig coarse = config, fast = config;
  coarse.step = kCoarseStep;
  fast.step = kFastStep;
  typename CoarseFast::Config mpc;
  mpc.fine_steps_per_upper_step = kFineStepsPerCoarseStep;
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
                                                              ThreadPool*, ProblemConfig, int);
template std::unique_ptr<BasicCoarseFast<1>> make_coarse_fast(const Motion&, const BasicState<1>&,
                                                              ThreadPool*, ProblemConfig, int);

}  // namespace hmpc::humanoid
