// The forearm's DDS topics on the generic layer: plain structs to and from the standard
// messages, and the checks of what comes in.
#include "hmpc/dds/forearm_dds.hpp"

#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <utility>

#include "hmpc/dds/bridge.hpp"
#include "hmpc/dds/cost_weights.hpp"
#include "hmpc/dds/endpoint.hpp"
#include "hmpc/models/forearm_target_range.hpp"

namespace hmpc::dds {

namespace {

constexpr std::size_t kStrategyCount = std::size(proto::kStrategyValues);

// The strategies' names as ModeCommand carries them.
const std::array<const char*, kStrategyCount>& strategy_names() {
  static const std::array<const char*, kStrategyCount> names = [] {
    std::array<const char*, kStrategyCount> n{};
    for (std::size_t i = 0; i < kStrategyCount; ++i) n[i] = proto::kStrategyValues[i].name;
    return n;
  }();
  return names;
}

const char* strategy_name(proto::Strategy s) {
  return proto::value_name(proto::kStrategyValues, std::uint32_t(s));
}

struct Topics {
  explicit Topics(const std::string& ns)
      : joint_states(ns + "/joint_states"), telemetry(ns + "/telemetry"), command(ns + "/command"),
        joint_trajectory(ns + "/joint_trajectory"), cost_weights(ns + "/cost_weights") {}
  std::string joint_states, telemetry, command, joint_trajectory, cost_weights;
  std::string diagnostics = "/diagnostics";
};

// What the diagnostics report, compared raw every publish (every 4 ms: no strings then) and
// written out only when it changed or is due.
struct DiagnosticsState {
  proto::BoardMode mode;
  std::uint8_t faults;
  proto::Strategy strategy;
  std::uint32_t rejected_frames, watchdog_trips, solver_failures, overruns;
  proto::SolveStatusCode solve_status;

  static DiagnosticsState of(const ForearmStateSample& s) {
    return {s.telemetry.mode, s.telemetry.faults, s.telemetry.strategy, s.rejected_frames,
            s.watchdog_trips, s.solver_failures,  s.overruns,           s.telemetry.solve_status};
  }
  bool operator==(const DiagnosticsState& o) const {
    return mode == o.mode && faults == o.faults && strategy == o.strategy &&
           rejected_frames == o.rejected_frames && watchdog_trips == o.watchdog_trips &&
           solver_failures == o.solver_failures && overruns == o.overruns &&
           solve_status == o.solve_status;
  }
  // The values of kDiagnosticKeys, in order.
  std::array<std::string, 8> text() const {
    char hex[8];
    std::snprintf(hex, sizeof hex, "0x%02x", unsigned{faults});
    return {proto::value_name(proto::kBoardModeValues, std::uint32_t(mode)),
            hex,
            strategy_name(strategy),
            std::to_string(rejected_frames),
            std::to_string(watchdog_trips),
            std::to_string(solver_failures),
            std::to_string(overruns),
            proto::value_name(proto::kSolveStatusValues, std::uint32_t(solve_status))};
  }
};
constexpr std::array<const char*, 8> kDiagnosticKeys = {
    "mode",           "faults",          "strategy", "rejected_frames",
    "watchdog_trips", "solver_failures", "overruns", "solve_status"};

}  // namespace

std::string default_namespace(proto::NodeId node) {
  return "/hmpc/forearm_" + std::to_string(unsigned{node});
}

const std::array<NamedRange, 4>& forearm_weight_limits() {
  static const std::array<NamedRange, 4> limits = [] {
    std::array<NamedRange, 4> l{};
    const proto::Signal signals[] = {
        proto::Signal::kCostWeightsTheta, proto::Signal::kCostWeightsPressure,
        proto::Signal::kCostWeightsTorque, proto::Signal::kCostWeightsValve};
    for (std::size_t i = 0; i < l.size(); ++i) {
      const auto& spec = protocol::signal_spec(signals[i]);
      l[i] = {spec.name, spec.factor, spec.max};
    }
    return l;
  }();
  return limits;
}

const JointLimits& forearm_joint_limits() {
  static const JointLimits limits = [] {
    const trajectory::JointRange range = forearm::target_range();
    return JointLimits{kJointName, range.min_position, range.max_position, range.max_speed};
  }();
  return limits;
}

// ------------------------------------------------------------------------ bridge

struct ForearmDdsBridge::Impl {
  Impl(std::uint32_t domain_id, proto::NodeId node_id, const std::string& config,
       const std::string& ns)
      : node(node_id), ros_namespace(ns), topics(ns), participant(domain_id, config),
        joint_states(participant, topics.joint_states, Qos::state()),
        telemetry(participant, topics.telemetry, Qos::state()),
        diagnostics(participant, topics.diagnostics, Qos::state()),
        commands(participant, topics.command, Qos::command(kCommandDeadlineS)),
        trajectories(participant, topics.joint_trajectory, Qos::state()),
        weights(participant, topics.cost_weights, Qos::state()),
        hardware_id("forearm board node " + std::to_string(unsigned{node_id})),
        diagnostic_name(ns.substr(1) + "/board") {
    points.reserve(kMaxTrajectoryPoints);
  }

