#include "hmpc/host/humanoid_host.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "hmpc/humanoid/problem.hpp"
#include "hmpc/humanoid/thread_pool.hpp"
#include "hmpc/mpc/deadline_stop.hpp"

namespace hmpc::host {

namespace hm = hmpc::humanoid;
using Clock = std::chrono::steady_clock;

const char* name_of(HostPhase phase) {
  switch (phase) {
    case HostPhase::kWaiting: return "waiting";
    case HostPhase::kZeroing: return "zeroing";
    case HostPhase::kHolding: return "holding";
    case HostPhase::kMpc: return "mpc";
    case HostPhase::kSafe: return "safe";
  }
  return "?";
}

// Fitted by least squares to the 2857 untruncated solves of humanoid_mpc_bench --real-robot
// --linearisation chain-rule (holding the hip, squatting, motion I, the slow squat; 2 threads,
// this machine), which prints the fit and this model's error beside the measured solves: median
// 2.2 %, 90th percentile 4.6 %. The intercept is a fit, not a cost: a solve always has steps.
const ComputeCostModel kHostComputeModel = [] {
  ComputeCostModel m;
  m.instructions_per_update = -1.062e-4;   // s
  m.upper.per_rollout_step = 7.944e-6;     // s per coarse step simulated
  m.upper.per_derivative_step = 8.587e-5;  // s per coarse step linearised, and its backward step
  m.fast.per_rollout_step = 1.544e-5;
  m.fast.per_derivative_step = 3.601e-5;
  m.clock_hz = 1;  // the model's "instructions" are seconds
  return m;
}();

namespace {

// Failed solves in a row after which the boards hold their posture (the forearm board's rule:
// the previous plan bridges two, a third means the solver cannot be trusted).
constexpr int kFailedSolvesBeforeHold = 3;
// Coarse-Fast's upper layer's share of the period when truncating (closed_loop_simulation.hpp's
// kUpperShare: the same split of the same solver's work).
constexpr double kUpperShare = 0.85;

std::uint32_t ticks_of(double seconds) { return std::uint32_t(std::lround(seconds * 1e3)); }

}  // namespace

// A plan: the composed torques of the lower layer's fine steps (Eq. 2.36), from `tick` on.
struct Plan {
  std::array<hm::JointVector, hm::kFastHorizon> torque{};
  std::uint32_t tick = 0;
  bool valid = false;
};

struct HumanoidHost::Mpc {
  hm::ThreadPool pool;
  std::unique_ptr<hm::CoarseFast> solver;
  IterationTime<Clock> upper_time, fast_time;
  Plan current, pending;
  std::uint32_t pending_effective = 0;
  bool running = false;  // the boards asked for run

