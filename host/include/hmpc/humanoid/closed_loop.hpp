// A humanoid motion in closed loop (thesis Algorithm 1 on the Sec. 2.6.2 simulation): every
// 30 ms sample an MPC solves from the simulated state, and its inputs drive our own step map
// at the simulator's 1 ms step (the modelling error the thesis had). The MPCs are those of
// Table 2.4:
//   Fine MPC         10 ms steps, N = 30: the inputs of steps 0-2 are applied, 10 ms each;
//   Coarse MPC       30 ms steps, N = 10: the input of step 0 is applied for 30 ms;
//   Coarse-Fast MPC  30 ms / 10 ms, N_c = N_f = 10 (coarse_fast.hpp): the composed inputs
//                    (Eq. 2.36) of fine steps 0-2.
// iLQR cap 6 and tolerance 5e-2 for every layer; with `truncate` a solve is stopped at the
// sampling time (by wall clock, as in the thesis) and its best plan is used: an iteration is
// started only if the longest one so far in the update would still end before it.
#pragma once

#include <string>
#include <vector>

#include "hmpc/estimation/invariant_ekf.hpp"
#include "hmpc/humanoid/coarse_fast.hpp"
#include "hmpc/humanoid/sensors.hpp"

namespace hmpc::humanoid {

enum class MpcKind { kFine, kCoarse, kCoarseFast };
constexpr int kMpcKinds = 3;
// "fine", "coarse", "coarse-fast" (command lines and logs).
const char* name_of(MpcKind kind);
// The kind named `name`; false if it names none.
bool parse_mpc_kind(const std::string& name, MpcKind& kind);

// What the MPC solves from at each sampling instant: the simulator's exact state, as the thesis's
// simulations had it, or what a robot without force sensors knows from the biped's simulated IMU,
// encoders and boards' velocities (hmpc/humanoid/sensors.hpp): the contact-aided invariant EKF
// (hmpc/estimation/biped_state_estimator.hpp) or the thesis's whole-body UKF with its base
// Kalman filter (hmpc/estimation/whole_body_ukf.hpp), which also takes the applied torques.
// And, to tell what an estimator's error costs the closed loop from what the joint sensors'
// does, the simulator's base (a perfect base estimator) with the encoders' angles and the
// boards' velocities.
enum class StateFeedback { kTruth, kInvariantEkf, kWholeBodyUkf, kTrueBase };
constexpr int kStateFeedbacks = 4;
// "truth", "invariant-ekf", "whole-body-ukf", "true-base".
const char* name_of(StateFeedback feedback);
bool parse_state_feedback(const std::string& name, StateFeedback& feedback);

// Table 2.4's Fine MPC.
constexpr double kFineStep = 0.010;
constexpr int kFineHorizon = 30;

// Every motion starts standing quietly (standing_state) at motion I's height, Table 2.2: the
// first phases of IV (0.65 m, sitting down) and VII-VIII (0 m, a crouch the legs cannot reach)
// are targets to move towards, not poses to start in.
constexpr double kStartHeight = 0.85;

struct ClosedLoopConfig {
  MpcKind mpc = MpcKind::kCoarseFast;
  double duration = 0.0;  // [s]; 0: the motion file's
  // Algorithm 1, line 1: the initial input sequence optimised offline (kOfflineIterations)
  // from the start state; without it the first solve starts from zero torques (Fig. 2.9's
  // "without optimisation of the initial inputs").
  bool warm_start = true;
  bool truncate = true;  // stop a solve at the sampling time (see above)
  // The run ends early when the robot has fallen: a part other than the feet (head, hips,
  // knees) within this height of the ground [m], or a state no longer finite. Our choice:
  // 5 cm, below which kneeling, sitting on the ground or lying is unmistakable, while the
  // deepest squat keeps the knees and hips some 0.3 m up.
  double fallen_clearance = 0.05;
  int threads = 2;  // linearisation threads (ThreadPool), 1: serial
  // The whole robot's velocity at the start [m/s], world (joint rates zero, so the feet slide
  // until friction stops them): the benchmark's perturbed starts. At most 1 m/s.
  Eigen::Vector3d initial_velocity = Eigen::Vector3d::Zero();
  // The base point's height in the starting stance [m]: another body (a demonstrator with longer
  // legs, hmpc/ioc/demonstrator.hpp) stands at its own.
  double start_height = kStartHeight;
  // The iLQR iteration cap per sample (Coarse-Fast: each layer's); 0: Table 2.4's
  // (kIterationCap). More makes each plan nearer a local optimum of its cost, as the human
  // demonstrator's (hmpc/ioc/demonstrator.hpp) should be.
  int iteration_cap = 0;
  // Keep every 1 ms simulator step (BasicClosedLoopRun::milliseconds): recorded truth for the
  // state estimator's sensors and checks.
  bool record_milliseconds = false;
  StateFeedback feedback = StateFeedback::kTruth;
  // With an estimator: its sensors, and how long the robot is held still in its starting
  // stance before the MPC takes over, the rest that starts the filter (attitude from gravity,
  // gyroscope bias from the mean rate). Choice: 0.5 s averages the gyroscope's white noise to
  // 0.02 deg/s, a fiftieth of its power-up bias.
  SensorConfig sensors{};
  double rest_seconds = 0.5;
  ProblemConfig problem{};
  // The sampling period (Coarse-Fast's upper step) and the lower layer's step: Table 2.4's, or
  // the real robot's of Sec. 2.7.3 (kRealRobotTiming, Coarse-Fast and Coarse only: the Fine
  // MPC's 10 ms steps do not divide its 12 ms period). The Coarse MPC steps at the period.
  CoarseFastTiming timing = kSimulationTiming;
};

// One 1 ms step of the simulator: the state at its end, the step's mean acceleration
// (v_end - v_start) / 1 ms, and the torque applied.
template <int A>
struct BasicSimulatorStep {
  double time = 0.0;  // [s], at the end of the step
  BasicState<A> state;
  BasicVelocity<A> acceleration;
  BasicJointVector<A> torque;
};

// One 30 ms sampling period, of the biped (A = 0) or the robot with an arm (A = 1).
template <int A>
struct BasicClosedLoopSample {
  double time = 0.0;           // [s], at the end of the period
  BasicState<A> state;         // simulated, at the end of the period
  BaseFeatures base;           // of `state`
  BasicJointVector<A> torque;  // the input applied during the period's first fine step [N m]
  // Vertical ground (and seat) force on each foot and on the seat points [N] (left, right,
  // seat), averaged over the period's 1 ms simulator steps (each step's force at its start):
  // what a load cell read at 33 Hz behind an anti-aliasing filter gives. A sample at one
  // instant instead catches the contact's millisecond bounces within a stance as lift-offs.
  double left_force = 0.0, right_force = 0.0, seat_force = 0.0;
  double solve_seconds = 0.0;  // wall clock of the MPC update that started the period
  LayerWork work{};            // that update's work, by layer (the solver's counters)
  int iterations = 0;          // the (upper) layer's
  int fast_iterations = 0;     // Coarse-Fast's lower layer's
  // Coarse-Fast: how much the lower layer changed the applied inputs, the largest |nu| (Eq.
  // 2.36) over the period's fine steps and the joints, as a fraction of the joint's torque
  // limit; 0 for the single-layer MPCs.
  double lower_layer_change = 0.0;
  bool plan_usable = false;
  bool truncated = false;  // the solve was stopped at the sampling time
  // What the MPC solved from at the period's start (the state itself with StateFeedback::kTruth)
  // and, with an estimator, its spread and trust then.
  BasicState<A> feedback;
  estimation::Spread spread;
  estimation::Trust trust = estimation::Trust::kTracking;
  // Sec. 4.3.1's running cost l(x, u, t) integrated over the period on the 1 ms simulator,
  // in units of coarse steps (divided by 30 ms), so that a period adds what one coarse-step
  // term of the MPC's objective would.
  double cost = 0.0;
};

template <int A>
struct BasicClosedLoopRun {
  std::vector<BasicClosedLoopSample<A>> samples;
  std::vector<BasicSimulatorStep<A>> milliseconds;  // with ClosedLoopConfig::record_milliseconds
  BasicState<A> initial;
  double sampling_period = kSamplingPeriod;        // [s], ClosedLoopConfig::timing's
  StateFeedback feedback = StateFeedback::kTruth;  // what the MPC solved from
  double fell_at = -1.0;  // [s] the sample where the run ended early (see fallen_height), or -1
  // [s] the sampling instant where the estimator said its estimate was lost, or -1: the run ends
  // there, as a controller would stop its MPC and leave the robot to the boards' posture hold.
  double estimate_lost_at = -1.0;
  bool fell() const { return fell_at >= 0.0; }
  bool estimate_lost() const { return estimate_lost_at >= 0.0; }
};
using ClosedLoopSample = BasicClosedLoopSample<0>;
using ClosedLoopRun = BasicClosedLoopRun<0>;
using SimulatorStep = BasicSimulatorStep<0>;
using ArmClosedLoopRun = BasicClosedLoopRun<1>;

// Runs `motion` from standing_state at ClosedLoopConfig::start_height, on the biped (A = 0) or, for
// a reaching motion (Motion::reach), the robot with an arm (A = 1). Throws std::invalid_argument
// for a negative or non-finite duration, threads outside 1..64, an iteration cap outside 0..1000, a
// start height outside 0.3..1.5 m, a model slip velocity outside 0..1 m/s, or a motion that
// needs the other robot; with an estimator, for the robot with an arm (the estimator knows the
// biped), a moving start, or a rest outside 0.01..10 s.
template <int A = 0>
BasicClosedLoopRun<A> run_closed_loop(const Motion& motion, const ClosedLoopConfig& config);

// A lower-layer correction that counts as acting: 1 % of the joint's torque limit (1 N m on the
// ankles' 100 N m). Our threshold; smaller corrections barely move a 1 ms simulator step.
constexpr double kLowerLayerActs = 0.01;

// Summary figures of a run.
struct ClosedLoopSummary {
  // The 99th percentile by nearest rank: the smallest solve that at least 99 % of the samples
  // do not exceed (with fewer than 100 samples, the largest).
  double max_solve_ms = 0.0, median_solve_ms = 0.0, p99_solve_ms = 0.0;
  double mean_iterations = 0.0;
  int truncated = 0, unusable = 0;
  int overruns = 0;  // solves that took longer than the sampling period
  int samples = 0;
  // Samples where the lower layer changed an applied input by more than kLowerLayerActs of its
  // joint's torque limit.
  int lower_layer_acted = 0;
  // How smoothly the applied torques change (Sec. 2.7.3's concern: "sudden jumps in the control
  // inputs can cause undesired oscillations"): the change of each joint's torque from one
  // sample to the next (ClosedLoopSample::torque), RMS over joints and samples and largest [N m].
  double torque_change_rms = 0.0, torque_change_max = 0.0;
  double total_cost = 0.0;
  double min_height = 0.0, max_height = 0.0;
};
template <int A>
ClosedLoopSummary summarise(const BasicClosedLoopRun<A>& run);

// How far what the MPC solved from was from the truth, RMS over a run's samples (each at its
// period's start): base height, horizontal velocity (world) and tilt; and the samples whose
// estimate was degraded.
struct FeedbackErrors {
  double height_rms = 0.0, horizontal_velocity_rms = 0.0, tilt_rms = 0.0;  // m, m/s, rad
  int degraded = 0;
};
template <int A>
FeedbackErrors feedback_errors(const BasicClosedLoopRun<A>& run);

}  // namespace hmpc::humanoid

namespace hmpc {

// The Fine MPC's solver is compiled once, in src/humanoid/solvers (as the layers' are,
// coarse_fast.hpp).
extern template class Ilqr<humanoid::HumanoidProblem<humanoid::kFineHorizon, 0>,
                           humanoid::kFineHorizon>;
extern template class Ilqr<humanoid::HumanoidProblem<humanoid::kFineHorizon, 1>,
                           humanoid::kFineHorizon>;

}  // namespace hmpc
