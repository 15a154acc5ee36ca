// Smooth contact and the step map (contact.hpp, step.hpp): standing load, landing, friction
// cone, chair, robustness at extreme states, no allocation in step(), and the slopes of the
// contact force and the end stops that the analytic linearisation uses.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include "hmpc/humanoid/contact.hpp"
#include "hmpc/humanoid/step.hpp"
#include "hmpc/platform/linux/heap_monitor.hpp"
#include "humanoid_mirror.hpp"
#include "humanoid_random_state.hpp"

namespace {

using namespace hmpc::humanoid;
namespace heap_monitor = hmpc::platform::heap_monitor;

constexpr double kDt = 1e-3;  // the test's PD runs at the simulator rate (Sec. 2.7)

double weight(StepMap& map) {
  return map.dynamics().model().total_mass() * -map.dynamics().model().gravity.z();
}

Vector3 centre_of_mass(StepMap& map, const State& x) {
  Kinematics kin;
  map.dynamics().kinematics(x.q, x.v, kin);
  Vector3 sum = Vector3::Zero();
  for (int i = 0; i < kBodies; ++i) {
    const Body& b = map.dynamics().model().bodies[i];
    sum += b.mass * (kin.position[i] + kin.rotation[i] * b.com);
  }
  return sum / map.dynamics().model().total_mass();
}

double lowest_sole(const ContactState& c) {
  double z = c.position[0].z();
  for (int i = 1; i < kSolePoints; ++i) z = std::min(z, c.position[i].z());
  return z;
}

// Torso pitch about world y (forward lean positive), from the torso's z axis.
double pitch(const State& x) {
  const Matrix3 R = Eigen::Quaterniond(x.q[3], x.q[4], x.q[5], x.q[6]).toRotationMatrix();
  return std::atan2(R(0, 2), R(2, 2));
}

// Quiet standing: feet flat, the body straight but leaning forward at the ankles by `lean` so
// that the centre of mass is over the middle of the soles (with all joints at zero it is
// 1 mm in front of the ankle, 4.7 cm from the heel edge: a rigid body that close to the edge
// tips over on 1 cm-compliant soles). Soles on the ground (zero gap), sole centre at x = 0.
struct Standing {
  State x;
  double lean = 0.0;
};
Standing standing(StepMap& map) {
  Standing s;
  s.x.q.setZero();
  s.x.v.setZero();
  for (int iteration = 0; iteration < 6; ++iteration) {
    s.x.q.head<3>().setZero();
    s.x.q.segment<4>(3) << std::cos(0.5 * s.lean), 0.0, std::sin(0.5 * s.lean), 0.0;
    for (int leg = 0; leg < 2; ++leg) s.x.q[7 + leg * kJointsPerLeg + kAnkle] = s.lean;
    const ContactState& c = map.evaluate_contact(s.x);
    double centre = 0.0;
    for (int i = 0; i < kSolePoints; ++i) centre += c.position[i].x() / kSolePoints;
    s.x.q[0] = -centre;
    s.x.q[2] = -lowest_sole(c);
    // Rotating about the ankles moves the CoM forward by its height per radian.
    const Vector3 com = centre_of_mass(map, s.x);
    s.lean -= com.x() / com.z();
  }
  return s;
}

// The test's controller. A joint PD about the pose: Kp = 800 N m/rad on every joint keeps
// the limbs near the pose under the body's weight; Kd critically damps each joint's own
// inertia M_jj (2 sqrt(Kp M_jj)), which at the 3.5e-3 kg m^2 foot is h Kd / M_jj = 0.95 < 2
// per 1 ms step. Standing, the 1 cm-compliant soles alone give the rigid body a pitch
// stiffness of only 8 k (0.105 m)^2 = 511 N m/rad against gravity's m g h = 415 N m/rad, in
// series with the ankle PD: too soft. So, as a person does, the ankles also feed back the
// torso's world pitch: K_theta = 1200 N m/rad per ankle puts the net stiffness at
// 2 K_theta - m g h = 1985 N m/rad, 7.8 rad/s on the body's 33 kg m^2 about the ankles, and
// D_theta = 200 N m s/rad per ankle damps that at zeta = 0.8.
struct Controller {
  static constexpr double kp = 800.0, k_pitch = 1200.0, d_pitch = 200.0;
  JointVector target, kd;
  bool balance;
  double lean;
  Controller(StepMap& map, const Configuration& q_ref, bool balance_pitch, double lean_ref = 0.0)
      : target(q_ref.tail<kJoints>()), balance(balance_pitch), lean(lean_ref) {
    const MassMatrix& M = map.dynamics().mass_matrix(q_ref);
    for (int j = 0; j < kJoints; ++j) kd[j] = 2.0 * std::sqrt(kp * M(kBaseDofs + j, kBaseDofs + j));
  }
  JointVector operator()(const State& x) const {
    JointVector tau = kp * (target - x.q.tail<kJoints>()) - kd.cwiseProduct(x.v.tail<kJoints>());
    if (balance) {
      for (int leg = 0; leg < 2; ++leg) {
        tau[leg * kJointsPerLeg + kAnkle] += k_pitch * (lean - pitch(x)) - d_pitch * x.v[1];
      }
    }
    return tau;
  }
};

bool finite(const State& x) { return x.q.allFinite() && x.v.allFinite(); }

TEST(HumanoidContact, JacobianMatchesBodyVelocities) {
  // p_dot = J v must agree with the body velocities of Dynamics::kinematics (model.hpp's v).
  StepMap map;
  Kinematics kin;
  State x = standing(map).x;
  x.q.tail<kJoints>().setRandom();
  x.q.segment<4>(3) = Eigen::Vector4d(0.9, 0.1, -0.2, 0.3).normalized();
  x.v.setRandom();
  map.dynamics().kinematics(x.q, x.v, kin);
  const Vector3 local(0.03, -0.02, -0.1);
  for (int body = 0; body < kBodies; ++body) {
    const Vector3 expected = kin.rotation[body] * (kin.velocity[body].tail<3>() +
                                                   kin.velocity[body].head<3>().cross(local));
    const Vector3 actual = point_jacobian(map.dynamics().model(), kin, body, local) * x.v;
    EXPECT_LT((actual - expected).norm(), 1e-12 * (1.0 + expected.norm())) << "body " << body;
  }
}

// (a) Standing still: after 1 s the soles carry m g to 2 % (static equilibrium), and the mean
// sink is W / (8 k) (linear springs: the mean penetration is the total load over 8 k).
TEST(HumanoidContact, StandingCarriesBodyWeight) {
  StepMap map;
  const Standing s = standing(map);
  State x = s.x;
  const Controller control(map, x.q, true, s.lean);
  for (int k = 0; k < 1000; ++k) x = map.step(x, control(x), kDt);
  const ContactState& c = map.evaluate_contact(x);
  const double w = weight(map);
  std::printf("standing after 1 s: sole load %.2f N (m g %.2f N)\n", vertical_load(c).sole, w);
  EXPECT_NEAR(vertical_load(c).sole, w, 0.02 * w);
  double mean_sink = 0.0;
  for (int i = 0; i < kSolePoints; ++i) mean_sink -= c.position[i].z() / kSolePoints;
  const double expected_sink = w / (kSolePoints * map.contact_model().parameters().stiffness);
  std::printf("mean sink %.4f m, W / 8k %.4f m\n", mean_sink, expected_sink);
  EXPECT_NEAR(mean_sink, expected_sink, 0.05 * expected_sink);
  EXPECT_NEAR(expected_sink, 0.01, 0.001);  // the ~1 cm the stiffness was chosen for
  EXPECT_LT(x.v.head<6>().norm(), 1e-2);    // at rest
}

// (b) Dropped from 5 cm (1 m/s at impact) under the test's controller: Hunt-Crossley
// restitution e ~ 1 - (2/3) c v = 0.33 predicts a rebound of e^2 5 cm = 0.6 cm; the bound
// is e < 0.5, 1.25 cm. After 2 s it is at rest on its full weight.
TEST(HumanoidContact, DropLandsAndComesToRest) {
  StepMap map;
  const Standing s = standing(map);
  State x = s.x;
  const Controller control(map, x.q, true, s.lean);
  x.q[2] += 0.05;
  bool touched = false;
  double rebound = 0.0;
  for (int k = 0; k < 2000; ++k) {
    x = map.step(x, control(x), kDt);
    const double lowest = lowest_sole(map.evaluate_contact(x));
    touched = touched || lowest < 0.0;
    if (touched) rebound = std::max(rebound, lowest);
  }
  EXPECT_TRUE(touched);
  std::printf("drop: rebound of the lowest sole point %.4f m\n", rebound);
  EXPECT_LT(rebound, 0.0125);
  const double w = weight(map);
  EXPECT_NEAR(vertical_load(map.evaluate_contact(x)).sole, w, 0.02 * w);
  EXPECT_LT(x.v.head<6>().norm(), 1e-2);
}

// (c) A horizontal push below the friction limit mu m g leaves the feet nearly still, one
// above it makes them slide. The push acts forward at both ankle joints (h = 6 cm above the
// ground), low enough that the robot does not tip while its feet stick: the push P moves the
// centre of pressure by P h / W = 2.4 cm for P = 0.5 mu W, within the soles' 10.5 cm
// half-length. Sliding, the friction at the soles pitches the body backwards; the test's
// balance feedback holds it for about 0.2 s (then the toes lift and it falls, a matter of
// control, not of contact), so the sliding run lasts 0.15 s.
struct Slide {
  double distance = 0.0, friction = 0.0, sole_load = 0.0, heel_speed = 0.0, weight = 0.0;
};
Slide slide(double push_over_limit, int steps) {
  StepMap map;
  const Standing s = standing(map);
  State x = s.x;
  const Controller control(map, x.q, true, s.lean);
  for (int k = 0; k < 1000; ++k) x = map.step(x, control(x), kDt);  // settle as in (a)
  const Model& model = map.dynamics().model();
  const double push = push_over_limit * map.contact_model().parameters().friction * weight(map);
  const Vector3 force_per_leg(0.5 * push, 0.0, 0.0);
  Kinematics kin;
  const double start = map.evaluate_contact(x).position[0].x();
  for (int k = 0; k < steps; ++k) {
    map.dynamics().kinematics(x.q, x.v, kin);
    Velocity external = Velocity::Zero();
    for (int leg = 0; leg < 2; ++leg) {
      external +=
          point_jacobian(model, kin, Model::body_of(leg, kAnkle), Vector3::Zero()).transpose() *
          force_per_leg;
    }
    x = map.step(x, control(x), kDt, external);
  }
  EXPECT_TRUE(finite(x));
  const ContactState& c = map.evaluate_contact(x);
  Slide result{c.position[0].x() - start, 0.0, vertical_load(c).sole, c.velocity[0].x(),
               weight(map)};
  for (int i = 0; i < kSolePoints; ++i) result.friction -= c.force[i].x();
  std::printf(
      "push %.1f mu m g for %d ms: heel slip %.4f m at %.3f m/s, friction %.1f N on %.1f N\n",
      push_over_limit, steps, result.distance, result.heel_speed, result.friction,
      result.sole_load);
  return result;
}

TEST(HumanoidContact, FrictionHoldsBelowLimit) {
  // Creep at half the limit: v_s / sqrt(3) = 5.8 mm/s, 2.9 mm in 0.5 s.
  EXPECT_LT(std::abs(slide(0.5, 500).distance), 0.01);
}

TEST(HumanoidContact, SlidesAboveLimit) {
  // At 1.2 mu m g Coulomb friction leaves 0.2 mu g = 1.57 m/s^2 for the whole body: 1.8 cm in
  // 0.15 s; the feet, pushed out under the body, go at least half that. Sliding faster than
  // 3 v_s the friction is within 5 % of mu F_n (3 / sqrt(10) = 0.95), and the robot is still
  // on its feet.
  const Slide result = slide(1.2, 150);
  const double mu = ContactParameters{}.friction, v_s = ContactParameters{}.slip_velocity;
  EXPECT_GT(result.distance, 0.5 * 0.5 * 0.2 * mu * 9.81 * 0.15 * 0.15);
  EXPECT_GT(result.heel_speed, 3.0 * v_s);
  EXPECT_NEAR(result.friction, mu * result.sole_load, 0.05 * mu * result.sole_load);
  EXPECT_GT(result.sole_load, 0.5 * result.weight);
}

// The body, its joints and its contacts are left-right symmetric: a lopsided motion and its
// mirror image, under mirrored torques, stay mirror images (sliding, one foot unloading).
TEST(HumanoidContact, MotionsMirrorInTheSagittalPlane) {
  StepMap map;
  State a = standing(map).x;
  a.v[4] = 0.3;                  // the whole robot moving left
  a.v[0] = 0.2;                  // and rolling
  a.q[7 + kHipAbduction] = 0.1;  // left leg abducted
  a.q[7 + kJointsPerLeg + kKnee] = 0.3;
  JointVector tau;
  tau << 20.0, -10.0, 30.0, 5.0, -15.0, 25.0, -20.0, 8.0;
  JointVector swapped;
  swapped << tau.tail<kJointsPerLeg>(), tau.head<kJointsPerLeg>();
  State b = test::mirrored(a);
  for (int k = 0; k < 300; ++k) {
    a = map.step(a, tau, kDt);
    b = map.step(b, swapped, kDt);
  }
  const State m = test::mirrored(a);
  EXPECT_GT(std::abs(a.q[1]), 0.001) << "it moved sideways";
  EXPECT_LT((m.q - b.q).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT((m.v - b.v).cwiseAbs().maxCoeff(), 1e-8);
}

// (d) Extreme states: finite forces inside the friction cone, finite steps.
TEST(HumanoidContact, FiniteAtExtremeStates) {
  StepMap map;
  const ContactModel& contact = map.contact_model();
  const double mu = contact.parameters().friction;
  for (double gap : {-10.0, -1.0, -1e-3, 0.0, 1e-3, 1.0, 1e3}) {
    for (double speed : {-1e4, -100.0, 0.0, 100.0, 1e4}) {
      Matrix3 d;
      const Vector3 f = contact.point_force(gap, Vector3(speed, -0.5 * speed, speed), 1.0, &d);
      ASSERT_TRUE(f.allFinite() && d.allFinite());
      EXPECT_GE(f.z(), 0.0);
      EXPECT_LE(f.head<2>().norm(), mu * f.z() * (1.0 + 1e-12));
      EXPECT_LE(Eigen::SelfAdjointEigenSolver<Matrix3>(d).eigenvalues().maxCoeff(),
                1e-9 * (1.0 + d.norm()));  // D <= 0
    }
  }
  // Legs buried half a metre, tumbling at 20 rad/s and thrown down at 10 m/s.
  State x = standing(map).x;
  x.q[2] -= 0.5;
  x.v << 20.0, -15.0, 10.0, 3.0, -2.0, -10.0, 30.0, -30.0, 30.0, -30.0, 30.0, -30.0, 30.0, -30.0;
  for (int k = 0; k < 10; ++k) {
    x = map.step(x, JointVector::Constant(100.0), 0.03);
    ASSERT_TRUE(finite(x)) << "step " << k;
    EXPECT_NEAR(x.q.segment<4>(3).norm(), 1.0, 1e-12);
  }
}

// (e) step() does not allocate, with and without the chair, at the MPC's 30 ms step.
TEST(HumanoidContact, StepDoesNotAllocate) {
  ContactParameters with_chair;
  with_chair.chair = true;
  auto map = std::make_unique<StepMap>(Model{}, Parameters{}, with_chair);
  State x = standing(*map).x;
  x.q[2] += 0.02;
  const JointVector tau = JointVector::Constant(5.0);
  const auto before = heap_monitor::allocations();
  heap_monitor::arm();
  for (int k = 0; k < 20; ++k) x = map->step(x, tau, 0.03);
  heap_monitor::disarm();
  EXPECT_EQ(heap_monitor::allocations() - before, 0u);
  EXPECT_TRUE(finite(x));
}

// (f) The chair: the robot in a sitting pose (hips and knees flexed 90 degrees, shanks
// vertical) dropped 2 cm onto a seat level with its ischia and onto the ground. The torso
// (58 % of the mass) rests on the ischia and the thighs (30 %) mostly on the seat, so the
// seat must carry more than half the weight, and seat and soles together all of it.
TEST(HumanoidContact, SittingLoadsTheSeat) {
  ContactParameters chair;
  chair.chair = true;
  StepMap probe(Model{}, Parameters{}, chair);
  State x = standing(probe).x;
  x.q.segment<4>(3) << 1.0, 0.0, 0.0, 0.0;
  x.q.tail<kJoints>().setZero();
  for (int leg = 0; leg < 2; ++leg) {
    x.q[7 + leg * kJointsPerLeg + kHipFlexion] = M_PI / 2;
    x.q[7 + leg * kJointsPerLeg + kKnee] = M_PI / 2;
  }
  // Soles on the ground, seat level with the lowest seat point (the ischia), reaching from
  // behind the pelvis to 5 cm past the front thigh points (3.5 cm short of the knees).
  const ContactState& c0 = probe.evaluate_contact(x);
  x.q[2] -= lowest_sole(c0);
  double seat = 1e9, front_x = -1e9;
  for (int i = kSolePoints; i < kContactPoints; ++i) {
    seat = std::min(seat, c0.position[i].z() - lowest_sole(c0));
    front_x = std::max(front_x, c0.position[i].x());
  }
  chair.seat_height = seat;
  chair.seat_x_min = -0.3;
  chair.seat_x_max = front_x + 0.05;
  StepMap map(Model{}, Parameters{}, chair);
  // Joint PD only: seat and feet give a broad base, no balance feedback is needed.
  const Controller control(map, x.q, false);
  x.q[2] += 0.02;
  for (int k = 0; k < 1500; ++k) x = map.step(x, control(x), kDt);
  const VerticalLoad load = vertical_load(map.evaluate_contact(x));
  const double w = weight(map);
  std::printf("sitting: seat %.1f N, soles %.1f N, m g %.1f N\n", load.seat, load.sole, w);
  EXPECT_GT(load.seat, 0.5 * w);
  EXPECT_GT(load.sole, 0.0);
  EXPECT_NEAR(load.seat + load.sole, w, 0.02 * w);
  EXPECT_LT(x.v.head<6>().norm(), 1e-2);
}

// The analytic linearisation's contact slopes (ContactModel::force_slopes): phi = f + h D w
// and its slopes in the position, velocity and w against central differences of force_at's
// f and D, on sole and seat points at gaps across the softplus corner, sticking and sliding,
// approaching and separating, and at the seat window's edge. Central differences with step
// 1e-7 against the contact's 1 mm and 1 cm/s scales err by about (1e-7 / 1e-3)^2 = 1e-8
// relative in truncation and eps |phi| / 1e-7 = 1e-9 N in round-off: 1e-5 of the largest
// slope leaves a wide margin and fails any wrong term.
// The step map's iteration matrix M - h sum_i J_i^T D_i J_i: subtract_damping must give the
// dense product's numbers to the last bit on the lower triangle (the closed loops built on it
// are chaotic at the level of round-off) and leave the upper one alone, for every point (chair
// included), on the Jacobians of random states and random D (generic numbers in every entry the
// product reads).
TEST(HumanoidContact, DampingIsTheDenseProductsToTheLastBit) {
  ContactParameters parameters;
  parameters.chair = true;
  const Model model;
  const ContactModel contact(model, Parameters{}, parameters);
  Dynamics dynamics(model);
  std::mt19937 rng(41);
  std::uniform_real_distribution<double> entry(-3e4, 3e4);
  int differing = 0, products = 0;
  for (int n = 0; n < 500; ++n) {
    const State x = hmpc::humanoid::test_states::random_state(model, rng);
    Kinematics kinematics;
    dynamics.kinematics(x.q, x.v, kinematics);
    ContactState state;
    contact.evaluate(kinematics, x.v, state);
    const double h = 1e-3 * (1 + n % 5);
    const MassMatrix M = dynamics.mass_matrix(x.q);
    MassMatrix dense = M, ours = M;
    for (int i = 0; i < state.count; ++i) {
      state.force_velocity[i] = Matrix3::NullaryExpr([&] { return entry(rng); });
      dense.noalias() -=
          h * state.jacobian[i].transpose() * state.force_velocity[i] * state.jacobian[i];
      contact.subtract_damping(i, state, h, ours);
      ++products;
    }
#if defined(__FMA__) || defined(__aarch64__) || defined(__ARM_FEATURE_FMA)
    // Where the compiler may fuse a multiply and an add the two orders are no longer the same.
    const double tolerance = 1e-15 * dense.norm();
#else
    const double tolerance = 0.0;
#endif
    const MassMatrix expected = dense.triangularView<Eigen::Lower>().toDenseMatrix() +
                                M.triangularView<Eigen::StrictlyUpper>().toDenseMatrix();
    differing += static_cast<int>(((ours - expected).array().abs() > tolerance).count());
  }
  EXPECT_EQ(products, 500 * kContactPoints);
  EXPECT_EQ(differing, 0);
}

// force_reads_position, which lets the step map skip a base translation's unchanged forces:
// moved along an axis it does not read, every point's force and its velocity derivative are
// the same to the last bit; along one it reads, a point in contact feels it.
TEST(HumanoidContact, ForceReadsOnlyThePositionsItSaysItReads) {
  ContactParameters parameters;
  parameters.chair = true;
  const ContactModel model(Model{}, Parameters{}, parameters);
  std::mt19937 rng(43);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  int unread = 0, read = 0;
  for (int trial = 0; trial < 200; ++trial) {
    for (int i = 0; i < kContactPoints; ++i) {
      const double surface = i >= kSolePoints ? parameters.seat_height : 0.0;
      // In contact (up to 5 mm deep), near the seat's edges in x, sliding or not.
      const Vector3 p(parameters.seat_x_max + 0.02 * unit(rng), 0.2 * unit(rng),
                      surface - 0.005 * (0.5 + 0.5 * unit(rng)));
      const Vector3 v(0.3 * unit(rng), 0.3 * unit(rng), 0.5 * unit(rng));
      Matrix3 D;
      const Vector3 f = model.force_at(i, p, v, D);
      for (int axis = 0; axis < 3; ++axis) {
        Matrix3 D_moved;
        const Vector3 f_moved = model.force_at(i, p + 1e-4 * Vector3::Unit(axis), v, D_moved);
        const bool same =
            (f_moved.array() == f.array()).all() && (D_moved.array() == D.array()).all();
        if (ContactModel::force_reads_position(i, axis)) {
          EXPECT_FALSE(same) << "point " << i << " axis " << axis;
          ++read;
        } else {
          EXPECT_TRUE(same) << "point " << i << " axis " << axis;
          ++unread;
        }
      }
    }
  }
  // Per trial: z on all 14 points, x on the 6 seat points; y and the soles' x unread.
  EXPECT_EQ(read, 200 * (kContactPoints + kContactPoints - kSolePoints));
  EXPECT_EQ(unread, 200 * (kContactPoints + kSolePoints));
}

TEST(HumanoidContact, ForceSlopesMatchCentralDifferences) {
  ContactParameters parameters;
  parameters.chair = true;
  const ContactModel model(Model{}, Parameters{}, parameters);
  const double h = 5e-3;
  const auto phi = [&](int i, const Vector3& p, const Vector3& v, const Vector3& w) {
    Matrix3 D;
    const Vector3 f = model.force_at(i, p, v, D);
    return Vector3(f + h * D * w);
  };
  int cases = 0;
  for (const int i : {0, 5, kSolePoints, kSolePoints + 3}) {
    const double surface = i >= kSolePoints ? parameters.seat_height : 0.0;
    for (const double gap : {-0.01, -0.001, 0.0005, 0.003}) {
      for (const Vector3& v : {Vector3(0.0, 0.0, 0.0), Vector3(0.003, -0.004, 0.1),
                               Vector3(0.3, 0.2, -0.4), Vector3(-0.05, 0.4, 1.5)}) {
        for (const double x : {0.0, parameters.seat_x_max - 0.002}) {
          const Vector3 p(x, 0.1, surface + gap), w(0.7, -1.3, 2.1);
          const PointForceSlopes slopes = model.force_slopes(i, p, v, w, h);
          ASSERT_LT((slopes.force - phi(i, p, v, w)).norm(), 1e-9 * (1.0 + slopes.force.norm()));
          Matrix3 by_position, by_velocity, by_acceleration;
          for (int n = 0; n < 3; ++n) {
            const Vector3 d = 1e-7 * Vector3::Unit(n);
            by_position.col(n) = (phi(i, p + d, v, w) - phi(i, p - d, v, w)) / 2e-7;
            by_velocity.col(n) = (phi(i, p, v + d, w) - phi(i, p, v - d, w)) / 2e-7;
            by_acceleration.col(n) = (phi(i, p, v, w + d) - phi(i, p, v, w - d)) / 2e-7;
          }
          const double scale = std::max({1.0, by_position.norm(), by_velocity.norm()});
          EXPECT_LT((slopes.by_position - by_position).norm(), 1e-5 * scale)
              << "point " << i << " gap " << gap << " v " << v.transpose() << " x " << x;
          EXPECT_LT((slopes.by_velocity - by_velocity).norm(), 1e-5 * scale)
              << "point " << i << " gap " << gap << " v " << v.transpose() << " x " << x;
          EXPECT_LT((slopes.by_acceleration - by_acceleration).norm(), 1e-5 * scale)
              << "point " << i << " gap " << gap << " v " << v.transpose() << " x " << x;
          ++cases;
        }
      }
    }
  }
  EXPECT_EQ(cases, 128);
}

// The joints' end stops (Parameters::stop_*): negligible inside the range, restoring past it.
TEST(HumanoidJointStops, QuietInsideTheRangeAndRestoringPastIt) {
  const Parameters p;
  const double lower = -0.5, upper = 0.5;
  for (double q : {-0.3, 0.0, 0.3}) {
    EXPECT_LT(std::abs(joint_stop(q, 1.0, lower, upper, p).torque), 0.01) << q;
  }
  const JointStop past_upper = joint_stop(upper + 0.05, 0.0, lower, upper, p);
  // k d <= k s(d) <= k (d + w log 2): the softplus rounds the corner by at most w log 2.
  EXPECT_LE(past_upper.torque, -p.stop_stiffness * 0.05);
  EXPECT_GE(past_upper.torque, -p.stop_stiffness * (0.05 + p.stop_width * std::log(2.0)));
  EXPECT_NEAR(past_upper.stiffness, p.stop_stiffness, 0.1 * p.stop_stiffness);
  EXPECT_GT(joint_stop(lower - 0.05, 0.0, lower, upper, p).torque, 0.9 * p.stop_stiffness * 0.05);
  // Damping opposes the rate at a stop, either way.
  EXPECT_LT(joint_stop(upper + 0.05, 1.0, lower, upper, p).torque, past_upper.torque);
  EXPECT_GT(joint_stop(upper + 0.05, -1.0, lower, upper, p).torque, past_upper.torque);
  EXPECT_TRUE(std::isfinite(joint_stop(1e6, 0.0, lower, upper, p).torque));
  EXPECT_TRUE(std::isfinite(joint_stop(-1e6, 0.0, lower, upper, p).torque));
}

// The stops' slopes: stiffness and damping are the torque's -d/dq (at zero rate) and -d/dv,
// and stiffness_slope, damping_slope their derivatives in q, against central differences
// (step 1e-7 against the stop's 1e-2-scale rounding width: truncation ~1e-10 relative),
// inside the range, in the rounded corner and past either limit.
TEST(HumanoidJointStops, SlopesMatchCentralDifferences) {
  const Parameters p;
  const double lower = -0.5, upper = 0.5, d = 1e-7;
  for (const double q : {0.0, 0.49, 0.5, 0.51, 0.56, -0.495, -0.53}) {
    for (const double v : {0.0, 1.5, -2.0}) {
      const JointStop stop = joint_stop(q, v, lower, upper, p);
      const JointStop plus = joint_stop(q + d, v, lower, upper, p),
                      minus = joint_stop(q - d, v, lower, upper, p);
      const auto near = [](double analytic, double difference) {
        return std::abs(analytic - difference) <= 1e-5 * std::max(1.0, std::abs(difference));
      };
      EXPECT_TRUE(
          near(stop.stiffness + v * stop.damping_slope, -(plus.torque - minus.torque) / (2.0 * d)))
          << q << " " << v;
      EXPECT_TRUE(near(stop.damping, -(joint_stop(q, v + d, lower, upper, p).torque -
                                       joint_stop(q, v - d, lower, upper, p).torque) /
                                         (2.0 * d)))
          << q << " " << v;
      EXPECT_TRUE(near(stop.stiffness_slope, (plus.stiffness - minus.stiffness) / (2.0 * d)))
          << q << " " << v;
      EXPECT_TRUE(near(stop.damping_slope, (plus.damping - minus.damping) / (2.0 * d)))
          << q << " " << v;
    }
  }
}

// A lifted body, every joint driven by its full torque limit towards a limit for 0.5 s, on
// the simulator's 1 ms sub-steps and the MPC model's 5 ms ones alike. Bounds from energy and
// statics: slamming through a range at the torque limit stores at most tau_max * range, which
// an undamped spring takes up over sqrt(2 tau_max range / k) = 0.62 rad (hip flexion: 150 N m
// over 2.6 rad); at rest a joint sits tau_max / k = 0.075 rad past its limit (plus the corner).
TEST(HumanoidJointStops, HoldJointsDrivenIntoThemAtFullTorque) {
  const Model model;
  for (double substep : {1e-3, 5e-3}) {
    StepMap map(model, Parameters{}, ContactParameters{}, substep);
    State x;
    x.q.setZero();
    x.q[3] = 1.0;
    x.q[2] = 3.0;  // far above the ground: no contact
    x.v.setZero();
    JointVector tau;
    for (int j = 0; j < kJoints; ++j) tau[j] = (j % 2 == 0 ? 1.0 : -1.0) * model.torque_limit[j];
    double worst = 0.0, resting = 0.0;
    for (int k = 0; k < 50; ++k) {
      x = map.step(x, tau, 0.01);
      resting = 0.0;
      for (int j = 0; j < kJoints; ++j) {
        const double q = x.q[7 + j];
        resting = std::max({resting, q - model.joint_upper[j], model.joint_lower[j] - q});
      }
      worst = std::max(worst, resting);
    }
    std::printf("sub-step %.0f ms: worst excursion past a limit %.4f rad, at rest %.4f rad\n",
                substep * 1e3, worst, resting);
    EXPECT_TRUE(x.q.allFinite() && x.v.allFinite());
    EXPECT_GT(worst, 0.0);  // the torques did push the joints into their stops
    EXPECT_LT(worst, 0.62);
    EXPECT_LT(resting, 0.075 + Parameters{}.stop_width);
    EXPECT_LT(x.v.tail<kJoints>().cwiseAbs().maxCoeff(), 1.0);  // and they came to rest there
  }
}

}  // namespace
