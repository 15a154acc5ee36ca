// Cyclone DDS behind hmpc/dds/forearm_dds.hpp: C types generated from forearm.idl, converted
// field by field to and from the plain structs users see.
#include "hmpc/dds/forearm_dds.hpp"

#include <dds/dds.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <mutex>
#include <stdexcept>
#include <utility>

#include "forearm.h"
#include "hmpc/models/forearm.hpp"

namespace hmpc::dds {

namespace {

// ------------------------------------------------------------------------ checking commands

template <class... Numbers>
std::string format(const char* pattern, Numbers... numbers) {
  char text[256];
  std::snprintf(text, sizeof text, pattern, double(numbers)...);
  return text;
}

ValidationResult reject(std::string reason) { return {false, std::move(reason)}; }

// Empty when value is finite and in [min, max].
std::string check_range(const char* field, double value, double min, double max, const char* unit) {
  if (!std::isfinite(value)) return std::string(field) + format(" is not finite (%g)", value);
  if (value < min || value > max) {
    return std::string(field) + format(" %g is outside %g..%g ", value, min, max) + unit;
  }
  return {};
}

// ------------------------------------------------------------------------ domains

// Cyclone runs one domain instance per domain id and process. A domain created with a
// configuration (dds_create_domain) lives until its handle is deleted, which also deletes
// every participant in it: count the users, delete it with the last one.
class DomainRegistry {
 public:
  static DomainRegistry& instance() {
    static DomainRegistry registry;
    return registry;
  }

  void acquire(std::uint32_t domain_id, const std::string& config) {
    const std::lock_guard<std::mutex> lock(mutex_);
    auto found = domains_.find(domain_id);
    if (found != domains_.end()) {
      if (!config.empty() && config != found->second.config) {
        throw std::runtime_error("DDS domain " + std::to_string(domain_id) +
                                 " is already in use in this process with another configuration");
      }
      ++found->second.users;
      return;
    }
    if (config.empty()) return;  // Cyclone's implicit domain, counted by Cyclone itself
    const dds_entity_t handle = dds_create_domain(domain_id, config.c_str());
    if (handle == DDS_RETCODE_PRECONDITION_NOT_MET) {
      throw std::runtime_error("DDS domain " + std::to_string(domain_id) +
                               " is already in use in this process without the configuration");
    }
    if (handle < 0) {
      throw std::runtime_error("cannot create DDS domain " + std::to_string(domain_id) +
                               " with the given configuration (" + dds_strretcode(handle) +
                               "); Cyclone's message on stderr says why");
    }
    domains_.emplace(domain_id, Domain{handle, config, 1});
  }

  void release(std::uint32_t domain_id) {
    const std::lock_guard<std::mutex> lock(mutex_);
    auto found = domains_.find(domain_id);
    if (found == domains_.end() || --found->second.users > 0) return;
    dds_delete(found->second.handle);
    domains_.erase(found);
  }

