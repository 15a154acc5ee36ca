// CAN protocol of the hydraulic joint boards (the humanoid's legs): the one source of truth for
// their frame ids, signal layouts, scaling, units and ranges. The codec, the end-to-end
// protection (CRC-8 and rolling counter in every frame) and the bit layout rules are
// codec.hpp's. common/protocol/hmpc_joint.dbc describes the same frames for cantools or
// SavvyCAN; tests/unit/dbc_test.cpp keeps it in agreement with kFrames and kSignals below.
//
// A joint board drives 1 to kMaxJointsPerBoard joints: a torque loop per joint (PID with
// load-velocity feedback, thesis Sec. 2.7.3) on the host's torque references, and a position
// hold of its own. Two buses:
//   robot bus  host <-> boards and the torso IMU: what a real robot carries, so its load is a
//              real figure (bus_load below).
//   I/O bus    HIL only: the plant emulates each board's local wiring (encoders, load cells,
//              pressure sensors, valve drivers) and its clock (Sync). A real board reads these
//              from its own pins; they never reach the robot bus.
//
// Identifiers: node 0..15 at base 0x200, stride 0x20 (a board's frames do not fit 16 offsets);
// node n is 0x200 + 0x20 n .. + 0x16, clear of the forearm protocol's 0x100..0x1FF so both
// kinds of board can share a bus. The emergency stop (robot bus) and the Sync (I/O bus) are
// bus-wide, below every node's range, so they win arbitration. Within a node the offsets put
// the heartbeat and the torque references first, then the IMU, the boards' feedback, status,
// gains and encoder offsets.
//
// Periods: frames with cycle_time_ms == kDefaultControlPeriodMs go once per control period
// (6 ms by default, thesis Sec. 2.7.3; 1 ms selectable): a board's control period sets their
// rate. The I/O bus's sensor and valve frames follow the plant's 1 ms step.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "hmpc/protocol/codec.hpp"

