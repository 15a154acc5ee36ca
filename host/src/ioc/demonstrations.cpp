#include "hmpc/ioc/demonstrations.hpp"

#include <memory>

namespace hmpc::ioc {

std::vector<Demonstration> coarse_mpc_plans(const humanoid::Motion& motion,
                                            const humanoid::ClosedLoopRun& run,
                                            const humanoid::ProblemConfig& problem,
                                            humanoid::ThreadPool* pool) {
  using Problem = humanoid::HumanoidProblem<humanoid::kCoarseHorizon>;
  humanoid::ProblemConfig config = humanoid::model_config(motion, problem);
  config.step = humanoid::kCoarseStep;
  const auto model = std::make_unique<Problem>(motion, run.initial, config, pool);
  // As RecedingHorizonMpc does for the Coarse MPC: the offline optimisation (Algorithm 1,
  // line 1), then per sample one solve from the measured state and a shift by one step.
  IlqrConfig<double> settings = humanoid::layer_solver(motion);
  IlqrConfig<double> offline = settings;
  offline.max_iterations = humanoid::kOfflineIterations;
  const auto solver = std::make_unique<Ilqr<Problem, humanoid::kCoarseHorizon>>(offline);
  humanoid::StateVector x = humanoid::to_vector(run.initial);
  model->set_start_time(0.0);
  solver->solve(*model, x);
  solver->set_config(settings);

  std::vector<Demonstration> plans;
  plans.reserve(run.samples.size());
  for (std::size_t k = 0; k < run.samples.size(); ++k) {
    const double time = static_cast<double>(k) * humanoid::kSamplingPeriod;
    model->set_start_time(time);
    solver->solve(*model, x);
    Demonstration plan;
    plan.start_time = time;
    plan.states.assign(solver->states().begin(), solver->states().end());
    plan.inputs.assign(solver->controls().begin(), solver->controls().end());
    plans.push_back(std::move(plan));
    solver->shift(1);  // Eq. 2.22
    x = humanoid::to_vector(run.samples[k].state);
  }
  return plans;
}

}  // namespace hmpc::ioc
