#include "hmpc/humanoid/coarse_fast.hpp"

namespace hmpc::humanoid {

std::unique_ptr<CoarseFast> make_coarse_fast(const Motion& motion, const State& initial,
                                             ThreadPool* pool, ProblemConfig config) {
  config.contact = contact_for(motion, config.contact);
  ProblemConfig coarse = config, fast = config;
  coarse.step = kCoarseStep;
  fast.step = kFastStep;
  CoarseFast::Config mpc;
  mpc.fine_steps_per_upper_step = kFineStepsPerCoarseStep;
  mpc.samples_per_upper_step = 1;  // sampling period = Delta t_c
  mpc.state_hold = CoarseFast::Config::StateHold::kLinear;
  mpc.upper = IlqrConfig<double>::with_cap_and_tolerance(kIterationCap, kTolerance);
  mpc.fast = mpc.upper;
  return std::make_unique<CoarseFast>(HumanoidProblem<kCoarseHorizon>(motion, initial, coarse, pool),
                                      FastSubsystem<kFastHorizon>(motion.weights, fast, pool), mpc);
}

}  // namespace hmpc::humanoid
