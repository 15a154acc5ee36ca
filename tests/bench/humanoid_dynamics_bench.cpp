// Our humanoid dynamics against Simbody's on the same model and the same random states, side by
// side in one run (DESIGN.md §6): bias forces (our RNEA), mass matrix (our CRBA) and forward
// dynamics (ours: RNEA + CRBA + Cholesky; Simbody: realize(Acceleration), its O(n)
// articulated-body method). Each Simbody call includes setting its state from ours (it must
// recompute from q and v, as ours does) and the conversion to our coordinates (14x14 products,
// plus one multiplyByM for the bias forces).
#include <benchmark/benchmark.h>

#include <Eigen/Geometry>
#include <cstdio>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "hmpc/humanoid/dynamics.hpp"
#include "simbody_humanoid.hpp"

namespace {

using namespace hmpc::humanoid;

struct Sample {
  Configuration q;
  Velocity v;
  Velocity tau;
};

const std::vector<Sample>& samples() {
  static const std::vector<Sample> all = [] {
    const Model model;
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    std::vector<Sample> out(64);
    for (auto& s : out) {
      s.q.head<3>() << unit(rng), unit(rng), 0.9;
      const Eigen::Quaterniond o =
          Eigen::Quaterniond(1.0, 0.3 * unit(rng), 0.3 * unit(rng), 0.3 * unit(rng)).normalized();
      s.q.segment<4>(3) << o.w(), o.x(), o.y(), o.z();
      for (int j = 0; j < kJoints; ++j) {
        s.q[7 + j] = model.joint_lower[j] +
                     0.5 * (unit(rng) + 1.0) * (model.joint_upper[j] - model.joint_lower[j]);
      }
      s.v = 2.0 * Velocity::Random();
      s.tau.head<kBaseDofs>().setZero();
      for (int j = 0; j < kJoints; ++j) s.tau[kBaseDofs + j] = model.torque_limit[j] * unit(rng);
    }
    return out;
  }();
  return all;
}

template <class Call>
void run(benchmark::State& state, Call call) {
  const auto& all = samples();
  std::size_t k = 0;
  for (auto _ : state) {
    call(all[k]);
    k = (k + 1) % all.size();
  }
}

void ours_rnea(benchmark::State& state) {
  Dynamics d;
  run(state, [&](const Sample& s) { benchmark::DoNotOptimize(d.bias_forces(s.q, s.v)); });
}
void ours_crba(benchmark::State& state) {
  Dynamics d;
  run(state, [&](const Sample& s) { benchmark::DoNotOptimize(d.mass_matrix(s.q)); });
}
void ours_forward(benchmark::State& state) {
  Dynamics d;
  run(state, [&](const Sample& s) { benchmark::DoNotOptimize(d.forward_dynamics(s.q, s.v, s.tau)); });
}
void simbody_bias(benchmark::State& state) {
  hmpc::hil::SimbodyHumanoid sim;
  run(state, [&](const Sample& s) {
    sim.set_state(s.q, s.v);
    benchmark::DoNotOptimize(sim.bias_forces());
  });
}
void simbody_mass(benchmark::State& state) {
  hmpc::hil::SimbodyHumanoid sim;
  run(state, [&](const Sample& s) {
    sim.set_state(s.q, s.v);
    benchmark::DoNotOptimize(sim.mass_matrix());
  });
}
void simbody_forward(benchmark::State& state) {
  hmpc::hil::SimbodyHumanoid sim;
  run(state, [&](const Sample& s) {
    sim.set_state(s.q, s.v);
    benchmark::DoNotOptimize(sim.forward_dynamics(s.tau));
  });
}
BENCHMARK(ours_rnea);
BENCHMARK(simbody_bias);
BENCHMARK(ours_crba);
BENCHMARK(simbody_mass);
BENCHMARK(ours_forward);
BENCHMARK(simbody_forward);

// Keeps each benchmark's time per call (ns) for the side-by-side table.
class Recorder : public benchmark::ConsoleReporter {
 public:
  std::map<std::string, double> ns;
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const auto& r : runs) ns[r.benchmark_name()] = r.GetAdjustedRealTime();
    ConsoleReporter::ReportRuns(runs);
  }
};

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  Recorder recorder;
  benchmark::RunSpecifiedBenchmarks(&recorder);
  std::printf("\nHumanoid dynamics (n = 29, 14 dofs), time per call on the same 64 states\n");
  std::printf("%-18s %12s %12s %14s\n", "quantity", "ours [us]", "Simbody [us]", "Simbody / ours");
  const char* rows[][3] = {{"bias forces c", "ours_rnea", "simbody_bias"},
                           {"mass matrix M", "ours_crba", "simbody_mass"},
                           {"forward dynamics", "ours_forward", "simbody_forward"}};
  for (const auto& row : rows) {
    const double ours = recorder.ns[row[1]], simbody = recorder.ns[row[2]];
    std::printf("%-18s %12.3f %12.3f %13.2fx\n", row[0], ours / 1e3, simbody / 1e3, simbody / ours);
  }
  benchmark::Shutdown();
  return 0;
}
