// The hydraulic joint actuator against its equations: the orifice law, the chambers'
// compression with the valve closed (integrated, against the closed form), the steady states
// of a blocked joint, and the load-velocity coupling's sign and size.
#include "hmpc/models/hydraulic_joint.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "hmpc/control/hydraulic_torque_tuning.hpp"
#include "hmpc/models/hydraulic_pendulum.hpp"

namespace {

namespace hy = hmpc::hydraulic;
using Parameters = hy::JointActuatorParameters<double>;
using State = hy::JointActuatorState<double>;

// One classic RK4 step of the actuator with the joint moving at theta(t) = theta0 + omega t.
State rk4_step(const Parameters& p, const State& s, double theta, double omega, double u,
               double h) {
  const auto add = [](const State& a, const State& d, double k) {
    return State{a.spool + k * d.spool, a.pressure_a + k * d.pressure_a,
                 a.pressure_b + k * d.pressure_b};
  };
  const State k1 = hy::derivative(p, s, theta, omega, u);
  const State k2 = hy::derivative(p, add(s, k1, h / 2), theta + omega * h / 2, omega, u);
  const State k3 = hy::derivative(p, add(s, k2, h / 2), theta + omega * h / 2, omega, u);
  const State k4 = hy::derivative(p, add(s, k3, h), theta + omega * h, omega, u);
  State next = s;
  next.spool += h / 6 * (k1.spool + 2 * k2.spool + 2 * k3.spool + k4.spool);
  next.pressure_a +=
      h / 6 * (k1.pressure_a + 2 * k2.pressure_a + 2 * k3.pressure_a + k4.pressure_a);
  next.pressure_b +=
      h / 6 * (k1.pressure_b + 2 * k2.pressure_b + 2 * k3.pressure_b + k4.pressure_b);
  return next;
}

TEST(HydraulicJointParameters, DefaultsAreValidAndEachBadOneIsNamed) {
  const Parameters good;
  EXPECT_EQ(hy::check(good), nullptr);
  // A 16 MPa supply on a 16 mm bore through a 35 mm lever: ~113 N·m, a human-sized knee.
  EXPECT_NEAR(good.stall_torque_positive(), 0.035 * 2.0106e-4 * 16e6, 1e-9);
  EXPECT_LT(good.stall_torque_negative(), 0);

  const auto named = [](Parameters p, const std::string& word) {
    const char* error = hy::check(p);
    return error != nullptr && std::string(error).find(word) != std::string::npos;
  };
  Parameters p;
  p.supply_pressure = std::nan("");
  EXPECT_TRUE(named(p, "supply"));
  p = Parameters{};
  p.return_pressure = p.supply_pressure;
  EXPECT_TRUE(named(p, "return"));
  p = Parameters{};
  p.area_b = 2 * p.area_a;
  EXPECT_TRUE(named(p, "areas"));
  p = Parameters{};
  p.bulk_modulus = -1;
  EXPECT_TRUE(named(p, "bulk"));
  p = Parameters{};
  p.valve_time_constant = 0;
  EXPECT_TRUE(named(p, "valve"));
  p = Parameters{};
  p.viscous_friction = -1;
  EXPECT_TRUE(named(p, "friction"));
}

TEST(HydraulicJointValve, OrificeIsTheSquareRootLawAwayFromZeroAndSmoothThroughIt) {
  const double pt = Parameters{}.transition_pressure;
  // |dp| >= 20 p_t: within (1 + 1/400)^(1/4) - 1 = 0.06 % of the turbulent law.
  for (double dp : {20 * pt, 4e6, 16e6}) {
    EXPECT_NEAR(hy::orifice_root(dp, pt), std::sqrt(dp), 1e-3 * std::sqrt(dp));
    EXPECT_DOUBLE_EQ(hy::orifice_root(-dp, pt), -hy::orifice_root(dp, pt));
  }
  // Finite slope 1 / sqrt(p_t) at zero (the laminar region), where the bare root's is infinite.
  const double h = 1e-3 * pt;
  EXPECT_NEAR((hy::orifice_root(h, pt) - hy::orifice_root(-h, pt)) / (2 * h), 1 / std::sqrt(pt),
              1e-6 / std::sqrt(pt));
}

// The slopes an implicit integrator steps with (the HIL plant's): the orifice root's and the
// seal friction's, each its function's central difference to 1e-6 of itself, through the
// transition region and beyond it.
TEST(HydraulicJointValve, SlopesAreTheDerivativesOfTheirLaws) {
  const Parameters p;
  for (const double dp : {-5e6, -3e5, -1e4, 0.0, 2e4, 2e5, 8e6}) {
    const double h = 1.0;  // Pa
    const double difference = (hy::orifice_root(dp + h, p.transition_pressure) -
                               hy::orifice_root(dp - h, p.transition_pressure)) /
                              (2 * h);
    EXPECT_NEAR(hy::orifice_root_slope(dp, p.transition_pressure), difference,
                1e-6 * std::abs(difference))
        << "dp " << dp;
  }
  for (const double v : {-0.1, -1e-3, 0.0, 5e-4, 0.02}) {
    const double h = 1e-7;  // m/s
    const double difference =
        (hy::piston_friction(p, v + h) - hy::piston_friction(p, v - h)) / (2 * h);
    EXPECT_NEAR(hy::piston_friction_slope(p, v), difference, 1e-6 * std::abs(difference))
        << "v " << v;
  }
}

TEST(HydraulicJointValve, SpoolIsAFirstOrderLagOnTheClampedCommand) {
  const Parameters p;
  const State s{0.2, 8e6, 8e6};
  EXPECT_DOUBLE_EQ(hy::derivative(p, s, 0.0, 0.0, 0.5).spool, (0.5 - 0.2) / p.valve_time_constant);
  EXPECT_DOUBLE_EQ(hy::derivative(p, s, 0.0, 0.0, 3.0).spool, (1.0 - 0.2) / p.valve_time_constant);
  EXPECT_DOUBLE_EQ(hy::derivative(p, s, 0.0, 0.0, -3.0).spool,
                   (-1.0 - 0.2) / p.valve_time_constant);
}

TEST(HydraulicJointValve, OpeningFillsTheChamberOnTheSupplySideAndDrainsTheOther) {
  const Parameters p;
  const State open_positive{0.5, 8e6, 8e6};
  const State open_negative{-0.5, 8e6, 8e6};
  const State closed{0.0, 8e6, 3e6};
  EXPECT_GT(hy::derivative(p, open_positive, 0.0, 0.0, 0.5).pressure_a, 0);
  EXPECT_LT(hy::derivative(p, open_positive, 0.0, 0.0, 0.5).pressure_b, 0);
  EXPECT_LT(hy::derivative(p, open_negative, 0.0, 0.0, -0.5).pressure_a, 0);
  EXPECT_GT(hy::derivative(p, open_negative, 0.0, 0.0, -0.5).pressure_b, 0);
  // A closed valve and a still joint hold any pressures: the chambers are sealed.
  EXPECT_EQ(hy::derivative(p, closed, 0.1, 0.0, 0.0).pressure_a, 0);
  EXPECT_EQ(hy::derivative(p, closed, 0.1, 0.0, 0.0).pressure_b, 0);
}

// Valve closed, joint turning at a constant rate: each chamber's oil is compressed or expanded
// as dp = -beta dV / V, so p(t) = p(0) - beta ln(V(t) / V(0)). The ODE, integrated, must give it.
TEST(HydraulicJointChambers, ClosedValveFollowsTheCompressionLaw) {
  const Parameters p;
  const double omega = 1.0, duration = 0.02, h = 1e-6;  // rad/s, s, s
  State s{0.0, 10e6, 6e6};
  const State start = s;
  const double theta0 = -0.1;
  for (int i = 0; i < int(std::lround(duration / h)); ++i) {
    s = rk4_step(p, s, theta0 + omega * i * h, omega, 0.0, h);
  }
  const double theta1 = theta0 + omega * duration;
  // Volumes from the geometry, independently of the model's helpers.
  const auto va = [&](double th) {
    return p.dead_volume + p.area_a * (p.stroke / 2 + p.lever * th);
  };
  const auto vb = [&](double th) {
    return p.dead_volume + p.area_b * (p.stroke / 2 - p.lever * th);
  };
  const double expected_a = start.pressure_a - p.bulk_modulus * std::log(va(theta1) / va(theta0));
  const double expected_b = start.pressure_b - p.bulk_modulus * std::log(vb(theta1) / vb(theta0));
  EXPECT_NEAR(s.pressure_a, expected_a, 1e-6 * start.pressure_a);
  EXPECT_NEAR(s.pressure_b, expected_b, 1e-6 * start.pressure_b);
  // Turning forward expands the piston side and compresses the rod side.
  EXPECT_LT(s.pressure_a, start.pressure_a);
  EXPECT_GT(s.pressure_b, start.pressure_b);
}

// The natural velocity feedback: with the valve closed, the torque's rate is
// -r^2 beta (A_a^2 / V_a + A_b^2 / V_b) theta'. At mid-stroke that is about -5.2e3 N·m/s per
// rad/s: at 1 rad/s the torque falls ~31 N·m within one 6 ms control period, a quarter of the
// stall torque, which is why the joint controller must compensate it.
TEST(HydraulicJointChambers, LoadVelocityCouplingOpposesTheMotionWithItsSize) {
  const Parameters p;
  for (double theta : {-0.5, 0.0, 0.5}) {
    SCOPED_TRACE(theta);
    const State s{0.0, 8e6, 8e6};
    const double omega = 0.7;
    const State d = hy::derivative(p, s, theta, omega, 0.0);
    const double torque_rate = p.lever * (p.area_a * d.pressure_a - p.area_b * d.pressure_b);
    const double va = p.dead_volume + p.area_a * (p.stroke / 2 + p.lever * theta);
    const double vb = p.dead_volume + p.area_b * (p.stroke / 2 - p.lever * theta);
    const double expected = -p.lever * p.lever * p.bulk_modulus *
                            (p.area_a * p.area_a / va + p.area_b * p.area_b / vb) * omega;
    EXPECT_LT(torque_rate, 0);
    EXPECT_NEAR(torque_rate, expected, 1e-9 * std::abs(expected));
    EXPECT_NEAR(hy::load_velocity_coupling(p, theta) * omega, expected, 1e-9 * std::abs(expected));
  }
  EXPECT_NEAR(hy::load_velocity_coupling(p, 0.0), -5.24e3, 0.05e3);
}

// The pressure torque's rate, r (A_a dp_a/dt - A_b dp_b/dt), from the model's derivative.
double torque_rate(const Parameters& p, const State& s, double theta, double theta_dot) {
  const State d = hy::derivative(p, s, theta, theta_dot, s.spool);
  return p.lever * (p.area_a * d.pressure_a - p.area_b * d.pressure_b);
}

// The linearised gains against central differences of the model, at operating points on both
// sides of the valve's centre; and the cancellation load-velocity feedback relies on: a spool
// opened by (k_v / k_q) theta' more leaves the torque's rate what it was with the joint still.
TEST(HydraulicJointLinearisation, GainsMatchTheModelAndTheirRatioCancelsTheMotion) {
  const Parameters p;
  for (const State& s : {State{0.2, 9e6, 5e6}, State{-0.3, 6e6, 11e6}, State{0.0, 8e6, 8e6}}) {
    for (double theta : {-0.4, 0.3}) {
      SCOPED_TRACE(testing::Message() << "spool " << s.spool << " theta " << theta);
      const hy::TorqueRateGains<double> g = hy::torque_rate_gains(p, s, theta);
      const double h = 1e-4;
      State up = s, down = s;
      // Stay on the operating point's side of the centre: the flows are linear there.
      up.spool = s.spool >= 0 ? s.spool + 2 * h : s.spool;
      down.spool = s.spool >= 0 ? s.spool : s.spool - 2 * h;
      const double valve_slope =
          (torque_rate(p, up, theta, 0.0) - torque_rate(p, down, theta, 0.0)) / (2 * h);
      EXPECT_NEAR(g.valve, valve_slope, 1e-6 * g.valve);
      const double velocity_slope =
          (torque_rate(p, s, theta, 1e-3) - torque_rate(p, s, theta, -1e-3)) / 2e-3;
      EXPECT_NEAR(-g.load_velocity, velocity_slope, 1e-6 * g.load_velocity);
      EXPECT_GT(g.valve, 0);
      EXPECT_GT(g.load_velocity, 0);

      const double omega = 0.8;
      State compensated = s;
      compensated.spool = s.spool + g.load_velocity / g.valve * omega;
      if ((compensated.spool >= 0) != (s.spool >= 0)) continue;  // crossed the centre
      EXPECT_NEAR(torque_rate(p, compensated, theta, omega), torque_rate(p, s, theta, 0.0),
                  1e-6 * std::abs(g.load_velocity * omega));
    }
  }
}

// A blocked joint (held still) with the valve fully open settles with the supply on one side
// and the return on the other: its torque is then the stall torque, and the valve passes no
// more flow.
TEST(HydraulicJointSteadyState, BlockedJointSettlesAtSupplyAndReturnPressures) {
  const Parameters p;
  for (double u : {1.0, -1.0}) {
    SCOPED_TRACE(u);
    State s{0.0, 5e6, 5e6};
    for (int i = 0; i < 40000; ++i) s = rk4_step(p, s, 0.0, 0.0, u, 5e-6);  // 0.2 s
    const double high = u > 0 ? s.pressure_a : s.pressure_b;
    const double low = u > 0 ? s.pressure_b : s.pressure_a;
    EXPECT_NEAR(s.spool, u, 1e-9);
    EXPECT_NEAR(high, p.supply_pressure, 1e-4 * p.supply_pressure);
    EXPECT_NEAR(low, p.return_pressure, 1e-4 * p.supply_pressure);
    const double stall = u > 0 ? p.stall_torque_positive() : p.stall_torque_negative();
    EXPECT_NEAR(hy::joint_torque(p, s, 0.0), stall, 1e-3 * std::abs(stall));
  }
}

TEST(HydraulicJointTorque, FrictionOpposesTheJointsMotion) {
  const Parameters p;
  const State s{0.0, 9e6, 4e6};
  const double still = hy::joint_torque(p, s, 0.0);
  EXPECT_DOUBLE_EQ(still, p.lever * (p.area_a * s.pressure_a - p.area_b * s.pressure_b));
  EXPECT_LT(hy::joint_torque(p, s, 0.5), still);
  EXPECT_GT(hy::joint_torque(p, s, -0.5), still);
  // Well above the smoothing speed the Coulomb part is whole: r (F_c + b r theta').
  const double fast = 0.5;
  EXPECT_NEAR(still - hy::joint_torque(p, s, fast),
              p.lever * (p.coulomb_friction + p.viscous_friction * p.lever * fast), 1e-6);
}

// The Cortex-M4 board computes in float: the same model in float agrees with double.
TEST(HydraulicJointTorque, FloatAgreesWithDouble) {
  const hy::JointActuatorParameters<float> pf;
  const Parameters pd;
  const State sd{0.3, 9e6, 4e6};
  const hy::JointActuatorState<float> sf{0.3F, 9e6F, 4e6F};
  const State dd = hy::derivative(pd, sd, 0.2, 0.4, 0.6);
  const hy::JointActuatorState<float> df = hy::derivative(pf, sf, 0.2F, 0.4F, 0.6F);
  EXPECT_NEAR(df.spool, dd.spool, 1e-4 * std::abs(dd.spool));
  EXPECT_NEAR(df.pressure_a, dd.pressure_a, 1e-4 * std::abs(dd.pressure_a));
  EXPECT_NEAR(df.pressure_b, dd.pressure_b, 1e-4 * std::abs(dd.pressure_b));
  EXPECT_NEAR(hy::joint_torque(pf, sf, 0.4F), hy::joint_torque(pd, sd, 0.4), 1e-3);
}

// ---------------------------------------------------------------------------------------
// The torque loop's tuning procedure and the in-process pendulum.

// The no-load operating point: no net force, and equal flow per piston area through both
// lands (a spool just opened moves the piston without loading it).
TEST(HydraulicTorqueTuning, NoLoadOperatingPointBalancesForceAndFlow) {
  const Parameters p;
  const State s = hy::no_load_operating_point(p);
  EXPECT_NEAR(p.area_a * s.pressure_a - p.area_b * s.pressure_b, 0.0, 1e-9 * p.supply_pressure);
  EXPECT_NEAR((p.supply_pressure - s.pressure_a) / (p.area_a * p.area_a),
              s.pressure_b / (p.area_b * p.area_b),
              1e-6 * p.supply_pressure / (p.area_a * p.area_a));
}

TEST(HydraulicTorqueTuning, GainsFollowTheStatedProcedure) {
  const Parameters p;
  const auto k = hy::torque_rate_gains(p, hy::no_load_operating_point(p), 0.0);
  for (const double period : {0.006, 0.001}) {
    const auto g = hy::tune_torque_loop(p, period);
    const double crossover = (M_PI / 6) / (period / 2 + 0.001 + p.valve_time_constant);
    EXPECT_NEAR(g.kp * k.valve, crossover, 1e-9 * crossover) << period;
    EXPECT_NEAR(g.ki, g.kp * crossover / 5, 1e-12) << period;
    EXPECT_NEAR(g.k_lv, 0.9 * k.load_velocity / k.valve, 1e-12) << period;
  }
  // Constants believed 20 % higher: less gain, and a smaller load-velocity term.
  Parameters high = p;
  high.bulk_modulus *= 1.2;
  high.valve_flow_gain *= 1.2;
  EXPECT_LT(hy::tune_torque_loop(high, 0.006).kp, hy::tune_torque_loop(p, 0.006).kp);
  EXPECT_NEAR(hy::tune_torque_loop(high, 0.006).k_lv, hy::tune_torque_loop(p, 0.006).k_lv / 1.2,
              1e-9);
}

// The schedule is 1 at the no-load point, rises as the open land's pressure drop shrinks (the
// valve's flow gain k_q falls, the coupling does not) and stays within [0, 2].
TEST(HydraulicTorqueTuning, LoadVelocityScheduleFollowsTheOperatingPoint) {
  const Parameters p;
  const State nominal = hy::no_load_operating_point(p);
  const double ratio = hy::no_load_velocity_ratio(p);
  EXPECT_NEAR(hy::load_velocity_schedule(p, ratio, nominal, 0.0), 1.0, 1e-12);
  State loaded = nominal;
  loaded.pressure_a = 0.8 * p.supply_pressure;  // pushing hard: little drop across land a
  const double pushing = hy::load_velocity_schedule(p, ratio, loaded, 0.0);
  EXPECT_GT(pushing, 1.0);
  EXPECT_LE(pushing, 2.0);
  loaded.pressure_a = p.supply_pressure;  // no drop at all: k_q of land a vanishes
  loaded.pressure_b = 0;
  EXPECT_EQ(hy::load_velocity_schedule(p, ratio, loaded, 0.0), 2.0);
}

// The in-process pendulum: at rest hanging it stays; released it swings at sqrt(m g l / I)
// while the locked chambers hold the actuator (the oil spring is far stiffer than gravity's).
TEST(HydraulicPendulum, RestsHangingAndHoldsAReleasedLegOnTheOil) {
  const Parameters p;
  const auto load = hy::PendulumLoad<double>::leg();
  auto x = hy::torque_free_rest(p);
  for (int i = 0; i < 100; ++i) hy::step_pendulum(p, load, x, 0.0, 1e-3, 20);
  EXPECT_NEAR(x.theta, 0.0, 1e-9);
  auto lifted = hy::torque_free_rest(p);
  lifted.theta = 0.2;
  for (int i = 0; i < 500; ++i) hy::step_pendulum(p, load, lifted, 0.0, 1e-3, 20);
  // Gravity's 12.5 N·m on the oil's ~5e3 N·m/rad: a few milliradians of sag, no fall.
  EXPECT_NEAR(lifted.theta, 0.2, 0.01);
  EXPECT_LT(lifted.theta, 0.2);
}

}  // namespace
