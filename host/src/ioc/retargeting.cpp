#include "hmpc/ioc/retargeting.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "hmpc/humanoid/physical_checks.hpp"

namespace hmpc::ioc {

using humanoid::Configuration;
using humanoid::State;

namespace {

constexpr int kLegJoints = 2 * humanoid::kJointsPerLeg;
constexpr int kJointOffset = 7;  // q = (p, quaternion, joints)

Eigen::Quaterniond quaternion_of(const Configuration& q) {
  return Eigen::Quaterniond(q[3], q[4], q[5], q[6]);
}

// What dynamic time warping compares, each part scaled by a deviation we count as equal:
// 5 cm of base height, 0.05 of a quaternion component (6 degrees), 0.1 rad of a joint angle.
Eigen::Matrix<double, 4 + kLegJoints, 1> warping_features(const Configuration& q) {
  Eigen::Matrix<double, 4 + kLegJoints, 1> f;
  f[0] = q[2] / 0.05;
  f.segment<3>(1) = q.segment<3>(4) / 0.05;
  f.tail<kLegJoints>() = q.tail<kLegJoints>() / 0.1;
  return f;
}

}  // namespace

Configuration map_pose(const Configuration& pose, double length_scale,
                       const humanoid::Parameters& robot) {
  Configuration q = pose;
  q.head<3>() *= length_scale;
  q.segment<4>(3).normalize();
  for (int j = 0; j < kLegJoints; ++j) {
    const int joint = j % humanoid::kJointsPerLeg;
    q[kJointOffset + j] =
        std::clamp(q[kJointOffset + j], robot.joint_lower[joint], robot.joint_upper[joint]);
  }
  return q;
}

std::vector<Configuration> low_pass(const std::vector<Configuration>& poses) {
  // Binomial weights (1 4 6 4 1) / 16, renormalised where the window runs past an end.
  constexpr double kWeights[5] = {1.0, 4.0, 6.0, 4.0, 1.0};
  const int n = static_cast<int>(poses.size());
  std::vector<Configuration> out(poses.size());
  for (int k = 0; k < n; ++k) {
    Configuration sum = Configuration::Zero();
    double total = 0.0;
    for (int l = -2; l <= 2; ++l) {
      if (k + l < 0 || k + l >= n) continue;
      Configuration q = poses[k + l];
      if (q.segment<4>(3).dot(poses[k].segment<4>(3)) < 0.0) q.segment<4>(3) = -q.segment<4>(3);
      sum += kWeights[l + 2] * q;
      total += kWeights[l + 2];
    }
    out[k] = sum / total;
    out[k].segment<4>(3).normalize();
  }
  return out;
}

std::vector<double> align(const std::vector<Configuration>& poses,
                          const std::vector<Configuration>& reference) {
  const int n = static_cast<int>(reference.size()), m = static_cast<int>(poses.size());
  if (n == 0 || m == 0) throw std::invalid_argument("align: empty pose sequence");
  // Accumulated cost D(i, j) = d(i, j) + min(D(i-1, j), D(i, j-1), D(i-1, j-1)).
  std::vector<double> D(static_cast<std::size_t>(n) * m);
  const auto at = [&](int i, int j) -> double& { return D[static_cast<std::size_t>(i) * m + j]; };
  const double inf = std::numeric_limits<double>::infinity();
  for (int i = 0; i < n; ++i) {
    const auto fi = warping_features(reference[i]);
    for (int j = 0; j < m; ++j) {
      const double d = (fi - warping_features(poses[j])).squaredNorm();
      double best = i == 0 && j == 0 ? 0.0 : inf;
      if (i > 0) best = std::min(best, at(i - 1, j));
      if (j > 0) best = std::min(best, at(i, j - 1));
      if (i > 0 && j > 0) best = std::min(best, at(i - 1, j - 1));
      at(i, j) = d + best;
    }
  }
  // Back along the cheapest path; each reference index takes the mean of its matches.
  std::vector<double> sum(n, 0.0), matches(n, 0.0);
  int i = n - 1, j = m - 1;
  while (true) {
    sum[i] += j;
    matches[i] += 1.0;
    if (i == 0 && j == 0) break;
    if (i == 0) {
      --j;
    } else if (j == 0) {
      --i;
    } else {
      const double diagonal = at(i - 1, j - 1), up = at(i - 1, j), left = at(i, j - 1);
      if (diagonal <= up && diagonal <= left) {
        --i;
        --j;
      } else if (up <= left) {
        --i;
      } else {
        --j;
      }
    }
  }
  std::vector<double> index(n), smooth(n);
  for (int k = 0; k < n; ++k) index[k] = sum[k] / matches[k];
  // DTW's staircase would make standstills and jumps of the velocities: a 5-sample average,
  // narrowed symmetrically at the ends so that a uniform match stays exact there.
  for (int k = 0; k < n; ++k) {
    const int half = std::min({2, k, n - 1 - k});
    double total = 0.0;
    for (int l = k - half; l <= k + half; ++l) total += index[l];
    smooth[k] = total / (2 * half + 1);
  }
  for (int k = 1; k < n; ++k) smooth[k] = std::max(smooth[k], smooth[k - 1]);
  return smooth;
}

std::vector<Configuration> resample(const std::vector<Configuration>& poses,
                                    const std::vector<double>& at) {
  if (poses.size() < 2) throw std::invalid_argument("resample: needs 2 poses or more");
  std::vector<Configuration> out;
  out.reserve(at.size());
  const int last_segment = static_cast<int>(poses.size()) - 2;
  for (const double a : at) {
    const double s = std::clamp(a, 0.0, last_segment + 1.0);
    const int k = std::min(static_cast<int>(s), last_segment);
    Configuration q = (1.0 - (s - k)) * poses[k] + (s - k) * poses[k + 1];
    q.segment<4>(3).normalize();
    out.push_back(q);
  }
  return out;
}

std::vector<State> with_velocities(const std::vector<Configuration>& poses, double step) {
  if (poses.size() < 2) throw std::invalid_argument("with_velocities: needs 2 poses or more");
  const int n = static_cast<int>(poses.size());
  std::vector<State> states(n);
  for (int k = 0; k < n; ++k) {
    const int a = std::max(0, k - 1), b = std::min(n - 1, k + 1);
    const double dt = (b - a) * step;
    const Eigen::Quaterniond qa = quaternion_of(poses[a]), qb = quaternion_of(poses[b]),
                             qk = quaternion_of(poses[k]);
    State& x = states[k];
    x.q = poses[k];
    // v = (torso angular velocity, torso origin velocity, joint rates), the first two in torso
    // coordinates (model.hpp).
    const Eigen::AngleAxisd turn(qa.conjugate() * qb);
    x.v.head<3>() = turn.angle() * turn.axis() / dt;
    x.v.segment<3>(3) =
        qk.conjugate() * Eigen::Vector3d((poses[b].head<3>() - poses[a].head<3>()) / dt);
    x.v.tail<kLegJoints>() = (poses[b].tail<kLegJoints>() - poses[a].tail<kLegJoints>()) / dt;
  }
  return states;
}

Eigen::Vector3d attitude_angles(const Eigen::Vector4d& q) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  return Eigen::Vector3d(std::atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y)),
                         std::asin(std::clamp(2.0 * (w * y - z * x), -1.0, 1.0)),
                         std::atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z)));
}

