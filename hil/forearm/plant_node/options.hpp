// Command line of hmpc-forearm-plant. Parsed once at start-up.
#pragma once

#include <cstdio>
#include <string>

#include "../simbody_forearm.hpp"
#include "hmpc/cli/arguments.hpp"
#include "hmpc/platform/linux/frame_faults.hpp"
#include "hmpc/protocol/forearm_protocol.hpp"

namespace hmpc::hil::plant_node {

using platform::FaultConfig;

// Sensor noise at --noise 1 (standard deviations, white, Gaussian): a 14-bit absolute encoder
// (0.38 mrad steps, std of its quantisation ~0.1 mrad, plus mounting play) gives theta 0.5 mrad;
// velocity differentiated from it and filtered at ~50 Hz, 0.01 rad/s; a 1 MPa pressure sensor
// at 0.1 % of full scale, 0.001 MPa = 0.01 bar. Our choices, typical of such an arm.
struct SensorNoise {
  double theta = 0.0005;       // rad
  double theta_dot = 0.01;     // rad/s
  double pressure_bar = 0.01;  // bar
};

struct Options {
  std::string interface = "vcan0";
  forearm_protocol::NodeId node = 0;
  bool lockstep = false;
  double duration_s = 0;  // 0: until SIGINT or SIGTERM
  double theta0 = 0;      // rad, at rest, held there by the PAM's equilibrium pressure
  ForearmMismatch mismatch{};
  double noise_scale = 0;             // multiplies SensorNoise
  int sensor_delay_ms = 0;            // transport delay of sensor readings
  FaultConfig sensor_faults{};        // on the Sensor frames
  bool wait_host = false;             // lock-step: wait for the host's heartbeat every 10 ticks
  double host_timeout_s = 2;          // ... at most this long, then stop waiting for it
  double drop_commands_fraction = 0;  // of the board's ActuatorCommand frames, lost on the way
  double die_at_s = -1;  // test hook: SIGKILL to itself at this simulated time; < 0: never
  std::string log_path;
};

using cli::kMaxDurationS;
inline constexpr int kMaxSensorDelayMs = 100;

inline void print_usage(std::FILE* out) {
  std::fprintf(
      out,
      "usage: hmpc-forearm-plant [--interface IFACE] [--node N] [--lockstep] [--duration S]\n"
      "         [--theta0 RAD] [--mass-scale X] [--friction-scale X] [--pam-time-scale X]\n"
      "         [--noise SCALE] [--seed N] [--sensor-delay-ms MS] [--drop-percent P]\n"
      "         [--corrupt-percent P] [--silence-at S] [--silence-ms MS] [--wait-host]\n"
      "         [--host-timeout S] [--drop-commands-percent P] [--die-at S] [--log FILE]\n"
      "The forearm in Simbody, stepped at 1 ms, speaking the board's CAN protocol: it sends a\n"
      "Sensor frame (theta, theta', P) every step and applies the board's latest\n"
      "ActuatorCommand (v_p, v_m) within the actuators' limits.\n"
      "  --interface IFACE    SocketCAN interface (default vcan0)\n"
      "  --node N             board node id 0..15 (default 0)\n"
      "  --lockstep           send a Sync after each Sensor frame and step when the board has\n"
      "                       answered it (deterministic); default: real time, 1 kHz timer\n"
      "  --duration S         simulated seconds to run (default: until SIGINT/SIGTERM)\n"
      "  --theta0 RAD         initial angle, at rest (default 0)\n"
      "  --mass-scale X, --friction-scale X, --pam-time-scale X\n"
      "                       plant-model mismatch factors in [0.5, 2] (default 1)\n"
      "  --noise SCALE        sensor noise, times the typical levels (0..10, default 0)\n"
      "  --seed N             seed of noise and faults (default 1)\n"
      "  --sensor-delay-ms MS sensor transport delay 0..%d ms (default 0)\n"
      "  --drop-percent P     lose P %% of Sensor frames (default 0)\n"
      "  --corrupt-percent P  flip a bit in P %% of Sensor frames (default 0)\n"
      "  --silence-at S, --silence-ms MS\n"
      "                       send no Sensor frame for MS ms from simulated time S\n"
      "  --wait-host          lock-step: every 10 ticks also wait for the host's heartbeat,\n"
      "                       so a run with a host is deterministic\n"
      "  --host-timeout S     ... for at most S s (default 2), then stop waiting for it\n"
      "  --drop-commands-percent P\n"
      "                       lose P %% of the board's ActuatorCommand frames (the actuators\n"
      "                       keep the last command they received)\n"
      "  --die-at S           test hook: the plant kills itself with SIGKILL at simulated time S\n"
      "  --log FILE           CSV of every step: time, state, inputs, torques\n"
      "Exit status: 0 at the end of --duration or on SIGINT/SIGTERM; 1 when the bus, the log\n"
      "or the board fails (no answer to a Sync in lock-step within 5 s); 2 for bad arguments.\n",
      kMaxSensorDelayMs);
}

using cli::ParseOutcome;

inline ParseOutcome parse_options(int argc, char** argv, Options& o, std::string& error) {
  cli::OptionParser parser;
  parser.interface("--interface", o.interface);
  parser.integer("--node", 0, forearm_protocol::kMaxNodeId, o.node);
  parser.flag("--lockstep", o.lockstep);
  parser.number("--duration", 1e-3, kMaxDurationS, "a number of seconds in [0.001, 1e6]",
                o.duration_s);
  parser.number("--theta0", -1.2, 1.6, "an angle in [-1.2, 1.6] rad", o.theta0);
  parser.number("--mass-scale", 0.5, 2, "a factor in [0.5, 2]", o.mismatch.mass_scale);
  parser.number("--friction-scale", 0.5, 2, "a factor in [0.5, 2]", o.mismatch.friction_scale);
  parser.number("--pam-time-scale", 0.5, 2, "a factor in [0.5, 2]",
                o.mismatch.pam_time_constant_scale);
  parser.number("--noise", 0, 10, "a scale in [0, 10]", o.noise_scale);
  parser.integer("--seed", 0, 2147483647L, o.sensor_faults.seed);
  parser.integer("--sensor-delay-ms", 0, kMaxSensorDelayMs, o.sensor_delay_ms);
  parser.number("--drop-percent", 0, 100, "a percentage in [0, 100]", o.sensor_faults.drop_fraction,
                0.01);
  parser.number("--corrupt-percent", 0, 100, "a percentage in [0, 100]",
                o.sensor_faults.corrupt_fraction, 0.01);
  double silence_at = -1, silence_ms = 100;
  parser.number("--silence-at", 0, kMaxDurationS, "a time in [0, 1e6] s", silence_at);
  parser.number("--silence-ms", 1, 1e6, "a duration in [1, 1e6] ms", silence_ms);
  parser.flag("--wait-host", o.wait_host);
  parser.number("--drop-commands-percent", 0, 100, "a percentage in [0, 100]",
                o.drop_commands_fraction, 0.01);
  parser.number("--die-at", 0, kMaxDurationS, "a time in [0, 1e6] s", o.die_at_s);
  parser.number("--host-timeout", 0.01, 600, "a number of seconds in [0.01, 600]",
                o.host_timeout_s);
  parser.text("--log", [&](const std::string& v) -> std::string {
    if (v.empty()) return "--log needs a file name";
    o.log_path = v;
    return {};
  });
  const ParseOutcome outcome = parser.parse(argc, argv, error);
  if (outcome != ParseOutcome::kRun) return outcome;
  o.sensor_faults.silence_start_s = silence_at;
  o.sensor_faults.silence_duration_s = silence_at >= 0 ? silence_ms * 1e-3 : 0;
  if (o.wait_host && !o.lockstep) {
    error = "--wait-host needs --lockstep";
    return ParseOutcome::kError;
  }
  return ParseOutcome::kRun;
}

}  // namespace hmpc::hil::plant_node
