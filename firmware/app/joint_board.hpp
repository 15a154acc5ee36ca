// The hydraulic joint board's application on the board runtime (board_runtime.hpp: modes,
// watchdogs, host clock, outbox): 1 to 4 joints, each a torque loop (PID with load-velocity
// feedback, thesis Sec. 2.7.3) that turns a torque reference into a valve command, at a 6 ms
// control period (Sec. 2.7.3; 1 ms selectable) inside the runtime's 1 kHz ticks.
//
//   run:  the host's torque references, each range-checked against the joint's torque limit,
//         rate-limited and timed out
//   hold: a position PID per joint, on the posture held when hold was entered, gives the
//         torque references instead (a cascade on the same torque loop)
//   idle, fault: valves centred (the safe state, below)
//
// The safe state, for a standing hydraulic robot: the servo valves centred (u = 0). A
// closed-centre valve then traps the oil in both chambers, so each joint locks where it is,
// held by the oil's stiffness; the robot freezes in its posture rather than collapsing, which
// venting the chambers (the forearm's choice for its PAM) would make it do. Losing supply
// pressure, it sags slowly through the valves' leakage.
//
// A stale torque reference (none for reference_timeout_ticks in run) is never acted on with
// the old torque: the board holds the posture it has at that moment, locally, under its hold
// PID, and flags kStaleReference; it returns to run when references flow again and the host's
// heartbeat still asks for run. A lost heartbeat goes on to the safe state, as on every board.
//
// Also what a board on a real robot needs: encoder zeroing (offsets stored in the
// configuration, re-taken at the zero posture on the host's zero_encoders in idle, reported),
// soft joint limits and chamber pressure limits (both fault), and the latched E-stop, which
// acts in the tick it arrives and is released only by clear_faults in idle.
//
// Nothing here allocates. Scalar float on a Cortex-M4F, double elsewhere.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <utility>

#include "board_runtime.hpp"
#include "hmpc/control/hydraulic_torque_tuning.hpp"
#include "hmpc/control/load_velocity_feedback_pid.hpp"
#include "hmpc/models/hydraulic_joint.hpp"
#include "hmpc/protocol/joint_protocol.hpp"

