// From the demonstrator's captures to the robot's (x, u) demonstrations (thesis Sec. 4.2.1).
//  1. Joint-angle mapping [93]: the robot has the demonstrator's joints, so each joint angle
//     maps to itself, clamped to the robot's range of motion; the base position scales by the
//     ratio of leg lengths (robot / demonstrator); the attitude is kept.
//  2. Time warping, in up to three steps:
//     a. dynamic time warping aligns every capture onto one reference capture (the one of
//        median length), which removes the performances' differing timings, so that all
//        demonstrations share one timeline and one set of targets;
//     b. time is scaled by sqrt(l_robot / l_demonstrator), Froude dynamic similarity: a motion
//        of a geometrically scaled body under the same gravity needs the same torques per unit
//        weight and length when its time scales as the square root of its lengths (a flight to a
//        scaled apex lasts exactly that much less). Played at the demonstrator's speed, the
//        robot's shorter legs would have to jump relatively higher than the demonstrator did;
//     c. with TimeWarping::kFeasibility, the thesis's warping against the motion feasibility
//        index [26] (feasibility.hpp) bends step b's timeline sample by sample where the mean
//        aligned capture needs a contact wrench the robot's soles cannot supply; the same
//        timeline then plays every capture, so they stay aligned.
//  3. Tracking MPC: the robot's Coarse MPC (untruncated) tracks each warped capture at the
//     coarse step, its joint angles (CostWeights::joint) and its base's attitude, height and
//     velocity (Eqs. 4.25-4.27 with the warped capture as the target); the executed run is the
//     demonstration (demonstration_of).
// The mean of the tracked motions is the demonstrated behaviour whose base attitude, height and
// velocity are the targets of learning and of generation (Sec. 4.3.2: "They were used as target
// attitude a, height p_z, and velocity v of the base link for motion generation"). The tracked
// motions, not the warped captures: with the same joint angles the robot's other proportions
// put its centre of mass elsewhere, so it balances the squat with its torso 0.1 rad RMS off the
// capture's (measured, 40 squats), and targets it cannot reach read to IOC as weak costs.
#pragma once

#include <functional>
#include <vector>

#include "hmpc/ioc/demonstrator.hpp"
#include "hmpc/ioc/feasibility.hpp"
#include "hmpc/ioc/local_ioc.hpp"

