// The joint board's servo valves: up to four coils, each on its own 2-input bridge driven
// sign-magnitude at pwm::kPwmHz (RM0433, general-purpose timers).
//
// ASSUMED WIRING (no schematic exists yet; change it here and in servo_valves.cpp together):
//   valve j (0..3)  IN1 = TIM4_CH(j+1) on PD12..PD15 (AF2)  } coil current + for IN1 PWM,
//                   IN2 = TIM3_CH(j+1) on PC6..PC9 (AF2)    } - for IN2, duty = |u|
// with each bridge's supply and series resistance sized so that full duty drives the valve's
// rated current (the command u is normalised to it, [-1, 1]; the coil's inductance filters the
// 20 kHz PWM to its mean). Both inputs low: no coil current, so the spool returns to its
// hydraulic null by its own feedback spring: the valves centred, the joint board's safe
// state, also when the board is dead or unpowered (pins low or floating into pull-down inputs).
#pragma once

#include <array>
#include <cstddef>

namespace hmpc::stm32h7::servo_valves {

inline constexpr std::size_t kValves = 4;

// Both timers in PWM mode 1, all duties 0, pins switched to the timers.
void init();
// Valve j's coil at u[j] of its rated current (clamped to [-1, 1]; NaN gives 0).
void apply(const std::array<double, kValves>& u);
// Every coil off from any state, even before init() or after a fault: the eight pins become
// plain GPIO outputs driven low, whatever the timers do.
void make_safe();

}  // namespace hmpc::stm32h7::servo_valves