namespace hmpc::firmware {

namespace joint_proto = hmpc::joint_protocol;

// The joint protocol as the board runtime uses it.
struct JointBoardProtocol {
  using Description = joint_proto::Description;
  using ModeCommand = joint_proto::ModeCommand;
  using Sync = joint_proto::Sync;
  using BoardMode = joint_proto::BoardMode;
  using RequestedMode = joint_proto::RequestedMode;
  using FaultBits = std::uint16_t;
  static constexpr FaultBits kHeartbeatTimeoutFault = joint_proto::fault::kHeartbeatTimeout;
  static constexpr FaultBits kSensorTimeoutFault = joint_proto::fault::kSensorTimeout;
};

// One joint's settings.
template <typename Scalar>
struct JointConfig {
  hydraulic::JointActuatorParameters<Scalar> actuator{};  // what the board believes of it
  Scalar encoder_offset = Scalar(0);  // rad, stored calibration: angle = reading - offset
  Scalar zero_posture = Scalar(0);    // rad, the angle at which zero_encoders is sent
  // Soft limits (rad), inside the cylinder's stroke (+-1.14 rad for the default actuator).
  Scalar theta_min = Scalar(-1.0), theta_max = Scalar(1.0);
  // N·m: references beyond it are refused; the default actuator's stall torque is 112.6 N·m
  // pushing and 68.6 N·m pulling, so 60 N·m stays within both with room to regulate.
  Scalar torque_limit = Scalar(60);
  // N·m/s: how fast the applied reference may change; 2 N·m per ms lets a reference cross
  // the whole +-60 N·m in 60 ms, and keeps a corrupt-but-valid jump from kicking the leg.
  Scalar torque_rate_limit = Scalar(2000);
  // Pa, gauge: a chamber above it (an external load beyond the actuator, a blocked return)
  // faults the board; 25 % above the 16 MPa supply.
  Scalar pressure_limit = Scalar(20e6);
  typename LoadVelocityFeedbackPid<Scalar>::Config torque_loop{};
  typename LoadVelocityFeedbackPid<Scalar>::Config hold_loop{};
};

template <typename Scalar>
struct JointBoardConfig {
  joint_proto::NodeId node = 0;
  std::size_t joints = joint_proto::kMaxJointsPerBoard;             // 1..4
  int control_period_ticks = joint_proto::kDefaultControlPeriodMs;  // 6 ms, or 1..5
  // ModeCommand comes every 10 ms: 70 ms (six lost in a row) trips. Choice: a robot bus that
  // loses a tenth of its frames (the fault the humanoid rides through) loses k in a row with
  // probability 0.1^k, so a timeout of two lost (30 ms) tripped a board within seconds and
  // six lose one every ~3 hours per board; a dead host's boards still stop acting on its
  // torques within the reference timeout below, holding their posture until this one
  // centres their valves.
  int heartbeat_timeout_ticks =
      7 * joint_proto::frame_spec(joint_proto::FrameType::kModeCommand).cycle_time_ms;
  // Sensors come every 1 ms: five lost in a row are a sensor fault.
  int sensor_timeout_ticks = 5;
  // Torque references come every control period: four periods without one (three lost in a
  // row, once a minute per board at a tenth lost) are stale.
  int reference_timeout_periods = 4;
  // Hold and run need encoders zeroed since boot (a board that trusts its stored offsets, e.g.
  // with absolute encoders calibrated in the factory, sets this false).
  bool require_zeroing = true;
  std::array<JointConfig<Scalar>, joint_proto::kMaxJointsPerBoard> joint{};

  // The tuned defaults for every joint at this control period: the torque loop by
  // hydraulic::tune_torque_loop from the believed actuator, the hold loop a stiff posture
  // (300 N·m/rad, 1 N·m per 3.3 mrad) with damping 20 N·m·s/rad and a slow integral.
  void tune_defaults() {
    tune_torque_loops();
    for (auto& j : joint) {
      j.hold_loop.kp = Scalar(300);
      j.hold_loop.ki = Scalar(100);
      j.hold_loop.kd = Scalar(20);
      j.hold_loop.derivative_time_constant = Scalar(0);
      j.hold_loop.integral_limit = Scalar(20);
      j.hold_loop.output_min = -j.torque_limit;
      j.hold_loop.output_max = j.torque_limit;
      j.hold_loop.safe_output = Scalar(0);
    }
  }
  // The torque loops alone, for the believed actuators as they are now.
  void tune_torque_loops() {
    const Scalar period = Scalar(control_period_ticks) * Scalar(0.001);
    for (auto& j : joint) {
      const auto gains = hydraulic::tune_torque_loop(j.actuator, period);
      j.torque_loop.kp = gains.kp;
      j.torque_loop.ki = gains.ki;
      j.torque_loop.load_velocity_gain = gains.k_lv;
      j.torque_loop.integral_limit = Scalar(0.5);
      j.torque_loop.output_min = Scalar(-1);
      j.torque_loop.output_max = Scalar(1);
      j.torque_loop.safe_output = Scalar(0);
    }
  }
  JointBoardConfig() { tune_defaults(); }

