// hmpc-forearm-cli: commands a forearm board through the host controller's DDS bridge, or
// watches its joint state, telemetry and diagnostics (the topics of hmpc/dds/forearm_dds.hpp).
// `run` sends its target as a JointTrajectory, then repeats the run command within the command
// topic's deadline until --duration has passed or it is interrupted, and then asks for hold: a
// run lasts only as long as its commander. Exit status: 0 done, 1 no bridge or no data in time
// (or a DDS failure), 2 bad arguments or an invalid target.
#include <signal.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "hmpc/dds/cost_weights.hpp"
#include "hmpc/dds/forearm_dds.hpp"
#include "hmpc/trajectory/joint_target.hpp"

namespace {

namespace dds = hmpc::dds;
namespace proto = hmpc::forearm_protocol;

constexpr double kPi = 3.14159265358979323846;
// A constant target is reached over this time from wherever the joint is: across the whole
// joint range (2.8 rad) at 2.8 rad/s, within forearm::kMaxTargetSpeed.
constexpr double kRampS = 1.0;
// The run command is repeated five times per deadline, so one lost or late sample never trips it.
constexpr double kRepeatS = dds::kCommandDeadlineS / 5;

volatile sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

void usage(std::FILE* out) {
  std::fprintf(
      out,
      "usage: hmpc-forearm-cli [OPTIONS] run|hold|idle [COMMAND OPTIONS]\n"
      "       hmpc-forearm-cli [OPTIONS] weights NAME=VALUE...\n"
      "       hmpc-forearm-cli [OPTIONS] watch [--samples K]\n"
      "options:\n"
      "  --domain N        DDS domain id, 0..232 (default 0)\n"
      "  --node N          forearm board node, 0..15 (default 0): topics /hmpc/forearm_N/...\n"
      "  --dds-loopback    DDS on 127.0.0.1 only, no multicast (tests, the HIL guest)\n"
      "  --timeout S       seconds to wait for a bridge or for data (default 10)\n"
      "commands:\n"
      "  run               run the MPC on the target, for --duration or until interrupted,\n"
      "                    then hold\n"
      "  hold              hold the present angle with the joint PID\n"
      "  idle              safe outputs\n"
      "  weights           set tracking-cost weights (Eq. 3.3) of the running MPC: w_theta\n"
      "                    (0.05..400), w_p (0.05..400), w_tau (0.0005..4), w_v\n"
      "                    (0.000005..0.04); the others stay as they are\n"
      "  watch             print the node's joint state, telemetry and diagnostics\n"
      "command options (run, hold, idle):\n"
      "  --strategy NAME   fine_4ms, fine_8ms, coarse_20ms, coarse_40ms, two_stage (default),\n"
      "                    pam_only\n"
      "  --sine AMP_DEG FREQ_HZ  sinusoidal target of this amplitude and frequency (run, needs\n"
      "                    --duration)\n"
      "  --target-file FILE  a target from a CSV file: lines time_s,position_rad[,velocity_rad_s]\n"
      "                    from the run's start (run)\n"
      "  --offset DEG      target offset (alone: a constant target reached in 1 s); default:\n"
      "                    hold the present angle\n"
      "  --duration S      how long the run lasts, 0 = until interrupted (default 0)\n"
      "  --clear-faults    clear the board's latched faults\n"
      "  --sequence N      sequence number of the command (default: milliseconds of the clock)\n"
      "watch options:\n"
      "  --samples K       stop after K samples, 1..1000000 (default 10)\n");
}

struct Options {
  std::uint32_t domain = 0;
  int node = 0;
  bool loopback = false;
  double timeout_s = 10;
  std::string command;
  std::string strategy = "two_stage";
  bool sine = false;
  double amplitude_deg = 0;
  double frequency_hz = 0;
  std::string target_file;
  bool offset_given = false;
  double offset_deg = 0;
  double duration_s = 0;
  bool clear_faults = false;
  bool sequence_given = false;
  unsigned long sequence = 0;
  long samples = 10;
  std::vector<std::pair<std::string, double>> weights;
};

// Errors name the option and the value; main prints usage after them.
struct ArgumentError {
  std::string message;
};

class Arguments {
 public:
  Arguments(int argc, char** argv) : args_(argv + 1, argv + argc) {}
  bool done() const { return next_ >= args_.size(); }
  std::string take() { return args_[next_++]; }
  std::string value_of(const std::string& option) {
    if (done()) throw ArgumentError{option + " needs a value"};
    return take();
  }

 private:
  std::vector<std::string> args_;
  std::size_t next_ = 0;
};

double number(const std::string& option, const std::string& text) {
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(value)) {
    throw ArgumentError{option + " needs a finite number, got '" + text + "'"};
  }
  return value;
}

