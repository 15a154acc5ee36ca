// The forearm strategies' iLQR solvers in double (forearm_mpc.hpp), compiled once for Linux
// programs in hmpc::forearm_solvers (src/models/forearm_solvers.cpp): a file that includes this
// header and links that library does not compile them again. The host's tests, benchmarks and
// the Linux board each use all five, and GCC takes about 20 s over them; a bare-metal image
// compiles them once anyway and does not include this.
#pragma once

#include "hmpc/models/forearm_mpc.hpp"

namespace hmpc {

extern template class Ilqr<forearm::ForearmProblem<double>, forearm::kFine4Horizon>;
extern template class Ilqr<forearm::ForearmProblem<double>, forearm::kFine8Horizon>;
extern template class Ilqr<forearm::ForearmProblem<double>, forearm::kCoarse20Horizon>;
extern template class Ilqr<forearm::ForearmProblem<double>, forearm::kCoarse40Horizon>;
extern template class Ilqr<forearm::ForearmFastSubsystem<double, forearm::kTwoStageFineHorizon>,
                           forearm::kTwoStageFineHorizon>;

}  // namespace hmpc
