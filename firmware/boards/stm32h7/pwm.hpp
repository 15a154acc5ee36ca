// PWM on the general-purpose timers (RM0433, TIM2..TIM5), what every board's actuator drive
// shares: 20 kHz (above hearing, below what bridges and valve amplifiers switch), PWM mode 1
// with preload so that a duty changes only at a period boundary, and the two ways a duty
// drives a load: one pin (a unipolar analogue input through an RC filter) or sign-magnitude
// on a 2-input bridge (a bipolar load: a motor, a servo-valve coil).
#pragma once

#include <cstdint>

#include "clock.hpp"
#include "registers.hpp"

namespace hmpc::stm32h7::pwm {

inline constexpr std::uint32_t kPwmHz = 20'000;
// Counter period in timer clocks: 200 MHz / 20 kHz = 10000 steps of duty resolution.
inline constexpr std::uint32_t kPeriod = clock::kApbTimerHz / kPwmHz;
static_assert(clock::kApbTimerHz % kPwmHz == 0 && kPeriod - 1 <= 0xFFFFu, "16-bit timers");

// A duty cycle 0..1 as a compare value (PWM mode 1: high while CNT < CCR); NaN gives 0.
constexpr std::uint32_t duty_to_compare(double fraction) {
  if (!(fraction > 0.0)) return 0;
  if (fraction >= 1.0) return kPeriod;
  return static_cast<std::uint32_t>(fraction * double(kPeriod) + 0.5);
}

// A signed fraction of full scale on a 2-input bridge: > 0 PWMs IN1, < 0 PWMs IN2, each
// clamped to full duty; 0 and NaN leave both low (the bridge off).
struct SignMagnitude {
  std::uint32_t in1 = 0;
  std::uint32_t in2 = 0;
};
constexpr SignMagnitude sign_magnitude(double fraction) {
  SignMagnitude s;
  if (fraction > 0.0) s.in1 = duty_to_compare(fraction);
  if (fraction < 0.0) s.in2 = duty_to_compare(-fraction);
  return s;
}

// Enables `timer`'s clock (its RCC_APB1LENR bit) and starts it at kPwmHz with every duty 0 on
// the channels of `channels` (bit c - 1 for channel c), outputs active high. The pins are the
// caller's to switch to the timer, after this, so they never drive anything but a low level.
void start(Timer& timer, std::uint32_t rcc_enable_bit, std::uint32_t channels);

}  // namespace hmpc::stm32h7::pwm
