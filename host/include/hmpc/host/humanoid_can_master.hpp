// The host's side of the humanoid's robot bus (joint protocol), independent of the bus: the two
// leg boards and the torso IMU of hmpc/humanoid/hydraulic_legs.hpp. What to send when (each
// board's heartbeat with the requested mode every 10 ms, its torque references every 6 ms, the
// bus-wide E-stop once), and what the boards and the IMU last reported: each board's status,
// its joints' angles, rates and torques, its encoders' zeroing, and the IMU's gyroscope and
// accelerometer. Every frame is validated by a Receiver per sender; a sender silent for longer
// than its timeout is forgotten (its frame counters too, so a restarted board is heard again).
// The host program (host/apps/hmpc_humanoid_host.cpp) moves the frames on SocketCAN.
//
// Frames go out on the ticks they are due: references first, then heartbeats, so a board in
// lock-step holds this tick's reference before it may be asked to run.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>

#include "hmpc/humanoid/hydraulic_legs.hpp"
#include "hmpc/humanoid/model.hpp"
#include "hmpc/protocol/joint_protocol.hpp"

namespace hmpc::host {

namespace jp = hmpc::joint_protocol;

struct HumanoidMasterConfig {
  // The protocol's periods (joint_protocol.hpp kFrames): ModeCommand 10 ms, TorqueReference
  // 6 ms.
  int heartbeat_period_ticks = 10;
  int reference_period_ticks = 6;
  // A board whose BoardStatus (20 ms) has not come for 5 periods, or an IMU silent for 5 of its
  // 6 ms frames, is lost (our choice: 4 lost frames in a row are a fault, not noise).
  int board_timeout_ticks = 100;
  int imu_timeout_ticks = 30;
};

// One board as last heard.
struct LegBoardView {
  jp::BoardStatus status{};
  bool heard = false;  // a valid BoardStatus within the timeout
  std::uint32_t last_status_tick = 0;
  std::array<bool, jp::kMaxJointsPerBoard> zeroed{};
  std::array<float, jp::kMaxJointsPerBoard> offset{};  // rad, as reported
  std::uint32_t joint_frames = 0, status_frames = 0;
  // Seen in hold or run; then found idle or booting while the host asks for hold or run, or
  // faulted for being asked them before zeroing, it has restarted: its encoders are no longer
  // zeroed, so it will not hold or run (its valves centred).
  bool engaged = false;
  bool restarted = false;
};

// What the boards and the IMU said last.
struct RobotReadings {
  humanoid::JointVector angle = humanoid::JointVector::Zero();     // rad, zeroed by the boards
  humanoid::JointVector rate = humanoid::JointVector::Zero();      // rad/s, the boards' filter
  humanoid::JointVector torque = humanoid::JointVector::Zero();    // N m, load cells
  std::array<std::uint32_t, humanoid::kJoints> joint_tick{};       // when each joint was heard
  humanoid::Vector3 angular_velocity = humanoid::Vector3::Zero();  // rad/s, IMU
  humanoid::Vector3 specific_force = humanoid::Vector3::Zero();    // m/s^2, IMU
  std::uint32_t gyro_tick = 0, accel_tick = 0;
  bool imu_heard = false;
  std::uint32_t imu_frames = 0;
};

// What on_frame() took.
enum class Heard { kNothing, kBoardStatus, kJointState, kEncoderOffset, kImuGyro, kImuAccel };

class HumanoidCanMaster {
 public:
  static constexpr int kBoards = humanoid::kLegBoards;

  explicit HumanoidCanMaster(const HumanoidMasterConfig& config = {}) : config_(config) {
    for (int b = 0; b < kBoards; ++b) {
      from_board_[std::size_t(b)] = jp::Receiver(jp::NodeId(b));
      to_board_[std::size_t(b)] = jp::Sender(jp::NodeId(b));
    }
  }

  // The mode every board is asked for from the next heartbeat on; clear_faults and
  // zero_encoders go out with the next heartbeat only.
  void request(jp::RequestedMode mode, bool clear_faults = false, bool zero_encoders = false) {
    mode_ = mode;
    clear_faults_ = clear_faults_ || clear_faults;
    zero_encoders_ = zero_encoders_ || zero_encoders;
  }
  // The bus-wide E-stop, sent on the next tick; every board latches its safe state.
  void estop() { estop_pending_ = true; }
  // The torques [N m] of the next references, and whether to send references at all.
  void set_references(const humanoid::JointVector& tau) {
    references_ = tau;
    streaming_ = true;
  }
  void stop_references() { streaming_ = false; }

