#include "hmpc/dds/validation.hpp"

#include <cmath>
#include <cstdio>
#include <cstring>

#include "hmpc/trajectory/joint_trajectory.hpp"

namespace hmpc::dds {

namespace {

constexpr std::uint32_t kNanosecondsPerSecond = 1000000000u;

template <class... Numbers>
std::string format(const char* pattern, Numbers... numbers) {
  char text[256];
  std::snprintf(text, sizeof text, pattern, numbers...);
  return text;
}

std::string text_of(const char* s) { return s ? s : "(null)"; }

// Accepted when value is finite and inside [min, max]; field() names it only on rejection.
template <class Field>
Verdict check_value(double value, double min, double max, Field&& field) {
  if (!std::isfinite(value)) {
    return Verdict::reject(Rejection::kNotFinite, field() + format(" is not finite (%g)", value));
  }
  if (value < min || value > max) {
    return Verdict::reject(Rejection::kOutOfRange,
                           field() + format(" = %g is outside %g..%g", value, min, max));
  }
  return Verdict::accept();
}

// point >= 0: the field of a trajectory point, named points[point].field.
Verdict check_finite(const char* field, long point, const dds_sequence_double& values) {
  for (std::uint32_t i = 0; i < values._length; ++i) {
    if (std::isfinite(values._buffer[i])) continue;
    const std::string where = point >= 0 ? format("points[%ld].%s", point, field) : field;
    return Verdict::reject(Rejection::kNotFinite,
                           where + format("[%u] is not finite (%g)", i, values._buffer[i]));
  }
  return Verdict::accept();
}

// The place of name among known's names; known_count when it is not there (or null).
std::size_t find_name(const char* name, const char* const* known, std::size_t known_count) {
  std::size_t k = 0;
  while (k < known_count && !(name && std::strcmp(name, known[k]) == 0)) ++k;
  return k;
}

// An unknown name's rejection: what was given, then the names known.
Verdict not_one_of(const std::string& given, const char* const* known, std::size_t known_count) {
  std::string expected;
  for (std::size_t n = 0; n < known_count; ++n) expected += (n ? ", " : "") + text_of(known[n]);
  return Verdict::reject(Rejection::kUnknownValue, given + " is not one of: " + expected);
}

// Names all different and each in `known` (if given): index[i] is name i's place in known.
Verdict check_names(const char* field, const dds_sequence_string& names, const char* const* known,
                    std::size_t known_count, std::size_t* index) {
  for (std::uint32_t i = 0; i < names._length; ++i) {
    const char* name = names._buffer[i];
    if (name == nullptr) {
      return Verdict::reject(Rejection::kUnknownValue, format("%s[%u] is null", field, i));
    }
    for (std::uint32_t j = 0; j < i; ++j) {
      if (std::strcmp(name, names._buffer[j]) == 0) {
        return Verdict::reject(Rejection::kDuplicateName,
                               format("%s[%u] '%s' is named twice", field, i, name));
      }
    }
    if (known == nullptr) continue;
    const std::size_t k = find_name(name, known, known_count);
    if (k == known_count) {
      return not_one_of(format("%s[%u] '%s'", field, i, name), known, known_count);
    }
    index[i] = k;
  }
  return Verdict::accept();
}

// check_names against entries with a .name (joints, weights): at most kMaxKnown of them.
constexpr std::size_t kMaxKnown = 64;
template <class Known>
Verdict check_names_of(const char* field, const dds_sequence_string& names, const Known* known,
                       std::size_t known_count, std::size_t* index) {
  if (known_count > kMaxKnown || names._length > kMaxKnown) {
    return Verdict::reject(Rejection::kTooLarge,
                           format("%s has %u names, at most %zu", field, names._length, kMaxKnown));
  }
  const char* known_names[kMaxKnown];
  for (std::size_t k = 0; k < known_count; ++k) known_names[k] = known[k].name;
  return check_names(field, names, known_names, known_count, index);
}

// Optional per-joint arrays: empty or one per joint.
Verdict check_length(const char* field, std::uint32_t point, const dds_sequence_double& values,
                     std::size_t joints, bool required) {
  if ((values._length == 0 && !required) || values._length == joints) return Verdict::accept();
  return Verdict::reject(
      Rejection::kLengthMismatch,
      format("points[%u].%s has %u values for %zu joints", point, field, values._length, joints));
}

}  // namespace

const char* rejection_name(Rejection reason) {
  switch (reason) {
    case Rejection::kNotFinite: return "not_finite";
    case Rejection::kOutOfRange: return "out_of_range";
    case Rejection::kUnknownValue: return "unknown_value";
    case Rejection::kLengthMismatch: return "length_mismatch";
    case Rejection::kDuplicateName: return "duplicate_name";
    case Rejection::kBadTimeStamp: return "bad_time_stamp";
    case Rejection::kNotIncreasing: return "not_increasing";
    case Rejection::kTooLarge: return "too_large";
    case Rejection::kRateLimit: return "rate_limit";
  }
  return "unknown";
}

std::uint64_t RejectCounters::total() const {
  std::uint64_t sum = 0;
  for (std::uint64_t c : counts_) sum += c;
  return sum;
}

std::string RejectCounters::summary() const {
  std::string s;
  for (std::size_t i = 0; i < kRejectionCount; ++i) {
    if (counts_[i] == 0) continue;
    s += (s.empty() ? "" : " ") + std::string(rejection_name(static_cast<Rejection>(i))) + "=" +
         std::to_string(counts_[i]);
  }
  return s.empty() ? "none" : s;
}

Verdict check_stamp(const msg::Time& stamp, double now_unix_s, const StampPolicy& policy) {
  if (stamp.nanosec >= kNanosecondsPerSecond) {
    return Verdict::reject(Rejection::kBadTimeStamp,
                           format("header.stamp.nanosec = %u is not below 1e9", stamp.nanosec));
  }
  if (stamp.sec == 0 && stamp.nanosec == 0) return Verdict::accept();
  const double skew = to_seconds(stamp) - now_unix_s;
  if (!(std::abs(skew) <= policy.max_skew_s)) {
    return Verdict::reject(Rejection::kBadTimeStamp,
                           format("header.stamp is %.3f s from this machine's clock (at most "
                                  "%.3f s allowed; 0 means unstamped)",
                                  skew, policy.max_skew_s));
  }
  return Verdict::accept();
}

Verdict validate(const msg::JointTrajectory& trajectory, const JointLimits* joints,
                 std::size_t joint_count, const TrajectoryLimits& limits, double now_unix_s,
                 const StampPolicy& stamps) {
  Verdict v = check_stamp(trajectory.header.stamp, now_unix_s, stamps);
  if (!v.ok) return v;
  const std::size_t n = trajectory.joint_names._length;
  if (n != joint_count) {
    return Verdict::reject(
        Rejection::kLengthMismatch,
        format("joint_names has %zu names; this robot has %zu joints", n, joint_count));
  }
  std::size_t index[kMaxKnown];
  v = check_names_of("joint_names", trajectory.joint_names, joints, joint_count, index);
  if (!v.ok) return v;

  const std::uint32_t count = trajectory.points._length;
  if (count == 0) return Verdict::reject(Rejection::kLengthMismatch, "points is empty");
  if (count > limits.max_points) {
    return Verdict::reject(Rejection::kTooLarge,
                           format("%u points, at most %zu", count, limits.max_points));
  }
  double previous_time = -1;
  for (std::uint32_t k = 0; k < count; ++k) {
    const msg::JointTrajectoryPoint& p = trajectory.points._buffer[k];
    if (p.time_from_start.nanosec >= kNanosecondsPerSecond) {
      return Verdict::reject(Rejection::kBadTimeStamp,
                             format("points[%u].time_from_start.nanosec = %u is not below 1e9", k,
                                    p.time_from_start.nanosec));
    }
    const double time = to_seconds(p.time_from_start);
    if (time < 0 || time > limits.max_duration_s) {
      return Verdict::reject(Rejection::kOutOfRange,
                             format("points[%u].time_from_start = %g s is outside 0..%g s", k, time,
                                    limits.max_duration_s));
    }
    if (!(time > previous_time)) {
      return Verdict::reject(
          Rejection::kNotIncreasing,
          format("points[%u].time_from_start = %g s does not follow %g s", k, time, previous_time));
    }
    previous_time = time;
    for (const Verdict& check :
         {check_length("positions", k, p.positions, n, true),
          check_length("velocities", k, p.velocities, n, false),
          check_length("accelerations", k, p.accelerations, n, false),
          check_length("effort", k, p.effort, n, false), check_finite("positions", k, p.positions),
          check_finite("velocities", k, p.velocities),
          check_finite("accelerations", k, p.accelerations), check_finite("effort", k, p.effort)}) {
      if (!check.ok) return check;
    }
    for (std::size_t i = 0; i < n; ++i) {
      const JointLimits& joint = joints[index[i]];
      v = check_value(p.positions._buffer[i], joint.min_position, joint.max_position,
                      [&] { return format("points[%u].positions[%zu] (%s)", k, i, joint.name); });
      if (!v.ok) return v;
      if (p.velocities._length > 0 && std::abs(p.velocities._buffer[i]) > joint.max_speed) {
        return Verdict::reject(Rejection::kRateLimit,
                               format("points[%u].velocities[%zu] (%s) = %g rad/s is beyond the "
                                      "joint's %g rad/s",
                                      k, i, joint.name, p.velocities._buffer[i], joint.max_speed));
      }
    }
  }
  // The interpolant between points, as the receiver will follow it.
  for (std::uint32_t k = 1; k < count; ++k) {
    const msg::JointTrajectoryPoint& a = trajectory.points._buffer[k - 1];
    const msg::JointTrajectoryPoint& b = trajectory.points._buffer[k];
    for (std::size_t i = 0; i < n; ++i) {
      const JointLimits& joint = joints[index[i]];
      const auto point = [i](const msg::JointTrajectoryPoint& p) {
        const bool has_velocity = p.velocities._length > 0;
        return trajectory::TrajectoryPoint{to_seconds(p.time_from_start), p.positions._buffer[i],
                                           has_velocity ? p.velocities._buffer[i] : 0,
                                           has_velocity};
      };
      const trajectory::SegmentBounds bounds = trajectory::segment_bounds(point(a), point(b));
      if (bounds.max_speed > joint.max_speed) {
        return Verdict::reject(Rejection::kRateLimit,
                               format("between points[%u] and [%u], %s moves at up to %g rad/s, "
                                      "beyond its %g rad/s",
                                      k - 1, k, joint.name, bounds.max_speed, joint.max_speed));
      }
      if (bounds.min_position < joint.min_position || bounds.max_position > joint.max_position) {
        return Verdict::reject(Rejection::kOutOfRange,
                               format("between points[%u] and [%u], %s swings to %g..%g rad, "
                                      "outside %g..%g rad",
                                      k - 1, k, joint.name, bounds.min_position,
                                      bounds.max_position, joint.min_position, joint.max_position));
      }
    }
  }
  return Verdict::accept();
}

Verdict validate(const msg::ModeCommand& command, const char* const* strategies,
                 std::size_t strategy_count, double now_unix_s, const StampPolicy& stamps) {
  Verdict v = check_stamp(command.header.stamp, now_unix_s, stamps);
  if (!v.ok) return v;
  if (command.mode < static_cast<std::uint8_t>(CommandMode::kIdle) ||
      command.mode > static_cast<std::uint8_t>(CommandMode::kRun)) {
    return Verdict::reject(
        Rejection::kUnknownValue,
        format("mode %u is not idle (1), hold (2) or run (3)", unsigned{command.mode}));
  }
  if (find_name(command.strategy, strategies, strategy_count) == strategy_count) {
    return not_one_of("strategy '" + text_of(command.strategy) + "'", strategies, strategy_count);
  }
  return Verdict::accept();
}

namespace {

// Named values against the known ones: as many values as names, each name known and given
// once, each value finite and inside its range.
Verdict check_named_values(const char* names_field, const dds_sequence_string& names,
                           const char* values_field, const dds_sequence_double& values,
                           const NamedRange* known, std::size_t known_count) {
  const std::size_t n = names._length;
  if (values._length != n) {
    return Verdict::reject(Rejection::kLengthMismatch, format("%u %s for %zu %s", values._length,
                                                              values_field, n, names_field));
  }
  std::size_t index[kMaxKnown];
  Verdict v = check_names_of(names_field, names, known, known_count, index);
  if (!v.ok) return v;
  for (std::size_t i = 0; i < n; ++i) {
    const NamedRange& r = known[index[i]];
    v = check_value(values._buffer[i], r.min, r.max,
                    [&] { return format("%s[%zu] (%s)", values_field, i, r.name); });
    if (!v.ok) return v;
  }
  return Verdict::accept();
}

}  // namespace

Verdict validate(const msg::CostWeights& weights, const NamedRange* known, std::size_t known_count,
                 double now_unix_s, const StampPolicy& stamps) {
  Verdict v = check_stamp(weights.header.stamp, now_unix_s, stamps);
  if (!v.ok) return v;
  if (weights.names._length == 0 && weights.values._length == 0) {
    return Verdict::reject(Rejection::kLengthMismatch, "no weights");
  }
  return check_named_values("names", weights.names, "values", weights.values, known, known_count);
}

Verdict validate(const msg::TaskCommand& command, const TaskSpec* tasks, std::size_t task_count,
                 double now_unix_s, const StampPolicy& stamps) {
  Verdict v = check_stamp(command.header.stamp, now_unix_s, stamps);
  if (!v.ok) return v;
  if (task_count > kMaxKnown) {
    return Verdict::reject(Rejection::kTooLarge,
                           format("%zu tasks known, at most %zu", task_count, kMaxKnown));
  }
  const char* names[kMaxKnown];
  for (std::size_t k = 0; k < task_count; ++k) names[k] = tasks[k].name;
  const std::size_t t = find_name(command.task, names, task_count);
  if (t == task_count) {
    return not_one_of("task '" + text_of(command.task) + "'", names, task_count);
  }
  return check_named_values("parameter_names", command.parameter_names, "parameter_values",
                            command.parameter_values, tasks[t].parameters,
                            tasks[t].parameter_count);
}

Verdict validate(const msg::JointState& state, double now_unix_s, const StampPolicy& stamps) {
  Verdict v = check_stamp(state.header.stamp, now_unix_s, stamps);
  if (!v.ok) return v;
  const std::size_t n = state.name._length;
  v = check_names("name", state.name, nullptr, 0, nullptr);
  if (!v.ok) return v;
  const std::pair<const char*, const dds_sequence_double*> fields[] = {
      {"position", &state.position}, {"velocity", &state.velocity}, {"effort", &state.effort}};
  for (const auto& [field, values] : fields) {
    if (values->_length != 0 && values->_length != n) {
      return Verdict::reject(Rejection::kLengthMismatch,
                             format("%s has %u values for %zu names", field, values->_length, n));
    }
    v = check_finite(field, -1, *values);
    if (!v.ok) return v;
  }
  return Verdict::accept();
}

}  // namespace hmpc::dds
