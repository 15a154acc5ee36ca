#include "hmpc/humanoid/stance.hpp"

#include <algorithm>
#include <cmath>

#include "hmpc/humanoid/dynamics.hpp"

namespace hmpc::humanoid {

BasicState<0> standing_stance(const Parameters& parameters,
                              const ContactParameters& contact_parameters,
                              const Vector3& base_point, double height) {
  const Model model(parameters);
  const ContactModel contact(model, parameters, contact_parameters);
  const Dynamics dynamics(model);
  const double sink = standing_sink(model.total_mass() * -model.gravity.z(), contact_parameters);
  Kinematics kin;
  ContactState soles;

  BasicState<0> x;
  x.v.setZero();
  // Knee flexion k and hip flexion h with the ankle at k - h keep the feet parallel to the
  // upright torso (hip and ankle turn about -y, the knee about +y).
  const auto pose = [&](double knee, double hip) {
    x.q.setZero();
    x.q[3] = 1.0;
    for (int leg = 0; leg < 2; ++leg) {
      x.q[7 + leg * kJointsPerLeg + kHipFlexion] = hip;
      x.q[7 + leg * kJointsPerLeg + kKnee] = knee;
      x.q[7 + leg * kJointsPerLeg + kAnkle] = knee - hip;
    }
    dynamics.kinematics(x.q, x.v, kin);
    contact.evaluate(kin, x.v, soles);
  };
  // Centre of mass minus the sole centre, along x.
  const auto com_offset = [&](double knee, double hip) {
    pose(knee, hip);
    double m = 0.0, com = 0.0, sole = 0.0;
    for (int i = 0; i < kBodies; ++i) {
      m += model.bodies[i].mass;
      com += model.bodies[i].mass * (kin.position[i] + kin.rotation[i] * model.bodies[i].com).x();
    }
    for (int i = 0; i < kSolePoints; ++i) sole += soles.position[i].x() / kSolePoints;
    return com / m - sole;
  };
  // Hip flexion balancing a given knee flexion: secant iterations on com_offset.
  const auto balanced_hip = [&](double knee) {
    double h0 = 0.5 * knee, h1 = 0.5 * knee + 0.01;
    double f0 = com_offset(knee, h0), f1 = com_offset(knee, h1);
    for (int i = 0; i < 30 && std::abs(f1) > 1e-12 && f1 != f0; ++i) {
      const double h2 = h1 - f1 * (h1 - h0) / (f1 - f0);
      h0 = h1;
      f0 = f1;
      h1 = h2;
      f1 = com_offset(knee, h1);
    }
    return h1;
  };
  // Base point height above the soles' sunk plane for a knee flexion.
  const auto base_height = [&](double knee) {
    pose(knee, balanced_hip(knee));
    double lowest = soles.position[0].z();
    for (int i = 1; i < kSolePoints; ++i) lowest = std::min(lowest, soles.position[i].z());
    return (kin.position[0] + kin.rotation[0] * base_point).z() - lowest - sink;
  };
  // Bisection on the knee: the base point lowers monotonically as the knee bends.
  double straight = 0.0, bent = model.joint_upper[kKnee];
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (straight + bent);
    (base_height(mid) > height ? straight : bent) = mid;
  }
  const double knee = 0.5 * (straight + bent);
  const double hip = balanced_hip(knee);
  pose(knee, hip);
  double lowest = soles.position[0].z(), centre = 0.0;
  for (int i = 0; i < kSolePoints; ++i) {
    lowest = std::min(lowest, soles.position[i].z());
    centre += soles.position[i].x() / kSolePoints;
  }
  x.q[0] = -centre;  // sole centre at x = 0
  x.q[2] = -lowest - sink;
  return x;
}

}  // namespace hmpc::humanoid
