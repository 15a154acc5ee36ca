// Optimal control problem interface for the iLQR solver (thesis Sec. 2.2).
//
// A problem is a plain type derived from ProblemBase (CRTP, so no virtual dispatch in the
// hot path). It must define
//   State  dynamics(const State& x, const Control& u, int t) const;      // Eq. 2.1
//   Scalar running_cost(const State& x, const Control& u, int t) const;  // l(x, u), Eq. 2.2
//   Scalar terminal_cost(const State& x, int t) const;                   // l_T(x), Eq. 2.2
// and may define, by hiding the defaults below,
//   dynamics_derivatives, running_cost_derivatives, terminal_cost_derivatives (analytic),
//   control_lower_bound(t), control_upper_bound(t) (box limits at step t; default: none),
//   control_change_weight() and previous_control() (a penalty on the change of the inputs,
//   sum_t (u_t - u_{t-1})' diag(w) (u_t - u_{t-1}) with u_{-1} = previous_control(), the input
//   applied last; it ties consecutive steps, so the solver adds it itself, exactly (ilqr.hpp);
//   default: w = 0, off),
//   for_each_step(count, linearize) (how the solver's N independent per-step linearisations
//   run; default: in order on the calling thread. A host problem may spread them over
//   threads: each call linearize(t) writes only step t's outputs, and the problem's
//   derivative functions must then be safe to call concurrently for different t).
//   kRolloutLanes, rollout_lanes(), rollout_dynamics(x, u, t, lane) and
//   for_each_rollout(count, rollout) (how many line-search rollouts may run at once: at
//   most kRolloutLanes, which sizes the solver's candidate buffers, and rollout_lanes() now;
//   and where; default: one lane, dynamics(), on the calling thread. A host problem with
//   several lanes gives each lane its own workspace, so that rollout_dynamics for different
//   lanes and the cost functions may run concurrently; rollout_dynamics must return exactly
//   what dynamics() does).
// The defaults differentiate numerically, so a model supplies either analytic or
// finite-difference derivatives simply by defining a function or not.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <limits>

#include "hmpc/solver/finite_difference.hpp"

namespace hmpc {

template <typename Scalar, int Nx, int Nu>
struct RunningCostDerivatives {
  Eigen::Matrix<Scalar, Nx, 1> lx;
  Eigen::Matrix<Scalar, Nu, 1> lu;
  Eigen::Matrix<Scalar, Nx, Nx> lxx;
  Eigen::Matrix<Scalar, Nu, Nu> luu;
  Eigen::Matrix<Scalar, Nu, Nx> lux;
};

template <typename Scalar, int Nx>
struct TerminalCostDerivatives {
  Eigen::Matrix<Scalar, Nx, 1> lx;
  Eigen::Matrix<Scalar, Nx, Nx> lxx;
};

template <class Derived, typename ScalarT, int Nx, int Nu>
class ProblemBase {
 public:
  using Scalar = ScalarT;
  static constexpr int kStateDim = Nx;
  static constexpr int kControlDim = Nu;
  using State = Eigen::Matrix<Scalar, Nx, 1>;
  using Control = Eigen::Matrix<Scalar, Nu, 1>;
  using StateJacobian = Eigen::Matrix<Scalar, Nx, Nx>;    // f_x
  using ControlJacobian = Eigen::Matrix<Scalar, Nx, Nu>;  // f_u
  using RunningDerivatives = RunningCostDerivatives<Scalar, Nx, Nu>;
  using TerminalDerivatives = TerminalCostDerivatives<Scalar, Nx>;

  // f_x, f_u of Eq. 2.7-2.11 by central differences of Derived::dynamics.
  void dynamics_derivatives(const State& x, const Control& u, int t, StateJacobian& fx,
                            ControlJacobian& fu) const {
    const Derived& self = derived();
    central_difference_jacobian([&](const State& xp) { return self.dynamics(xp, u, t); }, x, fx);
    central_difference_jacobian([&](const Control& up) { return self.dynamics(x, up, t); }, u, fu);
  }

  // l_x, l_u, l_xx, l_uu, l_ux by central differences of Derived::running_cost.
  void running_cost_derivatives(const State& x, const Control& u, int t,
                                RunningDerivatives& d) const {
    const Derived& self = derived();
    Eigen::Matrix<Scalar, Nx + Nu, 1> xu;
    xu << x, u;
    Eigen::Matrix<Scalar, Nx + Nu, 1> g;
    Eigen::Matrix<Scalar, Nx + Nu, Nx + Nu> h;
    central_difference_gradient_hessian(
        [&](const Eigen::Matrix<Scalar, Nx + Nu, 1>& z) {
          return self.running_cost(z.template head<Nx>(), z.template tail<Nu>(), t);
        },
        xu, g, h);
    d.lx = g.template head<Nx>();
    d.lu = g.template tail<Nu>();
    d.lxx = h.template topLeftCorner<Nx, Nx>();
    d.luu = h.template bottomRightCorner<Nu, Nu>();
    d.lux = h.template bottomLeftCorner<Nu, Nx>();
  }

  void terminal_cost_derivatives(const State& x, int t, TerminalDerivatives& d) const {
    const Derived& self = derived();
    central_difference_gradient_hessian([&](const State& xp) { return self.terminal_cost(xp, t); },
                                        x, d.lx, d.lxx);
  }

  template <class StepFunction>
  void for_each_step(int count, const StepFunction& linearize) const {
    for (int t = 0; t < count; ++t) linearize(t);
  }

  static constexpr int kRolloutLanes = 1;
  int rollout_lanes() const { return 1; }
  State rollout_dynamics(const State& x, const Control& u, int t, int /*lane*/) const {
    return derived().dynamics(x, u, t);
  }
  template <class LaneFunction>
  void for_each_rollout(int count, const LaneFunction& rollout) const {
    for (int lane = 0; lane < count; ++lane) rollout(lane);
  }

  Control control_change_weight() const { return Control::Zero(); }
  Control previous_control() const { return Control::Zero(); }

  Control control_lower_bound(int) const {
    return Control::Constant(-std::numeric_limits<Scalar>::infinity());
  }
  Control control_upper_bound(int) const {
    return Control::Constant(std::numeric_limits<Scalar>::infinity());
  }

 protected:
  ProblemBase() = default;

 private:
  const Derived& derived() const { return static_cast<const Derived&>(*this); }
};

}  // namespace hmpc
