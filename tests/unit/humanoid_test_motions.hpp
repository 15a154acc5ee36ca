// Motions the humanoid unit tests share.
#pragma once

#include <string>

#include "hmpc/humanoid/closed_loop.hpp"
#include "hmpc/humanoid/motion.hpp"

namespace hmpc::humanoid::test {

// Every weight zero and one phase: standing still, upright, at 0.85 m (Table 2.2, I).
inline Motion bare_motion() {
  Motion m;
  m.duration = 1.0;
  m.phase_count = 1;
  m.phases[0].height = 0.85;
  return m;
}

#ifdef HMPC_HUMANOID_MOTIONS
// A shipped motion file by name (host/humanoid/motions/<name>.motion).
inline Motion motion(const std::string& name) {
  return load_motion(std::string(HMPC_HUMANOID_MOTIONS) + "/" + name + ".motion");
}
#endif

// A closed-loop run without truncation: a truncated solve depends on the machine's load, and
// ctest shares 2 cores; without it a run is the same numbers every time (the thread pool's
// results are bit-identical to serial ones). Solve times against the 30 ms sampling time are
// measured by humanoid_mpc_bench --closed-loop. A = 1: the robot with an arm (reaching).
template <int A = 0>
BasicClosedLoopRun<A> run(const Motion& m, MpcKind kind, double duration) {
  ClosedLoopConfig config;
  config.mpc = kind;
  config.duration = duration;
  config.truncate = false;
  return run_closed_loop<A>(m, config);
}

// The same, Coarse-Fast in the real robot's timing (kRealRobotTiming), cold-started as the
// thesis ran it (Sec. 2.7.3).
inline ClosedLoopRun run_in_real_robots_timing(const Motion& m, double duration) {
  ClosedLoopConfig config;
  config.timing = kRealRobotTiming;
  config.warm_start = false;
  config.truncate = false;
  config.duration = duration;
  return run_closed_loop(m, config);
}

}  // namespace hmpc::humanoid::test
