// Command line of hmpc-forearm-board. Parsed once at start-up (it may allocate).
#pragma once

#include <net/if.h>

#include <cstdio>
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
  double duration_s = 0;           // 0: until SIGINT or SIGTERM
  std::string log_path;            // empty: no log
  double fail_solver_at_s = 0;     // test hook (BoardConfig::solver_failure_from_tick); 0: never
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
      "                          [--log FILE] [--fail-solver-at SECONDS]\n"
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
      "  --fail-solver-at SECONDS\n"
      "                      test hook for fault tests: every MPC step from this board time on\n"
      "                      ends in a numerical failure\n"
      "On exit the board commands safe outputs (valve vented, motor off). Exit status: 0 on\n"
      "SIGINT, SIGTERM or the end of --duration; 1 when the interface or the log cannot be\n"
      "used; 2 for bad arguments.\n",
      kLogMinutes);
}

using cli::ParseOutcome;

inline ParseOutcome parse_options(int argc, char** argv, Options& options, std::string& error) {
  cli::OptionParser parser;
  parser.text("--interface", [&](const std::string& v) -> std::string {
    if (v.empty() || v.size() >= IFNAMSIZ)
      return cli::bad_value("--interface",
                            "a name of 1.." + std::to_string(IFNAMSIZ - 1) + " characters", v);
    options.interface = v;
    return {};
  });
  parser.integer("--node", 0, forearm_protocol::kMaxNodeId, options.node);
  parser.flag("--lockstep", options.lockstep);
  parser.text("--emulate-target", [&](const std::string& v) -> std::string {
    if (v != "cortex-m7") return cli::bad_value("--emulate-target", "cortex-m7", v);
    options.emulate_cortex_m7 = true;
    return {};
  });
  parser.number("--w-v", 1e-6, 1, "a weight in [1e-6, 1]", options.w_v);
  parser.number("--fail-solver-at", 1e-3, kMaxDurationS, "a board time in [0.001, 1e6] s",
                options.fail_solver_at_s);
  parser.number("--duration", 1e-3, kMaxDurationS, "a number of seconds in [0.001, 1e6]",
                options.duration_s);
  parser.text("--log", [&](const std::string& v) -> std::string {
    if (v.empty()) return "--log needs a file name";
    options.log_path = v;
    return {};
  });
  const ParseOutcome outcome = parser.parse(argc, argv, error);
  if (outcome == ParseOutcome::kRun && options.emulate_cortex_m7 && !options.lockstep) {
    error = "--emulate-target needs --lockstep (in real time the solver's own time counts)";
    return ParseOutcome::kError;
  }
  return outcome;
}

}  // namespace hmpc::linux_board
