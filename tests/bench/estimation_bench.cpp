// The base estimator's cost per 1 ms sample, against that sample period, on a recorded walk
// (motion II under Coarse-Fast on the 1 ms simulator, read by the biped's simulated sensors):
// the invariant EKF's whole update (propagate with the IMU, correct with the legs, contact from
// the legs), its two halves, and the state the MPC is given once per 30 ms sample; the thesis's
// whole-body UKF's update (57 sigma points through the step map, the base Kalman filter), and
// the ratio of the two; each one's errors against the truth on that walk; and the closed loop's
// cost standing on the truth against on each estimate. Median, 99th percentile and
// largest over every sample of three passes; one process on a shared machine, so the largest is
// the machine's as much as the filter's.
#include <algorithm>
#include <chrono>
#include <cmath>
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

// Sums of squared errors of an estimate against the truth: height, horizontal velocity, tilt.
struct ErrorSums {
  double height = 0, velocity = 0, tilt = 0;
  int n = 0;
  void add(const est::BaseEstimate& e, const State& x) {
    const Eigen::Quaterniond q(x.q[3], x.q[4], x.q[5], x.q[6]);
    height += std::pow(e.position.z() - x.q[2], 2);
    velocity += (e.velocity - q * x.v.segment<3>(3)).head<2>().squaredNorm();
    const Vector3 up = q * Vector3::UnitZ(), up_estimated = e.orientation * Vector3::UnitZ();
    tilt += std::pow(std::acos(std::clamp(up.dot(up_estimated), -1.0, 1.0)), 2);
    ++n;
  }
  void print(const char* what) const {
    std::printf("%-44s height %.2f mm, horizontal velocity %.4f m/s, tilt %.3f deg RMS\n", what,
                1e3 * std::sqrt(height / n), std::sqrt(velocity / n),
                std::sqrt(tilt / n) * 180 / M_PI);
  }
};

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
  ErrorSums iekf_errors, ukf_errors;
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
      if (pass == 0) {
        iekf_errors.add(estimator.filter().estimate(), run.milliseconds[k].state);
        ukf_errors.add(ukf.estimate(), run.milliseconds[k].state);
      }
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
  std::printf("errors on the same walk, every sample after a 0.5 s rest:\n");
  iekf_errors.print("  invariant EKF (contact from the legs)");
  ukf_errors.print("  whole-body UKF");

  // The closed loop standing (motion I, 3 s, untruncated, sensor seed 1) on each feedback.
  std::printf("closed loop, motion I, 3 s, untruncated:\n");
  const Motion standing = load_motion(HMPC_HUMANOID_MOTIONS "/I-standing.motion");
  double truth_cost = 0;
  for (const StateFeedback feedback :
       {StateFeedback::kTruth, StateFeedback::kInvariantEkf, StateFeedback::kWholeBodyUkf}) {
    ClosedLoopConfig loop;
    loop.duration = 3.0;
    loop.truncate = false;
    loop.feedback = feedback;
    const ClosedLoopSummary s = summarise(run_closed_loop(standing, loop));
    if (feedback == StateFeedback::kTruth) truth_cost = s.total_cost;
    std::printf(
        "  on %-15s cost %8.2f (%.2f x the truth's), mean iterations %.2f, median solve %.1f ms\n",
        name_of(feedback), s.total_cost, s.total_cost / truth_cost, s.mean_iterations,
        s.median_solve_ms);
  }
  return 0;
}
