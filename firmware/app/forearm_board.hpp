// The forearm actuator board's application on the board runtime (board_runtime.hpp: modes,
// watchdogs, host clock, outbox): the two-stage MPC in run, the hold PID, the forearm's frames,
// independent of the board it runs on. Board support (firmware/boards/*) feeds it received
// frames and sensor readings, calls tick() at 1 kHz and run_mpc() when mpc_due(), applies
// outputs() and transmits what pop_frame() yields.
//
//   hold: PID with load-velocity feedback on the angle, around the gravity feedforward
//   run: the MPC strategy the host selects (thesis Table 3.1)
//   run --hold cmd, or repeated failed/overrun MPC steps--> hold (run then refused until the
//   kSolverFallback bit is cleared by an idle command with clear_faults)
//   hold or run --joint beyond its software limit--> fault
//
// Only the solver deadline reads a wall clock, and only when one is given.
//
// Nothing here allocates; the object holds every strategy's workspace (~60 kB for double):
// give it static storage.
#pragma once

#include <cmath>
#include <cstdint>
#include <type_traits>

#include "board_runtime.hpp"
#include "hmpc/control/load_velocity_feedback_pid.hpp"
#include "hmpc/models/forearm_disturbance.hpp"
#include "hmpc/models/forearm_mpc.hpp"
#include "hmpc/mpc/compute_model.hpp"
#include "hmpc/protocol/forearm_protocol.hpp"

