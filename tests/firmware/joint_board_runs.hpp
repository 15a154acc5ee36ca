// The hydraulic joint board application on the target, driving 4 joints: boot, zeroing, hold,
// then torque references (a 2 Hz, 20 N·m sinusoid, phase-shifted per joint) streamed as CAN frames
// with the host's heartbeat, and a plant inside the image (per joint the hydraulic actuator
// swinging a hanging leg, models/hydraulic_pendulum.hpp, RK4 at 50 us) answering every tick with
// the I/O frames. One "update" is one 6 ms control period: the tick that runs the four torque
// loops, timed from frame handling to the frames it queues. The board has no solver: its
// updates carry no solver work, and each counts as one iteration.
#pragma once

#include <Eigen/Dense>
#include <array>
#include <cmath>

#include "closed_loop_check.hpp"
#include "hmpc/constants.hpp"
#include "hmpc/models/hydraulic_pendulum.hpp"
#include "hmpc/mpc/compute_model.hpp"
#include "joint_board.hpp"

namespace hmpc::closed_loop_check {

constexpr int kSamples = 100;  // control periods in run: 600 ms

template <typename Scalar>
const ComputeCostModel* compute_model_to_verify() {
  return nullptr;  // no solver
}

template <typename Scalar>
struct JointBoardStorage {
  static inline firmware::JointBoard<Scalar> board{firmware::JointBoardConfig<Scalar>{}};
};

// What Counting asks of the controller it times.
struct JointBoardUpdate {
  int last_iterations() const { return 1; }
  bool last_plan_usable() const { return true; }
  LayerWork last_work() const { return {}; }
};

template <typename Scalar>
float to_sensor_mpa(Scalar pascal) {  // the pressure sensors' 0..32 MPa, saturating
  const Scalar mpa = pascal * Scalar(1e-6);
  return float(mpa < Scalar(0) ? Scalar(0) : (mpa > Scalar(32) ? Scalar(32) : mpa));
}

template <typename Scalar, class Observer, class Report>
void run_all(Observer& observer, Report& report) {
  namespace proto = joint_protocol;
  constexpr std::size_t kJoints = proto::kMaxJointsPerBoard;
  auto& board = JointBoardStorage<Scalar>::board;
  proto::Sender host(0), plant_bus(0);
  const hydraulic::JointActuatorParameters<Scalar> actuator{};
  const auto load = hydraulic::PendulumLoad<Scalar>::leg();
  std::array<hydraulic::PendulumState<Scalar>, kJoints> plant{};
  plant.fill(hydraulic::torque_free_rest(actuator));
  const auto torque = [&](std::size_t j) {
    return hydraulic::joint_torque(actuator, plant[j].actuator, plant[j].omega);
  };
  Counting<Observer> counting{observer};
  const JointBoardUpdate update{};
  Scalar cost = 0;
  int updates = 0;
  const auto reference = [](std::size_t joint, double t) {
    return float(20.0 * std::sin(2.0 * kPi<double> * 2.0 * t + 0.5 * double(joint)));
  };

  constexpr int kZeroTick = 20, kHoldStart = 40, kRunStart = 140;
  for (int tick = 0; updates < kSamples; ++tick) {
    const double t = tick * 1e-3;
    proto::Frame f;
    if (tick % 10 == 0) {
      proto::ModeCommand m;
      m.mode = tick >= kRunStart    ? proto::RequestedMode::kRun
               : tick >= kHoldStart ? proto::RequestedMode::kHold
                                    : proto::RequestedMode::kIdle;
      m.zero_encoders = tick == kZeroTick;
      m.host_time_us = static_cast<std::uint32_t>(tick) * 1000u;
      if (host.encode(m, f) == proto::EncodeResult::kOk) board.on_frame(f);
    }
    if (tick % 6 == 0 && tick >= kRunStart - 12) {
      proto::TorqueReference r;
      for (std::size_t j = 0; j < kJoints; ++j) r.tau[j] = reference(j, t);
      if (host.encode(r, f) == proto::EncodeResult::kOk) board.on_frame(f);
    }
    const auto send_sensor = [&](const auto& message) {
      if (plant_bus.encode(message, f) == proto::EncodeResult::kOk) board.on_frame(f);
    };
    const auto sensor = [&](std::size_t j) {
      return std::array<float, 3>{float(plant[j].theta), float(plant[j].omega), float(torque(j))};
    };
    const auto s0 = sensor(0), s1 = sensor(1), s2 = sensor(2), s3 = sensor(3);
    send_sensor(proto::JointSensor<0>{s0[0], s0[1], s0[2], 0});
    send_sensor(proto::JointSensor<1>{s1[0], s1[1], s1[2], 0});
    send_sensor(proto::JointSensor<2>{s2[0], s2[1], s2[2], 0});
    send_sensor(proto::JointSensor<3>{s3[0], s3[1], s3[2], 0});
    proto::ChamberPressures01 p01;
    proto::ChamberPressures23 p23;
    for (std::size_t i = 0; i < 2; ++i) {
      p01.p_a[i] = to_sensor_mpa(plant[i].actuator.pressure_a);
      p01.p_b[i] = to_sensor_mpa(plant[i].actuator.pressure_b);
      p23.p_a[i] = to_sensor_mpa(plant[2 + i].actuator.pressure_a);
      p23.p_b[i] = to_sensor_mpa(plant[2 + i].actuator.pressure_b);
    }
    send_sensor(p01);
    send_sensor(p23);

    const bool control_tick = tick >= kRunStart && (tick + 1) % 6 == 0;
    if (control_tick) counting.before_update(updates);
    board.tick();
    std::array<Scalar, kJoints> u{};
    while (board.pop_frame(f)) {
      proto::ValveDrive drive;
      if (proto::decode(f, 0, drive) == proto::DecodeResult::kOk) {
        for (std::size_t j = 0; j < kJoints; ++j) u[j] = Scalar(drive.u[j]);
      }
    }
    if (control_tick) {
      Eigen::Matrix<Scalar, 8, 1> x;
      Eigen::Matrix<Scalar, kJoints, 1> valves;
      for (std::size_t j = 0; j < kJoints; ++j) {
        x(Eigen::Index(2 * j)) = plant[j].theta;
        x(Eigen::Index(2 * j + 1)) = torque(j);
        valves(Eigen::Index(j)) = u[j];
        const Scalar error = Scalar(reference(j, t)) - torque(j);
        cost += error * error;
      }
      counting.after_update(updates, x, valves, update);
      ++updates;
    }
    for (std::size_t j = 0; j < kJoints; ++j) {
      hydraulic::step_pendulum(actuator, load, plant[j], u[j], Scalar(1e-3), 20);
    }
  }
  Eigen::Matrix<Scalar, 8, 1> final_state;
  for (std::size_t j = 0; j < kJoints; ++j) {
    final_state(Eigen::Index(2 * j)) = plant[j].theta;
    final_state(Eigen::Index(2 * j + 1)) = torque(j);
  }
  // Run reached, and the loops followed: the mean squared torque error stays under the
  // references' own (200 N·m^2 for a 20 N·m amplitude), or the image fails.
  const bool running = board.mode() == proto::BoardMode::kRun;
  report.method("joint-board-4-joints", final_state,
                running && cost < Scalar(200) * kSamples * kJoints ? cost : Scalar(NAN),
                counting.totals);
}

}  // namespace hmpc::closed_loop_check
