#include "hmpc/estimation/invariant_ekf.hpp"

#include <cmath>

#include "hmpc/humanoid/spatial.hpp"

namespace hmpc::estimation {

namespace {

using humanoid::spatial::skew;

// Blocks of the error xi (21): attitude, velocity, position, the two stance points, biases.
constexpr int kPhi = 0, kV = 3, kP = 6, kD = 9, kBg = 15, kBa = 18;
constexpr int kd(int foot) { return kD + 3 * foot; }
constexpr std::uint8_t kFlat = (1U << humanoid::kFootPoints) - 1;

// SO(3)'s exponential and left Jacobian J_l(phi) = I + (1 - cos t) / t^2 [phi]x
// + (t - sin t) / t^3 [phi]x^2, t = |phi| (series near zero).
Matrix3 exp_so3(const Vector3& phi) {
  const double t = phi.norm();
  if (t < 1e-9) return Matrix3::Identity() + skew(phi);
  return Eigen::AngleAxisd(t, phi / t).toRotationMatrix();
}
Matrix3 left_jacobian(const Vector3& phi) {
  const double t = phi.norm();
  const Matrix3 s = skew(phi);
  if (t < 1e-6) return Matrix3::Identity() + 0.5 * s + s * s / 6.0;
  return Matrix3::Identity() + (1 - std::cos(t)) / (t * t) * s +
         (t - std::sin(t)) / (t * t * t) * s * s;
}

}  // namespace

InvariantEkf::InvariantEkf(const humanoid::Parameters& parameters, const InvariantEkfConfig& config)
    : model_(parameters), dynamics_(model_), config_(config), mass_(model_.total_mass()),
      screen_(config.imu, config.stuck_samples) {
  const humanoid::ContactModel contact(model_, parameters, config.contact);
  for (int c = 0; c < humanoid::kFootPoints; ++c) sole_corner_[c] = contact.point(c).local;
}

double InvariantEkf::sink(double load, int feet) const {
  // A pull (a negative load from a specific force below zero) lifts no sole out of the ground.
  return humanoid::sole_sink(std::max(load, 0.0), feet * humanoid::kFootPoints, config_.contact);
}

void InvariantEkf::leg_kinematics(const JointVector& angles, const JointVector& rates) {
  humanoid::Configuration q;
  q << 0, 0, 0, 1, 0, 0, 0, angles;  // the torso at the origin, upright: torso coordinates
  humanoid::Velocity v;
  v << Eigen::Matrix<double, humanoid::kBaseDofs, 1>::Zero(), rates;
  dynamics_.kinematics(q, v, kinematics_);
  for (int foot = 0; foot < kFeet; ++foot) {
    const int body = Model::body_of(foot, humanoid::kAnkle);
    const Matrix3& r = kinematics_.rotation[body];
    // A point's velocity: the body's spatial velocity (omega, v_origin) in its coordinates.
    const auto& s = kinematics_.velocity[body];
    for (int c = 0; c < humanoid::kFootPoints; ++c) {
      const Vector3& local = sole_corner_[c];
      corner_[foot][c] = kinematics_.position[body] + r * local - model_.imu;
      corner_velocity_[foot][c] = r * (s.tail<3>() + s.head<3>().cross(local));
    }
  }
}

std::uint8_t InvariantEkf::support_corners(int foot) const {
  std::array<double, humanoid::kFootPoints> height{};
  double lowest = 0;
  for (int c = 0; c < humanoid::kFootPoints; ++c) {
    height[c] = rotation_.row(2).dot(corner_[foot][c]);
    lowest = c == 0 ? height[c] : std::min(lowest, height[c]);
  }
  std::uint8_t mask = 0;
  for (int c = 0; c < humanoid::kFootPoints; ++c) {
    const bool was = (support_[foot] & (1U << c)) != 0;
    const double band = was ? config_.support_band : config_.support_rejoin;
    if (height[c] <= lowest + band) mask |= static_cast<std::uint8_t>(1U << c);
  }
  return mask;
}

Vector3 InvariantEkf::mean_of_corners(int foot, std::uint8_t mask, Vector3* velocity) const {
  Vector3 point = Vector3::Zero();
  velocity->setZero();
  int count = 0;
  for (int c = 0; c < humanoid::kFootPoints; ++c) {
    if ((mask & (1U << c)) == 0) continue;
    point += corner_[foot][c];
    *velocity += corner_velocity_[foot][c];
    ++count;
  }
  *velocity /= count;
  return point / count;
}

template <int Rows>
void InvariantEkf::update(const Eigen::Matrix<double, Rows, kErrorSize>& h,
                          const Eigen::Matrix<double, Rows, 1>& z,
                          const Eigen::Matrix<double, Rows, Rows>& n,
                          const Eigen::Matrix<double, Rows, Rows>& unused) {
  // K = P H^T S^-1, S = H P H^T + N; an unused measurement's rows are zero in H and z, and
  // identity in S, so they take no part.
  const Eigen::Matrix<double, kErrorSize, Rows> pht = covariance_ * h.transpose();
  const Eigen::Matrix<double, Rows, Rows> s = h * pht + n + unused;
  const Eigen::Matrix<double, kErrorSize, Rows> k = pht * s.inverse();
  const Eigen::Matrix<double, kErrorSize, 1> delta = k * z;
  // X+ = exp(delta) X: rotation Exp(phi); each vector x becomes Exp(phi) x + J_l(phi) xi.
  const Vector3 dphi = delta.template segment<3>(kPhi);
  const Matrix3 dr = exp_so3(dphi), jl = left_jacobian(dphi);
  rotation_ = dr * rotation_;
  velocity_ = dr * velocity_ + jl * delta.template segment<3>(kV);
  position_ = dr * position_ + jl * delta.template segment<3>(kP);
  for (int foot = 0; foot < kFeet; ++foot) {
    stance_point_[foot] = dr * stance_point_[foot] + jl * delta.template segment<3>(kd(foot));
  }
  gyroscope_bias_ += delta.template segment<3>(kBg);
  accelerometer_bias_ += delta.template segment<3>(kBa);
  // Joseph form: (I - K H) P (I - K H)^T + K N K^T, symmetric and positive by construction.
  const Covariance ikh = Covariance::Identity() - k * h;
  covariance_ = ikh * covariance_ * ikh.transpose() + k * n * k.transpose();
}

void InvariantEkf::correct_with_level_soles() {
  // A level sole's normal, R n_i (n_i from the legs, IMU coordinates), is e_z. With
  // R_true = Exp(phi) R: R n_i = Exp(-phi) e_z = e_z + e_z x phi, so z = (R n_i)_xy =
  // (-phi_y, phi_x) = H phi. The soles flat on the ground at rest pass the gate one by one
  // (chi-square, 2 degrees of freedom, 99.9 %: 13.8) and are averaged into one measurement.
  constexpr double kGate = 13.8;
  Eigen::Matrix<double, 2, kErrorSize> h = Eigen::Matrix<double, 2, kErrorSize>::Zero();
  h(0, kPhi + 1) = -1;
  h(1, kPhi) = 1;
  const double variance = config_.level_sole_noise * config_.level_sole_noise;
  const Eigen::Matrix2d n = variance * Eigen::Matrix2d::Identity();
  const Eigen::Matrix2d s = h * covariance_ * h.transpose() + n;
  Vector3 normal = Vector3::Zero();
  for (int foot = 0; foot < kFeet; ++foot) {
    if (support_[foot] != kFlat) continue;
    const int body = Model::body_of(foot, humanoid::kAnkle);
    const Eigen::Vector2d z = (rotation_ * kinematics_.rotation[body].col(2)).head<2>();
    if (z.dot(s.ldlt().solve(z)) <= kGate) normal += kinematics_.rotation[body].col(2);
  }
  if (normal.isZero()) return;
  const Eigen::Vector2d z = (rotation_ * normal.normalized()).head<2>();
  update<2>(h, z, n, Eigen::Matrix2d::Zero());
}

void InvariantEkf::initialize_at_rest(const ImuRest& rest, const JointVector& joint_angles) {
  initialize_at_rest(rest, joint_angles, joint_angles, 0.0);
}

Vector3 InvariantEkf::turn_on_the_feet(const JointVector& from, const JointVector& to) {
  // With a sole fixed in the world, R_torso = R_sole R_fit^T (R_fit: the sole in torso
  // coordinates, from the legs), so the torso turned by R_fit(from) R_fit(to)^T, in its
  // coordinates at `from`; the mean of the two soles' rotation vectors.
  std::array<Matrix3, kFeet> before{};
  leg_kinematics(from, JointVector::Zero());
  for (int foot = 0; foot < kFeet; ++foot) {
    before[foot] = kinematics_.rotation[Model::body_of(foot, humanoid::kAnkle)];
  }
  leg_kinematics(to, JointVector::Zero());
  Vector3 turn = Vector3::Zero();
  for (int foot = 0; foot < kFeet; ++foot) {
    const Eigen::AngleAxisd turned(
        before[foot] * kinematics_.rotation[Model::body_of(foot, humanoid::kAnkle)].transpose());
    turn += turned.angle() * turned.axis() / kFeet;
  }
  return turn;
}

void InvariantEkf::initialize_at_rest(const ImuRest& rest, const JointVector& angles_at_start,
                                      const JointVector& joint_angles, double span) {
  const double g = model_.gravity.norm();
  // The torso's mean rate over the rest, from the legs (zero for a rest without a span), and
  // the mean force turned into the rest's last attitude: the mean stands for the middle one,
  // half the turn before it.
  const Vector3 turn = span > 0 ? turn_on_the_feet(angles_at_start, joint_angles) : Vector3::Zero();
  const Vector3 force = exp_so3(-0.5 * turn) * rest.mean_specific_force();
  // At rest the accelerometer reads R^T (0, 0, g) + b_a: its direction gives roll and pitch
  // (a horizontal bias tilts it, unobservably), its magnitude less g the bias along gravity.
  const Vector3 up = force.normalized();
  rotation_ = Eigen::Quaterniond::FromTwoVectors(up, Vector3::UnitZ()).toRotationMatrix();
  accelerometer_bias_ = (force.norm() - g) * up;
  gyroscope_bias_ =
      rest.mean_angular_velocity() - (span > 0 ? Vector3(turn / span) : Vector3::Zero());
  velocity_.setZero();
  last_rate_.setZero();
  leg_kinematics(joint_angles, JointVector::Zero());
  for (int foot = 0; foot < kFeet; ++foot) {
    support_[foot] = support_corners(foot);
    foot_[foot] = mean_of_corners(foot, support_[foot], &foot_velocity_[foot]);
  }
  position_.setZero();
  for (Vector3& point : stance_point_) point.setZero();
  covariance_.setZero();
  const auto& imu = config_.imu;
  const double a = imu.accelerometer.initial_bias / g, vel = config_.initial_velocity;
  const double pos = config_.initial_position;
  // Yaw is zero by convention: a small variance keeps the matrix positive definite.
  covariance_.block<3, 3>(kPhi, kPhi) = Vector3(a * a, a * a, 1e-4).asDiagonal();
  covariance_.block<3, 3>(kV, kV) = vel * vel * Matrix3::Identity();
  covariance_.block<3, 3>(kP, kP) = pos * pos * Matrix3::Identity();
  for (int foot = 0; foot < kFeet; ++foot) {
    covariance_.block<3, 3>(kd(foot), kd(foot)) = pos * pos * Matrix3::Identity();
  }
  // The rest's mean leaves white noise of density / sqrt(seconds) in the gyroscope's bias and
  // in the accelerometer's along gravity. Across gravity the accelerometer's power-up offset
  // and the attitude's error are one: the mean force R^T g e_z + b_a fixes only their sum, so
  // a tilt phi goes with the offset zeta_a = -g R^T [e_z]x phi (the pair that leaves the
  // velocity's error still at rest, A's [g]x phi - R zeta_a = 0).
  const double t = std::max(rest.seconds, imu.period);
  const double sg = imu.gyroscope.noise_density / std::sqrt(t);
  const double sa = imu.accelerometer.noise_density / std::sqrt(t);
  covariance_.block<3, 3>(kBg, kBg) = sg * sg * Matrix3::Identity();
  const Matrix3 tilt_to_offset = -g * rotation_.transpose() * skew(Vector3::UnitZ());
  const Matrix3 attitude = covariance_.block<3, 3>(kPhi, kPhi);
  covariance_.block<3, 3>(kBa, kPhi) = tilt_to_offset * attitude;
  covariance_.block<3, 3>(kPhi, kBa) = attitude * tilt_to_offset.transpose();
  covariance_.block<3, 3>(kBa, kBa) =
      tilt_to_offset * attitude * tilt_to_offset.transpose() + sa * sa * up * up.transpose();
  correct_with_level_soles();
  // The lower sole on the ground, in the attitude the soles corrected.
  const double lowest = std::min((rotation_ * foot_[0]).z(), (rotation_ * foot_[1]).z());
  position_ = Vector3(0, 0, -sink(mass_ * force.norm(), kFeet) - lowest);
  for (int foot = 0; foot < kFeet; ++foot) {
    stance_point_[foot] = position_ + rotation_ * foot_[foot];
    stance_[foot] = true;
    slipping_[foot] = false;
    fast_samples_[foot] = 0;
  }
  screen_.start(rest.mean_angular_velocity(), force);
  degraded_samples_ = 0;
  lost_ = false;
  on_ground_ = {true, true};
  initialized_ = true;
}

void InvariantEkf::propagate(const sensors::ImuReading& imu, double dt) {
  if (!initialized_) return;
  if (!std::isfinite(dt) || dt <= 0 || dt > config_.max_interval) {
    ++rejected_.bad_interval;
    // A gap too long to integrate loses the estimate; a bad time stamp loses only the sample.
    if (std::isfinite(dt) && dt > config_.max_interval) lost_ = true;
    degraded_samples_ = config_.recovery_samples;
    return;
  }
  const bool good = screen_.check(imu, rejected_);
  save(snapshot_);
  integrate(screen_.last_good().angular_velocity - gyroscope_bias_,
            screen_.last_good().specific_force - accelerometer_bias_, dt);
  if (good) {
    if (degraded_samples_ > 0) --degraded_samples_;
  } else {
    // The reading stood in for is unknown within unknown_rate and unknown_acceleration.
    const double sr = config_.unknown_rate * dt, sa = config_.unknown_acceleration * dt;
    covariance_.block<3, 3>(kPhi, kPhi) += sr * sr * Matrix3::Identity();
    covariance_.block<3, 3>(kV, kV) += sa * sa * Matrix3::Identity();
    degraded_samples_ = config_.recovery_samples;
  }
  if (!finite()) {
    restore(snapshot_);
    ++rejected_.state_not_finite;
    lost_ = true;
  }
}

void InvariantEkf::integrate(const Vector3& w, const Vector3& a, double dt) {
  last_rate_ = w;
  last_specific_force_ = a;
  const Matrix3 r = rotation_;
  const Vector3 v = velocity_, p = position_;
  const Vector3 acceleration = r * a + model_.gravity;  // world

  // A: the right-invariant error's dynamics; only the bias columns depend on the estimate.
  Covariance phi = Covariance::Identity();  // Phi = I + A dt
  phi.block<3, 3>(kV, kPhi) = skew(model_.gravity) * dt;
  phi.block<3, 3>(kP, kV) = Matrix3::Identity() * dt;
  phi.block<3, 3>(kPhi, kBg) = -r * dt;
  phi.block<3, 3>(kV, kBg) = -skew(v) * r * dt;
  phi.block<3, 3>(kP, kBg) = -skew(p) * r * dt;
  for (int foot = 0; foot < kFeet; ++foot) {
    phi.block<3, 3>(kd(foot), kBg) = -skew(stance_point_[foot]) * r * dt;
  }
  phi.block<3, 3>(kV, kBa) = -r * dt;

  // Process noise Ad_X Q Ad_X^T dt: the IMU's and the stance feet's white noise enter in the
  // IMU frame; Ad_X rotates them and couples attitude noise into each vector by [x]x R.
  const auto& gyro = config_.imu.gyroscope;
  const auto& accel = config_.imu.accelerometer;
  const double qg = gyro.noise_density * gyro.noise_density;
  const double qa = accel.noise_density * accel.noise_density;
  Covariance q = Covariance::Zero();
  const Matrix3 rrt_g = qg * Matrix3::Identity();  // R Qg R^T, isotropic
  const std::array<Vector3, 5> columns = {Vector3::Zero(), v, p, stance_point_[0],
                                          stance_point_[1]};
  // Attitude noise in every block (R Qg R^T, cross terms [x]x R Qg R^T [y]x^T).
  for (int i = 0; i < 5; ++i) {
    for (int j = 0; j < 5; ++j) {
      const Matrix3 si = i == 0 ? Matrix3::Identity() : skew(columns[i]);
      const Matrix3 sj = j == 0 ? Matrix3::Identity() : skew(columns[j]);
      q.block<3, 3>(3 * i, 3 * j) = si * rrt_g * sj.transpose();
    }
  }
  q.block<3, 3>(kV, kV) += qa * Matrix3::Identity();
  for (int foot = 0; foot < kFeet; ++foot) {
    const double noise =
        support_[foot] == kFlat ? config_.flat_stance_foot_noise : config_.stance_foot_noise;
    q.block<3, 3>(kd(foot), kd(foot)) += noise * noise * Matrix3::Identity();
  }
  q.block<3, 3>(kBg, kBg) = gyro.bias_random_walk * gyro.bias_random_walk * Matrix3::Identity();
  q.block<3, 3>(kBa, kBa) = accel.bias_random_walk * accel.bias_random_walk * Matrix3::Identity();

  covariance_ = phi * covariance_ * phi.transpose() + q * dt;

  // The mean: R+ = R Exp(w dt), v+ = v + (R a + g) dt, p+ = p + v dt + (R a + g) dt^2 / 2;
  // stance points stay.
  rotation_ = r * exp_so3(w * dt);
  velocity_ = v + acceleration * dt;
  position_ = p + v * dt + 0.5 * acceleration * dt * dt;
}

void InvariantEkf::anchor_swing_foot(int foot) {
  // d = p + R FK: its error is p's (xi_d = xi_p), plus the kinematics' own.
  const int d = kd(foot);
  stance_point_[foot] = position_ + rotation_ * foot_[foot];
  covariance_.block<3, kErrorSize>(d, 0) = covariance_.block<3, kErrorSize>(kP, 0);
  covariance_.block<kErrorSize, 3>(0, d) = covariance_.block<kErrorSize, 3>(0, kP);
  covariance_.block<3, 3>(d, d) = covariance_.block<3, 3>(kP, kP) + config_.kinematics_noise *
                                                                        config_.kinematics_noise *
                                                                        Matrix3::Identity();
}

void InvariantEkf::correct(const JointVector& joint_angles, const JointVector& joint_rates,
                           const std::array<bool, kFeet>& stance) {
  correct_checked(joint_angles, joint_rates, &stance);
}

void InvariantEkf::correct(const JointVector& joint_angles, const JointVector& joint_rates) {
  correct_checked(joint_angles, joint_rates, nullptr);
}

void InvariantEkf::correct_checked(const JointVector& joint_angles, const JointVector& joint_rates,
                                   const std::array<bool, kFeet>* stance) {
  if (!initialized_) return;
  if (!joint_angles.allFinite() || !joint_rates.allFinite()) {
    ++rejected_.joints_not_finite;
    degraded_samples_ = config_.recovery_samples;
    return;
  }
  save(snapshot_);
  correct_with_legs(joint_angles, joint_rates, stance);
  if (!finite()) {
    restore(snapshot_);
    ++rejected_.state_not_finite;
    lost_ = true;
  }
}

void InvariantEkf::correct_with_legs(const JointVector& joint_angles,
                                     const JointVector& joint_rates,
                                     const std::array<bool, kFeet>* asked) {
  leg_kinematics(joint_angles, joint_rates);
  // Which feet are used as fixed: asked to stand, and not sliding. A foot's velocity relative
  // to the IMU is w x FK plus the leg's own motion; in double support the two feet's relative
  // velocity does not involve the estimate's (the legs alone measure it), so a slip is two
  // stance feet moving apart, and the one slipping the faster in the world. In single support
  // the legs cannot tell a slip from an error of the estimated velocity: a test against that
  // velocity would, once it is off by slip_speed, drop every foot and never recover, so a
  // single stance foot is trusted (the innovation gate still rejects a jump).
  std::array<Vector3, kFeet> relative{};
  std::array<std::uint8_t, kFeet> support{};
  std::array<double, kFeet> heights{};
  for (int foot = 0; foot < kFeet; ++foot) {
    support[foot] = support_corners(foot);
    foot_[foot] = mean_of_corners(foot, support[foot], &foot_velocity_[foot]);
    relative[foot] = rotation_ * (last_rate_.cross(foot_[foot]) + foot_velocity_[foot]);
    heights[foot] = position_.z() + rotation_.row(2).dot(foot_[foot]);
    on_ground_[foot] =
        heights[foot] < (on_ground_[foot] ? config_.liftoff_height : config_.touchdown_height);
  }
  // The IMU overrules the legs: none stands in flight, one stands when not (flight_force).
  if (last_specific_force_.norm() < config_.flight_force) {
    on_ground_ = {false, false};
  } else if (!on_ground_[0] && !on_ground_[1]) {
    const int lower = heights[0] < heights[1] ? 0 : 1;
    on_ground_[lower] = heights[lower] < config_.support_reach;
  }
  const std::array<bool, kFeet>& stance = asked != nullptr ? *asked : on_ground_;
  const bool both = stance[0] && stance[1];
  const bool apart = both && (relative[0] - relative[1]).norm() > config_.slip_speed;
  const int faster = (velocity_ + relative[0]).norm() > (velocity_ + relative[1]).norm() ? 0 : 1;
  std::array<bool, kFeet> used{};
  for (int foot = 0; foot < kFeet; ++foot) {
    fast_samples_[foot] = apart && foot == faster ? fast_samples_[foot] + 1 : 0;
    slipping_[foot] = fast_samples_[foot] >= config_.slip_samples;
    // A foot just set down starts from where the legs put its support point. A standing foot
    // that bears on other corners than before (rolling onto its heel or toes, or back flat)
    // moves its stance point by the step from the old support point to the new one along its
    // own sole, which keeps what the filter knew of it, so a leg's kinematics cannot jump
    // past the innovation gate by changing the support.
    if (stance[foot] && !stance_[foot]) {
      anchor_swing_foot(foot);
    } else if (stance[foot] && support[foot] != support_[foot]) {
      Vector3 unused_velocity;
      const Vector3 before = mean_of_corners(foot, support_[foot], &unused_velocity);
      stance_point_[foot] += rotation_ * (foot_[foot] - before);
    }
    support_[foot] = support[foot];
    used[foot] = stance[foot] && !slipping_[foot];
  }

  // Per stance foot, with H = -dz/dxi (so that X+ = exp(K z) X removes the error):
  // kinematics z = R FK_i + p - d_i (zero for a fixed point), H = [0 0 -I ... I at d_i].
  constexpr int kRows = 3 * kFeet + 1, kGround = 3 * kFeet;
  Eigen::Matrix<double, kRows, kErrorSize> h = Eigen::Matrix<double, kRows, kErrorSize>::Zero();
  Eigen::Matrix<double, kRows, 1> z = Eigen::Matrix<double, kRows, 1>::Zero();
  Eigen::Matrix<double, kRows, kRows> n = Eigen::Matrix<double, kRows, kRows>::Zero();
  Eigen::Matrix<double, kRows, kRows> unused = Eigen::Matrix<double, kRows, kRows>::Zero();
  const double nk = config_.kinematics_noise * config_.kinematics_noise;
  bool any = false;
  for (int foot = 0; foot < kFeet; ++foot) {
    const int row = 3 * foot;
    gated_[foot] = false;
    if (!used[foot]) {
      unused.block<3, 3>(row, row).setIdentity();
      continue;
    }
    const Vector3& d = stance_point_[foot];
    const Vector3 innovation = rotation_ * foot_[foot] + position_ - d;
    // Its covariance H P H^T + N: p's and d's blocks, H = [-I, I].
    const Matrix3 spread = covariance_.block<3, 3>(kP, kP) +
                           covariance_.block<3, 3>(kd(foot), kd(foot)) -
                           covariance_.block<3, 3>(kP, kd(foot)) -
                           covariance_.block<3, 3>(kd(foot), kP) + nk * Matrix3::Identity();
    gated_[foot] = innovation.dot(spread.ldlt().solve(innovation)) > config_.innovation_gate;
    if (gated_[foot]) {
      used[foot] = false;
      unused.block<3, 3>(row, row).setIdentity();
      continue;
    }
    any = true;
    z.segment<3>(row) = innovation;
    h.block<3, 3>(row, kP) = -Matrix3::Identity();
    h.block<3, 3>(row, kd(foot)) = Matrix3::Identity();
    n.block<3, 3>(row, row) = nk * Matrix3::Identity();
  }
  // Ground, when every used foot stands flat: the mean height of their stance points is minus
  // their sink, z = mean_i e_z^T d_i + sink, H = mean_i [e_z^T [d_i]x 0 0 ... -e_z^T at d_i]
  // (d_i's error is phi x d_i + xi_d).
  int flat = 0, feet = 0;
  for (int foot = 0; foot < kFeet; ++foot) {
    feet += used[foot] ? 1 : 0;
    flat += used[foot] && support_[foot] == kFlat ? 1 : 0;
  }
  if (flat > 0 && flat == feet) {
    const double load = mass_ * (rotation_ * last_specific_force_).z();
    z[kGround] = sink(load, flat);
    for (int foot = 0; foot < kFeet; ++foot) {
      if (!used[foot]) continue;
      const Vector3& d = stance_point_[foot];
      z[kGround] += d.z() / flat;
      h.block<1, 3>(kGround, kPhi) += Vector3::UnitZ().transpose() * skew(d) / flat;
      h.block<1, 3>(kGround, kd(foot)) = -Vector3::UnitZ().transpose() / flat;
    }
    n(kGround, kGround) = config_.ground_noise * config_.ground_noise;
  } else {
    unused(kGround, kGround) = 1;
  }
  if (any) update<kRows>(h, z, n, unused);
  for (int foot = 0; foot < kFeet; ++foot) {
    if (!used[foot]) anchor_swing_foot(foot);
  }
  stance_ = used;
}

void InvariantEkf::save(Snapshot& out) const {
  out.rotation = rotation_;
  out.velocity = velocity_;
  out.position = position_;
  out.gyroscope_bias = gyroscope_bias_;
  out.accelerometer_bias = accelerometer_bias_;
  out.stance_point = stance_point_;
  out.covariance = covariance_;
}

void InvariantEkf::restore(const Snapshot& in) {
  rotation_ = in.rotation;
  velocity_ = in.velocity;
  position_ = in.position;
  gyroscope_bias_ = in.gyroscope_bias;
  accelerometer_bias_ = in.accelerometer_bias;
  stance_point_ = in.stance_point;
  covariance_ = in.covariance;
}

bool InvariantEkf::finite() const {
  return rotation_.allFinite() && velocity_.allFinite() && position_.allFinite() &&
         gyroscope_bias_.allFinite() && accelerometer_bias_.allFinite() &&
         stance_point_[0].allFinite() && stance_point_[1].allFinite() && covariance_.allFinite() &&
         last_rate_.allFinite();
}

Trust InvariantEkf::trust() const {
  if (!initialized_ || lost_) return Trust::kLost;
  const Spread s = spread();
  if (s.tilt > config_.trusted_tilt_sigma ||
      s.horizontal_velocity > config_.trusted_velocity_sigma) {
    return Trust::kLost;
  }
  return degraded_samples_ > 0 ? Trust::kDegraded : Trust::kTracking;
}

Spread InvariantEkf::spread() const {
  // The right-invariant error's blocks are in world axes: their diagonal, summed per direction.
  Spread s;
  s.height = std::sqrt(covariance_(kP + 2, kP + 2));
  s.horizontal_velocity = std::sqrt(covariance_(kV, kV) + covariance_(kV + 1, kV + 1));
  s.tilt = std::sqrt(covariance_(kPhi, kPhi) + covariance_(kPhi + 1, kPhi + 1));
  return s;
}

BaseEstimate InvariantEkf::estimate() const {
  BaseEstimate e;
  // The torso origin is -imu from the IMU, in torso (= IMU) coordinates.
  e.orientation = Eigen::Quaterniond(rotation_);
  e.angular_velocity = last_rate_;
  e.position = position_ - rotation_ * model_.imu;
  e.velocity = velocity_ - rotation_ * last_rate_.cross(model_.imu);
  e.gyroscope_bias = gyroscope_bias_;
  e.accelerometer_bias = accelerometer_bias_;
  e.stance_points = stance_point_;
  e.stance = stance_;
  e.slipping = slipping_;
  e.gated = gated_;
  for (int foot = 0; foot < kFeet; ++foot) e.support[foot] = stance_[foot] ? support_[foot] : 0;
  e.spread = spread();
  e.trust = trust();
  return e;
}

}  // namespace hmpc::estimation
