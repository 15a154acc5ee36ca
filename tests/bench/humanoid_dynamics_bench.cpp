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
#include "hmpc/humanoid/dynamics_derivatives.hpp"
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
// The analytic derivatives (dynamics_derivatives.hpp) in the same coordinates as
// forward_jacobian: the tangent columns chained to (p, quaternion) and the joint torques.
struct OursAnalytic {
  DynamicsDerivatives d{rigid_model()};
  BasicForwardDynamicsDerivatives<0> out;
  ForwardJacobian operator()(const Sample& s) {
    Velocity tau = Velocity::Zero();
    tau.tail<kJoints>() = s.tau.tail<kJoints>();
    d.forward_dynamics_derivatives(s.q, s.v, tau, out);
    const Eigen::Quaterniond orientation(s.q[3], s.q[4], s.q[5], s.q[6]);
    ForwardJacobian J;
    J.leftCols<3>() = out.da_dq.middleCols<3>(3) * orientation.toRotationMatrix().transpose();
    J.middleCols<4>(3) = out.da_dq.leftCols<3>() * tangent_of_quaternion(s.q.segment<4>(3));
    J.middleCols<kJoints>(7) = out.da_dq.rightCols<kJoints>();
    J.middleCols<kDofs>(kConfigurationSize) = out.da_dv;
    J.rightCols<kJoints>() = out.da_dtau.rightCols<kJoints>();
    return J;
  }
};
void ours_analytic_derivatives(benchmark::State& state) {
  DynamicsDerivatives d{rigid_model()};
  BasicForwardDynamicsDerivatives<0> out;
  run(state, [&](const Sample& s) {
    d.forward_dynamics_derivatives(s.q, s.v, s.tau, out);
    benchmark::DoNotOptimize(out.da_dq.data());
  });
}
void ours_inverse_derivatives(benchmark::State& state) {
  DynamicsDerivatives d{rigid_model()};
  InverseDynamicsDerivatives out;
  run(state, [&](const Sample& s) {
    d.inverse_dynamics_derivatives(s.q, s.v, s.tau, out);
    benchmark::DoNotOptimize(out.dtau_dq.data());
  });
}

// Largest |entry| difference of two Jacobians over the samples, relative to the largest
// entry.
template <class A, class B>
double disagreement(A&& a, B&& b) {
  double worst = 0.0;
  for (const Sample& s : samples()) {
    const ForwardJacobian x = a(s), y = b(s);
    worst = std::max(worst, (x - y).cwiseAbs().maxCoeff() / x.cwiseAbs().maxCoeff());
  }
  return worst;
}
double jacobian_disagreement() {
  OursForward ours;
  SimbodyForward simbody;
  return disagreement([&](const Sample& s) { return forward_jacobian(s, std::ref(ours)); },
                      [&](const Sample& s) { return forward_jacobian(s, std::ref(simbody)); });
}

BENCHMARK(ours_rnea);
BENCHMARK(simbody_bias);
BENCHMARK(ours_crba);
BENCHMARK(simbody_mass);
BENCHMARK(ours_forward);
BENCHMARK(simbody_forward);
BENCHMARK(ours_derivatives);
BENCHMARK(simbody_derivatives);
BENCHMARK(ours_analytic_derivatives);
BENCHMARK(ours_inverse_derivatives);

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

  // Ours by our own units: the forward dynamics' derivatives and the CRBA in forward dynamics
  // and RNEA calls of the same run.
  const double rnea = recorder.ns["ours_rnea"], forward = recorder.ns["ours_forward"];
  const double analytic = recorder.ns["ours_analytic_derivatives"];
  const double differences = recorder.ns["ours_derivatives"];
  const double inverse = recorder.ns["ours_inverse_derivatives"];
  std::printf("\nOurs in our own units (same run)\n");
  std::printf("%-44s %10s %10s\n", "quantity", "[us]", "ratio");
  std::printf("%-44s %10.3f %9.2fx RNEA\n", "mass matrix M (CRBA)", recorder.ns["ours_crba"] / 1e3,
              recorder.ns["ours_crba"] / rnea);
  std::printf("%-44s %10.3f %9.2fx RNEA\n", "d tau/d(q, v), analytic (RNEA derivatives)",
              inverse / 1e3, inverse / rnea);
  std::printf("%-44s %10.3f %9.2fx forward dynamics\n", "d qddot/d(q, v, tau), analytic",
              analytic / 1e3, analytic / forward);
  std::printf("%-44s %10.3f %9.2fx forward dynamics\n", "d qddot/d(q, v, tau), forward differences",
              differences / 1e3, differences / forward);
  std::printf(
      "analytic against forward differences: %.2fx faster; they differ by at most %.1e of "
      "the largest entry (the differences' own error)\n",
      differences / analytic, [] {
        OursForward f;
        OursAnalytic analytic_jacobian;
        return disagreement(std::ref(analytic_jacobian),
                            [&](const Sample& s) { return forward_jacobian(s, std::ref(f)); });
      }());
  benchmark::Shutdown();
  return 0;
}
