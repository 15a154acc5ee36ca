// The humanoid's discrete step map x_{k+1} = step(x_k, tau, dt) for the MPC and the 1 ms
// simulator (thesis Sec. 2.6.2: x = (q, v), n = 29; u = the 8 joint torques).
//
// Dynamics: M(q) a + c(q, v) = S^T tau + J(q)^T f(q, v) + tau_ext (dynamics.hpp, contact.hpp),
// S = [0 1] selecting the actuated joints; tau_ext an optional generalized disturbance.
//
// Integration (per sub-step of length h): semi-implicit (symplectic) Euler, velocity first,
// with the contact's velocity dependence taken linearly implicitly:
//   (M - h sum_i J_i^T D_i J_i) dv = h (S^T tau - c + sum_i J_i^T f_i + tau_ext),   (S1)
//   v+ = v + dv,
//   p+ = p + h R(quat) v_o+,  quat+ = normalise(quat (x) exp(h omega+ / 2)),           (S2)
//   joints+ = joints + h qdot+,
// with D_i = df_i / dp_dot (ContactModel::point_force). (S1) is one Newton step of backward
// Euler on the contact damping and friction (as in MuJoCo's implicit damping): friction's
// viscous slope mu F_n / v_s = 4.6e3 N s/m per point makes explicit Euler unstable at a free
// foot (h b / m ~ 30 for 0.61 kg at h = 1 ms), while the implicit form is stable for any
// h (D is negative semi-definite, so the matrix stays symmetric positive definite). The
// spring part stays explicit: it is what the sub-step bounds, omega h <= 0.2 for a foot on
// its 4 points (contact.hpp). (S2) moves the quaternion on the unit sphere by the exponential
// map of the body angular velocity (quat_dot = quat (x) (0, omega) / 2, model.hpp).
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
// No call allocates. One instance per thread (it owns a Dynamics workspace).
#pragma once

#include <Eigen/Cholesky>

#include "hmpc/humanoid/contact.hpp"
#include "hmpc/humanoid/dynamics.hpp"

namespace hmpc::humanoid {

struct State {
  Configuration q;
  Velocity v;
};

class StepMap {
 public:
  static constexpr double kMaxRotation = 0.2;  // [rad] per sub-step, see above
  static constexpr int kMaxRefinement = 1000;

  explicit StepMap(const Model& model = Model{}, const Parameters& parameters = Parameters{},
                   const ContactParameters& contact = ContactParameters{},
                   double max_substep = 1e-3);

  // x_{k+1} from x_k under joint torques tau held for dt (> 0), by (S1)-(S2).
  State step(const State& x, const JointVector& tau, double dt,
             const Velocity& external = Velocity::Zero());

  // The fast subsystem's step (Eqs. 2.50-2.51, fast_subsystem.hpp): the base held, pose and
  // velocity (Eq. 2.28: the slow variables are constant on the fast time scale), and the
  // legs moved by the leg rows of (S1) with the base acceleration zero,
  //   (M22 - h sum_i J_i,leg^T D_i J_i,leg) dv_leg = h (tau - c_leg + (sum_i J_i^T f_i)_leg),
  // M22 = epsilon Q22 of Eq. 2.50b. Same sub-steps as step().
  State step_legs(const State& x, const JointVector& tau, double dt);

  // The contact state last evaluated (forces, points, Jacobians): at the start of the last
  // sub-step, or by evaluate_contact().
  const ContactState& contact_state() const { return contact_state_; }
  // Contact forces at a given state, without stepping.
  const ContactState& evaluate_contact(const State& x);

  Dynamics& dynamics() { return dynamics_; }
  ContactModel& contact_model() { return contact_; }
  double max_substep() const { return max_substep_; }

 private:
  State advance(const State& x, const JointVector& tau, double dt, const Velocity& external,
                bool base_held);
  void substep(State& x, const JointVector& tau, double h, const Velocity& external,
               bool base_held);

  Dynamics dynamics_;
  ContactModel contact_;
  double max_substep_;
  // Workspace.
  Kinematics kinematics_;
  ContactState contact_state_;
  MassMatrix iteration_matrix_;
  // Factorised once at construction, so that a copy never reads an uninitialised state.
  Eigen::LLT<MassMatrix> cholesky_{MassMatrix::Identity()};
  Eigen::LLT<Eigen::Matrix<double, kJoints, kJoints>> leg_cholesky_{
      Eigen::Matrix<double, kJoints, kJoints>::Identity()};
};

}  // namespace hmpc::humanoid
