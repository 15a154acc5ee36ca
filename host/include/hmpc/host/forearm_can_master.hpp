// The host's side of the forearm board's CAN protocol, independent of the bus: what to send
// when (heartbeat with the requested mode and strategy, target trajectory samples streamed
// ahead of the board's MPC horizon) and what the board last reported. The host program
// (host/apps/hmpc_forearm_host.cpp) moves its frames on SocketCAN and bridges to DDS.
//
// Everything goes out on heartbeat ticks, every 10 ms: samples first, then new cost weights,
// then the ModeCommand.
// In HIL lock-step, where the plant waits for the heartbeat, the board therefore sees each
// tick's host frames before its next tick, whatever the scheduling of the processes.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "hmpc/models/forearm_target.hpp"
#include "hmpc/protocol/forearm_protocol.hpp"
#include "hmpc/trajectory/joint_trajectory.hpp"

namespace hmpc::host {

namespace proto = hmpc::forearm_protocol;
using trajectory::JointTrajectoryTarget;
using trajectory::TrajectoryPoint;

struct ForearmMasterConfig {
  proto::NodeId node = 0;
  // The protocol's ModeCommand period (forearm_protocol.hpp kFrames); the board's watchdog
  // allows two.
  double heartbeat_period_s = 0.010;
  // The protocol's TrajectorySample period, and how far ahead samples go: beyond the longest
  // MPC horizon of Table 3.1 (200 ms) plus a heartbeat period, within the board's 128-sample
  // buffer (512 ms).
  double sample_period_s = 0.004;
  double stream_lead_s = 0.300;
  // Points of the longest target trajectory the master holds (allocated once).
  std::size_t trajectory_capacity = 8192;
};

// What the board last said, as decoded (every frame validated by the host's Receiver).
struct BoardReport {
  proto::BoardStatus status{};
  proto::JointState joint{};
  proto::ActuatorOutputs outputs{};
  proto::SolveTelemetry telemetry{};
  std::uint64_t status_frames = 0, joint_frames = 0, output_frames = 0, telemetry_frames = 0;
};

class ForearmCanMaster {
 public:
  explicit ForearmCanMaster(const ForearmMasterConfig& config)
      : config_(config), receiver_(config.node), trajectory_(config.trajectory_capacity) {}

  // Mode and strategy asked for from the next heartbeat on; clear_faults is sent once.
  void request(proto::RequestedMode mode, proto::Strategy strategy, bool clear_faults = false) {
    mode_ = mode;
    strategy_ = strategy;
    clear_faults_ = clear_faults_ || clear_faults;
  }
  // theta_d(t) = offset + amplitude sin(2 pi f (t - t0)) on the host clock, streamed from t0.
  void stream_sinusoid(double amplitude, double frequency_hz, double offset, double t0) {
    target_.set_sinusoid(amplitude, frequency_hz, offset, t0);
    use_trajectory_ = false;
    start_streaming(t0);
  }
  // theta_d(t) = the trajectory's position at t - t0, held before and after it. Streamed from
  // now_s, or when it replaces a stream, after the samples already sent: the board takes
  // samples in increasing time only, so the old target's last stream_lead_s still play out.
  // False, and nothing changed, when it has no points or more than the capacity.
  bool stream_trajectory(const TrajectoryPoint* points, std::size_t n, double t0, double now_s) {
    if (!trajectory_.assign(points, n)) return false;
    use_trajectory_ = true;
    trajectory_t0_ = t0;
    start_streaming(streaming_ ? std::max(next_sample_s_, now_s) : now_s);
    return true;
  }
  // Tracking-cost weights (0 keeps the board's), sent once on the next heartbeat tick; the
  // board adopts them before its next MPC step.
  void send_cost_weights(const proto::CostWeights& weights) {
    weights_ = weights;
    weights_pending_ = true;
  }
  void stop_streaming() { streaming_ = false; }
  bool streaming() const { return streaming_; }
  double target_angle(double t) const {
    return use_trajectory_ ? trajectory_.position(t - trajectory_t0_) : target_.angle(t);
  }

  // Called every host tick (1 ms in HIL lock-step, or as often as the program wakes); on a
  // heartbeat tick, hands send() the trajectory samples due and the ModeCommand.
  // `heartbeat_enabled` false withholds the ModeCommand (fault injection: a dead host).
  template <class Send>
  void tick(double now_s, bool heartbeat_enabled, Send&& send) {
    if (now_s + 1e-9 < next_heartbeat_s_) return;
    next_heartbeat_s_ = now_s + config_.heartbeat_period_s;
    while (streaming_ && next_sample_s_ <= now_s + config_.stream_lead_s) {
      send(proto::TrajectorySample{float(target_angle(next_sample_s_)),
                                   to_host_time_us(next_sample_s_), 0});
      next_sample_s_ += config_.sample_period_s;
    }
    if (weights_pending_) {
      send(weights_);
      weights_pending_ = false;
    }
    if (!heartbeat_enabled) return;
    send(proto::ModeCommand{mode_, strategy_, clear_faults_, to_host_time_us(now_s), 0});
    clear_faults_ = false;
  }

  // A frame from the bus: this board's reports are decoded and kept; others are ignored.
  // Returns true for a SolveTelemetry (the board's 4 ms report).
  bool on_frame(const proto::Frame& frame) {
    proto::FrameType type;
    proto::NodeId node;
    if (!proto::identify(frame.id, type, node) || node != config_.node) return false;
    switch (type) {
      case proto::FrameType::kBoardStatus:
        if (receiver_.decode(frame, report_.status) == proto::DecodeResult::kOk)
          ++report_.status_frames;
        return false;
      case proto::FrameType::kJointState:
        if (receiver_.decode(frame, report_.joint) == proto::DecodeResult::kOk)
          ++report_.joint_frames;
        return false;
      case proto::FrameType::kActuatorOutputs:
        if (receiver_.decode(frame, report_.outputs) == proto::DecodeResult::kOk)
          ++report_.output_frames;
        return false;
      case proto::FrameType::kSolveTelemetry:
        if (receiver_.decode(frame, report_.telemetry) != proto::DecodeResult::kOk) return false;
        ++report_.telemetry_frames;
        return true;
      default: return false;
    }
  }

  const BoardReport& report() const { return report_; }
  const proto::RejectCounters& rejects() const { return receiver_.rejects; }
  proto::RequestedMode requested_mode() const { return mode_; }
  proto::Strategy requested_strategy() const { return strategy_; }

  // The host trajectory clock on the bus: microseconds modulo 2^32 (protocol).
  static std::uint32_t to_host_time_us(double t) {
    return std::uint32_t(std::uint64_t(std::llround(t * 1e6)) & 0xFFFFFFFFu);
  }

 private:
  void start_streaming(double from_s) {
    streaming_ = true;
    next_sample_s_ = from_s;
  }

  ForearmMasterConfig config_;
  proto::Receiver receiver_;
  forearm::TargetTrajectory<double> target_;
  JointTrajectoryTarget trajectory_;
  bool use_trajectory_ = false;
  double trajectory_t0_ = 0;
  bool streaming_ = false;
  double next_sample_s_ = 0;
  double next_heartbeat_s_ = 0;
  proto::RequestedMode mode_ = proto::RequestedMode::kIdle;
  proto::Strategy strategy_ = proto::Strategy::kTwoStage;
  bool clear_faults_ = false;
  proto::CostWeights weights_{};
  bool weights_pending_ = false;
  BoardReport report_;
};

}  // namespace hmpc::host
