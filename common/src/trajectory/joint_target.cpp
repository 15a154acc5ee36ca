#include "hmpc/trajectory/joint_target.hpp"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>

namespace hmpc::trajectory {

namespace {

constexpr double kPi = 3.14159265358979323846;

struct ShapeName {
  TargetShape shape;
  const char* name;
};
constexpr ShapeName kShapeNames[] = {{TargetShape::kSine, "sine"},
                                     {TargetShape::kStep, "step"},
                                     {TargetShape::kRamp, "ramp"},
                                     {TargetShape::kChirp, "chirp"},
                                     {TargetShape::kFile, "file"}};

std::string format(const char* pattern, ...) __attribute__((format(printf, 1, 2)));
std::string format(const char* pattern, ...) {
  char text[256];
  va_list args;
  va_start(args, pattern);
  std::vsnprintf(text, sizeof text, pattern, args);
  va_end(args);
  return text;
}

// theta(t) = offset + A sin(phi(t)), phi' = 2 pi f(t): points every kSampleSpacingS with their
// velocities, to duration_s.
template <typename Phase, typename Rate>
bool sample_curve(const TargetSpec& s, std::size_t max_points, Phase phase, Rate rate,
                  std::vector<TrajectoryPoint>& points, std::string& error) {
  const auto count = static_cast<std::size_t>(std::ceil(s.duration_s / kSampleSpacingS)) + 1;
  if (count > max_points) {
    error = format("%g s of %s at %g s spacing is %zu points, at most %zu", s.duration_s,
                   shape_name(s.shape), kSampleSpacingS, count, max_points);
    return false;
  }
  for (std::size_t k = 0; k < count; ++k) {
    const double t = double(k) * kSampleSpacingS;
    points.push_back({t, s.offset + s.amplitude * std::sin(phase(t)),
                      s.amplitude * std::cos(phase(t)) * rate(t), true});
  }
  return true;
}

bool shape_points_of(const TargetSpec& s, std::size_t max_points, std::vector<TrajectoryPoint>& out,
                     std::string& error) {
  for (const double value : {s.amplitude, s.frequency_hz, s.offset, s.chirp_end_hz, s.step_at_s,
                             s.step_rate, s.duration_s}) {
    if (!std::isfinite(value)) {
      error = "the target's parameters must be finite";
      return false;
    }
  }
  if (!(s.duration_s > 0)) {
    error = format("the target's duration must be positive, got %g s", s.duration_s);
    return false;
  }
  switch (s.shape) {
    case TargetShape::kSine: {
      const double w = 2 * kPi * s.frequency_hz;
      return sample_curve(
          s, max_points, [w](double t) { return w * t; }, [w](double) { return w; }, out, error);
    }
    case TargetShape::kChirp: {
      // phi(t) = 2 pi (f0 t + (f1 - f0) t^2 / (2 T)), phi'(t) = 2 pi (f0 + (f1 - f0) t / T).
      const double f0 = s.frequency_hz, sweep = (s.chirp_end_hz - f0) / s.duration_s;
      return sample_curve(
          s, max_points, [=](double t) { return 2 * kPi * (f0 * t + sweep * t * t / 2); },
          [=](double t) { return 2 * kPi * (f0 + sweep * t); }, out, error);
    }
    case TargetShape::kStep: {
      if (!(s.step_rate > 0)) {
        error = format("the step's rate must be positive, got %g rad/s", s.step_rate);
        return false;
      }
      if (!(s.step_at_s >= 0 && s.step_at_s < s.duration_s)) {
        error =
            format("the step at %g s must lie within the target's %g s", s.step_at_s, s.duration_s);
        return false;
      }
      out.push_back({0, s.offset, 0, false});
      if (s.step_at_s > 0) out.push_back({s.step_at_s, s.offset, 0, false});
      if (s.amplitude != 0) {
        out.push_back(
            {s.step_at_s + std::abs(s.amplitude) / s.step_rate, s.offset + s.amplitude, 0, false});
      }
      return true;
    }
    case TargetShape::kRamp: {
      if (!(s.frequency_hz > 0)) {
        error = format("a ramp needs a frequency above 0, got %g Hz", s.frequency_hz);
        return false;
      }
      // Corners a quarter period after the start, then every half period, up to the first one
      // at or past the duration.
      const double period = 1 / s.frequency_hz;
      const auto corners =
          static_cast<std::size_t>(std::ceil((s.duration_s - period / 4) / (period / 2))) + 1;
      if (corners + 1 > max_points) {
        error = format("%g s of ramps at %g Hz is %zu points, at most %zu", s.duration_s,
                       s.frequency_hz, corners + 1, max_points);
        return false;
      }
      out.push_back({0, s.offset, 0, false});
      for (std::size_t k = 0; k < corners; ++k) {
        const double sign = k % 2 == 0 ? 1 : -1;
        out.push_back(
            {period / 4 + double(k) * period / 2, s.offset + sign * s.amplitude, 0, false});
      }
      return true;
    }
    case TargetShape::kFile: return read_points_csv(s.file, max_points, out, error);
  }
  error = "unknown target shape";
  return false;
}

// The number in a CSV field, the whole field (surrounding blanks allowed).
bool parse_field(const std::string& field, double& out) {
  const char* begin = field.c_str();
  char* end = nullptr;
  errno = 0;
  out = std::strtod(begin, &end);
  if (end == begin || errno == ERANGE) return false;
  while (*end == ' ' || *end == '\t' || *end == '\r') ++end;
  return *end == '\0';
}

}  // namespace

std::string check_points(const TrajectoryPoint* points, std::size_t n, const JointRange& range) {
  if (n == 0) return "the target has no points";
  for (std::size_t k = 0; k < n; ++k) {
    const TrajectoryPoint& p = points[k];
    if (!std::isfinite(p.time_s) || !std::isfinite(p.position) ||
        (p.has_velocity && !std::isfinite(p.velocity))) {
      return format("point %zu is not finite (time %g s, position %g rad, velocity %g rad/s)", k,
                    p.time_s, p.position, p.velocity);
    }
    if (k == 0 && p.time_s < 0) return format("point 0 is at %g s, before the start", p.time_s);
    if (k > 0 && !(p.time_s > points[k - 1].time_s)) {
      return format("point %zu at %g s does not follow point %zu at %g s", k, p.time_s, k - 1,
                    points[k - 1].time_s);
    }
    if (p.position < range.min_position || p.position > range.max_position) {
      return format("point %zu (t = %g s) asks for %g rad, outside the joint's %g..%g rad", k,
                    p.time_s, p.position, range.min_position, range.max_position);
    }
    if (p.has_velocity && std::abs(p.velocity) > range.max_speed) {
      return format("point %zu (t = %g s) asks for %g rad/s, beyond the joint's %g rad/s", k,
                    p.time_s, p.velocity, range.max_speed);
    }
  }
  for (std::size_t k = 1; k < n; ++k) {
    const SegmentBounds b = segment_bounds(points[k - 1], points[k]);
    if (b.max_speed > range.max_speed) {
      return format(
          "between points %zu and %zu (t = %g..%g s) the target moves at %g rad/s, "
          "beyond the joint's %g rad/s",
          k - 1, k, points[k - 1].time_s, points[k].time_s, b.max_speed, range.max_speed);
    }
    if (b.min_position < range.min_position || b.max_position > range.max_position) {
      return format(
          "between points %zu and %zu (t = %g..%g s) the target swings to %g..%g rad, "
          "outside the joint's %g..%g rad",
          k - 1, k, points[k - 1].time_s, points[k].time_s, b.min_position, b.max_position,
          range.min_position, range.max_position);
    }
  }
  return {};
}

const char* shape_name(TargetShape shape) {
  for (const ShapeName& s : kShapeNames)
    if (s.shape == shape) return s.name;
  return "";
}

bool shape_of(const std::string& name, TargetShape& out) {
  for (const ShapeName& s : kShapeNames) {
    if (name == s.name) {
      out = s.shape;
      return true;
    }
  }
  return false;
}

bool shape_points(const TargetSpec& spec, std::size_t max_points,
                  std::vector<TrajectoryPoint>& points, std::string& error) {
  points.clear();
  return shape_points_of(spec, max_points, points, error);
}

bool make_points(const TargetSpec& spec, const JointRange& range, std::size_t max_points,
                 std::vector<TrajectoryPoint>& points, std::string& error) {
  if (!shape_points(spec, max_points, points, error)) return false;
  error = check_points(points.data(), points.size(), range);
  if (!error.empty() && spec.shape == TargetShape::kFile) error = spec.file + ": " + error;
  return error.empty();
}

bool read_points_csv(const std::string& path, std::size_t max_points,
                     std::vector<TrajectoryPoint>& points, std::string& error) {
  std::ifstream in(path);
  if (!in) {
    error = path + ": cannot open: " + std::strerror(errno);
    return false;
  }
  const std::size_t first = points.size();
  std::size_t line_number = 0;
  bool header_allowed = true;
  for (std::string line; std::getline(in, line);) {
    ++line_number;
    const std::size_t start = line.find_first_not_of(" \t\r");
    if (start == std::string::npos || line[start] == '#') continue;
    double values[3] = {0, 0, 0};
    std::size_t fields = 0;
    bool numbers = true, first_is_number = true;
    for (std::size_t from = 0; from <= line.size();) {
      std::size_t comma = line.find(',', from);
      if (comma == std::string::npos) comma = line.size();
      if (fields == 3) {
        fields = 4;
        break;
      }
      const bool number = parse_field(line.substr(from, comma - from), values[fields]);
      if (fields == 0) first_is_number = number;
      numbers = numbers && number;
      ++fields;
      from = comma + 1;
    }
    if (!first_is_number && header_allowed &&
        std::isalpha(static_cast<unsigned char>(line[start]))) {
      header_allowed = false;
      continue;
    }
    header_allowed = false;
    const std::string where = path + ":" + std::to_string(line_number) + ": ";
    if (fields < 2 || fields > 3) {
      error = where;
      error += "expected time_s,position_rad[,velocity_rad_s], got '";
      error += line;
      error += "'";
      return false;
    }
    if (!numbers) {
      error = where;
      error += "not a number in '";
      error += line;
      error += "'";
      return false;
    }
    if (points.size() - first == max_points) {
      error = where + "more than " + std::to_string(max_points) + " points";
      return false;
    }
    points.push_back({values[0], values[1], values[2], fields == 3});
  }
  if (in.bad()) {
    error = path + ": read error";
    return false;
  }
  if (points.size() == first) {
    error = path + ": no points";
    return false;
  }
  return true;
}

}  // namespace hmpc::trajectory