  Mpc(int threads, const hm::Motion& motion, const hm::BasicState<0>& start,
      const hm::ProblemConfig& problem, const hm::CoarseFastTiming& timing)
      : pool(threads), solver(hm::make_coarse_fast<0>(motion, start, threads > 1 ? &pool : nullptr,
                                                      problem, 0, timing)) {}
};

HumanoidHost::HumanoidHost(const HumanoidHostConfig& config, const hm::Motion& task)
    : config_(config), master_(config.master), task_(task), motion_paused_(config.motion_paused) {
  if (task.reach.active) {
    throw std::invalid_argument("HumanoidHost: the motion needs the robot with an arm");
  }
  config.timing.check("HumanoidHost");
  if (!(config.rest_seconds > 0) || config.rest_seconds >= config.hold_seconds) {
    throw std::invalid_argument("HumanoidHost: the estimator's rest must be within the hold");
  }
  // Sized for the session's solves up front: logging them never allocates in the loop.
  solves_.reserve(100000);
  master_.request(jp::RequestedMode::kIdle, true);
}

HumanoidHost::~HumanoidHost() = default;

double HumanoidHost::motion_time(std::uint32_t tick) const {
  if (motion_paused_) return 0.0;
  return tick >= motion_start_tick_ ? 1e-3 * double(tick - motion_start_tick_) : 0.0;
}

void HumanoidHost::on_frame(const jp::Frame& frame, std::uint32_t tick) {
  const Heard heard = master_.on_frame(frame, tick);
  if (heard != Heard::kImuGyro && heard != Heard::kImuAccel) return;
  const RobotReadings& r = master_.readings();
  // A period's reading is whole when its gyroscope and accelerometer frames have both come.
  if (r.gyro_tick != r.accel_tick || (have_imu_ && r.gyro_tick == last_imu_tick_)) return;
  estimate(tick);
}

void HumanoidHost::estimate(std::uint32_t tick) {
  const RobotReadings& r = master_.readings();
  const double dt = have_imu_ ? 1e-3 * double(tick - last_imu_tick_) : 0.006;
  have_imu_ = true;
  last_imu_tick_ = tick;
  if (phase_ != HostPhase::kHolding && phase_ != HostPhase::kMpc) return;
  hm::SensorReadings reading;
  reading.imu.angular_velocity = r.angular_velocity;
  reading.imu.specific_force = r.specific_force;
  reading.angles = r.angle;
  reading.rates = r.rate;
  if (!estimator_started_) {
    estimator_.rest(reading, dt);
    if (tick - phase_tick_ >= ticks_of(config_.rest_seconds)) {
      estimator_.start();
      estimator_started_ = true;
    }
    return;
  }
  estimator_.update(reading, dt);
}

void HumanoidHost::estop() {
  master_.estop();
  to_safe("E-stop", false);
}

void HumanoidHost::hold() {
  held_ = true;
  run_asked_ = false;
  if (phase_ != HostPhase::kMpc) return;
  master_.stop_references();
  master_.request(jp::RequestedMode::kHold);
  phase_ = HostPhase::kHolding;
  phase_tick_ = last_tick_;
}

void HumanoidHost::run() {
  held_ = false;
  run_asked_ = phase_ == HostPhase::kHolding;
}

void HumanoidHost::resume_motion() {
  if (!motion_paused_) return;
  motion_paused_ = false;
  motion_start_tick_ = last_tick_;
}

void HumanoidHost::set_task(const HipTask& task) {
  hm::Phase phase;
  phase.height = task.height;
  if (task.squat) {
    phase.squat_depth = task.depth;
    phase.squat_period = task.period;
  }
  task_.phases[0] = phase;
  task_.phase_count = 1;
  task_changed_ = true;
  motion_paused_ = false;
  motion_start_tick_ = last_tick_;
}

void HumanoidHost::set_weights(const hm::CostWeights& weights) {
  task_.weights = weights;
  task_changed_ = true;
}

void HumanoidHost::to_safe(const char* reason, bool hold_posture) {
  phase_ = HostPhase::kSafe;
  safe_tick_ = last_tick_;
  reason_ = reason;
  master_.stop_references();
  master_.request(hold_posture ? jp::RequestedMode::kHold : jp::RequestedMode::kIdle);
}

hm::JointVector HumanoidHost::plan_torque(std::uint32_t tick) const {
  const Plan& plan = mpc_->current;
  const std::uint32_t fine = ticks_of(config_.timing.fast_step);
  const std::uint32_t j = std::min<std::uint32_t>((tick - plan.tick) / fine, hm::kFastHorizon - 1);
  return plan.torque[j];
}

void HumanoidHost::step(std::uint32_t tick) {
  last_tick_ = tick;
  const std::uint32_t in_phase = tick - phase_tick_;
  const auto enter = [&](HostPhase next) {
    phase_ = next;
    phase_tick_ = tick;
  };
  const auto timed_out = [&] { return in_phase > ticks_of(config_.bring_up_timeout_s); };
  // Once the robot stands on its boards: whatever of it falls silent or restarts, the boards
  // still heard hold their posture (a silent board's valves are centred by its own watchdog
  // or its valve driver). Before a board's fault, which has every board go idle: a restarted
  // board faults for the hold it is asked, and the others should still hold.
  if (phase_ == HostPhase::kHolding || phase_ == HostPhase::kMpc) {
    if (!master_.boards_present()) {
      to_safe("a leg board fell silent", true);
      return;
    }
    if (master_.any_restarted()) {
      to_safe("a leg board restarted: its encoders are not zeroed", true);
      return;
    }
    if (!master_.readings().imu_heard) {
      to_safe("the IMU fell silent", true);
      return;
    }
  }
  if (phase_ != HostPhase::kSafe && phase_ != HostPhase::kWaiting && master_.any_fault()) {
    to_safe("a board reports a fault", false);
    return;
  }
  switch (phase_) {
    case HostPhase::kWaiting:
      if (master_.boards_present() && master_.readings().imu_heard &&
          master_.all_in(jp::BoardMode::kIdle)) {
        master_.request(jp::RequestedMode::kIdle, false, true);
        enter(HostPhase::kZeroing);
      } else if (timed_out()) {
        bring_up_failed_ = true;
        reason_ = !master_.readings().imu_heard ? "the IMU was not heard"
                  : !master_.boards_present()   ? "not every leg board was heard with protocol "
                                                  "version 1 and four joints"
                                                : "a board did not come to idle";
        enter(HostPhase::kSafe);
      } else if (in_phase % 100 == 0) {
        master_.request(jp::RequestedMode::kIdle, true);
      }
      break;
    case HostPhase::kZeroing:
      if (master_.all_zeroed()) {
        master_.request(jp::RequestedMode::kHold);
        enter(HostPhase::kHolding);
      } else if (timed_out()) {
        bring_up_failed_ = true;
        reason_ = "the encoders did not report zeroed";
        enter(HostPhase::kSafe);
      } else if (in_phase % 100 == 0) {
        // Again, in case the heartbeat that carried it was lost: zeroing in the zero posture
        // twice gives the same offsets.
        master_.request(jp::RequestedMode::kIdle, false, true);
      }
      break;
    case HostPhase::kHolding:
      if (estimator_started_ &&
          (run_asked_ || (!held_ && in_phase >= ticks_of(config_.hold_seconds)))) {
        mpc_ = std::make_unique<Mpc>(config_.threads, task_, estimator_.state(), config_.problem,
                                     config_.timing);
        task_changed_ = false;
        run_asked_ = false;
        mpc_start_tick_ = tick;
        if (!motion_paused_) motion_start_tick_ = tick;
        enter(HostPhase::kMpc);
        solve(tick);
      }
      break;
    case HostPhase::kMpc: {
      if (estimator_.filter().estimate().trust == estimation::Trust::kLost) {
        to_safe("the state estimate is lost", true);
        return;
      }
      Mpc& m = *mpc_;
      if (m.pending.valid && tick >= m.pending_effective) {
        m.current = m.pending;
        m.pending.valid = false;
      }
      if (m.current.valid) {
        master_.set_references(plan_torque(tick));
        if (!m.running) {
          // The references go out on this tick ahead of the heartbeat asking for run.
          master_.request(jp::RequestedMode::kRun);
          m.running = true;
        }
      }
      if ((tick - mpc_start_tick_) % ticks_of(config_.timing.upper_step) == 0 &&
          tick != mpc_start_tick_) {
        solve(tick);
      }
      break;
    }
    case HostPhase::kSafe: break;
  }
}

void HumanoidHost::solve(std::uint32_t tick) {
  Mpc& m = *mpc_;
  const hm::BasicState<0> x = solve_from_ ? *solve_from_ : estimator_.state();
  if (!x.q.allFinite() || !x.v.allFinite()) {
    to_safe("the state estimate is not finite", true);
    return;
  }
  auto& problem = m.solver->upper_problem();
  if (task_changed_) {
    problem.set_motion(task_);
    task_changed_ = false;
  }
  problem.set_start_time(motion_time(tick));
  if (m.current.valid) problem.set_applied_torque(plan_torque(tick));
  const Clock::time_point start = Clock::now();
  const Clock::time_point end =
      start + std::chrono::duration_cast<Clock::duration>(
                  std::chrono::duration<double>(config_.timing.upper_step));
  {
    DeadlineStop<Clock> upper(
        start + std::chrono::duration_cast<Clock::duration>(
                    std::chrono::duration<double>(kUpperShare * config_.timing.upper_step)),
        end, m.upper_time, config_.truncate);
    DeadlineStop<Clock> fast(end, end, m.fast_time, config_.truncate);
    m.solver->update(hm::to_vector(x), upper, fast);
  }
  SolveRecord record;
  record.tick = tick;
  record.estimate_tick = last_imu_tick_;
  record.wall_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  record.charged_ms = config_.solve_time == SolveTime::kWall
                          ? record.wall_ms
                          : 1e3 * kHostComputeModel.seconds(m.solver->last_work());
  record.upper_iterations = m.solver->last_upper_result().iterations;
  record.fast_iterations = m.solver->last_fast_result().iterations;
  record.motion_time = motion_time(tick);
  const bool hooked =
      config_.fail_solver_at_s >= 0 && 1e-3 * double(tick) >= config_.fail_solver_at_s;
  record.usable = m.solver->last_plan_usable() && !hooked;
  const std::uint32_t delay =
      std::max<std::uint32_t>(1, std::uint32_t(std::ceil(record.charged_ms)));
  record.effective_tick = tick + delay;
  if (solves_.size() < solves_.capacity()) solves_.push_back(record);
  if (!record.usable) {
    if (++failed_solves_ >= kFailedSolvesBeforeHold) to_safe("three failed solves in a row", true);
    return;
  }
  failed_solves_ = 0;
  largest_delay_ = std::max(largest_delay_, delay);
  for (int j = 0; j < hm::kFastHorizon; ++j)
    m.pending.torque[std::size_t(j)] = m.solver->planned_control(j);
  m.pending.tick = tick;
  m.pending.valid = true;
  m.pending_effective = record.effective_tick;
  const auto& upper = m.solver->upper_solver();
  for (int k = 0; k <= hm::kCoarseHorizon; ++k) plan_.states[std::size_t(k)] = upper.states()[k];
  for (int k = 0; k < hm::kCoarseHorizon; ++k) plan_.torques[std::size_t(k)] = upper.controls()[k];
  plan_.cost = m.solver->last_upper_result().cost;
  plan_.status = m.solver->last_upper_result().status;
  plan_.solve = record;
  ++plan_.sequence;
}

}  // namespace hmpc::host
