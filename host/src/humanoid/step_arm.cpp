// The step map of the robot with a right arm (step_map.hpp).
#include "step_map.hpp"

namespace hmpc::humanoid {

template class BasicStepMap<1>;

}  // namespace hmpc::humanoid
