// The humanoid's optimal control problem for the iLQR and the MPCs (thesis Secs. 2.5-2.6):
// state x = (q, v) of model.hpp (n = 29), control u = the 8 joint torques within the model's
// torque limits, dynamics x_{k+1} = the step map (step.hpp) over the model step Delta t, and
// the cost of Sec. 4.3.1:
//   l(x, u, t) = l_attitude + l_height + l_velocity + l_alpha + l_beta + l_omega   (4.25-4.30)
//              + tau' W_control tau                                                 (4.24)
//              + w_torque_change |tau_k - tau_{k-1}|^2, tau_{-1} the torque applied last
//                                           (Sec. 2.7.3; a term the iLQR adds, see below)
//              + l_foot                     (ours: foot heights, motion.hpp's Gait)
//              + l_position + l_joint_rates (Sec. 2.7.3: the initial hip position, the joints'
//                                            rates)
//              + l_reach                    (Eq. 2.53, the robot with an arm, n = 31)
// with the targets of the motion phase in force at the step's time (Tables 2.2-2.3), and
// l_T(x) the same state terms at the end of the horizon.
//
// Every state term is a weighted square of a residual, l_state = |r(x)|^2 with r the
// square-root-weighted residuals below. The cost derivatives are Gauss-Newton: l_x = 2 J' r,
// l_xx = 2 J' J with J = dr/dx by central differences (iLQG's usual choice, Tassa et al.
// 2012); l_xx stays positive semi-definite where the exact Hessian of the angle terms would
// not, and it costs 2n residual evaluations instead of the n^2 of a full difference Hessian.
// The dynamics Jacobians are the step map's own linearisation (StepMap::linearise: the chain
// rule over its sub-steps, each sub-step's residual derivatives analytic or, as before them,
// forward differences), or central differences of whole steps (ProblemBase's default); the
// last two are kept as references (ProblemConfig::linearisation).
//
// Where the thesis leaves a definition open (Fig. 4.2 is not in the text):
//   - base: p_z^r and v^r are the height and world velocity of a point fixed on the torso,
//     ProblemConfig::base_point (see there);
//   - alpha, beta: the angles of the line from the base point to each ankle joint, measured
//     from the torso's longitudinal axis in its sagittal (x-z) and frontal (y-z) planes.
//     The torso's axes rather than the world's: they coincide when upright (the attitude
//     term's target), and unlike world axes they neither swap the feet in motion VI's half
//     turn nor become singular in motion VIII's flips;
//   - alpha_L is measured positive backward and alpha_R positive forward, so Eq. 4.28's
//     (alpha_R - alpha_L)^2 vanishes with the base midway between the feet in the sagittal
//     plane ("the robot tries to maintain the position of the base link between its feet");
//   - omega^r: the torso's angular velocity in world coordinates;
//   - the robot's quaternion in Eq. 4.25 is used as integrated, never sign-flipped, so a
//     full flip (quaternion -1) is told apart from none (motion.hpp, attitude_quaternion).
//
// Threads: every horizon step t has its own step-map workspace and the costs only read
// shared data, so steps may be linearised concurrently; given a ThreadPool the problem hands
// its linearisations to it (the for_each_step hook of hmpc/solver/problem.hpp), with results
// bit-identical to a serial run. The problem holds N step maps (28 kB each, 0.3 MB at
// N = 10): build it on the heap.
#pragma once

#include <array>

#include "hmpc/humanoid/motion.hpp"
#include "hmpc/humanoid/stance.hpp"
#include "hmpc/humanoid/step.hpp"
#include "hmpc/humanoid/thread_pool.hpp"
#include "hmpc/solver/problem.hpp"