  void reject(const char* what, const Verdict& verdict) {
    log_rejection(rejects, "hmpc-forearm-dds", ros_namespace, what, verdict);
  }

  bool publish_diagnostics(const ForearmStateSample& s, double now) {
    const DiagnosticsState state = DiagnosticsState::of(s);
    if (now < next_diagnostics_s && state == last_diagnostics) return true;
    last_diagnostics = state;
    next_diagnostics_s = now + kDiagnosticsPeriodS;
    const std::array<std::string, 8> text = state.text();
    std::array<msg::KeyValue, kDiagnosticKeys.size()> values{};
    for (std::size_t i = 0; i < values.size(); ++i) {
      values[i].key = borrow(kDiagnosticKeys[i]);
      values[i].value = borrow(text[i].c_str());
    }
    const bool faulted = s.telemetry.mode == proto::BoardMode::kFault || s.telemetry.faults != 0;
    const std::string message =
        faulted ? "fault " + text[1]
                : text[0] +
                      (s.telemetry.mode == proto::BoardMode::kRun ? ", " + text[2] : std::string());
    return write_diagnostics(diagnostics, now,
                             faulted ? DiagnosticLevel::kError : DiagnosticLevel::kOk,
                             diagnostic_name.c_str(), message.c_str(), hardware_id.c_str(),
                             values.data(), values.size());
  }

