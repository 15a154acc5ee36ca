// CAN protocol of the forearm actuator board: the one source of truth for frame ids, signal
// layouts, scaling, units and ranges, and the codec that uses them.
// common/protocol/hmpc_forearm.dbc describes the same frames for cantools or SavvyCAN;
// tests/unit/dbc_test.cpp keeps it in agreement with kFrames and kSignals below.
//
// Bus: classic CAN, 11-bit identifiers, every frame 8 data bytes.
//
// Identifiers: frame_id(type, node) = kBaseId + kNodeIdStride * node + FrameSpec::id_offset,
// node 0..15. Node 0 is 0x100..0x108 and node 15 is 0x1F0..0x1F8, so 0x000..0x0FF stays free
// for bus-wide frames that must win arbitration (an emergency stop, a time sync). Inside a
// node the order of the offsets is the priority: heartbeat, then the 1 kHz I/O loop, then
// the 250 Hz trajectory and telemetry, then gains.
//
// End-to-end protection, the same in every frame:
//   byte 0       checksum: CRC-8/AUTOSAR (polynomial 0x2F, initial value 0xFF, final XOR 0xFF,
//                not reflected; check value 0xDF for "123456789") over the identifier as two
//                bytes, little-endian, then data bytes 1..7. Covering the identifier means a
//                frame cannot be taken for another node's or another frame type's.
//   byte 1 [3:0] rolling counter 0..15, one sequence per frame type and sender (Sender below).
//                A receiver (CounterTracker) accepts the first counter it sees, then only
//                advances of 1..7 modulo 16: 0 is a repeated frame, 8..15 is an old or
//                reordered one. It must forget a frame type (CounterTracker::reset) when that
//                frame times out, so a restarted sender is heard again.
// Board->host frames carry the same protection, so the host can reject corrupt telemetry too.
//
// Signals are little-endian (Intel, DBC "@1"); start bits count from bit 0 of byte 0. Bits
// no signal covers are sent as zero and ignored on receipt (the checksum still covers them).
//
// Physical values are float: every scaled signal has at most 16 bits, which float holds
// exactly, and the same float arithmetic on the host, the HIL and a Cortex-M4 without a
// double-precision FPU produces the same frames bit for bit.
//
// Nothing here allocates, throws, calls virtual functions or prints.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string_view>
#include <type_traits>

