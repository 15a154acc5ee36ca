// Replaying a lock-step robot bus log into the humanoid host (hmpc/host/humanoid_replay.hpp):
// a host's own run replays with every sent frame the same; a frame changed or missing in the
// log is found on its tick; a log that is not one is refused. (A whole run over vcan, frames
// heard included, replays bit for bit in humanoid_over_can.)
#include "hmpc/host/humanoid_replay.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <sstream>
#include <string>

#include "hmpc/humanoid/motion.hpp"
#include "hmpc/platform/linux/candump_log.hpp"
#include "hmpc/platform/linux/protocol_frames.hpp"

namespace {

using hmpc::host::HumanoidHost;
using hmpc::host::ReplayReport;
namespace jp = hmpc::joint_protocol;

hmpc::humanoid::Motion hip_hold() {
  return hmpc::humanoid::load_motion(std::string(HMPC_HUMANOID_MOTIONS) + "/hip-hold.motion");
}

// A candump -l line as the host's log has it, stamped with `tick`.
std::string line(std::uint32_t tick, const jp::Frame& f) {
  char frame[32], text[64];
  hmpc::platform::format_candump_frame(hmpc::platform::to_can_frame(f), frame);
  std::snprintf(text, sizeof text, "(%010u.%06u) vcan0 %s\n", tick / 1000, (tick % 1000) * 1000,
                frame);
  return text;
}

// 300 ticks of a host waiting for its boards: what it sends, as its log has it.
std::string waiting_run() {
  HumanoidHost host(hmpc::host::HumanoidHostConfig{}, hip_hold());
  std::string log;
  for (std::uint32_t tick = 0; tick < 300; ++tick) {
    host.tick(tick, true, [&](const jp::Frame& f) { log += line(tick, f); });
  }
  return log;
}

// `log` replayed into a fresh host, which must take it.
void replay(const std::string& log, ReplayReport& r) {
  HumanoidHost host(hmpc::host::HumanoidHostConfig{}, hip_hold());
  std::istringstream in(log);
  std::string error;
  ASSERT_TRUE(hmpc::host::replay_lockstep_log(in, host, r, error)) << error;
}

TEST(HumanoidReplay, AHostsOwnRunReplaysFrameForFrame) {
  ReplayReport r;
  ASSERT_NO_FATAL_FAILURE(replay(waiting_run(), r));
  EXPECT_GT(r.logged_sent, 20u);  // heartbeats to both boards every 10 ms
  EXPECT_EQ(r.sent, r.logged_sent);
  EXPECT_EQ(r.mismatches, 0u) << r.first_mismatch;
  EXPECT_EQ(r.skipped_lines, 0u);
}

TEST(HumanoidReplay, AChangedOrMissingFrameIsFoundOnItsTick) {
  std::string log = waiting_run();
  // The first heartbeat of tick 0.150 with its last data byte changed.
  const std::size_t at = log.find("(0000000000.150000) vcan0 ");
  ASSERT_NE(at, std::string::npos);
  const std::size_t end = log.find('\n', at);
  log[end - 1] = log[end - 1] == '0' ? '1' : '0';
  ReplayReport changed;
  ASSERT_NO_FATAL_FAILURE(replay(log, changed));
  EXPECT_EQ(changed.mismatches, 1u);
  EXPECT_EQ(changed.first_mismatch_tick, 150u);
  log.erase(at, end - at + 1);  // that frame gone from the log
  ReplayReport missing;
  ASSERT_NO_FATAL_FAILURE(replay(log, missing));
  EXPECT_GE(missing.mismatches, 1u);
  EXPECT_EQ(missing.first_mismatch_tick, 150u);
}

TEST(HumanoidReplay, ALogThatIsNotOneIsRefused) {
  HumanoidHost host(hmpc::host::HumanoidHostConfig{}, hip_hold());
  ReplayReport r;
  std::string error;
  std::istringstream garbage("not a candump line\n\n(12) vcan0 zz#\n");
  EXPECT_FALSE(hmpc::host::replay_lockstep_log(garbage, host, r, error));
  EXPECT_EQ(error, "the log holds no frame");
  EXPECT_EQ(r.skipped_lines, 3u);
  std::istringstream backwards(
      "(0000000000.010000) vcan0 200#0000000000000000\n"
      "(0000000000.009000) vcan0 200#0000000000000000\n");
  EXPECT_FALSE(hmpc::host::replay_lockstep_log(backwards, host, r, error));
  EXPECT_NE(error.find("backwards"), std::string::npos);
}

}  // namespace
