// Command line of hmpc-joint-board: the common board options and the joint board's own. Parsed
// once at start-up (it may allocate).
#pragma once

#include <array>
#include <cstdio>
#include <string>

#include "board_options.hpp"
#include "hmpc/protocol/joint_protocol.hpp"

namespace hmpc::linux_board {

struct JointOptions {
  BoardOptions board;
  long joints = 1;  // 1..4
  long control_period_ms = joint_protocol::kDefaultControlPeriodMs;
  bool load_velocity_feedback = true;  // false: the torque loop is a plain PID
  // The actuator constants the board believes, as a multiple of the nominal ones (bulk modulus
  // and valve flow gain): what a compensator tuned on a data sheet sees of a real joint.
  double believed_actuator_scale = 1;
  bool stored_offsets = false;  // trust the stored encoder offsets: hold and run without zeroing
  // One of the humanoid's legs (humanoid_leg_board.hpp): its four joints and actuators.
  bool humanoid_leg = false;
  std::array<double, joint_protocol::kMaxJointsPerBoard> zero_posture{};  // rad, per channel
};

inline void print_joint_usage(std::FILE* out) {
  std::fprintf(
      out,
      "usage: hmpc-joint-board [--interface IFACE] [--io-interface IFACE] [--node N] [--lockstep]\n"
      "                        [--duration SECONDS] [--log FILE] [--joints N]\n"
      "                        [--control-period-ms 1..6] [--no-load-velocity-feedback]\n"
      "                        [--believed-actuator-scale S] [--stored-offsets]\n"
      "                        [--humanoid-leg] [--zero-posture A,B,C,D]\n");
  print_board_options(out);
  std::fprintf(
      out,
      "  --joints N          hydraulic joints this board drives, 1..4 (default: 1)\n"
      "  --control-period-ms P\n"
      "                      torque loop period, 1..6 ms (default: 6, the thesis's Sec. 2.7.3)\n"
      "  --no-load-velocity-feedback\n"
      "                      plain PID torque loops (the same kp, ki; no velocity term)\n"
      "  --believed-actuator-scale S\n"
      "                      tune the loops for an actuator whose bulk modulus and valve flow\n"
      "                      gain are S times the nominal ones, S in [0.5, 2] (default: 1)\n"
      "  --stored-offsets    hold and run on the stored encoder offsets, without zeroing\n"
      "  --humanoid-leg      drive one of the humanoid's legs: four joints (hip abduction, hip\n"
      "                      flexion, knee, ankle) with the leg's actuators, torque limits and\n"
      "                      soft limits (replaces --joints)\n"
      "  --zero-posture A,B,C,D\n"
      "                      each channel's angle in rad when the host zeroes the encoders\n"
      "                      (default: 0 for each)\n"
      "On exit, and in idle and fault, the valves are centred (each joint hydraulically locked).\n"
      "Exit status: 0 on SIGINT, SIGTERM or the end of --duration; 1 when the interface or the\n"
      "log cannot be used; 2 for bad arguments.\n");
}

inline cli::ParseOutcome parse_joint_options(int argc, char** argv, JointOptions& options,
                                             std::string& error) {
  cli::OptionParser parser;
  add_board_options(parser, options.board, joint_protocol::kIds.max_node);
  parser.integer("--joints", 1, long(joint_protocol::kMaxJointsPerBoard), options.joints);
  parser.integer("--control-period-ms", 1, 6, options.control_period_ms);
  bool no_lvf = false;
  parser.flag("--no-load-velocity-feedback", no_lvf);
  parser.number("--believed-actuator-scale", 0.5, 2, "a factor in [0.5, 2]",
                options.believed_actuator_scale);
  parser.flag("--stored-offsets", options.stored_offsets);
  parser.flag("--humanoid-leg", options.humanoid_leg);
  parser.text("--zero-posture", [&options](const std::string& v) -> std::string {
    std::size_t start = 0;
    for (std::size_t j = 0; j < options.zero_posture.size(); ++j) {
      const std::size_t comma = v.find(',', start);
      const bool last = j + 1 == options.zero_posture.size();
      if ((comma == std::string::npos) != last ||
          !cli::parse_number(v.substr(start, last ? std::string::npos : comma - start), -3.1416,
                             3.1416, options.zero_posture[j])) {
        return cli::bad_value("--zero-posture", "four angles in [-pi, pi] rad, comma-separated", v);
      }
      start = comma + 1;
    }
    return {};
  });
  const cli::ParseOutcome outcome = parser.parse(argc, argv, error);
  options.load_velocity_feedback = !no_lvf;
  return outcome;
}

}  // namespace hmpc::linux_board
