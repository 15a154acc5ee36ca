// The closed loop with the Coarse-Fast MPC (coarse_fast.hpp).
#include "closed_loop_simulation.hpp"

namespace hmpc::humanoid::detail {

template <int A>
BasicClosedLoopRun<A> run_coarse_fast(const Motion& motion, const ClosedLoopConfig& config,
                                      const BasicState<A>& initial, ThreadPool* pool,
                                      double duration) {
  const auto mpc =
      make_coarse_fast(motion, initial, pool, config.problem, config.iteration_cap, config.timing);
  return simulate(*mpc, motion, config, initial, duration);
}

template ClosedLoopRun run_coarse_fast<0>(const Motion&, const ClosedLoopConfig&,
                                          const BasicState<0>&, ThreadPool*, double);
template ArmClosedLoopRun run_coarse_fast<1>(const Motion&, const ClosedLoopConfig&,
                                             const BasicState<1>&, ThreadPool*, double);

}  // namespace hmpc::humanoid::detail
