#include "hmpc/dds/bridge.hpp"

#include <cstdio>

namespace hmpc::dds {

std::string namespace_or(const std::string& ros_namespace, const std::string& fallback) {
  std::string ns = ros_namespace.empty() ? fallback : ros_namespace;
  dds_topic_name(ns);  // throws std::invalid_argument for a bad name
  return ns;
}

void log_rejection(RejectCounters& rejects, const char* program, const std::string& ros_namespace,
                   const char* what, const Verdict& verdict) {
  rejects.add(verdict.reason);
  std::fprintf(stderr, "%s: %s rejected a %s: %s: %s\n", program, ros_namespace.c_str(), what,
               rejection_name(verdict.reason), verdict.detail.c_str());
}

bool write_diagnostics(const Writer<msg::DiagnosticArray>& writer, double now,
                       DiagnosticLevel level, const char* name, const char* message,
                       const char* hardware_id, const msg::KeyValue* values, std::size_t count) {
  msg::DiagnosticStatus status{};
  status.level = static_cast<std::uint8_t>(level);
  status.name = borrow(name);
  status.message = borrow(message);
  status.hardware_id = borrow(hardware_id);
  status.values = borrow<decltype(status.values)>(values, count);
  msg::DiagnosticArray array{};
  array.header.stamp = from_seconds<msg::Time>(now);
  array.header.frame_id = borrow("");
  array.status = borrow<decltype(array.status)>(&status, 1);
  return writer.write(array);
}

}  // namespace hmpc::dds
