// Local inverse optimal control (thesis Sec. 4.2.2; Levine & Koltun 2012, "Continuous Inverse
// Optimal Control with Locally Optimal Examples"), at the coarse step Delta t_c so that the
// learned weights drive the upper layer of the Coarse-Fast MPC (Sec. 4.2.3).
//
// Demonstrations are cut into N-step windows (N = the coarse horizon, "Trajectory-length T is
// set to horizon N", M = D T_org / N). Window m is x_1 and the inputs u_1..u_N with the states
// x_2..x_{N+1} that followed; its cost (Eq. 4.2) is linear in the weights w (Eq. 4.3). The
// Laplace approximation of the maximum-entropy likelihood (Eqs. 4.7-4.9) summed over windows
// and steps is Eq. 4.10,
//   log p(D | w) = sum_m sum_t ( -1/2 Q_u' Q_uu^-1 Q_u + 1/2 log |Q_uu| - (m_t/2) log 2 pi ),
// with Q the DDP backward pass along the demonstration (Eqs. 2.16-2.17, every step t = N..1):
//   Q_u = l_u + B' V_x',  Q_uu = l_uu + B' V_xx' B,  Q_ux = B' V_xx' A,
//   Q_x = l_x + A' V_x',  Q_xx = l_xx + A' V_xx' A,
//   V_x = Q_x - Q_ux' k,  V_xx = Q_xx - Q_ux' K,  k = Q_uu^-1 Q_u, K = Q_uu^-1 Q_ux,
// from V = l_f at x_{N+1}; A, B the coarse step map linearised at the demonstration's (x_t, u_t)
// (its states, not a re-simulation). We keep the constant -(m_t/2) log 2 pi, which the thesis
// drops, so that the value is the log density itself.
//
// This recursion is Levine & Koltun's whole-trajectory form -1/2 g' H^-1 g + 1/2 log |H| with
// H factorised block by block from the last step; we use the recursion because
// the whole-trajectory H is not usable in floating point here: the open-loop sensitivity of
// late states to early torques grows so fast through the contacts that H's eigenvalues on a
// jump window spanned 1e-3 to 8e14 and its Cholesky factorisation failed, while every Q_uu of
// the recursion (the feedback of the later steps folded in) is well conditioned.
//
// The gradient (Eqs. 4.11-4.21) is d log p / d w_k = -h' g_k + 1/2 h' H_k h + 1/2 tr(H^-1 H_k)
// per window (g = dJ/dU, H = d^2J/dU^2, h = H^-1 g, g_k and H_k their parts of weight k,
// Eqs. 4.14-4.15), evaluated by a forward pass with the backward pass's gains: h is minus the
// LQ step the gains give and H^-1 the covariance of the Gaussian the Laplace approximation
// makes of U, both of which the gains propagate through the closed-loop dynamics A - B K
// (local_ioc.cpp). This is the thesis's gradient, computed another way: differentiating the
// backward pass itself (Eqs. 4.16-4.20) propagates open-loop products of A, and across a
// landing that lost every digit (measured on a jump window: -4014 against 1.72 by
// differences; 1.7203 by this pass, 1.7203 by differences in long double).
//
// State cost terms r(x)^2 enter with Gauss-Newton derivatives l_x = 2 J' r, l_xx = 2 J' J as in
// the MPC's own iLQR (problem.hpp); second derivatives of the dynamics are left out, as in
// Levine & Koltun's linearised variant and in our iLQR.
//
// Q_uu stays positive definite because the weights do: the control cost gives
// Q_uu >= 2 min(w_control) I, and with Gauss-Newton costs V_xx is positive semi-definite. The
// learner (learn.hpp) optimises log w, so every weight it tries is positive; this replaces the
// thesis's augmented Lagrangian. An input at a torque limit is not free (the MPC clamped it),
// so it is left out of u_t: m_t counts a step's free inputs.
#pragma once

#include <vector>

#include "hmpc/humanoid/closed_loop.hpp"
#include "hmpc/ioc/weights.hpp"

