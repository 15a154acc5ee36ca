// The message types on our DDS topics: the C structs idlc generates from host/dds/idl (ROS 2's
// standard definitions and our own hmpc_msgs in their style), under short C++ names.
//
// A received message points into memory DDS lends for the duration of a callback; a message to
// send points at the caller's memory through borrow(), so neither side copies or allocates.
#pragma once

#include <dds/dds.h>

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "builtin_interfaces/msg/Duration.h"
#include "builtin_interfaces/msg/Time.h"
#include "diagnostic_msgs/msg/DiagnosticArray.h"
#include "hmpc_msgs/msg/CostWeights.h"
#include "hmpc_msgs/msg/ForearmTelemetry.h"
#include "hmpc_msgs/msg/ModeCommand.h"
#include "hmpc_msgs/msg/MpcPlan.h"
#include "hmpc_msgs/msg/TaskCommand.h"
#include "nav_msgs/msg/Odometry.h"
#include "sensor_msgs/msg/Imu.h"
#include "sensor_msgs/msg/JointState.h"
#include "trajectory_msgs/msg/JointTrajectory.h"

namespace hmpc::dds {

namespace msg {
using Time = builtin_interfaces_msg_dds__Time_;
using Duration = builtin_interfaces_msg_dds__Duration_;
using Header = std_msgs_msg_dds__Header_;
using JointState = sensor_msgs_msg_dds__JointState_;
using Imu = sensor_msgs_msg_dds__Imu_;
using Odometry = nav_msgs_msg_dds__Odometry_;
using JointTrajectory = trajectory_msgs_msg_dds__JointTrajectory_;
using JointTrajectoryPoint = trajectory_msgs_msg_dds__JointTrajectoryPoint_;
using DiagnosticArray = diagnostic_msgs_msg_dds__DiagnosticArray_;
using DiagnosticStatus = diagnostic_msgs_msg_dds__DiagnosticStatus_;
using KeyValue = diagnostic_msgs_msg_dds__KeyValue_;
using ModeCommand = hmpc_msgs_msg_dds__ModeCommand_;
using CostWeights = hmpc_msgs_msg_dds__CostWeights_;
using ForearmTelemetry = hmpc_msgs_msg_dds__ForearmTelemetry_;
using MpcPlan = hmpc_msgs_msg_dds__MpcPlan_;
using TaskCommand = hmpc_msgs_msg_dds__TaskCommand_;
using Pose = geometry_msgs_msg_dds__Pose_;
using Twist = geometry_msgs_msg_dds__Twist_;
}  // namespace msg

// diagnostic_msgs/DiagnosticStatus's level constants.
enum class DiagnosticLevel : std::uint8_t { kOk = 0, kWarn = 1, kError = 2, kStale = 3 };

// hmpc_msgs/ModeCommand's mode values.
enum class CommandMode : std::uint8_t { kIdle = 1, kHold = 2, kRun = 3 };

// The type support idlc generated for each message, for creating its topics.
template <class Message>
const dds_topic_descriptor_t& descriptor();

#define HMPC_DDS_DESCRIPTOR(Message, generated)                \
  template <>                                                  \
  inline const dds_topic_descriptor_t& descriptor<Message>() { \
    return generated;                                          \
  }
HMPC_DDS_DESCRIPTOR(msg::JointState, sensor_msgs_msg_dds__JointState__desc)
HMPC_DDS_DESCRIPTOR(msg::Imu, sensor_msgs_msg_dds__Imu__desc)
HMPC_DDS_DESCRIPTOR(msg::Odometry, nav_msgs_msg_dds__Odometry__desc)
HMPC_DDS_DESCRIPTOR(msg::JointTrajectory, trajectory_msgs_msg_dds__JointTrajectory__desc)
HMPC_DDS_DESCRIPTOR(msg::DiagnosticArray, diagnostic_msgs_msg_dds__DiagnosticArray__desc)
HMPC_DDS_DESCRIPTOR(msg::ModeCommand, hmpc_msgs_msg_dds__ModeCommand__desc)
HMPC_DDS_DESCRIPTOR(msg::CostWeights, hmpc_msgs_msg_dds__CostWeights__desc)
HMPC_DDS_DESCRIPTOR(msg::ForearmTelemetry, hmpc_msgs_msg_dds__ForearmTelemetry__desc)
HMPC_DDS_DESCRIPTOR(msg::MpcPlan, hmpc_msgs_msg_dds__MpcPlan__desc)
HMPC_DDS_DESCRIPTOR(msg::TaskCommand, hmpc_msgs_msg_dds__TaskCommand__desc)
#undef HMPC_DDS_DESCRIPTOR

// A sequence over the caller's n elements; DDS reads them and never frees them. The generated C
// types take non-const pointers for both directions: writing never modifies them.
template <class Sequence, class Element>
Sequence borrow(const Element* elements, std::size_t n) {
  Sequence s{};
  s._maximum = s._length = static_cast<std::uint32_t>(n);
  s._buffer = const_cast<Element*>(elements);  // NOLINT(cppcoreguidelines-pro-type-const-cast)
  s._release = false;
  return s;
}
inline dds_sequence_double borrow(const double* values, std::size_t n) {
  return borrow<dds_sequence_double>(values, n);
}
// Strings are NUL-terminated; the generated type's char* is never written through.
inline dds_sequence_string borrow(const char* const* strings, std::size_t n) {
  dds_sequence_string s{};
  s._maximum = s._length = static_cast<std::uint32_t>(n);
  s._buffer = const_cast<char**>(strings);  // NOLINT(cppcoreguidelines-pro-type-const-cast)
  s._release = false;
  return s;
}
inline char* borrow(const char* text) {
  return const_cast<char*>(text);  // NOLINT(cppcoreguidelines-pro-type-const-cast)
}

// builtin_interfaces/Time and Duration from seconds (nanosec in 0..999999999, as the definition
// requires) and back.
template <class TimeOrDuration>
TimeOrDuration from_seconds(double seconds) {
  double sec = std::floor(seconds);
  double nanosec = std::round((seconds - sec) * 1e9);
  if (nanosec >= 1e9) {
    sec += 1;
    nanosec = 0;
  }
  TimeOrDuration t{};
  t.sec = static_cast<std::int32_t>(sec);
  t.nanosec = static_cast<std::uint32_t>(nanosec);
  return t;
}
template <class TimeOrDuration>
double to_seconds(const TimeOrDuration& t) {
  return double(t.sec) + 1e-9 * double(t.nanosec);
}

// The wall clock (Unix time) that ROS 2 stamps headers with.
double unix_time_s();

}  // namespace hmpc::dds