 private:
  struct Domain {
    dds_entity_t handle;
    std::string config;
    int users;
  };
  std::mutex mutex_;
  std::map<std::uint32_t, Domain> domains_;
};

std::string describe(const char* what, dds_return_t rc) {
  return std::string("cannot create ") + what + ": " + dds_strretcode(rc);
}

dds_entity_t checked(dds_entity_t entity, const char* what) {
  if (entity < 0) throw std::runtime_error(describe(what, entity));
  return entity;
}

// One participant on a domain, with the QoS all our readers and writers use. Deleting the
// participant deletes its topics, readers, writers and waitsets.
class Participant {
 public:
  Participant(std::uint32_t domain_id, const std::string& config) : domain_id_(domain_id) {
    DomainRegistry::instance().acquire(domain_id, config);
    handle_ = dds_create_participant(domain_id, nullptr, nullptr);
    if (handle_ < 0) {
      DomainRegistry::instance().release(domain_id);
      throw std::runtime_error(
          describe(("a DDS participant on domain " + std::to_string(domain_id)).c_str(), handle_));
    }
    qos_ = dds_create_qos();
    // Reliable with a short keep-last history: a write never blocks the control loop, and a
    // late reader gets the latest samples of each node.
    dds_qset_reliability(qos_, DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
    dds_qset_history(qos_, DDS_HISTORY_KEEP_LAST, kHistoryDepth);
  }
  ~Participant() {
    dds_delete_qos(qos_);
    dds_delete(handle_);
    DomainRegistry::instance().release(domain_id_);
  }
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;

  dds_entity_t topic(const dds_topic_descriptor_t& descriptor, const char* name) const {
    return checked(dds_create_topic(handle_, &descriptor, name, qos_, nullptr),
                   (std::string("DDS topic ") + name).c_str());
  }
  dds_entity_t writer(dds_entity_t topic, const char* name) const {
    return checked(dds_create_writer(handle_, topic, qos_, nullptr),
                   (std::string("DDS writer of ") + name).c_str());
  }
  dds_entity_t reader(dds_entity_t topic, const char* name) const {
    return checked(dds_create_reader(handle_, topic, qos_, nullptr),
                   (std::string("DDS reader of ") + name).c_str());
  }
  dds_entity_t handle() const { return handle_; }

 private:
  std::uint32_t domain_id_;
  dds_entity_t handle_;
  dds_qos_t* qos_ = nullptr;
};

// Takes every pending sample of reader in batches, calling visit on those with data (the
// others announce a writer's disposal or departure).
template <class CSample, class Visit>
void take_all(dds_entity_t reader, Visit&& visit) {
  constexpr std::size_t kBatch = 16;
  std::array<CSample, kBatch> samples{};
  std::array<void*, kBatch> pointers{};
  for (std::size_t i = 0; i < kBatch; ++i) pointers[i] = &samples[i];
  std::array<dds_sample_info_t, kBatch> infos{};
  for (;;) {
    const dds_return_t n = dds_take(reader, pointers.data(), infos.data(), kBatch, kBatch);
    if (n <= 0) return;
    for (dds_return_t i = 0; i < n; ++i) {
      if (infos[i].valid_data) visit(samples[i]);
    }
    if (static_cast<std::size_t>(n) < kBatch) return;
  }
}

dds_duration_t to_duration(double timeout_s) {
  // A week is "forever" here, and stays far inside dds_duration_t.
  constexpr double kLongest = 7 * 86400.0;
  if (!(timeout_s > 0)) return 0;
  return static_cast<dds_duration_t>(1e9 * (timeout_s < kLongest ? timeout_s : kLongest));
}

// ------------------------------------------------------------------------ conversions

hmpc_dds_ForearmState to_c(const ForearmStateSample& s) {
  hmpc_dds_ForearmState c{};
  c.node = s.node;
  c.board_time_s = s.board_time_s;
  c.mode = static_cast<std::uint8_t>(s.mode);
  c.faults = s.faults;
  c.strategy = static_cast<std::uint8_t>(s.strategy);
  c.theta = s.theta;
  c.theta_dot = s.theta_dot;
  c.pressure_mpa = s.pressure_mpa;
  c.theta_d = s.theta_d;
  c.v_p = s.v_p;
  c.v_m = s.v_m;
  c.tau_p = s.tau_p;
  c.tau_m = s.tau_m;
  c.rejected_frames = s.rejected_frames;
  c.watchdog_trips = s.watchdog_trips;
  c.solver_failures = s.solver_failures;
  c.overruns = s.overruns;
  return c;
}

ForearmStateSample from_c(const hmpc_dds_ForearmState& c) {
  ForearmStateSample s;
  s.node = c.node;
  s.board_time_s = c.board_time_s;
  s.mode = static_cast<proto::BoardMode>(c.mode);
  s.faults = c.faults;
  s.strategy = static_cast<proto::Strategy>(c.strategy);
  s.theta = c.theta;
  s.theta_dot = c.theta_dot;
  s.pressure_mpa = c.pressure_mpa;
  s.theta_d = c.theta_d;
  s.v_p = c.v_p;
  s.v_m = c.v_m;
  s.tau_p = c.tau_p;
  s.tau_m = c.tau_m;
  s.rejected_frames = c.rejected_frames;
  s.watchdog_trips = c.watchdog_trips;
  s.solver_failures = c.solver_failures;
  s.overruns = c.overruns;
  return s;
}

hmpc_dds_ForearmTelemetry to_c(const ForearmTelemetrySample& s) {
  hmpc_dds_ForearmTelemetry c{};
  c.node = s.node;
  c.time_s = s.time_s;
  c.solve_status = static_cast<std::uint8_t>(s.solve_status);
  c.coarse_iterations = s.coarse_iterations;
  c.fine_iterations = s.fine_iterations;
  c.solve_time_us = s.solve_time_us;
  c.tracking_error = s.tracking_error;
  return c;
}

ForearmTelemetrySample from_c(const hmpc_dds_ForearmTelemetry& c) {
  ForearmTelemetrySample s;
  s.node = c.node;
  s.time_s = c.time_s;
  s.solve_status = static_cast<proto::SolveStatusCode>(c.solve_status);
  s.coarse_iterations = c.coarse_iterations;
  s.fine_iterations = c.fine_iterations;
  s.solve_time_us = c.solve_time_us;
  s.tracking_error = c.tracking_error;
  return s;
}

hmpc_dds_ForearmCommand to_c(const ForearmCommandSample& s) {
  hmpc_dds_ForearmCommand c{};
  c.node = s.node;
  c.sequence_number = s.sequence_number;
  c.mode = static_cast<std::uint8_t>(s.mode);
  c.strategy = static_cast<std::uint8_t>(s.strategy);
  c.clear_faults = s.clear_faults;
  c.target.kind = static_cast<std::uint8_t>(s.target.kind);
  c.target.amplitude_rad = s.target.amplitude_rad;
  c.target.frequency_hz = s.target.frequency_hz;
  c.target.offset_rad = s.target.offset_rad;
  c.target.duration_s = s.target.duration_s;
  return c;
}

ForearmCommandSample from_c(const hmpc_dds_ForearmCommand& c) {
  ForearmCommandSample s;
  s.node = c.node;
  s.sequence_number = c.sequence_number;
  s.mode = static_cast<proto::RequestedMode>(c.mode);
  s.strategy = static_cast<proto::Strategy>(c.strategy);
  s.clear_faults = c.clear_faults;
  s.target.kind = static_cast<TargetKind>(c.target.kind);
  s.target.amplitude_rad = c.target.amplitude_rad;
  s.target.frequency_hz = c.target.frequency_hz;
  s.target.offset_rad = c.target.offset_rad;
  s.target.duration_s = c.target.duration_s;
  return s;
}

}  // namespace

// ------------------------------------------------------------------------ validation

const CommandLimits& command_limits() {
  static const CommandLimits limits = [] {
    const forearm::Parameters<double> arm{};
    CommandLimits l;
    l.theta_min_rad = arm.soft_limit_lower;
    l.theta_max_rad = arm.soft_limit_upper;
    return l;
  }();
  return limits;
}

ValidationResult validate(const ForearmCommandSample& command) {
  const CommandLimits& limits = command_limits();
  if (command.node > proto::kMaxNodeId) {
    return reject(format("node %g is outside 0..%g", command.node, proto::kMaxNodeId));
  }
  const auto mode = static_cast<unsigned>(command.mode);
  if (mode < static_cast<unsigned>(proto::RequestedMode::kIdle) ||
      mode > static_cast<unsigned>(proto::RequestedMode::kRun)) {
    return reject(format("mode %g is not idle (1), hold (2) or run (3)", mode));
  }
  const auto strategy = static_cast<unsigned>(command.strategy);
  if (strategy > static_cast<unsigned>(proto::Strategy::kPamOnly)) {
    return reject(
        format("strategy %g is not one of 0..5 (fine 4 ms, fine 8 ms, coarse 20 ms, "
               "coarse 40 ms, two-stage, PAM-only)",
               strategy));
  }
  const CommandTarget& target = command.target;
  const auto kind = static_cast<unsigned>(target.kind);
  if (kind > static_cast<unsigned>(TargetKind::kSinusoid)) {
    return reject(format("target.kind %g is not hold-current (0) or sinusoid (1)", kind));
  }
  const std::string problem[] = {
      check_range("target.amplitude_rad", target.amplitude_rad, 0, limits.max_amplitude_rad, "rad"),
      check_range("target.frequency_hz", target.frequency_hz, 0, limits.max_frequency_hz, "Hz"),
      check_range("target.offset_rad", target.offset_rad, -limits.max_abs_offset_rad,
                  limits.max_abs_offset_rad, "rad"),
      check_range("target.duration_s", target.duration_s, 0, limits.max_duration_s, "s"),
  };
  for (const std::string& p : problem) {
    if (!p.empty()) return reject(p);
  }
  const double low = target.offset_rad - target.amplitude_rad;
  const double high = target.offset_rad + target.amplitude_rad;
  if (low < limits.theta_min_rad || high > limits.theta_max_rad) {
    return reject(
        format("target.offset_rad +- target.amplitude_rad spans %g..%g rad, beyond the "
               "board's software joint limits %g..%g rad",
               low, high, limits.theta_min_rad, limits.theta_max_rad));
  }
  return {};
}

std::string loopback_config() {
  // ParticipantIndex auto gives each process a unicast discovery port of its own; Peers
  // 127.0.0.1 makes discovery probe the ports of indices 0..MaxAutoParticipantIndex there,
  // which is what replaces multicast discovery. 20 processes per domain is plenty for a
  // host controller, a few operators and tests.
  return "<CycloneDDS><Domain id=\"any\">"
         "<General><Interfaces><NetworkInterface address=\"127.0.0.1\"/></Interfaces>"
         "<AllowMulticast>false</AllowMulticast></General>"
         "<Discovery><ParticipantIndex>auto</ParticipantIndex>"
         "<MaxAutoParticipantIndex>20</MaxAutoParticipantIndex>"
         "<Peers><Peer address=\"127.0.0.1\"/></Peers></Discovery>"
         "</Domain></CycloneDDS>";
}

// ------------------------------------------------------------------------ bridge

struct ForearmDdsBridge::Impl {
  Impl(std::uint32_t domain_id, proto::NodeId node_id, const std::string& config)
      : node(node_id), participant(domain_id, config),
        state_writer(participant.writer(participant.topic(hmpc_dds_ForearmState_desc, kStateTopic),
                                        kStateTopic)),
        telemetry_writer(participant.writer(
            participant.topic(hmpc_dds_ForearmTelemetry_desc, kTelemetryTopic), kTelemetryTopic)),
        command_reader(participant.reader(
            participant.topic(hmpc_dds_ForearmCommand_desc, kCommandTopic), kCommandTopic)) {}

