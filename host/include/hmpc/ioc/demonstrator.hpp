// The human demonstrator (thesis Sec. 4.2.1's captured movements, which we do not have): a
// body with other proportions and masses than the robot's performs a task under hidden "true"
// weights, D times, each with its own timing, and a motion capture records its poses with
// noise. The pipeline (retargeting.hpp) sees only the captures; the tests compare what it
// learns with the hidden weights.
//
// The demonstrator moves by our own Coarse MPC (closed_loop.hpp, untruncated) on its own body:
// a stand-in for a human's motor control that optimises the task's cost (Eq. 4.3) with the
// demonstrator's weights, so there are true weights to recover.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "hmpc/humanoid/closed_loop.hpp"

namespace hmpc::ioc {

// The demonstrator's body (choice): the robot's de Leva model (parameters.hpp) for a taller,
// heavier subject, 1.72 m and 60 kg against 1.59 m and 47 kg, with longer thighs and a shorter
// trunk and shanks (thigh +3 cm, shank -1 cm, trunk -2 cm of de Leva's reference lengths), so
// that its legs are a larger fraction of its height than the robot's, and torque limits scaled
// with its mass. Only that it differs matters.
humanoid::Parameters demonstrator_parameters();

// Hip-to-sole length of a standing leg [m] (model.cpp's mid-hip height).
double leg_length(const humanoid::Parameters& parameters);

struct CaptureConfig {
  int count = 40;  // D, Sec. 4.2.1 (40 each for jumping and squatting)
  // Per-demonstration timing: each phase of the task lasts its nominal time times a factor
  // drawn uniformly from [1 - spread, 1 + spread] (choice: +-15 %, people repeating a jump on
  // cue vary by this order).
  double timing_spread = 0.15;
  // Motion-capture noise, standard deviations (choice: the order of marker-based systems'
  // joint-angle and segment-position errors): joint angles and the torso's attitude [rad], the
  // torso's position [m].
  double angle_noise = 0.01;
  double position_noise = 0.003;
  // The demonstrator's iLQR iterations per sample: an expert moves near a local optimum of its
  // cost, and local IOC reads a plan's distance from one as weaker state costs (measured: from
  // the robot's own Coarse MPC plans, solved 6 iterations per sample, the state weights came out
  // at 5-30 % of the truth relative to the torque weights; re-solved for 300 iterations, at
  // 47-88 %).
  int iteration_cap = 30;
  std::uint64_t seed = 1;
  int threads = 2;
};

// One capture: the demonstrator's pose q (base position, attitude quaternion (w, x, y, z), the
// eight leg joint angles) at the start and then every kCoarseStep (the capture rate, 33 Hz).
struct Capture {
  std::vector<humanoid::Configuration> poses;
};

// The demonstrator standing still at the start, its base point at this height [m]: the hips'
// height under the robot's kStartHeight scaled by the leg lengths (1.107: 0.933 m).
double demonstrator_start_height();

// Captures `config.count` performances of `task` (a motion whose targets are for the
// demonstrator's body and whose weights are its hidden weights). A performance in which the
// demonstrator fell is reported to `progress` and left out. Throws std::invalid_argument for a
// count outside 1..200, a spread outside [0, 0.5) or negative noise.
std::vector<Capture> capture_demonstrations(
    const humanoid::Motion& task, const CaptureConfig& config,
    const std::function<void(int index, const humanoid::ClosedLoopRun& run)>& progress = {});

}  // namespace hmpc::ioc
