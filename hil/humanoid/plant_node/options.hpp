// Command line of hmpc-humanoid-plant. Parsed once at start-up.
#pragma once

#include <cstdio>
#include <string>
#include <vector>

#include "../hydraulic_humanoid.hpp"
#include "hmpc/cli/arguments.hpp"
#include "hmpc/humanoid/model.hpp"
#include "hmpc/platform/linux/frame_faults.hpp"

namespace hmpc::hil::humanoid_plant {

using platform::FaultConfig;

// Sensor noise at --noise 1 (standard deviations) on what the joint boards read besides the
// encoders (which are quantised, hmpc/sensors/joint_sensors.hpp) and the IMU (whose noise is its
// data sheet's, hmpc/sensors/imu.hpp, always on): as the one-joint bench's, 0.5 % of a 100 N m
// load cell and 0.1 % of a 25 MPa pressure transducer.
struct SensorNoise {
  double torque = 0.5;      // N m
  double pressure = 2.5e4;  // Pa
};

struct Options {
  std::string robot_interface = "vcan0";  // the IMU's frames; the host's heard
  std::string io_interface = "vcan1";     // the boards' sensors and valves, and Sync
  bool lockstep = false;
  bool wait_host = false;      // lock-step: also wait for the host's heartbeat and references
  double host_timeout_s = 2;   // ... at most this long each, then stop waiting for it
  double duration_s = 0;       // 0: until SIGINT or SIGTERM
  double start_height = 0.85;  // m: the standing stance's base point height
  HumanoidMismatch mismatch{};
  double noise_scale = 0;
  std::uint64_t seed = 1;        // IMU biases and noise, encoder mounting offsets, sensor noise
  bool mounting_offsets = true;  // each encoder mounted off its joint's zero (boards must zero)
  FaultConfig imu_faults{};      // on the IMU's frames
  FaultConfig sensor_faults{};   // on the boards' sensor frames (the I/O bus)
  std::vector<Push> pushes;
  double die_at_s = -1;  // test hook: SIGKILL to itself at this simulated time; < 0: never
  std::string log_path;
};

inline void print_usage(std::FILE* out) {
  std::fprintf(
      out,
      "usage: hmpc-humanoid-plant [--robot-interface IFACE] [--io-interface IFACE] [--lockstep]\n"
      "         [--wait-host] [--host-timeout S] [--duration S] [--start-height M]\n"
      "         [--mass-scale X] [--inertia-scale X] [--friction-scale X]\n"
      "         [--bulk-modulus-scale X] [--valve-gain-scale X] [--noise F] [--seed N]\n"
      "         [--no-mounting-offsets] [--imu-drop-percent P] [--imu-silence-at S]\n"
      "         [--imu-silence-ms MS] [--sensor-drop-percent P] [--sensor-corrupt-percent P]\n"
      "         [--push BODY,FX,FY,FZ,START,DURATION]... [--die-at S] [--log FILE]\n"
      "The humanoid in Simbody with hydraulic legs (hil/humanoid/hydraulic_humanoid.hpp), stepped\n"
      "at 1 ms: every step it sends each leg board (nodes 0 and 1) its joints' encoder, velocity\n"
      "and load cell and their chamber pressures on the I/O bus, then a Sync, and applies the\n"
      "boards' latest ValveDrive; every 6 ms the torso IMU's mean gyroscope and accelerometer\n"
      "reading on the robot bus (node 2).\n"
      "  --robot-interface IFACE  the robot bus (default vcan0)\n"
      "  --io-interface IFACE     the HIL's I/O bus (default vcan1)\n"
      "  --lockstep               step when both boards have answered the Sync (deterministic\n"
      "                           pace); default: real time, 1 kHz timer\n"
      "  --wait-host              lock-step: also wait, once the host is heard, for its heartbeat\n"
      "                           every 10 ms and its torque references every 6 ms\n"
      "  --host-timeout S         ... at most S seconds each; after 3 misses in a row it stops\n"
      "                           waiting (default 2)\n"
      "  --duration S             simulated seconds (default: until SIGINT or SIGTERM)\n"
      "  --start-height M         standing at rest, the base point M metres up, 0.6..0.9\n"
      "                           (default 0.85, Table 2.2's)\n"
      "  --mass-scale X, --inertia-scale X, --friction-scale X, --bulk-modulus-scale X,\n"
      "  --valve-gain-scale X     plant/nominal factors in [0.5, 2]: every body's mass, inertia,\n"
      "                           the cylinders' seal friction, the oil's bulk modulus, the "
      "valves'\n"
      "                           flow gain\n"
      "  --noise F                load cell and pressure noise, F times 0.5 N m and 25 kPa\n"
      "  --seed N                 IMU biases and noise, encoder mounting, sensor noise (default "
      "1)\n"
      "  --no-mounting-offsets    encoders read the joint angles (default: each off by a seeded\n"
      "                           angle within +-0.3 rad, which zeroing must find)\n"
      "  --imu-drop-percent P     share of the IMU's frames lost\n"
      "  --imu-silence-at S, --imu-silence-ms MS\n"
      "                           the IMU falls silent at S for MS (default: for good)\n"
      "  --sensor-drop-percent P, --sensor-corrupt-percent P\n"
      "                           share of the boards' sensor frames lost, or with a bit flipped\n"
      "  --push BODY,FX,FY,FZ,START,DURATION\n"
      "                           a force (N, world) on a body's centre of mass (torso, or a body\n"
      "                           index 0..8) from START for DURATION seconds; repeatable\n"
      "  --die-at S               test hook: SIGKILL to itself at simulated time S\n"
      "  --log FILE               CSV, one row per ms: the plant's truth\n"
      "Exit status: 0 at the end of --duration or on SIGINT/SIGTERM; 1 when a bus or the log "
      "fails\n"
      "or a board stops answering in lock-step; 2 for bad arguments.\n");
}

// BODY,FX,FY,FZ,START,DURATION.
inline std::string parse_push(const std::string& text, Push& push) {
  std::vector<std::string> fields;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = text.find(',', start);
    fields.push_back(text.substr(start, comma == std::string::npos ? comma : comma - start));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  const std::string what = "BODY,FX,FY,FZ,START,DURATION (torso or 0..8, N, s)";
  if (fields.size() != 6) return cli::bad_value("--push", what, text);
  long body = 0;
  if (fields[0] == "torso") {
    body = 0;
  } else if (!cli::parse_integer(fields[0], 0, humanoid::kBodies - 1, body)) {
    return cli::bad_value("--push", what, text);
  }
  push.body = int(body);
  double values[5];
  for (int i = 0; i < 5; ++i) {
    const double bound = i < 3 ? 2000 : cli::kMaxDurationS;
    if (!cli::parse_number(fields[std::size_t(i) + 1], i < 3 ? -bound : 0, bound, values[i])) {
      return cli::bad_value("--push", what + ", forces within 2000 N", text);
    }
  }
  push.force = humanoid::Vector3(values[0], values[1], values[2]);
  push.start = values[3];
  push.duration = values[4];
  return {};
}

inline cli::ParseOutcome parse_options(int argc, char** argv, Options& o, std::string& error) {
  cli::OptionParser p;
  p.interface("--robot-interface", o.robot_interface);
  p.interface("--io-interface", o.io_interface);
  p.flag("--lockstep", o.lockstep);
  p.flag("--wait-host", o.wait_host);
  p.number("--host-timeout", 0.01, 60, "seconds in [0.01, 60]", o.host_timeout_s);
  p.number("--duration", 0.001, cli::kMaxDurationS, "seconds in [0.001, 1e6]", o.duration_s);
  p.number("--start-height", 0.6, 0.9, "metres in [0.6, 0.9]", o.start_height);
  p.number("--mass-scale", 0.5, 2, "a factor in [0.5, 2]", o.mismatch.mass_scale);
  p.number("--inertia-scale", 0.5, 2, "a factor in [0.5, 2]", o.mismatch.inertia_scale);
  p.number("--friction-scale", 0.5, 2, "a factor in [0.5, 2]", o.mismatch.joint_friction_scale);
  p.number("--bulk-modulus-scale", 0.5, 2, "a factor in [0.5, 2]", o.mismatch.bulk_modulus_scale);
  p.number("--valve-gain-scale", 0.5, 2, "a factor in [0.5, 2]", o.mismatch.valve_flow_gain_scale);
  p.number("--noise", 0, 10, "a factor in [0, 10]", o.noise_scale);
  p.integer("--seed", 0, 1L << 30, o.seed);
  bool no_offsets = false;
  p.flag("--no-mounting-offsets", no_offsets);
  double imu_drop = 0, sensor_drop = 0, sensor_corrupt = 0, imu_silence_ms = 0;
  p.number("--imu-drop-percent", 0, 100, "a percentage in [0, 100]", imu_drop);
  p.number("--imu-silence-at", 0, cli::kMaxDurationS, "seconds in [0, 1e6]",
           o.imu_faults.silence_start_s);
  p.number("--imu-silence-ms", 1, 1e9, "milliseconds >= 1", imu_silence_ms);
  p.number("--sensor-drop-percent", 0, 100, "a percentage in [0, 100]", sensor_drop);
  p.number("--sensor-corrupt-percent", 0, 100, "a percentage in [0, 100]", sensor_corrupt);
  p.text("--push", [&o](const std::string& v) -> std::string {
    Push push;
    std::string invalid = parse_push(v, push);
    if (invalid.empty()) o.pushes.push_back(push);
    return invalid;
  });
  p.number("--die-at", 0, cli::kMaxDurationS, "seconds in [0, 1e6]", o.die_at_s);
  p.text("--log", [&o](const std::string& v) -> std::string {
    if (v.empty()) return "--log needs a file name";
    o.log_path = v;
    return {};
  });
  const cli::ParseOutcome outcome = p.parse(argc, argv, error);
  if (outcome != cli::ParseOutcome::kRun) return outcome;
  if (o.io_interface == o.robot_interface) {
    error =
        "--io-interface must differ from --robot-interface (the robot bus carries no plant "
        "frames)";
    return cli::ParseOutcome::kError;
  }
  o.mounting_offsets = !no_offsets;
  o.imu_faults.drop_fraction = imu_drop / 100;
  o.imu_faults.silence_duration_s = imu_silence_ms > 0 ? imu_silence_ms / 1000 : cli::kMaxDurationS;
  o.imu_faults.seed = o.seed ^ 0x1a1a1a1aULL;
  o.sensor_faults.drop_fraction = sensor_drop / 100;
  o.sensor_faults.corrupt_fraction = sensor_corrupt / 100;
  o.sensor_faults.seed = o.seed ^ 0x5e5e5e5eULL;
  return outcome;
}

}  // namespace hmpc::hil::humanoid_plant
