// The humanoid's fast subsystem for the lower layer of the Coarse-Fast MPC (thesis Sec. 2.5.2,
// Eqs. 2.42-2.51; two_layer_mpc.hpp's FastSubsystem interface).
//
// Split (Eq. 2.47): slow y = the base, (q_base, v_base) = (position, quaternion; spatial
// velocity), 13 numbers; fast z = the joints, (q_joints, v_joints): the legs', n_f = 16, and
// for the robot with an arm the shoulder's too, n_f = 18 (Sec. 2.6.2). The inertia
// matrix splits as M = M_base + M_leg (Eq. 2.42), M_base = [M11 0; 0 0] with M11 the base's
// 6x6 block (linear and angular, the thesis's "latter assumption"), and
// epsilon = ||M_leg|| / ||M_base|| (Eq. 2.43; Frobenius norms, the thesis names none).
//
// With the slow variables frozen (Eq. 2.50a, and Eq. 2.28: y constant on the fast time
// scale) the deviation zeta = z - z_hat* of Eq. 2.48 obeys Eq. 2.50b,
//   epsilon Q22 zeta_v' = p_z,   epsilon Q22 = M22 (Q = M_leg / epsilon, Eq. 2.43),
// p_z the joint rows of the thesis's c + u (Eq. 2.49): joint torques, minus our bias forces,
// plus the contact forces. epsilon cancels, so the step is StepMap::step_joints: the joint
// rows of the model with the base held, discretised like the full model (Eq. 2.51c with the
// step map's sub-steps in place of one Euler step; z_hat* is piecewise constant, so
// zeta_v' = v_z').
//
// As in the two-layer MPC's contract, the reference (y_hat*, z_hat*, u_hat*) is the upper
// plan held on the fine grid (Eq. 2.35); zeta is re-referenced where z_hat* steps, so the
// underlying z evolves continuously. Cost: Eq. 2.52, w_fast zeta' zeta, plus the control cost
// w_fast_control nu' nu on the input deviation nu (Sec. 2.6.1: "the quadratic penalty on the
// deviation of control inputs as with the state-cost"). The composed input u_hat* + nu
// (Eq. 2.36) stays within the torque limits.
#pragma once

#include <array>

#include "hmpc/humanoid/problem.hpp"