namespace hmpc::ioc {

constexpr int kWindowSteps = humanoid::kCoarseHorizon;  // N
constexpr int kResiduals = humanoid::kCostResiduals<0>;

// A demonstration at the coarse step Delta t_c: states x_0..x_T and the inputs u_0..u_{T-1},
// each held for one coarse step between them.
struct Demonstration {
  double start_time = 0.0;  // time of states[0] in the motion's phase schedule [s]
  std::vector<humanoid::StateVector> states;
  std::vector<humanoid::JointVector> inputs;
};

// A closed-loop run's samples as a demonstration from its start: the input of each 30 ms
// period and the state it ended in. For a Coarse MPC run, whose input is held for the whole
// period (closed_loop.hpp); the other MPCs change it within the period.
Demonstration demonstration_of(const humanoid::ClosedLoopRun& run);

// One window, linearised once: everything the likelihood needs for any weights. Index t - 1
// holds step t = 1..N.
struct Window {
  std::array<humanoid::StepJacobian, kWindowSteps> A;  // dx_{t+1} / dx_t
  std::array<humanoid::StepControlJacobian, kWindowSteps>
      B;  // dx_{t+1} / du_t, limited inputs' columns zero
  // The state cost's residuals at x_{t+1} and their Jacobian, with the estimated weights' rows
  // unweighted and the fixed weights' rows square-root weighted.
  std::array<Eigen::Matrix<double, kResiduals, humanoid::kStateSize>, kWindowSteps> J;
  std::array<Eigen::Matrix<double, kResiduals, 1>, kWindowSteps> residual;
  std::array<humanoid::JointVector, kWindowSteps> inputs;
  std::array<std::array<bool, humanoid::kJoints>, kWindowSteps>
      free{};  // input not at a torque limit
};

// log p(D | w) and its gradient for one motion's demonstrations.
class LocalIoc {
 public:
  // `motion` gives the targets (phase schedule), the fixed weights, the chair and the model
  // sub-step; its estimated weights are ignored. Demonstrations shorter than one window add
  // nothing; a state or input that is not finite throws std::invalid_argument, as does a
  // demonstration whose counts do not match (T + 1 states, T inputs). `pool` (may be null)
  // linearises windows and evaluates the likelihood in parallel; it must outlive this.
  LocalIoc(const humanoid::Motion& motion, const std::vector<Demonstration>& demonstrations,
           humanoid::ThreadPool* pool = nullptr,
           humanoid::ProblemConfig config = humanoid::ProblemConfig{});
  ~LocalIoc();

  int window_count() const { return static_cast<int>(windows_.size()); }
  // log p(D | w), Eq. 4.10 in its whole-trajectory form, and (if non-null) its gradient in w
  // (Eq. 4.21; without it the forward pass is skipped). Every weight must be positive
  // (std::invalid_argument otherwise). -infinity (gradient unspecified) if round-off made a
  // Q_uu indefinite.
  double log_likelihood(const Weights& w, Weights* gradient = nullptr) const;
  // The demonstrations' excess cost: sum over windows of 1/2 g' H^-1 g = sum_t 1/2 Q_u' Q_uu^-1
  // Q_u, how far the Gauss-Newton model puts each window's cost above the local optimum it
  // predicts. Eq. 4.10 is -(this) + 1/2 log |H| + constant; at low temperature (every weight
  // scaled by c -> infinity) the excess cost, which grows like c, outweighs the log-determinant,
  // which grows like log c, so the likelihood's maximiser in the weights' ratios tends to this
  // one's minimiser. The gradient is Eq. 4.21's terms without 1/2 tr(H^-1 H_k). Same
  // conditions as log_likelihood; +infinity where that is -infinity.
  double excess_cost(const Weights& w, Weights* gradient = nullptr) const;
  // Each estimated weight's term of the demonstrations' cost under `w`: w_k times its feature
  // summed over every window's steps (Eq. 4.3), the fixed weights' terms left out. A term that
  // stays near zero along the demonstrations (e.g. lateral velocity in a jump in the sagittal
  // plane) is one they barely reveal.
  Weights term_costs(const Weights& w) const;

 private:
  struct Workspace;
  enum class Term { kLogLikelihood, kExcessCost };
  double evaluate(Term term, const Weights& w, Weights* gradient) const;
  // Window m's term and, if `gradient` is non-null, its gradient (the forward pass), in `work`.
  double window_term(Term term, const Window& window, const Weights& w, Workspace& work,
                     Weights* gradient) const;

  std::vector<Window> windows_;
  std::array<int, kResiduals> feature_of_row_{};  // estimated weight of residual row, or -1
  humanoid::ThreadPool* pool_;
  mutable std::vector<Workspace> lanes_;  // one per pool thread
  mutable std::vector<double> values_;
  mutable std::vector<Weights> gradients_;
};

}  // namespace hmpc::ioc
