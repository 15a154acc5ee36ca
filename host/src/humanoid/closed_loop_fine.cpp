// The closed loop with the Fine MPC of Table 2.4 (10 ms steps, N = 30).
#include "closed_loop_simulation.hpp"

namespace hmpc::humanoid::detail {

template <int A>
BasicClosedLoopRun<A> run_fine(const Motion& motion, const ClosedLoopConfig& config,
                               const BasicState<A>& initial, ThreadPool* pool, double duration) {
  const auto mpc =
      make_single_layer<kFineHorizon, A>(motion, initial, pool, config.problem, kFineStep,
                                         config.iteration_cap, config.timing.upper_step);
  return simulate(*mpc, motion, config, initial, duration);
}

template ClosedLoopRun run_fine<0>(const Motion&, const ClosedLoopConfig&, const BasicState<0>&,
                                   ThreadPool*, double);
template ArmClosedLoopRun run_fine<1>(const Motion&, const ClosedLoopConfig&, const BasicState<1>&,
                                      ThreadPool*, double);

}  // namespace hmpc::humanoid::detail
