// CAN protocol of the forearm actuator board: the one source of truth for its frame ids, signal
// layouts, scaling, units and ranges. The codec, the end-to-end protection (CRC-8 and rolling
// counter in every frame) and the bit layout rules are codec.hpp's, shared with the other board
// protocols. common/protocol/hmpc_forearm.dbc describes the same frames for cantools or
// SavvyCAN; tests/unit/dbc_test.cpp keeps it in agreement with kFrames and kSignals below.
//
// Identifiers: node 0..15 at base 0x100, stride 0x10. Node 0 is 0x100..0x109 and node 15 is
// 0x1F0..0x1F9, so 0x000..0x0FF stays free for bus-wide frames that must win arbitration. Inside
// a node the order of the offsets is the priority: heartbeat, then the 1 kHz I/O loop, then the
// 250 Hz trajectory and telemetry, then gains.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hmpc/protocol/codec.hpp"

namespace hmpc::forearm_protocol {

using protocol::ByteOrder;
using protocol::crc8_autosar;
using protocol::decode;
using protocol::DecodeResult;
using protocol::encode;
using protocol::EncodeResult;
using protocol::Endpoint;
using protocol::EnumValue;
using protocol::Frame;
using protocol::frame_checksum;
using protocol::frame_id;
using protocol::frame_spec;
using protocol::identify;
using protocol::index_of;
using protocol::kChecksumByte;
using protocol::kCounterModulo;
using protocol::kMaxCounterAdvance;
using protocol::kWorstCaseFrameBits;
using protocol::NodeId;
using protocol::raw_max;
using protocol::raw_min;
using protocol::raw_of;
using protocol::RejectCounters;
using protocol::signal_spec;
using protocol::SignalKind;
using protocol::to_string;
using protocol::value_name;
using protocol::value_of;
using protocol::values_of;
namespace detail = protocol::detail;

inline constexpr protocol::IdLayout kIds{0x100, 0x10, 15};
inline constexpr NodeId kMaxNodeId = kIds.max_node;
inline constexpr std::uint32_t kBaseId = kIds.base;
inline constexpr std::uint32_t kNodeIdStride = kIds.node_stride;

// ---------------------------------------------------------------------------------------
// Frames

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
  kCostWeights,       // host -> board: the MPC's tracking-cost weights (Eq. 3.3)
};
inline constexpr std::size_t kFrameTypeCount = 11;

using FrameSpec = protocol::FrameSpec<FrameType>;

// clang-format off
inline constexpr FrameSpec kFrames[kFrameTypeCount] = {
  // type                          name                 offset dlc sender            receiver         period ms  bus-wide
  {FrameType::kModeCommand,      "ModeCommand",      0x0, 8, Endpoint::kHost,  Endpoint::kBoard,  10, false},
  {FrameType::kSensor,           "Sensor",           0x1, 8, Endpoint::kPlant, Endpoint::kBoard,   1, false},
  {FrameType::kActuatorCommand,  "ActuatorCommand",  0x2, 8, Endpoint::kBoard, Endpoint::kPlant,   1, false},
  {FrameType::kTrajectorySample, "TrajectorySample", 0x3, 8, Endpoint::kHost,  Endpoint::kBoard,   4, false},
  {FrameType::kBoardStatus,      "BoardStatus",      0x4, 8, Endpoint::kBoard, Endpoint::kHost,   10, false},
  {FrameType::kJointState,       "JointState",       0x5, 8, Endpoint::kBoard, Endpoint::kHost,    4, false},
  {FrameType::kActuatorOutputs,  "ActuatorOutputs",  0x6, 8, Endpoint::kBoard, Endpoint::kHost,    4, false},
  {FrameType::kSolveTelemetry,   "SolveTelemetry",   0x7, 8, Endpoint::kBoard, Endpoint::kHost,    4, false},
  {FrameType::kGains,            "Gains",            0x8, 8, Endpoint::kHost,  Endpoint::kBoard,   0, false},
  {FrameType::kSync,             "Sync",             0x9, 8, Endpoint::kPlant, Endpoint::kBoard,   1, false},
  {FrameType::kCostWeights,      "CostWeights",      0xA, 8, Endpoint::kHost,  Endpoint::kBoard,   0, false},
};
// clang-format on

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

inline constexpr EnumValue kRequestedModeValues[] = {{1, "idle"}, {2, "hold"}, {3, "run"}};
inline constexpr EnumValue kBoardModeValues[] = {
    {0, "boot"}, {1, "idle"}, {2, "hold"}, {3, "run"}, {4, "fault"}};
