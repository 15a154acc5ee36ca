// The humanoid over CAN: hmpc-humanoid-plant (the Simbody humanoid with hydraulic legs on the
// I/O bus vcan1, its IMU on the robot bus vcan0), the two leg boards (hmpc-joint-board
// --humanoid-leg) and the host (hmpc-humanoid-host) as separate programs in lock-step, through
// the vcan launcher: the host brings the robot up, the boards zero and hold it, the MPC takes
// over; the logs the host writes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "hmpc/humanoid/hydraulic_legs.hpp"
#include "hmpc/humanoid/stance.hpp"
#include "hmpc/platform/linux/candump_log.hpp"
#include "hmpc/platform/linux/child_process.hpp"

namespace {

namespace hm = hmpc::humanoid;
using hmpc::platform::Child;
using Summary = std::map<std::string, std::string>;

// Lock-step runs take what the guest needs for the plant, the boards and the host's solves:
// about 15 s per simulated second in a QEMU guest without KVM, twice that as a margin.
constexpr double kWallPerSimulatedS = 30;

double number(const Summary& s, const std::string& key) {
  const auto it = s.find(key);
  return it == s.end() ? NAN : std::strtod(it->second.c_str(), nullptr);
}

struct HilRun {
  bool ok = false;
  std::string error, dir;
  Summary plant, host;
  std::vector<Summary> boards;
};

// The boards zero their encoders in the plant's starting stance.
std::string zero_posture(int board) {
  const hm::BasicState<0> start = hm::standing_stance(hm::Parameters{}, 0.85);
  std::string out;
  for (int c = 0; c < hm::kJointsPerBoard; ++c) {
    out += (c ? "," : "") + std::to_string(start.q[7 + hm::joint_of(board, c)]);
  }
  return out;
}

HilRun run(const std::string& name, std::vector<std::string> host_args, double duration_s) {
  HilRun r;
  const char* tmp = std::getenv("TMPDIR");
  r.dir = std::string(tmp ? tmp : "/tmp") + "/hmpc-humanoid-hil-test/" + name + "/";
  std::filesystem::remove_all(r.dir);
  std::filesystem::create_directories(r.dir);
  std::vector<Child> boards(hm::kLegBoards);
  for (int b = 0; b < hm::kLegBoards; ++b) {
    const std::vector<std::string> args{
        "--lockstep", "--interface",     "vcan0",          "--io-interface", "vcan1",
        "--node",     std::to_string(b), "--humanoid-leg", "--zero-posture", zero_posture(b)};
    if (!boards[std::size_t(b)].start(HMPC_JOINT_BOARD_PROGRAM, args,
                                      r.dir + "board" + std::to_string(b) + ".out", r.error) ||
        !boards[std::size_t(b)].await_output(": ready", 30)) {
      r.error = "board " + std::to_string(b) + " did not start: " + r.error;
      return r;
    }
  }
  host_args.insert(host_args.begin(),
                   {"--lockstep", "--io-interface", "vcan1", "--duration",
                    std::to_string(duration_s), "--solve-time", "model", "--log-dir", r.dir});
  Child host, plant;
  if (!host.start(HMPC_HUMANOID_HOST_PROGRAM, host_args, r.dir + "host.out", r.error) ||
      !host.await_output(": ready", 60)) {
    r.error = "the host did not start: " + r.error + host.errors();
    return r;
  }
  if (!plant.start(HMPC_HUMANOID_PLANT_PROGRAM,
                   {"--lockstep", "--wait-host", "--duration", std::to_string(duration_s), "--log",
                    r.dir + "plant.csv"},
                   r.dir + "plant.out", r.error)) {
    return r;
  }
  const int plant_status = plant.wait(60 + kWallPerSimulatedS * duration_s);
  const int host_status = host.wait(60);
  int board_status = 0;
  for (Child& b : boards) board_status |= b.stop(10);
  r.plant = hmpc::platform::parse_summary(plant.output());
  r.host = hmpc::platform::parse_summary(host.output());
  for (const Child& b : boards) r.boards.push_back(hmpc::platform::parse_summary(b.output()));
  if (plant_status != 0 || host_status != 0 || board_status != 0) {
    r.error = "exit status plant " + std::to_string(plant_status) + ", host " +
              std::to_string(host_status) + ", boards " + std::to_string(board_status) +
              "; plant said: " + plant.errors() + " host said: " + host.errors();
    return r;
  }
  r.ok = true;
  return r;
}

// Bring-up, 1 s of the boards' hold, then the MPC (hip-hold) on the estimate from the bus until
// 2 s: the robot brought up (both boards and the IMU heard, encoders zeroed), held upright, then
// run by the MPC's torque references with both boards in run; every frame valid; both buses
// logged.
TEST(HumanoidHil, BringsUpHoldsAndHandsOverToTheMpcOverCan) {
  constexpr double kSeconds = 2.0;
  const HilRun r = run("hold-then-mpc", {"--hold-seconds", "1.0"}, kSeconds);
  ASSERT_TRUE(r.ok) << r.error;
  std::printf(
      "plant: %.1f s simulated in %.1f s of wall time; lowest torso %.3f m, tilt up to "
      "%.3f rad; host: %g solves, largest charged %.2f ms, largest delay %g ticks\n",
      number(r.plant, "sim_seconds"), number(r.plant, "wall_seconds"),
      number(r.plant, "min_height"), number(r.plant, "max_tilt"), number(r.host, "solves"),
      number(r.host, "largest_solve_ms"), number(r.host, "largest_delay_ticks"));
  EXPECT_EQ(r.host.at("phase"), "mpc");
  EXPECT_EQ(r.host.at("board0_mode"), "run");
  EXPECT_EQ(r.host.at("board1_mode"), "run");
  EXPECT_EQ(number(r.host, "rejected_frames"), 0);
  // When the MPC took over (the host's estimate log, a row every 6 ms), and from then on one
  // solve every 12 ms.
  const std::string estimate = hmpc::platform::read_file(r.dir + "estimate.csv");
  const std::size_t mpc_row = estimate.find(",mpc,");
  ASSERT_NE(mpc_row, std::string::npos);
  const double mpc_start =
      std::strtod(estimate.c_str() + estimate.rfind('\n', mpc_row) + 1, nullptr);
  std::printf("the MPC took over at %.3f s\n", mpc_start);
  EXPECT_LT(mpc_start, kSeconds - 0.2);
  const double expected_solves = (kSeconds - mpc_start) / 0.012;
  EXPECT_NEAR(number(r.host, "solves"), expected_solves, 2);
  for (const Summary& b : r.boards) {
    EXPECT_EQ(number(b, "heap_allocations_in_loop"), 0);
    EXPECT_EQ(number(b, "rejected_frames"), 0);
    EXPECT_EQ(b.at("mode"), "run");
  }
  EXPECT_EQ(number(r.plant, "board_waits_timed_out"), 0);
  EXPECT_EQ(number(r.plant, "rejected_frames"), 0);
  // Upright: the torso within 0.1 rad of vertical, its origin within 3 cm of its standing height.
  EXPECT_LT(number(r.plant, "max_tilt"), 0.1);
  EXPECT_GT(number(r.plant, "min_height"), 0.78 - 0.03);

  // The robot bus's log holds the host's heartbeats, the boards' joint states and the IMU's
  // frames, each a valid candump line; the I/O bus's the Syncs.
  std::istringstream robot_log(hmpc::platform::read_file(r.dir + "robot_bus.log"));
  std::map<std::uint32_t, int> ids;
  std::string line, interface;
  int lines = 0;
  while (std::getline(robot_log, line)) {
    double t = 0;
    hmpc::platform::CanFrame f{};
    ASSERT_TRUE(hmpc::platform::read_candump_line(line, t, interface, f)) << line;
    ++ids[f.id];
    ++lines;
  }
  // Board 0's ModeCommand every 10 ms, board 1's JointState0 and the IMU's gyroscope every
  // 6 ms, over the run but for the start; board 1's torque references every 6 ms under the MPC.
  EXPECT_GT(ids[0x200], 0.9 * kSeconds / 0.010);
  EXPECT_GT(ids[0x225], 0.9 * kSeconds / 0.006);
  EXPECT_GT(ids[0x242], 0.9 * kSeconds / 0.006);
  EXPECT_GT(ids[0x221], 0.9 * (kSeconds - mpc_start) / 0.006);
  const std::string io_log = hmpc::platform::read_file(r.dir + "io_bus.log");
  EXPECT_NE(io_log.find(" vcan1 081#"), std::string::npos);
}

}  // namespace
