// Speed of the HIL's Simbody forearm plant: its real-time factor over 10 s of the thesis's
// tracking scenario's shape (a 0.5 Hz swing driven by valve and motor), against the
// controller's own model of Eq. 3.1 integrated by RK4 at the same 1 ms step, in the same run.
// A plant node keeps a 1 kHz real-time run only with a factor above 1; the lock-step HIL runs
// as fast as it allows.
#include <chrono>
#include <cmath>
#include <cstdio>

#include "hmpc/constants.hpp"
#include "hmpc/models/forearm.hpp"
#include "simbody_forearm.hpp"

namespace {

using hmpc::hil::ForearmMismatch;
using hmpc::hil::ForearmPlantState;
using hmpc::hil::SimbodyForearm;

constexpr double kDt = SimbodyForearm::kStep;
constexpr double kSeconds = 10;
constexpr double kTwoPi = 2 * hmpc::kPi<double>;

double valve(const hmpc::forearm::Parameters<double>& p, double p0, double t) {
  return p.k_vp * p0 + 1.0 * std::sin(kTwoPi * 0.5 * t);
}
double motor(double t) { return 2.0 * std::sin(kTwoPi * 2 * t); }

template <class Step>
double seconds_for(Step&& step, int steps) {
  const auto start = std::chrono::steady_clock::now();
  for (int k = 0; k < steps; ++k) step(k * kDt);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

int main() {
  const hmpc::forearm::Parameters<double> model;
  const double p0 = hmpc::forearm::equilibrium_pressure(model, 0.0);
  const int steps = int(std::lround(kSeconds / kDt));

  SimbodyForearm plant(model, ForearmMismatch{}, ForearmPlantState{0.0, 0.0, p0});
  const double simbody_s =
      seconds_for([&](double t) { plant.step(valve(model, p0, t), motor(t)); }, steps);

  Eigen::Vector3d x(0.0, 0.0, p0);
  const double model_s = seconds_for(
      [&](double t) {
        x = hmpc::forearm::integrate(model, x, Eigen::Vector2d(motor(t), valve(model, p0, t)), kDt);
      },
      steps);

  std::printf("Simbody forearm plant: %d steps of 1 ms in %.3f s, real-time factor %.1f\n", steps,
              simbody_s, kSeconds / simbody_s);
  std::printf("Eq. 3.1 by RK4 (the controller's model): %.3f s, real-time factor %.0f\n", model_s,
              kSeconds / model_s);
  std::printf("Simbody plant / RK4 model: %.1fx the time (end angles %.4f and %.4f rad)\n",
              simbody_s / model_s, plant.state().theta, x(0));
  return std::isfinite(plant.state().theta) && std::isfinite(x(0)) ? 0 : 1;
}
