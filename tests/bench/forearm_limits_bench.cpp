// Where the forearm's tracking limit lies, and what sets it: every strategy of Table 3.1 on the
// model (RK4 plant at 1 ms, each update's input delayed by its compute time on the Cortex-M7)
// tracking +-30 deg sinusoids from 0.25 to 2.5 Hz for 10 s, beside the actuators' first-harmonic
// limit (forearm_tracking_limit.hpp); then the same runs with the horizons changed (the
// Two-stage's second stage, Coarse 20 ms's whole horizon), with the terminal rate term in the
// Two-stage's stages and in every strategy, and with a faster valve. A study, not
// a timing: every figure is an RMS tracking error in degrees, and the ratios compare strategies
// of the same run.
#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "hmpc/models/forearm_mpc.hpp"
#include "hmpc/models/forearm_solvers.hpp"
#include "hmpc/models/forearm_tracking_limit.hpp"
#include "simbody_forearm.hpp"

namespace {

using namespace hmpc::forearm;
using S = Strategies<double>;
constexpr int kSamples = 2500;  // 10 s at 4 ms
constexpr double kAmplitude = 30 * M_PI / 180;
constexpr double kDegree = 180 / M_PI;

// The MPCs' model is `model`, the simulated arm `plant`.
struct Run {
  const Parameters<double>& plant;
  S::Setup setup;
  TargetTrajectory<double> target;
  Run(const Parameters<double>& model, double frequency_hz) : Run(model, model, frequency_hz) {}
  Run(const Parameters<double>& model, const Parameters<double>& p, double frequency_hz)
      : plant(p) {
    target.set_sinusoid(kAmplitude, frequency_hz, 0, 0);
    setup.parameters = model;
    setup.target = &target;
  }
  // RMS error (deg) of one strategy; the MPC is built on the heap (the Fine ones are large).
  template <class Mpc>
  double rms(std::unique_ptr<Mpc> mpc) const {
    NoTrackingObserver observer;
    const Eigen::Vector3d x0(0, 0, equilibrium_pressure(plant, 0.0));
    return simulate_tracking<double>(*mpc, plant, setup.weights, target, x0, kSamples,
                                     CortexM7ComputeDelay{}, observer)
               .rms_error *
           kDegree;
  }
  // The Two-stage with a second-stage horizon of NFast fine steps (Table 3.1's is 20, 80 ms)
  // and the terminal rate term's T_v in its stages (0: the thesis's cost).
  template <int NFast>
  double two_stage(TwoStageTerminalRate rate = {}) const {
    using Fast = ForearmFastSubsystem<double, NFast>;
    using Mpc = hmpc::CoarseFastMpc<S::Problem, kCoarse20Horizon, Fast, NFast>;
    Fast fast(setup.parameters, setup.weights, kTwoStageFineStep, setup.target);
    fast.set_terminal_rate_time(rate.second_stage);
    return rms(std::make_unique<Mpc>(
        S::problem(setup, kCoarse20Step, rate.first_stage), fast,
        typename Mpc::Config{kTwoStageFineStepsPerCoarseStep, S::samples_per_step(kCoarse20Step),
                             solver_config<double>(), solver_config<double>()}));
  }
  // Coarse 20 ms looking N steps ahead (Sec. 3.3's 200 ms is N = 10).
  template <int N>
  double coarse20() const {
    using Mpc = hmpc::RecedingHorizonMpc<S::Problem, N>;
    return rms(std::make_unique<Mpc>(
        S::problem(setup, kCoarse20Step, 0),
        typename Mpc::Config{S::samples_per_step(kCoarse20Step), solver_config<double>()}));
  }
  double strategy(Strategy s) const {
    switch (s) {
      case Strategy::kFine4: return rms(std::make_unique<S::Fine4>(S::fine4(setup)));
      case Strategy::kFine8: return rms(std::make_unique<S::Fine8>(S::fine8(setup)));
      case Strategy::kCoarse20: return rms(std::make_unique<S::Coarse20>(S::coarse20(setup)));
      case Strategy::kCoarse40: return rms(std::make_unique<S::Coarse40>(S::coarse40(setup)));
      case Strategy::kTwoStage: return rms(std::make_unique<S::TwoStage>(S::two_stage(setup)));
      case Strategy::kPamOnly: return rms(std::make_unique<S::PamOnly>(S::pam_only(setup)));
    }
    return 0;
  }
};

// Lowest RMS error among the strategies other than the Two-stage (PAM-only aside: Fig. 3.8b's
// comparison, not one of Fig. 3.6's).
double best_other(const std::vector<double>& rms) {
  double best = 1e9;
  for (Strategy s : {Strategy::kFine4, Strategy::kFine8, Strategy::kCoarse20, Strategy::kCoarse40})
    best = std::min(best, rms[static_cast<int>(s)]);
  return best;
}

}  // namespace