namespace hmpc::firmware {

namespace proto = hmpc::forearm_protocol;

// SolveTelemetry carries hmpc::SolveStatus values as they are.
static_assert(int(proto::SolveStatusCode::kConverged) == int(SolveStatus::kConverged) &&
                  int(proto::SolveStatusCode::kIterationCap) == int(SolveStatus::kIterationCap) &&
                  int(proto::SolveStatusCode::kBudgetExhausted) ==
                      int(SolveStatus::kBudgetExhausted) &&
                  int(proto::SolveStatusCode::kStalled) == int(SolveStatus::kStalled) &&
                  int(proto::SolveStatusCode::kInvalidInput) == int(SolveStatus::kInvalidInput) &&
                  int(proto::SolveStatusCode::kNumericalFailure) ==
                      int(SolveStatus::kNumericalFailure),
              "protocol solve status codes must match hmpc::SolveStatus");

// The forearm protocol as the board runtime uses it.
struct ForearmBoardProtocol {
  using Description = proto::Description;
  using ModeCommand = proto::ModeCommand;
  using Sync = proto::Sync;
  using BoardMode = proto::BoardMode;
  using RequestedMode = proto::RequestedMode;
  using FaultBits = std::uint8_t;
  static constexpr FaultBits kHeartbeatTimeoutFault = proto::fault::kHeartbeatTimeout;
  static constexpr FaultBits kSensorTimeoutFault = proto::fault::kSensorTimeout;
};

template <typename Scalar>
struct BoardConfig {
  proto::NodeId node = 0;
  // Two missed ModeCommand periods (the protocol's 10 ms) trip the watchdog.
  int heartbeat_timeout_ticks = 2 * proto::frame_spec(proto::FrameType::kModeCommand).cycle_time_ms;
  // Sensors arrive every 1 ms; five missed readings are a sensor fault.
  int sensor_timeout_ticks = 5;
  // Consecutive failed or overrun MPC steps before falling back to hold.
  int max_consecutive_bad_steps = 3;
  // Deadline of one MPC step inside its 4 ms period (leaves time for I/O and telemetry).
  double mpc_budget_s = 0.0035;
  // Software joint limits (rad): beyond them the board faults into its safe state.
  Scalar theta_min = forearm::Parameters<Scalar>{}.soft_limit_lower;
  Scalar theta_max = forearm::Parameters<Scalar>{}.soft_limit_upper;
  // Safe outputs (idle, fault): valve vented to atmosphere (0 V), motor off. The arm then
  // rests on its mechanical stop; a board with a holding brake would hold instead.
  Scalar safe_v_p = Scalar(0), safe_v_m = Scalar(0);
  // Hold mode: position PID with load-velocity feedback on the valve, on top of the gravity
  // feedforward k_vp P_eq(theta). Gains checked stable on the model from -0.5 to 1 rad with
  // the valve's 150 ms lag (worst deviation 0.019 rad under a 0.2 N·m load step); the
  // derivative supplies the damping. The load-velocity gain is 0 because the model's pressure
  // dynamics have no flow-velocity coupling; a real valve's is set over the Gains frame.
  typename LoadVelocityFeedbackPid<Scalar>::Config hold_pid = [] {
    typename LoadVelocityFeedbackPid<Scalar>::Config c;
    c.kp = Scalar(10);
    c.ki = Scalar(10);
    c.kd = Scalar(2);
    c.derivative_time_constant = Scalar(0.01);
    c.integral_limit = Scalar(2);
    c.output_min = Scalar(-5);
    c.output_max = Scalar(5);
    c.load_velocity_gain = Scalar(0);
    c.safe_output = Scalar(0);
    return c;
  }();
  forearm::Parameters<Scalar> model{};
  forearm::CostWeights<Scalar> weights{};
  // Offset-free MPC (forearm_problems.hpp OffsetFree): the disturbance observer runs in hold
  // and run, and every strategy's model carries its estimate. Off: the thesis's method.
  bool offset_free = false;
  typename forearm::DisturbanceObserver<Scalar>::Config disturbance_observer{};
  // The Two-stage with the terminal rate term in both stages (forearm::kTwoStageTerminalRate).
  // Off: the thesis's cost.
  bool two_stage_terminal_rate = false;
  // HIL lock-step only: the processor this board emulates. Each MPC step is charged the
  // compute time this model predicts from the solver's work (mpc/compute_model.hpp): its
  // output acts only that many ticks later, the previous output holding meanwhile, and no new
  // step starts before it is done, as on the thesis's real board, which had no solver
  // deadline (Sec. 3.4.2: a late solve delays the control). A step charged over
  // mpc_budget_s counts as an overrun but, unlike a real deadline miss, leads to no fallback:
  // the HIL compares strategies as the thesis ran them. nullptr: no emulation.
  const ComputeCostModel* emulated_target = nullptr;
  // Test hook for the HIL's fault tests: from this tick on, every MPC step ends in a numerical
  // failure, as a solve meeting non-finite numbers would, and its plan is not used. 0: never.
  std::uint32_t solver_failure_from_tick = 0;
};

struct BoardCounters {
  std::uint32_t watchdog_trips = 0;
  std::uint32_t sensor_timeouts = 0;
  std::uint32_t solver_failures = 0;   // unusable plans (previous plan used instead)
  std::uint32_t overruns = 0;          // MPC steps that hit their deadline
  std::uint32_t fallbacks = 0;         // run -> hold after repeated bad steps
  std::uint32_t refused_commands = 0;  // valid frames asking for a transition not allowed now
  std::uint32_t mpc_steps = 0;
  std::uint32_t syncs = 0;                // valid HIL lock-step Sync frames
  std::uint32_t cost_weight_updates = 0;  // valid CostWeights frames adopted
};

template <typename Scalar>
struct Outputs {
  Scalar v_p = 0;  // V, PAM valve
  Scalar v_m = 0;  // V, motor
};

template <typename Scalar>
class ForearmBoard : public BoardRuntime<ForearmBoard<Scalar>, ForearmBoardProtocol> {
  using Runtime = BoardRuntime<ForearmBoard<Scalar>, ForearmBoardProtocol>;
  friend Runtime;

 public:
  using Config = BoardConfig<Scalar>;
  using Strategies = forearm::Strategies<Scalar>;
  using State = Eigen::Matrix<Scalar, 3, 1>;
  using Control = Eigen::Matrix<Scalar, 2, 1>;
  using Pid = LoadVelocityFeedbackPid<Scalar>;
  using Observer = forearm::DisturbanceObserver<Scalar>;
  // Seconds from an arbitrary origin, for the solver deadline; nullptr: no deadline (HIL
  // lock-step, where the simulator charges compute time itself).
  using WallClock = double (*)();

  static constexpr int kTicksPerMpcStep = 4;  // 1 kHz I/O, 4 ms MPC (Sec. 3.3)
  // The telemetry of each MPC step goes at the period the protocol states for it.
  static_assert(
      proto::frame_spec(proto::FrameType::kSolveTelemetry).cycle_time_ms == kTicksPerMpcStep &&
          proto::frame_spec(proto::FrameType::kJointState).cycle_time_ms == kTicksPerMpcStep &&
          proto::frame_spec(proto::FrameType::kActuatorOutputs).cycle_time_ms == kTicksPerMpcStep,
      "the protocol's telemetry periods are the MPC's");
  static constexpr Scalar kTick = Scalar(0.001);

