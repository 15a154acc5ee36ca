// A joint's target trajectory from timed points, as trajectory_msgs/JointTrajectory gives it:
// cubic Hermite between two points that both give a velocity, linear otherwise, held at its
// ends (what ROS 2's joint_trajectory_controller does with positions and velocities). Storage
// is allocated once; assigning and sampling allocate nothing.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace hmpc::trajectory {

struct TrajectoryPoint {
  double time_s = 0;  // from the trajectory's start
  double position = 0;
  double velocity = 0;
  bool has_velocity = false;
};

// p(s) = c0 + c1 s + c2 s^2 + c3 s^3 for s = (t - a.time) / h in [0, 1], h = b.time - a.time:
// the cubic Hermite basis with end slopes h a.velocity and h b.velocity, or the line when either
// velocity is missing.
struct SegmentCubic {
  double c0, c1, c2, c3, h;

  SegmentCubic(const TrajectoryPoint& a, const TrajectoryPoint& b)
      : c0(a.position), c1(0), c2(0), c3(0), h(b.time_s - a.time_s) {
    const double dp = b.position - a.position;
    if (a.has_velocity && b.has_velocity) {
      c1 = h * a.velocity;
      c2 = 3 * dp - h * (2 * a.velocity + b.velocity);
      c3 = -2 * dp + h * (a.velocity + b.velocity);
    } else {
      c1 = dp;
    }
  }
  double position(double s) const { return c0 + s * (c1 + s * (c2 + s * c3)); }
  double velocity(double s) const { return (c1 + s * (2 * c2 + 3 * s * c3)) / h; }
};

// The interpolant's position range and largest speed over a segment, exactly: the speed is a
// quadratic in s, extreme at the ends or its vertex; the position is extreme at the ends or
// where the speed is zero.
struct SegmentBounds {
  double min_position, max_position, max_speed;
};
inline SegmentBounds segment_bounds(const TrajectoryPoint& a, const TrajectoryPoint& b) {
  const SegmentCubic c(a, b);
  SegmentBounds out{std::min(a.position, b.position), std::max(a.position, b.position),
                    std::max(std::abs(c.velocity(0)), std::abs(c.velocity(1)))};
  const auto inside = [](double s) { return s > 0 && s < 1; };
  if (c.c3 != 0) {
    const double vertex = -c.c2 / (3 * c.c3);
    if (inside(vertex)) out.max_speed = std::max(out.max_speed, std::abs(c.velocity(vertex)));
  }
  // Roots of c1 + 2 c2 s + 3 c3 s^2.
  const double qa = 3 * c.c3, qb = 2 * c.c2, qc = c.c1;
  double roots[2];
  int count = 0;
  if (qa == 0) {
    if (qb != 0) roots[count++] = -qc / qb;
  } else {
    const double disc = qb * qb - 4 * qa * qc;
    if (disc >= 0) {
      const double r = std::sqrt(disc);
      roots[count++] = (-qb - r) / (2 * qa);
      roots[count++] = (-qb + r) / (2 * qa);
    }
  }
  for (int i = 0; i < count; ++i) {
    if (!inside(roots[i])) continue;
    const double p = c.position(roots[i]);
    out.min_position = std::min(out.min_position, p);
    out.max_position = std::max(out.max_position, p);
  }
  return out;
}

class JointTrajectoryTarget {
 public:
  explicit JointTrajectoryTarget(std::size_t capacity) { points_.reserve(capacity); }

  std::size_t capacity() const { return points_.capacity(); }

  // Replaces the trajectory. False (and the old one kept) when n is 0 or over capacity.
  bool assign(const TrajectoryPoint* points, std::size_t n) {
    if (n == 0 || n > points_.capacity()) return false;
    points_.assign(points, points + n);
    return true;
  }

  bool empty() const { return points_.empty(); }
  double end_time() const { return points_.empty() ? 0 : points_.back().time_s; }

  // Position at t s from the start; 0 when empty.
  double position(double t) const {
    if (points_.empty()) return 0;
    if (t <= points_.front().time_s) return points_.front().position;
    if (t >= points_.back().time_s) return points_.back().position;
    const auto after =
        std::upper_bound(points_.begin(), points_.end(), t,
                         [](double time, const TrajectoryPoint& p) { return time < p.time_s; });
    const TrajectoryPoint& b = *after;
    const TrajectoryPoint& a = *(after - 1);
    return SegmentCubic(a, b).position((t - a.time_s) / (b.time_s - a.time_s));
  }

 private:
  std::vector<TrajectoryPoint> points_;
};

}  // namespace hmpc::trajectory