long integer(const std::string& option, const std::string& text, long min, long max) {
  char* end = nullptr;
  const long value = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || value < min || value > max) {
    throw ArgumentError{option + " must be an integer in " + std::to_string(min) + ".." +
                        std::to_string(max) + ", got '" + text + "'"};
  }
  return value;
}

double positive_seconds(const std::string& option, const std::string& text) {
  const double value = number(option, text);
  if (!(value > 0 && value <= 3600)) {
    throw ArgumentError{option + " must be a number of seconds in (0, 3600], got '" + text + "'"};
  }
  return value;
}

proto::Strategy strategy_of(const Options& o) {
  // The protocol's names (its DBC value table), as every program uses them.
  std::uint32_t value = 0;
  if (proto::value_of(proto::kStrategyValues, o.strategy, value)) {
    return static_cast<proto::Strategy>(value);
  }
  throw ArgumentError{
      "--strategy must be one of fine_4ms, fine_8ms, coarse_20ms, coarse_40ms, "
      "two_stage, pam_only, got '" +
      o.strategy + "'"};
}

Options parse(int argc, char** argv) {
  Options o;
  Arguments args(argc, argv);
  while (!args.done()) {
    const std::string arg = args.take();
    if (arg == "-h" || arg == "--help") {
      usage(stdout);
      std::exit(0);
    } else if (arg == "--domain") {
      // Cyclone maps domain ids to UDP ports 7400 + 250 d + ...: 232 is the last that fits.
      o.domain = static_cast<std::uint32_t>(integer(arg, args.value_of(arg), 0, 232));
    } else if (arg == "--node") {
      o.node = static_cast<int>(integer(arg, args.value_of(arg), 0, proto::kMaxNodeId));
    } else if (arg == "--dds-loopback") {
      o.loopback = true;
    } else if (arg == "--timeout") {
      o.timeout_s = positive_seconds(arg, args.value_of(arg));
    } else if (arg == "--strategy") {
      o.strategy = args.value_of(arg);
    } else if (arg == "--sine") {
      o.sine = true;
      o.amplitude_deg = number("--sine amplitude", args.value_of("--sine amplitude"));
      o.frequency_hz = number("--sine frequency", args.value_of("--sine frequency"));
    } else if (arg == "--target-file") {
      o.target_file = args.value_of(arg);
      if (o.target_file.empty()) throw ArgumentError{"--target-file needs a file name"};
    } else if (arg == "--offset") {
      o.offset_given = true;
      o.offset_deg = number(arg, args.value_of(arg));
    } else if (arg == "--duration") {
      o.duration_s = number(arg, args.value_of(arg));
      if (o.duration_s < 0) throw ArgumentError{"--duration must not be negative"};
    } else if (arg == "--clear-faults") {
      o.clear_faults = true;
    } else if (arg == "--sequence") {
      o.sequence_given = true;
      o.sequence = static_cast<unsigned long>(integer(arg, args.value_of(arg), 0, 4294967295L));
    } else if (arg == "--samples") {
      o.samples = integer(arg, args.value_of(arg), 1, 1000000);
    } else if (arg.rfind("--", 0) == 0) {
      throw ArgumentError{"unknown option '" + arg + "'"};
    } else if (o.command.empty()) {
      if (arg != "run" && arg != "hold" && arg != "idle" && arg != "weights" && arg != "watch") {
        throw ArgumentError{"unknown command '" + arg + "' (run, hold, idle, weights or watch)"};
      }
      o.command = arg;
    } else if (o.command == "weights") {
      const auto equals = arg.find('=');
      if (equals == std::string::npos) {
        throw ArgumentError{"weights takes NAME=VALUE, got '" + arg + "'"};
      }
      o.weights.emplace_back(arg.substr(0, equals), number(arg, arg.substr(equals + 1)));
    } else {
      throw ArgumentError{"unexpected argument '" + arg + "' after command " + o.command};
    }
  }
  if (o.command.empty()) {
    throw ArgumentError{"no command given (run, hold, idle, weights or watch)"};
  }
  if (o.command == "weights" && o.weights.empty()) {
    throw ArgumentError{"weights needs at least one NAME=VALUE"};
  }
  if ((o.sine || o.offset_given || !o.target_file.empty()) && o.command != "run") {
    throw ArgumentError{"--sine, --offset and --target-file are targets of run"};
  }
  if (!o.target_file.empty() && (o.sine || o.offset_given)) {
    throw ArgumentError{"--target-file takes neither --sine nor --offset"};
  }
  if (o.sine && !(o.duration_s > 0)) throw ArgumentError{"--sine needs a --duration"};
  return o;
}