  // The strategies point at target_: the board must stay where it was built.
  ForearmBoard(const ForearmBoard&) = delete;
  ForearmBoard& operator=(const ForearmBoard&) = delete;

  explicit ForearmBoard(const Config& config, WallClock clock = nullptr)
      : Runtime(RuntimeConfig{config.node, config.heartbeat_timeout_ticks,
                              config.sensor_timeout_ticks}),
        config_(config), clock_(clock), fine4_(Strategies::fine4(setup())),
        fine8_(Strategies::fine8(setup())), coarse20_(Strategies::coarse20(setup())),
        coarse40_(Strategies::coarse40(setup())), two_stage_(Strategies::two_stage(setup())),
        pam_only_(Strategies::pam_only(setup())) {
    target_.set_constant(Scalar(0));
  }

  // ---- inputs ------------------------------------------------------------------------

  using Runtime::on_frame;
  using Runtime::tick;

  // A sensor reading (from the bus in HIL, from the board's own ADC/encoder on hardware).
  // Pressure in MPa as on the bus; the model works in bar.
  void on_measurement(float theta, float theta_dot, float pressure_mpa) {
    if (!std::isfinite(theta) || !std::isfinite(theta_dot) || !std::isfinite(pressure_mpa))
      return;  // never acted on; the sensor watchdog notices the silence
    x_ << Scalar(theta), Scalar(theta_dot), Scalar(10) * Scalar(pressure_mpa);
    this->note_sensor();
  }

  // ---- scheduling --------------------------------------------------------------------

  bool mpc_due() const { return mpc_due_; }

  // The 4 ms MPC step (Table 3.1 strategy selected by the host). Runs the solver against the
  // deadline, keeps the previous plan (time-shifted by the MPC) on a failed or overrun step,
  // and falls back to hold after repeated bad steps.
  void run_mpc() {
    mpc_due_ = false;
    if (this->mode() != proto::BoardMode::kRun) return;
    if (weights_changed_) {
      for_each_strategy([&](auto& mpc) { forearm::set_weights(mpc, config_.weights); });
      weights_changed_ = false;
    }
    const double start = clock_ ? clock_() : 0.0;
    const double deadline = start + config_.mpc_budget_s;
    const auto stop = [this, deadline] { return clock_ && clock_() > deadline; };
    if (needs_initialization_) {
      // Algorithm 1, line 1: the initial inputs, optimised before the first online step. With
      // a clock, within this step's deadline, so that entering run never stalls the board's
      // ticks (the online solves go on improving them); in lock-step HIL whole and uncharged,
      // as the thesis's offline optimisation. The previous outputs stay applied meanwhile.
      with_strategy([&](auto& mpc) {
        forearm::set_time(mpc, host_time());
        forearm::set_offset_free(mpc, offset_free());
        mpc.initialize(x_, forearm::kIterationCap, stop);
      });
      needs_initialization_ = false;
    }
    SolveStatus status = SolveStatus::kConverged;
    Control plan = plan_;
    with_strategy([&](auto& mpc) {
      forearm::set_time(mpc, host_time());
      forearm::set_offset_free(mpc, offset_free());
      plan = mpc.update(x_, stop);
      usable_ = mpc.last_plan_usable();
      last_work_ = mpc.last_work();
      last_iterations_ = mpc.last_iterations();
      record_layers(mpc, status);
    });
    if (config_.solver_failure_from_tick != 0 &&
        this->ticks() >= config_.solver_failure_from_tick) {
      usable_ = false;
      status = SolveStatus::kNumericalFailure;
      plan = plan_;
    }
    ++counters_.mpc_steps;
    const ComputeCostModel* target = config_.emulated_target;
    double elapsed = 0.0;
    bool overrun = false;
    if (target) {
      elapsed = target->seconds(last_work_);
      overrun = elapsed > config_.mpc_budget_s;
      // Ready after the charged time, at the first tick not earlier; within one tick it is
      // as soon as on a real board, whose solve runs between ticks.
      const double ticks_late = std::ceil(elapsed / double(kTick));
      plan_ready_tick_ = this->ticks() + std::uint32_t(ticks_late < 1.0 ? 1.0 : ticks_late);
      pending_plan_ = plan;
      solve_pending_ = true;
    } else {
      elapsed = clock_ ? clock_() - start : 0.0;
      overrun = clock_ && elapsed > config_.mpc_budget_s;
      plan_ = plan;
    }
    counters_.solver_failures += usable_ ? 0 : 1;
    counters_.overruns += overrun ? 1 : 0;
    const bool counts_as_bad = !usable_ || (overrun && !target);
    consecutive_bad_steps_ = counts_as_bad ? consecutive_bad_steps_ + 1 : 0;
    telemetry_.status = static_cast<proto::SolveStatusCode>(status);
    telemetry_.solve_time_us =
        static_cast<std::uint16_t>(elapsed * 1e6 < 65535.0 ? elapsed * 1e6 : 65535.0);
    if (consecutive_bad_steps_ >= config_.max_consecutive_bad_steps) {
      ++counters_.fallbacks;
      this->set_fault_bits(proto::fault::kSolverFallback);
      enter_hold();
      this->set_mode(proto::BoardMode::kHold);
    }
  }

