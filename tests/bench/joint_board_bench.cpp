// The joint boards' budgets in one run: the CAN bus load of the joint protocol per bus, at the
// 6 ms control period and at 1 ms, for the humanoid's 8 leg joints in three board layouts
// (classic CAN at 1 Mbit/s, worst-case bit stuffing, from the protocol's tables); and the
// compute cost of one control period of the joint board (4 joints: the I/O frames of a tick,
// four torque loops, the telemetry) against one 4 ms control period of the forearm board (its
// two-stage MPC step), on this host. The Cortex-M instructions per control period are the
// joint_board_on_qemu tests' figures.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

#include "forearm_board.hpp"
#include "hmpc/models/forearm_solvers.hpp"
#include "hmpc/models/hydraulic_pendulum.hpp"
#include "joint_board.hpp"

namespace {

namespace jp = hmpc::joint_protocol;
namespace fp = hmpc::forearm_protocol;
namespace hy = hmpc::hydraulic;
using Clock = std::chrono::steady_clock;

std::vector<double>& joint_us() {
  static std::vector<double> v;
  return v;
}
std::vector<double>& forearm_us() {
  static std::vector<double> v;
  return v;
}

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// The joint board with 4 joints in run on torque sinusoids, its plant (the hanging legs) in
// the loop; each sample times the control tick: the tick's frames in, the tick, frames out.
void JointBoardControlPeriod(benchmark::State& state) {
  static hmpc::firmware::JointBoard<double> board{hmpc::firmware::JointBoardConfig<double>{}};
  const hy::JointActuatorParameters<double> actuator{};
  const auto load = hy::PendulumLoad<double>::leg();
  std::array<hy::PendulumState<double>, 4> plant{};
  plant.fill(hy::torque_free_rest(actuator));
  jp::Sender host(0), io(0);
  std::array<double, 4> u{};
  for (auto _ : state) {
    for (int tick = 0; tick < 2000; ++tick) {
      const double t = tick * 1e-3;
      jp::Frame f;
      const auto deliver = [&](const auto& m) {
        if (host.encode(m, f) == jp::EncodeResult::kOk) board.on_frame(f);
      };
      if (tick % 10 == 0) {
        jp::ModeCommand m;
        m.mode = tick >= 300   ? jp::RequestedMode::kRun
                 : tick >= 100 ? jp::RequestedMode::kHold
                               : jp::RequestedMode::kIdle;
        m.zero_encoders = tick == 50;
        deliver(m);
      }
      const bool control = (tick + 1) % 6 == 0;
      const auto start = Clock::now();
      if (tick % 6 == 0 && tick >= 290) {
        jp::TorqueReference r;
        for (std::size_t j = 0; j < 4; ++j) r.tau[j] = float(10 * std::sin(4 * M_PI * t + j));
        deliver(r);
      }
      const auto sense = [&](const auto& m) {
        if (io.encode(m, f) == jp::EncodeResult::kOk) board.on_frame(f);
      };
      const auto torque = [&](std::size_t j) {
        return float(hy::joint_torque(actuator, plant[j].actuator, plant[j].omega));
      };
      sense(jp::JointSensor<0>{float(plant[0].theta), float(plant[0].omega), torque(0), 0});
      sense(jp::JointSensor<1>{float(plant[1].theta), float(plant[1].omega), torque(1), 0});
      sense(jp::JointSensor<2>{float(plant[2].theta), float(plant[2].omega), torque(2), 0});
      sense(jp::JointSensor<3>{float(plant[3].theta), float(plant[3].omega), torque(3), 0});
      jp::ChamberPressures01 p01;
      jp::ChamberPressures23 p23;
      for (std::size_t i = 0; i < 2; ++i) {
        p01.p_a[i] = float(plant[i].actuator.pressure_a * 1e-6);
        p01.p_b[i] = float(plant[i].actuator.pressure_b * 1e-6);
        p23.p_a[i] = float(plant[2 + i].actuator.pressure_a * 1e-6);
        p23.p_b[i] = float(plant[2 + i].actuator.pressure_b * 1e-6);
      }
      sense(p01);
      sense(p23);
      board.tick();
      while (board.pop_frame(f)) {
        jp::ValveDrive d;
        if (jp::decode(f, 0, d) == jp::DecodeResult::kOk) {
          for (std::size_t j = 0; j < 4; ++j) u[j] = d.u[j];
        }
      }
      const double us = std::chrono::duration<double, std::micro>(Clock::now() - start).count();
      if (control && tick >= 300) joint_us().push_back(us);
      for (std::size_t j = 0; j < 4; ++j)
        hy::step_pendulum(actuator, load, plant[j], u[j], 1e-3, 20);
    }
    benchmark::DoNotOptimize(u);
  }
}

// The forearm board's control period in run (two-stage MPC), its Eq. 3.1 plant in the loop.
void ForearmBoardControlPeriod(benchmark::State& state) {
  static hmpc::firmware::ForearmBoard<double> board{hmpc::firmware::BoardConfig<double>{}};
  const hmpc::forearm::Parameters<double> p;
  Eigen::Vector3d x(0, 0, hmpc::forearm::equilibrium_pressure(p, 0.0));
  Eigen::Vector2d u(0, p.k_vp * x(2));
  fp::Sender host(0), plant(0);
  for (auto _ : state) {
    for (int tick = 0; tick < 1200; ++tick) {
      fp::Frame f;
      if (tick % 10 == 0) {
        fp::ModeCommand m;
        m.mode = tick >= 220 ? fp::RequestedMode::kRun : fp::RequestedMode::kHold;
        m.host_time_us = std::uint32_t(tick) * 1000u;
        if (host.encode(m, f) == fp::EncodeResult::kOk) board.on_frame(f);
      }
      if (tick % 4 == 0) {
        const double ahead = tick * 1e-3 + 0.3;
        fp::TrajectorySample s{float(0.5 * std::sin(2 * M_PI * ahead)),
                               std::uint32_t(ahead * 1e6 + 0.5), 0};
        if (host.encode(s, f) == fp::EncodeResult::kOk) board.on_frame(f);
      }
      const auto start = Clock::now();
      fp::SensorSample s{float(x(0)), float(x(1)), float(x(2) / 10), 0};
      if (plant.encode(s, f) == fp::EncodeResult::kOk) board.on_frame(f);
      board.tick();
      const bool due = board.mpc_due();
      if (due) board.run_mpc();
      while (board.pop_frame(f)) {
        fp::ActuatorCommand a;
        if (fp::decode(f, 0, a) == fp::DecodeResult::kOk) u << a.v_m, a.v_p;
      }
      const double us = std::chrono::duration<double, std::micro>(Clock::now() - start).count();
      if (due && tick >= 300) forearm_us().push_back(us);
      x = hmpc::forearm::integrate(p, x, u, 1e-3);
    }
  }
  state.counters["mpc_steps"] = double(board.counters().mpc_steps);
  state.counters["in_run"] = board.mode() == fp::BoardMode::kRun ? 1 : 0;
}

BENCHMARK(JointBoardControlPeriod)->Iterations(3)->Unit(benchmark::kMillisecond);
BENCHMARK(ForearmBoardControlPeriod)->Iterations(2)->Unit(benchmark::kMillisecond);

void print_bus_loads() {
  std::printf(
      "\nJoint protocol bus load, classic CAN 1 Mbit/s, worst-case stuffing (%u bits per "
      "frame), 8 leg joints and the torso IMU\n",
      unsigned(hmpc::protocol::kWorstCaseFrameBits));
  std::printf("%-22s %-10s %12s %12s\n", "layout", "period", "robot bus", "I/O bus (HIL)");
  struct Layout {
    const char* name;
    unsigned boards, joints;
  };
  for (const Layout l : {Layout{"2 boards x 4 joints", 2, 4}, Layout{"4 boards x 2 joints", 4, 2},
                         Layout{"8 boards x 1 joint", 8, 1}}) {
    for (const double period : {6.0, 1.0}) {
      const jp::BusLayout layout{l.boards, l.joints, true, period};
      std::printf("%-22s %4.0f ms    %10.1f %% %12.1f %%\n", l.name, period,
                  100 * jp::bus_load(jp::Bus::kRobot, 1'000'000, layout),
                  100 * jp::bus_load(jp::Bus::kIo, 1'000'000, layout));
    }
  }
  std::printf(
      "The I/O bus stands for each board's own wiring (encoders, load cells, pressure "
      "transducers, valve drivers); in the HIL it is one vcan, which has no bit rate.\n");
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  print_bus_loads();
  const double joint = median(joint_us()), forearm = median(forearm_us());
  std::printf(
      "\nControl period on this host (median): joint board, 4 joints, 6 ms period: %.2f us; "
      "forearm board, two-stage MPC, 4 ms period: %.1f us\n",
      joint, forearm);
  std::printf(
      "joint board / forearm board control period: %.4fx (%.2f %% vs %.2f %% of its period)\n",
      joint / forearm, 100 * joint / 6000, 100 * forearm / 4000);
  benchmark::Shutdown();
  return 0;
}
