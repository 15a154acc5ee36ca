// The biped standing still on level ground: the MPC's starting state (host) and the HIL plant's
// starting posture (hil), so one computation for both.
#pragma once

#include "hmpc/humanoid/contact.hpp"
#include "hmpc/humanoid/model.hpp"

namespace hmpc::humanoid {

// The base point (torso coordinates) whose height and velocity Eqs. 4.26-4.27 regulate and at
// which a stance's height is given. Choice: 7 cm above the hip joint centres, inside the pelvis
// (the lumbosacral joint is about 10 cm above them). The torso origin, at the hip joint centres,
// stands at most 0.79 m high in our de Leva model (1 cm sole sink), below Table 2.2's 0.85 m
// standing target; 7 cm higher, the 0.85 m target is a stance with the knees bent about 20
// degrees.
inline const Vector3 kBasePoint(0.0, 0.0, 0.07);

// At rest, torso upright, feet flat and parallel to it, soles sunk by the standing load
// (standing_sink), the centre of mass over the soles' centre, which stands at x = y = 0, and
// `base_point` (torso coordinates) `height` above the sunk sole plane; the knees bend as that
// height needs (bisection), the hips balance it (secant iterations).
BasicState<0> standing_stance(const Parameters& parameters, const ContactParameters& contact,
                              const Vector3& base_point, double height);
// The same at kBasePoint with the nominal contact.
inline BasicState<0> standing_stance(const Parameters& parameters, double height) {
  return standing_stance(parameters, ContactParameters{}, kBasePoint, height);
}

}  // namespace hmpc::humanoid
