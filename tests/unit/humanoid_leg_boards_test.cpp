// The humanoid's two leg boards (firmware/app/humanoid_leg_board.hpp) on the HIL plant
// (hil/humanoid/hydraulic_humanoid.hpp), in one process: the boards' frames passed as the
// buses would, a host's heartbeats zeroing the encoders and asking for hold.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include "hmpc/humanoid/hydraulic_legs.hpp"
#include "hmpc/humanoid/sensors.hpp"
#include "hmpc/humanoid/stance.hpp"
#include "humanoid_leg_board.hpp"
#include "hydraulic_humanoid.hpp"

namespace {

namespace hm = hmpc::humanoid;
namespace jp = hmpc::joint_protocol;
using Board = hmpc::firmware::JointBoard<double>;

struct Rig {
  hm::BasicState<0> start = hm::standing_stance(hm::Parameters{}, 0.85);
  hmpc::hil::SimbodyHydraulicHumanoid plant{hm::Parameters{}, hm::ContactParameters{}, {}, start};
  std::array<std::unique_ptr<Board>, 2> boards;
  jp::Sender host[2] = {jp::Sender(0), jp::Sender(1)};

  Rig() {
    for (int b = 0; b < 2; ++b) {
      Board::Config c;
      c.node = jp::NodeId(b);
      std::array<double, 4> zero{};
      for (int j = 0; j < 4; ++j) zero[std::size_t(j)] = start.q[7 + hm::joint_of(b, j)];
      hmpc::firmware::configure_humanoid_leg(c, zero);
      boards[std::size_t(b)] = std::make_unique<Board>(c);
    }
  }

  void tick(int k, jp::RequestedMode mode, bool zero) {
    const auto x = plant.state();
    const auto tau = plant.joint_torques();
    const auto act = plant.actuators();
    hm::JointVector u;
    for (int b = 0; b < 2; ++b) {
      Board& board = *boards[std::size_t(b)];
      if (k % 10 == 0) {
        jp::ModeCommand m;
        m.mode = mode;
        m.zero_encoders = zero;
        m.host_time_us = std::uint32_t(k) * 1000u;
        jp::Frame f;
        host[b].encode(m, f);
        board.on_frame(f);
      }
      for (int c = 0; c < 4; ++c) {
        const int j = hm::joint_of(b, c);
        board.on_joint_sensor(std::size_t(c), x.q[7 + j], x.v[6 + j], tau[j]);
        board.on_chamber_pressures(std::size_t(c), act[std::size_t(j)].pressure_a,
                                   act[std::size_t(j)].pressure_b);
      }
      board.tick();
      jp::Frame out;
      while (board.pop_frame(out)) {
      }
      for (int c = 0; c < 4; ++c) u[hm::joint_of(b, c)] = board.valve_commands()[std::size_t(c)];
    }
    plant.step(u);
  }
};

// Sec. 2.7.3: "the robot first holds its posture" under the boards' PID, for the thesis's 10 s:
// zeroed in its standing posture, the torso stays within 0.05 rad (3 degrees) of upright and
// the hip within 2 cm of where it stood, the boards in hold without a fault.
TEST(HumanoidLegBoards, HoldTheRobotStandingForTenSeconds) {
  Rig rig;
  int k = 0;
  for (; k < 100; ++k) rig.tick(k, jp::RequestedMode::kIdle, k == 50);
  for (const auto& board : rig.boards) ASSERT_TRUE(board->zeroed());
  double tilt = 0, drift = 0;
  for (; k < 10100; ++k) {
    rig.tick(k, jp::RequestedMode::kHold, false);
    const auto x = rig.plant.state();
    const Eigen::Quaterniond attitude(x.q[3], x.q[4], x.q[5], x.q[6]);
    tilt = std::max(tilt,
                    std::acos(std::min(1.0, (attitude.normalized() * hm::Vector3::UnitZ()).z())));
    drift = std::max(drift, (x.q.head<2>() - rig.start.q.head<2>()).norm());
  }
  std::printf("largest tilt %.4f rad, hip drift %.4f m over 10 s of hold\n", tilt, drift);
  EXPECT_LT(tilt, 0.05);
  EXPECT_LT(drift, 0.02);
  for (const auto& board : rig.boards) {
    EXPECT_EQ(board->mode(), jp::BoardMode::kHold);
    EXPECT_EQ(board->faults(), 0);
  }
}

}  // namespace
