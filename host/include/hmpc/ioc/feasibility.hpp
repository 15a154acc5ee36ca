// The motion feasibility index and the time warping against it (thesis Sec. 4.2.1, its [26]):
// a retargeted pose sequence, played at some speed, needs a net contact wrench (the floating
// base's rows of the inverse dynamics); the robot's soles can supply only the wrenches of their
// friction cones at the sole points in contact. The index is the distance from the needed wrench
// to that contact wrench cone: zero where the robot can perform the motion without slipping,
// tipping over a sole's edge or being pulled at; in flight the cone is {0} and the index is the
// whole wrench, zero only for a ballistic body. Slowing a motion down scales its accelerations by
// the speed squared and leaves gravity, so each sample gets the speed that brings the index
// nearest zero, within a smooth timeline close to the nominal one.
#pragma once

#include <vector>

#include "hmpc/humanoid/contact.hpp"
#include "hmpc/humanoid/dynamics.hpp"

namespace hmpc::ioc {

struct FeasibilityConfig {
  // A sole point at most this high [m] above the ground is in contact: 2 cm above a standing
  // sole (which sinks 1 cm, contact.hpp), room for the capture's noise and filtering, and below
  // a heel or toe visibly lifted.
  double contact_height = 0.01;
  // The robot's sole-ground friction (contact.hpp's mu), linearised by the pyramid inscribed in
  // its cone (mu / sqrt 2 along 4 edges), so that a wrench inside is inside the true cone.
  double friction = humanoid::ContactParameters{}.friction;
};

// The index is the Euclidean distance in units of body weight: forces divided by m g, moments
// (about the torso origin) by m g l with l the robot's leg length, so that 0.05 reads as 5 % of
// the weight missing, or the centre of pressure 5 % of a leg length outside the support.
class FeasibilityIndex {
 public:
  explicit FeasibilityIndex(const humanoid::Parameters& robot,
                            const FeasibilityConfig& config = FeasibilityConfig{});

  // At configuration q with velocity v and acceleration a (model.hpp's coordinates: a = dv/dt).
  double operator()(const humanoid::Configuration& q, const humanoid::Velocity& v,
                    const humanoid::Velocity& a);
  // The sole points in contact at the last call.
  int contacts() const { return contacts_; }

 private:
  FeasibilityConfig config_;
  humanoid::Dynamics dynamics_;
  humanoid::ContactModel contact_;
  humanoid::Kinematics kinematics_;
  double force_scale_ = 1.0, moment_scale_ = 1.0;
  int contacts_ = 0;
};

struct WarpConfig {
  // Speed factors sigma (against the nominal timeline): geometric levels exp(j step) for
  // |j| <= levels, 0.50..2.01 by default (choice: a factor of two either way; on the human
  // demonstrator's jumps and squats the chosen speeds measured 0.74..1.28, inside it).
  int levels = 14;
  double level_step = 0.05;
  // Each sample's cost (index / index_scale)^2 + (log sigma / speed_scale)^2, and each step
  // between samples (delta log sigma / smoothness)^2 (choice: 5 % of the weight missing costs
  // as much as a speed 1.65 times off the nominal, or a 5 % jump of speed from one sample to the
  // next: the timeline bends only where the motion is infeasible, and smoothly).
  double index_scale = 0.05;
  double speed_scale = 0.5;
  double smoothness = 0.05;
};

// Per-sample speed factors sigma_i for `poses` sampled `step` apart on the nominal timeline: the
// minimum over the levels of the costs above (a Viterbi pass over the samples). Velocities are
// central differences, accelerations second differences over two samples, scaled by
// sigma / step per derivative. Throws std::invalid_argument for fewer than kMinPoses poses or a
// step <= 0.
constexpr std::size_t kMinPoses = 5;  // the acceleration's stencil
std::vector<double> feasible_speeds(const std::vector<humanoid::Configuration>& poses, double step,
                                    FeasibilityIndex& index,
                                    const WarpConfig& config = WarpConfig{});

// The index of each pose played with `speeds` (nominal step `step`), for reporting.
std::vector<double> feasibility_along(const std::vector<humanoid::Configuration>& poses,
                                      double step, const std::vector<double>& speeds,
                                      FeasibilityIndex& index);

// The warped timeline: sample i to i + 1 lasts step / mean(sigma_i, sigma_i+1); returns the
// (fractional) pose index at each time k out_step up to the last pose. Throws
// std::invalid_argument for fewer than 2 speeds, a speed <= 0 or a step <= 0.
std::vector<double> warped_indices(const std::vector<double>& speeds, double step, double out_step);

}  // namespace hmpc::ioc
