// What every robot's DDS bridge does the same way: its namespace, its diagnostics, the log of
// what it rejects, and the watch on a commander who must keep sending.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "hmpc/dds/endpoint.hpp"
#include "hmpc/dds/validation.hpp"

namespace hmpc::dds {

// A bridge's diagnostics go out when they change, and at least this often (ROS 2's
// diagnostic_updater publishes once a second).
inline constexpr double kDiagnosticsPeriodS = 1.0;

// `ros_namespace`, or `fallback` when it is empty; std::invalid_argument for a bad name.
std::string namespace_or(const std::string& ros_namespace, const std::string& fallback);

// Counts a rejected sample and logs it to stderr, one line: "<program>: <ns> rejected a <what>:
// <reason>: <detail>".
void log_rejection(RejectCounters& rejects, const char* program, const std::string& ros_namespace,
                   const char* what, const Verdict& verdict);

// A JointState over the caller's n names and values, stamped `stamp`.
inline msg::JointState joint_state(const msg::Time& stamp, const char* const* names,
                                   const double* position, const double* velocity,
                                   const double* effort, std::size_t n) {
  msg::JointState joint{};
  joint.header.stamp = stamp;
  joint.header.frame_id = borrow("");
  joint.name = borrow(names, n);
  joint.position = borrow(position, n);
  joint.velocity = borrow(velocity, n);
  joint.effort = borrow(effort, n);
  return joint;
}

// One DiagnosticStatus in a DiagnosticArray stamped `now`, its key-value pairs the caller's.
bool write_diagnostics(const Writer<msg::DiagnosticArray>& writer, double now,
                       DiagnosticLevel level, const char* name, const char* message,
                       const char* hardware_id, const msg::KeyValue* values, std::size_t count);

// The commander in charge falls silent when its command reader's deadline passes without a
// command (a process that hangs, or whose liveliness lapsed), or when the writer of its last
// command leaves (a process that ended or died; other writers come and go without effect).
class CommanderWatch {
 public:
  // A command that puts `writer` in charge.
  void took_charge(dds_instance_handle_t writer) {
    commander_ = writer;
    in_charge_ = true;
  }
  // A command after which nobody need keep sending.
  void released() { in_charge_ = false; }
  // After taking a reader's samples: true once when the commander in charge fell silent.
  bool fell_silent(const Reader<msg::ModeCommand>& commands) {
    const std::uint32_t misses = commands.deadline_misses();
    const bool silent = misses > deadline_misses_ || !commands.matched(commander_);
    deadline_misses_ = misses;
    if (!silent || !in_charge_) return false;
    in_charge_ = false;
    ++silences_;
    return true;
  }
  std::uint64_t silences() const { return silences_; }

 private:
  dds_instance_handle_t commander_ = 0;
  bool in_charge_ = false;
  std::uint32_t deadline_misses_ = 0;
  std::uint64_t silences_ = 0;
};

}  // namespace hmpc::dds
