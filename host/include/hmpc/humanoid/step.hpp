// The humanoid's discrete step map x_{k+1} = step(x_k, tau, dt) for the MPC and the 1 ms
// simulator (thesis Sec. 2.6.2: x = (q, v), n = 29; u = the 8 joint torques).
//
// Dynamics: M(q) a + c(q, v) = S^T (tau + tau_stop(q, v)) + J(q)^T f(q, v) + tau_ext
// (dynamics.hpp, contact.hpp), S = [0 1] selecting the actuated joints, tau_stop the joints'
// end stops (Parameters::stop_*), tau_ext an optional generalized disturbance.
//
// Integration (per sub-step of length h): semi-implicit (symplectic) Euler, velocity first,
// with the contact's velocity dependence taken linearly implicitly:
//   (M - h sum_i J_i^T D_i J_i) dv = h (S^T tau - c + sum_i J_i^T f_i + tau_ext),   (S1)
//   v+ = v + dv,
//   p+ = p + h R(quat) v_o+,  quat+ = normalise(quat (x) exp(h omega+ / 2)),           (S2)
//   joints+ = joints + h qdot+,
// with D_i = df_i / dp_dot (ContactModel::point_force). The end stops enter the same way, per
// joint j, with K_j and B_j their stiffness and damping (joint_stop): h B_j + h^2 K_j added to
// A's diagonal and h (tau_stop + h (-K_j) qdot_j) to the bracket, linearly implicit in both
// the spring and the damper, so that a stiff stop needs no shorter sub-step. (S1) is one Newton
// step of backward Euler on the contact damping and friction (as in MuJoCo's implicit damping):
// friction's viscous slope mu F_n / v_s = 4.6e3 N s/m per point makes explicit Euler unstable at a
// free foot (h b / m ~ 30 for 0.61 kg at h = 1 ms), while the implicit form is stable for any h (D
// is negative semi-definite, so the matrix stays symmetric positive definite). The spring part
// stays explicit: it is what the sub-step bounds, omega h <= 0.2 for a foot on its 4 points
// (contact.hpp). (S2) moves the quaternion on the unit sphere by the exponential map of the body
// angular velocity (quat_dot = quat (x) (0, omega) / 2, model.hpp).
//
// Sub-steps: dt is split into ceil(dt / max_substep) equal sub-steps, max_substep = 1 ms by
// default: the HIL and thesis simulator step (Sec. 2.7), and 5x inside the stability bound
// of the stiffest explicit mode above. tau (zero-order hold) and tau_ext are held over dt.
// Rotation guard: the velocity-product (Coriolis, centrifugal) terms of c(q, v) are explicit
// too and blow up once a sub-step turns a body by about a radian (h |v| ~ 1). A free foot
// (3.5e-3 kg m^2 about the ankle) under its 100 N m torque limit gains 2.9e4 rad/s per second,
// 870 rad/s within one 30 ms MPC step: so a sub-step is shortened to turn no joint and the torso by
// more than kMaxRotation = 0.2 rad, down to max_substep / kMaxRefinement. Below 200 rad/s
// (every physically meaningful motion) the sub-steps are the fixed ones above, so the step
// map is smooth there; the guard only keeps wild optimiser rollouts finite.
//
// Linearisation (linearise, linearise_joints): the step's Jacobians are the product of its
// sub-steps' Jacobians (chain rule). In a sub-step, a = dv / h solves A a = b with
// A = M - h sum_i J_i^T D_i J_i and b the bracket of (S1); differentiating A a = b at the
// nominal a gives
//   dv+ = h A^-1 (dr/dx dx + S^T dtau + sum_i J_i^T D_i J_i a dh) + a dh,                (L1)
//   r(x') = b(x') - A(x') a
//         = S^T tau + tau_ext - (M(q') a + c(q', v')) + sum_i J_i^T (f_i + h D_i J_i a)  (L2)
//           + S^T (tau_stop - h K qdot - (h B + h^2 K) a_joints)  (at q', v')
// with J_i, f_i, D_i at x' = (q', v'). dr/dx is analytic (ResidualJacobian::kAnalytic): the
// RNEA's derivatives in q and v (dynamics_derivatives.hpp), each point's
// phi_i = f_i + h D_i J_i a with its exact slopes in the point's position, velocity and J_i a
// (ContactModel::force_slopes, D_i's own derivatives included), carried through the point
// Jacobians' derivatives (add_point_force_derivatives), and the stops' slopes; taken in the
// tangent directions and mapped to q's coordinates (the world position through R^T, the
// quaternion through tangent_of_quaternion). Its columns are exact to round-off, and cost one
// recursive pass and a few 3-vector products per point, against one RNEA per column (and the
// kinematics and contact points a column moves) for the forward differences it replaced,
// kept as ResidualJacobian::kForwardDifferences: step sqrt(eps), a relative error near 1e-5
// (contact's 1 mm length against the 1.5e-8 step). The nominal Cholesky of A serves every
// column in either way (humanoid_derivatives_test compares them).
// The torque columns are exact. (S2) is differentiated analytically except in the
// quaternion and omega+, by central differences of (S2) alone. dh: where the rotation guard
// shortens a sub-step, h = kMaxRotation / rate depends on the state, and the last sub-step
// takes what is left of dt; their derivatives enter the chain (dh = 0 for fixed lengths).
// Central differences of whole steps (ProblemBase's default, kept as the reference) instead
// run two complete steps per column, every sub-step with its CRBA and Cholesky: for a 30 ms
// step of 6 sub-steps, 444 sub-steps against 6 sub-steps and their 6 residual derivatives.
//
// No call allocates. One instance per thread (it owns a Dynamics workspace).
#pragma once

