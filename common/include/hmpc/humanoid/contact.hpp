// Smooth compliant contact for the humanoid: the foot soles against the ground (z = 0) and,
// for motion IV, the thighs and pelvis against a horizontal chair seat (thesis Sec. 2.6,
// Table 2.2). Every force is a smooth (C-infinity) function of the state, so the iLQR's
// finite-difference or analytic derivatives see no switching.
//
// Per contact point, with gap phi (height above the surface) and point velocity p_dot (world):
//   penetration  delta   = s softplus(-phi / s)                                         (C1)
//   normal force F_n     = k delta g(1 + c delta_dot),  delta_dot = -phi_dot,            (C2)
//                g(y)    = eps softplus(y / eps)   (a smooth max(y, 0))
//   friction     F_t     = -mu F_n v_t / sqrt(|v_t|^2 + v_s^2)                          (C3)
// (C2) is Hunt & Crossley's (1975) dissipative contact law, F = k delta (1 + c delta_dot):
// its damping is proportional to the penetration, so it vanishes smoothly out of contact and
// the force does not jump at touchdown; g keeps F_n >= 0 (no glue) when the point separates
// fast. (C3) is Coulomb friction |F_t| <= mu F_n regularised to a steep viscous law below the
// slip velocity v_s. Seat forces are multiplied by a smooth window of the seat's x-range.
// Sole points touch only the ground and seat points only the seat (below it the seat is solid).
// Generalized forces are J^T f with the point Jacobian J (p_dot = J v, model.hpp's v).
//
// No call allocates; fixed-size Eigen throughout.
#pragma once

#include <Eigen/Core>
#include <array>

#include "hmpc/humanoid/dynamics.hpp"
#include "hmpc/humanoid/dynamics_derivatives.hpp"

namespace hmpc::humanoid {

struct ContactParameters {
  // Ground normal law. The standing load m g = 461 N spread on 8 sole points is 57.6 N per
  // point; k = 5.8e3 N/m sinks the feet by 57.6 / 5.8e3 = 0.99 cm (the ~1 cm target of soft
  // tissue and shoe sole). The whole body then bounces on 8 k = 46 kN/m at
  // sqrt(46e3 / 47) = 31 rad/s (5 Hz), and a lone foot (0.61 kg on 4 k) at 195 rad/s, so a
  // 1 ms sub-step resolves both (omega h <= 0.2).
  double stiffness = 5.8e3;  // k [N/m] per point
  // Hunt-Crossley c: damping per point k delta c = 57.6 N * c at the standing sink. Critical
  // damping of one foot's mass on its four points is 2 sqrt(4 k m_foot) / 4 = sqrt(k m_foot)
  // = 59 N s/m per point, hence c = 59 / 57.6 = 1.0 s/m. Hunt-Crossley's restitution is then
  // e ~ 1 - (2/3) c v_impact (e ~ 0.3 at 1 m/s: a drop lands, it does not bounce).
  double damping = 1.0;  // c [s/m]
  // Softplus length s: the force is k s log 2 = 4 N at zero gap and falls e-fold every
  // millimetre above it, negligible against the standing 57.6 N; past 1 cm of penetration
  // (C1) equals the linear spring's -phi to s e^-10 = 5e-8 m.
  double smoothing = 1e-3;  // s [m]
  // Smooth clamp of 1 + c delta_dot: eps = 0.05 makes g(1) = 1 to 1e-9 (no bias at rest)
  // while still removing tension once the point separates faster than (1 + eps) / c.
  double clamp_smoothing = 0.05;  // eps [-]
  // Friction: mu = 0.8, rubber sole on a dry floor (0.6-1.0). v_s = 1 cm/s: below the limit
  // a tangential load F < mu F_n creeps at v = v_s (F / mu F_n) / sqrt(1 - (F / mu F_n)^2),
  // 5.8 mm/s at half the limit; the slope mu F_n / v_s (4.6e3 N s/m per standing point) is
  // far too stiff for explicit integration at a 0.61 kg foot, which is why step.hpp treats
  // the contact's velocity dependence implicitly.
  double friction = 0.8;        // mu [-]
  double slip_velocity = 0.01;  // v_s [m/s]

