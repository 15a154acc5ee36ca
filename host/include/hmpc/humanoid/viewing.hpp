// What a person looks at after a closed-loop run (closed_loop.hpp): the trajectory as CSV and
// pictures drawn by gnuplot, a filmstrip of stick figures like the thesis's Figs. 2.7-2.8
// (side view x-z above, front view y-z below, each frame centred on the base) and the base's
// height and forward velocity against the motion's targets.
#pragma once

#include <array>
#include <iosfwd>
#include <string>

#include "hmpc/humanoid/closed_loop.hpp"

namespace hmpc::humanoid {

// The stick figure's points (world) at a state; for the robot with an arm (A = 1) also the
// spine at shoulder height, the shoulder and the hand.
struct StickFigure {
  Vector3 vertex, mid_hip;
  std::array<Vector3, 2> hip, knee, ankle, heel, toe;  // left, right
  bool arm = false;
  Vector3 spine = Vector3::Zero(), shoulder = Vector3::Zero(), hand = Vector3::Zero();
};
template <int A>
StickFigure stick_figure(const BasicState<A>& x, const ProblemConfig& config = ProblemConfig{});

// One row per 30 ms sample (header line first; columns named there): time, base point
// position and velocity, torso quaternion, leg angles, joint angles, applied torques, foot and
// seat forces, solve time, iterations, truncation, period cost, and the phase targets; for the
// robot with an arm its joint and torque after the legs', and at the end the hand's position
// and the reach target.
template <int A>
void write_trajectory_csv(std::ostream& out, const Motion& motion,
                          const BasicClosedLoopRun<A>& run);

// Columns of trajectory.csv that scripts plot, 1-based as gnuplot counts: the base point's
// height and velocity, the torso quaternion (w, x, y, z from kQuaternionColumn), and the
// targets (height, v_x, v_y, v_z, roll, pitch, yaw from kTargetHeightColumn<A>).
constexpr int kHeightColumn = 4, kVelocityColumn = 5, kQuaternionColumn = 8;
template <int A>
constexpr int kTargetHeightColumn = 15 + 2 * Dimensions<A>::kJoints + 10;

// With an estimator in the loop (BasicClosedLoopRun::feedback): one row per 30 ms sample, at the
// period's start, of the torso origin's height, horizontal velocity (world) and roll and
// pitch, truth and what the MPC was given, the estimator's 1-sigma spread of height,
// horizontal velocity and tilt, and its trust (0 tracking, 1 degraded, 2 lost).
template <int A>
void write_estimation_csv(std::ostream& out, const BasicClosedLoopRun<A>& run);

// Writes DIR/trajectory.csv, DIR/filmstrip.dat, DIR/humanoid.gp and runs gnuplot for
// DIR/filmstrip.png (`frames` evenly spaced samples, 2..16) and DIR/base.png. `title` heads
// the pictures. Returns false (with the reason in `error`) if a file cannot be written or
// gnuplot fails; the CSV is written first, so it survives a plotting failure.
// A reaching motion's filmstrip also shows the arm and the target, and base.png the hand's
// distance to the target. With an estimator also DIR/estimation.csv and DIR/estimation.png
// (estimate against truth: height with its 2-sigma band, horizontal velocity, roll and pitch).
template <int A>
bool write_run(const std::string& dir, const std::string& title, const Motion& motion,
               const BasicClosedLoopRun<A>& run, int frames, std::string& error);

}  // namespace hmpc::humanoid