#include <Eigen/Cholesky>

#include "hmpc/humanoid/contact.hpp"
#include "hmpc/humanoid/dynamics.hpp"
#include "hmpc/humanoid/dynamics_derivatives.hpp"

namespace hmpc::humanoid {

// The end stops' torque on one joint at angle q and rate v (Parameters::stop_*), with the
// slopes the step map treats implicitly: stiffness = -d(spring torque)/dq >= 0 and
// damping = -d(torque)/dv >= 0; and, for the analytic linearisation, those slopes' own
// derivatives in q (d torque/dq = -stiffness - v d damping/dq).
struct JointStop {
  double torque = 0.0, stiffness = 0.0, damping = 0.0;
  double stiffness_slope = 0.0, damping_slope = 0.0;  // d stiffness/dq, d damping/dq
};
JointStop joint_stop(double q, double v, double lower, double upper, const Parameters& parameters);

// How a linearisation takes (L2)'s dr/dx: analytic (the rigid-body dynamics' derivatives,
// the contact force's and the stops' in one pass), or by forward differences, one RNEA and
// the contact points the column moves per column (kept as the reference the tests and the
// benchmark compare against).
enum class ResidualJacobian { kAnalytic, kForwardDifferences };

// The step map of a variant (model.hpp). Jacobians of a step: x = (q, v) stacked (n = 29 or
// 31), and the joints' z = (q_joints, v_joints) (the thesis's fast state, n_f = 16 or 18).
template <int ArmJoints>
class BasicStepMap {
 public:
  using D = Dimensions<ArmJoints>;
  static constexpr int kJoints = D::kJoints, kDofs = D::kDofs, kStateSize = D::kStateSize,
                       kConfigurationSize = D::kConfigurationSize, kJointStateSize = 2 * kJoints;
  using Model = BasicModel<ArmJoints>;
  using Configuration = BasicConfiguration<ArmJoints>;
  using Velocity = BasicVelocity<ArmJoints>;
  using JointVector = BasicJointVector<ArmJoints>;
  using MassMatrix = BasicMassMatrix<ArmJoints>;
  using State = BasicState<ArmJoints>;
  using Dynamics = BasicDynamics<ArmJoints>;
  using ContactModel = BasicContactModel<ArmJoints>;
  using ContactState = BasicContactState<ArmJoints>;
  using PointJacobian = BasicPointJacobian<ArmJoints>;
  using StateVector = Eigen::Matrix<double, kStateSize, 1>;
  using StepJacobian = Eigen::Matrix<double, kStateSize, kStateSize>;                 // dx+ / dx
  using StepControlJacobian = Eigen::Matrix<double, kStateSize, kJoints>;             // dx+ / dtau
  using JointStepJacobian = Eigen::Matrix<double, kJointStateSize, kJointStateSize>;  // dz+ / dz
  using JointControlJacobian = Eigen::Matrix<double, kJointStateSize, kJoints>;       // dz+ / dtau