  proto::NodeId node;
  std::string ros_namespace;
  Topics topics;
  Participant participant;
  Writer<msg::JointState> joint_states;
  Writer<msg::ForearmTelemetry> telemetry;
  Writer<msg::DiagnosticArray> diagnostics;
  Reader<msg::ModeCommand> commands;
  Reader<msg::JointTrajectory> trajectories;
  Reader<msg::CostWeights> weights;
  std::string hardware_id, diagnostic_name;
  std::vector<trajectory::TrajectoryPoint> points;
  RejectCounters rejects;
  DiagnosticsState last_diagnostics{};
  double next_diagnostics_s = 0;
  CommanderWatch commander;  // every command's writer is in charge until it falls silent
};

ForearmDdsBridge::ForearmDdsBridge(std::uint32_t domain_id, proto::NodeId node,
                                   const std::string& config, const std::string& ros_namespace) {
  if (node > proto::kMaxNodeId) {
    throw std::invalid_argument("forearm node " + std::to_string(node) + " is outside 0.." +
                                std::to_string(proto::kMaxNodeId));
  }
  impl_ = std::make_unique<Impl>(domain_id, node, config,
                                 namespace_or(ros_namespace, default_namespace(node)));
}

ForearmDdsBridge::~ForearmDdsBridge() = default;

bool ForearmDdsBridge::publish(const ForearmStateSample& s) {
  Impl& d = *impl_;
  const double now = unix_time_s();
  const msg::Time stamp = from_seconds<msg::Time>(now);
  const char* names[] = {kJointName};
  const double position[] = {s.theta};
  const double velocity[] = {s.theta_dot};
  const double effort[] = {s.telemetry.tau_p + s.telemetry.tau_m};
  const msg::JointState joint = joint_state(stamp, names, position, velocity, effort, 1);

  const ForearmTelemetrySample& t = s.telemetry;
  msg::ForearmTelemetry m{};
  m.header.stamp = stamp;
  m.header.frame_id = borrow("");
  m.board_mode = static_cast<std::uint8_t>(t.mode);
  m.faults = t.faults;
  m.strategy = borrow(strategy_name(t.strategy));
  m.solve_status = static_cast<std::uint8_t>(t.solve_status);
  m.coarse_iterations = t.coarse_iterations;
  m.fine_iterations = t.fine_iterations;
  m.solve_time_us = t.solve_time_us;
  m.target_position = t.theta_d;
  m.tracking_error = t.tracking_error;
  m.pressure = t.pressure_pa;
  m.valve_voltage = t.v_p;
  m.motor_voltage = t.v_m;
  m.muscle_torque = t.tau_p;
  m.motor_torque = t.tau_m;
  const bool joint_ok = d.joint_states.write(joint);
  const bool telemetry_ok = d.telemetry.write(m);
  return joint_ok && telemetry_ok && d.publish_diagnostics(s, now);
}

void ForearmDdsBridge::poll(const ForearmDdsHandlers& handlers) {
  Impl& d = *impl_;
  const double now = unix_time_s();
  const StampPolicy stamps;
  d.commands.take([&](const msg::ModeCommand& c, const dds_sample_info_t& info) {
    const Verdict v = validate(c, strategy_names().data(), kStrategyCount, now, stamps);
    if (!v.ok) return d.reject("ModeCommand", v);
    std::uint32_t strategy = 0;
    proto::value_of(proto::kStrategyValues, c.strategy, strategy);
    d.commander.took_charge(info.publication_handle);
    if (handlers.command) {
      handlers.command({c.sequence_number, static_cast<proto::RequestedMode>(c.mode),
                        static_cast<proto::Strategy>(strategy), c.clear_faults});
    }
  });
  d.trajectories.take([&](const msg::JointTrajectory& t) {
    Verdict v = validate(t, &forearm_joint_limits(), 1, TrajectoryLimits{kMaxTrajectoryPoints}, now,
                         stamps);
    if (!v.ok) return d.reject("JointTrajectory", v);
    d.points.clear();
    for (std::uint32_t k = 0; k < t.points._length; ++k) {
      const msg::JointTrajectoryPoint& p = t.points._buffer[k];
      const bool has_velocity = p.velocities._length > 0;
      d.points.push_back({to_seconds(p.time_from_start), p.positions._buffer[0],
                          has_velocity ? p.velocities._buffer[0] : 0, has_velocity});
    }
    const bool stamped = t.header.stamp.sec != 0 || t.header.stamp.nanosec != 0;
    const TrajectoryView view{d.points.data(), d.points.size(),
                              stamped ? to_seconds(t.header.stamp) - now : 0};
    if (handlers.trajectory) {
      v = handlers.trajectory(view);
      if (!v.ok) d.reject("JointTrajectory", v);
    }
  });
  d.weights.take([&](const msg::CostWeights& w) {
    const auto& limits = forearm_weight_limits();
    const Verdict v = validate(w, limits.data(), limits.size(), now, stamps);
    if (!v.ok) return d.reject("CostWeights", v);
    proto::CostWeights out{};
    float* fields[] = {&out.w_theta, &out.w_p, &out.w_tau, &out.w_v};
    for (std::uint32_t i = 0; i < w.names._length; ++i) {
      for (std::size_t k = 0; k < limits.size(); ++k) {
        if (std::strcmp(w.names._buffer[i], limits[k].name) == 0) {
          *fields[k] = static_cast<float>(w.values._buffer[i]);
        }
      }
    }
    if (handlers.weights) handlers.weights(out);
  });
  if (d.commander.fell_silent(d.commands)) {
    std::fprintf(stderr, "hmpc-forearm-dds: %s: the commander fell silent\n",
                 d.ros_namespace.c_str());
    if (handlers.commander_silent) handlers.commander_silent();
  }
}

const RejectCounters& ForearmDdsBridge::rejects() const { return impl_->rejects; }
std::uint64_t ForearmDdsBridge::commander_silences() const { return impl_->commander.silences(); }
const std::string& ForearmDdsBridge::ros_namespace() const { return impl_->ros_namespace; }

TrajectorySample::TrajectorySample(std::vector<trajectory::TrajectoryPoint> points)
    : points_(std::move(points)), out_(points_.size()) {
  for (std::size_t k = 0; k < points_.size(); ++k) {
    out_[k].positions = borrow(&points_[k].position, 1);
    out_[k].velocities = borrow(&points_[k].velocity, points_[k].has_velocity ? 1 : 0);
    out_[k].time_from_start = from_seconds<msg::Duration>(points_[k].time_s);
  }
  message_.header.frame_id = borrow("");
  message_.joint_names = borrow(names_, 1);
  message_.points = borrow<decltype(message_.points)>(out_.data(), out_.size());
}

// ------------------------------------------------------------------------ client

struct ForearmDdsClient::Impl {
  Impl(std::uint32_t domain_id, const std::string& config, const std::string& ns)
      : topics(ns), participant(domain_id, config),
        commands(participant, topics.command, Qos::command(kCommandDeadlineS)),
        trajectories(participant, topics.joint_trajectory, Qos::state()),
        weights(participant, topics.cost_weights, Qos::state()),
        joint_states(participant, topics.joint_states, Qos::state()),
        telemetry(participant, topics.telemetry, Qos::state()),
        diagnostics(participant, topics.diagnostics, Qos::state()),
        waitset(checked(dds_create_waitset(participant.handle()), "a DDS waitset")) {
    for (dds_entity_t reader : {joint_states.handle(), telemetry.handle(), diagnostics.handle()}) {
      const dds_entity_t condition =
          checked(dds_create_readcondition(reader, DDS_ANY_STATE), "a DDS read condition");
      checked(dds_waitset_attach(waitset, condition, 0), "a DDS waitset attachment");
    }
  }

