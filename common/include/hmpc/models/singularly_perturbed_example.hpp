// The numerical example of thesis Sec. 2.4: a two-dimensional nonlinear singularly perturbed
// system (Eq. 2.37) with the regulator costs of Eqs. 2.38-2.40, as iLQR problems for the
// Fine / Coarse MPC (full model), the Slow-Fast MPC (slow subsystem, Eqs. 2.24-2.27) and the
// lower layer of both hierarchical MPCs (fast subsystem, Eqs. 2.29 and 2.31).
//
//   dy/dt       = -y + z - u1 - u2                      (h of Eq. 2.23)
//   eps * dz/dt = -y z - cos z - u1 + u2                (g of Eq. 2.23)
//
// Both inputs act on the fast state, so u^z = u and u^y is empty: nu = u - u_hat (Eq. 2.40).
#pragma once

#include <array>
#include <cmath>

#include "hmpc/solver/problem.hpp"

namespace hmpc::sec24 {

template <typename Scalar>
struct Parameters {
  Scalar epsilon = Scalar(0.1);  // Eq. 2.37
  Scalar y_desired = Scalar(1);  // x^d = [1.0, 2.0] (Sec. 2.4.1)
  Scalar z_desired = Scalar(2);
  Scalar q_y = Scalar(1);  // Q = diag(1.0, 1.0)
  Scalar q_z = Scalar(1);
  Scalar r = Scalar(0.01);  // R = R_nu = diag(0.01, 0.01)
};

template <typename Scalar>
using Vector2 = Eigen::Matrix<Scalar, 2, 1>;
template <typename Scalar>
using Matrix2 = Eigen::Matrix<Scalar, 2, 2>;

// g(y, z, u) of Eq. 2.37 (the fast right-hand side times epsilon).
template <typename Scalar>
Scalar fast_rate(Scalar y, Scalar z, const Vector2<Scalar>& u) {
  using std::cos;
  return -y * z - cos(z) - u(0) + u(1);
}

// dx/dt of Eq. 2.37 (f_d of Eq. 2.1).
template <typename Scalar>
Vector2<Scalar> vector_field(const Parameters<Scalar>& p, const Vector2<Scalar>& x,
                             const Vector2<Scalar>& u) {
  return Vector2<Scalar>(-x(0) + x(1) - u(0) - u(1), fast_rate(x(0), x(1), u) / p.epsilon);
}

// The plant: Eq. 2.37 integrated over one sampling period with classical RK4, input held.
template <typename Scalar>
Vector2<Scalar> integrate_plant(const Parameters<Scalar>& p, const Vector2<Scalar>& x,
                                const Vector2<Scalar>& u, Scalar dt) {
  const Vector2<Scalar> k1 = vector_field(p, x, u);
  const Vector2<Scalar> k2 = vector_field(p, Vector2<Scalar>(x + Scalar(0.5) * dt * k1), u);
  const Vector2<Scalar> k3 = vector_field(p, Vector2<Scalar>(x + Scalar(0.5) * dt * k2), u);
  const Vector2<Scalar> k4 = vector_field(p, Vector2<Scalar>(x + dt * k3), u);
  return x + dt / Scalar(6) * (k1 + Scalar(2) * k2 + Scalar(2) * k3 + k4);
}

// Stage cost of Eq. 2.38 / 2.39: (x - x^d)' Q (x - x^d) + u' R u.
template <typename Scalar>
Scalar regulator_cost(const Parameters<Scalar>& p, const Vector2<Scalar>& x,
                      const Vector2<Scalar>& u) {
  const Scalar ey = x(0) - p.y_desired;
  const Scalar ez = x(1) - p.z_desired;
  return p.q_y * ey * ey + p.q_z * ez * ez + p.r * u.squaredNorm();
}

// Full model, Euler-discretised with step dt (Eq. 2.1 / 2.34b): the Fine MPC with dt = 1 ms
// and the Coarse MPC / upper layer of the Coarse-Fast MPC with dt = Delta t_c = 10 ms.
template <typename Scalar>
class FullProblem : public ProblemBase<FullProblem<Scalar>, Scalar, 2, 2> {
  using Base = ProblemBase<FullProblem<Scalar>, Scalar, 2, 2>;

 public:
  using typename Base::Control;
  using typename Base::ControlJacobian;
  using typename Base::RunningDerivatives;
  using typename Base::State;
  using typename Base::StateJacobian;
  using typename Base::TerminalDerivatives;