  // Empty (nullptr) when usable, otherwise what is wrong.
  const char* check() const {
    if (node > joint_proto::kIds.max_node) return "node id above 15";
    if (joints < 1 || joints > joint_proto::kMaxJointsPerBoard) return "joints must be 1..4";
    if (control_period_ticks < 1 || control_period_ticks > 6) {
      return "control period must be 1..6 ms";
    }
    if (heartbeat_timeout_ticks < 1 || sensor_timeout_ticks < 1 || reference_timeout_periods < 1) {
      return "timeouts must be positive";
    }
    for (std::size_t i = 0; i < joints; ++i) {
      const auto& j = joint[i];
      if (hydraulic::check(j.actuator) != nullptr) return hydraulic::check(j.actuator);
      if (!(j.theta_min < j.theta_max) || !(j.torque_limit > 0) || !(j.torque_rate_limit > 0) ||
          !(j.pressure_limit > 0) || !std::isfinite(j.encoder_offset) ||
          !std::isfinite(j.zero_posture)) {
        return "joint limits, offsets or rates invalid";
      }
      if (!LoadVelocityFeedbackPid<Scalar>::config_valid(j.torque_loop) ||
          !LoadVelocityFeedbackPid<Scalar>::config_valid(j.hold_loop)) {
        return "a joint's loop gains are invalid";
      }
    }
    return nullptr;
  }
};

struct JointBoardCounters {
  std::uint32_t watchdog_trips = 0;
  std::uint32_t sensor_timeouts = 0;
  std::uint32_t refused_commands = 0;    // mode requests not allowed now
  std::uint32_t refused_references = 0;  // torque references beyond a joint's limit
  std::uint32_t refused_gains = 0;       // gains for no joint of this board, or unusable
  std::uint32_t stale_references = 0;    // run -> hold for lack of references
  std::uint32_t estops = 0;
  std::uint32_t overruns = 0;  // late wake-ups the board support reports (real-time loop)
  std::uint32_t syncs = 0;
  std::uint32_t control_steps = 0;
};

// What a joint's sensors say, in the board's units (SI, the angle zeroed).
template <typename Scalar>
struct JointMeasurement {
  Scalar theta = 0, theta_dot = 0, tau = 0;  // rad, rad/s, N·m
  Scalar pressure_a = 0, pressure_b = 0;     // Pa
};

template <typename Scalar>
class JointBoard : public BoardRuntime<JointBoard<Scalar>, JointBoardProtocol> {
  using Runtime = BoardRuntime<JointBoard<Scalar>, JointBoardProtocol>;
  friend Runtime;

 public:
  using Config = JointBoardConfig<Scalar>;
  using Pid = LoadVelocityFeedbackPid<Scalar>;
  static constexpr std::size_t kMaxJoints = joint_proto::kMaxJointsPerBoard;
  static constexpr Scalar kTick = Scalar(0.001);

  // Precondition: config.check() == nullptr (the board support checks it and stays in boot,
  // reporting kInternal, otherwise).
  explicit JointBoard(const Config& config)
      : Runtime(RuntimeConfig{config.node, config.heartbeat_timeout_ticks,
                              config.sensor_timeout_ticks}),
        config_(config) {
    for (std::size_t j = 0; j < kMaxJoints; ++j) {
      offset_[j] = config.joint[j].encoder_offset;
      no_load_ratio_[j] = hydraulic::no_load_velocity_ratio(config.joint[j].actuator);
    }
  }

  using Runtime::on_frame;
  using Runtime::tick;

  // A joint's local readings (on hardware from the board's encoder, load cell and pressure
  // sensors; in the HIL from the I/O bus): the raw encoder angle, before the offset.
  void on_joint_sensor(std::size_t joint, Scalar encoder, Scalar theta_dot, Scalar tau) {
    if (joint >= config_.joints || !std::isfinite(encoder) || !std::isfinite(theta_dot) ||
        !std::isfinite(tau)) {
      return;  // never acted on; the sensor watchdog notices the silence
    }
    encoder_[joint] = encoder;
    measured_[joint].theta = encoder - offset_[joint];
    measured_[joint].theta_dot = theta_dot;
    measured_[joint].tau = tau;
    joint_sensor_tick_[joint] = this->ticks();
    joint_sensor_seen_[joint] = true;
    note_complete_reading();
  }
  void on_chamber_pressures(std::size_t joint, Scalar pressure_a, Scalar pressure_b) {
    if (joint >= config_.joints || !std::isfinite(pressure_a) || !std::isfinite(pressure_b)) {
      return;
    }
    measured_[joint].pressure_a = pressure_a;
    measured_[joint].pressure_b = pressure_b;
    pressure_tick_[joint] = this->ticks();
    pressure_seen_[joint] = true;
    note_complete_reading();
  }