humanoid::Motion motion_along(const std::vector<State>& states, const humanoid::Motion& task,
                              const humanoid::ProblemConfig& problem) {
  if (states.empty()) throw std::invalid_argument("motion_along: no states");
  if (static_cast<int>(states.size()) > humanoid::kMaxPhases) {
    throw std::invalid_argument(
        "motion_along: " + std::to_string(states.size()) + " samples need more than " +
        std::to_string(humanoid::kMaxPhases) + " phases (" +
        std::to_string(humanoid::kMaxPhases * humanoid::kCoarseStep) + " s)");
  }
  const humanoid::StateCost cost(task, states.front(), problem);
  humanoid::Motion m = task;
  m.phase_count = static_cast<int>(states.size());
  m.duration = (states.size() - 1) * humanoid::kCoarseStep;
  for (std::size_t k = 0; k < states.size(); ++k) {
    const humanoid::BaseFeatures f = cost.features(states[k]);
    humanoid::Phase& phase = m.phases[k];
    phase.start = k * humanoid::kCoarseStep;
    phase.attitude = attitude_angles(f.quaternion);
    phase.height = f.position.z();
    phase.velocity = f.velocity;
    for (int j = 0; j < kLegJoints; ++j) phase.joints[j] = states[k].q[kJointOffset + j];
  }
  return m;
}