  FullProblem(const Parameters<Scalar>& parameters, Scalar step) : p_(parameters), dt_(step) {}

  Scalar step() const { return dt_; }

  State dynamics(const State& x, const Control& u, int) const {
    return x + dt_ * vector_field(p_, x, u);
  }

  void dynamics_derivatives(const State& x, const Control&, int, StateJacobian& fx,
                            ControlJacobian& fu) const {
    using std::sin;
    const Scalar inv_eps = Scalar(1) / p_.epsilon;
    fx << Scalar(1) - dt_, dt_, -dt_ * inv_eps * x(1),
        Scalar(1) + dt_ * inv_eps * (-x(0) + sin(x(1)));
    fu << -dt_, -dt_, -dt_ * inv_eps, dt_ * inv_eps;
  }

  Scalar running_cost(const State& x, const Control& u, int) const {
    return regulator_cost(p_, x, u);
  }
  Scalar terminal_cost(const State& x, int) const {
    return regulator_cost(p_, x, Control(Control::Zero()));
  }

  void running_cost_derivatives(const State& x, const Control& u, int,
                                RunningDerivatives& d) const {
    d.lx = state_gradient(x);
    d.lu = Scalar(2) * p_.r * u;
    d.lxx = state_hessian();
    d.luu = Scalar(2) * p_.r * Matrix2<Scalar>::Identity();
    d.lux.setZero();
  }
  void terminal_cost_derivatives(const State& x, int, TerminalDerivatives& d) const {
    d.lx = state_gradient(x);
    d.lxx = state_hessian();
  }

 private:
  State state_gradient(const State& x) const {
    return State(Scalar(2) * p_.q_y * (x(0) - p_.y_desired),
                 Scalar(2) * p_.q_z * (x(1) - p_.z_desired));
  }
  StateJacobian state_hessian() const {
    return Vector2<Scalar>(Scalar(2) * p_.q_y, Scalar(2) * p_.q_z).asDiagonal();
  }

  Parameters<Scalar> p_;
  Scalar dt_;
};

// Slow subsystem, Eqs. 2.24-2.27: eps = 0, z replaced by the root z_hat of Eq. 2.25 found by
// Newton's method. Where Eq. 2.25 has no unique root (e.g. y = 0) the prediction is wrong:
// the failure mode the thesis reports for the Slow-Fast MPC. Derivatives are left to the
// finite-difference defaults of ProblemBase (the root has no closed form).
template <typename Scalar>
class SlowSubsystem : public ProblemBase<SlowSubsystem<Scalar>, Scalar, 1, 2> {
  using Base = ProblemBase<SlowSubsystem<Scalar>, Scalar, 1, 2>;

 public:
  using typename Base::Control;
  using typename Base::State;
  using FullState = Vector2<Scalar>;

  // Newton iterations for Eq. 2.25, from the desired fast state as initial guess.
  static constexpr int kNewtonIterations = 20;

  SlowSubsystem(const Parameters<Scalar>& parameters, Scalar step) : p_(parameters), dt_(step) {}

  // Eq. 2.26: z_hat = g_hat(y, u), the root of 0 = g(y, z, u) nearest the Newton path.
  Scalar fast_equilibrium(Scalar y, const Control& u) const {
    using std::abs;
    using std::sin;
    Scalar z = p_.z_desired;
    for (int i = 0; i < kNewtonIterations; ++i) {
      const Scalar slope = -y + sin(z);  // dg/dz
      if (abs(slope) < Scalar(1e-9)) break;
      const Scalar next = z - fast_rate(y, z, u) / slope;
      if (!std::isfinite(next)) break;
      z = next;
    }
    return z;
  }

  State slow_state(const FullState& x) const { return State(x(0)); }
  FullState full_state(const State& y, const Control& u) const {
    return FullState(y(0), fast_equilibrium(y(0), u));
  }

  // Eq. 2.30b with h_hat of Eq. 2.27.
  State dynamics(const State& y, const Control& u, int) const {
    const Scalar z = fast_equilibrium(y(0), u);
    return State(y(0) + dt_ * (-y(0) + z - u(0) - u(1)));
  }

  // J^s = J^c (Sec. 2.4.1) evaluated on [y; z_hat].
  Scalar running_cost(const State& y, const Control& u, int) const {
    return regulator_cost(p_, full_state(y, u), u);
  }
  Scalar terminal_cost(const State& y, int) const {
    return regulator_cost(p_, full_state(y, Control(Control::Zero())), Control(Control::Zero()));
  }

