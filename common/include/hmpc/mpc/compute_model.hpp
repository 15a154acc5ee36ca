// Compute time of a solve on a target processor, predicted from the solver's deterministic
// work counters (SolveWork) with per-unit instruction costs measured on that target. Used to
// charge realistic computation delays in simulations, reproducibly (a wall-clock measurement
// on a shared host is neither reproducible nor the target's).
#pragma once

#include "hmpc/solver/ilqr.hpp"

namespace hmpc {

// Instructions per unit of one layer's work (the problems of each layer differ in size).
// Backward steps come one per linearised step (plus rare regularisation retries), so their
// cost is folded into the derivative step.
struct LayerCost {
  double per_rollout_step = 0;     // dynamics + running cost
  double per_derivative_step = 0;  // linearisation + backward step
};

struct ComputeCostModel {
  double instructions_per_update = 0;  // fixed cost of one MPC update
  LayerCost upper{};                   // the only layer of a single-layer MPC
  LayerCost fast{};                    // the lower layer of a two-layer MPC
  double clock_hz = 1;
  double cycles_per_instruction = 1;  // an assumption: QEMU counts instructions, not cycles

  double instructions(const LayerWork& w) const {
    return instructions_per_update + upper.per_rollout_step * w.upper.rollout_steps +
           upper.per_derivative_step * w.upper.derivative_steps +
           fast.per_rollout_step * w.fast.rollout_steps +
           fast.per_derivative_step * w.fast.derivative_steps;
  }
  double seconds(const LayerWork& w) const {
    return instructions(w) * cycles_per_instruction / clock_hz;
  }
};

}  // namespace hmpc