  static constexpr double kMaxRotation = 0.2;  // [rad] per sub-step, see above
  static constexpr int kMaxRefinement = 1000;

  explicit BasicStepMap(const Model& model = Model{}, const Parameters& parameters = Parameters{},
                        const ContactParameters& contact = ContactParameters{},
                        double max_substep = 1e-3,
                        ResidualJacobian residual = ResidualJacobian::kAnalytic);

  // x_{k+1} from x_k under joint torques tau held for dt (> 0), by (S1)-(S2).
  State step(const State& x, const JointVector& tau, double dt,
             const Velocity& external = Velocity::Zero());

  // The fast subsystem's step (Eqs. 2.50-2.51, fast_subsystem.hpp): the base held, pose and
  // velocity (Eq. 2.28: the slow variables are constant on the fast time scale), and the
  // joints moved by the joint rows of (S1) with the base acceleration zero,
  //   (M22 - h sum_i J_i,z^T D_i J_i,z) dv_z = h (tau - c_z + (sum_i J_i^T f_i)_z),
  // M22 = epsilon Q22 of Eq. 2.50b. Same sub-steps as step().
  State step_joints(const State& x, const JointVector& tau, double dt);

  // step(x, tau, dt) (no tau_ext), the same numbers, and its Jacobians by (L1)-(L2).
  State linearise(const State& x, const JointVector& tau, double dt, StepJacobian& fx,
                  StepControlJacobian& fu);
  // step_joints(x, tau, dt), the same numbers, and its Jacobians with respect to the joints'
  // z and tau by (L1)-(L2) restricted to the joint rows and columns (the base held).
  State linearise_joints(const State& x, const JointVector& tau, double dt, JointStepJacobian& fz,
                         JointControlJacobian& fu);

  // The contact state last evaluated (forces, points, Jacobians): at the start of the last
  // sub-step, or by evaluate_contact(); after a linearisation, at some perturbed state.
  const ContactState& contact_state() const { return contact_state_; }
  // Contact forces at a given state, without stepping.
  const ContactState& evaluate_contact(const State& x);

  Dynamics& dynamics() { return dynamics_; }
  ContactModel& contact_model() { return contact_; }
  double max_substep() const { return max_substep_; }

 private:
  // A sub-step's length h and what set it (advance()): the nominal length (or the guard's
  // floor), the rotation guard's kMaxRotation / rate, or what was left of dt.
  struct SubStep {
    enum Rule { kFixed, kGuarded, kRemainder };
    double h;
    Rule rule;
  };
  using StateRow = Eigen::Matrix<double, 1, kStateSize>;
  using JointStateRow = Eigen::Matrix<double, 1, kJointStateSize>;
  using ControlRow = Eigen::Matrix<double, 1, kJoints>;

