// A joint's target as a user asks for it (a sinusoid, a rate-limited step, a triangle of ramps,
// a chirp, or timed points from a CSV file), turned into the timed points of joint_trajectory.hpp
// and checked against what the joint may do before anything is sent to a board. Shared by the
// host that streams the target and the HIL runner that scores the tracking against it. Building
// a target allocates (start-up only); sampling it does not.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "hmpc/trajectory/joint_trajectory.hpp"

namespace hmpc::trajectory {

// What a target may ask of the joint.
struct JointRange {
  double min_position = 0;  // rad
  double max_position = 0;
  double max_speed = 0;  // rad/s, of the interpolant anywhere
};

// "" when the points are a target the joint can follow: at least one; times finite, from 0
// up, strictly increasing; positions and given velocities finite; every position, and the
// interpolant between points (exactly, segment_bounds), inside the range and the speed.
// Otherwise the first problem, naming the point.
std::string check_points(const TrajectoryPoint* points, std::size_t n, const JointRange& range);

enum class TargetShape : std::uint8_t { kSine, kStep, kRamp, kChirp, kFile };

// The shapes' names on command lines; "" for none.
const char* shape_name(TargetShape shape);
bool shape_of(const std::string& name, TargetShape& out);

// The shapes, on the target's own clock t (0 at its start), held after duration_s:
//   sine   offset + amplitude sin(2 pi f t)
//   step   offset until step_at_s, then to offset + amplitude at step_rate (rad/s)
//   ramp   from offset, straight lines between offset + amplitude and offset - amplitude,
//          at the speed 4 amplitude f of a triangle wave of frequency f
//   chirp  offset + amplitude sin(2 pi (f t + (f_end - f) t^2 / (2 duration))): the frequency
//          sweeps linearly from f to f_end over the duration
//   file   the points of a CSV file (read_points_csv)
struct TargetSpec {
  TargetShape shape = TargetShape::kSine;
  double amplitude = 0.5235987755982988;  // rad (30 deg, the thesis's Sec. 3.3 targets)
  double frequency_hz = 1.0;
  double offset = 0;  // rad
  double chirp_end_hz = 2.0;
  double step_at_s = 1.0;
  double step_rate = 3.14159265358979323846;  // rad/s (hmpc-forearm-host says why)
  double duration_s = 10;
  std::string file;
};

// Sinusoids and chirps become points this far apart with their exact velocities: the cubic
// Hermite between them is within A (2 pi f h)^4 / 384 of the curve, 1.3e-5 rad at 30 deg and
// 2.5 Hz.
inline constexpr double kSampleSpacingS = 0.020;
// The most points a target may have (a host holds them all, allocated once): 164 s of a
// sinusoid at kSampleSpacingS.
inline constexpr std::size_t kMaxPoints = 8192;

// The target's points, at most max_points of them, not checked against any joint (a receiver
// that checks them itself, like the DDS bridge, takes these). False, with the reason in
// `error`, when the spec or the file makes no target.
bool shape_points(const TargetSpec& spec, std::size_t max_points,
                  std::vector<TrajectoryPoint>& points, std::string& error);

// shape_points, then checked against `range`: false, with the reason in `error`, when the
// target is not one the joint can follow.
bool make_points(const TargetSpec& spec, const JointRange& range, std::size_t max_points,
                 std::vector<TrajectoryPoint>& points, std::string& error);

// A CSV file of points: one per line, "time_s,position_rad" or
// "time_s,position_rad,velocity_rad_s"; an optional header line (the first, starting with a
// letter), blank lines and lines starting with '#' are skipped. False, with `error` naming the file
// and line, when it cannot be read, a line does not parse, or it holds more than max_points points.
// The points' values are not checked here (check_points does that).
bool read_points_csv(const std::string& path, std::size_t max_points,
                     std::vector<TrajectoryPoint>& points, std::string& error);

}  // namespace hmpc::trajectory
