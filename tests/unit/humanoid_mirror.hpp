// The biped's mirror image, for the humanoid tests' symmetry checks.
#pragma once

#include <utility>

#include "hmpc/humanoid/model.hpp"

namespace hmpc::humanoid::test {

// x's mirror image in the sagittal (x-z) plane: y and the rotations about x and z change
// sign, the legs swap (positive abduction abducts either leg, model.hpp).
inline State mirrored(const State& x) {
  State m = x;
  m.q[1] = -x.q[1];
  m.q[4] = -x.q[4];  // quaternion (w, x, y, z)
  m.q[6] = -x.q[6];
  m.v[0] = -x.v[0];  // omega, torso axes
  m.v[2] = -x.v[2];
  m.v[4] = -x.v[4];  // v_o, torso axes
  for (int j = 0; j < kJointsPerLeg; ++j) {
    std::swap(m.q[7 + j], m.q[7 + kJointsPerLeg + j]);  // q = (position, quaternion, joints)
    std::swap(m.v[kBaseDofs + j], m.v[kBaseDofs + kJointsPerLeg + j]);
  }
  return m;
}

}  // namespace hmpc::humanoid::test
