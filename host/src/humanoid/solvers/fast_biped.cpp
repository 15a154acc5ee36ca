// The iLQR of Coarse-Fast's lower layer for the biped, compiled here once (coarse_fast.hpp).
#include "hmpc/humanoid/coarse_fast.hpp"

namespace hmpc {

template class Ilqr<humanoid::FastSubsystem<humanoid::kFastHorizon, 0>, humanoid::kFastHorizon>;

}  // namespace hmpc
