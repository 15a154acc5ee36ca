// The runtime every actuator board shares, whatever it drives: the mode machine, the heartbeat
// and sensor watchdogs, host-clock tracking, the CAN receiver and sender with the outbox, and
// the event counters. An application (forearm_board.hpp, joint_board.hpp) derives from
// BoardRuntime<Application, Protocol> and supplies what its modes do.
//
//   boot --self-check--> idle --hold cmd--> hold          any --idle cmd--> idle
//   idle or hold --run cmd, if the application allows--> run
//   any active --heartbeat or sensor timeout, application fault--> fault (safe outputs, latched)
//   fault --idle cmd with clear_faults, sensors fresh--> idle
//
// Time is counted in 1 kHz ticks, so the same code runs paced by a timer (real time) or by the
// HIL plant's Sync frames (lock-step) with identical behaviour.
//
// Protocol: a traits struct naming the protocol's Description, its ModeCommand and Sync
// messages, its BoardMode and RequestedMode enums and the fault bits the runtime sets
// (heartbeat and sensor timeout). The application provides, as public or befriended members:
//   Protocol-specific frames  void on_application_frame(FrameType, const Frame&)
//   Heartbeat extras          void on_heartbeat(const ModeCommand&)   (every valid heartbeat)
//   Mode entry                bool may_enter_hold() const; void enter_hold();
//                             bool may_enter_run(const ModeCommand&) const;
//                             bool run_request_changes(const ModeCommand&) const;
//                             void enter_run(const ModeCommand&);
//   Control                   void control_step(BoardMode)   (every tick, after the watchdogs)
//                             void apply_safe_outputs()
//   Watchdogs                 FaultBits application_faults()  (bits to latch now, 0 if none)
//                             void forget_sensor_counters()   (a sensor timeout restarts them)
//   Telemetry                 void send_telemetry()           (every tick, after control)
//
// Nothing here allocates, throws or calls virtual functions.
#pragma once

#include <cstdint>

#include "hmpc/protocol/codec.hpp"

namespace hmpc::firmware {

// What the runtime itself needs of a board's configuration.
struct RuntimeConfig {
  protocol::NodeId node = 0;
  int heartbeat_timeout_ticks = 20;
  int sensor_timeout_ticks = 5;
};

struct RuntimeCounters {
  std::uint32_t watchdog_trips = 0;
  std::uint32_t sensor_timeouts = 0;
  std::uint32_t refused_commands = 0;  // valid frames asking for a transition not allowed now
  std::uint32_t syncs = 0;             // valid HIL lock-step Sync frames
};

template <class Application, class Protocol>
class BoardRuntime {
 public:
  using Description = typename Protocol::Description;
  using FrameType = typename Description::FrameType;
  using BoardMode = typename Protocol::BoardMode;
  using RequestedMode = typename Protocol::RequestedMode;
  using ModeCommand = typename Protocol::ModeCommand;
  using FaultBits = typename Protocol::FaultBits;
  using Receiver = protocol::Receiver<Description>;
  using Sender = protocol::Sender<Description>;

  static constexpr int kOutboxSize = 16;

  explicit BoardRuntime(const RuntimeConfig& config)
      : runtime_config_(config), receiver_(config.node), sender_(config.node) {}

  // ---- inputs ------------------------------------------------------------------------

  // Any frame from the bus. Frames of other nodes are ignored; this node's and bus-wide ones
  // are validated (id, length, checksum, counter, range) and counted when rejected, never
  // acted on.
  void on_frame(const protocol::Frame& frame) {
    FrameType type{};
    protocol::NodeId node = 0;
    if (!protocol::identify(frame.id, type, node)) return;
    if (!protocol::frame_spec(type).bus_wide && node != runtime_config_.node) return;
    if (type == ModeCommand::kType) {
      ModeCommand m;
      if (receiver_.decode(frame, m) == protocol::DecodeResult::kOk) on_mode_command(m);
    } else if (type == Protocol::Sync::kType) {  // the board support ticks on it in lock-step
      typename Protocol::Sync s;
      if (receiver_.decode(frame, s) == protocol::DecodeResult::kOk) ++runtime_counters_.syncs;
    } else {
      application().on_application_frame(type, frame);
    }
  }

