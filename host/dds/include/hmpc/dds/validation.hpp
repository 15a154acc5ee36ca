// Checks of every sample that comes in over DDS, before anything acts on it, and counters of
// what was rejected and why. Accepting a sample allocates nothing; a rejection's message does.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

#include "hmpc/dds/messages.hpp"

namespace hmpc::dds {

enum class Rejection : std::uint8_t {
  kNotFinite,       // a NaN or infinity
  kOutOfRange,      // a value outside its documented or configured range
  kUnknownValue,    // an enumerated value or name the receiver does not know
  kLengthMismatch,  // arrays that must have the same length do not
  kDuplicateName,   // a joint or weight named twice
  kBadTimeStamp,    // nanosec >= 1e9, or a stamp too far from the receiver's clock
  kNotIncreasing,   // trajectory times that do not strictly increase
  kTooLarge,        // more points, names or seconds than the receiver holds
  kRateLimit,       // a trajectory faster than the joint may move
};
inline constexpr std::size_t kRejectionCount = 9;

// snake_case name of a reason, as in logs and summaries.
const char* rejection_name(Rejection reason);

struct Verdict {
  bool ok = true;
  Rejection reason = Rejection::kOutOfRange;
  std::string detail;  // names the field, its value and what was expected; empty when ok

  static Verdict accept() { return {}; }
  static Verdict reject(Rejection reason, std::string detail) {
    return {false, reason, std::move(detail)};
  }
};

class RejectCounters {
 public:
  void add(Rejection reason) { ++counts_[static_cast<std::size_t>(reason)]; }
  std::uint64_t count(Rejection reason) const { return counts_[static_cast<std::size_t>(reason)]; }
  std::uint64_t total() const;
  // "not_finite=1 length_mismatch=2", the reasons seen; "none" when nothing was rejected.
  std::string summary() const;

 private:
  std::array<std::uint64_t, kRejectionCount> counts_{};
};

// Header stamps: builtin_interfaces/Time's nanosec below 1e9, and, unless zero (which ROS 2
// tools send when they do not stamp), within max_skew_s of the receiver's clock: further apart
// means a sender whose clock is wrong, or a sample from another run.
struct StampPolicy {
  double max_skew_s = 10.0;
};
Verdict check_stamp(const msg::Time& stamp, double now_unix_s, const StampPolicy& policy);

// One joint a trajectory may name, with what a trajectory may ask of it.
struct JointLimits {
  const char* name;
  double min_position;  // rad
  double max_position;
  double max_speed;  // rad/s: between points, of given velocities, and of the interpolant
};

struct TrajectoryLimits {
  std::size_t max_points = 8192;
  double max_duration_s = 600.0;
};

// trajectory_msgs/JointTrajectory: every joint of `joints` named exactly once, nothing else;
// 1..max_points points, time_from_start from 0 up, strictly increasing, within max_duration_s;
// positions (required), velocities, accelerations and effort (each empty or one per joint)
// finite; positions inside the joint's range and velocities inside its speed; the motion
// between points within max_speed. One joint per trajectory is what the forearm needs; the
// checks are per joint, in the order of joint_names.
Verdict validate(const msg::JointTrajectory& trajectory, const JointLimits* joints,
                 std::size_t joint_count, const TrajectoryLimits& limits, double now_unix_s,
                 const StampPolicy& stamps);

// hmpc_msgs/ModeCommand: mode 1..3, a strategy among `strategies` (the receiver's names), and
// a sane stamp.
Verdict validate(const msg::ModeCommand& command, const char* const* strategies,
                 std::size_t strategy_count, double now_unix_s, const StampPolicy& stamps);

// One named value a message may set (a cost weight, a task's parameter), with its range.
struct NamedRange {
  const char* name;
  double min;
  double max;
};
// hmpc_msgs/CostWeights: as many values as names, each name known and given once, each value
// finite and inside its limits. A message may set any subset of the weights.
Verdict validate(const msg::CostWeights& weights, const NamedRange* known, std::size_t known_count,
                 double now_unix_s, const StampPolicy& stamps);

// One task a TaskCommand may name, with the parameters it takes.
struct TaskSpec {
  const char* name;
  const NamedRange* parameters;
  std::size_t parameter_count;
};
// hmpc_msgs/TaskCommand: a task among `tasks`, a sane stamp, and its parameters as CostWeights'
// values are checked: as many values as names, each one of the task's, given once, finite and
// in range. No parameters at all is a task with its defaults.
Verdict validate(const msg::TaskCommand& command, const TaskSpec* tasks, std::size_t task_count,
                 double now_unix_s, const StampPolicy& stamps);

// sensor_msgs/JointState as a receiver needs it: position, velocity and effort each empty or
// one per name, finite, and a sane stamp.
Verdict validate(const msg::JointState& state, double now_unix_s, const StampPolicy& stamps);

}  // namespace hmpc::dds