  // ---- outputs -----------------------------------------------------------------------

  const Outputs<Scalar>& outputs() const { return outputs_; }
  proto::Strategy strategy() const { return strategy_; }
  BoardCounters counters() const {
    BoardCounters c = counters_;
    const RuntimeCounters& r = this->runtime_counters();
    c.watchdog_trips = r.watchdog_trips;
    c.sensor_timeouts = r.sensor_timeouts;
    c.refused_commands = r.refused_commands;
    c.syncs = r.syncs;
    return c;
  }
  const Config& config() const { return config_; }
  // The weights a strategy's MPC solves with: its problem's, and for the two-stage MPC its
  // fast subsystem's (the upper problem's are set with them).
  const forearm::CostWeights<Scalar>& solver_weights(proto::Strategy s) const {
    switch (s) {
      case proto::Strategy::kFine4ms: return fine4_.problem().weights();
      case proto::Strategy::kFine8ms: return fine8_.problem().weights();
      case proto::Strategy::kCoarse20ms: return coarse20_.problem().weights();
      case proto::Strategy::kCoarse40ms: return coarse40_.problem().weights();
      case proto::Strategy::kTwoStage: return two_stage_.fast_subsystem().weights();
      case proto::Strategy::kPamOnly: return pam_only_.problem().weights();
    }
    return config_.weights;
  }
  // The last MPC step, as an MPC reports it (for telemetry and compute accounting).
  int last_iterations() const { return last_iterations_; }
  // The disturbance observer's estimate, N·m (0 outside hold and run).
  Scalar disturbance_estimate() const { return disturbance_.estimate; }
  bool last_plan_usable() const { return usable_; }
  LayerWork last_work() const { return last_work_; }

 private:
  typename Strategies::Setup setup() const {
    typename Strategies::Setup s;
    s.parameters = config_.model;
    s.weights = config_.weights;
    s.target = &target_;
    if (config_.two_stage_terminal_rate) s.two_stage_terminal_rate = forearm::kTwoStageTerminalRate;
    return s;
  }

  template <class F>
  void with_strategy(F&& f) {
    switch (strategy_) {
      case proto::Strategy::kFine4ms: f(fine4_); break;
      case proto::Strategy::kFine8ms: f(fine8_); break;
      case proto::Strategy::kCoarse20ms: f(coarse20_); break;
      case proto::Strategy::kCoarse40ms: f(coarse40_); break;
      case proto::Strategy::kTwoStage: f(two_stage_); break;
      case proto::Strategy::kPamOnly: f(pam_only_); break;
    }
  }
  // Iterations per stage and the status the telemetry reports: the fast stage's unless the
  // coarse stage's plan was unusable.
  template <class Mpc>
  void record_layers(const Mpc& mpc, SolveStatus& status) {
    if constexpr (std::is_same_v<Mpc, typename Strategies::TwoStage>) {
      const auto& upper = mpc.last_upper_result();
      const auto& fast = mpc.last_fast_result();
      telemetry_.coarse_iterations = saturate_u8(upper.iterations);
      telemetry_.fine_iterations = saturate_u8(fast.iterations);
      status = plan_is_usable(upper.status) ? fast.status : upper.status;
    } else {
      telemetry_.coarse_iterations = saturate_u8(mpc.last_result().iterations);
      telemetry_.fine_iterations = 0;
      status = mpc.last_result().status;
    }
  }
  static std::uint8_t saturate_u8(int v) {
    return static_cast<std::uint8_t>(v < 0 ? 0 : (v > 255 ? 255 : v));
  }

  // The host's trajectory clock now, s.
  Scalar host_time() const { return Scalar(this->host_time_us()) * Scalar(1e-6); }

  // ---- runtime hooks -------------------------------------------------------------------

