#include "hmpc/ioc/demonstrator.hpp"

#include <Eigen/Geometry>
#include <random>
#include <stdexcept>

namespace hmpc::ioc {

humanoid::Parameters demonstrator_parameters() {
  const humanoid::Parameters robot;
  humanoid::Parameters p;
  p.stature = 1.72;
  p.body_mass = 60.0;
  p.thigh.reference_length += 0.03;
  p.shank.reference_length -= 0.01;
  p.trunk.reference_length -= 0.02;
  for (int j = 0; j < humanoid::kJointsPerLeg; ++j) {
    p.torque_limit[j] = robot.torque_limit[j] * p.body_mass / robot.body_mass;
  }
  return p;
}

double leg_length(const humanoid::Parameters& p) {
  return p.stature -
         (p.head.reference_length + p.trunk.reference_length) * p.stature / p.reference_stature;
}

double demonstrator_start_height() {
  const double base_point =
      humanoid::ProblemConfig{}.base_point.z();  // above the hips, either body
  return base_point + (humanoid::kStartHeight - base_point) *
                          leg_length(demonstrator_parameters()) /
                          leg_length(humanoid::Parameters{});
}

namespace {

// `task` with each phase's length (and the last one's, to the end) scaled by its own factor.
humanoid::Motion with_timing(const humanoid::Motion& task, double spread, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> factor(1.0 - spread, 1.0 + spread);
  humanoid::Motion m = task;
  double start = 0.0;
  for (int k = 1; k < task.phase_count; ++k) {
    start += (task.phases[k].start - task.phases[k - 1].start) * factor(rng);
    m.phases[k].start = start;
  }
  m.duration = start + (task.duration - task.phases[task.phase_count - 1].start) * factor(rng);
  return m;
}

}  // namespace

std::vector<Capture> capture_demonstrations(
    const humanoid::Motion& task, const CaptureConfig& config,
    const std::function<void(int index, const humanoid::ClosedLoopRun& run)>& progress) {
  if (config.count < 1 || config.count > 200)
    throw std::invalid_argument("captures: count must be in 1..200");
  if (!(config.timing_spread >= 0.0 && config.timing_spread < 0.5)) {
    throw std::invalid_argument("captures: the timing spread must be in [0, 0.5)");
  }
  if (!(config.angle_noise >= 0.0 && config.position_noise >= 0.0)) {
    throw std::invalid_argument("captures: noise must be >= 0");
  }
  std::mt19937_64 rng(config.seed);
  std::normal_distribution<double> angle(0.0, config.angle_noise),
      position(0.0, config.position_noise);
  humanoid::ClosedLoopConfig run_config;
  run_config.mpc = humanoid::MpcKind::kCoarse;
  run_config.truncate = false;
  run_config.threads = config.threads;
  run_config.start_height = demonstrator_start_height();
  run_config.iteration_cap = config.iteration_cap;
  run_config.problem.parameters = demonstrator_parameters();

  const auto captured = [&](const humanoid::Configuration& q) {
    humanoid::Configuration noisy = q;
    for (int i = 0; i < 3; ++i) noisy[i] += position(rng);
    const Eigen::Vector3d tilt(angle(rng), angle(rng), angle(rng));
    const Eigen::Quaterniond error =
        tilt.norm() > 0.0 ? Eigen::Quaterniond(Eigen::AngleAxisd(tilt.norm(), tilt.normalized()))
                          : Eigen::Quaterniond::Identity();
    const Eigen::Quaterniond attitude = Eigen::Quaterniond(q[3], q[4], q[5], q[6]) * error;
    noisy.segment<4>(3) << attitude.w(), attitude.x(), attitude.y(), attitude.z();
    noisy.segment<4>(3).normalize();
    for (int j = 7; j < noisy.size(); ++j) noisy[j] += angle(rng);
    return noisy;
  };

  std::vector<Capture> captures;
  for (int i = 0; i < config.count; ++i) {
    const humanoid::Motion performance = with_timing(task, config.timing_spread, rng);
    const humanoid::ClosedLoopRun run = humanoid::run_closed_loop(performance, run_config);
    if (progress) progress(i, run);
    if (run.fell()) continue;
    Capture capture;
    capture.poses.reserve(run.samples.size() + 1);
    capture.poses.push_back(captured(run.initial.q));
    for (const humanoid::ClosedLoopSample& sample : run.samples)
      capture.poses.push_back(captured(sample.state.q));
    captures.push_back(std::move(capture));
  }
  return captures;
}

}  // namespace hmpc::ioc
