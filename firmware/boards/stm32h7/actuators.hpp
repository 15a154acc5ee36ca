// Actuator outputs of the forearm board as PWM on TIM4 (RM0433, general-purpose timers).
//
// ASSUMED WIRING (no schematic exists yet; change it here and in actuators.cpp together):
//   PD12 TIM4_CH1 (AF2)  PAM valve command: 20 kHz PWM, RC-filtered and buffered to the
//                        proportional valve's 0..5 V analogue input; duty = v_p / 5 V.
//   PD14 TIM4_CH3 (AF2)  motor H-bridge IN1 } sign-magnitude drive of a 2-input bridge (a
//   PD15 TIM4_CH4 (AF2)  motor H-bridge IN2 } DRV8871-style part): v_m > 0 PWMs IN1, v_m < 0
//                        PWMs IN2, duty = |v_m| / kMotorSupplyVolts; both low: coast.
// Pins low is the safe state on every line: valve vented (0 V), motor bridge off.
#pragma once

#include <cstdint>

#include "clock.hpp"

namespace hmpc::stm32h7::actuators {

inline constexpr double kValveFullScaleVolts = 5.0;  // the thesis's 0 <= v_p <= 5 V
inline constexpr double kMotorSupplyVolts = 12.0;    // H-bridge supply (assumed)
inline constexpr std::uint32_t kPwmHz = 20'000;      // above hearing, below bridge switching limits
// Counter period in timer clocks: 200 MHz / 20 kHz = 10000 steps of duty resolution.
inline constexpr std::uint32_t kPwmPeriod = clock::kApbTimerHz / kPwmHz;
static_assert(clock::kApbTimerHz % kPwmHz == 0 && kPwmPeriod - 1 <= 0xFFFFu, "TIM4 is 16-bit");

struct Compare {
  std::uint32_t valve = 0;      // TIM4_CCR1
  std::uint32_t motor_in1 = 0;  // TIM4_CCR3
  std::uint32_t motor_in2 = 0;  // TIM4_CCR4
};

// A duty cycle 0..1 as a compare value (PWM mode 1: high while CNT < CCR); NaN gives 0.
constexpr std::uint32_t duty_to_compare(double fraction) {
  if (!(fraction > 0.0)) return 0;
  if (fraction >= 1.0) return kPwmPeriod;
  return static_cast<std::uint32_t>(fraction * double(kPwmPeriod) + 0.5);
}

// Timer compare values for the given voltages: clamped to the valve's 0..5 V and the
// bridge's supply; a non-finite voltage gives 0 (safe) on that actuator.
constexpr Compare compare_values(double valve_volts, double motor_volts) {
  Compare c;
  c.valve = duty_to_compare(valve_volts / kValveFullScaleVolts);
  if (motor_volts > 0.0) c.motor_in1 = duty_to_compare(motor_volts / kMotorSupplyVolts);
  if (motor_volts < 0.0) c.motor_in2 = duty_to_compare(-motor_volts / kMotorSupplyVolts);
  return c;
}

// TIM4 in PWM mode 1 at kPwmHz, all duties 0, pins switched to the timer.
void init();
void apply(double valve_volts, double motor_volts);
// Safe outputs from any state, even before init() or after a fault: the three pins become
// plain GPIO outputs driven low, whatever the timer does.
void make_safe();

}  // namespace hmpc::stm32h7::actuators