  void on_application_frame(proto::FrameType type, const proto::Frame& frame) {
    switch (type) {
      case proto::FrameType::kSensor: {
        proto::SensorSample s;
        if (this->receive(frame, s)) on_measurement(s.theta, s.theta_dot, s.pressure);
        break;
      }
      case proto::FrameType::kTrajectorySample: {
        proto::TrajectorySample s;
        if (this->receive(frame, s)) on_trajectory_sample(s);
        break;
      }
      case proto::FrameType::kGains: {
        proto::Gains g;
        if (this->receive(frame, g)) on_gains(g);
        break;
      }
      case proto::FrameType::kCostWeights: {
        proto::CostWeights w;
        if (this->receive(frame, w)) on_cost_weights(w);
        break;
      }
      default:  // frames this board sends, not receives
        break;
    }
  }

  void on_heartbeat(const proto::ModeCommand&) {}
  bool may_enter_hold() const { return true; }
  bool may_enter_run(const proto::ModeCommand&) const {
    return !(this->faults() & proto::fault::kSolverFallback);
  }
  bool run_request_changes(const proto::ModeCommand& m) const { return m.strategy != strategy_; }
  void enter_run(const proto::ModeCommand& m) { enter_run(m.strategy); }

  void control_step(proto::BoardMode mode) {
    if (solve_pending_ && this->ticks() >= plan_ready_tick_) {
      plan_ = pending_plan_;
      solve_pending_ = false;
    }
    // The observer sees the arm while something holds it (the vented arm on its stop is not a
    // disturbance to learn), with the motor voltage of the last tick.
    if (mode == proto::BoardMode::kHold || mode == proto::BoardMode::kRun) {
      Observer::update(config_.model, config_.disturbance_observer, disturbance_, x_(0), x_(1),
                       x_(2), outputs_.v_m, kTick);
    } else {
      Observer::reset(disturbance_);
    }
    switch (mode) {
      case proto::BoardMode::kHold: hold_step(); break;
      case proto::BoardMode::kRun: apply_plan(); break;
      default: apply_safe_outputs(); break;
    }
    mpc_due_ =
        mode == proto::BoardMode::kRun && this->ticks() % kTicksPerMpcStep == 0 && !solve_pending_;
  }

  void apply_safe_outputs() { outputs_ = {config_.safe_v_p, config_.safe_v_m}; }

  void forget_sensor_counters() { this->forget_counter(proto::FrameType::kSensor); }

  std::uint8_t application_faults() const {
    const auto mode = this->mode();
    const bool beyond = x_(0) < config_.theta_min || x_(0) > config_.theta_max;
    return this->have_sensor() && beyond && mode != proto::BoardMode::kFault &&
                   mode != proto::BoardMode::kIdle
               ? proto::fault::kJointLimit
               : std::uint8_t(0);
  }

  // ---- the forearm ---------------------------------------------------------------------

  void on_trajectory_sample(const proto::TrajectorySample& s) {
    target_.push_sample(Scalar(s.time_us) * Scalar(1e-6), Scalar(s.theta_d));
  }

  void on_gains(const proto::Gains& g) {
    auto c = config_.hold_pid;
    c.kp = Scalar(g.kp);
    c.ki = Scalar(g.ki);
    c.kd = Scalar(g.kd);
    c.load_velocity_gain = Scalar(g.k_lv);
    if (Pid::config_valid(c)) config_.hold_pid = c;
  }

  // Adopted by every strategy before the next MPC step (a CAN handler does not touch the MPCs,
  // which may be mid-solve on a board that solves outside its interrupt). The codec has
  // checked each value against its range; 0 keeps the present weight.
  void on_cost_weights(const proto::CostWeights& w) {
    const auto adopt = [](Scalar& weight, float value) {
      if (value > 0) weight = Scalar(value);
    };
    adopt(config_.weights.w_theta, w.w_theta);
    adopt(config_.weights.w_P, w.w_p);
    adopt(config_.weights.w_tau, w.w_tau);
    adopt(config_.weights.w_v, w.w_v);
    weights_changed_ = true;
    ++counters_.cost_weight_updates;
  }

  template <class F>
  void for_each_strategy(F&& f) {
    f(fine4_);
    f(fine8_);
    f(coarse20_);
    f(coarse40_);
    f(two_stage_);
    f(pam_only_);
  }

  void enter_hold() {
    hold_angle_ = x_(0);
    Pid::reset(pid_state_);
  }

