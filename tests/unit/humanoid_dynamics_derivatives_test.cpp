// The analytic derivatives of the humanoid's inverse dynamics (dynamics_derivatives.hpp) against
// central differences of the RNEA (dynamics.hpp), on random states of the biped (n = 29) and the
// reaching robot (n = 31): d tau / dv, d tau / dq in the tangent space (the base's pose perturbed
// on the right by a unit twist, as the header defines it), and the chain to the quaternion
// coordinates; the forward dynamics' derivatives likewise. Also: the world-frame pass reproduces
// the RNEA's tau, and no call allocates.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>

#include "hmpc/humanoid/dynamics_derivatives.hpp"
#include "hmpc/platform/linux/heap_monitor.hpp"
#include "humanoid_random_state.hpp"

namespace {

using namespace hmpc::humanoid;
namespace heap_monitor = hmpc::platform::heap_monitor;

constexpr int kRandomStates = 40;
// Central differences with step h err by h^2 |tau'''| / 6 (truncation) plus eps |tau| / h
// (round-off): with h = 1e-5 both are below 1e-8 of the largest entry for the torques and rates
// of these states (tau up to ~1e3). A wrong or missing term of the recursions is of the order of
// the entries themselves, far above 1e-6.
constexpr double kStep = 1e-5;
constexpr double kTolerance = 1e-6;  // of the Jacobian's largest entry

template <int A>
struct Sample {
  BasicConfiguration<A> q;
  BasicVelocity<A> v, a;
};

// A random state (humanoid_random_state.hpp) and the accelerations of a hard landing.
template <int A>
Sample<A> random_sample(const BasicModel<A>& model, std::mt19937& rng) {
  const BasicState<A> x = test_states::random_state(model, rng);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Sample<A> s{x.q, x.v, {}};
  for (int k = 0; k < Dimensions<A>::kDofs; ++k) s.a[k] = 30.0 * unit(rng);
  return s;
}

// q moved by eps along tangent direction c: a joint's angle, or the torso's pose by the twist
// eps e_c in torso coordinates (rotation R exp(eps e_c^), origin p + eps R e_c).
template <int A>
BasicConfiguration<A> moved(const BasicConfiguration<A>& q, int c, double eps) {
  BasicConfiguration<A> out = q;
  const Eigen::Quaterniond orientation(q[3], q[4], q[5], q[6]);
  if (c < 3) {
    const Eigen::Quaterniond turned =
        orientation * Eigen::Quaterniond(Eigen::AngleAxisd(eps, Eigen::Vector3d::Unit(c)));
    out.template segment<4>(3) << turned.w(), turned.x(), turned.y(), turned.z();
  } else if (c < kBaseDofs) {
    out.template head<3>() += eps * (orientation.toRotationMatrix() * Eigen::Vector3d::Unit(c - 3));
  } else {
    out[7 + c - kBaseDofs] += eps;
  }
  return out;
}

template <class M>
double largest(const M& m) {
  return m.cwiseAbs().maxCoeff();
}

template <int A>
void check_random_states(std::uint32_t seed) {
  const BasicModel<A> model;
  BasicDynamics<A> dynamics(model);
  BasicDynamicsDerivatives<A> derivatives(model);
  BasicInverseDynamicsDerivatives<A> d;
  std::mt19937 rng(seed);
  for (int n = 0; n < kRandomStates; ++n) {
    const Sample<A> s = random_sample(model, rng);
    derivatives.inverse_dynamics_derivatives(s.q, s.v, s.a, d);
    const BasicVelocity<A> tau = dynamics.inverse_dynamics(s.q, s.v, s.a);
    EXPECT_LE((d.tau - tau).cwiseAbs().maxCoeff(), 1e-9 * largest(tau)) << "state " << n;

    BasicMassMatrix<A> dq, dv;
    for (int c = 0; c < Dimensions<A>::kDofs; ++c) {
      dq.col(c) = (dynamics.inverse_dynamics(moved<A>(s.q, c, kStep), s.v, s.a) -
                   dynamics.inverse_dynamics(moved<A>(s.q, c, -kStep), s.v, s.a)) /
                  (2 * kStep);
      BasicVelocity<A> up = s.v, down = s.v;
      up[c] += kStep;
      down[c] -= kStep;
      dv.col(c) =
          (dynamics.inverse_dynamics(s.q, up, s.a) - dynamics.inverse_dynamics(s.q, down, s.a)) /
          (2 * kStep);
    }
    EXPECT_LE((d.dtau_dq - dq).cwiseAbs().maxCoeff(), kTolerance * largest(dq))
        << "state " << n << "\nanalytic\n"
        << d.dtau_dq << "\ndifferences\n"
        << dq;
    EXPECT_LE((d.dtau_dv - dv).cwiseAbs().maxCoeff(), kTolerance * largest(dv))
        << "state " << n << "\nanalytic\n"
        << d.dtau_dv << "\ndifferences\n"
        << dv;
  }
}

TEST(HumanoidDynamicsDerivatives, BipedMatchesCentralDifferences) { check_random_states<0>(7); }

TEST(HumanoidDynamicsDerivatives, ArmVariantMatchesCentralDifferences) {
  check_random_states<1>(11);
}

// Through tangent_of_quaternion, the tangent columns give d tau / d quaternion coordinates: the
// RNEA differenced in each quaternion coordinate (normalised inside, as set_configuration does).
TEST(HumanoidDynamicsDerivatives, QuaternionCoordinatesThroughTheTangentMap) {
  const Model model;
  Dynamics dynamics(model);
  DynamicsDerivatives derivatives(model);
  InverseDynamicsDerivatives d;
  std::mt19937 rng(5);
  for (int n = 0; n < 10; ++n) {
    const Sample<0> s = random_sample(model, rng);
    derivatives.inverse_dynamics_derivatives(s.q, s.v, s.a, d);
    const Eigen::Matrix<double, kDofs, 4> analytic =
        d.dtau_dq.leftCols<3>() * tangent_of_quaternion(s.q.segment<4>(3));
    Eigen::Matrix<double, kDofs, 4> differences;
    for (int k = 0; k < 4; ++k) {
      Configuration up = s.q, down = s.q;
      up[3 + k] += kStep;
      down[3 + k] -= kStep;
      differences.col(k) =
          (dynamics.inverse_dynamics(up, s.v, s.a) - dynamics.inverse_dynamics(down, s.v, s.a)) /
          (2 * kStep);
    }
    EXPECT_LE((analytic - differences).cwiseAbs().maxCoeff(), kTolerance * largest(differences))
        << "state " << n;
  }
}

// Forward dynamics a = M^-1 (tau - c): its derivatives in q (tangent), v and tau against central
// differences of dynamics.hpp's forward dynamics, with torques up to the limits and a base wrench.
TEST(HumanoidDynamicsDerivatives, ForwardDynamicsMatchesCentralDifferences) {
  const Model model;
  Dynamics dynamics(model);
  DynamicsDerivatives derivatives(model);
  BasicForwardDynamicsDerivatives<0> d;
  std::mt19937 rng(13);
  for (int n = 0; n < kRandomStates; ++n) {
    const Sample<0> s = random_sample(model, rng);
    const Velocity tau = test_states::random_generalized_force(model, rng);
    derivatives.forward_dynamics_derivatives(s.q, s.v, tau, d);
    EXPECT_LE((d.a - dynamics.forward_dynamics(s.q, s.v, tau)).cwiseAbs().maxCoeff(),
              1e-9 * largest(d.a));
    MassMatrix dq, dv, dtau;
    for (int c = 0; c < kDofs; ++c) {
      Velocity up_v = s.v, down_v = s.v, up_tau = tau, down_tau = tau;
      up_v[c] += kStep;
      down_v[c] -= kStep;
      up_tau[c] += kStep;
      down_tau[c] -= kStep;
      dq.col(c) = (dynamics.forward_dynamics(moved<0>(s.q, c, kStep), s.v, tau) -
                   dynamics.forward_dynamics(moved<0>(s.q, c, -kStep), s.v, tau)) /
                  (2 * kStep);
      dv.col(c) = (dynamics.forward_dynamics(s.q, up_v, tau) -
                   dynamics.forward_dynamics(s.q, down_v, tau)) /
                  (2 * kStep);
      dtau.col(c) = (dynamics.forward_dynamics(s.q, s.v, up_tau) -
                     dynamics.forward_dynamics(s.q, s.v, down_tau)) /
                    (2 * kStep);
    }
    EXPECT_LE((d.da_dq - dq).cwiseAbs().maxCoeff(), kTolerance * largest(dq)) << "state " << n;
    EXPECT_LE((d.da_dv - dv).cwiseAbs().maxCoeff(), kTolerance * largest(dv)) << "state " << n;
    EXPECT_LE((d.da_dtau - dtau).cwiseAbs().maxCoeff(), kTolerance * largest(dtau))
        << "state " << n;
  }
}

TEST(HumanoidDynamicsDerivatives, DoesNotAllocate) {
  const Model model;
  DynamicsDerivatives derivatives(model);
  InverseDynamicsDerivatives d;
  std::mt19937 rng(3);
  const Sample<0> s = random_sample(model, rng);
  derivatives.inverse_dynamics_derivatives(s.q, s.v, s.a, d);
  const auto before = heap_monitor::allocations();
  heap_monitor::arm();
  BasicForwardDynamicsDerivatives<0> forward;
  for (int n = 0; n < 10; ++n) {
    derivatives.inverse_dynamics_derivatives(s.q, s.v, s.a, d);
    derivatives.forward_dynamics_derivatives(s.q, s.v, s.a, forward);
  }
  heap_monitor::disarm();
  EXPECT_EQ(heap_monitor::allocations() - before, 0u);
}

}  // namespace
