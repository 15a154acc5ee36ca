// Our humanoid dynamics against Simbody's on the same model (the rigid bodies, without the joint
// armature Simbody's twin cannot mirror) and the same random states, side by side in one run: bias
// forces (our RNEA), mass matrix (our CRBA) and forward dynamics (ours: RNEA + CRBA + Cholesky;
// Simbody: realize(Acceleration), its O(n) articulated-body method). Each Simbody call includes
// setting its state from ours (it must recompute from q and v, as ours does) and the conversion to
// our coordinates (14x14 products, plus one multiplyByM for the bias forces). And the derivatives
// of forward dynamics by forward differences, the MPC's way (finite_difference.hpp's step), in q, v
// and the joint torques: 1 + 15 + 14 + 8 = 38 forward dynamics each, the same perturbed states for
// both (quaternion columns renormalised, so that each engine sees a valid state); the table also
// gives the largest difference between the two Jacobians.
#include <benchmark/benchmark.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cstdio>
#include <functional>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "hmpc/humanoid/dynamics.hpp"
#include "hmpc/solver/finite_difference.hpp"
#include "simbody_humanoid.hpp"

namespace {

using namespace hmpc::humanoid;

// Ours on Simbody's twin's model: the rigid bodies without joint armature (simbody_humanoid.hpp),
// so that both compute the same accelerations.
Model rigid_model() { return Model(hmpc::hil::SimbodyHumanoid::rigid_parameters()); }

struct Sample {
  Configuration q;
  Velocity v;
  Velocity tau;
};

const std::vector<Sample>& samples() {
  static const std::vector<Sample> all = [] {
    const Model model = rigid_model();
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
  Dynamics d{rigid_model()};
  run(state, [&](const Sample& s) { benchmark::DoNotOptimize(d.bias_forces(s.q, s.v)); });
}
void ours_crba(benchmark::State& state) {
  Dynamics d{rigid_model()};
  run(state, [&](const Sample& s) { benchmark::DoNotOptimize(d.mass_matrix(s.q)); });
}
void ours_forward(benchmark::State& state) {
  Dynamics d{rigid_model()};
  run(state,
      [&](const Sample& s) { benchmark::DoNotOptimize(d.forward_dynamics(s.q, s.v, s.tau)); });
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
// d(qddot)/d(q, v, tau_joints) by forward differences of `forward(q, v, tau)`, over the stacked
// point (q, v, tau_joints); the quaternion is renormalised at every point.
constexpr int kPoint = kConfigurationSize + kDofs + kJoints;
using ForwardJacobian = Eigen::Matrix<double, kDofs, kPoint>;
template <class Forward>
ForwardJacobian forward_jacobian(const Sample& s, Forward forward) {
  using Point = Eigen::Matrix<double, kPoint, 1>;
  const auto at = [&](const Point& p) {
    Configuration q = p.head<kConfigurationSize>();
    q.segment<4>(3).normalize();
    Velocity tau = Velocity::Zero();
    tau.tail<kJoints>() = p.tail<kJoints>();
    return forward(q, p.segment<kDofs>(kConfigurationSize), tau);
  };
  Point x;
  x << s.q, s.v, s.tau.tail<kJoints>();
  const Velocity a = at(x);
  ForwardJacobian J;
  for (int i = 0; i < kPoint; ++i) {
    const double d = hmpc::detail::fd_step(x[i], 0.5);
    Point p = x;
    p[i] += d;
    J.col(i) = (at(p) - a) / d;
  }
  return J;
}
struct OursForward {
  Dynamics d{rigid_model()};
  Velocity operator()(const Configuration& q, const Velocity& v, const Velocity& tau) {
    return d.forward_dynamics(q, v, tau);
  }
};
struct SimbodyForward {
  hmpc::hil::SimbodyHumanoid sim;
  Velocity operator()(const Configuration& q, const Velocity& v, const Velocity& tau) {
    sim.set_state(q, v);
    return sim.forward_dynamics(tau);
  }
};
void ours_derivatives(benchmark::State& state) {
  OursForward f;
  run(state, [&](const Sample& s) { benchmark::DoNotOptimize(forward_jacobian(s, std::ref(f))); });
}
void simbody_derivatives(benchmark::State& state) {
  SimbodyForward f;
  run(state, [&](const Sample& s) { benchmark::DoNotOptimize(forward_jacobian(s, std::ref(f))); });
}
// Largest |entry| difference of the two Jacobians over the samples, relative to the largest
// entry.
double jacobian_disagreement() {
  OursForward ours;
  SimbodyForward simbody;
  double worst = 0.0;
  for (const Sample& s : samples()) {
    const ForwardJacobian a = forward_jacobian(s, std::ref(ours)),
                          b = forward_jacobian(s, std::ref(simbody));
    worst = std::max(worst, (a - b).cwiseAbs().maxCoeff() / a.cwiseAbs().maxCoeff());
  }
  return worst;
}

BENCHMARK(ours_rnea);
BENCHMARK(simbody_bias);
BENCHMARK(ours_crba);
BENCHMARK(simbody_mass);
BENCHMARK(ours_forward);
BENCHMARK(simbody_forward);
BENCHMARK(ours_derivatives);
BENCHMARK(simbody_derivatives);

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
                           {"forward dynamics", "ours_forward", "simbody_forward"},
                           {"its derivatives", "ours_derivatives", "simbody_derivatives"}};
  for (const auto& row : rows) {
    const double ours = recorder.ns[row[1]], simbody = recorder.ns[row[2]];
    std::printf("%-18s %12.3f %12.3f %13.2fx\n", row[0], ours / 1e3, simbody / 1e3, simbody / ours);
  }
  std::printf(
      "derivatives: d(qddot)/d(q, v, tau) by forward differences, 38 forward dynamics; the two "
      "Jacobians differ by at most %.1e of their largest entry (finite-difference noise)\n",
      jacobian_disagreement());
  benchmark::Shutdown();
  return 0;
}
