#include "hmpc/humanoid/physical_checks.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>

namespace hmpc::humanoid {
namespace {

constexpr double kWeight = 47.0 * 9.81;      // m g [N], thesis Sec. 2.5.1
constexpr double kUnloaded = 0.1 * kWeight;  // a foot's load below this: off the ground
constexpr double kStandingHeight = 0.85;     // Table 2.2
constexpr double kRunningFlight = 0.09;      // [s] in all (physical_checks.hpp)
constexpr double kJumpFlight = 0.06;         // [s] in one flight phase
constexpr double kHeightBand = 0.05;
constexpr double kSquatTolerance = 0.25;  // of the squat's depth, see physical_checks.hpp
constexpr double kSettle = 0.3;           // [s] the landing/standing window at the end
constexpr double kPi = 3.14159265358979323846;

template <class... Numbers>
std::string format(const char* pattern, Numbers... numbers) {
  char text[256];
  std::snprintf(text, sizeof text, pattern, double(numbers)...);
  return text;
}

bool airborne(const ClosedLoopSample& s) {
  return s.left_force < kUnloaded && s.right_force < kUnloaded;
}

// Longest run of consecutive samples with both feet unloaded, and how many such samples.
void flight(const ClosedLoopRun& run, int& longest, int& total) {
  longest = total = 0;
  int current = 0;
  for (const ClosedLoopSample& s : run.samples) {
    current = airborne(s) ? current + 1 : 0;
    total += airborne(s) ? 1 : 0;
    longest = std::max(longest, current);
  }
}

// Touchdowns in order, 0 left, 1 right, as a string ("0101...").
std::string touchdowns(const ClosedLoopRun& run) {
  std::string order;
  bool loaded[2] = {true, true};
  for (const ClosedLoopSample& s : run.samples) {
    const double force[2] = {s.left_force, s.right_force};
    for (int foot = 0; foot < 2; ++foot) {
      const bool now = force[foot] >= kUnloaded;
      if (now && !loaded[foot]) order += static_cast<char>('0' + foot);
      loaded[foot] = now;
    }
  }
  return order;
}

double tilt(const ClosedLoopSample& s) {
  // Angle of the torso's z axis from the vertical: cos = 1 - 2 (x^2 + y^2) of the quaternion.
  const Eigen::Vector4d& q = s.base.quaternion;
  return std::acos(std::clamp(1.0 - 2.0 * (q[1] * q[1] + q[2] * q[2]), -1.0, 1.0));
}

double yaw(const ClosedLoopSample& s) {
  const Eigen::Vector4d& q = s.base.quaternion;  // (w, x, y, z)
  return std::atan2(2.0 * (q[0] * q[3] + q[1] * q[2]), 1.0 - 2.0 * (q[2] * q[2] + q[3] * q[3]));
}

// The last kSettle seconds: on the feet, base point in the standing band, upright.
bool lands_upright(const ClosedLoopRun& run, std::string& verdict) {
  const double end = run.samples.back().time;
  double low = 1e9, high = -1e9, worst_tilt = 0.0;
  bool on_feet = true;
  for (const ClosedLoopSample& s : run.samples) {
    if (s.time < end - kSettle) continue;
    low = std::min(low, s.base.position.z());
    high = std::max(high, s.base.position.z());
    worst_tilt = std::max(worst_tilt, tilt(s));
    on_feet = on_feet && !airborne(s);
  }
  verdict += format("; last 0.3 s: base %.3f..%.3f m, tilt up to %.2f rad", low, high, worst_tilt) +
             (on_feet ? ", on its feet" : ", not on its feet");
  return on_feet && low >= kStandingHeight - kHeightBand && high <= kStandingHeight + kHeightBand &&
         worst_tilt < 0.3;
}

PhysicalCheck standing(const ClosedLoopRun& run) {
  double low = 1e9, high = -1e9;
  for (const ClosedLoopSample& s : run.samples) {
    low = std::min(low, s.base.position.z());
    high = std::max(high, s.base.position.z());
  }
  PhysicalCheck c;
  c.passed = low >= kStandingHeight - kHeightBand && high <= kStandingHeight + kHeightBand;
  c.verdict = format("base point %.3f..%.3f m (required 0.80..0.90)", low, high);
  return c;
}

PhysicalCheck locomotion(const Motion& motion, const ClosedLoopRun& run, bool running) {
  const double target = motion.phase_at(0.0).velocity.x();
  const ClosedLoopSample* start = nullptr;
  for (const ClosedLoopSample& s : run.samples) {
    if (s.time >= 0.5) {
      start = &s;
      break;
    }
  }
  PhysicalCheck c;
  if (start == nullptr || run.samples.back().time - start->time < 0.5) {
    c.verdict = "the run is too short to measure a speed";
    return c;
  }
  const ClosedLoopSample& last = run.samples.back();
  const double speed =
      (last.base.position.x() - start->base.position.x()) / (last.time - start->time);
  const std::string order = touchdowns(run);
  int alternations = 0;
  for (std::size_t i = 1; i < order.size(); ++i) alternations += order[i] != order[i - 1] ? 1 : 0;
  const bool alternating = order.size() >= 4 && alternations >= static_cast<int>(order.size()) - 2;
  int longest = 0, flying = 0;
  flight(run, longest, flying);
  c.passed = speed >= 0.8 * target && alternating &&
             (!running || flying * run.sampling_period >= kRunningFlight - 1e-9);
  c.verdict = format("mean forward speed %.2f m/s (required >= %.2f)", speed, 0.8 * target) +
              ", touchdowns " + (order.empty() ? std::string("none") : order) +
              (alternating ? " (alternating)" : " (not alternating)") +
              format(", %.0f samples with both feet off the ground", flying);
  return c;
}

PhysicalCheck sitting(const ClosedLoopRun& run) {
  bool sat = false;
  double lowest_seated = 1e9;
  for (const ClosedLoopSample& s : run.samples) {
    if (s.seat_force >= 0.5 * kWeight && s.base.position.z() <= 0.72) {
      sat = true;
      lowest_seated = std::min(lowest_seated, s.base.position.z());
    }
  }
  const double end = run.samples.back().time;
  double low = 1e9, high = -1e9, seat = 0.0;
  for (const ClosedLoopSample& s : run.samples) {
    if (s.time < end - kSettle) continue;
    low = std::min(low, s.base.position.z());
    high = std::max(high, s.base.position.z());
    seat = std::max(seat, s.seat_force);
  }
  PhysicalCheck c;
  const bool stood = seat < kUnloaded && low >= kStandingHeight - kHeightBand &&
                     high <= kStandingHeight + kHeightBand;
  c.passed = sat && stood;
  c.verdict = (sat ? format("sat (base down to %.3f m on the seat)", lowest_seated)
                   : std::string("never sat (seat load >= m g / 2 with the base below 0.72 m)")) +
              format("; last 0.3 s: base %.3f..%.3f m, seat load up to %.0f N", low, high, seat);
  return c;
}

PhysicalCheck jump(const ClosedLoopRun& run, double turn, double pitch_rotations) {
  int longest = 0, flying = 0;
  flight(run, longest, flying);
  PhysicalCheck c;
  c.verdict = format("longest flight %.0f ms, apex %.3f m", longest * run.sampling_period * 1e3,
                     apex_height(run));
  bool passed = longest * run.sampling_period >= kJumpFlight - 1e-9;
  if (turn != 0.0) {
    const double turned = std::abs(yaw(run.samples.back()));
    c.verdict += format(", yaw turned %.2f rad (required %.2f +- 0.3)", turned, turn);
    passed = passed && std::abs(turned - turn) <= 0.3;
  }
  if (pitch_rotations != 0.0) {
    double pitch = 0.0;
    for (const ClosedLoopSample& s : run.samples)
      pitch += s.base.angular_velocity.y() * run.sampling_period;
    const double required = 2.0 * kPi * pitch_rotations - 0.5;
    c.verdict += format(", pitch rotated %.2f rad (required >= %.2f)", pitch, required);
    passed = passed && pitch >= required;
  }
  passed = lands_upright(run, c.verdict) && passed;
  c.passed = passed;
  return c;
}

// The failed check of a run that cannot be judged (no samples, a fall); none otherwise.
template <int A>
std::optional<PhysicalCheck> ended_early(const BasicClosedLoopRun<A>& run) {
  if (run.samples.empty()) return PhysicalCheck{false, "no samples"};
  if (run.fell()) return PhysicalCheck{false, format("fell at %.2f s", run.fell_at)};
  return std::nullopt;
}

}  // namespace

bool has_squat(const Motion& motion) {
  for (int i = 0; i < motion.phase_count; ++i) {
    if (motion.phases[i].squat_period > 0.0) return true;
  }
  return false;
}

PhysicalCheck check_squat(const Motion& motion, const ClosedLoopRun& run) {
  if (const std::optional<PhysicalCheck> early = ended_early(run)) return *early;
  double squared = 0.0, low = 1e9, target_low = 1e9, worst_tilt = 0.0, depth = 0.0;
  int count = 0, unloaded = 0;
  for (const ClosedLoopSample& s : run.samples) {
    worst_tilt = std::max(worst_tilt, tilt(s));
    unloaded += std::min(s.left_force, s.right_force) < kUnloaded ? 1 : 0;
    const Phase& phase = motion.phase_at(s.time);
    if (phase.squat_period <= 0.0) continue;
    const double target = phase.height_at(s.time);
    squared += (s.base.position.z() - target) * (s.base.position.z() - target);
    low = std::min(low, s.base.position.z());
    target_low = std::min(target_low, target);
    depth = std::max(depth, phase.squat_depth);
    ++count;
  }
  PhysicalCheck c;
  if (count == 0) {
    c.verdict = "the run ended before the squat started";
    return c;
  }
  const double rms = std::sqrt(squared / count);
  c.passed = rms <= kSquatTolerance * depth && unloaded == 0 && worst_tilt < 0.3;
  c.verdict = format(
      "base point %.1f mm RMS from the squat's target height (required <= %.0f), down to %.3f m "
      "(target %.3f m); %.0f samples with a foot unloaded (required 0); tilt up to %.2f rad",
      1e3 * rms, 1e3 * kSquatTolerance * depth, low, target_low, unloaded, worst_tilt);
  return c;
}

double hip_drift(const ClosedLoopRun& run) {
  double drift = 0.0;
  if (run.samples.empty()) return drift;
  for (const ClosedLoopSample& s : run.samples) {
    const Eigen::Vector2d from_start =
        (s.base.position - run.samples.front().base.position).head<2>();
    drift = std::max(drift, from_start.norm());
  }
  return drift;
}

PhysicalCheck check_hip_hold(const ClosedLoopRun& run) {
  if (const std::optional<PhysicalCheck> early = ended_early(run)) return *early;
  PhysicalCheck c = standing(run);
  const double drift = hip_drift(run);
  c.passed = c.passed && drift <= kHipHoldTolerance;
  c.verdict += format("; horizontal drift up to %.1f mm (required <= %.0f)", 1e3 * drift,
                      1e3 * kHipHoldTolerance);
  return c;
}

std::string motion_numeral(const std::string& name) {
  const std::size_t dash = name.find('-');
  std::string numeral = name.substr(0, dash);
  for (const char* known : {"I", "II", "III", "IV", "V", "VI", "VII", "VIII"}) {
    if (numeral == known) return numeral;
  }
  return {};
}

std::optional<MotionCheck> check_for(const std::string& name, const Motion& motion,
                                     const ClosedLoopRun& run) {
  const std::string numeral = motion_numeral(name);
  if (!numeral.empty()) return MotionCheck{"motion " + numeral, check_motion(numeral, motion, run)};
  if (has_squat(motion)) return MotionCheck{"the squat", check_squat(motion, run)};
  if (motion.weights.position > 0.0) return MotionCheck{"the hip hold", check_hip_hold(run)};
  return std::nullopt;
}

double longest_flight(const ClosedLoopRun& run) {
  int longest = 0, flying = 0;
  flight(run, longest, flying);
  return longest * run.sampling_period;
}

double apex_height(const ClosedLoopRun& run) {
  double apex = -1e9;
  for (const ClosedLoopSample& s : run.samples) apex = std::max(apex, s.base.position.z());
  return apex;
}

double lowest_height(const ClosedLoopRun& run) {
  double lowest = 1e9;
  for (const ClosedLoopSample& s : run.samples) lowest = std::min(lowest, s.base.position.z());
  return lowest;
}

PhysicalCheck check_motion(const std::string& numeral, const Motion& motion,
                           const ClosedLoopRun& run) {
  if (const std::optional<PhysicalCheck> early = ended_early(run)) return *early;
  if (numeral == "I") return standing(run);
  if (numeral == "II") return locomotion(motion, run, false);
  if (numeral == "III") return locomotion(motion, run, true);
  if (numeral == "IV") return sitting(run);
  if (numeral == "V" || numeral == "VII") return jump(run, 0.0, 0.0);
  if (numeral == "VI") return jump(run, kPi, 0.0);
  if (numeral == "VIII") return jump(run, 0.0, 2.0);
  return {false, "no physical check for motion '" + numeral + "'"};
}

ReachFigures reach_figures(const Motion& motion, const ArmClosedLoopRun& run) {
  ReachFigures f;
  for (const BasicClosedLoopSample<1>& s : run.samples) {
    if (s.time < motion.reach.start) continue;
    const double distance = (s.base.hand - motion.reach.target).norm();
    const double after = s.time - motion.reach.start;
    if (f.closest < 0.0 || distance < f.closest) {
      f.closest = distance;
      f.closest_after = after;
    }
    if (f.within_after < 0.0 && distance <= kReachTolerance) f.within_after = after;
  }
  return f;
}

PhysicalCheck check_reaching(const Motion& motion, const ArmClosedLoopRun& run) {
  if (const std::optional<PhysicalCheck> early = ended_early(run)) return *early;
  const ReachFigures f = reach_figures(motion, run);
  if (f.closest < 0.0) return {false, "the run ended before the reach started"};
  const std::string closest =
      format("hand closest to the target %.3f m, %.2f s after the reach started", f.closest,
             f.closest_after);
  if (f.within_after < 0.0)
    return {false, closest + format(" (required <= %.2f m)", kReachTolerance)};
  return {true,
          closest + format("; first within %.2f m after %.2f s", kReachTolerance, f.within_after)};
}

}  // namespace hmpc::humanoid
