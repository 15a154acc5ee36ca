#include "hmpc/ioc/local_ioc.hpp"

#include <Eigen/Cholesky>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

namespace hmpc::ioc {

using humanoid::kJoints;
using humanoid::kStateSize;
using StateVector = humanoid::StateVector;
using StateMatrix = humanoid::StateMatrix;
using JointVector = humanoid::JointVector;
using JointMatrix = Eigen::Matrix<double, kJoints, kJoints>;
using JointStateMatrix = Eigen::Matrix<double, kJoints, kStateSize>;

// The backward pass's value function and gains, for the forward pass that gives the gradient.
struct LocalIoc::Workspace {
  StateVector V_x;
  StateMatrix V_xx;
  std::array<JointVector, kWindowSteps> k;       // k_t = Q_uu^-1 Q_u
  std::array<JointStateMatrix, kWindowSteps> K;  // K_t = Q_uu^-1 Q_ux
  std::array<JointMatrix, kWindowSteps> Q_uu_inverse;
};

namespace {

// Residual rows of BasicStateCost::residual (problem.hpp) and the weight each is the square
// root of: attitude x, y, z, w; height; velocity x, y, z; alpha; beta right, left; angular
// velocity x, y, z; foot heights (4). -1: a weight that is not estimated.
std::array<int, kResiduals> feature_map() {
  std::array<int, kResiduals> map;
  map.fill(-1);
  map[0] = kQ1;
  map[1] = kQ2;
  map[2] = kQ3;
  map[4] = kHeight;
  map[5] = kVx;
  map[6] = kVy;
  map[7] = kVz;
  map[8] = kAlpha;
  map[9] = kBeta;
  map[10] = kBeta;
  return map;
}

void check_demonstration(const Demonstration& demo, std::size_t index) {
  const std::string name = "demonstration " + std::to_string(index);
  if (demo.states.size() != demo.inputs.size() + 1) {
    throw std::invalid_argument(name + ": " + std::to_string(demo.states.size()) + " states for " +
                                std::to_string(demo.inputs.size()) + " inputs (needs inputs + 1)");
  }
  if (!std::isfinite(demo.start_time))
    throw std::invalid_argument(name + ": start time not finite");
  for (std::size_t k = 0; k < demo.states.size(); ++k) {
    if (!demo.states[k].allFinite()) {
      throw std::invalid_argument(name + ": state " + std::to_string(k) + " not finite");
    }
  }
  for (std::size_t k = 0; k < demo.inputs.size(); ++k) {
    if (!demo.inputs[k].allFinite()) {
      throw std::invalid_argument(name + ": input " + std::to_string(k) + " not finite");
    }
  }
}

}  // namespace

Demonstration demonstration_of(const humanoid::ClosedLoopRun& run) {
  Demonstration demo;
  demo.states.push_back(humanoid::to_vector(run.initial));
  for (const humanoid::ClosedLoopSample& sample : run.samples) {
    demo.inputs.push_back(sample.torque);
    demo.states.push_back(humanoid::to_vector(sample.state));
  }
  return demo;
}

LocalIoc::LocalIoc(const humanoid::Motion& motion, const std::vector<Demonstration>& demonstrations,
                   humanoid::ThreadPool* pool, humanoid::ProblemConfig config)
    : feature_of_row_(feature_map()), pool_(pool) {
  struct Source {
    const Demonstration* demo;
    int first;  // index of the window's x_1 in the demonstration
  };
  std::vector<Source> sources;
  for (std::size_t d = 0; d < demonstrations.size(); ++d) {
    check_demonstration(demonstrations[d], d);
    const int steps = static_cast<int>(demonstrations[d].inputs.size());
    for (int first = 0; first + kWindowSteps <= steps; first += kWindowSteps) {
      sources.push_back({&demonstrations[d], first});
    }
  }
  windows_.resize(sources.size());

  // The estimated weights' rows unweighted (weight 1), the fixed ones as the motion has them.
  humanoid::Motion unit = motion;
  unit.weights = with_weights(motion.weights, Weights::Ones());
  config = humanoid::model_config(motion, config);
  config.step = humanoid::kCoarseStep;
  const humanoid::Model model(config.parameters);
  const JointVector limit = model.torque_limit;

  const int lanes = pool == nullptr ? 1 : pool->threads();
  using Problem = humanoid::HumanoidProblem<kWindowSteps>;
  // Eq. 4.29's beta^init from the state every motion starts in (closed_loop.hpp), as in the
  // MPC that generates with the learned weights.
  const humanoid::State start = humanoid::standing_state(config, humanoid::kStartHeight);
  std::vector<std::unique_ptr<Problem>>
      problems;  // one per lane: a problem's step maps are scratch
  problems.reserve(lanes);
  for (int lane = 0; lane < lanes; ++lane)
    problems.push_back(std::make_unique<Problem>(unit, start, config));
  const int count = static_cast<int>(sources.size());
  humanoid::run_on(pool, lanes, [&](int lane) {
    Problem& problem = *problems[lane];
    for (int m = lane; m < count; m += lanes) {
      const Source& source = sources[m];
      Window& window = windows_[m];
      problem.set_start_time(source.demo->start_time + source.first * humanoid::kCoarseStep);
      for (int t = 0; t < kWindowSteps; ++t) {
        const StateVector& x = source.demo->states[source.first + t];
        const JointVector& u = source.demo->inputs[source.first + t];
        window.inputs[t] = u;
        problem.dynamics_derivatives(x, u, t, window.A[t], window.B[t]);
        for (int j = 0; j < kJoints; ++j) {
          // At the limit to round-off: a clamped input, not an optimum's free one.
          window.free[t][j] = std::abs(u[j]) < limit[j] * (1.0 - 1e-9);
          if (!window.free[t][j]) window.B[t].col(j).setZero();
        }
        const StateVector& next = source.demo->states[source.first + t + 1];
        problem.cost().residual_jacobian(next, problem.time_of(t + 1), window.J[t]);
        window.residual[t] = problem.cost().residual(next, problem.time_of(t + 1));
      }
    }
  });

  lanes_.resize(lanes);
  values_.resize(windows_.size());
  gradients_.resize(windows_.size());
}

LocalIoc::~LocalIoc() = default;

double LocalIoc::window_term(Term term, const Window& window, const Weights& w, Workspace& work,
                             Weights* gradient) const {
  const bool likelihood = term == Term::kLogLikelihood;
  // Row weights: the estimated weight of the row's term, or 1 (the row carries its own).
  Eigen::Matrix<double, kResiduals, 1> c;
  for (int r = 0; r < kResiduals; ++r) c[r] = feature_of_row_[r] < 0 ? 1.0 : w[feature_of_row_[r]];
  // Gauss-Newton l_x = 2 J' C r, l_xx = 2 J' C J of the state cost at x_{t+1}, C = diag(c).
  const auto add_state_cost = [&](int t, StateVector& l_x, StateMatrix& l_xx) {
    const auto& J = window.J[t];
    l_x.noalias() += J.transpose() * (2.0 * c.cwiseProduct(window.residual[t]));
    l_xx.noalias() += J.transpose() * (2.0 * c).asDiagonal() * J;
  };
  // Control weight of input j (both legs alike).
  const auto control_weight = [&](int j) { return w[kHAA + j % humanoid::kJointsPerLeg]; };

  // Backward pass (see the header) from V = l_f at x_{N+1}.
  work.V_x.setZero();
  work.V_xx.setZero();
  add_state_cost(kWindowSteps - 1, work.V_x, work.V_xx);
  constexpr double kLog2Pi = 1.8378770664093453;
  double value = 0.0;
  for (int t = kWindowSteps - 1; t >= 0; --t) {
    const humanoid::StepJacobian& A = window.A[t];
    const humanoid::StepControlJacobian& B = window.B[t];
    // Control cost u' W_control u (Eq. 4.24) on the free inputs; a limited input is decoupled
    // with a unit pivot (its B column is zero), adding nothing to the value or the gradient.
    JointVector l_u = JointVector::Zero(), l_uu = JointVector::Ones();
    int free = 0;
    for (int j = 0; j < kJoints; ++j) {
      if (!window.free[t][j]) continue;
      l_u[j] = 2.0 * control_weight(j) * window.inputs[t][j];
      l_uu[j] = 2.0 * control_weight(j);
      ++free;
    }
    const Eigen::Matrix<double, kStateSize, kJoints> VB = work.V_xx * B;
    const JointVector Q_u = l_u + B.transpose() * work.V_x;
    const JointMatrix Q_uu = JointMatrix(l_uu.asDiagonal()) + B.transpose() * VB;
    const JointStateMatrix Q_ux = VB.transpose() * A;
    const Eigen::LLT<JointMatrix> llt(Q_uu);
    // Positive definite in exact arithmetic (see the header); round-off in V_xx across a
    // landing can still break it at extreme weights: the likelihood is then -infinity, which
    // the learner's line search backs away from.
    if (llt.info() != Eigen::Success) {
      return likelihood ? -std::numeric_limits<double>::infinity()
                        : std::numeric_limits<double>::infinity();
    }
    work.k[t] = llt.solve(Q_u);
    work.K[t] = llt.solve(Q_ux);
    if (likelihood) work.Q_uu_inverse[t] = llt.solve(JointMatrix::Identity());  // covariances
    value += likelihood ? -0.5 * Q_u.dot(work.k[t]) +
                              llt.matrixLLT().diagonal().array().log().sum() - 0.5 * free * kLog2Pi
                        : 0.5 * Q_u.dot(work.k[t]);
    if (t == 0) break;  // V at x_1 is not needed
    StateVector Q_x = A.transpose() * work.V_x;
    StateMatrix Q_xx = A.transpose() * work.V_xx * A;
    add_state_cost(t - 1, Q_x, Q_xx);
    work.V_x = Q_x - Q_ux.transpose() * work.k[t];
    work.V_xx = Q_xx - Q_ux.transpose() * work.K[t];
    work.V_xx = 0.5 * (work.V_xx + work.V_xx.transpose()).eval();  // symmetric despite round-off
  }

  // Forward pass for the gradient: under the Laplace approximation U is Gaussian with mean
  // U* = U - H^-1 g and covariance H^-1, and the backward pass factorises it step by step,
  //   u_t = u_t + du_t,  du_t = -k_t - K_t dx_t + e_t,  e_t ~ N(0, Q_uu^-1),  dx_1 = 0,
  // so the mean deviations (dx, du) and covariances follow the linear model forward:
  //   Sigma_u,t = K Sigma_x,t K' + Q_uu^-1,  Sigma_x,t+1 = (A - B K) Sigma_x,t (A - B K)' + B
  //   Q_uu^-1 B'.
  // The gradient's terms are sums over steps (g_k, H_k are, Eqs. 4.14-4.15 and the state
  // features' Gauss-Newton derivatives): -h' g_k = dU' g_k, h' H_k h = dU' H_k dU,
  // tr(H^-1 H_k) = sum_t tr(Sigma_t l_k,xx or uu). This is the same quantity as the thesis's
  // Eqs. 4.11-4.20 (differentiating the backward pass), computed through the closed-loop
  // dynamics A - B K instead: differentiating the backward pass carries the open-loop products
  // of A, which lost every digit on landing windows (measured: -4014 against 1.72 by
  // differences), while this pass stays within round-off of the differences. The excess cost
  // 1/2 g' H^-1 g has the gradient h' g_k - 1/2 h' H_k h: the mean deviations' terms, negated,
  // without the covariances.
  if (gradient == nullptr) return value;
  const double sign = likelihood ? 1.0 : -1.0;
  gradient->setZero();
  StateVector dx = StateVector::Zero();
  StateMatrix Sigma_x = StateMatrix::Zero();
  for (int t = 0; t < kWindowSteps; ++t) {
    const humanoid::StepJacobian& A = window.A[t];
    const humanoid::StepControlJacobian& B = window.B[t];
    const JointStateMatrix& K = work.K[t];
    const JointVector du = -work.k[t] - K * dx;
    JointVector Sigma_u_diagonal = JointVector::Zero();
    if (likelihood) {
      Sigma_u_diagonal = (K * Sigma_x * K.transpose() + work.Q_uu_inverse[t]).diagonal();
    }
    // A control weight's feature: l_u = 2 u_j, l_uu = 2 on its free inputs, so its terms are
    // 2 u_j du_j + du_j^2 + Sigma_u,jj.
    for (int j = 0; j < kJoints; ++j) {
      if (!window.free[t][j]) continue;
      (*gradient)[kHAA + j % humanoid::kJointsPerLeg] +=
          sign * (2.0 * window.inputs[t][j] * du[j] + du[j] * du[j]) + Sigma_u_diagonal[j];
    }
    if (likelihood) {
      const humanoid::StepJacobian closed_loop = A - B * K;
      Sigma_x = closed_loop * Sigma_x * closed_loop.transpose() +
                B * work.Q_uu_inverse[t] * B.transpose();
    }
    dx = A * dx + B * du;
    // A state row r of weight k at x_{t+1}: l_x = 2 r J_r', l_xx = 2 J_r' J_r, so its terms
    // are 2 r a + a^2 + J_r Sigma_x J_r' with a = J_r dx.
    const auto& J = window.J[t];
    for (int row = 0; row < kResiduals; ++row) {
      const int k = feature_of_row_[row];
      if (k < 0) continue;
      const double a = J.row(row).dot(dx);
      const double spread = likelihood ? J.row(row) * Sigma_x * J.row(row).transpose() : 0.0;
      (*gradient)[k] += sign * (2.0 * window.residual[t][row] * a + a * a) + spread;
    }
  }
  return value;
}

double LocalIoc::log_likelihood(const Weights& w, Weights* gradient) const {
  return evaluate(Term::kLogLikelihood, w, gradient);
}

double LocalIoc::excess_cost(const Weights& w, Weights* gradient) const {
  return evaluate(Term::kExcessCost, w, gradient);
}

Weights LocalIoc::term_costs(const Weights& w) const {
  Weights costs = Weights::Zero();
  for (const Window& window : windows_) {
    for (int t = 0; t < kWindowSteps; ++t) {
      for (int j = 0; j < kJoints; ++j) {
        const int k = kHAA + j % humanoid::kJointsPerLeg;
        if (window.free[t][j]) costs[k] += w[k] * window.inputs[t][j] * window.inputs[t][j];
      }
      for (int row = 0; row < kResiduals; ++row) {
        const int k = feature_of_row_[row];
        if (k >= 0) costs[k] += w[k] * window.residual[t][row] * window.residual[t][row];
      }
    }
  }
  return costs;
}

double LocalIoc::evaluate(Term term, const Weights& w, Weights* gradient) const {
  if (!(w.array() > 0.0).all() || !w.allFinite()) {
    throw std::invalid_argument("local IOC: every weight must be positive and finite");
  }
  const int lanes = static_cast<int>(lanes_.size());
  const int count = window_count();
  humanoid::run_on(pool_, lanes, [&](int lane) {
    for (int m = lane; m < count; m += lanes) {
      values_[m] =
          window_term(term, windows_[m], w, lanes_[lane], gradient ? &gradients_[m] : nullptr);
    }
  });
  // Summed in window order: the same total on any number of threads.
  double total = 0.0;
  for (int m = 0; m < count; ++m) total += values_[m];
  if (gradient != nullptr) {
    gradient->setZero();
    for (int m = 0; m < count; ++m) *gradient += gradients_[m];
  }
  return total;
}

}  // namespace hmpc::ioc
