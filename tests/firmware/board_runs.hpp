// The forearm board application on the target: boot, hold, then 1 s of two-stage MPC tracking
// a 1 Hz, +-30 deg trajectory streamed as CAN frames, with the host's heartbeat and a model
// plant (RK4, 1 ms) answering every actuator frame with a sensor frame, all inside the image.
// One "update" is one MPC step (every 4 ms).
#pragma once

#include <cmath>

#include "closed_loop_check.hpp"
#include "forearm_board.hpp"
#include "hmpc/constants.hpp"

namespace hmpc::closed_loop_check {

constexpr int kSamples = 250;

template <typename Scalar>
const ComputeCostModel* compute_model_to_verify() {
  return nullptr;  // the compute model covers the MPC alone, checked by forearm_runs.hpp
}

template <typename Scalar>
struct BoardStorage {
  static inline firmware::ForearmBoard<Scalar> board{firmware::BoardConfig<Scalar>{}};
};

template <typename Scalar, class Observer, class Report>
void run_all(Observer& observer, Report& report) {
  namespace proto = forearm_protocol;
  using State = Eigen::Matrix<Scalar, 3, 1>;
  using Control = Eigen::Matrix<Scalar, 2, 1>;
  auto& board = BoardStorage<Scalar>::board;
  const forearm::Parameters<Scalar> p;
  const forearm::CostWeights<Scalar> w;
  proto::Sender host(0), plant(0);
  State x(Scalar(0), Scalar(0), forearm::equilibrium_pressure(p, Scalar(0)));
  Control u(Scalar(0), p.k_vp * x(2));
  Counting<Observer> counting{observer};
  Scalar cost = 0;
  int updates = 0;
  const auto theta_d = [](double t) {
    return float(30.0 * kPi<double> / 180.0 * std::sin(2.0 * kPi<double> * t));
  };

  constexpr int kHoldStart = 20, kRunStart = 220;
  for (int tick = 0; updates < kSamples; ++tick) {
    const double t = tick * 1e-3;
    proto::Frame f;
    if (tick % 10 == 0) {
      proto::ModeCommand m;
      m.mode = tick >= kRunStart    ? proto::RequestedMode::kRun
               : tick >= kHoldStart ? proto::RequestedMode::kHold
                                    : proto::RequestedMode::kIdle;
      m.strategy = proto::Strategy::kTwoStage;
      m.host_time_us = static_cast<std::uint32_t>(tick) * 1000u;
      if (host.encode(m, f) == proto::EncodeResult::kOk) board.on_frame(f);
    }
    // Trajectory samples streamed 300 ms ahead of the 200 ms horizon's need, every 4 ms.
    if (tick % 4 == 0) {
      const double ahead = t + 0.3;
      proto::TrajectorySample s{theta_d(ahead), static_cast<std::uint32_t>(ahead * 1e6 + 0.5), 0};
      if (host.encode(s, f) == proto::EncodeResult::kOk) board.on_frame(f);
    }
    proto::SensorSample sensor{float(x(0)), float(x(1)), float(x(2) / Scalar(10)), 0};
    if (plant.encode(sensor, f) == proto::EncodeResult::kOk) board.on_frame(f);

    board.tick();
    if (board.mpc_due()) {
      counting.before_update(updates);
      board.run_mpc();
      counting.after_update(updates, x, u, board);
      cost += forearm::tracking_cost(p, w, x(0), Scalar(theta_d(t)), x(2), u(0), true).value +
              w.w_v * u.squaredNorm();
      ++updates;
    }
    while (board.pop_frame(f)) {
      proto::ActuatorCommand a;
      if (proto::decode(f, 0, a) == proto::DecodeResult::kOk) u << Scalar(a.v_m), Scalar(a.v_p);
    }
    x = forearm::integrate(p, x, u, Scalar(1e-3));
  }
  report.method("board-two-stage", x, cost, counting.totals);
}

}  // namespace hmpc::closed_loop_check