  // The board support's report of a control step that started late (real-time loop).
  void note_overrun() {
    ++counters_.overruns;
    this->set_fault_bits(joint_proto::fault::kOverrun);
  }

  // ---- observation ------------------------------------------------------------------------

  // Valve commands, [-1, 1], one per joint (0 beyond the board's joints).
  const std::array<Scalar, kMaxJoints>& valve_commands() const { return valve_; }
  // The torque references the loops follow now (after checks and the rate limit).
  const std::array<Scalar, kMaxJoints>& applied_references() const { return applied_; }
  const JointMeasurement<Scalar>& measurement(std::size_t joint) const { return measured_[joint]; }
  Scalar encoder_offset(std::size_t joint) const { return offset_[joint]; }
  bool zeroed() const { return zeroed_; }
  Scalar hold_target(std::size_t joint) const { return hold_target_[joint]; }
  JointBoardCounters counters() const {
    JointBoardCounters c = counters_;
    const RuntimeCounters& r = this->runtime_counters();
    c.watchdog_trips = r.watchdog_trips;
    c.sensor_timeouts = r.sensor_timeouts;
    c.refused_commands = r.refused_commands;
    c.syncs = r.syncs;
    return c;
  }
  const Config& config() const { return config_; }

 private:
  // ---- runtime hooks ---------------------------------------------------------------------

  void on_application_frame(joint_proto::FrameType type, const joint_proto::Frame& frame) {
    using joint_proto::FrameType;
    switch (type) {
      case FrameType::kEStop: {
        joint_proto::EStop stop;
        if (this->receive(frame, stop)) {
          ++counters_.estops;
          this->fault(joint_proto::fault::kEStop);
        }
        break;
      }
      case FrameType::kTorqueReference: {
        joint_proto::TorqueReference reference;
        if (this->receive(frame, reference)) on_torque_reference(reference);
        break;
      }
      case FrameType::kTorqueGains: {
        joint_proto::TorqueGains gains;
        if (this->receive(frame, gains)) on_torque_gains(gains);
        break;
      }
      case FrameType::kHoldGains: {
        joint_proto::HoldGains gains;
        if (this->receive(frame, gains)) on_hold_gains(gains);
        break;
      }
      case FrameType::kJointSensor0: receive_sensor<0>(frame); break;
      case FrameType::kJointSensor1: receive_sensor<1>(frame); break;
      case FrameType::kJointSensor2: receive_sensor<2>(frame); break;
      case FrameType::kJointSensor3: receive_sensor<3>(frame); break;
      case FrameType::kChamberPressures01:
        receive_pressures<joint_proto::ChamberPressures01>(frame, 0);
        break;
      case FrameType::kChamberPressures23:
        receive_pressures<joint_proto::ChamberPressures23>(frame, 2);
        break;
      default:  // frames this board sends, or the IMU's
        break;
    }
  }

  void on_heartbeat(const joint_proto::ModeCommand& m) {
    if (m.zero_encoders && this->mode() == joint_proto::BoardMode::kIdle && this->sensor_fresh()) {
      for (std::size_t j = 0; j < config_.joints; ++j) {
        offset_[j] = encoder_[j] - config_.joint[j].zero_posture;
        measured_[j].theta = config_.joint[j].zero_posture;
      }
      zeroed_ = true;
    }
  }