  // Sole geometry the model does not carry: foot breadth 0.055 stature (Drillis & Contini as
  // in Winter 2009, Fig. 4.1), 8.7 cm for 1.59 m. Heel and toe from Parameters.
  double foot_breadth = 0.055;  // fraction of stature

  // Chair (motion IV): a horizontal seat at `seat_height` for x in [seat_x_min, seat_x_max]
  // (world), the window's edges smoothed over `seat_edge` (C-infinity, logistic).
  bool chair = false;
  double seat_height = 0.45;                     // [m]
  double seat_x_min = -0.30, seat_x_max = 0.30;  // [m]
  double seat_edge = 5e-3;                       // [m]
  // Seat points (choice): the ischial tuberosities, which carry most of a seated person's
  // load, 8 cm below and 4 cm behind the mid-hip point and 5.5 cm to each side; and two points
  // per thigh on its posterior surface, 7 cm from the femur axis (half the thigh's
  // antero-posterior depth of a 47 kg adult), at 30 % and 75 % of the thigh length.
  double ischium_below_hip = 0.08, ischium_behind_hip = 0.04, ischium_half_spacing = 0.055;
  double thigh_half_depth = 0.07;
};

constexpr int kFootPoints = 4;                // heel and toe corners, per foot
constexpr int kSolePoints = 2 * kFootPoints;  // 8, indices 0-3 left foot, 4-7 right foot
constexpr int kSeatPoints = 6;                // two ischia, two per thigh
constexpr int kContactPoints = kSolePoints + kSeatPoints;
// The seat points follow the soles; they touch the seat's surface, inside its window in x.
constexpr bool is_seat_point(int i) { return i >= kSolePoints; }

template <int A>
using BasicPointJacobian = Eigen::Matrix<double, 3, Dimensions<A>::kDofs>;

struct ContactPoint {
  int body = 0;
  Vector3 local = Vector3::Zero();  // body coordinates
};

// Everything the step map and checks need about the contacts at one state.
template <int ArmJoints>
struct BasicContactState {
  int count = 0;  // active points: kSolePoints, or kContactPoints with the chair
  std::array<Vector3, kContactPoints> position, velocity, force;       // world
  std::array<BasicPointJacobian<ArmJoints>, kContactPoints> jacobian;  // p_dot = J v
  // df / dp_dot, symmetric negative semi-definite (see ContactModel::point_force).
  std::array<Matrix3, kContactPoints> force_velocity;
  // (C1)'s depth and the seat window at each position (force_moving).
  std::array<double, kContactPoints> depth, scale;
};

// How far `points` sole points in contact sink into the ground on average under a vertical
// `load` [N]: each is a linear spring, so the mean depth is load / (points k) however the load
// is shared among them.
inline double sole_sink(double load, int points, const ContactParameters& contact) {
  return load / (points * contact.stiffness);
}

// How far the soles sink into the ground under a standing robot of `weight` [N], its load
// shared by the eight sole points: the flat ground's height under a standing foot's sole
// points is minus this.
inline double standing_sink(double weight, const ContactParameters& contact) {
  return sole_sink(weight, kSolePoints, contact);
}

template <int ArmJoints>
class BasicContactModel {
 public:
  using Model = BasicModel<ArmJoints>;
  using Kinematics = BasicKinematics<ArmJoints>;
  using Velocity = BasicVelocity<ArmJoints>;
  using ContactState = BasicContactState<ArmJoints>;
  using MassMatrix = BasicMassMatrix<ArmJoints>;

  explicit BasicContactModel(const Model& model = Model{},
                             const Parameters& parameters = Parameters{},
                             const ContactParameters& contact = ContactParameters{});

  const ContactParameters& parameters() const { return contact_; }
  ContactParameters& parameters() { return contact_; }
  const ContactPoint& point(int i) const { return points_[i]; }

