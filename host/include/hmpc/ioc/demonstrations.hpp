// Demonstrations by the robot's own MPC under known weights (to check that IOC recovers them):
// the plans the Coarse MPC made along a closed-loop run, each an N-step window that its iLQR
// optimised from the measured state, as opposed to the run's executed trajectory, whose windows
// string together the first steps of different plans.
#pragma once

#include <vector>

#include "hmpc/ioc/local_ioc.hpp"

namespace hmpc::ioc {

// The Coarse MPC's plan at every sample of `run`, an untruncated, warm-started Coarse MPC run
// of `motion` (closed_loop.hpp), as one-window demonstrations: the MPC's computation replayed
// along the run's states, so plan k is the one whose first input the run applied in sample k.
// `problem` is the run's ClosedLoopConfig::problem. `pool` may be null.
std::vector<Demonstration> coarse_mpc_plans(
    const humanoid::Motion& motion, const humanoid::ClosedLoopRun& run,
    const humanoid::ProblemConfig& problem = humanoid::ProblemConfig{},
    humanoid::ThreadPool* pool = nullptr);

}  // namespace hmpc::ioc