dds::ModeCommandSample command_of(const Options& o) {
  dds::ModeCommandSample c;
  // Milliseconds of the wall clock, modulo 2^32: successive invocations count up.
  const auto now_ms = std::chrono::duration_cast<std::chrono::milliseconds>(
      std::chrono::system_clock::now().time_since_epoch());
  c.sequence_number = static_cast<std::uint32_t>(o.sequence_given ? o.sequence : now_ms.count());
  c.mode = o.command == "run"    ? proto::RequestedMode::kRun
           : o.command == "hold" ? proto::RequestedMode::kHold
                                 : proto::RequestedMode::kIdle;
  c.strategy = strategy_of(o);
  c.clear_faults = o.clear_faults;
  return c;
}

// The target as points: a sinusoid sampled with its velocities (joint_target.hpp), the points
// of a CSV file, or one point reached after kRampS; none to hold the present angle.
std::vector<hmpc::trajectory::TrajectoryPoint> target_of(const Options& o) {
  std::vector<hmpc::trajectory::TrajectoryPoint> points;
  hmpc::trajectory::TargetSpec spec;
  spec.offset = o.offset_deg * kPi / 180;
  if (o.sine || !o.target_file.empty()) {
    spec.shape =
        o.sine ? hmpc::trajectory::TargetShape::kSine : hmpc::trajectory::TargetShape::kFile;
    spec.amplitude = o.amplitude_deg * kPi / 180;
    spec.frequency_hz = o.frequency_hz;
    spec.duration_s = o.sine ? o.duration_s : 1;
    spec.file = o.target_file;
    std::string error;
    if (!hmpc::trajectory::shape_points(spec, dds::kMaxTrajectoryPoints, points, error)) {
      throw ArgumentError{"invalid target: " + error};
    }
  } else if (o.offset_given) {
    points.push_back({kRampS, spec.offset, 0, true});
  }
  return points;
}

// The bridge's own checks of the target, before it is sent: exit 2 with the reason.
void check_target(const std::vector<hmpc::trajectory::TrajectoryPoint>& points) {
  if (points.empty()) return;
  const dds::TrajectorySample sample(points);
  const dds::Verdict v = dds::validate(sample.message(), &dds::forearm_joint_limits(), 1,
                                       dds::TrajectoryLimits{dds::kMaxTrajectoryPoints}, 0, {});
  if (!v.ok) {
    throw ArgumentError{"invalid target: " + v.detail + " (--sine and --offset take degrees)"};
  }
}

bool deliver(dds::ForearmDdsClient& client, const Options& o) {
  if (client.wait_for_delivery(o.timeout_s)) return true;
  std::fprintf(stderr, "hmpc-forearm-cli: the bridge did not acknowledge within %g s\n",
               o.timeout_s);
  return false;
}

int send(const Options& o, const dds::ModeCommandSample& command,
         const std::vector<hmpc::trajectory::TrajectoryPoint>& target, const std::string& config) {
  dds::ForearmDdsClient client(o.domain, static_cast<proto::NodeId>(o.node), config);
  if (!client.wait_for_bridge(o.timeout_s)) {
    std::fprintf(stderr,
                 "hmpc-forearm-cli: no forearm bridge subscribed to %s/command on domain %u "
                 "within %g s (is the host controller running%s?)\n",
                 dds::default_namespace(static_cast<proto::NodeId>(o.node)).c_str(), o.domain,
                 o.timeout_s, o.loopback ? " with --dds-loopback" : "");
    return 1;
  }
  if (!target.empty() && !(client.send(target) && deliver(client, o))) return 1;
  if (!client.send(command) || !deliver(client, o)) return 1;
  std::printf("sent %s command %u to node %d%s\n", o.command.c_str(),
              unsigned{command.sequence_number}, o.node,
              target.empty()
                  ? ""
                  : (" with a target of " + std::to_string(target.size()) + " points").c_str());
  std::fflush(stdout);
  if (command.mode != proto::RequestedMode::kRun) return 0;
  // In charge of the run: repeat the command until the end, then ask for hold.
  const auto start = std::chrono::steady_clock::now();
  const auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  while (!g_stop && (o.duration_s == 0 || elapsed() < o.duration_s)) {
    std::this_thread::sleep_for(std::chrono::duration<double>(kRepeatS));
    if (!client.send(command)) {
      std::fprintf(stderr, "hmpc-forearm-cli: DDS refused the repeated run command\n");
      return 1;
    }
  }
  dds::ModeCommandSample hold = command;
  hold.mode = proto::RequestedMode::kHold;
  hold.clear_faults = false;
  if (!client.send(hold) || !deliver(client, o)) return 1;
  std::printf("run ended after %.1f s%s: sent hold\n", elapsed(), g_stop ? " (interrupted)" : "");
  return 0;
}