  // Host tick `tick` (1 ms): hands send(bus, message-encoded frame) what is due. Heartbeats
  // withheld (`heartbeat_enabled` false) stand for a host whose loop has died.
  template <class Send>
  void tick(std::uint32_t tick, bool heartbeat_enabled, Send&& send) {
    expire(tick);
    jp::Frame frame;
    if (estop_pending_) {
      if (stop_sender_.encode(jp::EStop{}, frame) == jp::EncodeResult::kOk) send(frame);
      estop_pending_ = false;
    }
    if (streaming_ && heartbeat_enabled &&
        tick % std::uint32_t(config_.reference_period_ticks) == 0) {
      for (int b = 0; b < kBoards; ++b) {
        jp::TorqueReference r;
        for (int c = 0; c < humanoid::kJointsPerBoard; ++c) {
          r.tau[std::size_t(c)] = float(references_[humanoid::joint_of(b, c)]);
        }
        if (to_board_[std::size_t(b)].encode(r, frame) == jp::EncodeResult::kOk) send(frame);
      }
    }
    if (heartbeat_enabled && tick % std::uint32_t(config_.heartbeat_period_ticks) == 0) {
      for (int b = 0; b < kBoards; ++b) {
        jp::ModeCommand m;
        m.mode = mode_;
        m.clear_faults = clear_faults_;
        m.zero_encoders = zero_encoders_;
        m.host_time_us = 1000u * tick;
        if (to_board_[std::size_t(b)].encode(m, frame) == jp::EncodeResult::kOk) send(frame);
      }
      clear_faults_ = zero_encoders_ = false;
    }
  }

  // A frame from the robot bus at host tick `tick`: the boards' and the IMU's are validated and
  // kept; others (ours, other nodes') are ignored.
  Heard on_frame(const jp::Frame& frame, std::uint32_t tick) {
    jp::FrameType type{};
    jp::NodeId node = 0;
    if (!jp::identify(frame.id, type, node)) return Heard::kNothing;
    if (node == humanoid::kImuNode) return on_imu_frame(type, frame, tick);
    if (node >= kBoards) return Heard::kNothing;
    jp::Receiver& rx = from_board_[node];
    LegBoardView& board = boards_[node];
    switch (type) {
      case jp::FrameType::kBoardStatus:
        if (rx.decode(frame, board.status) != jp::DecodeResult::kOk) return Heard::kNothing;
        note_mode(board);
        board.heard = true;
        board.last_status_tick = tick;
        ++board.status_frames;
        return Heard::kBoardStatus;
      case jp::FrameType::kJointState0: return joint_state<0>(node, frame, tick);
      case jp::FrameType::kJointState1: return joint_state<1>(node, frame, tick);
      case jp::FrameType::kJointState2: return joint_state<2>(node, frame, tick);
      case jp::FrameType::kJointState3: return joint_state<3>(node, frame, tick);
      case jp::FrameType::kEncoderOffset: {
        jp::EncoderOffset offset;
        if (rx.decode(frame, offset) != jp::DecodeResult::kOk ||
            offset.joint >= jp::kMaxJointsPerBoard) {
          return Heard::kNothing;
        }
        board.zeroed[offset.joint] = offset.zeroed;
        board.offset[offset.joint] = offset.offset;
        return Heard::kEncoderOffset;
      }
      default: return Heard::kNothing;
    }
  }

  // Every board heard, speaking our protocol version, with its leg's four joints.
  bool boards_present() const {
    for (const LegBoardView& b : boards_) {
      if (!b.heard || b.status.protocol_version != jp::kProtocolVersion ||
          b.status.joints != humanoid::kJointsPerBoard) {
        return false;
      }
    }
    return true;
  }
  // Every board in `mode`.
  bool all_in(jp::BoardMode mode) const {
    for (const LegBoardView& b : boards_) {
      if (!b.heard || b.status.mode != mode) return false;
    }
    return true;
  }
  bool any_restarted() const {
    for (const LegBoardView& b : boards_) {
      if (b.restarted) return true;
    }
    return false;
  }
  bool any_fault() const {
    for (const LegBoardView& b : boards_) {
      if (b.heard && b.status.mode == jp::BoardMode::kFault) return true;
    }
    return false;
  }
  // Every joint's encoder reported zeroed since its board's boot.
  bool all_zeroed() const {
    for (const LegBoardView& b : boards_) {
      for (int c = 0; c < humanoid::kJointsPerBoard; ++c) {
        if (!b.zeroed[std::size_t(c)]) return false;
      }
    }
    return true;
  }

