// Command line of hmpc-forearm-board. Parsed once at start-up (it may allocate).
#pragma once

#include <net/if.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "hmpc/cli/arguments.hpp"
#include "hmpc/protocol/forearm_protocol.hpp"

namespace hmpc::linux_board {

struct Options {
  std::string interface = "vcan0";
  forearm_protocol::NodeId node = 0;
  bool lockstep = false;
  bool emulate_cortex_m7 = false;  // lock-step: charge solves the STM32H743's compute time
  double w_v = 0;                  // voltage weight of Eq. 3.3; 0: the thesis's (CostWeights)
  double duration_s = 0;  // 0: until SIGINT or SIGTERM
  std::string log_path;   // empty: no log
};

// Long enough for any run a test or an experiment needs, short enough that the tick count
// (uint32 at 1 kHz) cannot wrap.
inline constexpr double kMaxDurationS = 1e6;
// How much of the run --log keeps in memory (about 20 MB at 1 kHz).
inline constexpr int kLogMinutes = 10;

inline void print_usage(std::FILE* out) {
  std::fprintf(
      out,
      "usage: hmpc-forearm-board [--interface IFACE] [--node N] [--lockstep]\n"
      "                          [--emulate-target cortex-m7] [--w-v W] [--duration SECONDS]\n"
      "                          [--log FILE]\n"
      "  --interface IFACE   SocketCAN interface, e.g. can0 or vcan0 (default: vcan0)\n"
      "  --node N            board node id on the bus, 0..15 (default: 0)\n"
      "  --lockstep          HIL lock-step: each valid Sync frame from the plant is one 1 kHz\n"
      "                      tick, and the MPC has no wall-clock deadline (deterministic)\n"
      "                      (default: real time, ticks paced by a 1 kHz CLOCK_MONOTONIC timer)\n"
      "  --emulate-target cortex-m7\n"
      "                      with --lockstep: each MPC output acts after the compute time the\n"
      "                      STM32H743 board (Cortex-M7, 400 MHz) would take for that solve\n"
      "  --w-v W             the MPC's input-voltage weight w_v of Eq. 3.3, in [1e-6, 1]\n"
      "                      (default 0.002, the thesis's; Fig. 3.4 varies it)\n"
      "  --duration SECONDS  stop after this long (default: run until SIGINT or SIGTERM)\n"
      "  --log FILE          write mode and outputs of every tick as CSV at exit (the last\n"
      "                      %d minutes are kept in memory meanwhile)\n"
      "On exit the board commands safe outputs (valve vented, motor off). Exit status: 0 on\n"
      "SIGINT, SIGTERM or the end of --duration; 1 when the interface or the log cannot be\n"
      "used; 2 for bad arguments.\n",
      kLogMinutes);
}

enum class ParseOutcome { kRun, kHelp, kError };

inline ParseOutcome parse_options(int argc, char** argv, Options& options, std::string& error) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "-h" || arg == "--help") return ParseOutcome::kHelp;
    if (arg == "--lockstep") {
      options.lockstep = true;
      continue;
    }
    if (arg != "--interface" && arg != "--node" && arg != "--duration" && arg != "--log" &&
        arg != "--emulate-target" && arg != "--w-v") {
      error = "unknown option '" + arg + "'";
      return ParseOutcome::kError;
    }
    if (i + 1 >= argc) {
      error = arg + " needs a value";
      return ParseOutcome::kError;
    }
    const std::string value = argv[++i];
    if (arg == "--interface") {
      if (value.empty() || value.size() >= IFNAMSIZ) {
        error = "--interface must be a name of 1.." + std::to_string(IFNAMSIZ - 1) +
                " characters, got '" + value + "'";
        return ParseOutcome::kError;
      }
      options.interface = value;
    } else if (arg == "--node") {
      char* end = nullptr;
      const long node = std::strtol(value.c_str(), &end, 10);
      if (value.empty() || *end != '\0' || node < 0 || node > forearm_protocol::kMaxNodeId) {
        error = "--node must be an integer in 0.." + std::to_string(forearm_protocol::kMaxNodeId) +
                ", got '" + value + "'";
        return ParseOutcome::kError;
      }
      options.node = static_cast<forearm_protocol::NodeId>(node);
    } else if (arg == "--duration") {
      char* end = nullptr;
      const double seconds = std::strtod(value.c_str(), &end);
      if (value.empty() || *end != '\0' || !std::isfinite(seconds) || seconds <= 0 ||
          seconds > kMaxDurationS) {
        error = "--duration must be a number of seconds in (0, 1e6], got '" + value + "'";
        return ParseOutcome::kError;
      }
      options.duration_s = seconds;
    } else if (arg == "--w-v") {
      double w = 0;
      if (!cli::parse_number(value, 1e-6, 1, w)) {
        error = cli::bad_value("--w-v", "a weight in [1e-6, 1]", value);
        return ParseOutcome::kError;
      }
      options.w_v = w;
    } else if (arg == "--emulate-target") {
      if (value != "cortex-m7") {
        error = "--emulate-target knows only 'cortex-m7', got '" + value + "'";
        return ParseOutcome::kError;
      }
      options.emulate_cortex_m7 = true;
    } else {
      if (value.empty()) {
        error = "--log needs a file name";
        return ParseOutcome::kError;
      }
      options.log_path = value;
    }
  }
  if (options.emulate_cortex_m7 && !options.lockstep) {
    error = "--emulate-target needs --lockstep (in real time the solver's own time counts)";
    return ParseOutcome::kError;
  }
  return ParseOutcome::kRun;
}

}  // namespace hmpc::linux_board
