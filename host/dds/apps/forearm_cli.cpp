// hmpc-forearm-cli: commands a forearm board through the host controller's DDS bridge, or
// watches its state and telemetry. Exit status: 0 done, 1 no bridge or no data in time (or a
// DDS failure), 2 bad arguments or an invalid command.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

#include "hmpc/dds/forearm_dds.hpp"

namespace {

namespace dds = hmpc::dds;
namespace proto = hmpc::forearm_protocol;

constexpr double kPi = 3.14159265358979323846;

void usage(std::FILE* out) {
  std::fprintf(
      out,
      "usage: hmpc-forearm-cli [OPTIONS] run|hold|idle [COMMAND OPTIONS]\n"
      "       hmpc-forearm-cli [OPTIONS] watch [--samples K]\n"
      "options:\n"
      "  --domain N        DDS domain id, 0..232 (default 0)\n"
      "  --node N          forearm board node, 0..15 (default 0)\n"
      "  --dds-loopback    DDS on 127.0.0.1 only, no multicast (tests, the HIL guest)\n"
      "  --timeout S       seconds to wait for a bridge or for data (default 10)\n"
      "commands:\n"
      "  run               run the MPC on the target\n"
      "  hold              hold the target with the joint PID\n"
      "  idle              safe outputs\n"
      "  watch             print the node's state and telemetry as they arrive\n"
      "command options (run, hold, idle):\n"
      "  --strategy NAME   fine_4ms, fine_8ms, coarse_20ms, coarse_40ms, two_stage (default),\n"
      "                    pam_only\n"
      "  --sine AMP_DEG FREQ_HZ  sinusoidal target of this amplitude and frequency\n"
      "  --offset DEG      target offset (alone: a constant target); default: hold the\n"
      "                    current angle\n"
      "  --duration S      how long the target runs, 0 = until the next command (default 0)\n"
      "  --clear-faults    clear the board's latched faults\n"
      "  --sequence N      sequence number of the command (default: milliseconds of the clock)\n"
      "  --raw-sample      send the command without checking it (tests the bridge's checks)\n"
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
  bool offset_given = false;
  double offset_deg = 0;
  double duration_s = 0;
  bool clear_faults = false;
  bool sequence_given = false;
  unsigned long sequence = 0;
  bool raw_sample = false;
  long samples = 10;
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

// Numbers as strtod reads them, nan and inf included: validate() rejects those unless
// --raw-sample asks to send them as they are.
double number(const std::string& option, const std::string& text) {
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0') {
    throw ArgumentError{option + " needs a number, got '" + text + "'"};
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

// A name, or with --raw-sample any code 0..255 (to send an invalid one on purpose).
proto::Strategy strategy_of(const Options& o) {
  // The protocol's names (its DBC value table), as every program uses them.
  std::uint32_t value = 0;
  if (proto::value_of(proto::kStrategyValues, o.strategy, value)) {
    return static_cast<proto::Strategy>(value);
  }
  if (o.raw_sample) {
    return static_cast<proto::Strategy>(integer("--strategy", o.strategy, 0, 255));
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
      // Up to 255 so --raw-sample can address a node the bridge must refuse.
      o.node = static_cast<int>(integer(arg, args.value_of(arg), 0, 255));
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
    } else if (arg == "--offset") {
      o.offset_given = true;
      o.offset_deg = number(arg, args.value_of(arg));
    } else if (arg == "--duration") {
      o.duration_s = number(arg, args.value_of(arg));
    } else if (arg == "--clear-faults") {
      o.clear_faults = true;
    } else if (arg == "--sequence") {
      o.sequence_given = true;
      o.sequence = static_cast<unsigned long>(integer(arg, args.value_of(arg), 0, 4294967295L));
    } else if (arg == "--raw-sample") {
      o.raw_sample = true;
    } else if (arg == "--samples") {
      o.samples = integer(arg, args.value_of(arg), 1, 1000000);
    } else if (arg.rfind("--", 0) == 0) {
      throw ArgumentError{"unknown option '" + arg + "'"};
    } else if (o.command.empty()) {
      if (arg != "run" && arg != "hold" && arg != "idle" && arg != "watch") {
        throw ArgumentError{"unknown command '" + arg + "' (run, hold, idle or watch)"};
      }
      o.command = arg;
    } else {
      throw ArgumentError{"unexpected argument '" + arg + "' after command " + o.command};
    }
  }
  if (o.command.empty()) throw ArgumentError{"no command given (run, hold, idle or watch)"};
  return o;
}

dds::ForearmCommandSample command_of(const Options& o) {
  dds::ForearmCommandSample c;
  c.node = static_cast<proto::NodeId>(o.node);
  // Milliseconds of the wall clock, modulo 2^32: successive invocations count up.
  const auto now_ms = std::chrono::duration_cast<std::chrono::milliseconds>(
      std::chrono::system_clock::now().time_since_epoch());
  c.sequence_number = static_cast<std::uint32_t>(o.sequence_given ? o.sequence : now_ms.count());
  c.mode = o.command == "run"    ? proto::RequestedMode::kRun
           : o.command == "hold" ? proto::RequestedMode::kHold
                                 : proto::RequestedMode::kIdle;
  c.strategy = strategy_of(o);
  c.clear_faults = o.clear_faults;
  if (o.sine || o.offset_given) {
    c.target.kind = dds::TargetKind::kSinusoid;
    c.target.amplitude_rad = o.amplitude_deg * kPi / 180;
    c.target.frequency_hz = o.frequency_hz;
    c.target.offset_rad = o.offset_deg * kPi / 180;
  }
  c.target.duration_s = o.duration_s;
  return c;
}

int send(const Options& o, const dds::ForearmCommandSample& command, const std::string& config) {
  dds::ForearmDdsClient client(o.domain, config);
  if (!client.wait_for_bridge(o.timeout_s)) {
    std::fprintf(stderr,
                 "hmpc-forearm-cli: no forearm bridge subscribed to commands on domain %u within "
                 "%g s (is the host controller running%s?)\n",
                 o.domain, o.timeout_s, o.loopback ? " with --dds-loopback" : "");
    return 1;
  }
  if (!client.send(command) || !client.wait_for_delivery(o.timeout_s)) {
    std::fprintf(stderr, "hmpc-forearm-cli: the command was not acknowledged within %g s\n",
                 o.timeout_s);
    return 1;
  }
  std::printf("sent %s command %u to node %d\n", o.command.c_str(),
              unsigned{command.sequence_number}, o.node);
  return 0;
}

template <std::size_t N>
const char* name_of(const proto::EnumValue (&values)[N], unsigned value) {
  for (const proto::EnumValue& v : values) {
    if (v.value == value) return v.name;
  }
  return "unknown";
}

int watch(const Options& o, const std::string& config) {
  dds::ForearmDdsClient client(o.domain, config);
  long printed = 0;
  const auto print_state = [&](const dds::ForearmStateSample& s) {
    if (s.node != o.node || printed >= o.samples) return;
    ++printed;
    std::printf(
        "state     node %u t %.3f s mode %s faults 0x%02x strategy %s theta %.4f rad "
        "theta_dot %.4f rad/s P %.4f MPa theta_d %.4f rad v_p %.3f V v_m %.3f V "
        "tau_p %.3f N.m tau_m %.3f N.m rejected %u watchdog %u solver failures %u "
        "overruns %u\n",
        unsigned{s.node}, s.board_time_s, name_of(proto::kBoardModeValues, unsigned(s.mode)),
        unsigned{s.faults}, name_of(proto::kStrategyValues, unsigned(s.strategy)), s.theta,
        s.theta_dot, s.pressure_mpa, s.theta_d, s.v_p, s.v_m, s.tau_p, s.tau_m,
        unsigned{s.rejected_frames}, unsigned{s.watchdog_trips}, unsigned{s.solver_failures},
        unsigned{s.overruns});
  };
  const auto print_telemetry = [&](const dds::ForearmTelemetrySample& t) {
    if (t.node != o.node || printed >= o.samples) return;
    ++printed;
    std::printf(
        "telemetry node %u t %.3f s status %s coarse iterations %u fine iterations %u "
        "solve %u us tracking error %.4f rad\n",
        unsigned{t.node}, t.time_s, name_of(proto::kSolveStatusValues, unsigned(t.solve_status)),
        unsigned{t.coarse_iterations}, unsigned{t.fine_iterations}, unsigned{t.solve_time_us},
        t.tracking_error);
  };
  while (printed < o.samples) {
    if (!client.wait_for_data(o.timeout_s)) {
      std::fprintf(stderr, "hmpc-forearm-cli: %ld of %ld samples from node %d within %g s\n",
                   printed, o.samples, o.node, o.timeout_s);
      return 1;
    }
    client.poll_state(print_state);
    client.poll_telemetry(print_telemetry);
    std::fflush(stdout);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  dds::ForearmCommandSample command;
  try {
    options = parse(argc, argv);
    if (options.command != "watch") {
      command = command_of(options);
      const dds::ValidationResult check = dds::validate(command);
      if (!check.ok && !options.raw_sample) {
        throw ArgumentError{"invalid command: " + check.reason +
                            " (--sine and --offset take degrees)"};
      }
    }
  } catch (const ArgumentError& e) {
    std::fprintf(stderr, "hmpc-forearm-cli: %s\n", e.message.c_str());
    usage(stderr);
    return 2;
  }
  const std::string config = options.loopback ? dds::loopback_config() : std::string();
  try {
    return options.command == "watch" ? watch(options, config) : send(options, command, config);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hmpc-forearm-cli: %s\n", e.what());
    return 1;
  }
}