  // Positions, Jacobians, velocities, forces and their velocity derivatives at (q, v), from
  // kinematics computed at the same state.
  void evaluate(const Kinematics& kinematics, const Velocity& v, ContactState& out) const;
  // The same for point i only (out's entries i).
  void evaluate_point(int i, const Kinematics& kinematics, const Velocity& v,
                      ContactState& out) const;
  // Force on point i at a world position and velocity, and its velocity derivative (as
  // point_force's).
  Vector3 force_at(int i, const Vector3& position, const Vector3& velocity, Matrix3& dforce) const;
  // The same where point i is in `at` (evaluate_point's), moving at `velocity` instead: the
  // same numbers, without the depth and window of a position that has not moved.
  Vector3 force_moving(int i, const ContactState& at, const Vector3& velocity,
                       Matrix3& dforce) const;
  // The step map's implicit contact force on point i, phi = f + h D w (D = force_at's dforce,
  // w = J a), and its exact slopes in the point's position, velocity and w (D's own
  // derivatives included), for the analytic linearisation.
  PointForceSlopes force_slopes(int i, const Vector3& position, const Vector3& velocity,
                                const Vector3& w, double h) const;
  // Whether point i is carried by `body` (fixed on it or on a descendant), so moves with its
  // joint.
  bool moves_with(int i, int body) const;
  // Whether point i's force reads its world position's coordinate `axis` (0..2): the depth
  // reads z, a seat point's window x, nothing reads y. A point moved along another axis at the
  // same velocity has the same force to the last bit.
  static bool force_reads_position(int i, int axis) {
    return axis == 2 || (axis == 0 && is_seat_point(i));
  }
  // matrix -= h J^T D J for point i of `state` (J its Jacobian, D its force_velocity) on the
  // lower triangle, all that a Cholesky factorisation reads: the step map's implicit damping,
  // M - h sum_i J_i^T D_i J_i. With the numbers of that dense product to the last bit (the same
  // intermediate (h J^T) D, each entry's three terms added left to right as Eigen's
  // matrix-product kernel adds them), on the coordinates that move the point only: J's other
  // columns are exact zeros, which cannot change a sum. (The dense product packs its small
  // operands for Eigen's kernel, on every point of every sub-step.)
  void subtract_damping(int i, const ContactState& state, double h, MassMatrix& matrix) const;

  // sum_i J_i^T f_i: the contact's generalized force, in model.hpp's v coordinates (first six
  // entries the moment about the torso origin and the force, torso coordinates).
  static Velocity generalized_force(const ContactState& state);

  // Force (C1)-(C3) on one point with gap phi and world velocity p_dot, times `scale` (the
  // seat window). If `dforce` is given it receives a symmetric negative semi-definite
  // approximation of df / dp_dot: the exact normal and tangential diagonal blocks, without
  // the normal-tangential coupling mu v_t dF_n / dphi_dot (whose omission keeps it symmetric).
  Vector3 point_force(double gap, const Vector3& velocity, double scale, Matrix3* dforce) const;

 private:
  // point_force's two parts: (C1)'s depth at a gap; the force from it. Point i's depth and
  // seat window (1 on the soles) at a world position.
  double depth_of(double gap) const;
  double depth_at(int i, const Vector3& position) const;
  double window_at(int i, const Vector3& position) const;
  Vector3 force_at_depth(double depth, double scale, const Vector3& velocity,
                         Matrix3* dforce) const;
  // The seat's window S(x) of the seat's x-range, and S'(x) into `slope` if given.
  double seat_window(double x, double* slope = nullptr) const;

  Model model_;
  ContactParameters contact_;
  std::array<ContactPoint, kContactPoints> points_;
  // The coordinates of v that move each point (the base's, then the joints carrying it, in
  // increasing order), and how many.
  std::array<std::array<int, Dimensions<ArmJoints>::kDofs>, kContactPoints> moving_dofs_{};
  std::array<int, kContactPoints> moving_count_{};
  // The same coordinates as runs of consecutive indices.
  struct MovingRuns {
    int count = 0;
    std::array<int, Dimensions<ArmJoints>::kDofs> first{}, length{};
  };
  std::array<MovingRuns, kContactPoints> moving_runs_{};
};

// Jacobian of a point fixed on `body` at `local` (body coordinates): p_dot = J v, p world.
template <int A>
BasicPointJacobian<A> point_jacobian(const BasicModel<A>& model,
                                     const BasicKinematics<A>& kinematics, int body,
                                     const Vector3& local);

// sum of the active points' vertical forces, split into soles and seat.
struct VerticalLoad {
  double sole = 0.0, seat = 0.0;
};
template <int A>
VerticalLoad vertical_load(const BasicContactState<A>& state);

using PointJacobian = BasicPointJacobian<0>;
using ContactState = BasicContactState<0>;
using ContactModel = BasicContactModel<0>;

}  // namespace hmpc::humanoid
