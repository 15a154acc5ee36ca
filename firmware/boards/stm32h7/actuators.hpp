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

#include "pwm.hpp"

namespace hmpc::stm32h7::actuators {

inline constexpr double kValveFullScaleVolts = 5.0;  // the thesis's 0 <= v_p <= 5 V
inline constexpr double kMotorSupplyVolts = 12.0;    // H-bridge supply (assumed)

struct Compare {
  std::uint32_t valve = 0;      // TIM4_CCR1
  std::uint32_t motor_in1 = 0;  // TIM4_CCR3
  std::uint32_t motor_in2 = 0;  // TIM4_CCR4
};

// Timer compare values for the given voltages: clamped to the valve's 0..5 V and the
// bridge's supply; a non-finite voltage gives 0 (safe) on that actuator.
constexpr Compare compare_values(double valve_volts, double motor_volts) {
  const pwm::SignMagnitude motor = pwm::sign_magnitude(motor_volts / kMotorSupplyVolts);
  return {pwm::duty_to_compare(valve_volts / kValveFullScaleVolts), motor.in1, motor.in2};
}

// TIM4 in PWM mode 1 at pwm::kPwmHz, all duties 0, pins switched to the timer.
void init();
void apply(double valve_volts, double motor_volts);
// Safe outputs from any state, even before init() or after a fault: the three pins become
// plain GPIO outputs driven low, whatever the timer does.
void make_safe();

}  // namespace hmpc::stm32h7::actuators
