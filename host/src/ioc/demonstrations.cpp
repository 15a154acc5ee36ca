#include "hmpc/ioc/demonstrations.hpp"

#include <algorithm>
#include <cmath>
#include <memory>

namespace hmpc::ioc {

Eigen::Vector3d demonstration_start_velocity(int i, int count) {
  constexpr double kNudge = 0.05;  // [m/s]
  if (i == 0) return Eigen::Vector3d::Zero();
  const double angle = 2.0 * M_PI * (i - 1) / std::max(1, count - 1);
  return kNudge * Eigen::Vector3d(std::cos(angle), std::sin(angle), 0.0);
}

IlqrConfig<double> optimum_solver() {
  IlqrConfig<double> config = IlqrConfig<double>::with_cap_and_tolerance(50, 1e-8);
  config.gradient_tolerance = 1e-9;
  return config;
}

std::vector<Demonstration> coarse_mpc_plans(const humanoid::Motion& motion,
                                            const humanoid::ClosedLoopRun& run,
                                            const humanoid::ProblemConfig& problem,
                                            humanoid::ThreadPool* pool,
                                            const std::optional<IlqrConfig<double>>& solve,
                                            std::vector<SolveStatus>* status) {
  using Problem = humanoid::HumanoidProblem<humanoid::kCoarseHorizon>;
  humanoid::ProblemConfig config = humanoid::model_config(motion, problem);
  config.step = humanoid::kCoarseStep;
  const auto model = std::make_unique<Problem>(motion, run.initial, config, pool);
  // As RecedingHorizonMpc does for the Coarse MPC: the offline optimisation (Algorithm 1,
  // line 1), then per sample one solve from the measured state and a shift by one step.
  const IlqrConfig<double> settings = solve ? *solve : humanoid::layer_solver(motion);
  IlqrConfig<double> offline = settings;
  offline.max_iterations = humanoid::kOfflineIterations;
  const auto solver = std::make_unique<Ilqr<Problem, humanoid::kCoarseHorizon>>(offline);
  humanoid::StateVector x = humanoid::to_vector(run.initial);
  model->set_start_time(0.0);
  solver->solve(*model, x);
  solver->set_config(settings);

  std::vector<Demonstration> plans;
  plans.reserve(run.samples.size());
  if (status != nullptr) status->clear();
  for (std::size_t k = 0; k < run.samples.size(); ++k) {
    const double time = static_cast<double>(k) * humanoid::kSamplingPeriod;
    model->set_start_time(time);
    const SolveStatus solved = solver->solve(*model, x).status;
    if (status != nullptr) status->push_back(solved);
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