  // ---- scheduling --------------------------------------------------------------------

  // The 1 kHz step: self-check, watchdogs, the mode's control, telemetry.
  void tick() {
    ++ticks_;
    if (mode_ == BoardMode::kBoot) mode_ = BoardMode::kIdle;  // self-check: the config
    check_watchdogs();
    application().control_step(mode_);
    application().send_telemetry();
  }

  // ---- outputs and observation ---------------------------------------------------------

  bool pop_frame(protocol::Frame& out) {
    if (outbox_count_ == 0) return false;
    out = outbox_[outbox_head_];
    outbox_head_ = (outbox_head_ + 1) % kOutboxSize;
    --outbox_count_;
    return true;
  }

  BoardMode mode() const { return mode_; }
  FaultBits faults() const { return faults_; }
  const protocol::RejectCounters& rejects() const { return receiver_.rejects; }
  std::uint32_t ticks() const { return ticks_; }
  // Ticks since the last accepted heartbeat and sensor reading: what the watchdogs compare
  // with their timeouts (logged, so a trip's latency can be read off the log).
  std::uint32_t heartbeat_age() const { return ticks_ - last_heartbeat_tick_; }
  std::uint32_t sensor_age() const { return ticks_ - last_sensor_tick_; }
  std::uint32_t dropped_frames() const { return dropped_frames_; }
  std::uint32_t syncs() const { return runtime_counters_.syncs; }

 protected:
  Application& application() { return static_cast<Application&>(*this); }

  // ---- for the application ---------------------------------------------------------------

  // Decodes one of this node's frames through the receiver (counter checked, rejects counted).
  template <class Message>
  bool receive(const protocol::Frame& frame, Message& out) {
    return receiver_.decode(frame, out) == protocol::DecodeResult::kOk;
  }

  // A complete, valid sensor reading arrived: now, or (a board whose readings come in several
  // frames) when the oldest of its parts did.
  void note_sensor() { note_sensor_at(ticks_); }
  void note_sensor_at(std::uint32_t tick) {
    last_sensor_tick_ = tick;
    have_sensor_ = true;
  }
  bool have_sensor() const { return have_sensor_; }
  bool sensor_fresh() const {
    return have_sensor_ &&
           ticks_ - last_sensor_tick_ <= std::uint32_t(runtime_config_.sensor_timeout_ticks);
  }

  // Latches fault bits and the safe state.
  void fault(FaultBits bits) {
    faults_ = FaultBits(faults_ | bits);
    mode_ = BoardMode::kFault;
    application().apply_safe_outputs();
  }
  void set_fault_bits(FaultBits bits) { faults_ = FaultBits(faults_ | bits); }
  void set_mode(BoardMode mode) { mode_ = mode; }
  void forget_counter(FrameType type) { receiver_.counters.reset(type); }
  void count_refused() { ++runtime_counters_.refused_commands; }

  // The host's clock now, us modulo 2^32: board ticks plus the offset between the clocks.
  std::uint32_t host_time_us() const { return 1000u * ticks_ + host_offset_us_; }

  // Encodes and queues a frame; a full outbox (a bus that is not draining) drops the oldest.
  template <class Message>
  void send(const Message& m) {
    protocol::Frame f;
    if (sender_.encode(m, f) != protocol::EncodeResult::kOk) return;
    if (outbox_count_ == kOutboxSize) {
      outbox_head_ = (outbox_head_ + 1) % kOutboxSize;
      --outbox_count_;
      ++dropped_frames_;
    }
    outbox_[(outbox_head_ + outbox_count_) % kOutboxSize] = f;
    ++outbox_count_;
  }

