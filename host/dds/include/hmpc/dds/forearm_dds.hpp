// The forearm host controller's DDS interface: board state and MPC telemetry out, operator
// commands in, over Cyclone DDS with the types of host/dds/forearm.idl.
//
// Users see only the plain structs below; the DDS types stay inside the library. Enumerated
// fields carry the CAN protocol's enums (hmpc/protocol/forearm_protocol.hpp) and may hold any
// value of their underlying type, as a received sample can: validate() says whether a command
// is acceptable, and the bridge passes on only commands it accepts.
//
// Topics (keyed by node, reliable, keep-last kHistoryDepth per node, volatile):
//   kStateTopic      ForearmState      bridge -> operators
//   kTelemetryTopic  ForearmTelemetry  bridge -> operators
//   kCommandTopic    ForearmCommand    operators -> bridge
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "hmpc/protocol/forearm_protocol.hpp"

namespace hmpc::dds {

namespace proto = hmpc::forearm_protocol;

inline constexpr const char* kStateTopic = "hmpc_forearm_state";
inline constexpr const char* kTelemetryTopic = "hmpc_forearm_telemetry";
inline constexpr const char* kCommandTopic = "hmpc_forearm_command";
// Commands are rare and state is superseded every 4 ms: a reader that falls behind needs only
// the latest few samples of each node.
inline constexpr std::int32_t kHistoryDepth = 8;

// Angles in rad, pressure in MPa, voltages in V, torques in N.m, times in s.
struct ForearmStateSample {
  proto::NodeId node = 0;
  double board_time_s = 0;  // when the board's frames were received (the host's clock)
  proto::BoardMode mode = proto::BoardMode::kBoot;
  std::uint8_t faults = 0;  // proto::fault bits
  proto::Strategy strategy = proto::Strategy::kTwoStage;
  double theta = 0;
  double theta_dot = 0;  // rad/s
  double pressure_mpa = 0;
  double theta_d = 0;  // target joint angle
  double v_p = 0;
  double v_m = 0;
  double tau_p = 0;
  double tau_m = 0;
  std::uint32_t rejected_frames = 0;
  std::uint32_t watchdog_trips = 0;
  std::uint32_t solver_failures = 0;
  std::uint32_t overruns = 0;
};

struct ForearmTelemetrySample {
  proto::NodeId node = 0;
  double time_s = 0;
  proto::SolveStatusCode solve_status = proto::SolveStatusCode::kNoSolve;
  std::uint16_t coarse_iterations = 0;
  std::uint16_t fine_iterations = 0;
  std::uint32_t solve_time_us = 0;
  double tracking_error = 0;  // rad
};

enum class TargetKind : std::uint8_t {
  kHoldCurrent = 0,  // keep the joint angle the board has when the command arrives
  kSinusoid = 1,     // theta_d(t) = offset + amplitude sin(2 pi f t), t from the command
};

// The target joint trajectory of a command. A constant angle is a sinusoid of amplitude 0.
struct CommandTarget {
  TargetKind kind = TargetKind::kHoldCurrent;
  double amplitude_rad = 0;
  double frequency_hz = 0;
  double offset_rad = 0;
  double duration_s = 0;  // 0: until the next command
};

struct ForearmCommandSample {
  proto::NodeId node = 0;
  std::uint32_t sequence_number = 0;  // chosen by the sender, echoed in logs
  proto::RequestedMode mode = proto::RequestedMode::kIdle;
  proto::Strategy strategy = proto::Strategy::kTwoStage;
  bool clear_faults = false;
  CommandTarget target;
};

// What validate() accepts. Every field is checked, whether the command's kind uses it or not:
// garbage in an unused field means a broken sender.
struct CommandLimits {
  // Sanity bounds with room around the thesis's tracking patterns, +-30 deg at 0.25..1 Hz
  // (Sec. 3.3); not a promise that the MPC tracks everything inside them.
  double max_amplitude_rad = 1.0;
  double max_frequency_hz = 5.0;
  double max_abs_offset_rad = 1.0;
  double max_duration_s = 3600.0;
  // offset +- amplitude must stay inside the board's software joint limits, past which it
  // faults (firmware BoardConfig's defaults).
  double theta_min_rad = 0;
  double theta_max_rad = 0;
};
const CommandLimits& command_limits();

struct ValidationResult {
  bool ok = true;
  std::string reason;  // empty when ok; otherwise names the field and the range it broke
};

// Whether a command may be acted on: finite, enums valid, inside command_limits(). No DDS.
ValidationResult validate(const ForearmCommandSample& command);

// A Cyclone DDS configuration (XML) for loopback only: interface 127.0.0.1, no multicast,
// unicast discovery of participant indices 0..20 on 127.0.0.1. For tests, the HIL guest (whose
// lo has no multicast) and the programs' --dds-loopback.
std::string loopback_config();

// The host controller's side: publishes one board's state and telemetry, takes its commands.
// Every constructor below takes `config`: Cyclone DDS configuration XML (or file names, as in
// CYCLONEDDS_URI) for the domain; empty uses Cyclone's default (CYCLONEDDS_URI if set). All
// objects of one process on one domain share that domain: the first one's config applies, a
// different config later throws std::runtime_error, and so does any failure to create the
// participant, topics, writers or readers. Use each object from one thread at a time.
class ForearmDdsBridge {
 public:
  using CommandHandler = std::function<void(const ForearmCommandSample&)>;

  // std::invalid_argument for a node outside 0..proto::kMaxNodeId.
  ForearmDdsBridge(std::uint32_t domain_id, proto::NodeId node, const std::string& config = {});
  ~ForearmDdsBridge();
  ForearmDdsBridge(const ForearmDdsBridge&) = delete;
  ForearmDdsBridge& operator=(const ForearmDdsBridge&) = delete;

  // Written with this bridge's node, whatever sample.node says. False if DDS refused it.
  bool publish(const ForearmStateSample& state);
  bool publish(const ForearmTelemetrySample& telemetry);

  // Takes every pending command sample. Valid ones for this node go to handler, in arrival
  // order; the others are counted and logged to stderr, one line each with the reason.
  // Returns how many went to handler.
  std::size_t poll_commands(const CommandHandler& handler);

  std::uint64_t rejected_commands() const;
  proto::NodeId node() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The operator's side (hmpc-forearm-cli, tests): sends commands, receives every node's state
// and telemetry. It sends what it is given, unvalidated, so a test can send a malformed one.
class ForearmDdsClient {
 public:
  using StateHandler = std::function<void(const ForearmStateSample&)>;
  using TelemetryHandler = std::function<void(const ForearmTelemetrySample&)>;

  explicit ForearmDdsClient(std::uint32_t domain_id, const std::string& config = {});
  ~ForearmDdsClient();
  ForearmDdsClient(const ForearmDdsClient&) = delete;
  ForearmDdsClient& operator=(const ForearmDdsClient&) = delete;

  // Waits until a bridge's command reader has been discovered; false on timeout.
  bool wait_for_bridge(double timeout_s);
  // False if DDS refused the sample.
  bool send(const ForearmCommandSample& command);
  // Waits until every discovered bridge acknowledged what was sent; false on timeout.
  bool wait_for_delivery(double timeout_s);

  // Waits until state or telemetry is pending; false on timeout.
  bool wait_for_data(double timeout_s);
  // Take every pending sample; return how many went to handler.
  std::size_t poll_state(const StateHandler& handler);
  std::size_t poll_telemetry(const TelemetryHandler& handler);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace hmpc::dds