inline constexpr EnumValue kStrategyValues[] = {{0, "fine_4ms"},    {1, "fine_8ms"},
                                                {2, "coarse_20ms"}, {3, "coarse_40ms"},
                                                {4, "two_stage"},   {5, "pam_only"}};
inline constexpr EnumValue kSolveStatusValues[] = {
    {0, "converged"},     {1, "iteration_cap"},     {2, "budget_exhausted"}, {3, "stalled"},
    {4, "invalid_input"}, {5, "numerical_failure"}, {6, "no_solve"}};

// ---------------------------------------------------------------------------------------
// Signals

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
  kCostWeightsChecksum, kCostWeightsCounter, kCostWeightsTheta, kCostWeightsPressure,
  kCostWeightsTorque, kCostWeightsValve,
};
// clang-format on
inline constexpr std::size_t kSignalCount = 61;

using SignalSpec = protocol::SignalSpec<Signal, FrameType>;

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

  {Signal::kCostWeightsChecksum,             FrameType::kCostWeights,      "checksum",          0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",          SignalKind::kChecksum,    {}},
  {Signal::kCostWeightsCounter,              FrameType::kCostWeights,      "counter",           8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",          SignalKind::kCounter,     {}},
  {Signal::kCostWeightsTheta,                FrameType::kCostWeights,      "w_theta",          12, 13, ByteOrder::kLittleEndian, false, 0.05,    0, 0,       400,        "",          SignalKind::kPhysical,    {}},
  {Signal::kCostWeightsPressure,             FrameType::kCostWeights,      "w_p",              25, 13, ByteOrder::kLittleEndian, false, 0.05,    0, 0,       400,        "",          SignalKind::kPhysical,    {}},
  {Signal::kCostWeightsTorque,               FrameType::kCostWeights,      "w_tau",            38, 13, ByteOrder::kLittleEndian, false, 0.0005,  0, 0,       4,          "",          SignalKind::kPhysical,    {}},
  {Signal::kCostWeightsValve,                FrameType::kCostWeights,      "w_v",              51, 13, ByteOrder::kLittleEndian, false, 0.000005,0, 0,       0.04,       "",          SignalKind::kPhysical,    {}},
};
// clang-format on

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

// The weights of the tracking cost, Eq. 3.3 (forearm::CostWeights), set while the board runs
// and adopted before its next MPC step. 0 keeps a weight as it is, so that a host can change
// one without knowing the others (the board may have been started with its own). Ranges: 10x
// the thesis's values (Sec. 3.3) and down to the resolution, 0.25 % of them or finer.
struct CostWeights {
  static constexpr FrameType kType = FrameType::kCostWeights;
  float w_theta = 0;  // tracking
  float w_p = 0;      // pressure above the threshold P0
  float w_tau = 0;    // motor torque
  float w_v = 0;      // valve voltage
  std::uint8_t counter = 0;
  template <class Self, class Visitor>
  static constexpr void visit(Self& self, Visitor&& visitor) {
    visitor(Signal::kCostWeightsCounter, self.counter);
    visitor(Signal::kCostWeightsTheta, self.w_theta);
    visitor(Signal::kCostWeightsPressure, self.w_p);
    visitor(Signal::kCostWeightsTorque, self.w_tau);
    visitor(Signal::kCostWeightsValve, self.w_v);
  }
};

// ---------------------------------------------------------------------------------------
// The description the codec reads, and the codec over it

struct Description {
  using FrameType = forearm_protocol::FrameType;
  using Signal = forearm_protocol::Signal;
  static constexpr const protocol::IdLayout& kIds = forearm_protocol::kIds;
  static constexpr const auto& kFrames = forearm_protocol::kFrames;
  static constexpr const auto& kSignals = forearm_protocol::kSignals;
};
constexpr Description protocol_of(FrameType) { return {}; }
constexpr Description protocol_of(Signal) { return {}; }

using Messages =
    protocol::MessageList<ModeCommand, SensorSample, ActuatorCommand, TrajectorySample, BoardStatus,
                          JointState, ActuatorOutputs, SolveTelemetry, Gains, Sync, CostWeights>;
static_assert(protocol::is_well_formed<Description>(Messages{}),
              "tables or messages break a rule of codec.hpp (see its compile-time checks)");

using CounterTracker = protocol::CounterTracker<Description>;
using Receiver = protocol::Receiver<Description>;
using Sender = protocol::Sender<Description>;

// ---------------------------------------------------------------------------------------
// Bus load

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
    bits_per_second += protocol::frame_bits_per_second(1, frame.cycle_time_ms);
  }
  return bits_per_second * boards / bitrate_bps;
}

}  // namespace hmpc::forearm_protocol