  forearm::OffsetFree<Scalar> offset_free() const {
    return {config_.offset_free, disturbance_.estimate};
  }

  // Entering run is cheap here (it may happen in a CAN handler); the strategy's offline
  // initialisation runs in the first MPC step.
  void enter_run(proto::Strategy strategy) {
    strategy_ = strategy;
    consecutive_bad_steps_ = 0;
    needs_initialization_ = true;
    if (target_.sample_count() == 0) target_.set_constant(x_(0));  // hold where it is
    plan_ = Control(Scalar(0), config_.model.k_vp * x_(2));
    solve_pending_ = false;
  }

  // Hold: PID on theta with load-velocity feedback, around the gravity feedforward.
  void hold_step() {
    const auto& p = config_.model;
    const Scalar feedforward = p.k_vp * forearm::equilibrium_pressure(p, hold_angle_);
    const Scalar correction =
        Pid::update(config_.hold_pid, pid_state_, hold_angle_, x_(0), x_(1), kTick);
    outputs_ = {clamp(feedforward + correction, p.v_p_min, p.v_p_max), Scalar(0)};
  }

  void apply_plan() {
    const auto& p = config_.model;
    outputs_ = {clamp(plan_(1), p.v_p_min, p.v_p_max), clamp(plan_(0), p.v_m_min, p.v_m_max)};
  }

  static Scalar clamp(Scalar v, Scalar lo, Scalar hi) { return v < lo ? lo : (v > hi ? hi : v); }

  void send_telemetry() {
    const std::uint32_t ticks = this->ticks();
    // To the actuators (the plant, in HIL) every tick.
    this->send(proto::ActuatorCommand{float(outputs_.v_p), float(outputs_.v_m), 0});
    if (ticks % kTicksPerMpcStep == 0) {
      const auto& p = config_.model;
      this->send(proto::JointState{float(x_(0)), float(x_(1)), float(x_(2) / Scalar(10)), 0});
      const Scalar tau_p = forearm::pam_torque(p, x_(2), x_(0)).tau;
      this->send(proto::ActuatorOutputs{float(outputs_.v_p), float(outputs_.v_m),
                                        float(clamp(tau_p, Scalar(-30), Scalar(30))),
                                        float(p.motor_gain * outputs_.v_m), 0});
      telemetry_.tracking_error =
          float(clamp(target_.angle(host_time()) - x_(0), Scalar(-6.28), Scalar(6.28)));
      if (this->mode() != proto::BoardMode::kRun) {
        telemetry_.status = proto::SolveStatusCode::kNoSolve;
      }
      this->send(telemetry_);
    }
    if (ticks % proto::frame_spec(proto::FrameType::kBoardStatus).cycle_time_ms == 0) {
      proto::BoardStatus s;
      s.mode = this->mode();
      s.faults = this->faults();
      s.strategy = strategy_;
      s.rejected_frames = this->rejected_frames_mod_256();
      s.watchdog_trips = std::uint8_t(this->runtime_counters().watchdog_trips);
      s.solver_failures = std::uint8_t(counters_.solver_failures);
      s.overruns = std::uint8_t(counters_.overruns);
      this->send(s);
    }
  }

  Config config_;
  WallClock clock_;
  forearm::TargetTrajectory<Scalar> target_;
  typename Strategies::Fine4 fine4_;
  typename Strategies::Fine8 fine8_;
  typename Strategies::Coarse20 coarse20_;
  typename Strategies::Coarse40 coarse40_;
  typename Strategies::TwoStage two_stage_;
  typename Strategies::PamOnly pam_only_;

  proto::Strategy strategy_ = proto::Strategy::kTwoStage;
  BoardCounters counters_{};  // the application's; counters() adds the runtime's
  State x_ = State::Zero();
  Scalar hold_angle_ = 0;
  typename Pid::State pid_state_{};
  typename Observer::State disturbance_{};
  Control plan_ = Control::Zero();
  Control pending_plan_ = Control::Zero();  // emulated target: computed, not yet ready
  bool solve_pending_ = false;
  std::uint32_t plan_ready_tick_ = 0;
  bool usable_ = true;
  int last_iterations_ = 0;
  LayerWork last_work_{};
  bool mpc_due_ = false;
  bool needs_initialization_ = false;
  bool weights_changed_ = false;
  int consecutive_bad_steps_ = 0;
  proto::SolveTelemetry telemetry_{};
  Outputs<Scalar> outputs_{};
};

}  // namespace hmpc::firmware
