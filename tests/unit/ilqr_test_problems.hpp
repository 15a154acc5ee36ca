// Problems the iLQR tests share: a random linear-quadratic problem with its Riccati solution,
// and a torque-limited pendulum.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <limits>
#include <random>

#include "hmpc/solver/ilqr.hpp"

namespace ilqr_test {

constexpr int kNx = 4;
constexpr int kNu = 2;
constexpr int kN = 30;
using Vx = Eigen::Matrix<double, kNx, 1>;
using Vu = Eigen::Matrix<double, kNu, 1>;
using Mxx = Eigen::Matrix<double, kNx, kNx>;
using Mxu = Eigen::Matrix<double, kNx, kNu>;
using Muu = Eigen::Matrix<double, kNu, kNu>;
using Mux = Eigen::Matrix<double, kNu, kNx>;

struct LqData {
  Mxx A, Q, Qf;
  Mxu B;
  Muu R;
  Vu lower = Vu::Constant(-std::numeric_limits<double>::infinity());
  Vu upper = Vu::Constant(std::numeric_limits<double>::infinity());
};

inline LqData random_lq(unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  LqData d;
  for (int i = 0; i < kNx; ++i)
    for (int j = 0; j < kNx; ++j) d.A(i, j) = (i == j ? 1.0 : 0.0) + 0.15 * n(rng);
  for (int i = 0; i < kNx; ++i)
    for (int j = 0; j < kNu; ++j) d.B(i, j) = 0.5 * n(rng);
  Mxx L;
  for (int i = 0; i < kNx; ++i)
    for (int j = 0; j < kNx; ++j) L(i, j) = n(rng);
  d.Q = L * L.transpose() * 0.1 + Mxx::Identity();
  d.Qf = 5.0 * d.Q;
  d.R = Muu::Identity() * 0.3;
  d.R(0, 1) = d.R(1, 0) = 0.05;
  return d;
}


// Linear dynamics, quadratic cost; a derived problem chooses how it gives the derivatives.
template <class Self>
class LqBase : public hmpc::ProblemBase<Self, double, kNx, kNu> {
 public:
  explicit LqBase(const LqData& d) : d_(d) {}
  Vx dynamics(const Vx& x, const Vu& u, int) const { return d_.A * x + d_.B * u; }
  double running_cost(const Vx& x, const Vu& u, int) const {
    return 0.5 * x.dot(d_.Q * x) + 0.5 * u.dot(d_.R * u);
  }
  double terminal_cost(const Vx& x, int) const { return 0.5 * x.dot(d_.Qf * x); }
  Vu control_lower_bound(int) const { return d_.lower; }
  Vu control_upper_bound(int) const { return d_.upper; }

 protected:
  const LqData& d_;
};

// Finite-horizon discrete Riccati recursion: u_t = K_t x_t.
struct RiccatiSolution {
  std::array<Mux, kN> K;
  std::array<Vu, kN> u;
  std::array<Vx, kN + 1> x;
};
inline RiccatiSolution riccati(const LqData& d, const Vx& x0) {
  RiccatiSolution s;
  Mxx P = d.Qf;
  for (int t = kN - 1; t >= 0; --t) {
    const Muu H = d.R + d.B.transpose() * P * d.B;
    s.K[t] = -H.ldlt().solve(d.B.transpose() * P * d.A);
    P = d.Q + d.A.transpose() * P * (d.A + d.B * s.K[t]);
    P = 0.5 * (P + P.transpose()).eval();
  }
  s.x[0] = x0;
  for (int t = 0; t < kN; ++t) {
    s.u[t] = s.K[t] * s.x[t];
    s.x[t + 1] = d.A * s.x[t] + d.B * s.u[t];
  }
  return s;
}

inline hmpc::IlqrConfig<double> exact_newton_config() {
  hmpc::IlqrConfig<double> c;
  c.regularization_init = 0;  // plain Newton: one step solves an LQR problem exactly
  c.tolerance = 1e-12;
  return c;
}


// Torque-limited pendulum: theta'' = -(g/l) sin(theta) - b theta' + u / (m l^2).
class Pendulum : public hmpc::ProblemBase<Pendulum, double, 2, 1> {
 public:
  static constexpr double kDt = 0.05, kG = 9.81, kL = 1.0, kM = 1.0, kB = 0.1;
  double torque_limit = 2.0;  // below m g l: a swing-up needs pumping
  State dynamics(const State& x, const Control& u, int) const {
    const double acc = -kG / kL * std::sin(x(0)) - kB * x(1) + u(0) / (kM * kL * kL);
    return State(x(0) + kDt * x(1), x(1) + kDt * acc);
  }
  void dynamics_derivatives(const State& x, const Control&, int, StateJacobian& fx,
                            ControlJacobian& fu) const {
    fx << 1.0, kDt, -kDt * kG / kL * std::cos(x(0)), 1.0 - kDt * kB;
    fu << 0.0, kDt / (kM * kL * kL);
  }
  double running_cost(const State& x, const Control& u, int) const {
    return 0.01 * u.squaredNorm() + 0.001 * goal_error(x);
  }
  double terminal_cost(const State& x, int) const { return 100.0 * goal_error(x); }
  Control control_lower_bound(int) const { return Control(-torque_limit); }
  Control control_upper_bound(int) const { return Control(torque_limit); }

 private:
  static double goal_error(const State& x) {
    return (x(0) - M_PI) * (x(0) - M_PI) + 0.1 * x(1) * x(1);
  }
};

}  // namespace ilqr_test
