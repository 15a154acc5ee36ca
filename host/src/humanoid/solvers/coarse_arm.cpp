// The coarse problem's iLQR (the Coarse MPC and Coarse-Fast's upper layer) for the robot with an
// arm, compiled here once (coarse_fast.hpp).
#include "hmpc/humanoid/coarse_fast.hpp"

namespace hmpc {

template class Ilqr<humanoid::HumanoidProblem<humanoid::kCoarseHorizon, 1>,
                    humanoid::kCoarseHorizon>;

}  // namespace hmpc
