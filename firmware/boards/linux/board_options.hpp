// The command-line options every Linux board program has (the application's own are in its
// main). Parsed once at start-up (it may allocate).
#pragma once

#include <cstdio>
#include <string>

#include "hmpc/cli/arguments.hpp"
#include "hmpc/protocol/codec.hpp"

namespace hmpc::linux_board {

struct BoardOptions {
  std::string interface = "vcan0";
  std::string io_interface;  // HIL: the plant's I/O bus; empty: the same as `interface`
  protocol::NodeId node = 0;
  bool lockstep = false;
  double duration_s = 0;  // 0: until SIGINT or SIGTERM
  std::string log_path;   // empty: no log
};

using cli::kMaxDurationS;
// How much of the run --log keeps in memory (about 20 MB at 1 kHz).
inline constexpr int kLogMinutes = 10;

// Usage lines of the common options, for the programs' print_usage.
inline void print_board_options(std::FILE* out) {
  std::fprintf(
      out,
      "  --interface IFACE   SocketCAN interface, e.g. can0 or vcan0 (default: vcan0)\n"
      "  --io-interface IFACE\n"
      "                      HIL: the interface of the plant's I/O bus (sensors, valves, Sync)\n"
      "                      when it is not --interface, e.g. vcan1\n"
      "  --node N            board node id on the bus, 0..15 (default: 0)\n"
      "  --lockstep          HIL lock-step: each valid Sync frame from the plant is one 1 kHz\n"
      "                      tick (deterministic; default: real time, ticks paced by a 1 kHz\n"
      "                      CLOCK_MONOTONIC timer)\n"
      "  --duration SECONDS  stop after this long (default: run until SIGINT or SIGTERM)\n"
      "  --log FILE          write the board's state at every tick as CSV at exit (the last\n"
      "                      %d minutes are kept in memory meanwhile)\n",
      kLogMinutes);
}

inline void add_board_options(cli::OptionParser& parser, BoardOptions& options,
                              protocol::NodeId max_node) {
  parser.interface("--interface", options.interface);
  parser.interface("--io-interface", options.io_interface);
  parser.integer("--node", 0, max_node, options.node);
  parser.flag("--lockstep", options.lockstep);
  parser.number("--duration", 1e-3, kMaxDurationS, "a number of seconds in [0.001, 1e6]",
                options.duration_s);
  parser.text("--log", [&options](const std::string& v) -> std::string {
    if (v.empty()) return "--log needs a file name";
    options.log_path = v;
    return {};
  });
}

}  // namespace hmpc::linux_board
