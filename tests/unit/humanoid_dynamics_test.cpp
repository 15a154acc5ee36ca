// Our humanoid dynamics (CRBA, RNEA, Cholesky forward dynamics) against the same model built in
// Simbody, for random states: mass matrix, bias forces and contact-free accelerations agree to
// 1e-9 relative, for the biped (n = 29) and the reaching robot with its arm (n = 31). Also: M is
// symmetric positive definite, 0.5 v^T M v equals the links' summed kinetic energy, the model
// weighs 47.0 kg and stands 1.59 m tall (thesis Sec. 2.5.1), and no dynamics call allocates.
// The CRBA, which skips the products that are exact zeros, gives the dense textbook CRBA's
// numbers to the last bit.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <tuple>
#include <type_traits>

#include "hmpc/humanoid/dynamics.hpp"
#include "hmpc/humanoid/spatial.hpp"
#include "hmpc/platform/linux/heap_monitor.hpp"
#include "humanoid_random_state.hpp"
#include "simbody_humanoid.hpp"

namespace {

using namespace hmpc::humanoid;
namespace heap_monitor = hmpc::platform::heap_monitor;

constexpr int kRandomStates = 50;
constexpr double kAgreement = 1e-9;  // relative: the same model, so only round-off differs

template <int A>
struct RandomState {
  BasicConfiguration<A> q;
  BasicVelocity<A> v;
  BasicVelocity<A> tau;
};
using State = RandomState<0>;

template <int A>
RandomState<A> random_state(const BasicModel<A>& model, std::mt19937& rng) {
  const BasicState<A> x = test_states::random_state(model, rng);
  return {x.q, x.v, test_states::random_generalized_force(model, rng)};
}

template <class A, class B>
double relative_error(const A& ours, const B& reference) {
  return (ours - reference).norm() / reference.norm();
}

// The rigid bodies only: Simbody has no armature (simbody_humanoid.hpp).
template <int A = 0>
BasicModel<A> rigid_model() {
  return BasicModel<A>(hmpc::hil::BasicSimbodyHumanoid<A>::rigid_parameters());
}

// Both variants: the biped (n = 29) and the reaching robot with its arm (n = 31), each with
// its rigid model, our dynamics and the Simbody twin.
template <class Arm>
class HumanoidVariants : public ::testing::Test {
 protected:
  static constexpr int A = Arm::value;
  const BasicModel<A> model = rigid_model<A>();
  BasicDynamics<A> dynamics{model};
  hmpc::hil::BasicSimbodyHumanoid<A> simbody{model};
};
using Variants = ::testing::Types<std::integral_constant<int, 0>, std::integral_constant<int, 1>>;
TYPED_TEST_SUITE(HumanoidVariants, Variants);

TYPED_TEST(HumanoidVariants, AgreesWithSimbody) {
  constexpr int A = TypeParam::value;
  auto [model, dynamics, simbody] = std::tie(this->model, this->dynamics, this->simbody);
  std::mt19937 rng(5);
  double worst_mass = 0.0, worst_bias = 0.0, worst_acceleration = 0.0;
  for (int n = 0; n < kRandomStates; ++n) {
    const RandomState<A> s = random_state(model, rng);
    simbody.set_state(s.q, s.v);
    const BasicMassMatrix<A> M = dynamics.mass_matrix(s.q);
    worst_mass = std::max(worst_mass, relative_error(M, simbody.mass_matrix()));
    worst_bias =
        std::max(worst_bias, relative_error(dynamics.bias_forces(s.q, s.v), simbody.bias_forces()));
    worst_acceleration =
        std::max(worst_acceleration, relative_error(dynamics.forward_dynamics(s.q, s.v, s.tau),
                                                    simbody.forward_dynamics(s.tau)));
  }
  std::printf("n = %d: max relative error vs Simbody over %d states: M %.2e, c %.2e, a %.2e\n",
              Dimensions<A>::kStateSize, kRandomStates, worst_mass, worst_bias, worst_acceleration);
  EXPECT_LT(worst_mass, kAgreement);
  EXPECT_LT(worst_bias, kAgreement);
  EXPECT_LT(worst_acceleration, kAgreement);
}

// 0.5 v^T M v against the sum over links of 0.5 m |v_com|^2 + 0.5 omega^T I_com omega, with link
// velocities from forward kinematics, and against Simbody's kinetic energy.
TYPED_TEST(HumanoidVariants, KineticEnergyMatchesLinkEnergies) {
  constexpr int A = TypeParam::value;
  auto [model, dynamics, simbody] = std::tie(this->model, this->dynamics, this->simbody);
  BasicKinematics<A> kinematics;
  std::mt19937 rng(7);
  for (int n = 0; n < kRandomStates; ++n) {
    const RandomState<A> s = random_state(model, rng);
    dynamics.kinematics(s.q, s.v, kinematics);
    double links = 0.0;
    for (int i = 0; i < Dimensions<A>::kBodies; ++i) {
      const Body& b = model.bodies[i];
      const Vector3 omega = kinematics.velocity[i].template head<3>();
      const Vector3 v_com = kinematics.velocity[i].template tail<3>() + omega.cross(b.com);
      links += 0.5 * b.mass * v_com.squaredNorm() + 0.5 * omega.dot(b.inertia * omega);
    }
    const double quadratic = 0.5 * s.v.dot(dynamics.mass_matrix(s.q) * s.v);
    EXPECT_NEAR(quadratic, links, 1e-12 * links);
    simbody.set_state(s.q, s.v);
    EXPECT_NEAR(quadratic, simbody.kinetic_energy(), 1e-12 * links);
  }
}

// The arm is the biped's right arm made its own body: at zero angles the robots are the same
// mass distribution, so the whole-body (base) block of M agrees; the hand's centre lies the
// arm's length, upper arm + forearm + the hand's centre of mass (de Leva), below the shoulder.
TEST(HumanoidArmModel, IsTheBipedsRightArmOnItsOwnJoint) {
  const Model biped;
  const ArmModel robot;
  EXPECT_NEAR(robot.total_mass(), 47.0, 1e-12);
  BasicConfiguration<1> q = BasicConfiguration<1>::Zero();
  q[3] = 1.0;
  ArmDynamics arm_dynamics(robot);
  Dynamics dynamics(biped);
  const Eigen::Matrix<double, 6, 6> whole_body =
      dynamics.mass_matrix(q.head<kConfigurationSize>()).topLeftCorner<6, 6>();
  EXPECT_LE((arm_dynamics.mass_matrix(q).topLeftCorner<6, 6>() - whole_body).norm(),
            1e-12 * whole_body.norm());

  const Parameters p;
  const double scale = p.stature / p.reference_stature;
  const double arm_to_hand = scale * (p.upper_arm.reference_length + p.forearm.reference_length +
                                      p.hand.com_from_proximal * p.hand.reference_length);
  BasicKinematics<1> kinematics;
  arm_dynamics.kinematics(q, BasicVelocity<1>::Zero(), kinematics);
  const int arm = Dimensions<1>::kArmBody;
  const Vector3 shoulder = kinematics.position[arm];
  const Vector3 hand = shoulder + kinematics.rotation[arm] * robot.hand;
  EXPECT_NEAR((shoulder - hand).norm(), arm_to_hand, 1e-12);
  EXPECT_NEAR(hand.z(), shoulder.z() - arm_to_hand, 1e-12);
  // Flexion raises the arm forward: at pi / 2 the hand points along +x.
  q[7 + Dimensions<1>::kArmJoint] = 0.5 * M_PI;
  arm_dynamics.kinematics(q, BasicVelocity<1>::Zero(), kinematics);
  const Vector3 raised = kinematics.position[arm] + kinematics.rotation[arm] * robot.hand;
  EXPECT_NEAR(raised.x() - shoulder.x(), arm_to_hand, 1e-12);
  EXPECT_NEAR(raised.z(), shoulder.z(), 1e-12);
}

// Featherstone's CRBA (Table 6.2) with dense 6x6 products, as Eigen evaluates them.
template <int A>
BasicMassMatrix<A> dense_crba(const BasicModel<A>& model, const BasicConfiguration<A>& q) {
  using hmpc::humanoid::spatial::Matrix6;
  using hmpc::humanoid::spatial::Vector6;
  constexpr int kBodies = Dimensions<A>::kBodies;
  const auto dof = [](int body) { return kBaseDofs + body - 1; };
  std::array<Matrix6, kBodies> X, composite;
  std::array<Vector6, kBodies> S;
  for (int i = 0; i < kBodies; ++i) {
    const Body& b = model.bodies[i];
    composite[i] = spatial::spatial_inertia(b.mass, b.com, b.inertia);
    S[i] << b.axis, Vector3::Zero();
    const Matrix3 E = Eigen::AngleAxisd(i > 0 ? q[7 + i - 1] : 0.0, b.axis).toRotationMatrix();
    X[i] = spatial::motion_transform(E.transpose(), b.joint_origin);
  }
  for (int i = kBodies - 1; i > 0; --i) {
    composite[model.bodies[i].parent] += X[i].transpose() * composite[i] * X[i];
  }
  BasicMassMatrix<A> M = BasicMassMatrix<A>::Zero();
  M.template topLeftCorner<6, 6>() = composite[0];
  for (int i = kBodies - 1; i > 0; --i) {
    Vector6 F = composite[i] * S[i];
    M(dof(i), dof(i)) = S[i].dot(F) + model.armature[i - 1];
    for (int j = i; model.bodies[j].parent >= 0;) {
      F = X[j].transpose() * F;
      j = model.bodies[j].parent;
      if (j == 0) {
        M.template block<6, 1>(0, dof(i)) = F;
        M.template block<1, 6>(dof(i), 0) = F.transpose();
      } else {
        M(dof(j), dof(i)) = M(dof(i), dof(j)) = S[j].dot(F);
      }
    }
  }
  return M;
}

// Entries of two matrices that differ at all, or by more than round-off where the compiler may
// fuse a multiply and an add (then the two orders of operations are no longer the same).
template <class M>
int differing_entries(const M& ours, const M& reference) {
#if defined(__FMA__) || defined(__aarch64__) || defined(__ARM_FEATURE_FMA)
  const double tolerance = 1e-15 * reference.norm();
#else
  const double tolerance = 0.0;
#endif
  return static_cast<int>(((ours - reference).array().abs() > tolerance).count());
}

// The dynamics' CRBA skips the products that are exact zeros for every joint angle (a joint
// about a coordinate axis, an origin on an axis) and must give the dense CRBA's numbers to the
// last bit: the closed loops built on it are chaotic at the level of round-off. Checked on the
// models as they are and with every joint turned about a tilted axis from a general origin,
// whose products have no such zeros.
TYPED_TEST(HumanoidVariants, MassMatrixIsTheDenseCrbasToTheLastBit) {
  constexpr int A = TypeParam::value;
  BasicModel<A> tilted{Parameters{}};
  for (int i = 1; i < Dimensions<A>::kBodies; ++i) {
    Body& b = tilted.bodies[i];
    b.axis = (b.axis + Vector3(0.3, -0.2, 0.4)).normalized();
    b.joint_origin += Vector3(0.01, -0.02, 0.03);
  }
  std::mt19937 rng(31);
  for (const BasicModel<A>& model : {BasicModel<A>{Parameters{}}, this->model, tilted}) {
    BasicDynamics<A> dynamics(model);
    int differing = 0;
    for (int n = 0; n < 2000; ++n) {
      const BasicConfiguration<A> q = random_state(model, rng).q;
      differing += differing_entries(dynamics.mass_matrix(q), dense_crba(model, q));
    }
    EXPECT_EQ(differing, 0);
  }
}

// The step map's differenced linearisation moves one coordinate at a time and redoes the RNEA
// and the kinematics on the subtree it moves only (the base's transform only for the base's
// pose); that must give the full calls' numbers to the last bit, for every joint's rate,
// acceleration and angle.
TYPED_TEST(HumanoidVariants, SubtreeRneaAndKinematicsAreTheFullOnesToTheLastBit) {
  constexpr int A = TypeParam::value;
  constexpr int kBodies = Dimensions<A>::kBodies;
  constexpr int kFirstJoint = 7;  // q: the base's position and quaternion, then the joints
  std::mt19937 rng(37);
  std::uniform_real_distribution<double> change(-0.5, 0.5);
  BasicDynamics<A> partial(this->model), full(this->model);
  typename BasicDynamics<A>::InverseDynamicsPasses passes;
  BasicKinematics<A> nominal, moved, expected;
  const auto differing_kinematics = [&] {
    int count = 0;
    for (int i = 0; i < kBodies; ++i) {
      count += differing_entries(moved.rotation[i], expected.rotation[i]) +
               differing_entries(moved.position[i], expected.position[i]) +
               differing_entries(moved.velocity[i], expected.velocity[i]);
    }
    return count;
  };
  int differing = 0;
  for (int n = 0; n < 200; ++n) {
    const RandomState<A> s = random_state(this->model, rng);
    partial.set_configuration(s.q);
    partial.inverse_dynamics(s.v, s.tau, passes);
    partial.kinematics(s.v, nominal);
    for (int body = 0; body < kBodies; ++body) {
      // A rate and an acceleration of the body's joint (the base's angular rate for the torso).
      const int dof = body == 0 ? 2 : kBaseDofs + body - 1;
      BasicVelocity<A> v = s.v, a = s.tau;
      v[dof] += change(rng);
      a[dof] += change(rng);
      differing += differing_entries(partial.inverse_dynamics_in_subtree(body, v, a, passes),
                                     full.inverse_dynamics(s.q, v, a));
      if (body == 0) continue;
      moved = nominal;
      partial.kinematics_in_subtree(body, v, moved);
      full.kinematics(s.q, v, expected);
      differing += differing_kinematics();
      // Its angle.
      BasicConfiguration<A> q = s.q;
      q[kFirstJoint + body - 1] += change(rng);
      partial.set_joint_angle(body, q[kFirstJoint + body - 1]);
      differing += differing_entries(partial.inverse_dynamics_in_subtree(body, s.v, s.tau, passes),
                                     full.inverse_dynamics(q, s.v, s.tau));
      moved = nominal;
      partial.kinematics_in_subtree(body, s.v, moved);
      full.kinematics(q, s.v, expected);
      differing += differing_kinematics();
      partial.set_joint_angle(body, s.q[kFirstJoint + body - 1]);
    }
    // The base's pose alone (a quaternion entry), the joints kept.
    BasicConfiguration<A> q = s.q;
    q[3 + n % 4] += change(rng);
    partial.set_base_pose(q);
    differing += differing_entries(partial.inverse_dynamics(s.v, s.tau),
                                   full.inverse_dynamics(q, s.v, s.tau));
    partial.kinematics(s.v, moved);
    full.kinematics(q, s.v, expected);
    differing += differing_kinematics();
  }
  EXPECT_EQ(differing, 0);
}

TEST(HumanoidDynamics, MassMatrixIsSymmetricPositiveDefinite) {
  const Model model;
  Dynamics dynamics(model);
  std::mt19937 rng(6);
  for (int n = 0; n < kRandomStates; ++n) {
    const MassMatrix M = dynamics.mass_matrix(random_state(model, rng).q);
    EXPECT_LE((M - M.transpose()).norm(), 1e-14 * M.norm());
    const Eigen::SelfAdjointEigenSolver<MassMatrix> eigen(M);
    EXPECT_GT(eigen.eigenvalues().minCoeff(), 0.0);
  }
}

// The armature adds a constant to each joint's diagonal entry of M and armature times its
// acceleration to its torque; the rigid-body entries are unchanged.
TEST(HumanoidDynamics, ArmatureAddsToTheJointDiagonal) {
  const Model with(Parameters{}), without = rigid_model();
  ASSERT_GT(with.armature.minCoeff(), 0.0);
  Dynamics armed(with), rigid(without);
  std::mt19937 rng(8);
  for (int n = 0; n < 10; ++n) {
    const State s = random_state(with, rng);
    MassMatrix expected = rigid.mass_matrix(s.q);
    expected.diagonal().tail<kJoints>() += with.armature;
    EXPECT_LE((armed.mass_matrix(s.q) - expected).norm(), 1e-14 * expected.norm());
    Velocity tau = rigid.inverse_dynamics(s.q, s.v, s.tau);
    tau.tail<kJoints>() += with.armature.cwiseProduct(s.tau.tail<kJoints>());
    EXPECT_LE((armed.inverse_dynamics(s.q, s.v, s.tau) - tau).norm(), 1e-12 * tau.norm());
  }
  EXPECT_THROW(hmpc::hil::SimbodyHumanoid{with}, std::invalid_argument);
}

// At rest, the bias force on the base is the weight carried by the base: m g upward.
TEST(HumanoidDynamics, BiasAtRestIsTheWeight) {
  const Model model;
  Dynamics dynamics(model);
  Configuration q = Configuration::Zero();
  q[3] = 1.0;
  const Velocity c = dynamics.bias_forces(q, Velocity::Zero());
  EXPECT_NEAR(c[5], 47.0 * 9.81, 1e-9);
  EXPECT_NEAR(c.segment<2>(3).norm(), 0.0, 1e-12);
}

TEST(HumanoidModel, MassAndHeightAreTheThesis) {
  const Model model;
  EXPECT_NEAR(model.total_mass(), 47.0, 1e-12);
  // Standing upright with all joints at zero: vertex above the soles.
  const Dynamics dynamics(model);
  Configuration q = Configuration::Zero();
  q[3] = 1.0;
  Kinematics kinematics;
  dynamics.kinematics(q, Velocity::Zero(), kinematics);
  const double vertex = (kinematics.rotation[0] * model.vertex + kinematics.position[0]).z();
  for (int leg = 0; leg < 2; ++leg) {
    const double sole = kinematics.position[Model::body_of(leg, kAnkle)].z() - model.sole_height;
    EXPECT_NEAR(vertex - sole, 1.59, 1e-12);
  }
}

TEST(HumanoidDynamics, CallsDoNotAllocate) {
  const Model model;
  Dynamics dynamics(model);
  Kinematics kinematics;
  std::mt19937 rng(8);
  const State s = random_state(model, rng);
  const auto before = heap_monitor::allocations();
  heap_monitor::arm();
  const MassMatrix M = dynamics.mass_matrix(s.q);
  const Velocity c = dynamics.bias_forces(s.q, s.v);
  const Velocity tau = dynamics.inverse_dynamics(s.q, s.v, s.tau);
  const Velocity a = dynamics.forward_dynamics(s.q, s.v, s.tau);
  dynamics.kinematics(s.q, s.v, kinematics);
  heap_monitor::disarm();
  EXPECT_EQ(heap_monitor::allocations() - before, 0u);
  EXPECT_TRUE(M.allFinite() && c.allFinite() && tau.allFinite() && a.allFinite());
}

}  // namespace
