#include "hmpc/models/forearm_solvers.hpp"

namespace hmpc {

template class Ilqr<forearm::ForearmProblem<double>, forearm::kFine4Horizon>;
template class Ilqr<forearm::ForearmProblem<double>, forearm::kFine8Horizon>;
template class Ilqr<forearm::ForearmProblem<double>, forearm::kCoarse20Horizon>;
template class Ilqr<forearm::ForearmProblem<double>, forearm::kCoarse40Horizon>;
template class Ilqr<forearm::ForearmFastSubsystem<double, forearm::kTwoStageFineHorizon>,
                    forearm::kTwoStageFineHorizon>;

}  // namespace hmpc