  bool may_enter_hold() {
    if (config_.require_zeroing && !zeroed_) {
      this->set_fault_bits(joint_proto::fault::kNotZeroed);
      return false;
    }
    return true;
  }
  bool may_enter_run(const joint_proto::ModeCommand&) {
    if (!may_enter_hold()) return false;
    return have_reference_ && reference_age_ticks() <= reference_timeout_ticks();
  }
  bool run_request_changes(const joint_proto::ModeCommand&) const { return false; }

  void enter_hold() {
    for (std::size_t j = 0; j < kMaxJoints; ++j) {
      hold_target_[j] = measured_[j].theta;
      Pid::reset(hold_state_[j]);
    }
  }
  void enter_run(const joint_proto::ModeCommand&) {
    // The loops continue from the torques the joints carry now, so entering run does not kick.
    for (std::size_t j = 0; j < kMaxJoints; ++j) applied_[j] = measured_[j].tau;
  }

  void control_step(joint_proto::BoardMode mode) {
    if (mode == joint_proto::BoardMode::kRun && reference_age_ticks() > reference_timeout_ticks()) {
      ++counters_.stale_references;
      this->set_fault_bits(joint_proto::fault::kStaleReference);
      enter_hold();
      this->set_mode(joint_proto::BoardMode::kHold);
      mode = joint_proto::BoardMode::kHold;
    }
    if (mode != joint_proto::BoardMode::kHold && mode != joint_proto::BoardMode::kRun) {
      apply_safe_outputs();
      return;
    }
    if (this->ticks() % std::uint32_t(config_.control_period_ticks) != 0) return;
    ++counters_.control_steps;
    const Scalar period = Scalar(config_.control_period_ticks) * kTick;
    for (std::size_t j = 0; j < config_.joints; ++j) {
      const JointConfig<Scalar>& c = config_.joint[j];
      const JointMeasurement<Scalar>& m = measured_[j];
      Scalar wanted = reference_[j];
      if (mode == joint_proto::BoardMode::kHold) {
        wanted =
            Pid::update(c.hold_loop, hold_state_[j], hold_target_[j], m.theta, m.theta_dot, period);
      }
      // The rate limit: the applied reference moves at most torque_rate_limit * T per step.
      const Scalar step = c.torque_rate_limit * period;
      applied_[j] = clamp(wanted, applied_[j] - step, applied_[j] + step);
      // The load-velocity term at this operating point: the configured (no-load) gain times the
      // model's k_v / k_q here over its no-load value, from the measured pressures, angle and
      // valve side. The factor scales the velocity the loop is given, which only that term
      // uses, so the configured gain stays as set.
      const hydraulic::JointActuatorState<Scalar> here{valve_[j], m.pressure_a, m.pressure_b};
      const Scalar schedule =
          hydraulic::load_velocity_schedule(c.actuator, no_load_ratio_[j], here, m.theta);
      valve_[j] = Pid::update(c.torque_loop, torque_state_[j], applied_[j], m.tau,
                              schedule * m.theta_dot, period);
    }
  }

  void apply_safe_outputs() {
    valve_.fill(Scalar(0));
    for (std::size_t j = 0; j < kMaxJoints; ++j) {
      Pid::reset(torque_state_[j]);
      applied_[j] = measured_[j].tau;
    }
  }

  void forget_sensor_counters() {
    for (std::size_t j = 0; j < kMaxJoints; ++j) {
      this->forget_counter(joint_proto::joint_frame(joint_proto::FrameType::kJointSensor0, j));
    }
    this->forget_counter(joint_proto::FrameType::kChamberPressures01);
    this->forget_counter(joint_proto::FrameType::kChamberPressures23);
  }

