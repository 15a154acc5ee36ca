// Command line of hmpc-forearm-board: the common board options and the forearm's own. Parsed
// once at start-up (it may allocate).
#pragma once

#include <cstdio>
#include <string>

#include "board_options.hpp"
#include "hmpc/models/forearm_mpc.hpp"
#include "hmpc/protocol/forearm_protocol.hpp"

namespace hmpc::linux_board {

struct Options {
  BoardOptions board;
  bool emulate_cortex_m7 = false;  // lock-step: charge solves the STM32H743's compute time
  double w_v = 0;                  // voltage weight of Eq. 3.3; 0: the thesis's (CostWeights)
  double fail_solver_at_s = 0;     // test hook (BoardConfig::solver_failure_from_tick); 0: never
  bool offset_free = false;        // BoardConfig::offset_free
  bool terminal_rate = false;      // BoardConfig::two_stage_terminal_rate
};

inline void print_usage(std::FILE* out) {
  std::fprintf(
      out,
      "usage: hmpc-forearm-board [--interface IFACE] [--io-interface IFACE] [--node N] "
      "[--lockstep]\n"
      "                          [--emulate-target cortex-m7] [--w-v W] [--offset-free]\n"
      "                          [--terminal-rate]\n"
      "                          [--duration SECONDS] [--log FILE] [--fail-solver-at SECONDS]\n");
  print_board_options(out);
  std::fprintf(
      out,
      "                      (lock-step: the MPC has no wall-clock deadline)\n"
      "  --emulate-target cortex-m7\n"
      "                      with --lockstep: each MPC output acts after the compute time the\n"
      "                      STM32H743 board (Cortex-M7, 400 MHz) would take for that solve\n"
      "  --w-v W             the MPC's input-voltage weight w_v of Eq. 3.3, in [1e-6, 1]\n"
      "                      (default 0.002, the thesis's; Fig. 3.4 varies it)\n"
      "  --offset-free       offset-free MPC: a disturbance observer on the joint, its estimate\n"
      "                      in every strategy's model, the torque penalty counted beyond the\n"
      "                      holding torque (default: the thesis's Eq. 3.1 and 3.3)\n"
      "  --terminal-rate     the Two-stage also prices the joint rate's error where each\n"
      "                      stage's horizon ends, w_theta T_v^2 (theta' - theta_d')^2, T_v %g s\n"
      "                      in the first stage and %g s in the second (default: the thesis's\n"
      "                      Eq. 3.3b)\n"
      "  --fail-solver-at SECONDS\n"
      "                      test hook for fault tests: every MPC step from this board time on\n"
      "                      ends in a numerical failure\n"
      "On exit the board commands safe outputs (valve vented, motor off). Exit status: 0 on\n"
      "SIGINT, SIGTERM or the end of --duration; 1 when the interface or the log cannot be\n"
      "used; 2 for bad arguments.\n",
      forearm::kTwoStageTerminalRate.first_stage, forearm::kTwoStageTerminalRate.second_stage);
}

using cli::ParseOutcome;

inline ParseOutcome parse_options(int argc, char** argv, Options& options, std::string& error) {
  cli::OptionParser parser;
  add_board_options(parser, options.board, forearm_protocol::kMaxNodeId);
  parser.text("--emulate-target", [&](const std::string& v) -> std::string {
    if (v != "cortex-m7") return cli::bad_value("--emulate-target", "cortex-m7", v);
    options.emulate_cortex_m7 = true;
    return {};
  });
  parser.number("--w-v", 1e-6, 1, "a weight in [1e-6, 1]", options.w_v);
  parser.flag("--offset-free", options.offset_free);
  parser.flag("--terminal-rate", options.terminal_rate);
  parser.number("--fail-solver-at", 1e-3, kMaxDurationS, "a board time in [0.001, 1e6] s",
                options.fail_solver_at_s);
  const ParseOutcome outcome = parser.parse(argc, argv, error);
  if (outcome == ParseOutcome::kRun && options.emulate_cortex_m7 && !options.board.lockstep) {
    error = "--emulate-target needs --lockstep (in real time the solver's own time counts)";
    return ParseOutcome::kError;
  }
  return outcome;
}

}  // namespace hmpc::linux_board