namespace hmpc::forearm_protocol {

// ---------------------------------------------------------------------------------------
// Frame, nodes, identifiers

// A classic CAN data frame, independent of any operating system's CAN headers.
struct Frame {
  std::uint32_t id = 0;  // 11-bit standard identifier
  std::uint8_t dlc = 0;  // data length code, 0..8
  std::array<std::uint8_t, 8> data{};
};

using NodeId = std::uint8_t;
inline constexpr NodeId kMaxNodeId = 15;
inline constexpr std::uint32_t kBaseId = 0x100;
inline constexpr std::uint32_t kNodeIdStride = 0x10;

// The bus participants; the DBC's BU_ nodes.
enum class Endpoint : std::uint8_t { kHost, kBoard, kPlant };

constexpr const char* to_string(Endpoint endpoint) {
  switch (endpoint) {
    case Endpoint::kHost: return "HOST";
    case Endpoint::kBoard: return "BOARD";
    case Endpoint::kPlant: return "PLANT";
  }
  return "?";
}

enum class FrameType : std::uint8_t {
  kModeCommand,       // host -> board: heartbeat, requested mode and strategy
  kSensor,            // plant (HIL simulator) -> board: measured joint state
  kActuatorCommand,   // board -> plant: valve and motor voltages to apply
  kTrajectorySample,  // host -> board: one sample of the target joint angle
  kBoardStatus,       // board -> host: mode, fault bits, event counters
  kJointState,        // board -> host: the board's joint state
  kActuatorOutputs,   // board -> host: applied voltages and the torques they produce
  kSolveTelemetry,    // board -> host: MPC solve of the last control period
  kGains,             // host -> board: hold-mode PID gains
  kSync,              // plant (HIL simulator) -> board: lock-step clock tick
};
inline constexpr std::size_t kFrameTypeCount = 10;

struct FrameSpec {
  FrameType type;
  const char* name;        // DBC message name
  std::uint8_t id_offset;  // added to the node's base id
  std::uint8_t dlc;        // bytes
  Endpoint sender;
  Endpoint receiver;
  std::uint16_t cycle_time_ms;  // nominal period; 0: sent when the value changes
};

// clang-format off
inline constexpr FrameSpec kFrames[kFrameTypeCount] = {
  // type                          name                 offset dlc sender            receiver         period ms
  {FrameType::kModeCommand,      "ModeCommand",      0x0, 8, Endpoint::kHost,  Endpoint::kBoard,  10},
  {FrameType::kSensor,           "Sensor",           0x1, 8, Endpoint::kPlant, Endpoint::kBoard,   1},
  {FrameType::kActuatorCommand,  "ActuatorCommand",  0x2, 8, Endpoint::kBoard, Endpoint::kPlant,   1},
  {FrameType::kTrajectorySample, "TrajectorySample", 0x3, 8, Endpoint::kHost,  Endpoint::kBoard,   4},
  {FrameType::kBoardStatus,      "BoardStatus",      0x4, 8, Endpoint::kBoard, Endpoint::kHost,   10},
  {FrameType::kJointState,       "JointState",       0x5, 8, Endpoint::kBoard, Endpoint::kHost,    4},
  {FrameType::kActuatorOutputs,  "ActuatorOutputs",  0x6, 8, Endpoint::kBoard, Endpoint::kHost,    4},
  {FrameType::kSolveTelemetry,   "SolveTelemetry",   0x7, 8, Endpoint::kBoard, Endpoint::kHost,    4},
  {FrameType::kGains,            "Gains",            0x8, 8, Endpoint::kHost,  Endpoint::kBoard,   0},
  {FrameType::kSync,             "Sync",             0x9, 8, Endpoint::kPlant, Endpoint::kBoard,   1},
};
// clang-format on

constexpr std::size_t index_of(FrameType type) { return static_cast<std::size_t>(type); }
constexpr const FrameSpec& frame_spec(FrameType type) { return kFrames[index_of(type)]; }

// Precondition: node <= kMaxNodeId.
constexpr std::uint32_t frame_id(FrameType type, NodeId node) {
  return kBaseId + kNodeIdStride * node + frame_spec(type).id_offset;
}

// The frame type and node an identifier belongs to; false for identifiers of no frame here.
constexpr bool identify(std::uint32_t id, FrameType& type, NodeId& node) {
  if (id < kBaseId || id >= kBaseId + kNodeIdStride * (kMaxNodeId + 1)) return false;
  const std::uint32_t offset = (id - kBaseId) % kNodeIdStride;
  for (const FrameSpec& spec : kFrames) {
    if (spec.id_offset == offset) {
      type = spec.type;
      node = static_cast<NodeId>((id - kBaseId) / kNodeIdStride);
      return true;
    }
  }
  return false;
}

// ---------------------------------------------------------------------------------------
// Enumerated signal values

// Mode the host asks for. 0 is no request, so an all-zero payload never commands anything.
enum class RequestedMode : std::uint8_t { kIdle = 1, kHold = 2, kRun = 3 };

// Mode the board is in: boot -> idle (safe outputs) -> hold (PID) -> run (MPC), and fault.
enum class BoardMode : std::uint8_t { kBoot = 0, kIdle = 1, kHold = 2, kRun = 3, kFault = 4 };

// Control strategies of the thesis's Table 3.1.
enum class Strategy : std::uint8_t {
  kFine4ms = 0,     // Fine MPC, 4 ms, N = 50
  kFine8ms = 1,     // Fine MPC, 8 ms, N = 25
  kCoarse20ms = 2,  // Coarse MPC, 20 ms, N = 10
  kCoarse40ms = 3,  // Coarse MPC, 40 ms, N = 5
  kTwoStage = 4,    // coarse 20 ms N = 10, fine 4 ms N_f = 20
  kPamOnly = 5,     // PAM alone, motor off
};

// Outcome of the MPC solve. 0..5 have the values of hmpc::SolveStatus (solver/ilqr.hpp).
enum class SolveStatusCode : std::uint8_t {
  kConverged = 0,
  kIterationCap = 1,
  kBudgetExhausted = 2,
  kStalled = 3,
  kInvalidInput = 4,
  kNumericalFailure = 5,
  kNoSolve = 6,  // no MPC ran this period (board not in run)
};

// BoardStatus fault bits; a set bit stays set until a ModeCommand with clear_faults.
namespace fault {
inline constexpr std::uint8_t kHeartbeatTimeout = 1u << 0;  // no valid ModeCommand in time
inline constexpr std::uint8_t kSensorTimeout = 1u << 1;     // no valid sensor reading in time
inline constexpr std::uint8_t kSensorOutOfRange = 1u << 2;  // a reading outside its range
inline constexpr std::uint8_t kSolverFallback = 1u << 3;    // repeated solver failures: hold
inline constexpr std::uint8_t kOverrun = 1u << 4;           // a control step missed its deadline
inline constexpr std::uint8_t kBusError = 1u << 5;          // CAN error passive or bus-off
inline constexpr std::uint8_t kJointLimit = 1u << 6;        // theta beyond the software limit
inline constexpr std::uint8_t kInternal = 1u << 7;          // failed self-check (stack, config)
}  // namespace fault

struct EnumValue {
  std::uint32_t value;
  const char* name;  // DBC VAL_ description
};

inline constexpr EnumValue kRequestedModeValues[] = {{1, "idle"}, {2, "hold"}, {3, "run"}};
inline constexpr EnumValue kBoardModeValues[] = {
    {0, "boot"}, {1, "idle"}, {2, "hold"}, {3, "run"}, {4, "fault"}};
inline constexpr EnumValue kStrategyValues[] = {{0, "fine_4ms"},    {1, "fine_8ms"},
                                                {2, "coarse_20ms"}, {3, "coarse_40ms"},
                                                {4, "two_stage"},   {5, "pam_only"}};
inline constexpr EnumValue kSolveStatusValues[] = {
    {0, "converged"},     {1, "iteration_cap"},     {2, "budget_exhausted"}, {3, "stalled"},
    {4, "invalid_input"}, {5, "numerical_failure"}, {6, "no_solve"}};

// The DBC's name of an enumerated signal value (BoardMode, Strategy, ...), or "?".
template <std::size_t N>
constexpr const char* value_name(const EnumValue (&values)[N], std::uint32_t value) {
  for (const auto& v : values)
    if (v.value == value) return v.name;
  return "?";
}

// The value of an enumerated signal by its DBC name (as the programs' command lines take them);
// false for an unknown name.
template <std::size_t N>
constexpr bool value_of(const EnumValue (&values)[N], std::string_view name, std::uint32_t& out) {
  for (const auto& v : values) {
    if (name == v.name) {
      out = v.value;
      return true;
    }
  }
  return false;
}

struct EnumValueList {
  const EnumValue* values = nullptr;
  std::uint8_t count = 0;
};

template <std::size_t N>
constexpr EnumValueList values_of(const EnumValue (&values)[N]) {
  return {values, static_cast<std::uint8_t>(N)};
}

// ---------------------------------------------------------------------------------------
// Signals

enum class SignalKind : std::uint8_t {
  kChecksum,     // CRC-8 of the frame, computed by the codec
  kCounter,      // rolling counter 0..15
  kPhysical,     // scaled quantity: physical = raw * factor + offset, a float field
  kInteger,      // unscaled count, time or bit set, an unsigned integer field
  kMode,         // RequestedMode or BoardMode; other values decode as kUnknownMode
  kEnumeration,  // another enumeration; other values decode as kUnknownEnum
};

enum class ByteOrder : std::uint8_t { kLittleEndian };  // DBC "@1"; the only one used

// clang-format off
enum class Signal : std::uint8_t {
  kModeCommandChecksum, kModeCommandCounter, kModeCommandRequestedMode, kModeCommandStrategy,
  kModeCommandClearFaults, kModeCommandHostTime,
  kSensorChecksum, kSensorCounter, kSensorTheta, kSensorThetaDot, kSensorPressure,
  kActuatorCommandChecksum, kActuatorCommandCounter, kActuatorCommandVp, kActuatorCommandVm,
  kTrajectorySampleChecksum, kTrajectorySampleCounter, kTrajectorySampleThetaD,
  kTrajectorySampleTime,
  kBoardStatusChecksum, kBoardStatusCounter, kBoardStatusMode, kBoardStatusFaults,
  kBoardStatusStrategy, kBoardStatusRejectedFrames, kBoardStatusWatchdogTrips,
  kBoardStatusSolverFailures, kBoardStatusOverruns,
  kJointStateChecksum, kJointStateCounter, kJointStateTheta, kJointStateThetaDot,
  kJointStatePressure,
  kActuatorOutputsChecksum, kActuatorOutputsCounter, kActuatorOutputsVp, kActuatorOutputsVm,
  kActuatorOutputsTauP, kActuatorOutputsTauM,
  kSolveTelemetryChecksum, kSolveTelemetryCounter, kSolveTelemetryStatus,
  kSolveTelemetryCoarseIterations, kSolveTelemetryFineIterations, kSolveTelemetrySolveTime,
  kSolveTelemetryTrackingError,
  kGainsChecksum, kGainsCounter, kGainsKp, kGainsKi, kGainsKd, kGainsLoadVelocity,
  kSyncChecksum, kSyncCounter, kSyncTick,
};
// clang-format on
inline constexpr std::size_t kSignalCount = 55;

struct SignalSpec {
  Signal signal;
  FrameType frame;
  const char* name;  // DBC signal name, unique within its frame
  std::uint8_t start_bit;
  std::uint8_t length;  // bits
  ByteOrder byte_order;
  bool is_signed;  // two's complement
  double factor;
  double offset;
  double min;  // physical range; both ends lie on the raw grid
  double max;
  const char* unit;
  SignalKind kind;
  EnumValueList values;  // kMode and kEnumeration only
};

// Resolution is the factor. Ranges: theta [-pi, pi] rad (to the next grid step), theta_dot
// [-20, 20] rad/s, P [0, 0.8] MPa, v_p [0, 5] V, v_m [-5, 5] V (the thesis's input limits,
// Sec. 3.3), torques [-30, 30] N.m. ActuatorCommand carries the voltages at 16 bits since the
// plant applies them; ActuatorOutputs, telemetry that also needs both torques, at 12 bits (the
// resolution of a typical valve DAC). Gains: the hold-mode joint PID with load-velocity
// feedback (thesis Sec. 2.7.3), output = kp e + ki integral(e) + kd de/dt + k_lv theta_dot,
// e = theta_d - theta in rad, output a valve command in V.
// clang-format off
inline constexpr SignalSpec kSignals[kSignalCount] = {
  // signal                                  frame                          name                start len byte order                 signed factor   offset min      max         unit         kind                     values
  {Signal::kModeCommandChecksum,             FrameType::kModeCommand,      "checksum",          0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",          SignalKind::kChecksum,    {}},
  {Signal::kModeCommandCounter,              FrameType::kModeCommand,      "counter",           8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",          SignalKind::kCounter,     {}},
  {Signal::kModeCommandRequestedMode,        FrameType::kModeCommand,      "requested_mode",   12,  4, ByteOrder::kLittleEndian, false, 1,       0, 1,       3,          "",          SignalKind::kMode,        values_of(kRequestedModeValues)},
  {Signal::kModeCommandStrategy,             FrameType::kModeCommand,      "strategy",         16,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       5,          "",          SignalKind::kEnumeration, values_of(kStrategyValues)},
  {Signal::kModeCommandClearFaults,          FrameType::kModeCommand,      "clear_faults",     20,  1, ByteOrder::kLittleEndian, false, 1,       0, 0,       1,          "",          SignalKind::kInteger,     {}},
  {Signal::kModeCommandHostTime,             FrameType::kModeCommand,      "host_time",        32, 32, ByteOrder::kLittleEndian, false, 1,       0, 0,       4294967295, "us",        SignalKind::kInteger,     {}},

  {Signal::kSensorChecksum,                  FrameType::kSensor,           "checksum",          0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",          SignalKind::kChecksum,    {}},
  {Signal::kSensorCounter,                   FrameType::kSensor,           "counter",           8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",          SignalKind::kCounter,     {}},
  {Signal::kSensorTheta,                     FrameType::kSensor,           "theta",            16, 16, ByteOrder::kLittleEndian, true,  0.0001,  0, -3.1416, 3.1416,     "rad",       SignalKind::kPhysical,    {}},
  {Signal::kSensorThetaDot,                  FrameType::kSensor,           "theta_dot",        32, 16, ByteOrder::kLittleEndian, true,  0.001,   0, -20,     20,         "rad/s",     SignalKind::kPhysical,    {}},
  {Signal::kSensorPressure,                  FrameType::kSensor,           "pressure",         48, 16, ByteOrder::kLittleEndian, false, 0.00002, 0, 0,       0.8,        "MPa",       SignalKind::kPhysical,    {}},

  {Signal::kActuatorCommandChecksum,         FrameType::kActuatorCommand,  "checksum",          0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",          SignalKind::kChecksum,    {}},
  {Signal::kActuatorCommandCounter,          FrameType::kActuatorCommand,  "counter",           8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",          SignalKind::kCounter,     {}},
  {Signal::kActuatorCommandVp,               FrameType::kActuatorCommand,  "v_p",              16, 16, ByteOrder::kLittleEndian, false, 0.0001,  0, 0,       5,          "V",         SignalKind::kPhysical,    {}},
  {Signal::kActuatorCommandVm,               FrameType::kActuatorCommand,  "v_m",              32, 16, ByteOrder::kLittleEndian, true,  0.0002,  0, -5,      5,          "V",         SignalKind::kPhysical,    {}},

  {Signal::kTrajectorySampleChecksum,        FrameType::kTrajectorySample, "checksum",          0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",          SignalKind::kChecksum,    {}},
  {Signal::kTrajectorySampleCounter,         FrameType::kTrajectorySample, "counter",           8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",          SignalKind::kCounter,     {}},
  {Signal::kTrajectorySampleThetaD,          FrameType::kTrajectorySample, "theta_d",          16, 16, ByteOrder::kLittleEndian, true,  0.0001,  0, -3.1416, 3.1416,     "rad",       SignalKind::kPhysical,    {}},
  {Signal::kTrajectorySampleTime,            FrameType::kTrajectorySample, "time",             32, 32, ByteOrder::kLittleEndian, false, 1,       0, 0,       4294967295, "us",        SignalKind::kInteger,     {}},

  {Signal::kBoardStatusChecksum,             FrameType::kBoardStatus,      "checksum",          0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",          SignalKind::kChecksum,    {}},
  {Signal::kBoardStatusCounter,              FrameType::kBoardStatus,      "counter",           8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",          SignalKind::kCounter,     {}},
  {Signal::kBoardStatusMode,                 FrameType::kBoardStatus,      "mode",             12,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       4,          "",          SignalKind::kMode,        values_of(kBoardModeValues)},
  {Signal::kBoardStatusFaults,               FrameType::kBoardStatus,      "faults",           16,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",          SignalKind::kInteger,     {}},
  {Signal::kBoardStatusStrategy,             FrameType::kBoardStatus,      "strategy",         24,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       5,          "",          SignalKind::kEnumeration, values_of(kStrategyValues)},
  {Signal::kBoardStatusRejectedFrames,       FrameType::kBoardStatus,      "rejected_frames",  32,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",          SignalKind::kInteger,     {}},
  {Signal::kBoardStatusWatchdogTrips,        FrameType::kBoardStatus,      "watchdog_trips",   40,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",          SignalKind::kInteger,     {}},
  {Signal::kBoardStatusSolverFailures,       FrameType::kBoardStatus,      "solver_failures",  48,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",          SignalKind::kInteger,     {}},
  {Signal::kBoardStatusOverruns,             FrameType::kBoardStatus,      "overruns",         56,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",          SignalKind::kInteger,     {}},

  {Signal::kJointStateChecksum,              FrameType::kJointState,       "checksum",          0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",          SignalKind::kChecksum,    {}},
  {Signal::kJointStateCounter,               FrameType::kJointState,       "counter",           8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",          SignalKind::kCounter,     {}},
  {Signal::kJointStateTheta,                 FrameType::kJointState,       "theta",            16, 16, ByteOrder::kLittleEndian, true,  0.0001,  0, -3.1416, 3.1416,     "rad",       SignalKind::kPhysical,    {}},
  {Signal::kJointStateThetaDot,              FrameType::kJointState,       "theta_dot",        32, 16, ByteOrder::kLittleEndian, true,  0.001,   0, -20,     20,         "rad/s",     SignalKind::kPhysical,    {}},
  {Signal::kJointStatePressure,              FrameType::kJointState,       "pressure",         48, 16, ByteOrder::kLittleEndian, false, 0.00002, 0, 0,       0.8,        "MPa",       SignalKind::kPhysical,    {}},

  {Signal::kActuatorOutputsChecksum,         FrameType::kActuatorOutputs,  "checksum",          0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",          SignalKind::kChecksum,    {}},
  {Signal::kActuatorOutputsCounter,          FrameType::kActuatorOutputs,  "counter",           8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",          SignalKind::kCounter,     {}},
  {Signal::kActuatorOutputsVp,               FrameType::kActuatorOutputs,  "v_p",              12, 12, ByteOrder::kLittleEndian, false, 0.002,   0, 0,       5,          "V",         SignalKind::kPhysical,    {}},
  {Signal::kActuatorOutputsVm,               FrameType::kActuatorOutputs,  "v_m",              24, 12, ByteOrder::kLittleEndian, true,  0.0025,  0, -5,      5,          "V",         SignalKind::kPhysical,    {}},
  {Signal::kActuatorOutputsTauP,             FrameType::kActuatorOutputs,  "tau_p",            36, 14, ByteOrder::kLittleEndian, true,  0.004,   0, -30,     30,         "N.m",       SignalKind::kPhysical,    {}},
  {Signal::kActuatorOutputsTauM,             FrameType::kActuatorOutputs,  "tau_m",            50, 14, ByteOrder::kLittleEndian, true,  0.004,   0, -30,     30,         "N.m",       SignalKind::kPhysical,    {}},

  {Signal::kSolveTelemetryChecksum,          FrameType::kSolveTelemetry,   "checksum",          0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",          SignalKind::kChecksum,    {}},
  {Signal::kSolveTelemetryCounter,           FrameType::kSolveTelemetry,   "counter",           8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",          SignalKind::kCounter,     {}},
  {Signal::kSolveTelemetryStatus,            FrameType::kSolveTelemetry,   "solve_status",     12,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       6,          "",          SignalKind::kEnumeration, values_of(kSolveStatusValues)},
  {Signal::kSolveTelemetryCoarseIterations,  FrameType::kSolveTelemetry,   "coarse_iterations",16,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",          SignalKind::kInteger,     {}},
  {Signal::kSolveTelemetryFineIterations,    FrameType::kSolveTelemetry,   "fine_iterations",  24,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",          SignalKind::kInteger,     {}},
  {Signal::kSolveTelemetrySolveTime,         FrameType::kSolveTelemetry,   "solve_time",       32, 16, ByteOrder::kLittleEndian, false, 1,       0, 0,       65535,      "us",        SignalKind::kInteger,     {}},
  {Signal::kSolveTelemetryTrackingError,     FrameType::kSolveTelemetry,   "tracking_error",   48, 16, ByteOrder::kLittleEndian, true,  0.0002,  0, -6.2832, 6.2832,     "rad",       SignalKind::kPhysical,    {}},

  {Signal::kGainsChecksum,                   FrameType::kGains,            "checksum",          0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",          SignalKind::kChecksum,    {}},
  {Signal::kGainsCounter,                    FrameType::kGains,            "counter",           8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",          SignalKind::kCounter,     {}},
  {Signal::kGainsKp,                         FrameType::kGains,            "kp",               12, 12, ByteOrder::kLittleEndian, false, 0.05,    0, 0,       200,        "V/rad",     SignalKind::kPhysical,    {}},
  {Signal::kGainsKi,                         FrameType::kGains,            "ki",               24, 12, ByteOrder::kLittleEndian, false, 0.1,     0, 0,       400,        "V/(rad.s)", SignalKind::kPhysical,    {}},
  {Signal::kGainsKd,                         FrameType::kGains,            "kd",               36, 12, ByteOrder::kLittleEndian, false, 0.005,   0, 0,       20,         "V.s/rad",   SignalKind::kPhysical,    {}},
  {Signal::kGainsLoadVelocity,               FrameType::kGains,            "k_lv",             48, 12, ByteOrder::kLittleEndian, true,  0.001,   0, -2,      2,          "V.s/rad",   SignalKind::kPhysical,    {}},

  {Signal::kSyncChecksum,                    FrameType::kSync,             "checksum",          0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",          SignalKind::kChecksum,    {}},
  {Signal::kSyncCounter,                     FrameType::kSync,             "counter",           8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",          SignalKind::kCounter,     {}},
  {Signal::kSyncTick,                        FrameType::kSync,             "tick",             32, 32, ByteOrder::kLittleEndian, false, 1,       0, 0,       4294967295, "ms",        SignalKind::kInteger,     {}},
};
// clang-format on

constexpr std::size_t index_of(Signal signal) { return static_cast<std::size_t>(signal); }
constexpr const SignalSpec& signal_spec(Signal signal) { return kSignals[index_of(signal)]; }

// Half away from zero. Not std::lround, which is not constexpr; the one number it rounds
// otherwise (0.5 less an ulp, which + 0.5 carries to 1) is immaterial at a signal's resolution.
constexpr std::int64_t round_half_away(double x) {
  // NOLINTNEXTLINE(bugprone-incorrect-roundings)
  return x < 0 ? -static_cast<std::int64_t>(-x + 0.5) : static_cast<std::int64_t>(x + 0.5);
}
// Raw value of a physical value that lies on the signal's grid.
constexpr std::int64_t raw_of(const SignalSpec& spec, double physical) {
  return round_half_away((physical - spec.offset) / spec.factor);
}
constexpr std::int64_t raw_min(const SignalSpec& spec) { return raw_of(spec, spec.min); }
constexpr std::int64_t raw_max(const SignalSpec& spec) { return raw_of(spec, spec.max); }

// ---------------------------------------------------------------------------------------
// Messages: one plain struct per frame. visit() names the signal of every field; the codec,
// and the compile-time check that each struct covers exactly its frame's signals, use it.

struct ModeCommand {
  static constexpr FrameType kType = FrameType::kModeCommand;
  RequestedMode mode = RequestedMode::kIdle;
  Strategy strategy = Strategy::kTwoStage;
  bool clear_faults = false;       // clear latched fault bits (the board honours it in idle)
  std::uint32_t host_time_us = 0;  // host trajectory clock, us modulo 2^32
  std::uint8_t counter = 0;
  template <class Self, class Visitor>
  static constexpr void visit(Self& self, Visitor&& visitor) {
    visitor(Signal::kModeCommandCounter, self.counter);
    visitor(Signal::kModeCommandRequestedMode, self.mode);
    visitor(Signal::kModeCommandStrategy, self.strategy);
    visitor(Signal::kModeCommandClearFaults, self.clear_faults);
    visitor(Signal::kModeCommandHostTime, self.host_time_us);
  }
};

struct SensorSample {
  static constexpr FrameType kType = FrameType::kSensor;
  float theta = 0;      // rad
  float theta_dot = 0;  // rad/s
  float pressure = 0;   // MPa, PAM gauge pressure
  std::uint8_t counter = 0;
  template <class Self, class Visitor>
  static constexpr void visit(Self& self, Visitor&& visitor) {
    visitor(Signal::kSensorCounter, self.counter);
    visitor(Signal::kSensorTheta, self.theta);
    visitor(Signal::kSensorThetaDot, self.theta_dot);
    visitor(Signal::kSensorPressure, self.pressure);
  }
};

struct ActuatorCommand {
  static constexpr FrameType kType = FrameType::kActuatorCommand;
  float v_p = 0;  // V, PAM valve
  float v_m = 0;  // V, motor
  std::uint8_t counter = 0;
  template <class Self, class Visitor>
  static constexpr void visit(Self& self, Visitor&& visitor) {
    visitor(Signal::kActuatorCommandCounter, self.counter);
    visitor(Signal::kActuatorCommandVp, self.v_p);
    visitor(Signal::kActuatorCommandVm, self.v_m);
  }
};

// The board keeps a short queue of samples ahead of time to fill the MPC horizon; it maps
// time_us onto its own clock through ModeCommand::host_time_us.
struct TrajectorySample {
  static constexpr FrameType kType = FrameType::kTrajectorySample;
  float theta_d = 0;          // rad
  std::uint32_t time_us = 0;  // host trajectory clock, us modulo 2^32 (wraps after 71.6 min)
  std::uint8_t counter = 0;
  template <class Self, class Visitor>
  static constexpr void visit(Self& self, Visitor&& visitor) {
    visitor(Signal::kTrajectorySampleCounter, self.counter);
    visitor(Signal::kTrajectorySampleThetaD, self.theta_d);
    visitor(Signal::kTrajectorySampleTime, self.time_us);
  }
};

// Event counters count modulo 256; the host takes differences.
struct BoardStatus {
  static constexpr FrameType kType = FrameType::kBoardStatus;
  BoardMode mode = BoardMode::kBoot;
  std::uint8_t faults = 0;  // fault:: bits
  Strategy strategy = Strategy::kTwoStage;
  std::uint8_t rejected_frames = 0;  // RejectCounters::total()
  std::uint8_t watchdog_trips = 0;
  std::uint8_t solver_failures = 0;
  std::uint8_t overruns = 0;
  std::uint8_t counter = 0;
  template <class Self, class Visitor>
  static constexpr void visit(Self& self, Visitor&& visitor) {
    visitor(Signal::kBoardStatusCounter, self.counter);
    visitor(Signal::kBoardStatusMode, self.mode);
    visitor(Signal::kBoardStatusFaults, self.faults);
    visitor(Signal::kBoardStatusStrategy, self.strategy);
    visitor(Signal::kBoardStatusRejectedFrames, self.rejected_frames);
    visitor(Signal::kBoardStatusWatchdogTrips, self.watchdog_trips);
    visitor(Signal::kBoardStatusSolverFailures, self.solver_failures);
    visitor(Signal::kBoardStatusOverruns, self.overruns);
  }
};

struct JointState {
  static constexpr FrameType kType = FrameType::kJointState;
  float theta = 0;      // rad
  float theta_dot = 0;  // rad/s
  float pressure = 0;   // MPa
  std::uint8_t counter = 0;
  template <class Self, class Visitor>
  static constexpr void visit(Self& self, Visitor&& visitor) {
    visitor(Signal::kJointStateCounter, self.counter);
    visitor(Signal::kJointStateTheta, self.theta);
    visitor(Signal::kJointStateThetaDot, self.theta_dot);
    visitor(Signal::kJointStatePressure, self.pressure);
  }
};

struct ActuatorOutputs {
  static constexpr FrameType kType = FrameType::kActuatorOutputs;
  float v_p = 0;    // V
  float v_m = 0;    // V
  float tau_p = 0;  // N.m, PAM torque on the joint
  float tau_m = 0;  // N.m, motor torque on the joint
  std::uint8_t counter = 0;
  template <class Self, class Visitor>
  static constexpr void visit(Self& self, Visitor&& visitor) {
    visitor(Signal::kActuatorOutputsCounter, self.counter);
    visitor(Signal::kActuatorOutputsVp, self.v_p);
    visitor(Signal::kActuatorOutputsVm, self.v_m);
    visitor(Signal::kActuatorOutputsTauP, self.tau_p);
    visitor(Signal::kActuatorOutputsTauM, self.tau_m);
  }
};

struct SolveTelemetry {
  static constexpr FrameType kType = FrameType::kSolveTelemetry;
  SolveStatusCode status = SolveStatusCode::kNoSolve;  // the worse of the stages
  std::uint8_t coarse_iterations = 0;  // also the only stage of single-stage strategies
  std::uint8_t fine_iterations = 0;
  std::uint16_t solve_time_us = 0;  // us, both stages; saturate at 65535
  float tracking_error = 0;         // rad, theta_d - theta
  std::uint8_t counter = 0;
  template <class Self, class Visitor>
  static constexpr void visit(Self& self, Visitor&& visitor) {
    visitor(Signal::kSolveTelemetryCounter, self.counter);
    visitor(Signal::kSolveTelemetryStatus, self.status);
    visitor(Signal::kSolveTelemetryCoarseIterations, self.coarse_iterations);
    visitor(Signal::kSolveTelemetryFineIterations, self.fine_iterations);
    visitor(Signal::kSolveTelemetrySolveTime, self.solve_time_us);
    visitor(Signal::kSolveTelemetryTrackingError, self.tracking_error);
  }
};

struct Gains {
  static constexpr FrameType kType = FrameType::kGains;
  float kp = 0;    // V/rad
  float ki = 0;    // V/(rad s)
  float kd = 0;    // V s/rad
  float k_lv = 0;  // V s/rad, load-velocity feedback
  std::uint8_t counter = 0;
  template <class Self, class Visitor>
  static constexpr void visit(Self& self, Visitor&& visitor) {
    visitor(Signal::kGainsCounter, self.counter);
    visitor(Signal::kGainsKp, self.kp);
    visitor(Signal::kGainsKi, self.ki);
    visitor(Signal::kGainsKd, self.kd);
    visitor(Signal::kGainsLoadVelocity, self.k_lv);
  }
};

// HIL lock-step clock (absent on the real robot, where the board's own timer ticks): one
// frame per simulated millisecond, sent after that millisecond's Sensor frame. A board in
// lock-step runs one tick per valid Sync, so it keeps time even when sensor frames are lost,
// like a board with its own crystal, while the simulation waits for it. (The same role as
// CANopen's SYNC object.)
struct Sync {
  static constexpr FrameType kType = FrameType::kSync;
  std::uint32_t tick = 0;  // simulated milliseconds since the plant started, modulo 2^32
  std::uint8_t counter = 0;
  template <class Self, class Visitor>
  static constexpr void visit(Self& self, Visitor&& visitor) {
    visitor(Signal::kSyncCounter, self.counter);
    visitor(Signal::kSyncTick, self.tick);
  }
};

// ---------------------------------------------------------------------------------------
// Results

enum class EncodeResult : std::uint8_t {
  kOk,
  kInvalidNode,  // node id above kMaxNodeId
  kNotFinite,    // a physical value is NaN or infinite
  kOutOfRange,   // a value outside its signal's [min, max], or a counter above 15
  kUnknownMode,  // a mode value with no meaning in this frame
  kUnknownEnum,  // a strategy or solve status value with no meaning
};

// Decoded values come from integers, so they are always finite: kNotFinite is encode-only.
enum class DecodeResult : std::uint8_t {
  kOk,
  kWrongId,       // not this frame type of this node
  kWrongLength,   // DLC is not the frame's
  kBadChecksum,   // CRC-8 mismatch: corrupt frame
  kStaleCounter,  // rolling counter repeated or gone backwards
  kOutOfRange,    // a raw value outside its signal's range
  kUnknownMode,   // a mode value with no meaning in this frame
  kUnknownEnum,   // a strategy or solve status value with no meaning
};

constexpr const char* to_string(EncodeResult result) {
  switch (result) {
    case EncodeResult::kOk: return "ok";
    case EncodeResult::kInvalidNode: return "invalid-node";
    case EncodeResult::kNotFinite: return "not-finite";
    case EncodeResult::kOutOfRange: return "out-of-range";
    case EncodeResult::kUnknownMode: return "unknown-mode";
    case EncodeResult::kUnknownEnum: return "unknown-enum";
  }
  return "?";
}

constexpr const char* to_string(DecodeResult result) {
  switch (result) {
    case DecodeResult::kOk: return "ok";
    case DecodeResult::kWrongId: return "wrong-id";
    case DecodeResult::kWrongLength: return "wrong-length";
    case DecodeResult::kBadChecksum: return "bad-checksum";
    case DecodeResult::kStaleCounter: return "stale-counter";
    case DecodeResult::kOutOfRange: return "out-of-range";
    case DecodeResult::kUnknownMode: return "unknown-mode";
    case DecodeResult::kUnknownEnum: return "unknown-enum";
  }
  return "?";
}

// ---------------------------------------------------------------------------------------
// Checksum

inline constexpr std::size_t kChecksumByte = 0;

constexpr std::uint8_t crc8_autosar_update(std::uint8_t crc, std::uint8_t byte) {
  crc = static_cast<std::uint8_t>(crc ^ byte);
  for (int bit = 0; bit < 8; ++bit) {
    const unsigned shifted = static_cast<unsigned>(crc) << 1;
    crc = static_cast<std::uint8_t>((crc & 0x80u) ? shifted ^ 0x2Fu : shifted);
  }
  return crc;
}

constexpr std::uint8_t crc8_autosar(const std::uint8_t* bytes, std::size_t count) {
  std::uint8_t crc = 0xFF;
  for (std::size_t i = 0; i < count; ++i) crc = crc8_autosar_update(crc, bytes[i]);
  return static_cast<std::uint8_t>(crc ^ 0xFFu);
}

// The checksum a frame must carry in byte kChecksumByte (over its id and the other bytes).
constexpr std::uint8_t frame_checksum(const Frame& frame) {
  std::uint8_t crc = 0xFF;
  crc = crc8_autosar_update(crc, static_cast<std::uint8_t>(frame.id & 0xFFu));
  crc = crc8_autosar_update(crc, static_cast<std::uint8_t>((frame.id >> 8) & 0xFFu));
  for (std::size_t i = 0; i < frame.data.size(); ++i) {
    if (i != kChecksumByte) crc = crc8_autosar_update(crc, frame.data[i]);
  }
  return static_cast<std::uint8_t>(crc ^ 0xFFu);
}

// ---------------------------------------------------------------------------------------
// Codec internals

namespace detail {

constexpr std::uint64_t low_bits(unsigned length) {
  return length >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << length) - 1;
}

constexpr std::uint64_t bits_of(const SignalSpec& spec) {
  return low_bits(spec.length) << spec.start_bit;
}

// The table in the form the codec uses at run time: float scaling, so no double arithmetic
// reaches a single-precision FPU.
struct CodecSpec {
  std::uint8_t start_bit = 0;
  std::uint8_t length = 0;
  bool is_signed = false;
  SignalKind kind = SignalKind::kInteger;
  float factor = 1;
  float offset = 0;
  float min = 0;
  float max = 0;
  std::int64_t raw_min = 0;
  std::int64_t raw_max = 0;
  EnumValueList values;
};

constexpr std::array<CodecSpec, kSignalCount> make_codec_specs() {
  std::array<CodecSpec, kSignalCount> specs{};
  for (std::size_t i = 0; i < kSignalCount; ++i) {
    const SignalSpec& s = kSignals[i];
    specs[i] = CodecSpec{s.start_bit,
                         s.length,
                         s.is_signed,
                         s.kind,
                         static_cast<float>(s.factor),
                         static_cast<float>(s.offset),
                         static_cast<float>(s.min),
                         static_cast<float>(s.max),
                         raw_min(s),
                         raw_max(s),
                         s.values};
  }
  return specs;
}
inline constexpr std::array<CodecSpec, kSignalCount> kCodecSpecs = make_codec_specs();

constexpr std::uint64_t payload_of(const Frame& frame) {
  std::uint64_t payload = 0;
  for (std::size_t i = 0; i < frame.data.size(); ++i) {
    payload |= static_cast<std::uint64_t>(frame.data[i]) << (8 * i);
  }
  return payload;
}

constexpr std::int64_t extract_raw(std::uint64_t payload, const CodecSpec& spec) {
  const std::uint64_t bits = (payload >> spec.start_bit) & low_bits(spec.length);
  const bool negative = spec.is_signed && ((bits >> (spec.length - 1)) & 1u);
  return negative ? static_cast<std::int64_t>(bits) -
                        static_cast<std::int64_t>(std::uint64_t{1} << spec.length)
                  : static_cast<std::int64_t>(bits);
}

constexpr void insert_raw(std::uint64_t& payload, const CodecSpec& spec, std::int64_t raw) {
  payload |= (static_cast<std::uint64_t>(raw) & low_bits(spec.length)) << spec.start_bit;
}

enum class Violation : std::uint8_t { kNone, kOutOfRange, kUnknownMode, kUnknownEnum };

constexpr Violation check_integer(const CodecSpec& spec, std::int64_t raw) {
  if (spec.kind == SignalKind::kMode || spec.kind == SignalKind::kEnumeration) {
    for (std::uint8_t i = 0; i < spec.values.count; ++i) {
      if (static_cast<std::int64_t>(spec.values.values[i].value) == raw) return Violation::kNone;
    }
    return spec.kind == SignalKind::kMode ? Violation::kUnknownMode : Violation::kUnknownEnum;
  }
  return raw < spec.raw_min || raw > spec.raw_max ? Violation::kOutOfRange : Violation::kNone;
}

constexpr EncodeResult to_encode_result(Violation violation) {
  switch (violation) {
    case Violation::kNone: return EncodeResult::kOk;
    case Violation::kOutOfRange: return EncodeResult::kOutOfRange;
    case Violation::kUnknownMode: return EncodeResult::kUnknownMode;
    case Violation::kUnknownEnum: return EncodeResult::kUnknownEnum;
  }
  return EncodeResult::kOutOfRange;
}

constexpr DecodeResult to_decode_result(Violation violation) {
  switch (violation) {
    case Violation::kNone: return DecodeResult::kOk;
    case Violation::kOutOfRange: return DecodeResult::kOutOfRange;
    case Violation::kUnknownMode: return DecodeResult::kUnknownMode;
    case Violation::kUnknownEnum: return DecodeResult::kUnknownEnum;
  }
  return DecodeResult::kOutOfRange;
}

template <class T>
constexpr std::int64_t integer_value(T value) {
  if constexpr (std::is_enum_v<T>) {
    return static_cast<std::int64_t>(static_cast<std::underlying_type_t<T>>(value));
  } else {
    return static_cast<std::int64_t>(value);
  }
}

// Rounds half away from zero; the caller has bounded x to the signal's raw range, which
// has at most 24 bits for physical signals, so int32 holds it.
// round_half_away's rounding in float, for the encoder on a single-precision board.
inline std::int32_t round_float(float x) {
  // NOLINTNEXTLINE(bugprone-incorrect-roundings)
  return x < 0 ? -static_cast<std::int32_t>(-x + 0.5f) : static_cast<std::int32_t>(x + 0.5f);
}

struct SignalWriter {
  std::uint64_t payload = 0;
  EncodeResult result = EncodeResult::kOk;

  void operator()(Signal signal, float value) {
    if (result != EncodeResult::kOk) return;
    const CodecSpec& spec = kCodecSpecs[index_of(signal)];
    if (!std::isfinite(value)) {
      result = EncodeResult::kNotFinite;
      return;
    }
    if (value < spec.min || value > spec.max) {
      result = EncodeResult::kOutOfRange;
      return;
    }
    std::int64_t raw = round_float((value - spec.offset) / spec.factor);
    // Float rounding next to a range end must not step off the raw range.
    raw = raw < spec.raw_min ? spec.raw_min : raw > spec.raw_max ? spec.raw_max : raw;
    insert_raw(payload, spec, raw);
  }

  template <class T, std::enable_if_t<!std::is_floating_point_v<T>, int> = 0>
  void operator()(Signal signal, T value) {
    if (result != EncodeResult::kOk) return;
    const CodecSpec& spec = kCodecSpecs[index_of(signal)];
    const std::int64_t raw = integer_value(value);
    result = to_encode_result(check_integer(spec, raw));
    if (result == EncodeResult::kOk) insert_raw(payload, spec, raw);
  }
};

struct SignalReader {
  std::uint64_t payload = 0;
  DecodeResult result = DecodeResult::kOk;

  void operator()(Signal signal, float& value) {
    if (result != DecodeResult::kOk) return;
    const CodecSpec& spec = kCodecSpecs[index_of(signal)];
    const std::int64_t raw = extract_raw(payload, spec);
    if (raw < spec.raw_min || raw > spec.raw_max) {
      result = DecodeResult::kOutOfRange;
      return;
    }
    const float physical = static_cast<float>(raw) * spec.factor + spec.offset;
    // Float rounding at a range end must not step outside [min, max] either.
    value = physical < spec.min ? spec.min : physical > spec.max ? spec.max : physical;
  }

  template <class T, std::enable_if_t<!std::is_floating_point_v<T>, int> = 0>
  void operator()(Signal signal, T& value) {
    if (result != DecodeResult::kOk) return;
    const CodecSpec& spec = kCodecSpecs[index_of(signal)];
    const std::int64_t raw = extract_raw(payload, spec);
    result = to_decode_result(check_integer(spec, raw));
    if (result == DecodeResult::kOk) value = static_cast<T>(raw);
  }
};

// ---------------------------------------------------------------------------------------
// Compile-time checks of the table and of every message's visit().

constexpr bool signals_are_indexed() {
  for (std::size_t i = 0; i < kSignalCount; ++i) {
    if (index_of(kSignals[i].signal) != i) return false;
  }
  return true;
}

constexpr bool frames_are_indexed_with_distinct_offsets() {
  for (std::size_t i = 0; i < kFrameTypeCount; ++i) {
    if (index_of(kFrames[i].type) != i || kFrames[i].id_offset >= kNodeIdStride) return false;
    if (kFrames[i].dlc != 8) return false;
    for (std::size_t j = 0; j < i; ++j) {
      if (kFrames[j].id_offset == kFrames[i].id_offset) return false;
    }
  }
  return true;
}

constexpr double magnitude(double x) { return x < 0 ? -x : x; }

constexpr bool on_grid(const SignalSpec& s, double physical) {
  const double back = static_cast<double>(raw_of(s, physical)) * s.factor + s.offset;
  return magnitude(back - physical) <= 1e-9 * (magnitude(physical) > 1 ? magnitude(physical) : 1);
}

constexpr bool signal_is_well_formed(const SignalSpec& s) {
  if (s.byte_order != ByteOrder::kLittleEndian) return false;
  if (s.length < 1 || s.length > 32 || s.start_bit + s.length > 8 * frame_spec(s.frame).dlc) {
    return false;
  }
  if (!(s.factor > 0) || s.min > s.max || !on_grid(s, s.min) || !on_grid(s, s.max)) return false;
  const std::int64_t lowest = s.is_signed ? -(std::int64_t{1} << (s.length - 1)) : 0;
  const std::int64_t highest =
      s.is_signed ? (std::int64_t{1} << (s.length - 1)) - 1 : (std::int64_t{1} << s.length) - 1;
  if (raw_min(s) < lowest || raw_max(s) > highest) return false;
  const bool integer_kind = s.kind != SignalKind::kPhysical;
  // Integer kinds are unscaled and unsigned; physical ones fit a float mantissa exactly.
  if (integer_kind && (s.is_signed || s.factor != 1 || s.offset != 0)) return false;
  if (!integer_kind && s.length > 24) return false;
  const bool enumerated = s.kind == SignalKind::kMode || s.kind == SignalKind::kEnumeration;
  if (enumerated != (s.values.count > 0)) return false;
  for (std::uint8_t i = 0; i < s.values.count; ++i) {
    const double v = s.values.values[i].value;
    if (v < s.min || v > s.max) return false;
  }
  if (s.kind == SignalKind::kChecksum) {
    return s.start_bit == 8 * kChecksumByte && s.length == 8;
  }
  if (s.kind == SignalKind::kCounter) return s.length == 4 && s.min == 0 && s.max == 15;
  return true;
}

constexpr bool signals_are_well_formed() {
  for (const SignalSpec& s : kSignals) {
    if (!signal_is_well_formed(s)) return false;
  }
  return true;
}

// Per frame: no two signals share a bit, one checksum, one counter.
constexpr bool frames_are_well_formed() {
  for (const FrameSpec& frame : kFrames) {
    std::uint64_t used = 0;
    int checksums = 0;
    int counters = 0;
    for (const SignalSpec& s : kSignals) {
      if (s.frame != frame.type) continue;
      if (used & bits_of(s)) return false;
      used |= bits_of(s);
      checksums += s.kind == SignalKind::kChecksum;
      counters += s.kind == SignalKind::kCounter;
    }
    if (checksums != 1 || counters != 1) return false;
  }
  return true;
}

// Signals a message's visit() must name: all of its frame's but the checksum.
constexpr std::uint64_t visited_signals_of(FrameType type) {
  std::uint64_t mask = 0;
  for (const SignalSpec& s : kSignals) {
    if (s.frame == type && s.kind != SignalKind::kChecksum) {
      mask |= std::uint64_t{1} << index_of(s.signal);
    }
  }
  return mask;
}

// Records what visit() names and whether each field's type suits its signal.
struct VisitAudit {
  std::uint64_t visited = 0;
  bool consistent = true;

  constexpr void note(Signal signal) {
    const std::uint64_t bit = std::uint64_t{1} << index_of(signal);
    if (visited & bit) consistent = false;
    visited |= bit;
  }
  constexpr void operator()(Signal signal, float&) {
    note(signal);
    if (signal_spec(signal).kind != SignalKind::kPhysical) consistent = false;
  }
  template <class T, std::enable_if_t<!std::is_floating_point_v<T>, int> = 0>
  constexpr void operator()(Signal signal, T&) {
    note(signal);
    const SignalSpec& s = signal_spec(signal);
    using Stored = typename std::conditional_t<std::is_enum_v<T>, std::underlying_type<T>,
                                               std::common_type<T>>::type;
    if (s.kind == SignalKind::kPhysical || s.kind == SignalKind::kChecksum) consistent = false;
    if (static_cast<double>(std::numeric_limits<Stored>::max()) < s.max) consistent = false;
  }
};

template <class Message>
constexpr bool visits_exactly_its_signals() {
  Message message{};
  VisitAudit audit{};
  Message::visit(message, audit);
  return audit.consistent && audit.visited == visited_signals_of(Message::kType);
}

}  // namespace detail

static_assert(kSignalCount <= 64, "visit audits keep one bit per signal");
static_assert(detail::signals_are_indexed(), "kSignals[i].signal must be Signal(i)");
static_assert(detail::frames_are_indexed_with_distinct_offsets(),
              "kFrames[i].type must be FrameType(i), offsets distinct and below the stride");
static_assert(detail::signals_are_well_formed(), "a signal does not fit its frame or range");
static_assert(detail::frames_are_well_formed(), "signals overlap, or checksum/counter missing");
static_assert(kBaseId + kNodeIdStride * (kMaxNodeId + 1) <= 0x800, "11-bit identifiers");
static_assert(detail::visits_exactly_its_signals<ModeCommand>());
static_assert(detail::visits_exactly_its_signals<SensorSample>());
static_assert(detail::visits_exactly_its_signals<ActuatorCommand>());
static_assert(detail::visits_exactly_its_signals<TrajectorySample>());
static_assert(detail::visits_exactly_its_signals<BoardStatus>());
static_assert(detail::visits_exactly_its_signals<JointState>());
static_assert(detail::visits_exactly_its_signals<ActuatorOutputs>());
static_assert(detail::visits_exactly_its_signals<SolveTelemetry>());
static_assert(detail::visits_exactly_its_signals<Gains>());
static_assert(detail::visits_exactly_its_signals<Sync>());

// ---------------------------------------------------------------------------------------
// Codec

// Encodes msg for node into out, counter included, checksum computed. On any error out is
// left untouched.
template <class Message>
EncodeResult encode(const Message& msg, NodeId node, Frame& out) {
  static_assert(detail::visits_exactly_its_signals<Message>(), "not a message of this protocol");
  if (node > kMaxNodeId) return EncodeResult::kInvalidNode;
  detail::SignalWriter writer;
  Message::visit(msg, writer);
  if (writer.result != EncodeResult::kOk) return writer.result;
  Frame frame;
  frame.id = frame_id(Message::kType, node);
  frame.dlc = frame_spec(Message::kType).dlc;
  for (std::size_t i = 0; i < frame.data.size(); ++i) {
    frame.data[i] = static_cast<std::uint8_t>(writer.payload >> (8 * i));
  }
  frame.data[kChecksumByte] = frame_checksum(frame);
  out = frame;
  return EncodeResult::kOk;
}

// Checks id, length, checksum and every signal's range; on kOk fills out (counter included,
// not checked against earlier frames: that is Receiver's job), otherwise leaves it untouched.
template <class Message>
DecodeResult decode(const Frame& frame, NodeId node, Message& out) {
  static_assert(detail::visits_exactly_its_signals<Message>(), "not a message of this protocol");
  if (node > kMaxNodeId || frame.id != frame_id(Message::kType, node)) {
    return DecodeResult::kWrongId;
  }
  if (frame.dlc != frame_spec(Message::kType).dlc) return DecodeResult::kWrongLength;
  if (frame.data[kChecksumByte] != frame_checksum(frame)) return DecodeResult::kBadChecksum;
  detail::SignalReader reader{detail::payload_of(frame)};
  Message decoded{};
  Message::visit(decoded, reader);
  if (reader.result == DecodeResult::kOk) out = decoded;
  return reader.result;
}

// ---------------------------------------------------------------------------------------
// Rolling counters and reject counting

inline constexpr std::uint8_t kCounterModulo = 16;
inline constexpr std::uint8_t kMaxCounterAdvance = 7;  // up to 6 lost frames in a row

// Validates the rolling counter of each frame type from one sender.
class CounterTracker {
 public:
  // kOk (and remembers counter) for the first frame of a type or an advance of
  // 1..kMaxCounterAdvance; kStaleCounter for a repeat or a step back.
  constexpr DecodeResult accept(FrameType type, std::uint8_t counter) {
    const std::size_t i = index_of(type);
    const std::uint16_t bit = static_cast<std::uint16_t>(1u << i);
    if (synced_ & bit) {
      const unsigned advance = (unsigned{counter} + kCounterModulo - last_[i]) % kCounterModulo;
      if (advance == 0 || advance > kMaxCounterAdvance) return DecodeResult::kStaleCounter;
    }
    synced_ = static_cast<std::uint16_t>(synced_ | bit);
    last_[i] = counter;
    return DecodeResult::kOk;
  }
  constexpr void reset(FrameType type) {
    synced_ = static_cast<std::uint16_t>(synced_ & ~(1u << index_of(type)));
  }
  constexpr void reset_all() { synced_ = 0; }

 private:
  std::array<std::uint8_t, kFrameTypeCount> last_{};
  std::uint16_t synced_ = 0;  // bit i: a counter of FrameType(i) has been accepted
};

struct RejectCounters {
  std::uint32_t wrong_id = 0;
  std::uint32_t wrong_length = 0;
  std::uint32_t bad_checksum = 0;
  std::uint32_t stale_counter = 0;
  std::uint32_t out_of_range = 0;
  std::uint32_t unknown_mode = 0;
  std::uint32_t unknown_enum = 0;

  constexpr void count(DecodeResult result) {
    switch (result) {
      case DecodeResult::kOk: break;
      case DecodeResult::kWrongId: ++wrong_id; break;
      case DecodeResult::kWrongLength: ++wrong_length; break;
      case DecodeResult::kBadChecksum: ++bad_checksum; break;
      case DecodeResult::kStaleCounter: ++stale_counter; break;
      case DecodeResult::kOutOfRange: ++out_of_range; break;
      case DecodeResult::kUnknownMode: ++unknown_mode; break;
      case DecodeResult::kUnknownEnum: ++unknown_enum; break;
    }
  }
  constexpr std::uint32_t total() const {
    return wrong_id + wrong_length + bad_checksum + stale_counter + out_of_range + unknown_mode +
           unknown_enum;
  }
};

// One node's inbound frames from one sender: decodes, checks the rolling counter, counts
// rejects. A rejected frame leaves the tracker where it was. Call decode only with frames
// meant for this node (see identify); others count as kWrongId.
struct Receiver {
  NodeId node = 0;
  CounterTracker counters;
  RejectCounters rejects;

  constexpr Receiver() = default;
  constexpr explicit Receiver(NodeId node_id) : node(node_id) {}

  template <class Message>
  DecodeResult decode(const Frame& frame, Message& out) {
    Message candidate{};
    DecodeResult result = forearm_protocol::decode(frame, node, candidate);
    if (result == DecodeResult::kOk) result = counters.accept(Message::kType, candidate.counter);
    if (result == DecodeResult::kOk) out = candidate;
    rejects.count(result);
    return result;
  }
};

// Stamps each frame type's rolling counter; it advances only when a frame was encoded.
struct Sender {
  NodeId node = 0;
  std::array<std::uint8_t, kFrameTypeCount> next_counter{};

  constexpr Sender() = default;
  constexpr explicit Sender(NodeId node_id) : node(node_id) {}

  template <class Message>
  EncodeResult encode(Message msg, Frame& out) {
    std::uint8_t& counter = next_counter[index_of(Message::kType)];
    msg.counter = counter;
    const EncodeResult result = forearm_protocol::encode(msg, node, out);
    if (result == EncodeResult::kOk) {
      counter = static_cast<std::uint8_t>((counter + 1) % kCounterModulo);
    }
    return result;
  }
};

// ---------------------------------------------------------------------------------------
// Bus load

// Worst-case bits of a classic data frame with an 11-bit id and 8 data bytes, interframe
// space included: 111 bits plus at most 24 stuff bits (8n + 47 + floor((34 + 8n - 1) / 4)).
inline constexpr std::uint32_t kWorstCaseFrameBits = 135;

enum class Setup : std::uint8_t {
  kRobot,  // host and boards; sensors wired to the board, no plant frames on the bus
  kHil,    // the HIL plant also exchanges sensor and actuator frames on the bus
};

// Fraction of the bus the periodic frames of `boards` boards use, worst-case stuffing.
constexpr double bus_load(Setup setup, std::uint32_t bitrate_bps, unsigned boards = 1) {
  double bits_per_second = 0;
  for (const FrameSpec& frame : kFrames) {
    const bool plant_frame = frame.sender == Endpoint::kPlant || frame.receiver == Endpoint::kPlant;
    if (frame.cycle_time_ms == 0 || (plant_frame && setup == Setup::kRobot)) continue;
    bits_per_second += kWorstCaseFrameBits * 1000.0 / frame.cycle_time_ms;
  }
  return bits_per_second * boards / bitrate_bps;
}

}  // namespace hmpc::forearm_protocol
