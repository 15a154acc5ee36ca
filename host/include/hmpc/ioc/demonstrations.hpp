// Demonstrations by the robot's own MPC under known weights (to check that IOC recovers them):
// the plans the Coarse MPC made along a closed-loop run, each an N-step window that its iLQR
// optimised from the measured state, as opposed to the run's executed trajectory, whose windows
// string together the first steps of different plans.
#pragma once

#include <optional>
#include <vector>

#include "hmpc/ioc/local_ioc.hpp"

namespace hmpc::ioc {

// The start of own-MPC demonstration i of `count` (ClosedLoopConfig::initial_velocity): the
// first at rest, the others with the whole robot moving at 5 cm/s in evenly spread horizontal
// directions (as the humanoid benchmark's perturbed starts), so that they differ.
Eigen::Vector3d demonstration_start_velocity(int i, int count);

// Re-solving a plan towards a local optimum of its N-step problem: 50 iterations and a
// tolerance far below any window's cost, so that a solve stops where the iLQR cannot improve
// the plan further (most of a jump's dynamic phase reaches the cap: its solves make slow
// progress through the contacts; the status says which plans converged).
IlqrConfig<double> optimum_solver();

// The Coarse MPC's plan at every sample of `run`, an untruncated, warm-started Coarse MPC run
// of `motion` (closed_loop.hpp), as one-window demonstrations: the MPC's computation replayed
// along the run's states, so plan k is the one whose first input the run applied in sample k.
// `problem` is the run's ClosedLoopConfig::problem. `pool` may be null. `solve`: each
// sample's solve, by default the MPC's own (Table 2.4's iteration cap and tolerance); a
// tighter one re-solves each window towards a local optimum of the N-step problem from the
// run's state, warm-started by the previous plan as the MPC is. `status` (if non-null) gets
// each plan's solve status: only a converged plan is a local optimum.
std::vector<Demonstration> coarse_mpc_plans(
    const humanoid::Motion& motion, const humanoid::ClosedLoopRun& run,
    const humanoid::ProblemConfig& problem = humanoid::ProblemConfig{},
    humanoid::ThreadPool* pool = nullptr,
    const std::optional<IlqrConfig<double>>& solve = std::nullopt,
    std::vector<SolveStatus>* status = nullptr);

}  // namespace hmpc::ioc