  // dt cut into sub-steps (see above), each done by substep(x, SubStep).
  template <class Substep>
  State advance(const State& x, double dt, const Substep& substep) const;
  void substep(State& x, const JointVector& tau, double h, const Velocity& external,
               bool base_held);
  // (S1)'s a = dv / h at x (base_held: its first six entries zero, the rest from the joint
  // rows); leaves kinematics_, contact_state_, the dynamics' configuration and the Cholesky
  // factor of A (cholesky_, or joint_cholesky_) at x.
  Velocity acceleration(const State& x, const JointVector& tau, double h, const Velocity& external,
                        bool base_held);
  // For the linearisation, right after acceleration(x, ...) returned a: dr/dx of (L2) into
  // residual_jacobian_ by forward differences, its first q_count columns for q's entries
  // from first_q, the next v_count for v's from first_v; and d(b - A a)/dh, sum_i J_i^T D_i
  // J_i a plus the end stops' part, into damping_acceleration_ (for dv+/dh). Leaves
  // contact_state_, kinematics_ and the dynamics at perturbed states.
  void residual_jacobian(const State& x, const Velocity& a, double h, int first_q, int q_count,
                         int first_v, int v_count);
  // residual_jacobian()'s two ways (ResidualJacobian): the analytic one fills every column
  // into analytic_jacobian_ and copies the asked ones; it leaves contact_state_ and the
  // dynamics at x.
  void differenced_residual_jacobian(const State& x, const Velocity& a, double h, int first_q,
                                     int q_count, int first_v, int v_count);
  void analytic_residual_jacobian(const State& x, const Velocity& a, double h);
  // linearise()'s and linearise_joints()'s chain over the sub-steps: fx = I, fu = 0, then per
  // sub-step linearised(s, h, dh_x, dh_u) with the length's derivatives (see step.cpp).
  template <int Rates, class Jacobian, class ControlJacobian, class Linearised>
  State linearise_chain(const State& x, double dt, Jacobian& fx, ControlJacobian& fu,
                        const Linearised& linearised);
  // One sub-step of linearise() (linearise_joints()): x moved as by substep(), fx and fu
  // (fz, fu) multiplied by its Jacobians; dh: the sub-step length's derivatives.
  void linearised_substep(State& x, const JointVector& tau, double h, const StateRow& dh_x,
                          const ControlRow& dh_u, StepJacobian& fx, StepControlJacobian& fu);
  void linearised_joint_substep(State& x, const JointVector& tau, double h,
                                const JointStateRow& dh_z, const ControlRow& dh_u,
                                JointStepJacobian& fz, JointControlJacobian& fu);

  // The end stops' part of (L2)'s r for joint j at (q, v) and the nominal acceleration a
  // (see step.hpp's file comment).
  double stop_term(int j, double q, double v, double a, double h) const;

  Dynamics dynamics_;
  ContactModel contact_;
  Parameters parameters_;  // the end stops'
  JointVector joint_lower_, joint_upper_;
  double max_substep_;
  ResidualJacobian residual_;
  // Workspace.
  BasicKinematics<ArmJoints> kinematics_;
  ContactState contact_state_;
  MassMatrix iteration_matrix_;  // its lower triangle: the Cholesky factorisations read no more
  // Factorised once at construction, so that a copy never reads an uninitialised state.
  Eigen::LLT<MassMatrix> cholesky_{MassMatrix::Identity()};
  Eigen::LLT<Eigen::Matrix<double, kJoints, kJoints>> joint_cholesky_{
      Eigen::Matrix<double, kJoints, kJoints>::Identity()};
  // Linearisation workspace (residual_jacobian()).
  Eigen::Matrix<double, kDofs, kStateSize> residual_jacobian_;
  std::array<Velocity, kContactPoints> contact_terms_;       // J_i^T (f_i + h D_i J_i a) at x
  typename Dynamics::InverseDynamicsPasses nominal_passes_;  // the RNEA's at (x, a)
  BasicKinematics<ArmJoints> moved_kinematics_;              // with one joint angle moved
  Velocity damping_acceleration_;
  BasicDynamicsDerivatives<ArmJoints> derivatives_;
  BasicInverseDynamicsDerivatives<ArmJoints> inverse_;
  MassMatrix residual_by_tangent_;  // dr/dq in the tangent columns (dynamics_derivatives.hpp)
  Eigen::Matrix<double, kDofs, kStateSize> analytic_jacobian_;
};

using State = BasicState<0>;
using StepMap = BasicStepMap<0>;
using ArmStepMap = BasicStepMap<1>;
constexpr int kJointStateSize = StepMap::kJointStateSize;  // 16
using StateVector = StepMap::StateVector;
using StepJacobian = StepMap::StepJacobian;
using StepControlJacobian = StepMap::StepControlJacobian;
using JointStepJacobian = StepMap::JointStepJacobian;
using JointControlJacobian = StepMap::JointControlJacobian;

}  // namespace hmpc::humanoid