  proto::NodeId node;
  Participant participant;
  dds_entity_t state_writer;
  dds_entity_t telemetry_writer;
  dds_entity_t command_reader;
  std::uint64_t rejected = 0;
};

ForearmDdsBridge::ForearmDdsBridge(std::uint32_t domain_id, proto::NodeId node,
                                   const std::string& config) {
  if (node > proto::kMaxNodeId) {
    throw std::invalid_argument("forearm node " + std::to_string(node) + " is outside 0.." +
                                std::to_string(proto::kMaxNodeId));
  }
  impl_ = std::make_unique<Impl>(domain_id, node, config);
}

ForearmDdsBridge::~ForearmDdsBridge() = default;

bool ForearmDdsBridge::publish(const ForearmStateSample& state) {
  hmpc_dds_ForearmState c = to_c(state);
  c.node = impl_->node;
  return dds_write(impl_->state_writer, &c) == DDS_RETCODE_OK;
}

bool ForearmDdsBridge::publish(const ForearmTelemetrySample& telemetry) {
  hmpc_dds_ForearmTelemetry c = to_c(telemetry);
  c.node = impl_->node;
  return dds_write(impl_->telemetry_writer, &c) == DDS_RETCODE_OK;
}

std::size_t ForearmDdsBridge::poll_commands(const CommandHandler& handler) {
  std::size_t accepted = 0;
  take_all<hmpc_dds_ForearmCommand>(impl_->command_reader, [&](const hmpc_dds_ForearmCommand& c) {
    const ForearmCommandSample command = from_c(c);
    ValidationResult check = validate(command);
    if (check.ok && command.node != impl_->node) {
      check = reject("for node " + std::to_string(command.node) + ", this bridge is node " +
                     std::to_string(impl_->node));
    }
    if (!check.ok) {
      ++impl_->rejected;
      std::fprintf(stderr, "hmpc-forearm-dds: node %u rejected command %u: %s\n",
                   unsigned{impl_->node}, unsigned{command.sequence_number}, check.reason.c_str());
      return;
    }
    ++accepted;
    handler(command);
  });
  return accepted;
}

std::uint64_t ForearmDdsBridge::rejected_commands() const { return impl_->rejected; }

proto::NodeId ForearmDdsBridge::node() const { return impl_->node; }

// ------------------------------------------------------------------------ client

struct ForearmDdsClient::Impl {
  Impl(std::uint32_t domain_id, const std::string& config)
      : participant(domain_id, config),
        command_writer(participant.writer(
            participant.topic(hmpc_dds_ForearmCommand_desc, kCommandTopic), kCommandTopic)),
        state_reader(participant.reader(participant.topic(hmpc_dds_ForearmState_desc, kStateTopic),
                                        kStateTopic)),
        telemetry_reader(participant.reader(
            participant.topic(hmpc_dds_ForearmTelemetry_desc, kTelemetryTopic), kTelemetryTopic)),
        waitset(checked(dds_create_waitset(participant.handle()), "DDS waitset")) {
    for (dds_entity_t reader : {state_reader, telemetry_reader}) {
      const dds_entity_t condition =
          checked(dds_create_readcondition(reader, DDS_ANY_STATE), "DDS read condition");
      const dds_return_t rc = dds_waitset_attach(waitset, condition, 0);
      if (rc != DDS_RETCODE_OK) throw std::runtime_error(describe("DDS waitset attachment", rc));
    }
  }