  const RuntimeCounters& runtime_counters() const { return runtime_counters_; }
  std::uint8_t rejected_frames_mod_256() const { return std::uint8_t(receiver_.rejects.total()); }

 private:
  // Each heartbeat measures host time - board time, short by the heartbeat's latency, which
  // jitters (by a tick or two in lock-step, more on a busy bus). The offset follows the
  // largest measurement (the shortest latency) and falls back only beyond a deadband, so the
  // host time does not jitter with the latency, yet a host clock that drifts or restarts is
  // followed. Arithmetic modulo 2^32 us, as the host clock on the bus.
  void track_host_clock(std::uint32_t host_time_us) {
    constexpr std::int32_t kDeadbandUs = 3000;  // > the arrival jitter, < a control step
    const std::uint32_t measured = host_time_us - 1000u * ticks_;
    const std::int32_t change = std::int32_t(measured - host_offset_us_);
    if (!have_host_offset_ || change > 0 || change < -kDeadbandUs) host_offset_us_ = measured;
    have_host_offset_ = true;
  }

  void on_mode_command(const ModeCommand& m) {
    last_heartbeat_tick_ = ticks_;
    track_host_clock(m.host_time_us);
    application().on_heartbeat(m);
    if (mode_ == BoardMode::kFault) {
      if (m.mode == RequestedMode::kIdle && m.clear_faults && sensor_fresh()) {
        faults_ = 0;
        mode_ = BoardMode::kIdle;
      } else if (m.mode != RequestedMode::kIdle) {
        ++runtime_counters_.refused_commands;
      }
      return;
    }
    switch (m.mode) {
      case RequestedMode::kIdle:
        if (m.clear_faults) faults_ = 0;
        mode_ = BoardMode::kIdle;
        break;
      case RequestedMode::kHold:
        if (mode_ == BoardMode::kHold) break;
        if (!sensor_fresh() || !application().may_enter_hold()) {
          ++runtime_counters_.refused_commands;
          break;
        }
        application().enter_hold();
        mode_ = BoardMode::kHold;
        break;
      case RequestedMode::kRun:
        if (!sensor_fresh() || !application().may_enter_run(m)) {
          if (mode_ != BoardMode::kRun) ++runtime_counters_.refused_commands;
          break;
        }
        if (mode_ != BoardMode::kRun || application().run_request_changes(m)) {
          application().enter_run(m);
          mode_ = BoardMode::kRun;
        }
        break;
    }
  }

  void check_watchdogs() {
    const bool active = mode_ == BoardMode::kHold || mode_ == BoardMode::kRun;
    if (active &&
        ticks_ - last_heartbeat_tick_ > std::uint32_t(runtime_config_.heartbeat_timeout_ticks)) {
      ++runtime_counters_.watchdog_trips;
      receiver_.counters.reset(ModeCommand::kType);
      fault(Protocol::kHeartbeatTimeoutFault);
    }
    if (active && !sensor_fresh()) {
      ++runtime_counters_.sensor_timeouts;
      application().forget_sensor_counters();
      fault(Protocol::kSensorTimeoutFault);
    }
    const FaultBits application_faults = application().application_faults();
    if (application_faults != 0) fault(application_faults);
  }

  RuntimeConfig runtime_config_;
  Receiver receiver_;
  Sender sender_;
  RuntimeCounters runtime_counters_{};
  BoardMode mode_ = BoardMode::kBoot;
  FaultBits faults_ = 0;
  bool have_sensor_ = false;
  std::uint32_t ticks_ = 0;
  std::uint32_t last_sensor_tick_ = 0;
  std::uint32_t last_heartbeat_tick_ = 0;
  std::uint32_t host_offset_us_ = 0;  // host clock - board clock, us modulo 2^32
  bool have_host_offset_ = false;
  protocol::Frame outbox_[kOutboxSize]{};
  int outbox_head_ = 0;
  int outbox_count_ = 0;
  std::uint32_t dropped_frames_ = 0;
};

}  // namespace hmpc::firmware
