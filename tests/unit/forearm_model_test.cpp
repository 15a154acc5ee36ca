// The forearm model of thesis Eq. 3.1, its problems (Eq. 3.3) and the fast subsystem of
// Eq. 3.2: analytic derivatives against finite differences, and the reduction as stated.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <complex>
#include <random>

#include "hmpc/models/forearm_disturbance.hpp"
#include "hmpc/models/forearm_mpc.hpp"
#include "hmpc/models/forearm_tracking_limit.hpp"
#include "hmpc/solver/finite_difference.hpp"

namespace {

using namespace hmpc::forearm;
using V3 = Eigen::Vector3d;
using V2 = Eigen::Vector2d;
constexpr double kDeg = M_PI / 180.0;

struct Fixture : ::testing::Test {
  Parameters<double> p;
  CostWeights<double> w;
  TargetTrajectory<double> target;
  std::mt19937 rng{7};
  Fixture() { target.set_sinusoid(30 * kDeg, 0.5, 0.0, 0.0); }
  double uniform(double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(rng);
  }
  V3 random_state() { return V3(uniform(-60 * kDeg, 80 * kDeg), uniform(-4, 4), uniform(0.1, 5)); }
  V2 random_input() { return V2(uniform(-5, 5), uniform(0, 5)); }
};

TEST_F(Fixture, PamTorquePartialsMatchFiniteDifferences) {
  for (int i = 0; i < 50; ++i) {
    const double P = uniform(0.1, 5), th = uniform(-1, 1.4), h = 1e-6;
    const auto t = pam_torque(p, P, th);
    EXPECT_NEAR(t.d_pressure,
                (pam_torque(p, P + h, th).tau - pam_torque(p, P - h, th).tau) / (2 * h), 1e-5);
    EXPECT_NEAR(t.d_theta, (pam_torque(p, P, th + h).tau - pam_torque(p, P, th - h).tau) / (2 * h),
                1e-5);
    EXPECT_NEAR(t.d_theta_theta,
                (pam_torque(p, P, th + h).d_theta - pam_torque(p, P, th - h).d_theta) / (2 * h),
                1e-4);
    EXPECT_NEAR(t.d_theta_pressure,
                (pam_torque(p, P + h, th).d_theta - pam_torque(p, P - h, th).d_theta) / (2 * h),
                1e-4);
  }
}

TEST_F(Fixture, PamIsStrongAndSlowMotorWeakAndFast) {
  // Strong: at full pressure the PAM lifts the arm with margin at every angle of the task.
  for (double th : {-30 * kDeg, 0.0, 30 * kDeg}) {
    const double gravity = p.mass * p.gravity * p.com_distance * std::cos(th);
    EXPECT_GT(pam_torque(p, 5.0, th).tau, 2.5 * gravity);
    EXPECT_GT(pam_torque(p, 5.0, th).tau, 10 * p.motor_gain * p.v_m_max);
  }
  // Slow: pressure time constant T_p / k_vp of 150 ms, far above the 4 ms control period.
  EXPECT_NEAR(p.T_p / p.k_vp, 0.15, 1e-12);
  // The equilibrium pressure holds the arm: zero acceleration at rest.
  const double P = equilibrium_pressure(p, 0.2);
  EXPECT_NEAR(joint_acceleration(p, 0.2, 0.0, P, 0.0).value, 0.0, 1e-9);
  EXPECT_GT(P, 1.0);
  EXPECT_LT(P, 2.5);
}

TEST_F(Fixture, FullProblemDynamicsJacobiansMatchFiniteDifferences) {
  for (double step : {kFine4Step, kCoarse40Step}) {
    ForearmProblem<double> problem(p, w, step, &target);
    for (int i = 0; i < 50; ++i) {
      problem.set_offset_free({i % 2 == 1, uniform(-2, 2)});
      const V3 x = random_state();
      const V2 u = random_input();
      Eigen::Matrix3d A, A_fd;
      Eigen::Matrix<double, 3, 2> B, B_fd;
      problem.dynamics_derivatives(x, u, 0, A, B);
      hmpc::central_difference_jacobian([&](const V3& xp) { return problem.dynamics(xp, u, 0); }, x,
                                        A_fd);
      hmpc::central_difference_jacobian([&](const V2& up) { return problem.dynamics(x, up, 0); }, u,
                                        B_fd);
      EXPECT_LT((A - A_fd).norm(), 1e-7 * (1 + A.norm()));
      EXPECT_LT((B - B_fd).norm(), 1e-7 * (1 + B.norm()));
    }
  }
}

// Every other case offset-free, with a disturbance estimate in the model and the torque
// penalty counted beyond the holding torque.
TEST_F(Fixture, CostGradientsMatchFiniteDifferencesAndHessianIsPsd) {
  ForearmProblem<double> problem(p, w, kCoarse20Step, &target);
  problem.set_start_time(0.3);
  for (int i = 0; i < 50; ++i) {
    problem.set_offset_free({i % 2 == 1, uniform(-2, 2)});
    problem.set_terminal_rate_time(i % 3 == 0 ? 0.2 : 0.0);
    const V3 x = random_state();
    const V2 u = random_input();
    const int k = i % 10;
    ForearmProblem<double>::RunningDerivatives d;
    problem.running_cost_derivatives(x, u, k, d);
    V3 gx;
    V2 gu;
    Eigen::Matrix3d hxx_unused;
    Eigen::Matrix2d huu_unused;
    hmpc::central_difference_gradient_hessian(
        [&](const V3& xp) { return problem.running_cost(xp, u, k); }, x, gx, hxx_unused);
    hmpc::central_difference_gradient_hessian(
        [&](const V2& up) { return problem.running_cost(x, up, k); }, u, gu, huu_unused);
    EXPECT_LT((d.lx - gx).norm(), 1e-4 * (1 + gx.norm()));
    EXPECT_LT((d.lu - gu).norm(), 1e-4 * (1 + gu.norm()));
    // Gauss-Newton Hessian of the torque term: positive semi-definite by construction.
    Eigen::Matrix<double, 5, 5> H = Eigen::Matrix<double, 5, 5>::Zero();
    H.topLeftCorner<3, 3>() = d.lxx;
    H.bottomRightCorner<2, 2>() = d.luu;
    using Solver = Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 5, 5>>;
    EXPECT_GE(Solver(H).eigenvalues().minCoeff(), -1e-9);
    ForearmProblem<double>::TerminalDerivatives t;
    problem.terminal_cost_derivatives(x, 10, t);
    V3 gt;
    hmpc::central_difference_gradient_hessian(
        [&](const V3& xp) { return problem.terminal_cost(xp, 10); }, x, gt, hxx_unused);
    EXPECT_LT((t.lx - gt).norm(), 1e-4 * (1 + gt.norm()));
    EXPECT_LT((t.lxx - hxx_unused).norm(), 1e-2 * (1 + t.lxx.norm()));  // exact without torque
  }
}

TEST_F(Fixture, SmoothMinPenalisesOnlyLowPressure) {
  // Eq. 3.4: smin(a, 0) ~ min(a, 0) away from 0, smooth across it.
  EXPECT_NEAR(smin_zero(2.0, w.gamma).value, 0.0, 2e-3);
  EXPECT_NEAR(smin_zero(-2.0, w.gamma).value, -2.0, 2e-3);
  EXPECT_NEAR(smin_zero(0.0, w.gamma).value, -w.gamma / 2, 1e-12);
}

using Fast = ForearmFastSubsystem<double, kTwoStageFineHorizon>;

// Holds a coarse plan on the fine grid (Eq. 2.35) from a rollout of the full model.
void hold_rollout_as_reference(const Parameters<double>& p, const CostWeights<double>& w,
                               const TargetTrajectory<double>& target, Fast& fast, const V3& x0,
                               const V2& u, std::vector<V3>* rollout) {
  ForearmProblem<double> fine_full(p, w, kTwoStageFineStep, &target);
  V3 x = x0;
  for (int j = 0; j <= kTwoStageFineHorizon; ++j) {
    fast.set_reference(j, x, u);
    if (rollout) rollout->push_back(x);
    x = fine_full.dynamics(x, u, j);
  }
}

TEST_F(Fixture, FastSubsystemReducesAsEquation32States) {
  Fast fast(p, w, kTwoStageFineStep, &target);
  // At constant pressure (v_p = k_vp P: Eq. 3.2a holds exactly) the fast subsystem with nu = 0
  // around the full model's own trajectory stays at zeta = 0: Eq. 3.2b is the joint row of
  // Eq. 3.1 with P frozen.
  const V3 x0(0.1, 0.5, 1.8);
  const V2 u(1.0, p.k_vp * 1.8);
  hold_rollout_as_reference(p, w, target, fast, x0, u, nullptr);
  Fast::State zeta = fast.deviation(x0);
  EXPECT_EQ(zeta.norm(), 0.0);
  for (int j = 0; j < kTwoStageFineHorizon; ++j) {
    zeta = fast.dynamics(zeta, Fast::Control::Zero(), j);
    EXPECT_LT(zeta.norm(), 1e-12) << "step " << j;
  }
  // Only the motor acts on the fast states: the input Jacobian is the full model's v_m column.
  ForearmProblem<double> full(p, w, kTwoStageFineStep, &target);
  Eigen::Matrix3d A;
  Eigen::Matrix<double, 3, 2> B;
  full.dynamics_derivatives(x0, u, 0, A, B);
  Fast::StateJacobian fx;
  Fast::ControlJacobian fu;
  fast.dynamics_derivatives(Fast::State::Zero(), Fast::Control::Zero(), 0, fx, fu);
  EXPECT_LT((fu - B.topLeftCorner<2, 1>()).norm(), 1e-12);
  EXPECT_LT((fx - A.topLeftCorner<2, 2>()).norm(), 1e-12);
  // Composition (Eq. 2.36): nu refines v_m only; v_p is the coarse plan's.
  const Fast::FullControl composed = fast.compose(u, Fast::Control(0.7));
  EXPECT_DOUBLE_EQ(composed(0), u(0) + 0.7);
  EXPECT_DOUBLE_EQ(composed(1), u(1));
}

TEST_F(Fixture, FastSubsystemDerivativesMatchFiniteDifferences) {
  Fast fast(p, w, kTwoStageFineStep, &target);
  hold_rollout_as_reference(p, w, target, fast, V3(0.2, -1.0, 2.2), V2(-2.0, 3.0), nullptr);
  for (int i = 0; i < 30; ++i) {
    fast.set_offset_free({i % 2 == 1, uniform(-2, 2)});
    const Fast::State zeta(uniform(-0.2, 0.2), uniform(-1, 1));
    const Fast::Control nu(uniform(-3, 3));
    const int j = i % kTwoStageFineHorizon;
    Fast::StateJacobian fx, fx_fd;
    Fast::ControlJacobian fu, fu_fd;
    fast.dynamics_derivatives(zeta, nu, j, fx, fu);
    hmpc::central_difference_jacobian([&](const Fast::State& z) { return fast.dynamics(z, nu, j); },
                                      zeta, fx_fd);
    hmpc::central_difference_jacobian(
        [&](const Fast::Control& n) { return fast.dynamics(zeta, n, j); }, nu, fu_fd);
    EXPECT_LT((fx - fx_fd).norm(), 1e-7);
    EXPECT_LT((fu - fu_fd).norm(), 1e-7);
    Fast::RunningDerivatives d;
    fast.running_cost_derivatives(zeta, nu, j, d);
    Eigen::Vector2d g;
    Eigen::Matrix2d unused;
    hmpc::central_difference_gradient_hessian(
        [&](const Fast::State& z) { return fast.running_cost(z, nu, j); }, zeta, g, unused);
    EXPECT_LT((d.lx - g).norm(), 1e-4 * (1 + g.norm()));
    // The terminal cost, with the terminal rate term on every other sample: squares of affine
    // functions of zeta (the pressure is frozen), so its Hessian is exact too.
    fast.set_terminal_rate_time(i % 2 == 0 ? kTwoStageTerminalRate.second_stage : 0.0);
    Fast::TerminalDerivatives t;
    fast.terminal_cost_derivatives(zeta, kTwoStageFineHorizon, t);
    Eigen::Matrix2d h;
    hmpc::central_difference_gradient_hessian(
        [&](const Fast::State& z) { return fast.terminal_cost(z, kTwoStageFineHorizon); }, zeta, g,
        h);
    EXPECT_LT((t.lx - g).norm(), 1e-5 * (1 + g.norm()));
    EXPECT_LT((t.lxx - h).norm(), 1e-3 * (1 + h.norm()));
  }
  // The composed motor input stays in -5..5 V through the bounds on nu.
  EXPECT_DOUBLE_EQ(fast.control_lower_bound(0)(0), -5.0 - (-2.0));
  EXPECT_DOUBLE_EQ(fast.control_upper_bound(0)(0), 5.0 - (-2.0));
}

// The momentum observer on a plant 30 % heavier than the model, valve held at the model's
// equilibrium for the horizontal: the arm sinks to where the PAM holds the real weight, and the
// estimate converges to the torque the model misses there, -0.3 m g l cos(theta). With the rate
// sensor's noise (0.01 rad/s, as the HIL plant's) the estimate's noise is K I 0.01: the
// observer passes the rate straight through its gain.
TEST_F(Fixture, DisturbanceObserverFindsTheTorqueTheModelMisses) {
  using Observer = DisturbanceObserver<double>;
  Parameters<double> plant = p;
  plant.mass *= 1.3;
  const Observer::Config config{};
  Observer::State state;
  std::normal_distribution<double> noise(0.0, 0.01);
  V3 x(0, 0, equilibrium_pressure(p, 0.0));
  const V2 u(0.0, p.k_vp * x(2));
  double sum = 0, sum_squares = 0;
  int n = 0;
  for (int k = 0; k < 10000; ++k) {  // 10 s at 1 ms
    const double estimate = Observer::update(p, config, state, x(0),
                                             x(1) + (k >= 8000 ? noise(rng) : 0), x(2), u(0), 1e-3);
    if (k == 7999) {
      const double missed = -0.3 * p.mass * p.gravity * p.com_distance * std::cos(x(0));
      EXPECT_LT(std::abs(x(1)), 1e-6);  // at rest
      EXPECT_NEAR(estimate, missed, 1e-4) << "theta " << x(0);
    }
    if (k >= 8000) {
      sum += estimate;
      sum_squares += estimate * estimate;
      ++n;
    }
    x = integrate(plant, x, u, 1e-3);
  }
  const double mean = sum / n, spread = std::sqrt(sum_squares / n - mean * mean);
  const double expected = config.bandwidth * p.inertia() * 0.01;
  EXPECT_GT(spread, 0.5 * expected);
  EXPECT_LT(spread, 1.5 * expected);
  // A reset forgets: the first sample after it only records the momentum.
  Observer::reset(state);
  EXPECT_EQ(Observer::update(p, config, state, x(0), x(1), x(2), u(0), 1e-3), 0.0);
}

// The first-harmonic tracking limit against Eq. 3.1 itself: driven open loop by the inputs the
// bound assumes (the valve's rectangle between its limits about the holding voltage, the motor's
// +-5 V square wave in phase with the PAM's torque), from the linearised periodic state so that
// the lightly damped free response (0.7 Hz) is hardly excited, the RK4 plant swings the joint by
// the bound's amplitude. Open loop, nothing holds the swing's centre: the mean of gravity's and
// the muscle's torque over a swing differs from their value at the centre, and over a swing
// above ~15 deg the arm drifts off, so the check runs where the limit is 6-10 deg. There the
// centre still drifts by 2-5 deg, which changes the muscle's force per bar by a few per cent:
// 10 % tolerance. The swing's fundamental is read over the last 5 periods of 20 s.
TEST_F(Fixture, TrackingLimitIsTheSwingTheExtremeInputsMake) {
  for (const double f : {2.5, 3.0}) {
    const TrackingLimit limit = tracking_limit(p, f, 30 * kDeg, 0.0);
    const double w = 2 * M_PI * f, lag = std::atan2(w * p.T_p, p.k_vp);
    const double hold = equilibrium_pressure(p, 0.0);
    const PamTorque<double> pam = pam_torque(p, hold, 0.0);
    // Linearised periodic state: torque U sin(w t - lag), joint U / Z with
    // Z = -(I w^2 + K) + j w b.
    const std::complex<double> z(-p.inertia() * w * w - pam.d_theta, w * p.viscous_friction);
    const double swing_linear = (limit.pam_torque + limit.motor_torque) / std::abs(z);
    const double phase0 = -lag - std::arg(z);
    V3 x(swing_linear * std::sin(phase0), w * swing_linear * std::cos(phase0),
         hold + limit.pam_torque / pam.d_pressure * std::sin(-lag));
    const double half_width = M_PI * p.k_vp * hold / (p.v_p_max - p.v_p_min);  // pi d
    const double dt = 2e-4;
    const int steps = static_cast<int>(20.0 / dt), window = static_cast<int>(5 / f / dt);
    double in_phase = 0, quadrature = 0;
    for (int k = 0; k < steps; ++k) {
      const double phase = w * k * dt;
      const double from_crest = std::remainder(phase - M_PI / 2, 2 * M_PI);
      const V2 u(std::sin(phase - lag) >= 0 ? p.v_m_max : p.v_m_min,
                 std::abs(from_crest) <= half_width ? p.v_p_max : p.v_p_min);
      x = integrate(p, x, u, dt);
      if (k >= steps - window) {
        in_phase += x(0) * std::sin(w * (k + 1) * dt);
        quadrature += x(0) * std::cos(w * (k + 1) * dt);
      }
    }
    const double swing = 2 * std::hypot(in_phase, quadrature) / window;
    EXPECT_NEAR(swing, limit.max_amplitude, 0.1 * limit.max_amplitude) << f << " Hz";
    EXPECT_NEAR(limit.rms_error_floor, (30 * kDeg - limit.max_amplitude) / std::sqrt(2.0), 1e-12);
  }
  // A faster valve reaches further; a target inside the limit has no floor.
  Parameters<double> faster = p;
  faster.T_p /= 2;
  EXPECT_GT(tracking_limit(faster, 1.8, 0.0, 0.0).max_amplitude,
            tracking_limit(p, 1.8, 0.0, 0.0).max_amplitude);
  EXPECT_EQ(tracking_limit(p, 0.5, 30 * kDeg, 0.0).rms_error_floor, 0.0);
}

TEST(ForearmTarget, SinusoidAndSamples) {
  TargetTrajectory<double> t;
  t.set_sinusoid(0.5, 1.0, 0.1, 0.0);
  EXPECT_NEAR(t.angle(0.25), 0.6, 1e-12);
  EXPECT_TRUE(t.push_sample(1.0, 0.2));
  EXPECT_TRUE(t.push_sample(2.0, 0.4));
  EXPECT_FALSE(t.push_sample(2.0, 0.5)) << "times must increase";
  EXPECT_FALSE(t.push_sample(3.0, std::nan(""))) << "non-finite samples are dropped";
  EXPECT_NEAR(t.angle(1.5), 0.3, 1e-12);
  EXPECT_NEAR(t.angle(0.0), 0.2, 1e-12) << "held before the first sample";
  EXPECT_NEAR(t.angle(9.0), 0.4, 1e-12) << "held after the last sample";
  for (int i = 0; i < 300; ++i) t.push_sample(3.0 + i, i);
  EXPECT_EQ(t.sample_count(), TargetTrajectory<double>::kCapacity);
  EXPECT_NEAR(t.angle(301.5), 298.5, 1e-9);
}

// theta_d' is the derivative of theta_d: the sinusoid's against central differences, the
// samples' the slope of the segment, 0 where the ends are held.
TEST(ForearmTarget, RateIsTheDerivativeOfTheAngle) {
  TargetTrajectory<double> t;
  t.set_sinusoid(0.5, 1.8, 0.1, 0.3);
  for (double time : {0.0, 0.1, 0.37, 1.2}) {
    const double fd = (t.angle(time + 1e-6) - t.angle(time - 1e-6)) / 2e-6;
    EXPECT_NEAR(t.rate(time), fd, 1e-6 * (1 + std::abs(fd))) << "t = " << time;
  }
  EXPECT_EQ(t.rate(0.0), 0.5 * 2 * M_PI * 1.8 * std::cos(2 * M_PI * 1.8 * -0.3));
  t.push_sample(1.0, 0.2);
  EXPECT_EQ(t.rate(1.0), 0.0) << "one sample: held";
  t.push_sample(2.0, 0.4);
  t.push_sample(2.5, 0.3);
  EXPECT_NEAR(t.rate(1.0), 0.2, 1e-12);
  EXPECT_NEAR(t.rate(1.99), 0.2, 1e-12);
  EXPECT_NEAR(t.rate(2.0), -0.2, 1e-12);
  EXPECT_EQ(t.rate(0.5), 0.0) << "held before the first sample";
  EXPECT_EQ(t.rate(2.5), 0.0) << "held from the last sample on";
}

// The terminal rate term prices the rate error at the horizon's end as w_theta prices an angle
// error T_v later, and nothing else: on the target's rate it adds nothing.
TEST_F(Fixture, TerminalRateTermPricesTheRateErrorOnly) {
  Fast thesis(p, w, kTwoStageFineStep, &target);
  Fast rate(p, w, kTwoStageFineStep, &target);
  rate.set_terminal_rate_time(0.4);
  EXPECT_EQ(thesis.terminal_rate_time(), 0.0) << "the thesis's cost by default";
  const V3 x0(0.2, -1.0, 2.2);
  hold_rollout_as_reference(p, w, target, thesis, x0, V2(-2.0, 3.0), nullptr);
  std::vector<V3> rollout;
  hold_rollout_as_reference(p, w, target, rate, x0, V2(-2.0, 3.0), &rollout);
  const int n = kTwoStageFineHorizon;
  const double target_rate = target.rate(n * kTwoStageFineStep);
  const Fast::State on_rate(0.05, target_rate - rollout[n](1));
  EXPECT_NEAR(rate.terminal_cost(on_rate, n), thesis.terminal_cost(on_rate, n), 1e-12);
  const Fast::State off_rate(0.05, on_rate(1) + 0.5);
  EXPECT_NEAR(rate.terminal_cost(off_rate, n) - thesis.terminal_cost(off_rate, n),
              w.w_theta * (0.4 * 0.5) * (0.4 * 0.5), 1e-9);
  EXPECT_EQ(rate.running_cost(off_rate, Fast::Control(0.3), 3),
            thesis.running_cost(off_rate, Fast::Control(0.3), 3))
      << "the running cost stays Eq. 3.3a";
}

}  // namespace
