#include "hmpc/humanoid/contact.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "hmpc/humanoid/spatial.hpp"

namespace hmpc::humanoid {
namespace {

// log(1 + e^x) and its slope, the logistic function, without overflow, from e = e^-|x|: where
// both are needed they share one exponential (the numbers are those of each alone).
double softplus(double x, double e) { return std::max(x, 0.0) + std::log1p(e); }
double logistic(double x, double e) { return x >= 0.0 ? 1.0 / (1.0 + e) : e / (1.0 + e); }
double softplus(double x) { return softplus(x, std::exp(-std::abs(x))); }
double logistic(double x) { return logistic(x, std::exp(-std::abs(x))); }

}  // namespace

using spatial::skew;

template <int A>
BasicPointJacobian<A> point_jacobian(const BasicModel<A>& model,
                                     const BasicKinematics<A>& kinematics, int body,
                                     const Vector3& local) {
  using PointJacobian = BasicPointJacobian<A>;
  // Base columns from p_dot = R (v_o + omega x (p - p_0)_torso); joint columns
  // (R_b axis_b) x (p - p_b) for every joint b between the torso and the body.
  const Vector3 p = kinematics.position[body] + kinematics.rotation[body] * local;
  PointJacobian J = PointJacobian::Zero();
  J.template leftCols<3>() = -skew(p - kinematics.position[0]) * kinematics.rotation[0];
  J.template middleCols<3>(3) = kinematics.rotation[0];
  for (int b = body; b > 0; b = model.bodies[b].parent) {
    J.col(kBaseDofs + b - 1) =
        (kinematics.rotation[b] * model.bodies[b].axis).cross(p - kinematics.position[b]);
  }
  return J;
}

template <int A>
BasicContactModel<A>::BasicContactModel(const Model& model, const Parameters& p,
                                        const ContactParameters& contact)
    : model_(model), contact_(contact) {
  // Sole rectangle in foot coordinates (origin at the ankle joint, x forward): heel and toe
  // tip from the foot length, sole plane sole_height below the ankle.
  const double foot_length = p.stature / p.reference_stature * p.foot.reference_length;
  const double heel = -p.heel_behind_ankle * foot_length;
  const double toe = heel + foot_length;
  const double half_breadth = 0.5 * contact_.foot_breadth * p.stature;
  const double sole = -model_.sole_height;
  for (int leg = 0; leg < 2; ++leg) {
    const int foot = Model::body_of(leg, kAnkle);
    const int first = leg * kFootPoints;
    points_[first + 0] = {foot, Vector3(heel, half_breadth, sole)};
    points_[first + 1] = {foot, Vector3(heel, -half_breadth, sole)};
    points_[first + 2] = {foot, Vector3(toe, half_breadth, sole)};
    points_[first + 3] = {foot, Vector3(toe, -half_breadth, sole)};
  }
  // Seat points. Thigh coordinates: origin at the hip joint centre, femur along -z, posterior
  // surface on -x (it faces down when the hip is flexed by 90 degrees).
  const double thigh_length = p.stature / p.reference_stature * p.thigh.reference_length;
  int i = kSolePoints;
  for (int side = 0; side < 2; ++side) {
    const double y = side == 0 ? contact_.ischium_half_spacing : -contact_.ischium_half_spacing;
    points_[i++] = {0, Vector3(-contact_.ischium_behind_hip, y, -contact_.ischium_below_hip)};
  }
  for (int leg = 0; leg < 2; ++leg) {
    const int thigh = Model::body_of(leg, kHipFlexion);
    for (double fraction : {0.30, 0.75}) {
      points_[i++] = {thigh, Vector3(-contact_.thigh_half_depth, 0.0, -fraction * thigh_length)};
    }
  }
  for (int k = 0; k < kContactPoints; ++k) {
    int& count = moving_count_[k];
    for (int d = 0; d < kBaseDofs; ++d) moving_dofs_[k][count++] = d;
    for (int b = 1; b < Dimensions<A>::kBodies; ++b) {
      if (moves_with(k, b)) moving_dofs_[k][count++] = kBaseDofs + b - 1;
    }
    MovingRuns& runs = moving_runs_[k];
    for (int c = 0; c < count; ++c) {
      const int dof = moving_dofs_[k][c];
      if (runs.count > 0 && runs.first[runs.count - 1] + runs.length[runs.count - 1] == dof) {
        ++runs.length[runs.count - 1];
      } else {
        runs.first[runs.count] = dof;
        runs.length[runs.count++] = 1;
      }
    }
  }
}

template <int A>
double BasicContactModel<A>::seat_window(double x, double* slope) const {
  const double w = contact_.seat_edge;
  const double left = logistic((x - contact_.seat_x_min) / w),
               right = logistic((contact_.seat_x_max - x) / w);
  // logistic' = sigma (1 - sigma).
  if (slope != nullptr) *slope = (left * (1.0 - left) * right - left * right * (1.0 - right)) / w;
  return left * right;
}

template <int A>
Vector3 BasicContactModel<A>::point_force(double gap, const Vector3& velocity, double scale,
                                          Matrix3* dforce) const {
  return force_at_depth(depth_of(gap), scale, velocity, dforce);
}

template <int A>
double BasicContactModel<A>::depth_of(double gap) const {
  const double s = contact_.smoothing;
  return s * softplus(-gap / s);  // (C1)
}

template <int A>
Vector3 BasicContactModel<A>::force_at_depth(double depth, double scale, const Vector3& velocity,
                                             Matrix3* dforce) const {
  const ContactParameters& c = contact_;
  const double eps = c.clamp_smoothing;
  const double rate_factor = 1.0 - c.damping * velocity.z();  // 1 + c delta_dot
  const double y = rate_factor / eps, e = std::exp(-std::abs(y));
  const double clamp = eps * softplus(y, e);                  // g
  const double normal = scale * c.stiffness * depth * clamp;  // (C2)
  const Eigen::Vector2d slip = velocity.head<2>();
  const double slip_norm = std::sqrt(slip.squaredNorm() + c.slip_velocity * c.slip_velocity);
  Vector3 force;
  force.head<2>() = -c.friction * normal / slip_norm * slip;  // (C3)
  force.z() = normal;
  if (dforce != nullptr) {
    dforce->setZero();
    // d(C3)/dv_t = -mu F_n (1 / r - v_t v_t^T / r^3), r = sqrt(|v_t|^2 + v_s^2).
    dforce->topLeftCorner<2, 2>() =
        -c.friction * normal / slip_norm *
        (Eigen::Matrix2d::Identity() - slip * slip.transpose() / (slip_norm * slip_norm));
    // d(C2)/dphi_dot = -k delta g'(y) c, g' the logistic.
    (*dforce)(2, 2) = -scale * c.stiffness * depth * logistic(y, e) * c.damping;
  }
  return force;
}

template <int A>
void BasicContactModel<A>::evaluate(const Kinematics& kinematics, const Velocity& v,
                                    ContactState& out) const {
  out.count = contact_.chair ? kContactPoints : kSolePoints;
  for (int i = 0; i < out.count; ++i) evaluate_point(i, kinematics, v, out);
}

template <int A>
void BasicContactModel<A>::evaluate_point(int i, const Kinematics& kinematics, const Velocity& v,
                                          ContactState& out) const {
  const ContactPoint& point = points_[i];
  const Vector3 p = kinematics.position[point.body] + kinematics.rotation[point.body] * point.local;
  out.jacobian[i] = point_jacobian(model_, kinematics, point.body, point.local);
  out.position[i] = p;
  out.velocity[i] = out.jacobian[i] * v;
  out.depth[i] = depth_at(i, p);
  out.scale[i] = window_at(i, p);
  out.force[i] =
      force_at_depth(out.depth[i], out.scale[i], out.velocity[i], &out.force_velocity[i]);
}

template <int A>
Vector3 BasicContactModel<A>::force_moving(int i, const ContactState& at, const Vector3& velocity,
                                           Matrix3& dforce) const {
  return force_at_depth(at.depth[i], at.scale[i], velocity, &dforce);
}

template <int A>
Vector3 BasicContactModel<A>::force_at(int i, const Vector3& position, const Vector3& velocity,
                                       Matrix3& dforce) const {
  return force_at_depth(depth_at(i, position), window_at(i, position), velocity, &dforce);
}

template <int A>
double BasicContactModel<A>::depth_at(int i, const Vector3& position) const {
  return depth_of(is_seat_point(i) ? position.z() - contact_.seat_height : position.z());
}

template <int A>
double BasicContactModel<A>::window_at(int i, const Vector3& position) const {
  return is_seat_point(i) ? seat_window(position.x()) : 1.0;
}

template <int A>
PointForceSlopes BasicContactModel<A>::force_slopes(int i, const Vector3& position,
                                                    const Vector3& velocity, const Vector3& w,
                                                    double h) const {
  const ContactParameters& c = contact_;
  const double s = c.smoothing, eps = c.clamp_smoothing, k = c.stiffness, mu = c.friction;
  const bool seat = is_seat_point(i);
  const double gap = seat ? position.z() - c.seat_height : position.z();
  // The seat window S(x) and S'(x); 1 and 0 on the soles.
  double dscale = 0.0;
  const double scale = seat ? seat_window(position.x(), &dscale) : 1.0;
  // (C1), (C2) and their slopes: d depth/dgap = -sigma_d, dg/dv_z = -c sigma_g.
  const double x_d = -gap / s, e_d = std::exp(-std::abs(x_d));
  const double depth = s * softplus(x_d, e_d), sigma_d = logistic(x_d, e_d);
  const double y = 1.0 - c.damping * velocity.z();
  const double x_g = y / eps, e_g = std::exp(-std::abs(x_g));
  const double clamp = eps * softplus(x_g, e_g), sigma_g = logistic(x_g, e_g);
  const double normal = scale * k * depth * clamp;
  Vector3 dnormal;  // dF_n / d(x, gap, v_z)
  dnormal << dscale * k * depth * clamp, -scale * k * sigma_d * clamp,
      -scale * k * depth * c.damping * sigma_g;
  // D's normal entry D_zz = -S k depth c sigma_g and its slopes in (x, gap, v_z).
  const double d_zz = -scale * k * depth * c.damping * sigma_g;
  Vector3 dd_zz;
  dd_zz << -dscale * k * depth * c.damping * sigma_g, scale * k * c.damping * sigma_g * sigma_d,
      scale * k * depth * c.damping * c.damping * sigma_g * (1.0 - sigma_g) / eps;
  // (C3): F_t = -mu F_n t / r, D_tt = -mu F_n Q, Q = (1 - t t^T / r^2) / r; D_tt w_t's slope
  // in t is -mu F_n dE/dt with E = Q w_t = w_t / r - t (t . w_t) / r^3.
  const Eigen::Vector2d t = velocity.head<2>(), wt = w.head<2>();
  const double r2 = t.squaredNorm() + c.slip_velocity * c.slip_velocity, r = std::sqrt(r2);
  const Eigen::Matrix2d Q = (Eigen::Matrix2d::Identity() - t * t.transpose() / r2) / r;
  const Eigen::Vector2d E = Q * wt;
  const double tw = t.dot(wt), r3 = r2 * r;
  const Eigen::Matrix2d dE =
      -(wt * t.transpose() + tw * Eigen::Matrix2d::Identity() + t * wt.transpose()) / r3 +
      3.0 * tw * t * t.transpose() / (r3 * r2);
  PointForceSlopes out;
  out.force.head<2>() = -mu * normal * (t / r + h * E);
  out.force.z() = normal + h * d_zz * w.z();
  // Each of (x, gap, v_z) moves F_n and D_zz; x is p_x and gap is p_z.
  const Eigen::Vector2d by_normal = -mu * (t / r + h * E);
  const auto slope = [&](int n) {
    return Vector3(by_normal.x() * dnormal[n], by_normal.y() * dnormal[n],
                   dnormal[n] + h * dd_zz[n] * w.z());
  };
  out.by_position.col(0) = slope(0);
  out.by_position.col(2) = slope(1);
  out.by_velocity.col(2) = slope(2);
  out.by_velocity.topLeftCorner<2, 2>() = -mu * normal * (Q + h * dE);
  out.by_acceleration.topLeftCorner<2, 2>() = -h * mu * normal * Q;
  out.by_acceleration(2, 2) = h * d_zz;
  return out;
}

template <int A>
bool BasicContactModel<A>::moves_with(int i, int body) const {
  // A parent is numbered below its children (model.hpp).
  int b = points_[i].body;
  while (b > body) b = model_.bodies[b].parent;
  return b == body;
}

template <int A>
void BasicContactModel<A>::subtract_damping(int i, const ContactState& state, double h,
                                            MassMatrix& matrix) const {
  const BasicPointJacobian<A>& J = state.jacobian[i];
  const Eigen::Matrix<double, Dimensions<A>::kDofs, 3> scaled =
      h * J.transpose() * state.force_velocity[i];
  const MovingRuns& runs = moving_runs_[i];
  for (int c = 0; c < moving_count_[i]; ++c) {
    const int col = moving_dofs_[i][c];
    const double j0 = J(0, col), j1 = J(1, col), j2 = J(2, col);
    // Column col's rows from the diagonal down, a run of consecutive rows at a time.
    for (int run = 0; run < runs.count; ++run) {
      const int end = runs.first[run] + runs.length[run];
      const int first = std::max(runs.first[run], col);
      if (first >= end) continue;
      const int n = end - first;
      matrix.col(col).segment(first, n) -=
          (scaled.col(0).segment(first, n) * j0 + scaled.col(1).segment(first, n) * j1) +
          scaled.col(2).segment(first, n) * j2;
    }
  }
}

template <int A>
BasicVelocity<A> BasicContactModel<A>::generalized_force(const ContactState& state) {
  Velocity tau = Velocity::Zero();
  for (int i = 0; i < state.count; ++i)
    tau.noalias() += state.jacobian[i].transpose() * state.force[i];
  return tau;
}

template <int A>
VerticalLoad vertical_load(const BasicContactState<A>& state) {
  VerticalLoad load;
  for (int i = 0; i < state.count; ++i)
    (is_seat_point(i) ? load.seat : load.sole) += state.force[i].z();
  return load;
}

template class BasicContactModel<0>;
template class BasicContactModel<1>;
template BasicPointJacobian<0> point_jacobian(const BasicModel<0>&, const BasicKinematics<0>&, int,
                                              const Vector3&);
template BasicPointJacobian<1> point_jacobian(const BasicModel<1>&, const BasicKinematics<1>&, int,
                                              const Vector3&);
template VerticalLoad vertical_load(const BasicContactState<0>&);
template VerticalLoad vertical_load(const BasicContactState<1>&);

}  // namespace hmpc::humanoid
