#include "hmpc/ioc/feasibility.hpp"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "hmpc/ioc/demonstrator.hpp"
#include "hmpc/ioc/retargeting.hpp"

namespace hmpc::ioc {

using humanoid::Configuration;
using humanoid::Vector6;

namespace {

constexpr int kEdges = 4;  // of the friction pyramid
constexpr int kGenerators = humanoid::kSolePoints * kEdges;
using Generators = Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, kGenerators>;

// Lawson and Hanson's active-set method for min ||G x - b||, x >= 0 ("Solving Least Squares
// Problems", 1974, Ch. 23): the distance from b to the cone G spans. Returns that distance.
double cone_distance(const Generators& G, const Vector6& b) {
  const int n = static_cast<int>(G.cols());
  if (n == 0) return b.norm();
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n), z(n);
  std::vector<bool> passive(n, false);
  constexpr double kTolerance = 1e-12;
  // Least squares over the passive set, zero elsewhere.
  const auto solve_passive = [&](Eigen::VectorXd& out) {
    std::vector<int> columns;
    for (int j = 0; j < n; ++j) {
      if (passive[j]) columns.push_back(j);
    }
    Eigen::MatrixXd A(6, columns.size());
    for (std::size_t c = 0; c < columns.size(); ++c) A.col(c) = G.col(columns[c]);
    const Eigen::VectorXd y = A.colPivHouseholderQr().solve(b);
    out.setZero();
    for (std::size_t c = 0; c < columns.size(); ++c) out[columns[c]] = y[c];
  };
  for (int outer = 0; outer < 3 * n; ++outer) {
    const Eigen::VectorXd w = G.transpose() * (b - G * x);
    int best = -1;
    for (int j = 0; j < n; ++j) {
      if (!passive[j] && w[j] > kTolerance && (best < 0 || w[j] > w[best])) best = j;
    }
    if (best < 0) break;
    passive[best] = true;
    solve_passive(z);
    for (int inner = 0; inner < 3 * n; ++inner) {
      double alpha = std::numeric_limits<double>::infinity();
      for (int j = 0; j < n; ++j) {
        if (passive[j] && z[j] <= 0.0) alpha = std::min(alpha, x[j] / (x[j] - z[j]));
      }
      if (!std::isfinite(alpha)) break;
      x += alpha * (z - x);
      for (int j = 0; j < n; ++j) {
        if (passive[j] && x[j] <= kTolerance) {
          passive[j] = false;
          x[j] = 0.0;
        }
      }
      solve_passive(z);
    }
    x = z;
  }
  return (G * x - b).norm();
}

}  // namespace

FeasibilityIndex::FeasibilityIndex(const humanoid::Parameters& robot,
                                   const FeasibilityConfig& config)
    : config_(config), dynamics_(humanoid::Model(robot)),
      contact_(humanoid::Model(robot), robot, humanoid::ContactParameters{}) {
  const double weight = dynamics_.model().total_mass() * dynamics_.model().gravity.norm();
  force_scale_ = 1.0 / weight;
  moment_scale_ = 1.0 / (weight * leg_length(robot));
}

double FeasibilityIndex::operator()(const Configuration& q, const humanoid::Velocity& v,
                                    const humanoid::Velocity& a) {
  // The wrench the contacts must supply: M a + c = tau + J'f with the base unactuated, so the
  // base rows of the RNEA (torso coordinates, moment about the torso origin first).
  const humanoid::Velocity tau = dynamics_.inverse_dynamics(q, v, a);
  dynamics_.kinematics(v, kinematics_);  // at q, reusing the RNEA's joint transforms
  const humanoid::Matrix3& R = kinematics_.rotation[0];
  const humanoid::Vector3& origin = kinematics_.position[0];
  Vector6 needed;
  needed.head<3>() = moment_scale_ * (R * tau.head<3>());
  needed.tail<3>() = force_scale_ * (R * tau.segment<3>(3));
  // The cone: each edge e of each contact point p's pyramid, as the wrench (p x e, e) about the
  // torso origin in world coordinates.
  const double tangent = config_.friction / std::sqrt(2.0);
  const humanoid::Vector3 edges[kEdges] = {
      {tangent, 0.0, 1.0}, {-tangent, 0.0, 1.0}, {0.0, tangent, 1.0}, {0.0, -tangent, 1.0}};
  Generators G(6, kGenerators);
  contacts_ = 0;
  for (int i = 0; i < humanoid::kSolePoints; ++i) {
    const humanoid::ContactPoint& point = contact_.point(i);
    const humanoid::Vector3 p =
        kinematics_.position[point.body] + kinematics_.rotation[point.body] * point.local;
    if (p.z() > config_.contact_height) continue;
    for (int j = 0; j < kEdges; ++j) {
      const humanoid::Vector3 e = edges[j].normalized();
      G.col(kEdges * contacts_ + j) << moment_scale_ * (p - origin).cross(e), force_scale_ * e;
    }
    ++contacts_;
  }
  G.conservativeResize(6, kEdges * contacts_);
  return cone_distance(G, needed);
}

