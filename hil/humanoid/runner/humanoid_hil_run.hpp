// One run of the humanoid over CAN, and its figures as Sec. 2.7.4 reports the real robot's:
// hmpc-humanoid-plant (the Simbody humanoid with hydraulic legs: the joint boards' sensors and
// valves on the I/O bus vcan1, its IMU on the robot bus vcan0), the two leg boards
// (hmpc-joint-board --humanoid-leg) and the host (hmpc-humanoid-host) as separate programs in
// lock-step, each plan charged the compute time the host's model gives it (the guest's wall
// time stands for nothing). The figures come from what the programs log: the host's solves and
// estimate, the plant's truth, both buses in candump format.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace hmpc::hil {

using Summary = std::map<std::string, std::string>;

struct HumanoidHilConfig {
  std::string dir;                     // the run's logs go here (emptied first)
  double seconds = 2.0;                // simulated
  double hold_seconds = 1.0;           // the boards' hold before the MPC
  std::vector<std::string> host_args;  // more of the host's options (a task: --motion ...)
};

struct HumanoidHilRun {
  bool ok = false;
  std::string error, dir;
  Summary plant, host;  // each program's summary line
  std::vector<Summary> boards;
};

// Starts the boards, the host and the plant (a vcan0 and a vcan1 must exist) and waits for
// the plant's end.
HumanoidHilRun run_humanoid_hil(const HumanoidHilConfig& config);

struct HumanoidHilFigures {
  double mpc_start_s = 0;  // when the MPC took over
  // Solves after the take-over: how many, the largest charged compute time and the share over
  // the 12 ms sampling period (the thesis's robot: 13.30 ms and 0.84 % holding the hip).
  int solves = 0;
  double largest_solve_ms = 0, share_over_period = 0;  // share in [0, 1]
  // The estimate against the plant's truth under the MPC, RMS: the torso's height [m], its
  // horizontal velocity [m/s] and its tilt [rad].
  double height_rms = 0, horizontal_velocity_rms = 0, tilt_rms = 0;
  // Each bus's load at 1 Mbit/s (worst-case stuffing) over the run, as logged, and as the
  // protocol's periods give it.
  double robot_bus_load = 0, io_bus_load = 0;
  double robot_bus_design_load = 0, io_bus_design_load = 0;
  // Sensor to torque, in plant ticks (1 ms): from the IMU reading the solve's estimate took
  // last to the first torque reference of its plan on the robot bus.
  int latency_min = 0, latency_max = 0;
  double latency_median = 0;
  // The task on the plant's truth from the take-over on: the base point's (hmpc/humanoid/
  // stance.hpp) largest horizontal distance from where it was [m], the torso's largest tilt
  // [rad] and its lowest height [m].
  double hip_drift = 0, max_tilt = 0, min_height = 0;
  // Simulated seconds per wall-clock second of the lock-step.
  double lockstep_speed = 0;
};

// The figures of a finished run; false (and why) when its logs do not hold them.
bool figures_of(const HumanoidHilRun& run, HumanoidHilFigures& out, std::string& error);

}  // namespace hmpc::hil
