#include "hmpc/humanoid/coarse_fast.hpp"

#include <chrono>

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

std::vector<ClosedLoopSample> run_coarse_fast(const Motion& motion, double duration,
                                              ThreadPool* pool, const ProblemConfig& config) {
  using Clock = std::chrono::steady_clock;
  ProblemConfig plant = config;
  plant.contact = contact_for(motion, config.contact);
  State x = standing_state(plant, motion.phase_at(0.0).height);
  const auto mpc = make_coarse_fast(motion, x, pool, config);
  const StateCost observer(motion, x, plant);
  StepMap simulator(Model(plant.parameters), plant.parameters, plant.contact, kSimulatorStep);

  mpc->initialize(to_vector(x), kOfflineIterations);
  std::vector<ClosedLoopSample> samples;
  const int count = static_cast<int>(duration / kSamplingPeriod + 0.5);
  samples.reserve(count);
  for (int k = 0; k < count; ++k) {
    mpc->upper_problem().set_start_time(k * kSamplingPeriod);
    const auto start = Clock::now();
    mpc->update(to_vector(x));
    ClosedLoopSample sample;
    sample.solve_seconds = std::chrono::duration<double>(Clock::now() - start).count();
    for (int j = 0; j < kFineStepsPerCoarseStep; ++j) {
      const JointVector u = mpc->planned_control(j);
      for (int i = 0; i < static_cast<int>(kFastStep / kSimulatorStep + 0.5); ++i)
        x = simulator.step(x, u, kSimulatorStep);
    }
    sample.time = (k + 1) * kSamplingPeriod;
    sample.base = observer.features(x);
    sample.upper_iterations = mpc->last_upper_result().iterations;
    sample.fast_iterations = mpc->last_fast_result().iterations;
    sample.plan_usable = mpc->last_plan_usable();
    samples.push_back(sample);
  }
  return samples;
}

}  // namespace hmpc::humanoid