namespace {

struct Derivatives {
  std::vector<humanoid::Velocity> velocity, acceleration;  // per unit of sample index
};

Derivatives per_sample(const std::vector<Configuration>& poses) {
  // Central differences v_k, then a_k = (v_k+1 - v_k-1) / 2 = (q_k+2 - 2 q_k + q_k-2) / 4, the
  // second difference over two samples: exact for a parabola like the one-sample one, with a
  // quarter of its noise (a capture's 3 mm of position noise, low-passed, reads as 0.4 g of
  // acceleration over one 33 Hz sample, 0.1 g over two). The two samples at each end take the
  // acceleration of the nearest sample with the whole stencil.
  Derivatives d;
  for (const humanoid::State& x : with_velocities(poses, 1.0)) d.velocity.push_back(x.v);
  const int n = static_cast<int>(poses.size());
  for (int k = 0; k < n; ++k) {
    const int c = std::clamp(k, 2, n - 3);
    d.acceleration.push_back(0.5 * (d.velocity[c + 1] - d.velocity[c - 1]));
  }
  return d;
}

double level_speed(int j, const WarpConfig& config) {
  return std::exp((j - config.levels) * config.level_step);
}

}  // namespace

std::vector<double> feasible_speeds(const std::vector<Configuration>& poses, double step,
                                    FeasibilityIndex& index, const WarpConfig& config) {
  if (poses.size() < kMinPoses)
    throw std::invalid_argument("feasible_speeds: needs 5 poses or more");
  if (!(step > 0.0)) throw std::invalid_argument("feasible_speeds: the step must be positive");
  const Derivatives d = per_sample(poses);
  const int n = static_cast<int>(poses.size()), levels = 2 * config.levels + 1;
  // Viterbi: cost[k][j] = sample cost(k, j) + min_i (cost[k-1][i] + step cost(i, j)).
  std::vector<double> cost(static_cast<std::size_t>(n) * levels);
  std::vector<int> from(cost.size(), 0);
  const auto at = [levels](int k, int j) { return static_cast<std::size_t>(k) * levels + j; };
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < levels; ++j) {
      const double rate = level_speed(j, config) / step;
      const double f = index(poses[k], rate * d.velocity[k], rate * rate * d.acceleration[k]) /
                       config.index_scale;
      const double s = (j - config.levels) * config.level_step / config.speed_scale;
      double best = 0.0;
      if (k > 0) {
        best = std::numeric_limits<double>::infinity();
        for (int i = 0; i < levels; ++i) {
          const double change = (j - i) * config.level_step / config.smoothness;
          const double c = cost[at(k - 1, i)] + change * change;
          if (c < best) {
            best = c;
            from[at(k, j)] = i;
          }
        }
      }
      cost[at(k, j)] = f * f + s * s + best;
    }
  }
  int j = 0;
  for (int i = 1; i < levels; ++i) {
    if (cost[at(n - 1, i)] < cost[at(n - 1, j)]) j = i;
  }
  std::vector<double> speeds(n);
  for (int k = n - 1; k >= 0; --k) {
    speeds[k] = level_speed(j, config);
    j = from[at(k, j)];
  }
  return speeds;
}

std::vector<double> feasibility_along(const std::vector<Configuration>& poses, double step,
                                      const std::vector<double>& speeds, FeasibilityIndex& index) {
  if (speeds.size() != poses.size() || poses.size() < kMinPoses)
    throw std::invalid_argument("feasibility_along: needs 5 poses or more, a speed for each");
  const Derivatives d = per_sample(poses);
  std::vector<double> out;
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const double rate = speeds[k] / step;
    out.push_back(index(poses[k], rate * d.velocity[k], rate * rate * d.acceleration[k]));
  }
  return out;
}

std::vector<double> warped_indices(const std::vector<double>& speeds, double step,
                                   double out_step) {
  if (speeds.size() < 2) throw std::invalid_argument("warped_indices: needs 2 speeds or more");
  if (!(step > 0.0 && out_step > 0.0))
    throw std::invalid_argument("warped_indices: the steps must be positive");
  for (const double s : speeds) {
    if (!(s > 0.0)) throw std::invalid_argument("warped_indices: a speed must be positive");
  }
  // t[i]: when pose i is reached on the warped timeline.
  std::vector<double> t(speeds.size(), 0.0);
  for (std::size_t i = 1; i < speeds.size(); ++i)
    t[i] = t[i - 1] + 2.0 * step / (speeds[i - 1] + speeds[i]);
  std::vector<double> at;
  std::size_t i = 0;
  for (int k = 0;; ++k) {
    const double time = k * out_step;
    if (time > t.back() + 1e-9 * out_step) break;
    while (i + 2 < t.size() && t[i + 1] < time) ++i;
    at.push_back(std::min(i + (time - t[i]) / (t[i + 1] - t[i]), t.size() - 1.0));
  }
  return at;
}

}  // namespace hmpc::ioc