MotionErrors motion_errors(const humanoid::Motion& targets, const humanoid::ClosedLoopRun& run) {
  MotionErrors e;
  if (run.samples.empty()) return e;
  for (const humanoid::ClosedLoopSample& s : run.samples) {
    const humanoid::Phase& target = targets.phase_at(s.time);
    e.height += std::pow(s.base.position.z() - target.height_at(s.time), 2);
    const Eigen::Vector4d a = humanoid::attitude_quaternion(target.attitude);
    const double cosine = std::min(1.0, std::abs(a.dot(s.base.quaternion)));
    e.attitude += std::pow(2.0 * std::acos(cosine), 2);
    e.velocity += (s.base.velocity - target.velocity_at(s.time)).squaredNorm();
    for (int j = 0; j < kLegJoints; ++j)
      e.joints += std::pow(s.state.q[kJointOffset + j] - target.joints[j], 2) / kLegJoints;
  }
  const double n = static_cast<double>(run.samples.size());
  e.height = std::sqrt(e.height / n);
  e.attitude = std::sqrt(e.attitude / n);
  e.velocity = std::sqrt(e.velocity / n);
  e.joints = std::sqrt(e.joints / n);
  return e;
}

HeightRange target_heights(const humanoid::Motion& motion) {
  HeightRange r{std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  for (int k = 0; k * 0.01 <= motion.duration; ++k) {
    const double t = k * 0.01, height = motion.phase_at(t).height_at(t);
    r.lowest = std::min(r.lowest, height);
    r.highest = std::max(r.highest, height);
  }
  return r;
}

namespace {

// Sample by sample over equally long motions; quaternions summed with the first motion's sign,
// then normalised (the motions differ by a few degrees).
std::vector<State> mean_motion(const std::vector<std::vector<State>>& motions) {
  std::size_t samples = motions.front().size();
  for (const std::vector<State>& m : motions) samples = std::min(samples, m.size());
  std::vector<State> mean(samples);
  for (std::size_t k = 0; k < samples; ++k) {
    const Eigen::Vector4d sign = motions.front()[k].q.segment<4>(3);
    State sum{Configuration::Zero(), humanoid::Velocity::Zero()};
    for (const std::vector<State>& m : motions) {
      Configuration q = m[k].q;
      if (q.segment<4>(3).dot(sign) < 0.0) q.segment<4>(3) = -q.segment<4>(3);
      sum.q += q;
      sum.v += m[k].v;
    }
    sum.q /= static_cast<double>(motions.size());
    sum.q.segment<4>(3).normalize();
    sum.v /= static_cast<double>(motions.size());
    mean[k] = sum;
  }
  return mean;
}

}  // namespace

WarpedCaptures warp_captures(const std::vector<Capture>& captures, const RetargetConfig& config) {
  if (captures.empty()) throw std::invalid_argument("retarget: no captures");
  for (const Capture& c : captures) {
    if (c.poses.size() < 2) throw std::invalid_argument("retarget: a capture shorter than 2 poses");
  }
  WarpedCaptures out;
  // Step 1, after the capture's low-pass filter.
  const double length_scale = leg_length(config.robot.parameters) / leg_length(config.demonstrator);
  std::vector<std::vector<Configuration>> mapped;
  for (const Capture& c : captures) {
    std::vector<Configuration> poses;
    for (const Configuration& q : low_pass(c.poses))
      poses.push_back(map_pose(q, length_scale, config.robot.parameters));
    mapped.push_back(std::move(poses));
  }
  // Step 2: the reference is the capture of median length; robot sample k (time k Delta t_c) is
  // the reference's sample k / c, c = sqrt(l_robot / l_demonstrator).
  std::vector<std::size_t> order(mapped.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return mapped[a].size() < mapped[b].size(); });
  const std::vector<Configuration>& reference = mapped[order[order.size() / 2]];
  out.time_scale = std::sqrt(length_scale);
  std::vector<std::vector<double>> matches;
  std::vector<std::vector<State>> aligned;
  for (const std::vector<Configuration>& poses : mapped) {
    matches.push_back(align(poses, reference));
    std::vector<State> states;
    for (const Configuration& q : resample(poses, matches.back()))
      states.push_back({q, humanoid::Velocity::Zero()});
    aligned.push_back(std::move(states));
  }
  // Step 2c on the mean aligned capture, whose samples last kCoarseStep * time_scale of the
  // robot's time on step 2b's timeline.
  std::vector<Configuration> mean_aligned;
  for (const State& x : mean_motion(aligned)) mean_aligned.push_back(x.q);
  const double nominal_step = humanoid::kCoarseStep * out.time_scale;
  out.speeds.assign(mean_aligned.size(), 1.0);
  if (mean_aligned.size() >= kMinPoses) {
    FeasibilityIndex index(config.robot.parameters);
    out.nominal_index = feasibility_along(mean_aligned, nominal_step, out.speeds, index);
    if (config.warping == TimeWarping::kFeasibility)
      out.speeds = feasible_speeds(mean_aligned, nominal_step, index, config.warp);
    out.warped_index = feasibility_along(mean_aligned, nominal_step, out.speeds, index);
  }
  const std::vector<double> reference_at =
      warped_indices(out.speeds, nominal_step, humanoid::kCoarseStep);
  const int samples = static_cast<int>(reference_at.size());
  for (std::size_t c = 0; c < mapped.size(); ++c) {
    const std::vector<Configuration>& poses = mapped[c];
    const std::vector<double>& match = matches[c];
    std::vector<double> at(samples);
    for (int k = 0; k < samples; ++k) {
      const double s = std::min(reference_at[k], static_cast<double>(match.size() - 1));
      const int i =
          std::min(static_cast<int>(s), static_cast<int>(match.size()) - 2);  // match has >= 2
      at[k] = match[i] + (s - i) * (match[i + 1] - match[i]);
    }
    out.states.push_back(with_velocities(resample(poses, at), humanoid::kCoarseStep));
  }
  return out;
}

