#include "hmpc/humanoid/closed_loop.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "closed_loop_simulation.hpp"

namespace hmpc::humanoid {
namespace {

constexpr const char* kNames[kMpcKinds] = {"fine", "coarse", "coarse-fast"};
constexpr const char* kFeedbackNames[kStateFeedbacks] = {"truth", "invariant-ekf", "whole-body-ukf",
                                                         "true-base"};

// The enumerator whose name, in `names` (the enumerators' order), is `name`.
template <class Enum, int N>
bool parse_name(const char* const (&names)[N], const std::string& name, Enum& out) {
  for (int i = 0; i < N; ++i) {
    if (name == names[i]) {
      out = static_cast<Enum>(i);
      return true;
    }
  }
  return false;
}

}  // namespace

const char* name_of(StateFeedback feedback) { return kFeedbackNames[static_cast<int>(feedback)]; }

bool parse_state_feedback(const std::string& name, StateFeedback& feedback) {
  return parse_name(kFeedbackNames, name, feedback);
}

const char* name_of(MpcKind kind) { return kNames[static_cast<int>(kind)]; }

bool parse_mpc_kind(const std::string& name, MpcKind& kind) {
  return parse_name(kNames, name, kind);
}

template <int A>
BasicClosedLoopRun<A> run_closed_loop(const Motion& motion, const ClosedLoopConfig& config) {
  if (!(config.duration >= 0.0) || !std::isfinite(config.duration)) {
    throw std::invalid_argument("closed loop: the duration must be a positive number of seconds");
  }
  const double duration = config.duration > 0.0 ? config.duration : motion.duration;
  if (!(duration > 0.0)) {
    throw std::invalid_argument("closed loop: the duration must be a positive number of seconds");
  }
  if (config.threads < 1 || config.threads > 64) {
    throw std::invalid_argument("closed loop: threads must be in 1..64");
  }
  config.timing.check("closed loop");
  if (config.mpc == MpcKind::kFine && (config.timing.upper_step != kSimulationTiming.upper_step ||
                                       config.timing.fast_step != kSimulationTiming.fast_step)) {
    throw std::invalid_argument("closed loop: the Fine MPC runs in Table 2.4's timing only");
  }
  if (config.iteration_cap < 0 || config.iteration_cap > 1000) {
    throw std::invalid_argument("closed loop: the iteration cap must be in 0..1000");
  }
  if (!(config.problem.model_slip_velocity >= 0.0 && config.problem.model_slip_velocity <= 1.0)) {
    throw std::invalid_argument("closed loop: the model's slip velocity must be within 0..1 m/s");
  }
  if (!(config.start_height > 0.3 && config.start_height < 1.5)) {
    throw std::invalid_argument("closed loop: the start height must be within 0.3..1.5 m");
  }
  if (config.feedback != StateFeedback::kTruth) {
    if (A != 0) {
      throw std::invalid_argument("closed loop: the estimator knows the biped, not the arm robot");
    }
    if (!config.initial_velocity.isZero()) {
      throw std::invalid_argument("closed loop: the estimator starts from a robot at rest");
    }
    if (!(config.rest_seconds >= 0.01 && config.rest_seconds <= 10.0)) {
      throw std::invalid_argument("closed loop: the estimator's rest must be within 0.01..10 s");
    }
  }
  ThreadPool pool(config.threads);
  ThreadPool* workers = config.threads > 1 ? &pool : nullptr;
  ProblemConfig start = config.problem;
  start.contact = contact_for(motion, config.problem.contact);
  if (!config.initial_velocity.allFinite() || config.initial_velocity.norm() > 1.0) {
    throw std::invalid_argument(
        "closed loop: the initial velocity must be finite and at most 1 m/s");
  }
  BasicState<A> initial = standing_state<A>(start, config.start_height);
  // v's linear part is the torso origin's velocity in torso coordinates (model.hpp).
  const Eigen::Quaterniond orientation(initial.q[3], initial.q[4], initial.q[5], initial.q[6]);
  initial.v.template segment<3>(3) = orientation.conjugate() * config.initial_velocity;
  switch (config.mpc) {
    case MpcKind::kFine: return detail::run_fine(motion, config, initial, workers, duration);
    case MpcKind::kCoarse: return detail::run_coarse(motion, config, initial, workers, duration);
    case MpcKind::kCoarseFast:
    default: return detail::run_coarse_fast(motion, config, initial, workers, duration);
  }
}

template <int A>
ClosedLoopSummary summarise(const BasicClosedLoopRun<A>& run) {
  ClosedLoopSummary s;
  s.samples = static_cast<int>(run.samples.size());
  if (run.samples.empty()) return s;
  std::vector<double> solve;
  solve.reserve(run.samples.size());
  s.min_height = s.max_height = run.samples.front().base.position.z();
  double iterations = 0.0, change2 = 0.0;
  const BasicJointVector<A>* before = nullptr;
  for (const BasicClosedLoopSample<A>& sample : run.samples) {
    if (before != nullptr) {
      const BasicJointVector<A> change = sample.torque - *before;
      change2 += change.squaredNorm();
      s.torque_change_max = std::max(s.torque_change_max, change.cwiseAbs().maxCoeff());
    }
    before = &sample.torque;
    solve.push_back(sample.solve_seconds * 1e3);
    iterations += sample.iterations;
    s.truncated += sample.truncated ? 1 : 0;
    s.unusable += sample.plan_usable ? 0 : 1;
    s.overruns += sample.solve_seconds > run.sampling_period ? 1 : 0;
    s.total_cost += sample.cost;
    s.lower_layer_acted += sample.lower_layer_change > kLowerLayerActs ? 1 : 0;
    s.min_height = std::min(s.min_height, sample.base.position.z());
    s.max_height = std::max(s.max_height, sample.base.position.z());
  }
  std::sort(solve.begin(), solve.end());
  s.max_solve_ms = solve.back();
  s.median_solve_ms = solve[solve.size() / 2];
  s.p99_solve_ms = solve[(99 * solve.size() + 99) / 100 - 1];  // rank ceil(0.99 n)
  s.mean_iterations = iterations / static_cast<double>(run.samples.size());
  if (run.samples.size() > 1) {
    s.torque_change_rms =
        std::sqrt(change2 / static_cast<double>((run.samples.size() - 1) *
                                                run.samples.front().torque.size()));
  }
  return s;
}

template <int A>
FeedbackErrors feedback_errors(const BasicClosedLoopRun<A>& run) {
  FeedbackErrors e;
  if (run.samples.empty()) return e;
  double height2 = 0.0, velocity2 = 0.0, tilt2 = 0.0;
  const BasicState<A>* truth = &run.initial;  // at the first period's start
  for (const BasicClosedLoopSample<A>& sample : run.samples) {
    const BasicState<A>& fed = sample.feedback;
    const Eigen::Quaterniond q(truth->q[3], truth->q[4], truth->q[5], truth->q[6]);
    const Eigen::Quaterniond q_fed(fed.q[3], fed.q[4], fed.q[5], fed.q[6]);
    height2 += std::pow(fed.q[2] - truth->q[2], 2);
    // v's linear part is in torso coordinates (model.hpp).
    const Vector3 velocity = q * truth->v.template segment<3>(3);
    const Vector3 velocity_fed = q_fed * fed.v.template segment<3>(3);
    velocity2 += (velocity_fed - velocity).template head<2>().squaredNorm();
    const double cosine = (q * Vector3::UnitZ()).dot(q_fed * Vector3::UnitZ());
    tilt2 += std::pow(std::acos(std::clamp(cosine, -1.0, 1.0)), 2);
    e.degraded += sample.trust == estimation::Trust::kDegraded ? 1 : 0;
    truth = &sample.state;
  }
  const double n = static_cast<double>(run.samples.size());
  e.height_rms = std::sqrt(height2 / n);
  e.horizontal_velocity_rms = std::sqrt(velocity2 / n);
  e.tilt_rms = std::sqrt(tilt2 / n);
  return e;
}

template ClosedLoopRun run_closed_loop<0>(const Motion&, const ClosedLoopConfig&);
template ArmClosedLoopRun run_closed_loop<1>(const Motion&, const ClosedLoopConfig&);
template ClosedLoopSummary summarise(const ClosedLoopRun&);
template ClosedLoopSummary summarise(const ArmClosedLoopRun&);
template FeedbackErrors feedback_errors(const ClosedLoopRun&);
template FeedbackErrors feedback_errors(const ArmClosedLoopRun&);

}  // namespace hmpc::humanoid