  std::uint16_t application_faults() const {
    const auto mode = this->mode();
    if (mode != joint_proto::BoardMode::kHold && mode != joint_proto::BoardMode::kRun) return 0;
    std::uint16_t bits = 0;
    for (std::size_t j = 0; j < config_.joints; ++j) {
      const JointConfig<Scalar>& c = config_.joint[j];
      const JointMeasurement<Scalar>& m = measured_[j];
      if (m.theta < c.theta_min || m.theta > c.theta_max) bits |= joint_proto::fault::kJointLimit;
      if (m.pressure_a > c.pressure_limit || m.pressure_b > c.pressure_limit) {
        bits |= joint_proto::fault::kPressureLimit;
      }
    }
    return bits;
  }

  void send_telemetry() {
    const std::uint32_t ticks = this->ticks();
    joint_proto::ValveDrive drive;  // to the valves (the plant, in HIL) every tick
    for (std::size_t j = 0; j < kMaxJoints; ++j) drive.u[j] = float(valve_[j]);
    this->send(drive);
    if (ticks % std::uint32_t(config_.control_period_ticks) == 0) {
      send_joint_states(std::make_index_sequence<kMaxJoints>{});
      joint_proto::ValveCommands commands;
      commands.u = drive.u;
      this->send(commands);
    }
    if (ticks % frame_period(joint_proto::FrameType::kBoardStatus) == 0) {
      joint_proto::BoardStatus s;
      s.mode = this->mode();
      s.faults = this->faults();
      s.joints = std::uint8_t(config_.joints);
      s.rejected_frames = this->rejected_frames_mod_256();
      s.watchdog_trips = std::uint8_t(this->runtime_counters().watchdog_trips);
      s.overruns = std::uint8_t(counters_.overruns);
      this->send(s);
    }
    if (ticks % frame_period(joint_proto::FrameType::kEncoderOffset) == 0) {
      const std::size_t j = offset_report_next_;
      offset_report_next_ = (offset_report_next_ + 1) % config_.joints;
      joint_proto::EncoderOffset report;
      report.joint = std::uint8_t(j);
      report.offset = float(clamp(offset_[j], Scalar(-3.1416), Scalar(3.1416)));
      report.zeroed = zeroed_;
      this->send(report);
    }
  }

  // ---- the joints --------------------------------------------------------------------------

  static std::uint32_t frame_period(joint_proto::FrameType type) {
    return joint_proto::frame_spec(type).cycle_time_ms;
  }
  std::uint32_t reference_timeout_ticks() const {
    return std::uint32_t(config_.reference_timeout_periods * config_.control_period_ticks);
  }
  std::uint32_t reference_age_ticks() const { return this->ticks() - reference_tick_; }

  // The board's reading is complete when every joint's sensor and pressure frames have come;
  // it is as old as the oldest of them.
  void note_complete_reading() {
    std::uint32_t oldest_age = 0;
    for (std::size_t j = 0; j < config_.joints; ++j) {
      if (!joint_sensor_seen_[j] || !pressure_seen_[j]) return;
      const std::uint32_t age =
          std::max(this->ticks() - joint_sensor_tick_[j], this->ticks() - pressure_tick_[j]);
      oldest_age = std::max(oldest_age, age);
    }
    this->note_sensor_at(this->ticks() - oldest_age);
  }

  template <std::size_t kJoint>
  void receive_sensor(const joint_proto::Frame& frame) {
    joint_proto::JointSensor<kJoint> s;
    if (this->receive(frame, s))
      on_joint_sensor(kJoint, Scalar(s.theta), Scalar(s.theta_dot), Scalar(s.tau));
  }
  template <class Message>
  void receive_pressures(const joint_proto::Frame& frame, std::size_t first_joint) {
    Message p;
    if (!this->receive(frame, p)) return;
    for (std::size_t i = 0; i < 2; ++i) {
      on_chamber_pressures(first_joint + i, Scalar(p.p_a[i]) * Scalar(1e6),
                           Scalar(p.p_b[i]) * Scalar(1e6));
    }
  }

