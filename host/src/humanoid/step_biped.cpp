// The step map of the biped (step_map.hpp).
#include "step_map.hpp"

namespace hmpc::humanoid {

template class BasicStepMap<0>;

}  // namespace hmpc::humanoid