namespace hmpc::humanoid {

// z of Eq. 2.47 from x = (q, v) of either variant (n = 13 + 2 joints), and x with its z
// replaced.
template <class StateVector>
Eigen::Matrix<double, StateVector::RowsAtCompileTime - 13, 1> fast_part(const StateVector& x) {
  constexpr int joints = (StateVector::RowsAtCompileTime - 13) / 2;
  Eigen::Matrix<double, 2 * joints, 1> z;
  z << x.template segment<joints>(7), x.template tail<joints>();
  return z;
}
template <class StateVector, class Fast>
StateVector with_fast_part(StateVector x, const Fast& z) {
  constexpr int joints = Fast::RowsAtCompileTime / 2;
  x.template segment<joints>(7) = z.template head<joints>();
  x.template tail<joints>() = z.template tail<joints>();
  return x;
}

// epsilon = ||M_leg||_F / ||M_base||_F, Eqs. 2.42-2.43.
double perturbation_parameter(const MassMatrix& M);

template <int NFast, int ArmJoints = 0>
class FastSubsystem
    : public StepMapProblem<FastSubsystem<NFast, ArmJoints>, 2 * Dimensions<ArmJoints>::kJoints,
                            Dimensions<ArmJoints>::kJoints, ArmJoints, NFast> {
  using Base = StepMapProblem<FastSubsystem<NFast, ArmJoints>, 2 * Dimensions<ArmJoints>::kJoints,
                              Dimensions<ArmJoints>::kJoints, ArmJoints, NFast>;
  friend Base;
  static constexpr int A = ArmJoints, kJoints = Dimensions<ArmJoints>::kJoints;
  using StepMap = BasicStepMap<ArmJoints>;

 public:
  using typename Base::Control;
  using typename Base::ControlJacobian;
  using typename Base::RunningDerivatives;
  using typename Base::State;
  using typename Base::StateJacobian;
  using typename Base::TerminalDerivatives;
  using FullState = BasicStateVector<ArmJoints>;
  using FullControl = BasicJointVector<ArmJoints>;

  // config.step is Delta t_f. `pool` (may be null: serial) must outlive the problem.
  FastSubsystem(const CostWeights& weights, const ProblemConfig& config, ThreadPool* pool = nullptr)
      : Base(config, pool), weights_(weights), config_(config) {
    const BasicModel<ArmJoints> model(config.parameters);
    limit_ = model.torque_limit;
    // A valid reference (identity attitude, at rest) until the MPC sets the upper plan.
    for (auto& x : x_hat_) {
      x.setZero();
      x[3] = 1.0;
    }
    for (auto& u : u_hat_) u.setZero();
  }

  const ProblemConfig& config() const { return config_; }

  // An interpolated reference (TwoLayerMpc's linear state hold) gets its quaternion normalised.
  void set_reference(int j, const FullState& x_hat, const FullControl& u_hat) {
    x_hat_[j] = x_hat;
    x_hat_[j].template segment<4>(3).normalize();
    u_hat_[j] = u_hat;
  }
  State deviation(const FullState& x) const { return fast_part(x) - fast_part(x_hat_[0]); }
  FullControl compose(const FullControl& u_hat, const Control& nu) const { return u_hat + nu; }
  // The full state the lower layer predicts at fine step j: (y_hat_j, z_hat_j + zeta).
  FullState full_state(const State& zeta, int j) const {
    return with_fast_part(x_hat_[j], fast_part(x_hat_[j]) + zeta);
  }

  // fz = dzeta_{j+1} / dzeta_j = dz+ / dz (z_hat is fixed), from the step map's
  // linearisation, or by whole-step central differences (ProblemConfig::linearisation).
  void dynamics_derivatives(const State& zeta, const Control& nu, int j, StateJacobian& fz,
                            ControlJacobian& fu) const {
    if (config_.linearisation == Linearisation::kWholeStepDifferences) {
      Base::dynamics_derivatives(zeta, nu, j, fz, fu);
    } else {
      this->step_map(j).linearise_joints(to_state<A>(full_state(zeta, j)), u_hat_[j] + nu,
                                         config_.step, fz, fu);
    }
  }

  double running_cost(const State& zeta, const Control& nu, int) const {
    return weights_.fast * zeta.squaredNorm() + weights_.fast_control * nu.squaredNorm();
  }
  double terminal_cost(const State& zeta, int) const { return weights_.fast * zeta.squaredNorm(); }
  void running_cost_derivatives(const State& zeta, const Control& nu, int,
                                RunningDerivatives& d) const {
    d.lx = 2.0 * weights_.fast * zeta;
    d.lu = 2.0 * weights_.fast_control * nu;
    d.lxx = 2.0 * weights_.fast * StateJacobian::Identity();
    d.luu = 2.0 * weights_.fast_control * Eigen::Matrix<double, kJoints, kJoints>::Identity();
    d.lux.setZero();
  }
  void terminal_cost_derivatives(const State& zeta, int, TerminalDerivatives& d) const {
    d.lx = 2.0 * weights_.fast * zeta;
    d.lxx = 2.0 * weights_.fast * StateJacobian::Identity();
  }

  Control control_lower_bound(int j) const { return -limit_ - u_hat_[j]; }
  Control control_upper_bound(int j) const { return limit_ - u_hat_[j]; }

 private:
  // Eq. 2.51c: zeta_{j+1} = z(t_j + Delta t_f) - z_hat_{j+1}, z moved with y held at y_hat_j
  // (dynamics() in step j's workspace, StepMapProblem).
  State dynamics_in(StepMap& map, const State& zeta, const Control& nu, int j) const {
    const BasicState<ArmJoints> next =
        map.step_joints(to_state<A>(full_state(zeta, j)), u_hat_[j] + nu, config_.step);
    return fast_part(to_vector(next)) - fast_part(x_hat_[j + 1]);
  }

  CostWeights weights_;
  ProblemConfig config_;
  FullControl limit_;
  std::array<FullState, NFast + 1> x_hat_;
  std::array<FullControl, NFast + 1> u_hat_;
};

}  // namespace hmpc::humanoid