  // A whole reference is refused if any of the board's joints' is beyond its limit: the
  // joints of one leg act together, half a reference would be a different motion.
  void on_torque_reference(const joint_proto::TorqueReference& r) {
    for (std::size_t j = 0; j < config_.joints; ++j) {
      if (std::fabs(Scalar(r.tau[j])) > config_.joint[j].torque_limit) {
        ++counters_.refused_references;
        return;
      }
    }
    for (std::size_t j = 0; j < config_.joints; ++j) reference_[j] = Scalar(r.tau[j]);
    reference_tick_ = this->ticks();
    have_reference_ = true;
  }

  void on_torque_gains(const joint_proto::TorqueGains& g) {
    adopt_gains(g.joint, &JointConfig<Scalar>::torque_loop, [&g](typename Pid::Config& c) {
      c.kp = Scalar(g.kp);
      c.ki = Scalar(g.ki);
      c.load_velocity_gain = Scalar(g.k_lv);
    });
  }
  void on_hold_gains(const joint_proto::HoldGains& g) {
    adopt_gains(g.joint, &JointConfig<Scalar>::hold_loop, [&g](typename Pid::Config& c) {
      c.kp = Scalar(g.kp);
      c.ki = Scalar(g.ki);
      c.kd = Scalar(g.kd);
    });
  }
  // Gains for a joint the board lacks, or that make an unusable loop, are refused and counted.
  template <class Set>
  void adopt_gains(std::size_t joint, typename Pid::Config JointConfig<Scalar>::*loop, Set&& set) {
    if (joint >= config_.joints) {
      ++counters_.refused_gains;
      return;
    }
    typename Pid::Config c = config_.joint[joint].*loop;
    set(c);
    if (!Pid::config_valid(c)) {
      ++counters_.refused_gains;
      return;
    }
    config_.joint[joint].*loop = c;
  }

  template <std::size_t... kJoints>
  void send_joint_states(std::index_sequence<kJoints...>) {
    (send_joint_state<kJoints>(), ...);
  }
  template <std::size_t kJoint>
  void send_joint_state() {
    if (kJoint >= config_.joints) return;
    const JointMeasurement<Scalar>& m = measured_[kJoint];
    joint_proto::JointState<kJoint> s;
    s.theta = float(clamp(m.theta, Scalar(-3.1416), Scalar(3.1416)));
    s.theta_dot = float(clamp(m.theta_dot, Scalar(-20), Scalar(20)));
    s.tau = float(clamp(m.tau, Scalar(-200), Scalar(200)));
    this->send(s);
  }

  static Scalar clamp(Scalar v, Scalar lo, Scalar hi) { return v < lo ? lo : (v > hi ? hi : v); }

  Config config_;
  JointBoardCounters counters_{};  // the application's; counters() adds the runtime's
  std::array<JointMeasurement<Scalar>, kMaxJoints> measured_{};
  std::array<Scalar, kMaxJoints> encoder_{};
  std::array<Scalar, kMaxJoints> offset_{};
  std::array<Scalar, kMaxJoints> no_load_ratio_{};  // k_v / k_q of each believed actuator
  bool zeroed_ = false;
  std::array<std::uint32_t, kMaxJoints> joint_sensor_tick_{};
  std::array<std::uint32_t, kMaxJoints> pressure_tick_{};
  std::array<bool, kMaxJoints> joint_sensor_seen_{};
  std::array<bool, kMaxJoints> pressure_seen_{};
  std::array<Scalar, kMaxJoints> reference_{};  // the host's last accepted references
  std::uint32_t reference_tick_ = 0;
  bool have_reference_ = false;
  std::array<Scalar, kMaxJoints> applied_{};  // after the rate limit
  std::array<Scalar, kMaxJoints> hold_target_{};
  std::array<typename Pid::State, kMaxJoints> torque_state_{};
  std::array<typename Pid::State, kMaxJoints> hold_state_{};
  std::array<Scalar, kMaxJoints> valve_{};
  std::size_t offset_report_next_ = 0;
};

}  // namespace hmpc::firmware
