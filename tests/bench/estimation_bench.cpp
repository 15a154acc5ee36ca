// The base estimator's cost per 1 ms sample, against that sample period, on a recorded walk
// (motion II under Coarse-Fast on the 1 ms simulator, read by the biped's simulated sensors):
// the invariant EKF's whole update (propagate with the IMU, correct with the legs, contact from
// the legs), its two halves, and the state the MPC is given once per 30 ms sample; the thesis's
// whole-body UKF's update (57 sigma points through the step map, the base Kalman filter), and
// the ratio of the two. Median, 99th percentile and
// largest over every sample of three passes; one process on a shared machine, so the largest is
// the machine's as much as the filter's.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <vector>

#include "hmpc/estimation/biped_state_estimator.hpp"
#include "hmpc/estimation/whole_body_ukf.hpp"
#include "hmpc/humanoid/closed_loop.hpp"
#include "hmpc/humanoid/motion.hpp"

namespace {

using namespace hmpc::humanoid;
namespace est = hmpc::estimation;
using Clock = std::chrono::steady_clock;

constexpr double kDt = 1e-3;
constexpr int kPasses = 3;

struct Figures {
  double median = 0, p99 = 0, largest = 0;  // [us]
};

Figures figures(std::vector<double> us) {
  std::sort(us.begin(), us.end());
  return {us[us.size() / 2], us[us.size() * 99 / 100], us.back()};
}

double microseconds(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double, std::micro>(to - from).count();
}

void print(const char* what, const Figures& f) {
  std::printf("%-44s median %6.1f us, p99 %6.1f us, largest %7.1f us\n", what, f.median, f.p99,
              f.largest);
}

}  // namespace

int main() {
  ClosedLoopConfig config;
  config.duration = 2.0;
  config.truncate = false;
  config.record_milliseconds = true;
  const ClosedLoopRun run =
      run_closed_loop(load_motion(HMPC_HUMANOID_MOTIONS "/II-walking.motion"), config);
  const Model model;
  BipedSensors sensors(model);
  sensors.start_at_rest(run.initial.q);
  std::vector<SensorReadings> readings;
  readings.reserve(run.milliseconds.size());
  const Velocity still = Velocity::Zero();
  const SensorReadings at_rest = sensors.measure(run.initial.q, still, still);
  for (const SimulatorStep& step : run.milliseconds) {
    readings.push_back(sensors.measure(step.state.q, step.state.v, step.acceleration));
  }

  std::vector<double> update, propagate, correct, state, ukf_update;
  for (int pass = 0; pass < kPasses; ++pass) {
    est::BipedStateEstimator estimator;
    est::InvariantEkf halves;
    est::WholeBodyUkf ukf;
    est::ImuRest rest;
    for (int k = 0; k < 500; ++k) {
      estimator.rest(at_rest, kDt);
      rest.add(at_rest.imu, kDt);
    }
    estimator.start();
    halves.initialize_at_rest(rest, at_rest.angles);
    ukf.initialize_at_rest(rest, at_rest.angles);
    for (std::size_t k = 0; k < readings.size(); ++k) {
      const SensorReadings& r = readings[k];
      auto t0 = Clock::now();
      estimator.update(r, kDt);
      auto t1 = Clock::now();
      update.push_back(microseconds(t0, t1));
      if (k % 30 == 29) {
        t0 = Clock::now();
        static_cast<void>(estimator.state());
        t1 = Clock::now();
        state.push_back(microseconds(t0, t1));
      }
      t0 = Clock::now();
      halves.propagate(r.imu, kDt);
      t1 = Clock::now();
      halves.correct(r.angles, r.rates);
      const auto t2 = Clock::now();
      propagate.push_back(microseconds(t0, t1));
      correct.push_back(microseconds(t1, t2));
      t0 = Clock::now();
      ukf.update(run.milliseconds[k].torque, r, kDt);
      t1 = Clock::now();
      ukf_update.push_back(microseconds(t0, t1));
    }
  }
  std::printf("base estimator on %zu samples of motion II (x%d passes), %.0f us sample period:\n",
              readings.size(), kPasses, kDt * 1e6);
  const Figures whole = figures(update);
  print("update (propagate, correct, contact from legs)", whole);
  print("  propagate with the IMU", figures(propagate));
  print("  correct with the legs", figures(correct));
  print("the MPC's state (once per 30 ms sample)", figures(state));
  std::printf("estimator update / 1 ms sample period: median %.3f, p99 %.3f, largest %.3f\n",
              whole.median / (kDt * 1e6), whole.p99 / (kDt * 1e6), whole.largest / (kDt * 1e6));
  const Figures thesis = figures(ukf_update);
  print("whole-body UKF update (with base KF)", thesis);
  std::printf("whole-body UKF update / 1 ms sample period: median %.3f, p99 %.3f, largest %.3f\n",
              thesis.median / (kDt * 1e6), thesis.p99 / (kDt * 1e6), thesis.largest / (kDt * 1e6));
  std::printf("whole-body UKF / invariant EKF update, median: %.1f\n",
              thesis.median / whole.median);
  return 0;
}
