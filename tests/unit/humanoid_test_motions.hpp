// Motions the humanoid unit tests share.
#pragma once

#include "hmpc/humanoid/motion.hpp"

namespace hmpc::humanoid::test {

// Every weight zero and one phase: standing still, upright, at 0.85 m (Table 2.2, I).
inline Motion bare_motion() {
  Motion m;
  m.duration = 1.0;
  m.phase_count = 1;
  m.phases[0].height = 0.85;
  return m;
}

}  // namespace hmpc::humanoid::test
