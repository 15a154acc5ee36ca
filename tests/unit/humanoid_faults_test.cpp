// The humanoid's faults end to end in one process (humanoid_in_process.hpp: plant, boards and
// host, every frame encoded as on the buses): for each, the defined reaction, how many ticks
// (1 ms) it took, and whether the robot stayed up. The MPC solves from the plant's truth here,
// so that what is measured is the reaction to the fault, not the estimate's hold.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "hmpc/humanoid/motion.hpp"
#include "humanoid_in_process.hpp"

namespace {

namespace hm = hmpc::humanoid;
namespace jp = hmpc::joint_protocol;
using hmpc::host::HostPhase;
using hmpc::test::HumanoidInProcess;

hmpc::host::HumanoidHostConfig config() {
  hmpc::host::HumanoidHostConfig c;
  c.hold_seconds = 1.0;
  c.solve_time = hmpc::host::SolveTime::kModel;  // the same run on any machine
  return c;
}

hm::Motion hip_hold() {
  return hm::load_motion(std::string(HMPC_HUMANOID_MOTIONS) + "/hip-hold.motion");
}

double tilt(const hm::BasicState<0>& x) {
  const Eigen::Quaterniond q(x.q[3], x.q[4], x.q[5], x.q[6]);
  return std::acos(std::min(1.0, (q.normalized() * hm::Vector3::UnitZ()).z()));
}

// The robot under the MPC, 0.3 s after its take-over.
void run_to_mpc(HumanoidInProcess& robot) {
  robot.solve_from_truth();
  robot.run(1.0);
  while (robot.host().phase() != HostPhase::kMpc && robot.ticks() < 3000) robot.tick();
  ASSERT_EQ(robot.host().phase(), HostPhase::kMpc) << robot.host().reason();
  robot.run(0.3);
}

// Ticks until `done` holds, at most `limit`; limit + 1 if it never did.
template <class Done>
std::uint32_t ticks_until(HumanoidInProcess& robot, std::uint32_t limit, Done&& done) {
  for (std::uint32_t k = 0; k <= limit; ++k) {
    if (done()) return k;
    robot.tick();
  }
  return limit + 1;
}

// Ticks until the host is in its safe phase, at most `limit`; limit + 1 if it never was.
std::uint32_t ticks_to_safe(HumanoidInProcess& robot, std::uint32_t limit) {
  return ticks_until(robot, limit, [&] { return robot.host().phase() == HostPhase::kSafe; });
}

// Ticks until both boards are in `mode`, at most `limit`; limit + 1 if they never were.
std::uint32_t ticks_to_both_in(HumanoidInProcess& robot, std::uint32_t limit, jp::BoardMode mode) {
  return ticks_until(
      robot, limit, [&] { return robot.board(0).mode() == mode && robot.board(1).mode() == mode; });
}

// The host's loop dies (SIGKILL): no reference, no heartbeat. Each board stops acting on the
// last torques once they are stale (four 6 ms control periods) and holds its posture; then its
// heartbeat watchdog (seven 10 ms heartbeat periods) trips and latches its safe state, valves
// centred, which lock the joints hydraulically.
TEST(HumanoidFaults, TheHostDyingHasEveryBoardHoldThenCentreItsValves) {
  HumanoidInProcess robot(config(), hip_hold());
  run_to_mpc(robot);
  robot.kill_host();
  const auto& board = robot.board(0).config();
  const int stale = board.reference_timeout_periods * board.control_period_ticks;
  const std::uint32_t held = ticks_to_both_in(robot, 200, jp::BoardMode::kHold);
  // The last reference came at most one control period before the death, and a board looks
  // at its age once per control period.
  EXPECT_LE(held, std::uint32_t(stale + board.control_period_ticks + 1));
  EXPECT_GE(held + std::uint32_t(board.control_period_ticks), std::uint32_t(stale));
  const std::uint32_t safe = held + ticks_to_both_in(robot, 200, jp::BoardMode::kFault);
  std::printf(
      "host killed: both boards hold after %u ticks (references stale after %d), safe after %u "
      "(heartbeat timeout %d); tilt %.3f rad\n",
      held, stale, safe, board.heartbeat_timeout_ticks, tilt(robot.plant().state()));
  // The last heartbeat came up to one period (10 ticks) before the death.
  EXPECT_LE(safe, std::uint32_t(board.heartbeat_timeout_ticks + 1));
  EXPECT_GE(safe + 10, std::uint32_t(board.heartbeat_timeout_ticks));
  for (int b = 0; b < hm::kLegBoards; ++b) {
    EXPECT_NE(robot.board(b).faults() & jp::fault::kHeartbeatTimeout, 0);
    for (int c = 0; c < hm::kJointsPerBoard; ++c) {
      EXPECT_EQ(robot.board(b).valve_commands()[std::size_t(c)], 0.0);
    }
  }
}

// The IMU stops: the host's master forgets it after 30 ticks (five of its 6 ms frames), the
// host stops the MPC and has the boards hold their posture: the robot stays up.
TEST(HumanoidFaults, TheImuFallingSilentHandsTheRobotToTheBoardsHold) {
  HumanoidInProcess robot(config(), hip_hold());
  run_to_mpc(robot);
  robot.silence_imu();
  const std::uint32_t silenced = robot.ticks();
  const std::uint32_t took = ticks_to_safe(robot, 200);
  EXPECT_EQ(robot.host().reason(), "the IMU fell silent");
  const int timeout = robot.host().master().config().imu_timeout_ticks;
  EXPECT_LE(took, std::uint32_t(timeout + 1));
  EXPECT_GE(took + 6, std::uint32_t(timeout));
  const std::uint32_t held = ticks_to_both_in(robot, 50, jp::BoardMode::kHold);
  EXPECT_LE(held, 11u);  // the next heartbeat (10 ms) asks for hold
  robot.run(2.0);
  const double up = tilt(robot.plant().state());
  std::printf(
      "IMU silent: host safe after %u ticks, boards in hold %u ticks later; tilt after 2 s of "
      "hold %.3f rad\n",
      robot.host().safe_tick() - silenced, held, up);
  EXPECT_LT(up, 0.1);
}

// A leg board dies: the host's master forgets it once its BoardStatus (20 ms) has not come for
// more than its timeout (100 ticks), the host stops the MPC on its next tick and has the other
// board hold; the dead board's valve driver centres its valves.
TEST(HumanoidFaults, ABoardFallingSilentHandsTheOtherToItsHold) {
  HumanoidInProcess robot(config(), hip_hold());
  run_to_mpc(robot);
  robot.kill_board(1);
  const std::uint32_t killed = robot.ticks();
  const std::uint32_t took = ticks_to_safe(robot, 300);
  EXPECT_EQ(robot.host().reason(), "a leg board fell silent");
  const int timeout = robot.host().master().config().board_timeout_ticks;
  EXPECT_LE(took, std::uint32_t(timeout + 2));
  EXPECT_GE(took + 20, std::uint32_t(timeout));
  robot.run(0.02);
  EXPECT_EQ(robot.board(0).mode(), jp::BoardMode::kHold);
  robot.run(1.0);
  std::printf("board 1 dead: host safe after %u ticks; tilt 1 s later %.3f rad\n",
              robot.host().safe_tick() - killed, tilt(robot.plant().state()));
}

// A leg board restarts: it comes back idle, its encoders not zeroed, and faults for the hold or
// run it is asked (a board never acts on unzeroed encoders). Its frames' rolling counters start
// again at 0: the host's receiver takes them at once if they fall within 7 ahead of the last it
// accepted, else after three running on; so the host sees the restart within three of the
// board's BoardStatus frames, stops the MPC and has the other board hold.
TEST(HumanoidFaults, ARestartedBoardStopsTheMpcAndTheOtherHolds) {
  HumanoidInProcess robot(config(), hip_hold());
  run_to_mpc(robot);
  robot.restart_board(0);
  const std::uint32_t restarted = robot.ticks();
  const int timeout = robot.host().master().config().board_timeout_ticks;
  const std::uint32_t took = ticks_to_safe(robot, std::uint32_t(timeout + 2));
  const std::string reason = robot.host().reason();
  EXPECT_EQ(reason, "a leg board restarted: its encoders are not zeroed");
  // Its counters start again from 0: at worst stale until three of its BoardStatus frames
  // (every 20 ms) run on (CounterTracker), before the silence's timeout.
  const auto status_period =
      std::uint32_t(jp::frame_spec(jp::FrameType::kBoardStatus).cycle_time_ms);
  EXPECT_LE(took, 3 * status_period + 2);
  EXPECT_LT(took, std::uint32_t(timeout));
  robot.run(0.02);
  EXPECT_FALSE(robot.board(0).zeroed());
  EXPECT_NE(robot.board(0).mode(), jp::BoardMode::kHold);
  EXPECT_NE(robot.board(0).mode(), jp::BoardMode::kRun);
  EXPECT_EQ(robot.board(1).mode(), jp::BoardMode::kHold);
  std::printf("board 0 restarted: host safe after %u ticks (%s)\n",
              robot.host().safe_tick() - restarted, reason.c_str());
}

// A burst of corrupted frames on the robot bus (every frame for 15 ms, a data byte flipped):
// every one is rejected by its receiver's checksum and counted, none is acted on; the boards'
// watchdogs (heartbeat 70 ms, references four 6 ms periods) outlast the burst, so the MPC
// rides through.
TEST(HumanoidFaults, ABurstOfCorruptedFramesIsRejectedAndRiddenThrough) {
  HumanoidInProcess robot(config(), hip_hold());
  run_to_mpc(robot);
  const std::uint64_t rejected_before = robot.host().master().rejected_frames();
  robot.corrupt_frames_until(robot.ticks() + 15);
  robot.run(1.0);
  EXPECT_GT(robot.host().master().rejected_frames(), rejected_before);
  EXPECT_EQ(robot.host().phase(), HostPhase::kMpc) << robot.host().reason();
  for (int b = 0; b < hm::kLegBoards; ++b) {
    EXPECT_EQ(robot.board(b).mode(), jp::BoardMode::kRun);
    EXPECT_GT(robot.host().master().board(b).status.rejected_frames, 0);  // as it reports
  }
  EXPECT_LT(tilt(robot.plant().state()), 0.1);
}

// A tenth of the robot bus's frames lost, at random, for 10 s under the MPC: the boards'
// watchdogs outlast the losses in a row (the IMU's 6 ms means and the joints' frames lost are
// skipped by the host), so it rides through: no board trips, the MPC keeps control, the robot
// stays up.
TEST(HumanoidFaults, ATenthOfTheRobotBusLostIsRiddenThrough) {
  HumanoidInProcess robot(config(), hip_hold());
  run_to_mpc(robot);
  robot.lose_frames(10, 7);
  const std::uint64_t frames_before = robot.robot_bus_frames();
  double worst_tilt = 0;
  for (int k = 0; k < 10000; ++k) {
    robot.tick();
    worst_tilt = std::max(worst_tilt, tilt(robot.plant().state()));
  }
  std::printf("a tenth lost for 10 s: %llu frames lost, stale references %u/%u, tilt up to %.3f\n",
              static_cast<unsigned long long>(robot.lost_frames()),
              robot.board(0).counters().stale_references,
              robot.board(1).counters().stale_references, worst_tilt);
  const double lost =
      double(robot.lost_frames()) / double(robot.robot_bus_frames() - frames_before);
  EXPECT_NEAR(lost, 0.1, 0.01);
  EXPECT_EQ(robot.host().phase(), HostPhase::kMpc) << robot.host().reason();
  for (int b = 0; b < hm::kLegBoards; ++b) {
    EXPECT_EQ(robot.board(b).counters().watchdog_trips, 0u);
    EXPECT_EQ(robot.board(b).faults() & ~jp::fault::kStaleReference, 0);
  }
  EXPECT_LT(worst_tilt, 0.1);
}

}  // namespace
