// The forearm host controller on DDS, the ROS 2 way: one board's joint state, MPC telemetry and
// diagnostics out; mode commands, target trajectories and cost weights in, each checked before
// anything acts on it.
//
// Topics, under a namespace <ns> (default /hmpc/forearm_<node>; "rt" + name on the wire):
//   <ns>/joint_states      sensor_msgs/JointState           state QoS    bridge -> operators
//   <ns>/telemetry         hmpc_msgs/ForearmTelemetry       state QoS    bridge -> operators
//   /diagnostics           diagnostic_msgs/DiagnosticArray  state QoS    bridge -> operators
//   <ns>/command           hmpc_msgs/ModeCommand            command QoS  operators -> bridge
//   <ns>/joint_trajectory  trajectory_msgs/JointTrajectory  state QoS    operators -> bridge
//   <ns>/cost_weights      hmpc_msgs/CostWeights            state QoS    operators -> bridge
// (QoS profiles: hmpc/dds/participant.hpp.) The joint is named kJointName; strategies by the
// CAN protocol's names (forearm_protocol's kStrategyValues: fine_4ms, ..., two_stage, pam_only).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "hmpc/dds/participant.hpp"
#include "hmpc/dds/validation.hpp"
#include "hmpc/protocol/forearm_protocol.hpp"
#include "hmpc/trajectory/joint_target.hpp"

namespace hmpc::dds {

namespace proto = hmpc::forearm_protocol;

inline constexpr const char* kJointName = "elbow";
// Target trajectories the host holds.
inline constexpr std::size_t kMaxTrajectoryPoints = trajectory::kMaxPoints;

// "/hmpc/forearm_<node>".
std::string default_namespace(proto::NodeId node);

// The joint's limits for targets: forearm::target_range() under the joint's name.
const JointLimits& forearm_joint_limits();

// The board's mode and its MPC's last solve, with the actuator outputs, in SI units: what
// hmpc_msgs/ForearmTelemetry carries.
struct ForearmTelemetrySample {
  double stamp_s = 0;  // Unix time; the bridge stamps what it publishes with its clock
  proto::BoardMode mode = proto::BoardMode::kBoot;
  std::uint8_t faults = 0;  // proto::fault bits
  proto::Strategy strategy = proto::Strategy::kTwoStage;
  proto::SolveStatusCode solve_status = proto::SolveStatusCode::kNoSolve;
  std::uint16_t coarse_iterations = 0;
  std::uint16_t fine_iterations = 0;
  std::uint32_t solve_time_us = 0;
  double theta_d = 0;         // target joint angle, rad
  double tracking_error = 0;  // rad
  double pressure_pa = 0;
  double v_p = 0;  // V
  double v_m = 0;
  double tau_p = 0;  // N.m
  double tau_m = 0;
};

// The weights a CostWeights message may set, by the CAN frame's signal names (w_theta, w_p,
// w_tau, w_v: Eq. 3.3), each from its smallest non-zero value to its maximum on the bus.
const std::array<NamedRange, 4>& forearm_weight_limits();

// What the host knows of its board after each SolveTelemetry.
struct ForearmStateSample {
  double theta = 0;      // rad
  double theta_dot = 0;  // rad/s
  ForearmTelemetrySample telemetry;
  std::uint32_t rejected_frames = 0;
  std::uint32_t watchdog_trips = 0;
  std::uint32_t solver_failures = 0;
  std::uint32_t overruns = 0;
};

struct ModeCommandSample {
  std::uint32_t sequence_number = 0;
  proto::RequestedMode mode = proto::RequestedMode::kIdle;
  proto::Strategy strategy = proto::Strategy::kTwoStage;
  bool clear_faults = false;
};

// A validated target: points with times from its start, which is start_delay_s after receipt
// (0 for an unstamped trajectory; negative when its stamp lies in the past).
struct TrajectoryView {
  const trajectory::TrajectoryPoint* points = nullptr;
  std::size_t count = 0;
  double start_delay_s = 0;
};

// What the bridge hands on. A trajectory handler may still refuse a target (e.g. a first
// segment from the joint's present angle that is too fast): the rejection it returns is counted.
struct ForearmDdsHandlers {
  std::function<void(const ModeCommandSample&)> command;
  std::function<Verdict(const TrajectoryView&)> trajectory;
  std::function<void()> commander_silent;  // the commander stopped within kCommandDeadlineS
  // The weights given, the others 0 (the board keeps those).
  std::function<void(const proto::CostWeights&)> weights;
};

// The host controller's side. Every constructor here takes `config`, Cyclone DDS configuration
// XML or empty for Cyclone's default (see Participant), and throws std::runtime_error when DDS
// fails. Use each object from one thread at a time.
class ForearmDdsBridge {
 public:
  // std::invalid_argument for a node outside 0..proto::kMaxNodeId or a bad namespace.
  ForearmDdsBridge(std::uint32_t domain_id, proto::NodeId node, const std::string& config = {},
                   const std::string& ros_namespace = {});
  ~ForearmDdsBridge();
  ForearmDdsBridge(const ForearmDdsBridge&) = delete;
  ForearmDdsBridge& operator=(const ForearmDdsBridge&) = delete;