  const HumanoidMasterConfig& config() const { return config_; }
  const LegBoardView& board(int b) const { return boards_[std::size_t(b)]; }
  const RobotReadings& readings() const { return readings_; }
  jp::RequestedMode requested_mode() const { return mode_; }
  const humanoid::JointVector& references() const { return references_; }
  std::uint64_t rejected_frames() const {
    std::uint64_t n = imu_receiver_.rejects.total();
    for (const jp::Receiver& rx : from_board_) n += rx.rejects.total();
    return n;
  }

 private:
  void expire(std::uint32_t tick) {
    for (int b = 0; b < kBoards; ++b) {
      LegBoardView& board = boards_[std::size_t(b)];
      if (board.heard &&
          tick - board.last_status_tick > std::uint32_t(config_.board_timeout_ticks)) {
        board.heard = false;
        board.engaged = false;
        board.zeroed.fill(false);
        from_board_[std::size_t(b)].counters = {};
      }
    }
    const std::uint32_t last_imu = std::max(readings_.gyro_tick, readings_.accel_tick);
    if (readings_.imu_heard && tick - last_imu > std::uint32_t(config_.imu_timeout_ticks)) {
      readings_.imu_heard = false;
      imu_receiver_.counters = {};
    }
  }

  void note_mode(LegBoardView& board) const {
    const jp::BoardMode mode = board.status.mode;
    if (mode == jp::BoardMode::kHold || mode == jp::BoardMode::kRun) {
      board.engaged = true;
    } else if (board.engaged &&
               (mode == jp::BoardMode::kBoot || mode == jp::BoardMode::kIdle ||
                (mode == jp::BoardMode::kFault && board.status.faults == jp::fault::kNotZeroed)) &&
               (mode_ == jp::RequestedMode::kHold || mode_ == jp::RequestedMode::kRun)) {
      board.restarted = true;
      board.engaged = false;
    }
  }

  template <std::size_t kChannel>
  Heard joint_state(jp::NodeId node, const jp::Frame& frame, std::uint32_t tick) {
    jp::JointState<kChannel> s;
    if (from_board_[node].decode(frame, s) != jp::DecodeResult::kOk) return Heard::kNothing;
    const int j = humanoid::joint_of(int(node), int(kChannel));
    readings_.angle[j] = double(s.theta);
    readings_.rate[j] = double(s.theta_dot);
    readings_.torque[j] = double(s.tau);
    readings_.joint_tick[std::size_t(j)] = tick;
    ++boards_[node].joint_frames;
    return Heard::kJointState;
  }

  Heard on_imu_frame(jp::FrameType type, const jp::Frame& frame, std::uint32_t tick) {
    if (type == jp::FrameType::kImuAngularVelocity) {
      jp::ImuAngularVelocity gyro;
      if (imu_receiver_.decode(frame, gyro) != jp::DecodeResult::kOk) return Heard::kNothing;
      readings_.angular_velocity = {gyro.omega[0], gyro.omega[1], gyro.omega[2]};
      readings_.gyro_tick = tick;
      readings_.imu_heard = true;
      ++readings_.imu_frames;
      return Heard::kImuGyro;
    }
    if (type == jp::FrameType::kImuLinearAcceleration) {
      jp::ImuLinearAcceleration accel;
      if (imu_receiver_.decode(frame, accel) != jp::DecodeResult::kOk) return Heard::kNothing;
      readings_.specific_force = {accel.specific_force[0], accel.specific_force[1],
                                  accel.specific_force[2]};
      readings_.accel_tick = tick;
      readings_.imu_heard = true;
      ++readings_.imu_frames;
      return Heard::kImuAccel;
    }
    return Heard::kNothing;
  }

  HumanoidMasterConfig config_;
  std::array<jp::Receiver, kBoards> from_board_{};
  std::array<jp::Sender, kBoards> to_board_{};
  jp::Receiver imu_receiver_{jp::NodeId(humanoid::kImuNode)};
  jp::Sender stop_sender_{0};
  std::array<LegBoardView, kBoards> boards_{};
  RobotReadings readings_;
  jp::RequestedMode mode_ = jp::RequestedMode::kIdle;
  bool clear_faults_ = false, zero_encoders_ = false, estop_pending_ = false, streaming_ = false;
  humanoid::JointVector references_ = humanoid::JointVector::Zero();
};

}  // namespace hmpc::host