int main() {
  const Parameters<double> model{};
  const double frequencies[] = {0.25, 0.5, 1.0, 1.5, 1.8, 2.0, 2.5};

  std::printf(
      "Forearm tracking +-30 deg sinusoids on the model, 10 s, RK4 plant at 1 ms, Cortex-M7 "
      "compute time charged: RMS error (deg)\n\n"
      "| f (Hz) | actuator limit (deg) | RMS floor | Fine 4 ms | Fine 8 ms | Coarse 20 ms | "
      "Coarse 40 ms | Two-stage | PAM only | Two-stage / best other |\n"
      "|---|---|---|---|---|---|---|---|---|---|\n");
  double two_stage_over_best_at_1_8 = 0;
  std::vector<double> best_others;
  for (double f : frequencies) {
    const Run run(model, f);
    std::vector<double> rms;
    for (Strategy s : kAllStrategies) rms.push_back(run.strategy(s));
    const TrackingLimit limit = tracking_limit(model, f, kAmplitude, 0.0);
    best_others.push_back(best_other(rms));
    const double ratio = rms[static_cast<int>(Strategy::kTwoStage)] / best_others.back();
    if (f == 1.8) two_stage_over_best_at_1_8 = ratio;
    std::printf("| %.2f | %.1f | %.2f |", f, limit.max_amplitude * kDegree,
                limit.rms_error_floor * kDegree);
    for (double r : rms) std::printf(" %.2f |", r);
    std::printf(" %.2f |\n", ratio);
  }

  std::printf(
      "\nHorizons: the Two-stage's second stage looking 80 (Table 3.1), 120, 160 and 200 ms "
      "ahead; Coarse 20 ms looking 200 (Sec. 3.3), 300 and 400 ms ahead. RMS error (deg)\n\n"
      "| f (Hz) | Two-stage 80 | 120 | 160 | 200 | Coarse 20 ms 200 | 300 | 400 |\n"
      "|---|---|---|---|---|---|---|---|\n");
  double coarse_400_over_200_at_1_8 = 0;
  for (double f : {0.25, 1.0, 1.8}) {
    const Run run(model, f);
    const double c200 = run.coarse20<10>(), c400 = run.coarse20<20>();
    if (f == 1.8) coarse_400_over_200_at_1_8 = c400 / c200;
    std::printf("| %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f |\n", f,
                run.two_stage<20>(), run.two_stage<30>(), run.two_stage<40>(), run.two_stage<50>(),
                c200, run.coarse20<15>(), c400);
  }

  std::printf(
      "\nThe terminal rate term w_theta T_v^2 (theta' - theta_d')^2 beside Eq. 3.3b (T_v = 0: the "
      "thesis's cost). The Two-stage with it in its second stage, then also in its first "
      "stage (second stage %.1f s), on the model and on the model with the HIL demo's "
      "mismatch (mass x%g, friction x%g, valve x%g). RMS error (deg), and the Two-stage with "
      "T_v %.2f s / %.1f s over the best other strategy as the thesis has it\n\n"
      "| plant | f (Hz) | second 0 | 0.1 | 0.2 | 0.4 | 0.8 s | first 0.05 | 0.1 | 0.15 s | "
      "chosen / best other |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|\n",
      kTwoStageTerminalRate.second_stage, hmpc::hil::kDemoMismatch.mass_scale,
      hmpc::hil::kDemoMismatch.friction_scale, hmpc::hil::kDemoMismatch.pam_time_constant_scale,
      kTwoStageTerminalRate.first_stage, kTwoStageTerminalRate.second_stage);
  double rate_term_over_best_at_1_8 = 0;
  const Parameters<double> mismatched = hmpc::hil::with_mismatch(model, hmpc::hil::kDemoMismatch);
  for (const Parameters<double>* plant : {&model, &mismatched}) {
    for (int i = 0; frequencies[i] <= 1.8; ++i) {
      const Run run(model, *plant, frequencies[i]);
      double best = best_others[i];
      if (plant == &mismatched) {
        std::vector<double> rms;
        for (Strategy s : kAllStrategies)
          rms.push_back(s == Strategy::kPamOnly || s == Strategy::kTwoStage ? 0.0
                                                                            : run.strategy(s));
        best = best_other(rms);
      }
      std::printf("| %s | %.2f |", plant == &model ? "model" : "mismatched", frequencies[i]);
      for (double t_v : {0.0, 0.1, 0.2, 0.4, 0.8})
        std::printf(" %.2f |", run.two_stage<20>({0, t_v}));
      for (double t_v : {0.05, 0.1, 0.15})
        std::printf(" %.2f |", run.two_stage<20>({t_v, kTwoStageTerminalRate.second_stage}));
      const double ratio = run.two_stage<20>(kTwoStageTerminalRate) / best;
      if (plant == &model && frequencies[i] == 1.8) rate_term_over_best_at_1_8 = ratio;
      std::printf(" %.2f |\n", ratio);
    }
  }

  std::printf(
      "\nThe terminal rate term in every strategy's whole-horizon problem (Fine, Coarse, the "
      "Two-stage's first stage), T_v 0.1 and 0.2 s; the Two-stage's second stage with T_v %.1f "
      "s. RMS error (deg)\n\n"
      "| f (Hz) | T_v (s) | Fine 4 ms | Fine 8 ms | Coarse 20 ms | Coarse 40 ms | Two-stage | "
      "Two-stage / best other |\n"
      "|---|---|---|---|---|---|---|---|\n",
      kTwoStageTerminalRate.second_stage);
  for (int i = 0; frequencies[i] <= 1.8; ++i) {
    Run run(model, frequencies[i]);
    for (double t_v : {0.1, 0.2}) {
      run.setup.terminal_rate_time = t_v;
      run.setup.two_stage_terminal_rate = {t_v, kTwoStageTerminalRate.second_stage};
      std::vector<double> rms;
      for (Strategy s : kAllStrategies)
        rms.push_back(s == Strategy::kPamOnly ? 0.0 : run.strategy(s));
      std::printf("| %.2f | %.1f |", frequencies[i], t_v);
      for (std::size_t k = 0; k + 1 < rms.size(); ++k) std::printf(" %.2f |", rms[k]);
      std::printf(" %.2f |\n", rms[static_cast<int>(Strategy::kTwoStage)] / best_other(rms));
    }
  }

  std::printf(
      "\nValve time constant at 1.8 Hz (model and plant alike): RMS error (deg)\n\n"
      "| T_p / k_vp (ms) | actuator limit (deg) | Fine 4 ms | Coarse 20 ms | Two-stage |\n"
      "|---|---|---|---|---|\n");
  for (double scale : {1.0, 2.0 / 3.0, 0.4}) {
    Parameters<double> faster = model;
    faster.T_p *= scale;
    const Run run(faster, 1.8);
    std::printf("| %.0f | %.1f | %.2f | %.2f | %.2f |\n", 1e3 * faster.T_p / faster.k_vp,
                tracking_limit(faster, 1.8, kAmplitude, 0.0).max_amplitude * kDegree,
                run.strategy(Strategy::kFine4), run.strategy(Strategy::kCoarse20),
                run.strategy(Strategy::kTwoStage));
  }

  std::printf("\ntwo-stage / best other at 1.8 Hz: RMS %.2fx\n", two_stage_over_best_at_1_8);
  std::printf("two-stage with the terminal rate term / best other at 1.8 Hz: RMS %.2fx\n",
              rate_term_over_best_at_1_8);
  std::printf("coarse-20ms 400 ms / 200 ms horizon at 1.8 Hz: RMS %.2fx\n",
              coarse_400_over_200_at_1_8);
  return 0;
}
