// The Fine MPC's iLQR for the biped, compiled here once (closed_loop.hpp).
#include "hmpc/humanoid/closed_loop.hpp"

namespace hmpc {

template class Ilqr<humanoid::HumanoidProblem<humanoid::kFineHorizon, 0>, humanoid::kFineHorizon>;

}  // namespace hmpc
