// The humanoid over its buses in one process, for tests: the HIL plant
// (hil/humanoid/hydraulic_humanoid.hpp), the two leg boards (firmware/app/humanoid_leg_board.hpp)
// and the host controller (hmpc/host/humanoid_host.hpp), every frame between them encoded and
// decoded as on the buses, one 1 ms tick at a time as the HIL's lock-step runs them: the plant
// sends each board its joints' readings and the IMU its 6 ms means, the boards tick, the host
// ticks, the plant steps under the boards' valve commands. No sockets, no guest: the whole
// chain at native speed, deterministic.
#pragma once

#include <array>
#include <memory>
#include <random>
#include <vector>

#include "hmpc/host/humanoid_host.hpp"
#include "hmpc/humanoid/hydraulic_legs.hpp"
#include "hmpc/humanoid/sensors.hpp"
#include "hmpc/humanoid/stance.hpp"
#include "humanoid_leg_board.hpp"
#include "hydraulic_humanoid.hpp"

namespace hmpc::test {

namespace hm = hmpc::humanoid;
namespace jp = hmpc::joint_protocol;

class HumanoidInProcess {
 public:
  // The IMU's frames' period (joint protocol), as the plant node sends them.
  static constexpr int kImuPeriodTicks = 6;
  using Board = firmware::JointBoard<double>;

  HumanoidInProcess(const host::HumanoidHostConfig& host_config, const hm::Motion& task,
                    double start_height = 0.85, const hil::HumanoidMismatch& mismatch = {})
      : start_(hm::standing_stance(hm::Parameters{}, start_height)),
        plant_(hm::Parameters{}, hm::ContactParameters{}, mismatch, start_),
        sensors_(plant_.model()), host_(host_config, task) {
    for (int b = 0; b < hm::kLegBoards; ++b) {
      Board::Config& c = board_config_[std::size_t(b)];
      c.node = jp::NodeId(b);
      std::array<double, hm::kJointsPerLeg> zero{};
      for (int j = 0; j < hm::kJointsPerLeg; ++j)
        zero[std::size_t(j)] = start_.q[7 + hm::joint_of(b, j)];
      firmware::configure_humanoid_leg(c, zero);
      boards_[std::size_t(b)] = std::make_unique<Board>(c);
    }
    sensors_.start_at_rest(start_.q);
    reading_ = sensors_.measure(start_.q, start_.v, hm::Velocity::Zero());
  }

