// Replaying a lock-step run's robot bus log (candump -l, as hmpc-humanoid-host --log-dir writes
// it) into a host, offline: the frames the host heard go to it again on the ticks they came,
// the host ticks as it did, and every frame it sends is compared with the one it sent in the
// run. With the run's configuration (and plans charged by the compute model, which the log
// alone decides) the replay is the run, bit for bit: a controller's decisions can be stepped
// through, logged or changed and compared, away from the robot.
//
// The stamps: in lock-step the host stamps each line with the tick it is on, so a frame it
// heard stamped k came after tick k - 1 and before tick k, and a frame it sent stamped k is
// tick k's.
#pragma once

#include <cstdint>
#include <functional>
#include <istream>
#include <string>

#include "hmpc/host/humanoid_host.hpp"

namespace hmpc::host {

struct ReplayReport {
  std::uint32_t ticks = 0;            // the host ticked
  std::uint64_t heard = 0, sent = 0;  // frames given to it; frames it sent in the replay
  std::uint64_t logged_sent = 0;      // frames it sent in the run
  std::uint64_t mismatches = 0;       // sent frames that differ from the run's, or are missing
  std::uint32_t first_mismatch_tick = 0;
  std::string first_mismatch;       // what differed first
  std::uint64_t skipped_lines = 0;  // not a candump line, or not a protocol frame
};

// Replays `log` into `host` (constructed with the run's configuration, not yet ticked);
// `before_tick(tick)`, when given, is called before each tick (what the run's program did then:
// resume a paused motion, an E-stop). False when the log holds no frame or its stamps go
// backwards.
bool replay_lockstep_log(std::istream& log, HumanoidHost& host, ReplayReport& report,
                         std::string& error,
                         const std::function<void(std::uint32_t)>& before_tick = {});

}  // namespace hmpc::host