  // JointState and ForearmTelemetry, and DiagnosticArray when it changed or is due. False if
  // DDS refused a sample.
  bool publish(const ForearmStateSample& state);

  // Takes everything pending. Valid samples go to the handlers, in arrival order per topic; the
  // others are counted by reason and logged to stderr, one line each.
  void poll(const ForearmDdsHandlers& handlers);

  const RejectCounters& rejects() const;
  std::uint64_t commander_silences() const;
  const std::string& ros_namespace() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The joint's target points as a JointTrajectory sample (unstamped: it starts on receipt),
// over its own storage.
class TrajectorySample {
 public:
  explicit TrajectorySample(std::vector<trajectory::TrajectoryPoint> points);
  TrajectorySample(const TrajectorySample&) = delete;
  TrajectorySample& operator=(const TrajectorySample&) = delete;
  const msg::JointTrajectory& message() const { return message_; }

 private:
  std::vector<trajectory::TrajectoryPoint> points_;
  std::vector<msg::JointTrajectoryPoint> out_;
  const char* names_[1] = {kJointName};
  msg::JointTrajectory message_{};
};

// The board's diagnostics as an operator reads them.
struct DiagnosticSample {
  DiagnosticLevel level = DiagnosticLevel::kOk;
  std::string name, message, hardware_id;
  std::vector<std::pair<std::string, std::string>> values;
};

struct JointStateSample {
  double stamp_s = 0;  // Unix time
  double position = 0, velocity = 0, effort = 0;
};

// The operator's side (hmpc-forearm-cli, tests). Commands and trajectories go out as given,
// unchecked: the bridge checks them.
class ForearmDdsClient {
 public:
  ForearmDdsClient(std::uint32_t domain_id, proto::NodeId node, const std::string& config = {},
                   const std::string& ros_namespace = {});
  ~ForearmDdsClient();
  ForearmDdsClient(const ForearmDdsClient&) = delete;
  ForearmDdsClient& operator=(const ForearmDdsClient&) = delete;

  // Waits until a bridge's command and trajectory readers have matched; false on timeout.
  bool wait_for_bridge(double timeout_s);
  bool send(const ModeCommandSample& command);
  // Points of the joint, starting on receipt. False if DDS refused the sample.
  bool send(const std::vector<trajectory::TrajectoryPoint>& points);
  // Named cost weights. False if DDS refused the sample.
  bool send(const std::vector<std::pair<std::string, double>>& weights);
  // Waits until every matched bridge acknowledged what was sent; false on timeout.
  bool wait_for_delivery(double timeout_s);

  // Waits until a sample is pending on any of the three topics; false on timeout.
  bool wait_for_data(double timeout_s);
  // Take every pending sample of one topic; return how many went to handler. Samples that fail
  // their checks (a JointState not of this one joint, a telemetry with an unknown mode or
  // strategy) are counted in rejects() instead.
  std::size_t poll_joint_states(const std::function<void(const JointStateSample&)>& handler);
  std::size_t poll_telemetry(const std::function<void(const ForearmTelemetrySample&)>& handler);
  std::size_t poll_diagnostics(const std::function<void(const DiagnosticSample&)>& handler);
  const RejectCounters& rejects() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace hmpc::dds