  // One millisecond: the plant's readings to the boards and (every 6 ms) the IMU's to the host,
  // the boards' tick with their frames to the host, the host's tick with its frames to the
  // boards, then the plant's step under the valve commands.
  void tick() {
    truth_ = plant_.state();
    const auto tau = plant_.joint_torques();
    const auto actuators = plant_.actuators();
    for (int b = 0; b < hm::kLegBoards; ++b) {
      Board& board = *boards_[std::size_t(b)];
      for (int c = 0; c < hm::kJointsPerBoard; ++c) {
        const int j = hm::joint_of(b, c);
        board.on_joint_sensor(std::size_t(c), reading_.angles[j], reading_.rates[j], tau[j]);
        board.on_chamber_pressures(std::size_t(c), actuators[std::size_t(j)].pressure_a,
                                   actuators[std::size_t(j)].pressure_b);
      }
    }
    imu_angular_ += reading_.imu.angular_velocity;
    imu_force_ += reading_.imu.specific_force;
    if (++imu_samples_ == kImuPeriodTicks) {
      jp::ImuAngularVelocity gyro;
      jp::ImuLinearAcceleration accel;
      for (int i = 0; i < 3; ++i) {
        gyro.omega[std::size_t(i)] = float(imu_angular_[i] / kImuPeriodTicks);
        accel.specific_force[std::size_t(i)] = float(imu_force_[i] / kImuPeriodTicks);
      }
      jp::Frame f;
      if (!imu_silent_ && imu_.encode(gyro, f) == jp::EncodeResult::kOk) to_host(f);
      if (!imu_silent_ && imu_.encode(accel, f) == jp::EncodeResult::kOk) to_host(f);
      imu_angular_.setZero();
      imu_force_.setZero();
      imu_samples_ = 0;
    }
    hm::JointVector u;
    for (int b = 0; b < hm::kLegBoards; ++b) {
      Board& board = *boards_[std::size_t(b)];
      // A dead board sends nothing; its valve driver centres its valves.
      if (dead_[std::size_t(b)]) {
        for (int c = 0; c < hm::kJointsPerBoard; ++c) u[hm::joint_of(b, c)] = 0;
        continue;
      }
      board.tick();
      jp::Frame out;
      while (board.pop_frame(out)) to_host(out);
      for (int c = 0; c < hm::kJointsPerBoard; ++c) {
        u[hm::joint_of(b, c)] = board.valve_commands()[std::size_t(c)];
      }
    }
    if (!host_dead_) {
      host_.tick(tick_, true, [&](const jp::Frame& sent) {
        jp::Frame f = sent;
        if (!through_robot_bus(f)) return;
        for (int b = 0; b < hm::kLegBoards; ++b) {
          if (!dead_[std::size_t(b)]) boards_[std::size_t(b)]->on_frame(f);
        }
      });
    }
    plant_.step(u);
    const hm::BasicState<0> x = plant_.state();
    reading_ = sensors_.measure(x.q, x.v, plant_.acceleration());
    ++tick_;
  }
  // Faults. The IMU stops sending; board b dies (sends nothing, takes nothing, its valves
  // centred) or restarts (a fresh board: idle, its encoders not zeroed); the host dies (no
  // tick, no frame); of the robot bus's frames, `percent` are lost (seeded) or, until tick
  // `until`, every one is corrupted (a data byte flipped).
  void silence_imu() { imu_silent_ = true; }
  void kill_board(int b) { dead_[std::size_t(b)] = true; }
  void restart_board(int b) {
    boards_[std::size_t(b)] = std::make_unique<Board>(board_config_[std::size_t(b)]);
  }
  void kill_host() { host_dead_ = true; }
  void lose_frames(double percent, std::uint64_t seed) {
    loss_ = percent / 100;
    random_.seed(seed);
  }
  void corrupt_frames_until(std::uint32_t until) { corrupt_until_ = until; }
  std::uint64_t lost_frames() const { return lost_frames_; }
  std::uint64_t robot_bus_frames() const { return robot_bus_frames_; }

  // The host's MPC solves from the plant's truth (HumanoidHost::solve_from) from now on.
  void solve_from_truth() { host_.solve_from(&truth_); }

  void run(double seconds) {
    const std::uint32_t end = tick_ + std::uint32_t(seconds * 1e3 + 0.5);
    while (tick_ < end) tick();
  }

  const hm::BasicState<0>& start() const { return start_; }
  hil::SimbodyHydraulicHumanoid& plant() { return plant_; }
  host::HumanoidHost& host() { return host_; }
  const Board& board(int b) const { return *boards_[std::size_t(b)]; }
  std::uint32_t ticks() const { return tick_; }

 private:
  // A robot-bus frame on its way, lost or corrupted as the faults say; false: lost.
  bool through_robot_bus(jp::Frame& f) {
    ++robot_bus_frames_;
    if (loss_ > 0 && uniform_(random_) < loss_) {
      ++lost_frames_;
      return false;
    }
    if (tick_ < corrupt_until_ && f.dlc > 0) f.data[f.dlc - 1] ^= 0x5A;
    return true;
  }
  void to_host(const jp::Frame& sent) {
    jp::Frame f = sent;
    if (!host_dead_ && through_robot_bus(f)) host_.on_frame(f, tick_);
  }

  hm::BasicState<0> start_;
  hil::SimbodyHydraulicHumanoid plant_;
  hm::BasicState<0> truth_;
  hm::BipedSensors sensors_;
  hm::SensorReadings reading_;
  std::array<Board::Config, hm::kLegBoards> board_config_{};
  std::array<std::unique_ptr<Board>, hm::kLegBoards> boards_;
  std::array<bool, hm::kLegBoards> dead_{};
  bool imu_silent_ = false, host_dead_ = false;
  double loss_ = 0;
  std::uint32_t corrupt_until_ = 0;
  std::uint64_t lost_frames_ = 0, robot_bus_frames_ = 0;
  std::mt19937_64 random_{1};
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
  host::HumanoidHost host_;
  jp::Sender imu_{jp::NodeId(hm::kImuNode)};
  hm::Vector3 imu_angular_ = hm::Vector3::Zero(), imu_force_ = hm::Vector3::Zero();
  int imu_samples_ = 0;
  std::uint32_t tick_ = 0;
};

}  // namespace hmpc::test