namespace hmpc::humanoid {

template <int A>
using BasicStateVector = Eigen::Matrix<double, Dimensions<A>::kStateSize, 1>;
template <int A>
using BasicStateMatrix =
    Eigen::Matrix<double, Dimensions<A>::kStateSize, Dimensions<A>::kStateSize>;
using StateMatrix = BasicStateMatrix<0>;

template <int A>
BasicStateVector<A> to_vector(const BasicState<A>& x) {
  BasicStateVector<A> out;
  out << x.q, x.v;
  return out;
}
// A: the variant (model.hpp), not deduced; the biped's by default.
template <int A = 0>
BasicState<A> to_state(const BasicStateVector<A>& x) {
  return BasicState<A>{x.template head<Dimensions<A>::kConfigurationSize>(),
                       x.template tail<Dimensions<A>::kDofs>()};
}

// How the problems linearise the step map (see the file comment): the sub-step chain rule with
// analytic residual derivatives, the same with differenced ones, or whole-step differences.
enum class Linearisation { kAnalytic, kSubStepChainRule, kWholeStepDifferences };

struct ProblemConfig {
  double step = 0.03;  // Delta t of the model [s]: 30 ms coarse, 10 ms fine (Table 2.4)
  // Sub-step of the step map inside the MPC's model. The simulator steps at 1 ms (Sec.
  // 2.6.2: "modeling error occurs"); the MPC's model may be coarser to make the
  // finite-difference linearisation affordable. Semi-implicit Euler is stable for omega h < 2:
  // the stiffest explicit mode, a foot on its soles at 195 rad/s (contact.hpp), allows h up to
  // 10 ms; 5 ms (omega h ~ 1) is our choice, still resolving the 5 Hz whole-body bounce.
  // (The step map's rotation guard then refines sub-steps above 40 rad/s instead of 200.)
  double max_substep = 5e-3;
  // The base point whose height and velocity Eqs. 4.26-4.27 regulate (stance.hpp says why).
  Vector3 base_point = kBasePoint;
  Parameters parameters{};
  ContactParameters contact{};
  // The slip velocity v_s of the MPC's friction law (contact.hpp's (C3)) [m/s]; 0: the plant's.
  // A model given a state whose foot velocities are off by more than v_s (an estimate, filtered
  // joint rates) predicts full Coulomb friction in its first sub-step where the plant's feet
  // stick; a wider v_s keeps that force proportional to the error. model_config applies it.
  double model_slip_velocity = 0.0;
  // The differenced chain rule stays the closed loop's default for now: the motion checks
  // certify single trajectories, which round-off-level changes flip (README), so a change of
  // linearisation waits for checks over perturbed starts.
  Linearisation linearisation = Linearisation::kSubStepChainRule;
  // Line-search rollouts run at once on a pool with a second thread (rollout_lanes in
  // hmpc/solver/problem.hpp): 2, or 1 for one at a time (the benchmark's comparison); the
  // solution is the same either way.
  int line_search_lanes = 2;
};

// The quantities the state cost reads from a state (see the file comment for definitions).
struct BaseFeatures {
  Eigen::Vector4d quaternion;  // torso, (w, x, y, z), normalised
  Vector3 position;            // base point, world
  Vector3 velocity;            // base point, world
  Vector3 angular_velocity;    // torso, world
  double alpha_left = 0.0, alpha_right = 0.0, beta_left = 0.0, beta_right = 0.0;  // [rad]
  // Heights above the ground of the soles' heel and toe edge centres [m]: left heel, left
  // toe, right heel, right toe (for the foot-height term; at the standing sink when standing).
  std::array<double, 4> sole_height{};
  Vector3 hand = Vector3::Zero();  // the hand's centre, world (the robot with an arm)
};

// Square-root-weighted residuals: 4 attitude, 1 height, 3 velocity, 1 alpha, 2 beta (right,
// left), 3 angular velocity, 4 foot heights (as BaseFeatures::sole_height; Gait in motion.hpp),
// 8 leg joint angles (CostWeights::joint, the tracking MPC's), 2 for the base point's horizontal
// position (CostWeights::position), 8 leg joint rates (CostWeights::joint_velocity), and for the
// robot with an arm 3 for the hand (Eq. 2.53).
template <int A>
constexpr int kCostResiduals = 36 + 3 * A;

// The state cost of Sec. 4.3.1 for one motion. Every const function is safe to call from
// several threads; set_motion only between solves.
template <int ArmJoints>
class BasicStateCost {
 public:
  using State = BasicState<ArmJoints>;
  using StateVector = BasicStateVector<ArmJoints>;
  using StateMatrix = BasicStateMatrix<ArmJoints>;
  using JointVector = BasicJointVector<ArmJoints>;
  using CostResidual = Eigen::Matrix<double, kCostResiduals<ArmJoints>, 1>;

  // beta^init of Eq. 4.29 and the held horizontal position are taken from `initial`. Throws
  // std::invalid_argument if the motion reaches (Motion::reach) and the robot has no arm, or the
  // other way round.
  BasicStateCost(const Motion& motion, const State& initial, const ProblemConfig& config);