namespace hmpc::joint_protocol {

using protocol::ByteOrder;
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
using protocol::NodeId;
using protocol::raw_max;
using protocol::raw_min;
using protocol::RejectCounters;
using protocol::signal_spec;
using protocol::SignalKind;
using protocol::to_string;
using protocol::value_name;
using protocol::value_of;
using protocol::values_of;
namespace detail = protocol::detail;

inline constexpr protocol::IdLayout kIds{0x200, 0x20, 15};
inline constexpr std::size_t kMaxJointsPerBoard = 4;
inline constexpr std::uint8_t kProtocolVersion = 1;  // BoardStatus::protocol_version
inline constexpr std::uint16_t kDefaultControlPeriodMs = 6;

// ---------------------------------------------------------------------------------------
// Frames

enum class FrameType : std::uint8_t {
  kEStop,                  // host -> boards, bus-wide: latch the safe state
  kModeCommand,            // host -> board: heartbeat, requested mode, zeroing, fault clearing
  kTorqueReference,        // host -> board: torque reference of each joint
  kImuAngularVelocity,     // IMU -> host: gyroscope
  kImuLinearAcceleration,  // IMU -> host: accelerometer (specific force)
  kImuAttitude,            // IMU -> host: orientation quaternion
  kJointState0,            // board -> host: angle, velocity, torque of joint 0
  kJointState1,
  kJointState2,
  kJointState3,
  kValveCommands,  // board -> host: the valve command of each joint
  kBoardStatus,    // board -> host: mode, fault bits, joints, protocol version, counters
  kTorqueGains,    // host -> board: one joint's torque loop gains
  kHoldGains,      // host -> board: one joint's position hold gains
  kEncoderOffset,  // board -> host: one joint's encoder offset, joints in turn
  kSync,           // plant -> boards, I/O bus, bus-wide: lock-step clock tick
  kJointSensor0,   // plant -> board, I/O bus: encoder, velocity, load cell of joint 0
  kJointSensor1,
  kJointSensor2,
  kJointSensor3,
  kChamberPressures01,  // plant -> board, I/O bus: chamber pressures of joints 0 and 1
  kChamberPressures23,  // ... of joints 2 and 3
  kValveDrive,          // board -> plant, I/O bus: the valve command of each joint
};
inline constexpr std::size_t kFrameTypeCount = 23;

using FrameSpec = protocol::FrameSpec<FrameType>;

// clang-format off
inline constexpr FrameSpec kFrames[kFrameTypeCount] = {
  // type                               name                    offset dlc sender           receiver         period ms  bus-wide
  {FrameType::kEStop,                 "EStop",                0x080, 8, Endpoint::kHost,  Endpoint::kBoard,  0, true},
  {FrameType::kModeCommand,           "ModeCommand",           0x00, 8, Endpoint::kHost,  Endpoint::kBoard, 10, false},
  {FrameType::kTorqueReference,       "TorqueReference",       0x01, 8, Endpoint::kHost,  Endpoint::kBoard,  6, false},
  {FrameType::kImuAngularVelocity,    "ImuAngularVelocity",    0x02, 8, Endpoint::kImu,   Endpoint::kHost,   6, false},
  {FrameType::kImuLinearAcceleration, "ImuLinearAcceleration", 0x03, 8, Endpoint::kImu,   Endpoint::kHost,   6, false},
  {FrameType::kImuAttitude,           "ImuAttitude",           0x04, 8, Endpoint::kImu,   Endpoint::kHost,   6, false},
  {FrameType::kJointState0,           "JointState0",           0x05, 8, Endpoint::kBoard, Endpoint::kHost,   6, false},
  {FrameType::kJointState1,           "JointState1",           0x06, 8, Endpoint::kBoard, Endpoint::kHost,   6, false},
  {FrameType::kJointState2,           "JointState2",           0x07, 8, Endpoint::kBoard, Endpoint::kHost,   6, false},
  {FrameType::kJointState3,           "JointState3",           0x08, 8, Endpoint::kBoard, Endpoint::kHost,   6, false},
  {FrameType::kValveCommands,         "ValveCommands",         0x09, 8, Endpoint::kBoard, Endpoint::kHost,   6, false},
  {FrameType::kBoardStatus,           "BoardStatus",           0x0A, 8, Endpoint::kBoard, Endpoint::kHost,  20, false},
  {FrameType::kTorqueGains,           "TorqueGains",           0x0B, 8, Endpoint::kHost,  Endpoint::kBoard,  0, false},
  {FrameType::kHoldGains,             "HoldGains",             0x0C, 8, Endpoint::kHost,  Endpoint::kBoard,  0, false},
  {FrameType::kEncoderOffset,         "EncoderOffset",         0x0D, 8, Endpoint::kBoard, Endpoint::kHost, 100, false},
  {FrameType::kSync,                  "Sync",                 0x081, 8, Endpoint::kPlant, Endpoint::kBoard,  1, true},
  {FrameType::kJointSensor0,          "JointSensor0",          0x10, 8, Endpoint::kPlant, Endpoint::kBoard,  1, false},
  {FrameType::kJointSensor1,          "JointSensor1",          0x11, 8, Endpoint::kPlant, Endpoint::kBoard,  1, false},
  {FrameType::kJointSensor2,          "JointSensor2",          0x12, 8, Endpoint::kPlant, Endpoint::kBoard,  1, false},
  {FrameType::kJointSensor3,          "JointSensor3",          0x13, 8, Endpoint::kPlant, Endpoint::kBoard,  1, false},
  {FrameType::kChamberPressures01,    "ChamberPressures01",    0x14, 8, Endpoint::kPlant, Endpoint::kBoard,  1, false},
  {FrameType::kChamberPressures23,    "ChamberPressures23",    0x15, 8, Endpoint::kPlant, Endpoint::kBoard,  1, false},
  {FrameType::kValveDrive,            "ValveDrive",            0x16, 8, Endpoint::kBoard, Endpoint::kPlant,  1, false},
};
// clang-format on

// Frame types that come once per joint slot (kJointState0 + j, kJointSensor0 + j).
constexpr FrameType joint_frame(FrameType first, std::size_t joint) {
  return static_cast<FrameType>(static_cast<std::size_t>(first) + joint);
}

// The lowest joint a frame carries, or kMaxJointsPerBoard for a frame about no joint: a board
// with n joints sends and receives a per-joint frame only if that joint is below n.
constexpr std::size_t first_joint_of(FrameType type) {
  switch (type) {
    case FrameType::kJointState0:
    case FrameType::kJointSensor0: return 0;
    case FrameType::kJointState1:
    case FrameType::kJointSensor1: return 1;
    case FrameType::kJointState2:
    case FrameType::kJointSensor2: return 2;
    case FrameType::kJointState3:
    case FrameType::kJointSensor3: return 3;
    case FrameType::kChamberPressures01: return 0;
    case FrameType::kChamberPressures23: return 2;
    default: return kMaxJointsPerBoard;
  }
}

// The HIL's frames: the plant's, on the I/O bus.
constexpr bool on_io_bus(const FrameSpec& frame) {
  return frame.sender == Endpoint::kPlant || frame.receiver == Endpoint::kPlant;
}

// ---------------------------------------------------------------------------------------
// Enumerated signal values

// Mode the host asks for. 0 is no request, so an all-zero payload never commands anything.
enum class RequestedMode : std::uint8_t { kIdle = 1, kHold = 2, kRun = 3 };

// Mode the board is in: boot -> idle (valves centred) -> hold (position hold) -> run (torque
// references), and fault (the safe state, latched).
enum class BoardMode : std::uint8_t { kBoot = 0, kIdle = 1, kHold = 2, kRun = 3, kFault = 4 };

// BoardStatus fault bits; a set bit stays set until a ModeCommand with clear_faults in idle.
namespace fault {
inline constexpr std::uint16_t kHeartbeatTimeout = 1u << 0;  // no valid ModeCommand in time
inline constexpr std::uint16_t kSensorTimeout = 1u << 1;     // no valid sensor frame in time
inline constexpr std::uint16_t kSensorOutOfRange = 1u << 2;  // a reading outside its range
inline constexpr std::uint16_t kStaleReference = 1u << 3;    // run without a fresh reference
inline constexpr std::uint16_t kOverrun = 1u << 4;           // a control step missed its deadline
inline constexpr std::uint16_t kBusError = 1u << 5;          // CAN error passive or bus-off
inline constexpr std::uint16_t kJointLimit = 1u << 6;        // a joint beyond its software limit
inline constexpr std::uint16_t kPressureLimit = 1u << 7;     // a chamber beyond its pressure limit
inline constexpr std::uint16_t kEStop = 1u << 8;             // an EStop frame was received
inline constexpr std::uint16_t kNotZeroed = 1u << 9;         // hold or run asked before zeroing
inline constexpr std::uint16_t kInternal = 1u << 15;         // failed self-check (stack, config)
}  // namespace fault

inline constexpr EnumValue kRequestedModeValues[] = {{1, "idle"}, {2, "hold"}, {3, "run"}};
inline constexpr EnumValue kBoardModeValues[] = {
    {0, "boot"}, {1, "idle"}, {2, "hold"}, {3, "run"}, {4, "fault"}};

// ---------------------------------------------------------------------------------------
// Signals

// clang-format off
enum class Signal : std::uint8_t {
  kEStopChecksum, kEStopCounter, kEStopEngage,
  kModeCommandChecksum, kModeCommandCounter, kModeCommandRequestedMode, kModeCommandClearFaults,
  kModeCommandZeroEncoders, kModeCommandHostTime,
  kTorqueReferenceChecksum, kTorqueReferenceCounter, kTorqueReferenceTau0, kTorqueReferenceTau1,
  kTorqueReferenceTau2, kTorqueReferenceTau3,
  kImuAngularVelocityChecksum, kImuAngularVelocityCounter, kImuAngularVelocityX,
  kImuAngularVelocityY, kImuAngularVelocityZ,
  kImuLinearAccelerationChecksum, kImuLinearAccelerationCounter, kImuLinearAccelerationX,
  kImuLinearAccelerationY, kImuLinearAccelerationZ,
  kImuAttitudeChecksum, kImuAttitudeCounter, kImuAttitudeW, kImuAttitudeX, kImuAttitudeY,
  kImuAttitudeZ,
  kJointState0Checksum, kJointState0Counter, kJointState0Theta, kJointState0ThetaDot, kJointState0Tau,
  kJointState1Checksum, kJointState1Counter, kJointState1Theta, kJointState1ThetaDot, kJointState1Tau,
  kJointState2Checksum, kJointState2Counter, kJointState2Theta, kJointState2ThetaDot, kJointState2Tau,
  kJointState3Checksum, kJointState3Counter, kJointState3Theta, kJointState3ThetaDot, kJointState3Tau,
  kValveCommandsChecksum, kValveCommandsCounter, kValveCommandsU0, kValveCommandsU1,
  kValveCommandsU2, kValveCommandsU3,
  kBoardStatusChecksum, kBoardStatusCounter, kBoardStatusMode, kBoardStatusFaults,
  kBoardStatusJoints, kBoardStatusProtocolVersion, kBoardStatusRejectedFrames,
  kBoardStatusWatchdogTrips, kBoardStatusOverruns,
  kTorqueGainsChecksum, kTorqueGainsCounter, kTorqueGainsJoint, kTorqueGainsKp, kTorqueGainsKi,
  kTorqueGainsLoadVelocity,
  kHoldGainsChecksum, kHoldGainsCounter, kHoldGainsJoint, kHoldGainsKp, kHoldGainsKi,
  kHoldGainsKd,
  kEncoderOffsetChecksum, kEncoderOffsetCounter, kEncoderOffsetJoint, kEncoderOffsetOffset,
  kEncoderOffsetZeroed,
  kSyncChecksum, kSyncCounter, kSyncTick,
  kJointSensor0Checksum, kJointSensor0Counter, kJointSensor0Theta, kJointSensor0ThetaDot, kJointSensor0Tau,
  kJointSensor1Checksum, kJointSensor1Counter, kJointSensor1Theta, kJointSensor1ThetaDot, kJointSensor1Tau,
  kJointSensor2Checksum, kJointSensor2Counter, kJointSensor2Theta, kJointSensor2ThetaDot, kJointSensor2Tau,
  kJointSensor3Checksum, kJointSensor3Counter, kJointSensor3Theta, kJointSensor3ThetaDot, kJointSensor3Tau,
  kChamberPressures01Checksum, kChamberPressures01Counter, kChamberPressures01PressureA0,
  kChamberPressures01PressureB0, kChamberPressures01PressureA1, kChamberPressures01PressureB1,
  kChamberPressures23Checksum, kChamberPressures23Counter, kChamberPressures23PressureA2,
  kChamberPressures23PressureB2, kChamberPressures23PressureA3, kChamberPressures23PressureB3,
  kValveDriveChecksum, kValveDriveCounter, kValveDriveU0, kValveDriveU1, kValveDriveU2,
  kValveDriveU3,
};
// clang-format on
inline constexpr std::size_t kSignalCount = 124;

using SignalSpec = protocol::SignalSpec<Signal, FrameType>;

// Resolution is the factor. Ranges and why:
//   torque   [-200, 200] N.m: above the stall torque of the joint actuator (about 113 N.m for
//            16 MPa on a 16 mm piston at 35 mm, models/hydraulic_joint.hpp), 0.05 N.m steps in
//            the 13-bit references (four joints in one frame), 0.01 N.m in the 16-bit feedback.
//   angle    [-pi, pi] rad at 0.1 mrad; velocity [-20, 20] rad/s at 1 mrad/s.
//   valve    [-1, 1] of the rated spool opening, 13 bits (a 12-bit DAC's resolution and sign).
//   pressure [0, 32] MPa at 4 kPa: twice the 16 MPa supply, room for the pressure peaks of a
//            joint driven against a closed valve.
//   IMU      rate [-32, 32] rad/s at 1 mrad/s, specific force [-160, 160] m/s^2 at 5 mm/s^2
//            (beyond the +-2000 deg/s and +-16 g of common MEMS IMUs), quaternion components
//            [-1, 1] at 2.5e-4.
//   gains    torque loop: u = kp e + ki integral(e) + k_lv theta_dot, e = tau_ref - tau in N.m,
//            u the valve command; hold: tau_ref = kp e + ki integral(e) - kd theta_dot,
//            e = theta_hold - theta in rad. Ranges a decade above the tuned defaults.
// clang-format off
inline constexpr SignalSpec kSignals[kSignalCount] = {
  // signal                                      frame                              name               start len byte order                 signed factor   offset min      max         unit          kind                     values
  {Signal::kEStopChecksum,                       FrameType::kEStop,                 "checksum",         0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",           SignalKind::kChecksum,    {}},
  {Signal::kEStopCounter,                        FrameType::kEStop,                 "counter",          8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",           SignalKind::kCounter,     {}},
  {Signal::kEStopEngage,                         FrameType::kEStop,                 "engage",          12,  1, ByteOrder::kLittleEndian, false, 1,       0, 1,       1,          "",           SignalKind::kInteger,     {}},

  {Signal::kModeCommandChecksum,                 FrameType::kModeCommand,           "checksum",         0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",           SignalKind::kChecksum,    {}},
  {Signal::kModeCommandCounter,                  FrameType::kModeCommand,           "counter",          8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",           SignalKind::kCounter,     {}},
  {Signal::kModeCommandRequestedMode,            FrameType::kModeCommand,           "requested_mode",  12,  4, ByteOrder::kLittleEndian, false, 1,       0, 1,       3,          "",           SignalKind::kMode,        values_of(kRequestedModeValues)},
  {Signal::kModeCommandClearFaults,              FrameType::kModeCommand,           "clear_faults",    16,  1, ByteOrder::kLittleEndian, false, 1,       0, 0,       1,          "",           SignalKind::kInteger,     {}},
  {Signal::kModeCommandZeroEncoders,             FrameType::kModeCommand,           "zero_encoders",   17,  1, ByteOrder::kLittleEndian, false, 1,       0, 0,       1,          "",           SignalKind::kInteger,     {}},
  {Signal::kModeCommandHostTime,                 FrameType::kModeCommand,           "host_time",       32, 32, ByteOrder::kLittleEndian, false, 1,       0, 0,       4294967295, "us",         SignalKind::kInteger,     {}},

  {Signal::kTorqueReferenceChecksum,             FrameType::kTorqueReference,       "checksum",         0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",           SignalKind::kChecksum,    {}},
  {Signal::kTorqueReferenceCounter,              FrameType::kTorqueReference,       "counter",          8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",           SignalKind::kCounter,     {}},
  {Signal::kTorqueReferenceTau0,                 FrameType::kTorqueReference,       "tau_0",           12, 13, ByteOrder::kLittleEndian, true,  0.05,    0, -200,    200,        "N.m",        SignalKind::kPhysical,    {}},
  {Signal::kTorqueReferenceTau1,                 FrameType::kTorqueReference,       "tau_1",           25, 13, ByteOrder::kLittleEndian, true,  0.05,    0, -200,    200,        "N.m",        SignalKind::kPhysical,    {}},
  {Signal::kTorqueReferenceTau2,                 FrameType::kTorqueReference,       "tau_2",           38, 13, ByteOrder::kLittleEndian, true,  0.05,    0, -200,    200,        "N.m",        SignalKind::kPhysical,    {}},
  {Signal::kTorqueReferenceTau3,                 FrameType::kTorqueReference,       "tau_3",           51, 13, ByteOrder::kLittleEndian, true,  0.05,    0, -200,    200,        "N.m",        SignalKind::kPhysical,    {}},

  {Signal::kImuAngularVelocityChecksum,          FrameType::kImuAngularVelocity,    "checksum",         0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",           SignalKind::kChecksum,    {}},
  {Signal::kImuAngularVelocityCounter,           FrameType::kImuAngularVelocity,    "counter",          8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",           SignalKind::kCounter,     {}},
  {Signal::kImuAngularVelocityX,                 FrameType::kImuAngularVelocity,    "omega_x",         16, 16, ByteOrder::kLittleEndian, true,  0.001,   0, -32,     32,         "rad/s",      SignalKind::kPhysical,    {}},
  {Signal::kImuAngularVelocityY,                 FrameType::kImuAngularVelocity,    "omega_y",         32, 16, ByteOrder::kLittleEndian, true,  0.001,   0, -32,     32,         "rad/s",      SignalKind::kPhysical,    {}},
  {Signal::kImuAngularVelocityZ,                 FrameType::kImuAngularVelocity,    "omega_z",         48, 16, ByteOrder::kLittleEndian, true,  0.001,   0, -32,     32,         "rad/s",      SignalKind::kPhysical,    {}},

  {Signal::kImuLinearAccelerationChecksum,       FrameType::kImuLinearAcceleration, "checksum",         0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",           SignalKind::kChecksum,    {}},
  {Signal::kImuLinearAccelerationCounter,        FrameType::kImuLinearAcceleration, "counter",          8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",           SignalKind::kCounter,     {}},
  {Signal::kImuLinearAccelerationX,              FrameType::kImuLinearAcceleration, "accel_x",         16, 16, ByteOrder::kLittleEndian, true,  0.005,   0, -160,    160,        "m/s^2",      SignalKind::kPhysical,    {}},
  {Signal::kImuLinearAccelerationY,              FrameType::kImuLinearAcceleration, "accel_y",         32, 16, ByteOrder::kLittleEndian, true,  0.005,   0, -160,    160,        "m/s^2",      SignalKind::kPhysical,    {}},
  {Signal::kImuLinearAccelerationZ,              FrameType::kImuLinearAcceleration, "accel_z",         48, 16, ByteOrder::kLittleEndian, true,  0.005,   0, -160,    160,        "m/s^2",      SignalKind::kPhysical,    {}},

  {Signal::kImuAttitudeChecksum,                 FrameType::kImuAttitude,           "checksum",         0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",           SignalKind::kChecksum,    {}},
  {Signal::kImuAttitudeCounter,                  FrameType::kImuAttitude,           "counter",          8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",           SignalKind::kCounter,     {}},
  {Signal::kImuAttitudeW,                        FrameType::kImuAttitude,           "q_w",             12, 13, ByteOrder::kLittleEndian, true,  0.00025, 0, -1,      1,          "",           SignalKind::kPhysical,    {}},
  {Signal::kImuAttitudeX,                        FrameType::kImuAttitude,           "q_x",             25, 13, ByteOrder::kLittleEndian, true,  0.00025, 0, -1,      1,          "",           SignalKind::kPhysical,    {}},
  {Signal::kImuAttitudeY,                        FrameType::kImuAttitude,           "q_y",             38, 13, ByteOrder::kLittleEndian, true,  0.00025, 0, -1,      1,          "",           SignalKind::kPhysical,    {}},
  {Signal::kImuAttitudeZ,                        FrameType::kImuAttitude,           "q_z",             51, 13, ByteOrder::kLittleEndian, true,  0.00025, 0, -1,      1,          "",           SignalKind::kPhysical,    {}},

  {Signal::kJointState0Checksum,                 FrameType::kJointState0,           "checksum",         0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",           SignalKind::kChecksum,    {}},
  {Signal::kJointState0Counter,                  FrameType::kJointState0,           "counter",          8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",           SignalKind::kCounter,     {}},
  {Signal::kJointState0Theta,                    FrameType::kJointState0,           "theta",           16, 16, ByteOrder::kLittleEndian, true,  0.0001,  0, -3.1416, 3.1416,     "rad",        SignalKind::kPhysical,    {}},
  {Signal::kJointState0ThetaDot,                 FrameType::kJointState0,           "theta_dot",       32, 16, ByteOrder::kLittleEndian, true,  0.001,   0, -20,     20,         "rad/s",      SignalKind::kPhysical,    {}},
  {Signal::kJointState0Tau,                      FrameType::kJointState0,           "tau",             48, 16, ByteOrder::kLittleEndian, true,  0.01,    0, -200,    200,        "N.m",        SignalKind::kPhysical,    {}},
  {Signal::kJointState1Checksum,                 FrameType::kJointState1,           "checksum",         0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",           SignalKind::kChecksum,    {}},
  {Signal::kJointState1Counter,                  FrameType::kJointState1,           "counter",          8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",           SignalKind::kCounter,     {}},
  {Signal::kJointState1Theta,                    FrameType::kJointState1,           "theta",           16, 16, ByteOrder::kLittleEndian, true,  0.0001,  0, -3.1416, 3.1416,     "rad",        SignalKind::kPhysical,    {}},
  {Signal::kJointState1ThetaDot,                 FrameType::kJointState1,           "theta_dot",       32, 16, ByteOrder::kLittleEndian, true,  0.001,   0, -20,     20,         "rad/s",      SignalKind::kPhysical,    {}},
  {Signal::kJointState1Tau,                      FrameType::kJointState1,           "tau",             48, 16, ByteOrder::kLittleEndian, true,  0.01,    0, -200,    200,        "N.m",        SignalKind::kPhysical,    {}},
  {Signal::kJointState2Checksum,                 FrameType::kJointState2,           "checksum",         0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",           SignalKind::kChecksum,    {}},
  {Signal::kJointState2Counter,                  FrameType::kJointState2,           "counter",          8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",           SignalKind::kCounter,     {}},
  {Signal::kJointState2Theta,                    FrameType::kJointState2,           "theta",           16, 16, ByteOrder::kLittleEndian, true,  0.0001,  0, -3.1416, 3.1416,     "rad",        SignalKind::kPhysical,    {}},
  {Signal::kJointState2ThetaDot,                 FrameType::kJointState2,           "theta_dot",       32, 16, ByteOrder::kLittleEndian, true,  0.001,   0, -20,     20,         "rad/s",      SignalKind::kPhysical,    {}},
  {Signal::kJointState2Tau,                      FrameType::kJointState2,           "tau",             48, 16, ByteOrder::kLittleEndian, true,  0.01,    0, -200,    200,        "N.m",        SignalKind::kPhysical,    {}},
  {Signal::kJointState3Checksum,                 FrameType::kJointState3,           "checksum",         0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",           SignalKind::kChecksum,    {}},
  {Signal::kJointState3Counter,                  FrameType::kJointState3,           "counter",          8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",           SignalKind::kCounter,     {}},
  {Signal::kJointState3Theta,                    FrameType::kJointState3,           "theta",           16, 16, ByteOrder::kLittleEndian, true,  0.0001,  0, -3.1416, 3.1416,     "rad",        SignalKind::kPhysical,    {}},
  {Signal::kJointState3ThetaDot,                 FrameType::kJointState3,           "theta_dot",       32, 16, ByteOrder::kLittleEndian, true,  0.001,   0, -20,     20,         "rad/s",      SignalKind::kPhysical,    {}},
  {Signal::kJointState3Tau,                      FrameType::kJointState3,           "tau",             48, 16, ByteOrder::kLittleEndian, true,  0.01,    0, -200,    200,        "N.m",        SignalKind::kPhysical,    {}},

  {Signal::kValveCommandsChecksum,               FrameType::kValveCommands,         "checksum",         0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",           SignalKind::kChecksum,    {}},
  {Signal::kValveCommandsCounter,                FrameType::kValveCommands,         "counter",          8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",           SignalKind::kCounter,     {}},
  {Signal::kValveCommandsU0,                     FrameType::kValveCommands,         "u_0",             12, 13, ByteOrder::kLittleEndian, true,  0.00025, 0, -1,      1,          "",           SignalKind::kPhysical,    {}},
  {Signal::kValveCommandsU1,                     FrameType::kValveCommands,         "u_1",             25, 13, ByteOrder::kLittleEndian, true,  0.00025, 0, -1,      1,          "",           SignalKind::kPhysical,    {}},
  {Signal::kValveCommandsU2,                     FrameType::kValveCommands,         "u_2",             38, 13, ByteOrder::kLittleEndian, true,  0.00025, 0, -1,      1,          "",           SignalKind::kPhysical,    {}},
  {Signal::kValveCommandsU3,                     FrameType::kValveCommands,         "u_3",             51, 13, ByteOrder::kLittleEndian, true,  0.00025, 0, -1,      1,          "",           SignalKind::kPhysical,    {}},

  {Signal::kBoardStatusChecksum,                 FrameType::kBoardStatus,           "checksum",         0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",           SignalKind::kChecksum,    {}},
  {Signal::kBoardStatusCounter,                  FrameType::kBoardStatus,           "counter",          8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",           SignalKind::kCounter,     {}},
  {Signal::kBoardStatusMode,                     FrameType::kBoardStatus,           "mode",            12,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       4,          "",           SignalKind::kMode,        values_of(kBoardModeValues)},
  {Signal::kBoardStatusFaults,                   FrameType::kBoardStatus,           "faults",          16, 16, ByteOrder::kLittleEndian, false, 1,       0, 0,       65535,      "",           SignalKind::kInteger,     {}},
  {Signal::kBoardStatusJoints,                   FrameType::kBoardStatus,           "joints",          32,  3, ByteOrder::kLittleEndian, false, 1,       0, 1,       4,          "",           SignalKind::kInteger,     {}},
  {Signal::kBoardStatusProtocolVersion,          FrameType::kBoardStatus,           "protocol_version",35,  5, ByteOrder::kLittleEndian, false, 1,       0, 0,       31,         "",           SignalKind::kInteger,     {}},
  {Signal::kBoardStatusRejectedFrames,           FrameType::kBoardStatus,           "rejected_frames", 40,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",           SignalKind::kInteger,     {}},
  {Signal::kBoardStatusWatchdogTrips,            FrameType::kBoardStatus,           "watchdog_trips",  48,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",           SignalKind::kInteger,     {}},
  {Signal::kBoardStatusOverruns,                 FrameType::kBoardStatus,           "overruns",        56,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",           SignalKind::kInteger,     {}},

  {Signal::kTorqueGainsChecksum,                 FrameType::kTorqueGains,           "checksum",         0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",           SignalKind::kChecksum,    {}},
  {Signal::kTorqueGainsCounter,                  FrameType::kTorqueGains,           "counter",          8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",           SignalKind::kCounter,     {}},
  {Signal::kTorqueGainsJoint,                    FrameType::kTorqueGains,           "joint",           12,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       3,          "",           SignalKind::kInteger,     {}},
  {Signal::kTorqueGainsKp,                       FrameType::kTorqueGains,           "kp",              16, 12, ByteOrder::kLittleEndian, false, 0.00001, 0, 0,       0.04,       "1/(N.m)",    SignalKind::kPhysical,    {}},
  {Signal::kTorqueGainsKi,                       FrameType::kTorqueGains,           "ki",              28, 12, ByteOrder::kLittleEndian, false, 0.0002,  0, 0,       0.8,        "1/(N.m.s)",  SignalKind::kPhysical,    {}},
  {Signal::kTorqueGainsLoadVelocity,             FrameType::kTorqueGains,           "k_lv",            40, 13, ByteOrder::kLittleEndian, true,  0.0001,  0, -0.4,    0.4,        "s/rad",      SignalKind::kPhysical,    {}},

  {Signal::kHoldGainsChecksum,                   FrameType::kHoldGains,             "checksum",         0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",           SignalKind::kChecksum,    {}},
  {Signal::kHoldGainsCounter,                    FrameType::kHoldGains,             "counter",          8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",           SignalKind::kCounter,     {}},
  {Signal::kHoldGainsJoint,                      FrameType::kHoldGains,             "joint",           12,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       3,          "",           SignalKind::kInteger,     {}},
  {Signal::kHoldGainsKp,                         FrameType::kHoldGains,             "kp",              16, 12, ByteOrder::kLittleEndian, false, 0.5,     0, 0,       2000,       "N.m/rad",    SignalKind::kPhysical,    {}},
  {Signal::kHoldGainsKi,                         FrameType::kHoldGains,             "ki",              28, 12, ByteOrder::kLittleEndian, false, 1,       0, 0,       4000,       "N.m/(rad.s)",SignalKind::kPhysical,    {}},
  {Signal::kHoldGainsKd,                         FrameType::kHoldGains,             "kd",              40, 12, ByteOrder::kLittleEndian, false, 0.05,    0, 0,       200,        "N.m.s/rad",  SignalKind::kPhysical,    {}},

  {Signal::kEncoderOffsetChecksum,               FrameType::kEncoderOffset,         "checksum",         0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",           SignalKind::kChecksum,    {}},
  {Signal::kEncoderOffsetCounter,                FrameType::kEncoderOffset,         "counter",          8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",           SignalKind::kCounter,     {}},
  {Signal::kEncoderOffsetJoint,                  FrameType::kEncoderOffset,         "joint",           12,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       3,          "",           SignalKind::kInteger,     {}},
  {Signal::kEncoderOffsetOffset,                 FrameType::kEncoderOffset,         "offset",          16, 16, ByteOrder::kLittleEndian, true,  0.0001,  0, -3.1416, 3.1416,     "rad",        SignalKind::kPhysical,    {}},
  {Signal::kEncoderOffsetZeroed,                 FrameType::kEncoderOffset,         "zeroed",          32,  1, ByteOrder::kLittleEndian, false, 1,       0, 0,       1,          "",           SignalKind::kInteger,     {}},

  {Signal::kSyncChecksum,                        FrameType::kSync,                  "checksum",         0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",           SignalKind::kChecksum,    {}},
  {Signal::kSyncCounter,                         FrameType::kSync,                  "counter",          8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",           SignalKind::kCounter,     {}},
  {Signal::kSyncTick,                            FrameType::kSync,                  "tick",            32, 32, ByteOrder::kLittleEndian, false, 1,       0, 0,       4294967295, "ms",         SignalKind::kInteger,     {}},

  {Signal::kJointSensor0Checksum,                FrameType::kJointSensor0,          "checksum",         0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",           SignalKind::kChecksum,    {}},
  {Signal::kJointSensor0Counter,                 FrameType::kJointSensor0,          "counter",          8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",           SignalKind::kCounter,     {}},
  {Signal::kJointSensor0Theta,                   FrameType::kJointSensor0,          "theta",           16, 16, ByteOrder::kLittleEndian, true,  0.0001,  0, -3.1416, 3.1416,     "rad",        SignalKind::kPhysical,    {}},
  {Signal::kJointSensor0ThetaDot,                FrameType::kJointSensor0,          "theta_dot",       32, 16, ByteOrder::kLittleEndian, true,  0.001,   0, -20,     20,         "rad/s",      SignalKind::kPhysical,    {}},
  {Signal::kJointSensor0Tau,                     FrameType::kJointSensor0,          "tau",             48, 16, ByteOrder::kLittleEndian, true,  0.01,    0, -200,    200,        "N.m",        SignalKind::kPhysical,    {}},
  {Signal::kJointSensor1Checksum,                FrameType::kJointSensor1,          "checksum",         0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",           SignalKind::kChecksum,    {}},
  {Signal::kJointSensor1Counter,                 FrameType::kJointSensor1,          "counter",          8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",           SignalKind::kCounter,     {}},
  {Signal::kJointSensor1Theta,                   FrameType::kJointSensor1,          "theta",           16, 16, ByteOrder::kLittleEndian, true,  0.0001,  0, -3.1416, 3.1416,     "rad",        SignalKind::kPhysical,    {}},
  {Signal::kJointSensor1ThetaDot,                FrameType::kJointSensor1,          "theta_dot",       32, 16, ByteOrder::kLittleEndian, true,  0.001,   0, -20,     20,         "rad/s",      SignalKind::kPhysical,    {}},
  {Signal::kJointSensor1Tau,                     FrameType::kJointSensor1,          "tau",             48, 16, ByteOrder::kLittleEndian, true,  0.01,    0, -200,    200,        "N.m",        SignalKind::kPhysical,    {}},
  {Signal::kJointSensor2Checksum,                FrameType::kJointSensor2,          "checksum",         0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",           SignalKind::kChecksum,    {}},
  {Signal::kJointSensor2Counter,                 FrameType::kJointSensor2,          "counter",          8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",           SignalKind::kCounter,     {}},
  {Signal::kJointSensor2Theta,                   FrameType::kJointSensor2,          "theta",           16, 16, ByteOrder::kLittleEndian, true,  0.0001,  0, -3.1416, 3.1416,     "rad",        SignalKind::kPhysical,    {}},
  {Signal::kJointSensor2ThetaDot,                FrameType::kJointSensor2,          "theta_dot",       32, 16, ByteOrder::kLittleEndian, true,  0.001,   0, -20,     20,         "rad/s",      SignalKind::kPhysical,    {}},
  {Signal::kJointSensor2Tau,                     FrameType::kJointSensor2,          "tau",             48, 16, ByteOrder::kLittleEndian, true,  0.01,    0, -200,    200,        "N.m",        SignalKind::kPhysical,    {}},
  {Signal::kJointSensor3Checksum,                FrameType::kJointSensor3,          "checksum",         0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",           SignalKind::kChecksum,    {}},
  {Signal::kJointSensor3Counter,                 FrameType::kJointSensor3,          "counter",          8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",           SignalKind::kCounter,     {}},
  {Signal::kJointSensor3Theta,                   FrameType::kJointSensor3,          "theta",           16, 16, ByteOrder::kLittleEndian, true,  0.0001,  0, -3.1416, 3.1416,     "rad",        SignalKind::kPhysical,    {}},
  {Signal::kJointSensor3ThetaDot,                FrameType::kJointSensor3,          "theta_dot",       32, 16, ByteOrder::kLittleEndian, true,  0.001,   0, -20,     20,         "rad/s",      SignalKind::kPhysical,    {}},
  {Signal::kJointSensor3Tau,                     FrameType::kJointSensor3,          "tau",             48, 16, ByteOrder::kLittleEndian, true,  0.01,    0, -200,    200,        "N.m",        SignalKind::kPhysical,    {}},

  {Signal::kChamberPressures01Checksum,          FrameType::kChamberPressures01,    "checksum",         0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",           SignalKind::kChecksum,    {}},
  {Signal::kChamberPressures01Counter,           FrameType::kChamberPressures01,    "counter",          8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",           SignalKind::kCounter,     {}},
  {Signal::kChamberPressures01PressureA0,        FrameType::kChamberPressures01,    "p_a_0",           12, 13, ByteOrder::kLittleEndian, false, 0.004,   0, 0,       32,         "MPa",        SignalKind::kPhysical,    {}},
  {Signal::kChamberPressures01PressureB0,        FrameType::kChamberPressures01,    "p_b_0",           25, 13, ByteOrder::kLittleEndian, false, 0.004,   0, 0,       32,         "MPa",        SignalKind::kPhysical,    {}},
  {Signal::kChamberPressures01PressureA1,        FrameType::kChamberPressures01,    "p_a_1",           38, 13, ByteOrder::kLittleEndian, false, 0.004,   0, 0,       32,         "MPa",        SignalKind::kPhysical,    {}},
  {Signal::kChamberPressures01PressureB1,        FrameType::kChamberPressures01,    "p_b_1",           51, 13, ByteOrder::kLittleEndian, false, 0.004,   0, 0,       32,         "MPa",        SignalKind::kPhysical,    {}},
  {Signal::kChamberPressures23Checksum,          FrameType::kChamberPressures23,    "checksum",         0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",           SignalKind::kChecksum,    {}},
  {Signal::kChamberPressures23Counter,           FrameType::kChamberPressures23,    "counter",          8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",           SignalKind::kCounter,     {}},
  {Signal::kChamberPressures23PressureA2,        FrameType::kChamberPressures23,    "p_a_2",           12, 13, ByteOrder::kLittleEndian, false, 0.004,   0, 0,       32,         "MPa",        SignalKind::kPhysical,    {}},
  {Signal::kChamberPressures23PressureB2,        FrameType::kChamberPressures23,    "p_b_2",           25, 13, ByteOrder::kLittleEndian, false, 0.004,   0, 0,       32,         "MPa",        SignalKind::kPhysical,    {}},
  {Signal::kChamberPressures23PressureA3,        FrameType::kChamberPressures23,    "p_a_3",           38, 13, ByteOrder::kLittleEndian, false, 0.004,   0, 0,       32,         "MPa",        SignalKind::kPhysical,    {}},
  {Signal::kChamberPressures23PressureB3,        FrameType::kChamberPressures23,    "p_b_3",           51, 13, ByteOrder::kLittleEndian, false, 0.004,   0, 0,       32,         "MPa",        SignalKind::kPhysical,    {}},

  {Signal::kValveDriveChecksum,                  FrameType::kValveDrive,            "checksum",         0,  8, ByteOrder::kLittleEndian, false, 1,       0, 0,       255,        "",           SignalKind::kChecksum,    {}},
  {Signal::kValveDriveCounter,                   FrameType::kValveDrive,            "counter",          8,  4, ByteOrder::kLittleEndian, false, 1,       0, 0,       15,         "",           SignalKind::kCounter,     {}},
  {Signal::kValveDriveU0,                        FrameType::kValveDrive,            "u_0",             12, 13, ByteOrder::kLittleEndian, true,  0.00025, 0, -1,      1,          "",           SignalKind::kPhysical,    {}},
  {Signal::kValveDriveU1,                        FrameType::kValveDrive,            "u_1",             25, 13, ByteOrder::kLittleEndian, true,  0.00025, 0, -1,      1,          "",           SignalKind::kPhysical,    {}},
  {Signal::kValveDriveU2,                        FrameType::kValveDrive,            "u_2",             38, 13, ByteOrder::kLittleEndian, true,  0.00025, 0, -1,      1,          "",           SignalKind::kPhysical,    {}},
  {Signal::kValveDriveU3,                        FrameType::kValveDrive,            "u_3",             51, 13, ByteOrder::kLittleEndian, true,  0.00025, 0, -1,      1,          "",           SignalKind::kPhysical,    {}},
};
// clang-format on

// The signal of joint slot `joint` in a per-joint frame, from joint 0's (frames of one kind
// list the same signals in the same order, `stride` signals each).
constexpr Signal joint_signal(Signal of_joint_0, std::size_t joint, std::size_t stride) {
  return static_cast<Signal>(static_cast<std::size_t>(of_joint_0) + joint * stride);
}
inline constexpr std::size_t kJointFrameSignals = 5;  // JointState_j, JointSensor_j

// ---------------------------------------------------------------------------------------
// Messages: one plain struct per frame (a template over the joint slot for per-joint frames).

// Any valid EStop latches the safe state on every board that hears it; engage is 1 so that an
// all-zero payload never stops a robot by accident. Only clear_faults in idle releases it.
struct EStop {
  static constexpr FrameType kType = FrameType::kEStop;
  std::uint8_t engage = 1;
  std::uint8_t counter = 0;
  template <class Self, class Visitor>
  static constexpr void visit(Self& self, Visitor&& visitor) {
    visitor(Signal::kEStopCounter, self.counter);
    visitor(Signal::kEStopEngage, self.engage);
  }
};

struct ModeCommand {
  static constexpr FrameType kType = FrameType::kModeCommand;
  RequestedMode mode = RequestedMode::kIdle;
  bool clear_faults = false;       // clear latched faults and a latched E-stop (honoured in idle)
  bool zero_encoders = false;      // take the present angles as the zero posture (in idle)
  std::uint32_t host_time_us = 0;  // host clock, us modulo 2^32
  std::uint8_t counter = 0;
  template <class Self, class Visitor>
  static constexpr void visit(Self& self, Visitor&& visitor) {
    visitor(Signal::kModeCommandCounter, self.counter);
    visitor(Signal::kModeCommandRequestedMode, self.mode);
    visitor(Signal::kModeCommandClearFaults, self.clear_faults);
    visitor(Signal::kModeCommandZeroEncoders, self.zero_encoders);
    visitor(Signal::kModeCommandHostTime, self.host_time_us);
  }
};

// Slots beyond the board's joints are ignored by it (the host sends 0).
struct TorqueReference {
  static constexpr FrameType kType = FrameType::kTorqueReference;
  std::array<float, kMaxJointsPerBoard> tau{};  // N.m
  std::uint8_t counter = 0;
  template <class Self, class Visitor>
  static constexpr void visit(Self& self, Visitor&& visitor) {
    visitor(Signal::kTorqueReferenceCounter, self.counter);
    for (std::size_t j = 0; j < kMaxJointsPerBoard; ++j) {
      visitor(joint_signal(Signal::kTorqueReferenceTau0, j, 1), self.tau[j]);
    }
  }
};

// Body frame of the IMU (mounted on the torso, axes along the torso's).
struct ImuAngularVelocity {
  static constexpr FrameType kType = FrameType::kImuAngularVelocity;
  std::array<float, 3> omega{};  // rad/s
  std::uint8_t counter = 0;
  template <class Self, class Visitor>
  static constexpr void visit(Self& self, Visitor&& visitor) {
    visitor(Signal::kImuAngularVelocityCounter, self.counter);
    for (std::size_t i = 0; i < 3; ++i) {
      visitor(joint_signal(Signal::kImuAngularVelocityX, i, 1), self.omega[i]);
    }
  }
};

struct ImuLinearAcceleration {
  static constexpr FrameType kType = FrameType::kImuLinearAcceleration;
  std::array<float, 3> specific_force{};  // m/s^2, gravity included (an accelerometer's reading)
  std::uint8_t counter = 0;
  template <class Self, class Visitor>
  static constexpr void visit(Self& self, Visitor&& visitor) {
    visitor(Signal::kImuLinearAccelerationCounter, self.counter);
    for (std::size_t i = 0; i < 3; ++i) {
      visitor(joint_signal(Signal::kImuLinearAccelerationX, i, 1), self.specific_force[i]);
    }
  }
};

struct ImuAttitude {
  static constexpr FrameType kType = FrameType::kImuAttitude;
  float w = 1, x = 0, y = 0, z = 0;  // unit quaternion, body to world
  std::uint8_t counter = 0;
  template <class Self, class Visitor>
  static constexpr void visit(Self& self, Visitor&& visitor) {
    visitor(Signal::kImuAttitudeCounter, self.counter);
    visitor(Signal::kImuAttitudeW, self.w);
    visitor(Signal::kImuAttitudeX, self.x);
    visitor(Signal::kImuAttitudeY, self.y);
    visitor(Signal::kImuAttitudeZ, self.z);
  }
};

// Angle, velocity and torque of one joint: feedback to the host (JointState, zeroed angle) and,
// in the HIL, the board's local sensors (JointSensor: the raw encoder angle, before the board's
// offset; the load cell's torque).
template <FrameType kJoint0Type, Signal kJoint0Counter, std::size_t kJoint>
struct JointFrame {
  static_assert(kJoint < kMaxJointsPerBoard, "joint slots are 0..3");
  static constexpr FrameType kType = joint_frame(kJoint0Type, kJoint);
  static constexpr std::size_t kJointSlot = kJoint;
  float theta = 0;      // rad
  float theta_dot = 0;  // rad/s
  float tau = 0;        // N.m
  std::uint8_t counter = 0;
  template <class Self, class Visitor>
  static constexpr void visit(Self& self, Visitor&& visitor) {
    const Signal counter = joint_signal(kJoint0Counter, kJoint, kJointFrameSignals);
    visitor(counter, self.counter);
    visitor(joint_signal(counter, 1, 1), self.theta);
    visitor(joint_signal(counter, 2, 1), self.theta_dot);
    visitor(joint_signal(counter, 3, 1), self.tau);
  }
};
template <std::size_t kJoint>
using JointState = JointFrame<FrameType::kJointState0, Signal::kJointState0Counter, kJoint>;
template <std::size_t kJoint>
using JointSensor = JointFrame<FrameType::kJointSensor0, Signal::kJointSensor0Counter, kJoint>;

// The valve command of each joint, normalised to the rated spool opening: telemetry to the host
// (ValveCommands) and, in the HIL, the board's valve drivers (ValveDrive).
template <FrameType kFrameType, Signal kCounter>
struct ValveFrame {
  static constexpr FrameType kType = kFrameType;
  std::array<float, kMaxJointsPerBoard> u{};
  std::uint8_t counter = 0;
  template <class Self, class Visitor>
  static constexpr void visit(Self& self, Visitor&& visitor) {
    visitor(kCounter, self.counter);
    for (std::size_t j = 0; j < kMaxJointsPerBoard; ++j) {
      visitor(joint_signal(kCounter, 1 + j, 1), self.u[j]);
    }
  }
};
using ValveCommands = ValveFrame<FrameType::kValveCommands, Signal::kValveCommandsCounter>;
using ValveDrive = ValveFrame<FrameType::kValveDrive, Signal::kValveDriveCounter>;

// Event counters count modulo 256; the host takes differences.
struct BoardStatus {
  static constexpr FrameType kType = FrameType::kBoardStatus;
  BoardMode mode = BoardMode::kBoot;
  std::uint16_t faults = 0;  // fault:: bits
  std::uint8_t joints = 1;   // joints this board drives
  std::uint8_t protocol_version = kProtocolVersion;
  std::uint8_t rejected_frames = 0;  // RejectCounters::total()
  std::uint8_t watchdog_trips = 0;
  std::uint8_t overruns = 0;
  std::uint8_t counter = 0;
  template <class Self, class Visitor>
  static constexpr void visit(Self& self, Visitor&& visitor) {
    visitor(Signal::kBoardStatusCounter, self.counter);
    visitor(Signal::kBoardStatusMode, self.mode);
    visitor(Signal::kBoardStatusFaults, self.faults);
    visitor(Signal::kBoardStatusJoints, self.joints);
    visitor(Signal::kBoardStatusProtocolVersion, self.protocol_version);
    visitor(Signal::kBoardStatusRejectedFrames, self.rejected_frames);
    visitor(Signal::kBoardStatusWatchdogTrips, self.watchdog_trips);
    visitor(Signal::kBoardStatusOverruns, self.overruns);
  }
};

struct TorqueGains {
  static constexpr FrameType kType = FrameType::kTorqueGains;
  std::uint8_t joint = 0;
  float kp = 0;    // 1/(N.m): valve command per N.m of torque error
  float ki = 0;    // 1/(N.m s)
  float k_lv = 0;  // s/rad: load-velocity feedback, valve command per rad/s
  std::uint8_t counter = 0;
  template <class Self, class Visitor>
  static constexpr void visit(Self& self, Visitor&& visitor) {
    visitor(Signal::kTorqueGainsCounter, self.counter);
    visitor(Signal::kTorqueGainsJoint, self.joint);
    visitor(Signal::kTorqueGainsKp, self.kp);
    visitor(Signal::kTorqueGainsKi, self.ki);
    visitor(Signal::kTorqueGainsLoadVelocity, self.k_lv);
  }
};

struct HoldGains {
  static constexpr FrameType kType = FrameType::kHoldGains;
  std::uint8_t joint = 0;
  float kp = 0;  // N.m/rad
  float ki = 0;  // N.m/(rad s)
  float kd = 0;  // N.m s/rad
  std::uint8_t counter = 0;
  template <class Self, class Visitor>
  static constexpr void visit(Self& self, Visitor&& visitor) {
    visitor(Signal::kHoldGainsCounter, self.counter);
    visitor(Signal::kHoldGainsJoint, self.joint);
    visitor(Signal::kHoldGainsKp, self.kp);
    visitor(Signal::kHoldGainsKi, self.ki);
    visitor(Signal::kHoldGainsKd, self.kd);
  }
};

// A joint's angle = encoder reading - offset.
struct EncoderOffset {
  static constexpr FrameType kType = FrameType::kEncoderOffset;
  std::uint8_t joint = 0;
  float offset = 0;     // rad
  bool zeroed = false;  // the offset was taken since boot (not the stored default)
  std::uint8_t counter = 0;
  template <class Self, class Visitor>
  static constexpr void visit(Self& self, Visitor&& visitor) {
    visitor(Signal::kEncoderOffsetCounter, self.counter);
    visitor(Signal::kEncoderOffsetJoint, self.joint);
    visitor(Signal::kEncoderOffsetOffset, self.offset);
    visitor(Signal::kEncoderOffsetZeroed, self.zeroed);
  }
};

// HIL lock-step clock, one per simulated millisecond for every board on the I/O bus, after
// that millisecond's sensor frames (the forearm protocol's Sync, bus-wide here).
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

// Chamber pressures of two joints (slots 0 and 1, or 2 and 3), gauge.
template <FrameType kFrameType, Signal kCounter>
struct ChamberPressures {
  static constexpr FrameType kType = kFrameType;
  std::array<float, 2> p_a{};  // MPa, piston side
  std::array<float, 2> p_b{};  // MPa, rod side
  std::uint8_t counter = 0;
  template <class Self, class Visitor>
  static constexpr void visit(Self& self, Visitor&& visitor) {
    visitor(kCounter, self.counter);
    for (std::size_t i = 0; i < 2; ++i) {
      visitor(joint_signal(kCounter, 1 + 2 * i, 1), self.p_a[i]);
      visitor(joint_signal(kCounter, 2 + 2 * i, 1), self.p_b[i]);
    }
  }
};
using ChamberPressures01 =
    ChamberPressures<FrameType::kChamberPressures01, Signal::kChamberPressures01Counter>;
using ChamberPressures23 =
    ChamberPressures<FrameType::kChamberPressures23, Signal::kChamberPressures23Counter>;

// ---------------------------------------------------------------------------------------
// The description the codec reads, and the codec over it

struct Description {
  using FrameType = joint_protocol::FrameType;
  using Signal = joint_protocol::Signal;
  static constexpr const protocol::IdLayout& kIds = joint_protocol::kIds;
  static constexpr const auto& kFrames = joint_protocol::kFrames;
  static constexpr const auto& kSignals = joint_protocol::kSignals;
};
constexpr Description protocol_of(FrameType) { return {}; }
constexpr Description protocol_of(Signal) { return {}; }

using Messages = protocol::MessageList<
    EStop, ModeCommand, TorqueReference, ImuAngularVelocity, ImuLinearAcceleration, ImuAttitude,
    JointState<0>, JointState<1>, JointState<2>, JointState<3>, ValveCommands, BoardStatus,
    TorqueGains, HoldGains, EncoderOffset, Sync, JointSensor<0>, JointSensor<1>, JointSensor<2>,
    JointSensor<3>, ChamberPressures01, ChamberPressures23, ValveDrive>;
static_assert(protocol::is_well_formed<Description>(Messages{}),
              "tables or messages break a rule of codec.hpp (see its compile-time checks)");

using CounterTracker = protocol::CounterTracker<Description>;
using Receiver = protocol::Receiver<Description>;
using Sender = protocol::Sender<Description>;

// ---------------------------------------------------------------------------------------
// Bus load

enum class Bus : std::uint8_t { kRobot, kIo };

struct BusLayout {
  unsigned boards = 2;            // joint boards on the bus
  unsigned joints_per_board = 4;  // 1..kMaxJointsPerBoard
  bool imu = true;                // the torso IMU on the robot bus
  double control_period_ms = kDefaultControlPeriodMs;
};

// Fraction of a bus at bitrate_bps that the periodic frames of `layout` use, worst-case
// stuffing. Per board: the frames of its joints; once per bus: the IMU's and the Sync.
constexpr double bus_load(Bus bus, std::uint32_t bitrate_bps, const BusLayout& layout) {
  double bits_per_second = 0;
  for (const FrameSpec& frame : kFrames) {
    if (frame.cycle_time_ms == 0 || on_io_bus(frame) != (bus == Bus::kIo)) continue;
    const double period = frame.cycle_time_ms == kDefaultControlPeriodMs ? layout.control_period_ms
                                                                         : frame.cycle_time_ms;
    double copies = layout.boards;
    if (frame.sender == Endpoint::kImu) copies = layout.imu ? 1 : 0;
    if (frame.bus_wide) copies = 1;
    const std::size_t first_joint = first_joint_of(frame.type);
    if (first_joint < kMaxJointsPerBoard && first_joint >= layout.joints_per_board) copies = 0;
    bits_per_second += protocol::frame_bits_per_second(copies, period);
  }
  return bits_per_second / bitrate_bps;
}

}  // namespace hmpc::joint_protocol