 private:
  Parameters<Scalar> p_;
  Scalar dt_;
};

// Fast subsystem, Eqs. 2.29 and 2.31b, for the lower layer with horizon NFast. The slow state
// y_hat, fast state z_hat and inputs u_hat are the upper plan held on the fine grid
// (Eq. 2.35). The state is zeta = z - z_hat; because z_hat is piecewise constant, zeta is
// re-referenced where z_hat steps, so the underlying z evolves continuously.
template <typename Scalar, int NFast>
class FastSubsystem : public ProblemBase<FastSubsystem<Scalar, NFast>, Scalar, 1, 2> {
  using Base = ProblemBase<FastSubsystem<Scalar, NFast>, Scalar, 1, 2>;

 public:
  using typename Base::Control;
  using typename Base::ControlJacobian;
  using typename Base::RunningDerivatives;
  using typename Base::State;
  using typename Base::StateJacobian;
  using typename Base::TerminalDerivatives;
  using FullState = Vector2<Scalar>;
  using FullControl = Vector2<Scalar>;

  FastSubsystem(const Parameters<Scalar>& parameters, Scalar fine_step)
      : p_(parameters), dt_(fine_step) {
    for (int j = 0; j <= NFast; ++j) set_reference(j, FullState::Zero(), FullControl::Zero());
  }

  void set_reference(int j, const FullState& x_hat, const FullControl& u_hat) {
    y_hat_[j] = x_hat(0);
    z_hat_[j] = x_hat(1);
    u_hat_[j] = u_hat;
  }
  State deviation(const FullState& x) const { return State(x(1) - z_hat_[0]); }
  FullControl compose(const FullControl& u_hat, const Control& nu) const { return u_hat + nu; }

  // Eq. 2.31b: zeta_{j+1} = zeta_j + (Delta t_f / eps) g(y_hat_j, zeta_j + z_hat_j, u_hat_j +
  // nu_j).
  State dynamics(const State& zeta, const Control& nu, int j) const {
    const Scalar z = zeta(0) + z_hat_[j];
    const Scalar z_next =
        z + dt_ / p_.epsilon * fast_rate(y_hat_[j], z, FullControl(u_hat_[j] + nu));
    return State(z_next - z_hat_[j + 1]);
  }

  void dynamics_derivatives(const State& zeta, const Control&, int j, StateJacobian& fx,
                            ControlJacobian& fu) const {
    using std::sin;
    const Scalar z = zeta(0) + z_hat_[j];
    const Scalar gain = dt_ / p_.epsilon;
    fx(0, 0) = Scalar(1) + gain * (-y_hat_[j] + sin(z));
    fu << -gain, gain;
  }

  // Eq. 2.40: (x - x^d)' Q (x - x^d) + nu' R_nu nu with x = [y_hat; z_hat + zeta].
  Scalar running_cost(const State& zeta, const Control& nu, int j) const {
    return regulator_cost(p_, full(zeta, j), nu);
  }
  Scalar terminal_cost(const State& zeta, int) const {
    return regulator_cost(p_, full(zeta, NFast), Control(Control::Zero()));
  }
  void running_cost_derivatives(const State& zeta, const Control& nu, int j,
                                RunningDerivatives& d) const {
    d.lx(0) = Scalar(2) * p_.q_z * (zeta(0) + z_hat_[j] - p_.z_desired);
    d.lu = Scalar(2) * p_.r * nu;
    d.lxx(0, 0) = Scalar(2) * p_.q_z;
    d.luu = Scalar(2) * p_.r * Matrix2<Scalar>::Identity();
    d.lux.setZero();
  }
  void terminal_cost_derivatives(const State& zeta, int, TerminalDerivatives& d) const {
    d.lx(0) = Scalar(2) * p_.q_z * (zeta(0) + z_hat_[NFast] - p_.z_desired);
    d.lxx(0, 0) = Scalar(2) * p_.q_z;
  }

 private:
  FullState full(const State& zeta, int j) const {
    return FullState(y_hat_[j], zeta(0) + z_hat_[j]);
  }

  Parameters<Scalar> p_;
  Scalar dt_;
  std::array<Scalar, NFast + 1> y_hat_{};
  std::array<Scalar, NFast + 1> z_hat_{};
  std::array<FullControl, NFast + 1> u_hat_{};
};

}  // namespace hmpc::sec24