  Participant participant;
  dds_entity_t command_writer;
  dds_entity_t state_reader;
  dds_entity_t telemetry_reader;
  dds_entity_t waitset;
};

ForearmDdsClient::ForearmDdsClient(std::uint32_t domain_id, const std::string& config)
    : impl_(std::make_unique<Impl>(domain_id, config)) {}

ForearmDdsClient::~ForearmDdsClient() = default;

bool ForearmDdsClient::wait_for_bridge(double timeout_s) {
  const dds_time_t deadline = dds_time() + to_duration(timeout_s);
  for (;;) {
    dds_publication_matched_status_t status{};
    if (dds_get_publication_matched_status(impl_->command_writer, &status) != DDS_RETCODE_OK) {
      return false;
    }
    if (status.current_count > 0) return true;
    if (dds_time() >= deadline) return false;
    dds_sleepfor(DDS_MSECS(10));
  }
}

bool ForearmDdsClient::send(const ForearmCommandSample& command) {
  const hmpc_dds_ForearmCommand c = to_c(command);
  return dds_write(impl_->command_writer, &c) == DDS_RETCODE_OK;
}

bool ForearmDdsClient::wait_for_delivery(double timeout_s) {
  return dds_wait_for_acks(impl_->command_writer, to_duration(timeout_s)) == DDS_RETCODE_OK;
}

bool ForearmDdsClient::wait_for_data(double timeout_s) {
  return dds_waitset_wait(impl_->waitset, nullptr, 0, to_duration(timeout_s)) > 0;
}

std::size_t ForearmDdsClient::poll_state(const StateHandler& handler) {
  std::size_t count = 0;
  take_all<hmpc_dds_ForearmState>(impl_->state_reader, [&](const hmpc_dds_ForearmState& c) {
    ++count;
    handler(from_c(c));
  });
  return count;
}

std::size_t ForearmDdsClient::poll_telemetry(const TelemetryHandler& handler) {
  std::size_t count = 0;
  take_all<hmpc_dds_ForearmTelemetry>(impl_->telemetry_reader,
                                      [&](const hmpc_dds_ForearmTelemetry& c) {
                                        ++count;
                                        handler(from_c(c));
                                      });
  return count;
}

}  // namespace hmpc::dds
