// One forearm HIL run over CAN: the three programs a lab would run, as separate processes on
// one SocketCAN interface (vcan0 through hil/vcan/run-with-vcan.sh) in lock-step:
//   hmpc-forearm-board  --lockstep --emulate-target cortex-m7   (the firmware, Linux build)
//   hmpc-forearm-host   --lockstep --run STRATEGY ...            (CAN master, target stream)
//   hmpc-forearm-plant  --lockstep --wait-host ...               (Simbody forearm)
// and the figures of the run from their logs and summaries: accumulated cost (Eq. 3.3a per
// 4 ms control period, as forearm::simulate_tracking counts it), RMS tracking error, solve
// times charged by the emulated Cortex-M7, deadline misses and the torque shares. The target is
// checked before any program starts, and the run scored against the same points the host
// streams.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "hmpc/models/forearm.hpp"
#include "hmpc/protocol/forearm_protocol.hpp"
#include "hmpc/trajectory/joint_target.hpp"
#include "simbody_forearm.hpp"

namespace hmpc::hil {

struct HilPrograms {
  std::string board, plant, host;  // executables
  // The build's own programs (compiled-in paths).
  static HilPrograms built();
};

struct HilRunSpec {
  forearm_protocol::Strategy strategy = forearm_protocol::Strategy::kTwoStage;
  forearm_protocol::NodeId node = 0;  // board node id: runs at once on one bus use different ones
  // The target from the run's start (its duration is run_for_s); by default the thesis's
  // Sec. 3.3 target, +-30 deg at 1 Hz.
  trajectory::TargetSpec target{};
  double run_for_s = 10;   // thesis Sec. 3.4: 10-s trials
  double run_at_s = 0.3;   // idle, then hold, then run from here (host's script)
  double settle_s = 0.1;   // plant keeps stepping after the run (board back in hold)
  double noise_scale = 0;  // plant sensor noise (plant_node/options.hpp SensorNoise)
  std::uint64_t seed = 1;
  ForearmMismatch mismatch{};
  double w_v = 0;  // board's voltage weight of Eq. 3.3; 0: the thesis's default
  std::vector<std::string> board_args, plant_args, host_args;  // extra options, e.g. faults
  bool host_dies = false;  // the host is to kill itself (--die-at): it must end by SIGKILL
  std::string directory;   // where logs and program outputs go (created)
};

// A row of the plant's log: the state at `time` and the inputs applied during the millisecond
// before it (row k of a lock-step run: step k, driven by the board's answer to Sync k, which
// the board computed in its tick k + 1).
struct PlantRow {
  double time, theta, theta_dot, pressure_bar, v_p, v_m, tau_p, tau_m;
};

// A row of the board's tick log.
struct BoardTickRow {
  std::uint32_t tick = 0;
  std::string mode;
  unsigned faults = 0;
  double v_p = 0, v_m = 0;
  std::uint32_t heartbeat_age = 0, sensor_age = 0;  // ticks since the last accepted one
};

struct HilRunResult {
  bool ok = false;
  std::string error;            // why not ok: a program failed, timed out, or a log was unreadable
  double accumulated_cost = 0;  // Eq. 3.3a over the run, per control period
  double rms_error = 0;         // rad, theta - theta_d over the run
  double solve_time_max_us = 0, solve_time_median_us = 0;  // charged Cortex-M7 time
  double deadline_misses = 0;  // MPC steps charged over the board's 3.5 ms budget
  double mean_abs_pam_torque = 0, mean_abs_motor_torque = 0;  // N·m over the run
  double theta_min = 0, theta_max = 0;                        // over the whole plant log
  bool within_stops = false;
  // key=value summaries the programs printed at exit.
  std::map<std::string, std::string> board, plant, host;
  std::vector<PlantRow> plant_log;
  std::vector<BoardTickRow> board_log;
  double motor_share() const {
    return mean_abs_motor_torque / (mean_abs_pam_torque + mean_abs_motor_torque);
  }
  double number(const std::map<std::string, std::string>& summary, const std::string& key) const;
};

HilRunResult run_hil(const HilRunSpec& spec, const HilPrograms& programs);

// The logs the plant node and the board write with --log: the header, then one row per line.
// False, with `error` naming the file and its first malformed row, when a row does not parse.
bool read_plant_log(const std::string& path, std::vector<PlantRow>& rows, std::string& error);
bool read_board_log(const std::string& path, std::vector<BoardTickRow>& rows, std::string& error);

}  // namespace hmpc::hil
