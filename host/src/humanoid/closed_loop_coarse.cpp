// The closed loop with the Coarse MPC of Table 2.4 (30 ms steps, N = 10).
#include "closed_loop_simulation.hpp"

namespace hmpc::humanoid::detail {

template <int A>
BasicClosedLoopRun<A> run_coarse(const Motion& motion, const ClosedLoopConfig& config,
                                 const BasicState<A>& initial, ThreadPool* pool, double duration) {
  const auto mpc = make_single_layer<kCoarseHorizon, A>(
      motion, initial, pool, config.problem, config.timing.upper_step, config.iteration_cap,
      config.timing.upper_step);
  return simulate(*mpc, motion, config, initial, duration);
}

template ClosedLoopRun run_coarse<0>(const Motion&, const ClosedLoopConfig&, const BasicState<0>&,
                                     ThreadPool*, double);
template ArmClosedLoopRun run_coarse<1>(const Motion&, const ClosedLoopConfig&,
                                        const BasicState<1>&, ThreadPool*, double);

}  // namespace hmpc::humanoid::detail