  const Motion& motion() const { return motion_; }
  // New targets and weights for the next solve (an operator's task or learned weights): the
  // motion's phases and weights. Its chair, gait and reach must be those the cost was built
  // with, since they shape the model; std::invalid_argument otherwise.
  void set_motion(const Motion& motion);
  BaseFeatures features(const State& x) const;
  CostResidual residual(const StateVector& x, double time) const;
  double value(const StateVector& x, double time) const { return residual(x, time).squaredNorm(); }
  using ResidualJacobian =
      Eigen::Matrix<double, kCostResiduals<ArmJoints>, Dimensions<ArmJoints>::kStateSize>;
  // J = dr/dx by central differences (the residual's entries, in the file comment's terms).
  void residual_jacobian(const StateVector& x, double time, ResidualJacobian& J) const;
  // Gauss-Newton gradient and Hessian of value() (see the file comment).
  void derivatives(const StateVector& x, double time, StateVector& lx, StateMatrix& lxx) const;
  // tau' W_control tau, Eq. 4.24.
  double control_cost(const JointVector& tau) const;
  JointVector control_weights() const;  // the diagonal of W_control

 private:
  Motion motion_;
  Vector3 base_point_;
  std::array<Vector3, 4>
      sole_points_;  // heel and toe edge centres in foot coordinates, as sole_height
  double beta_left_init_ = 0.0, beta_right_init_ = 0.0;
  Eigen::Vector2d position_init_ = Eigen::Vector2d::Zero();  // base point, world x and y
  BasicDynamics<ArmJoints> dynamics_;  // kinematics only (a const member function)
};

using StateCost = BasicStateCost<0>;

// The base of the humanoid's iLQR problems (HumanoidProblem, FastSubsystem): dynamics by the
// step map, one workspace per step so that the solver's per-step linearisations may run on a
// ThreadPool (for_each_step), and one more for the line search's second lane (rollout lanes,
// hmpc/solver/problem.hpp). Derived defines
//   State dynamics_in(BasicStepMap<A>& map, const State& x, const Control& u, int t) const,
// its step t in `map`'s workspace; a step depends on its arguments only, so every workspace
// gives the same value.
template <class Derived, int Nx, int Nu, int A, int Steps>
class StepMapProblem : public ProblemBase<Derived, double, Nx, Nu> {
  using Base = ProblemBase<Derived, double, Nx, Nu>;

 public:
  using typename Base::Control;
  using typename Base::State;

  State dynamics(const State& x, const Control& u, int t) const {
    return derived().dynamics_in(step_maps_[t], x, u, t);
  }
  template <class StepFunction>
  void for_each_step(int count, const StepFunction& linearize) const {
    run_on(pool_, count, linearize);
  }
  // Hides ProblemBase's 1 on purpose: the solver reads it from the problem type (problem.hpp).
  // cppcheck-suppress duplInheritedMember
  static constexpr int kRolloutLanes = 2;
  int rollout_lanes() const { return rollout_lanes_on(pool_, lanes_); }
  State rollout_dynamics(const State& x, const Control& u, int t, int lane) const {
    return derived().dynamics_in(lane == 0 ? step_maps_[t] : lane_map_, x, u, t);
  }
  template <class LaneFunction>
  void for_each_rollout(int count, const LaneFunction& rollout) const {
    run_on(pool_, count, rollout);
  }

 protected:
  // `pool` (may be null: serial) must outlive the problem and its copies.
  StepMapProblem(const ProblemConfig& config, ThreadPool* pool)
      : pool_(pool), lanes_(config.line_search_lanes) {
    const BasicModel<A> model(config.parameters);
    step_maps_.fill(BasicStepMap<A>(model, config.parameters, config.contact, config.max_substep,
                                    config.linearisation == Linearisation::kSubStepChainRule
                                        ? ResidualJacobian::kForwardDifferences
                                        : ResidualJacobian::kAnalytic));
    lane_map_ = step_maps_[0];
  }
  BasicStepMap<A>& step_map(int t) const { return step_maps_[t]; }

 private:
  const Derived& derived() const { return static_cast<const Derived&>(*this); }

