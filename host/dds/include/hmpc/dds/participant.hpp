// One DDS participant on a domain, and the topic names and QoS profiles of ROS 2, so that a
// ROS 2 machine on the same domain sees our topics as its own.
#pragma once

#include <dds/dds.h>

#include <cstdint>
#include <string>

namespace hmpc::dds {

// ROS 2's QoS habits (rmw_qos_profile_sensor_data, rmw_qos_profile_default), and commands that
// must keep coming: a reader of commands requests a deadline and a liveliness lease, so that a
// commander who stops sending, or whose process dies, is noticed within them. DDS matches a
// command reader only with writers offering at least as much (rclcpp: QoS::deadline() and
// QoS::liveliness_lease_duration() no longer than these).
enum class QosProfile {
  kSensorData,  // best effort, keep last 5, volatile
  kDefault,     // reliable, keep last 10, volatile: state, telemetry, diagnostics
  kCommand,     // reliable, keep last 10, volatile, deadline and automatic liveliness
};

// A commander repeats its ModeCommand within this (the command topics' deadline and liveliness
// lease); half a second of silence is long enough not to trip on a busy machine and short
// enough that a lost operator is noticed before the robot has gone far.
inline constexpr double kCommandDeadlineS = 0.5;

struct Qos {
  QosProfile profile = QosProfile::kDefault;
  double deadline_s = 0;  // kCommand only: the longest gap between two samples
  double lease_s = 0;     // kCommand only: liveliness lease

  static Qos sensor_data() { return {QosProfile::kSensorData, 0, 0}; }
  static Qos state() { return {QosProfile::kDefault, 0, 0}; }
  static Qos command(double deadline_s) { return {QosProfile::kCommand, deadline_s, deadline_s}; }
};

// The DDS topic of a ROS 2 topic name: "rt" + name, e.g. "/hmpc/forearm_0/joint_states" ->
// "rt/hmpc/forearm_0/joint_states". std::invalid_argument unless name is absolute and made of
// ROS 2's name characters (letters, digits, '_', '/' between non-empty tokens not starting with
// a digit).
std::string dds_topic_name(const std::string& ros_name);

// A Cyclone DDS configuration (XML) for loopback only: interface 127.0.0.1, no multicast,
// unicast discovery of participant indices 0..20 on 127.0.0.1. For tests, the HIL guest (whose
// lo has no multicast) and the programs' --dds-loopback.
std::string loopback_config();

// A participant. `config` is Cyclone DDS configuration XML (or file names, as in
// CYCLONEDDS_URI) for the domain; empty uses Cyclone's default (CYCLONEDDS_URI if set). All
// participants of one process on one domain share that domain: the first one's config applies,
// a different config later throws std::runtime_error, and so does any failure to create the
// participant or, later, its topics, readers and writers. Deleting the participant deletes them.
class Participant {
 public:
  explicit Participant(std::uint32_t domain_id, const std::string& config = {});
  ~Participant();
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;

  // A topic of this type under the DDS name of ros_name (dds_topic_name()).
  dds_entity_t topic(const dds_topic_descriptor_t& type, const std::string& ros_name) const;
  // A writer or reader on topic with the profile's QoS.
  dds_entity_t writer(dds_entity_t topic, const Qos& qos) const;
  dds_entity_t reader(dds_entity_t topic, const Qos& qos) const;

  dds_entity_t handle() const { return handle_; }

 private:
  std::uint32_t domain_id_;
  dds_entity_t handle_;
};

// Throws std::runtime_error naming what could not be created when entity is an error code.
dds_entity_t checked(dds_entity_t entity, const std::string& what);

// Seconds as a DDS timeout: <= 0 or NaN is "do not wait", beyond a week is a week.
dds_duration_t to_duration(double seconds);

}  // namespace hmpc::dds
