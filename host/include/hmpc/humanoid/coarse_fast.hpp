// The humanoid's Coarse-Fast MPC (thesis Sec. 2.3.3 on the humanoid of Secs. 2.5-2.6) with
// the settings of Table 2.4 and Sec. 2.6.2 (closed loop: closed_loop.hpp).
#pragma once

#include <memory>

#include "hmpc/humanoid/fast_subsystem.hpp"
#include "hmpc/mpc/two_layer_mpc.hpp"

namespace hmpc::humanoid {

// Table 2.4 (seconds) and Sec. 2.6.2.
constexpr double kCoarseStep = 0.030;
constexpr int kCoarseHorizon = 10;
constexpr double kFastStep = 0.010;
constexpr int kFastHorizon = 10;
constexpr int kFineStepsPerCoarseStep = 3;  // M = Delta t_c / Delta t_f, Eq. 2.35
constexpr double kSamplingPeriod = 0.030;
constexpr double kSimulatorStep = 0.001;
constexpr int kIterationCap = 6;
constexpr double kTolerance = 5e-2;
// The reaching experiment's (Sec. 2.6.2: "The maximum number of iterations and the
// termination criteria for iLQR was respectively 4 and 5.0 x 10^-1").
constexpr int kReachingIterationCap = 4;
constexpr double kReachingTolerance = 0.5;
// A Coarse-Fast MPC's time grid (horizons N_c = N_f = 10 in every setting): the upper step
// Delta t_c, which is also the sampling period (the upper plan shifts by one step per sample,
// Eq. 2.22), and the lower layer's Delta t_f.
struct CoarseFastTiming {
  double upper_step = kCoarseStep;  // [s]
  double fast_step = kFastStep;     // [s]
  // M = Delta t_c / Delta t_f, Eq. 2.35.
  int fine_steps_per_upper_step() const;
  // Fine steps of Delta t_f cover the upper step, each a whole number of simulator steps.
  bool valid() const;
  // Throws std::invalid_argument, the message starting with `who`, unless valid().
  void check(const char* who) const;
};
// Table 2.4's, the simulations' (Sec. 2.6).
constexpr CoarseFastTiming kSimulationTiming{kCoarseStep, kFastStep};
// The real robot's (Sec. 2.7.3): "We set the sampling time to 12 ms. The time-step and the
// horizon for the upper-layer optimization were 12 ms and 10 ... For the lower-layer
// optimization, they are 6 ms and 10."
constexpr CoarseFastTiming kRealRobotTiming{0.012, 0.006};

// Every layer's iLQR settings for `motion`: the reaching ones for a reaching motion.
IlqrConfig<double> layer_solver(const Motion& motion);
// Offline optimisation of the initial inputs (Sec. 2.3.4, Fig. 2.2). Our choice: from zero
// torques the standing problem converges in under 10 iterations; 30 leaves a margin.
constexpr int kOfflineIterations = 30;

// For the biped (A = 0) or the robot with an arm (A = 1).
template <int A>
using BasicCoarseFast = CoarseFastMpc<HumanoidProblem<kCoarseHorizon, A>, kCoarseHorizon,
                                      FastSubsystem<kFastHorizon, A>, kFastHorizon>;
using CoarseFast = BasicCoarseFast<0>;

// The lower layer's reference is the upper plan with its states interpolated linearly between
// the 30 ms nodes (TwoLayerMpc's StateHold::kLinear) rather than held as Eq. 2.35 says: the
// fast subsystem holds the base where the reference puts it, so a held base jumps by the
// plan's 30 ms of motion every third fine step while the legs (pinned by the stance feet)
// cannot follow. Measured on motion I (2 s, w_fast = 0.003, 2 threads): with the zero-order
// hold the robot fell within 0.6 s (input deviations nu grew to 32 N m on a joint by 0.3 s);
// with the linear hold it stands for 5 s (|nu| at most 8.8 N m on a joint, in the first sample).
// Moving the held base with its own velocity instead (Eq. 2.51a) fell as well.
// The MPC for `motion` from `initial` (`config`'s step is overridden per layer by `timing`'s,
// its contact gets the motion's chair), each layer capped at `iteration_cap` iLQR iterations per
// update (0: layer_solver's). `pool` may be null (serial) and must outlive the MPC. Throws
// std::invalid_argument for a timing that is not valid() (CoarseFastTiming::check).
template <int A>
std::unique_ptr<BasicCoarseFast<A>> make_coarse_fast(
    const Motion& motion, const BasicState<A>& initial, ThreadPool* pool,
    ProblemConfig config = ProblemConfig{}, int iteration_cap = 0,
    const CoarseFastTiming& timing = kSimulationTiming);

}  // namespace hmpc::humanoid

namespace hmpc {

// Each layer's solver is compiled once, in src/humanoid/solvers: the files that run an MPC
// (closed loops, demonstrations, tests, benchmarks) would otherwise each spend GCC tens of
// seconds on the same fixed-size backward pass.
extern template class Ilqr<humanoid::HumanoidProblem<humanoid::kCoarseHorizon, 0>,
                           humanoid::kCoarseHorizon>;
extern template class Ilqr<humanoid::HumanoidProblem<humanoid::kCoarseHorizon, 1>,
                           humanoid::kCoarseHorizon>;
extern template class Ilqr<humanoid::FastSubsystem<humanoid::kFastHorizon, 0>,
                           humanoid::kFastHorizon>;
extern template class Ilqr<humanoid::FastSubsystem<humanoid::kFastHorizon, 1>,
                           humanoid::kFastHorizon>;

}  // namespace hmpc
