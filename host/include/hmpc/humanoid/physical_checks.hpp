// Did the motion really happen? Physical checks of a closed-loop run (closed_loop.hpp), one per
// motion of Tables 2.2-2.3, with thresholds from physics:
//   I     standing: base point at 0.85 +- 0.05 m throughout (Table 2.2's target; 5 cm is a
//         knee bend of a few degrees, a fall leaves it within a few hundred ms);
//   II    walking at 1.2 m/s, III running at 2.0 m/s: mean forward speed after the first
//         0.5 s (the start from rest) at least 80 % of the target, at least 4 touchdowns with
//         the feet alternating (a touchdown: a foot's vertical load rising through 10 % of
//         m g, well above contact noise and far below a stance's 50 %); III also with
//         flight phases, both feet unloaded in samples adding up to at least 90 ms (three
//         of Table 2.4's 30 ms samples);
//   IV    sitting: the seat carrying at least half the weight with the base point below
//         0.72 m (within 7 cm of Table 2.3's 0.65 m: the seat's 0.50 m height plus our
//         pelvis), then standing: the last 0.3 s unloaded seat and base at 0.85 +- 0.05 m;
//   V-VII jumps: a flight phase, both feet unloaded in consecutive samples over at least
//         60 ms (two 30 ms samples: longer than a stumble's lift-off), and an upright
//         landing: the last 0.3 s on the feet, base at 0.85 +- 0.05 m, torso tilt below 0.3
//         rad; VI also the yaw turned by pi +- 0.3 rad; VII's apex above V's (checked across
//         runs by the caller);
//   VIII  double flip: the torso's pitch integrated over the run at least 4 pi - 0.5 rad (two
//         full rotations), a flight phase, and an upright landing as for V-VII;
//   squat (a phase with a sinusoidal height target: Sec. 2.7.3's slow squat): from the squat's
//         start on, the base point's RMS deviation from the target height at most a quarter of
//         the squat's depth (1 cm of our 4 cm squat: a robot that stands instead is 0.61 depths
//         off, 2.4 cm, one lagging by an eighth of the period 0.27 depths, 1.1 cm), both feet
//         loaded at every sample (the squat keeps its soles down) and the torso tilt below 0.3
//         rad (upright, as a landing);
//   hip hold (Sec. 2.7.3's first task, "maintain [the] initial hip position"): motion I's
//         standing band, and the base point's horizontal position within 5 cm of where the
//         first sample has it (the standing band's half-width: a hold is judged in x and y as
//         standing is in z);
//   reaching (Sec. 2.6.1, Eq. 2.53; the robot with an arm): the hand's centre within 5 cm of
//         the target at a sample after the reach starts (5 cm: a hand's half-width, so the
//         palm touches a ball there).
// Every motion also must not have fallen (closed_loop.hpp's fallen_clearance).
#pragma once

#include <optional>
#include <string>

#include "hmpc/humanoid/closed_loop.hpp"

namespace hmpc::humanoid {

struct PhysicalCheck {
  bool passed = false;
  std::string verdict;  // what was measured against what was required
};

// The motion's numeral (I..VIII) from a motion file name such as "II-walking"; empty if none.
std::string motion_numeral(const std::string& name);

// The check for motion `numeral` (I..VIII). An unknown numeral fails with a verdict saying so.
PhysicalCheck check_motion(const std::string& numeral, const Motion& motion,
                           const ClosedLoopRun& run);

// Whether `motion` has a squat phase, and its check (above).
bool has_squat(const Motion& motion);
PhysicalCheck check_squat(const Motion& motion, const ClosedLoopRun& run);

// The hip hold's check (above), and the largest horizontal distance of the base point from where
// the run's first sample has it [m] (0 without samples).
constexpr double kHipHoldTolerance = 0.05;  // [m]
PhysicalCheck check_hip_hold(const ClosedLoopRun& run);
double hip_drift(const ClosedLoopRun& run);

// The check a motion file's run gets: its numeral's (check_motion), else the squat's, else the
// hip hold's (a motion with CostWeights::position); none for other motions. `name` is the
// file's name, as motion_numeral takes it; `what` names the check for a report ("motion I",
// "the squat", "the hip hold").
struct MotionCheck {
  std::string what;
  PhysicalCheck check;
};
std::optional<MotionCheck> check_for(const std::string& name, const Motion& motion,
                                     const ClosedLoopRun& run);

// The highest base point of a run [m] (VII against V), and the lowest (a squat's depth).
double apex_height(const ClosedLoopRun& run);
double lowest_height(const ClosedLoopRun& run);
// The longest flight phase of a run [s]: consecutive samples with both feet unloaded, as the
// jumps' check counts them.
double longest_flight(const ClosedLoopRun& run);

constexpr double kReachTolerance = 0.05;  // [m] hand to target, see above
// How a reaching run (Motion::reach) went: the smallest hand-to-target distance at a sample
// from the reach's start on, when it happened and when the hand first came within
// kReachTolerance (both in seconds after the start; -1 if never): the latter is our analogue
// of the thesis's reaching time (Sec. 2.6.3: 1.66 s from the start to the smallest distance).
struct ReachFigures {
  double closest = -1.0;        // [m]
  double closest_after = -1.0;  // [s]
  double within_after = -1.0;   // [s]
};
ReachFigures reach_figures(const Motion& motion, const ArmClosedLoopRun& run);
PhysicalCheck check_reaching(const Motion& motion, const ArmClosedLoopRun& run);

}  // namespace hmpc::humanoid
