// The Fine MPC's iLQR for the robot with an arm, compiled here once (closed_loop.hpp).
#include "hmpc/humanoid/closed_loop.hpp"

namespace hmpc {

template class Ilqr<humanoid::HumanoidProblem<humanoid::kFineHorizon, 1>, humanoid::kFineHorizon>;

}  // namespace hmpc