  ThreadPool* pool_;
  int lanes_;
  mutable std::array<BasicStepMap<A>, Steps> step_maps_;
  mutable BasicStepMap<A> lane_map_;
};

// The problem of horizon N for the biped (ArmJoints 0) or the robot with an arm (1).
template <int N, int ArmJoints = 0>
class HumanoidProblem
    : public StepMapProblem<HumanoidProblem<N, ArmJoints>, Dimensions<ArmJoints>::kStateSize,
                            Dimensions<ArmJoints>::kJoints, ArmJoints, N> {
  using Base = StepMapProblem<HumanoidProblem<N, ArmJoints>, Dimensions<ArmJoints>::kStateSize,
                              Dimensions<ArmJoints>::kJoints, ArmJoints, N>;
  friend Base;
  using StepMap = BasicStepMap<ArmJoints>;
  using JointVector = BasicJointVector<ArmJoints>;
  static constexpr int A = ArmJoints;

 public:
  using typename Base::Control;
  using typename Base::ControlJacobian;
  using typename Base::RunningDerivatives;
  using typename Base::State;
  using typename Base::StateJacobian;
  using typename Base::TerminalDerivatives;

  // `pool` (may be null: serial) must outlive the problem and its copies.
  HumanoidProblem(const Motion& motion, const BasicState<ArmJoints>& initial,
                  const ProblemConfig& config = ProblemConfig{}, ThreadPool* pool = nullptr)
      : Base(config, pool), config_(config), cost_(motion, initial, config) {
    const BasicModel<ArmJoints> model(config.parameters);
    upper_ = model.torque_limit;
    lower_ = -model.torque_limit;
  }

  const ProblemConfig& config() const { return config_; }
  const BasicStateCost<ArmJoints>& cost() const { return cost_; }
  void set_motion(const Motion& motion) { cost_.set_motion(motion); }
  // Time of the horizon's first state in the motion's schedule [s].
  void set_start_time(double t) { start_time_ = t; }
  double start_time() const { return start_time_; }
  double time_of(int t) const { return start_time_ + t * config_.step; }

  void dynamics_derivatives(const State& x, const Control& u, int t, StateJacobian& fx,
                            ControlJacobian& fu) const {
    if (config_.linearisation == Linearisation::kWholeStepDifferences) {
      Base::dynamics_derivatives(x, u, t, fx, fu);
    } else {
      this->step_map(t).linearise(to_state<A>(x), u, config_.step, fx, fu);
    }
  }
  double running_cost(const State& x, const Control& u, int t) const {
    return cost_.value(x, time_of(t)) + cost_.control_cost(u);
  }
  double terminal_cost(const State& x, int t) const { return cost_.value(x, time_of(t)); }

  void running_cost_derivatives(const State& x, const Control& u, int t,
                                RunningDerivatives& d) const {
    cost_.derivatives(x, time_of(t), d.lx, d.lxx);
    const JointVector w = cost_.control_weights();
    d.lu = 2.0 * w.cwiseProduct(u);
    d.luu = (2.0 * w).asDiagonal();
    d.lux.setZero();
  }
  void terminal_cost_derivatives(const State& x, int t, TerminalDerivatives& d) const {
    cost_.derivatives(x, time_of(t), d.lx, d.lxx);
  }

  Control control_lower_bound(int) const { return lower_; }
  Control control_upper_bound(int) const { return upper_; }

  // Sec. 2.7.3's change of torques (CostWeights::torque_change): it ties each input to the one
  // before, so the iLQR adds it to the cost itself (problem.hpp's control_change_weight), on
  // the whole plan and against the torque applied last, which the caller sets before each
  // solve. Until one is set (a run's first sample) the term is off.
  void set_applied_torque(const Control& u) {
    applied_ = u;
    has_applied_ = true;
  }
  Control control_change_weight() const {
    return Control::Constant(has_applied_ ? cost_.motion().weights.torque_change : 0.0);
  }
  Control previous_control() const { return applied_; }

 private:
  State dynamics_in(StepMap& map, const State& x, const Control& u, int) const {
    return to_vector(map.step(to_state<A>(x), u, config_.step));
  }

  ProblemConfig config_;
  BasicStateCost<ArmJoints> cost_;
  double start_time_ = 0.0;
  Control lower_, upper_;
  Control applied_ = Control::Zero();
  bool has_applied_ = false;
};

// `contact` with the motion's chair, if it has one.
ContactParameters contact_for(const Motion& motion,
                              ContactParameters contact = ContactParameters{});
// The MPC's model of `motion`: `config` with the motion's contact surfaces (contact_for), if
// the motion asks for one, its model sub-step (Motion::model_substep), and, if set, the
// model's slip velocity (ProblemConfig::model_slip_velocity).
ProblemConfig model_config(const Motion& motion, ProblemConfig config);

// A quiet stance for motion starts: torso upright with its base point at `height`, feet flat
// and side by side, knees bent as needed (straight if `height` is out of reach), the centre
// of mass over the middle of the soles, the soles sunk by the static load's mean W / (8 k),
// at rest; the arm, if any (A = 1), hanging (the same mass distribution as the biped's).
template <int A = 0>
BasicState<A> standing_state(const ProblemConfig& config, double height);

}  // namespace hmpc::humanoid