  Topics topics;
  Participant participant;
  Writer<msg::ModeCommand> commands;
  Writer<msg::JointTrajectory> trajectories;
  Writer<msg::CostWeights> weights;
  Reader<msg::JointState> joint_states;
  Reader<msg::ForearmTelemetry> telemetry;
  Reader<msg::DiagnosticArray> diagnostics;
  dds_entity_t waitset;
  RejectCounters rejects;
};

ForearmDdsClient::ForearmDdsClient(std::uint32_t domain_id, proto::NodeId node,
                                   const std::string& config, const std::string& ros_namespace)
    : impl_(std::make_unique<Impl>(domain_id, config,
                                   namespace_or(ros_namespace, default_namespace(node)))) {}

ForearmDdsClient::~ForearmDdsClient() = default;

bool ForearmDdsClient::wait_for_bridge(double timeout_s) {
  const dds_time_t end = dds_time() + to_duration(timeout_s);
  const auto left = [&] { return double(end - dds_time()) * 1e-9; };
  return impl_->commands.wait_for_reader(timeout_s) &&
         impl_->trajectories.wait_for_reader(left()) && impl_->weights.wait_for_reader(left());
}

bool ForearmDdsClient::send(const ModeCommandSample& command) {
  msg::ModeCommand c{};
  c.header.stamp = from_seconds<msg::Time>(unix_time_s());
  c.header.frame_id = borrow("");
  c.sequence_number = command.sequence_number;
  c.mode = static_cast<std::uint8_t>(command.mode);
  c.strategy = borrow(strategy_name(command.strategy));
  c.clear_faults = command.clear_faults;
  return impl_->commands.write(c);
}

bool ForearmDdsClient::send(const std::vector<trajectory::TrajectoryPoint>& points) {
  const TrajectorySample sample(points);
  return impl_->trajectories.write(sample.message());
}

bool ForearmDdsClient::send(const std::vector<std::pair<std::string, double>>& weights) {
  const CostWeightsSample sample(weights);
  return impl_->weights.write(sample.message());
}

bool ForearmDdsClient::wait_for_delivery(double timeout_s) {
  return impl_->commands.wait_for_acks(timeout_s) && impl_->trajectories.wait_for_acks(timeout_s) &&
         impl_->weights.wait_for_acks(timeout_s);
}

bool ForearmDdsClient::wait_for_data(double timeout_s) {
  return dds_waitset_wait(impl_->waitset, nullptr, 0, to_duration(timeout_s)) > 0;
}

std::size_t ForearmDdsClient::poll_joint_states(
    const std::function<void(const JointStateSample&)>& handler) {
  std::size_t count = 0;
  impl_->joint_states.take([&](const msg::JointState& j) {
    Verdict v = validate(j, unix_time_s(), StampPolicy{});
    if (v.ok && (j.name._length != 1 || std::string(j.name._buffer[0]) != kJointName ||
                 j.position._length != 1 || j.velocity._length != 1 || j.effort._length != 1)) {
      v = Verdict::reject(Rejection::kLengthMismatch, "not the one joint's full state");
    }
    if (!v.ok) return impl_->rejects.add(v.reason);
    ++count;
    handler({to_seconds(j.header.stamp), j.position._buffer[0], j.velocity._buffer[0],
             j.effort._buffer[0]});
  });
  return count;
}

std::size_t ForearmDdsClient::poll_telemetry(
    const std::function<void(const ForearmTelemetrySample&)>& handler) {
  std::size_t count = 0;
  impl_->telemetry.take([&](const msg::ForearmTelemetry& m) {
    std::uint32_t strategy = 0;
    if (m.strategy == nullptr || !proto::value_of(proto::kStrategyValues, m.strategy, strategy) ||
        std::string(proto::value_name(proto::kBoardModeValues, m.board_mode)) == "?" ||
        std::string(proto::value_name(proto::kSolveStatusValues, m.solve_status)) == "?") {
      return impl_->rejects.add(Rejection::kUnknownValue);
    }
    ForearmTelemetrySample t;
    t.stamp_s = to_seconds(m.header.stamp);
    t.mode = static_cast<proto::BoardMode>(m.board_mode);
    t.faults = m.faults;
    t.strategy = static_cast<proto::Strategy>(strategy);
    t.solve_status = static_cast<proto::SolveStatusCode>(m.solve_status);
    t.coarse_iterations = m.coarse_iterations;
    t.fine_iterations = m.fine_iterations;
    t.solve_time_us = m.solve_time_us;
    t.theta_d = m.target_position;
    t.tracking_error = m.tracking_error;
    t.pressure_pa = m.pressure;
    t.v_p = m.valve_voltage;
    t.v_m = m.motor_voltage;
    t.tau_p = m.muscle_torque;
    t.tau_m = m.motor_torque;
    ++count;
    handler(t);
  });
  return count;
}

std::size_t ForearmDdsClient::poll_diagnostics(
    const std::function<void(const DiagnosticSample&)>& handler) {
  std::size_t count = 0;
  const auto text = [](const char* s) { return std::string(s ? s : ""); };
  impl_->diagnostics.take([&](const msg::DiagnosticArray& a) {
    for (std::uint32_t i = 0; i < a.status._length; ++i) {
      const msg::DiagnosticStatus& s = a.status._buffer[i];
      if (s.level > static_cast<std::uint8_t>(DiagnosticLevel::kStale)) {
        impl_->rejects.add(Rejection::kUnknownValue);
        continue;
      }
      DiagnosticSample d;
      d.level = static_cast<DiagnosticLevel>(s.level);
      d.name = text(s.name);
      d.message = text(s.message);
      d.hardware_id = text(s.hardware_id);
      for (std::uint32_t k = 0; k < s.values._length; ++k) {
        d.values.emplace_back(text(s.values._buffer[k].key), text(s.values._buffer[k].value));
      }
      ++count;
      handler(d);
    }
  });
  return count;
}

const RejectCounters& ForearmDdsClient::rejects() const { return impl_->rejects; }

}  // namespace hmpc::dds