namespace hmpc::ioc {

// Motion capture's usual first step, low-pass filtering before differentiating: the noise,
// differentiated into velocities, would otherwise become targets the tracking MPC chases.
// Choice: a zero-phase binomial filter (1 4 6 4 1) / 16 over the 33 Hz samples, gain 0.5 at
// 6 Hz (the order of the cut-offs biomechanics uses for whole-body motion) and 0.89 at 2.6 Hz.
std::vector<humanoid::Configuration> low_pass(const std::vector<humanoid::Configuration>& poses);

// Step 1 for one pose.
humanoid::Configuration map_pose(const humanoid::Configuration& pose, double length_scale,
                                 const humanoid::Parameters& robot);

// Step 2a: for each pose of `reference`, the (fractional) index of the pose of `poses` that
// dynamic time warping matches to it, over base height, attitude and joint angles; the match
// is smoothed over 5 samples (fewer at the ends, symmetrically) and kept non-decreasing.
std::vector<double> align(const std::vector<humanoid::Configuration>& poses,
                          const std::vector<humanoid::Configuration>& reference);

// `poses` at fractional indices `at` (linear interpolation, the quaternion renormalised).
std::vector<humanoid::Configuration> resample(const std::vector<humanoid::Configuration>& poses,
                                              const std::vector<double>& at);

// States from poses `step` apart, the velocities by central differences (one-sided at the ends).
std::vector<humanoid::State> with_velocities(const std::vector<humanoid::Configuration>& poses,
                                             double step);

// Roll, pitch, yaw of a unit quaternion (w, x, y, z): the inverse of attitude_quaternion
// (motion.hpp) for pitch within (-pi/2, pi/2).
Eigen::Vector3d attitude_angles(const Eigen::Vector4d& quaternion);

// A motion whose phases, one per kCoarseStep, target `states`: the base point's attitude,
// height and velocity (problem.hpp's features) and the joint angles; the other settings from
// `task`. Throws std::invalid_argument if the states need more than kMaxPhases phases.
humanoid::Motion motion_along(const std::vector<humanoid::State>& states,
                              const humanoid::Motion& task, const humanoid::ProblemConfig& problem);

enum class TimeWarping { kFroude, kFeasibility };  // steps 2a-b, or 2a-c

struct RetargetConfig {
  humanoid::Parameters demonstrator = demonstrator_parameters();
  TimeWarping warping = TimeWarping::kFroude;
  WarpConfig warp{};
  humanoid::ProblemConfig robot{};
  // The tracking MPC's w_joint, by Bryson's rule as the motion files' weights: 0.05 rad.
  double joint_weight = 400.0;
  // The tracking MPC's iLQR iterations per sample, for plans near their optimum as the
  // demonstrator's (CaptureConfig::iteration_cap).
  int iteration_cap = 30;
  int threads = 2;
};

// A run's root-mean-square errors against a motion's targets over its samples: the base point's
// height [m], the torso's attitude (the angle between it and the target's [rad]), the base
// point's velocity (norm [m/s]) and the legs' joint angles (Phase::joints [rad]).
struct MotionErrors {
  double height = 0.0, attitude = 0.0, velocity = 0.0, joints = 0.0;
};
MotionErrors motion_errors(const humanoid::Motion& targets, const humanoid::ClosedLoopRun& run);

// The lowest and highest base point height a motion targets over its duration [m] (every 10
// ms): a demonstrated behaviour's squat depth and jump apex.
struct HeightRange {
  double lowest = 0.0, highest = 0.0;
};
HeightRange target_heights(const humanoid::Motion& motion);

struct TrackedDemonstration {
  Demonstration demonstration;
  MotionErrors errors;  // of the tracking run against its targets
  bool fell = false;    // the robot fell: no demonstration
  // The tracking run's highest base point [m] and longest flight phase [s]
  // (physical_checks.hpp).
  double apex = 0.0, flight = 0.0;
};

// Steps 1-2's result.
struct WarpedCaptures {
  std::vector<std::vector<humanoid::State>> states;  // per capture, every kCoarseStep
  double time_scale = 1.0;                           // step 2b's factor
  // Per sample of the reference capture: step 2c's speed factors (all 1 without it), and the
  // feasibility index of the mean aligned capture on step 2b's timeline and on the final one
  // (empty for a reference shorter than kMinPoses).
  std::vector<double> speeds, nominal_index, warped_index;
};

struct Retargeted {
  // Targets of the demonstrated behaviour (the mean tracked motion), `task`'s weights.
  humanoid::Motion reference;
  std::vector<humanoid::State> mean;  // the mean tracked motion, every kCoarseStep
  std::vector<TrackedDemonstration> tracked;
  WarpedCaptures warping;
};

// Steps 1-2 for every capture. Throws std::invalid_argument without captures or if one is
// shorter than 2 poses.
WarpedCaptures warp_captures(const std::vector<Capture>& captures, const RetargetConfig& config);

// Steps 1-3 for every capture; `task` is the robot's motion for the task (its weights are the
// tracking MPC's, with w_joint added, and the targets' other settings). `progress` hears of
// each tracked demonstration. Throws std::invalid_argument without captures or if one is
// shorter than 2 poses.
Retargeted retarget(
    const std::vector<Capture>& captures, const humanoid::Motion& task,
    const RetargetConfig& config,
    const std::function<void(int index, const TrackedDemonstration&)>& progress = {});

}  // namespace hmpc::ioc