// The bridge's own checks of the weights, before they are sent: exit 2 with the reason.
void check_weights(const Options& o) {
  const dds::CostWeightsSample sample(o.weights);
  const auto& limits = dds::forearm_weight_limits();
  const dds::Verdict v =
      dds::validate(sample.message(), limits.data(), limits.size(), dds::unix_time_s(), {});
  if (!v.ok) throw ArgumentError{"invalid weights: " + v.detail};
}

int send_weights(const Options& o, const std::string& config) {
  dds::ForearmDdsClient client(o.domain, static_cast<proto::NodeId>(o.node), config);
  if (!client.wait_for_bridge(o.timeout_s)) {
    std::fprintf(stderr,
                 "hmpc-forearm-cli: no forearm bridge subscribed to %s/cost_weights on domain %u "
                 "within %g s\n",
                 dds::default_namespace(static_cast<proto::NodeId>(o.node)).c_str(), o.domain,
                 o.timeout_s);
    return 1;
  }
  if (!client.send(o.weights) || !deliver(client, o)) return 1;
  std::printf("sent %zu cost weights to node %d\n", o.weights.size(), o.node);
  return 0;
}

int watch(const Options& o, const std::string& config) {
  dds::ForearmDdsClient client(o.domain, static_cast<proto::NodeId>(o.node), config);
  long printed = 0;
  const auto room = [&] { return printed < o.samples; };
  const auto print_joint = [&](const dds::JointStateSample& j) {
    if (!room()) return;
    ++printed;
    std::printf("joint     %s position %.4f rad velocity %.4f rad/s effort %.3f N.m\n",
                dds::kJointName, j.position, j.velocity, j.effort);
  };
  const auto print_telemetry = [&](const dds::ForearmTelemetrySample& t) {
    if (!room()) return;
    ++printed;
    std::printf(
        "telemetry mode %s faults 0x%02x strategy %s status %s coarse iterations %u fine "
        "iterations %u solve %u us target %.4f rad error %.4f rad P %.0f Pa v_p %.3f V v_m "
        "%.3f V tau_p %.3f N.m tau_m %.3f N.m\n",
        proto::value_name(proto::kBoardModeValues, unsigned(t.mode)), unsigned{t.faults},
        proto::value_name(proto::kStrategyValues, unsigned(t.strategy)),
        proto::value_name(proto::kSolveStatusValues, unsigned(t.solve_status)),
        unsigned{t.coarse_iterations}, unsigned{t.fine_iterations}, unsigned{t.solve_time_us},
        t.theta_d, t.tracking_error, t.pressure_pa, t.v_p, t.v_m, t.tau_p, t.tau_m);
  };
  const auto print_diagnostics = [&](const dds::DiagnosticSample& d) {
    if (!room()) return;
    ++printed;
    std::string values;
    for (const auto& [key, value] : d.values)
      values.append(" ").append(key).append("=").append(value);
    static const char* const kLevels[] = {"OK", "WARN", "ERROR", "STALE"};
    std::printf("diagnostics %s %s '%s' (%s):%s\n", d.name.c_str(),
                kLevels[static_cast<int>(d.level)], d.message.c_str(), d.hardware_id.c_str(),
                values.c_str());
  };
  while (room()) {
    if (!client.wait_for_data(o.timeout_s)) {
      std::fprintf(stderr, "hmpc-forearm-cli: %ld of %ld samples from node %d within %g s\n",
                   printed, o.samples, o.node, o.timeout_s);
      return 1;
    }
    client.poll_joint_states(print_joint);
    client.poll_telemetry(print_telemetry);
    client.poll_diagnostics(print_diagnostics);
    std::fflush(stdout);
  }
  if (client.rejects().total() > 0) {
    std::fprintf(stderr, "hmpc-forearm-cli: ignored malformed samples: %s\n",
                 client.rejects().summary().c_str());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  dds::ModeCommandSample command;
  std::vector<hmpc::trajectory::TrajectoryPoint> target;
  try {
    options = parse(argc, argv);
    if (options.command == "weights") {
      check_weights(options);
    } else if (options.command != "watch") {
      command = command_of(options);
      target = target_of(options);
      check_target(target);
    }
  } catch (const ArgumentError& e) {
    std::fprintf(stderr, "hmpc-forearm-cli: %s\n", e.message.c_str());
    usage(stderr);
    return 2;
  }
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  const std::string config = options.loopback ? dds::loopback_config() : std::string();
  try {
    if (options.command == "watch") return watch(options, config);
    if (options.command == "weights") return send_weights(options, config);
    return send(options, command, target, config);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hmpc-forearm-cli: %s\n", e.what());
    return 1;
  }
}