Retargeted retarget(const std::vector<Capture>& captures, const humanoid::Motion& task,
                    const RetargetConfig& config,
                    const std::function<void(int index, const TrackedDemonstration&)>& progress) {
  Retargeted out;
  out.warping = warp_captures(captures, config);
  const std::vector<std::vector<State>>& warped = out.warping.states;
  // Step 3.
  humanoid::ClosedLoopConfig run_config;
  run_config.mpc = humanoid::MpcKind::kCoarse;
  run_config.truncate = false;
  run_config.threads = config.threads;
  run_config.iteration_cap = config.iteration_cap;
  run_config.problem = config.robot;
  for (std::size_t d = 0; d < warped.size(); ++d) {
    humanoid::Motion tracking = motion_along(warped[d], task, config.robot);
    tracking.weights.joint = config.joint_weight;
    const humanoid::ClosedLoopRun run = humanoid::run_closed_loop(tracking, run_config);
    TrackedDemonstration t;
    t.fell = run.fell();
    t.errors = motion_errors(tracking, run);
    t.apex = humanoid::apex_height(run);
    t.flight = humanoid::longest_flight(run);
    if (!t.fell) t.demonstration = demonstration_of(run);
    if (progress) progress(static_cast<int>(d), t);
    out.tracked.push_back(std::move(t));
  }
  // The demonstrated behaviour: the mean tracked motion, or, if the robot fell in every tracking
  // run, the mean warped capture.
  std::vector<std::vector<State>> robot;
  for (const TrackedDemonstration& t : out.tracked) {
    if (t.fell) continue;
    std::vector<State> states;
    for (const humanoid::StateVector& x : t.demonstration.states)
      states.push_back(humanoid::to_state(x));
    robot.push_back(std::move(states));
  }
  out.mean = mean_motion(robot.empty() ? warped : robot);
  out.reference = motion_along(out.mean, task, config.robot);
  return out;
}

}  // namespace hmpc::ioc
