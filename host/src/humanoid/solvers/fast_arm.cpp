// The iLQR of Coarse-Fast's lower layer for the robot with an arm, compiled here once
// (coarse_fast.hpp).
#include "hmpc/humanoid/coarse_fast.hpp"

namespace hmpc {

template class Ilqr<humanoid::FastSubsystem<humanoid::kFastHorizon, 1>, humanoid::kFastHorizon>;

}  // namespace hmpc
