// TIM4 PWM for the valve and motor bridge; the wiring is assumed, see actuators.hpp.
#include "actuators.hpp"

#include <limits>

#include "registers.hpp"

namespace hmpc::stm32h7::actuators {
namespace {

constexpr Pin kValvePin{Port::D, 12};
constexpr Pin kMotorIn1Pin{Port::D, 14};
constexpr Pin kMotorIn2Pin{Port::D, 15};
constexpr std::uint32_t kTim4AlternateFunction = 2;

}  // namespace

// The mapping at its corners: half scale, clamping, both motor directions, NaN and infinity.
static_assert(compare_values(2.5, 0.0).valve == pwm::kPeriod / 2);
static_assert(compare_values(7.0, 0.0).valve == pwm::kPeriod &&
              compare_values(-1.0, 0.0).valve == 0);
static_assert(compare_values(0.0, 6.0).motor_in1 == pwm::kPeriod / 2 &&
              compare_values(0.0, 6.0).motor_in2 == 0);
static_assert(compare_values(0.0, -6.0).motor_in2 == pwm::kPeriod / 2 &&
              compare_values(0.0, -6.0).motor_in1 == 0);
static_assert(compare_values(std::numeric_limits<double>::quiet_NaN(),
                             std::numeric_limits<double>::quiet_NaN())
                      .valve == 0 &&
              compare_values(0.0, std::numeric_limits<double>::quiet_NaN()).motor_in1 == 0 &&
              compare_values(0.0, std::numeric_limits<double>::quiet_NaN()).motor_in2 == 0);
static_assert(compare_values(0.0, -std::numeric_limits<double>::infinity()).motor_in2 ==
              pwm::kPeriod);

void init() {
  pwm::start(tim4_regs(), rcc::kApb1LenrTim4En, 0b1101);  // channels 1, 3 and 4
  // Pins last: they leave their reset state (input) only once the timer drives them low.
  configure_alternate_function(kValvePin, kTim4AlternateFunction, false);
  configure_alternate_function(kMotorIn1Pin, kTim4AlternateFunction, false);
  configure_alternate_function(kMotorIn2Pin, kTim4AlternateFunction, false);
}

void apply(double valve_volts, double motor_volts) {
  const Compare c = compare_values(valve_volts, motor_volts);
  Timer& t = tim4_regs();
  t.CCR[0] = c.valve;
  t.CCR[2] = c.motor_in1;
  t.CCR[3] = c.motor_in2;
}

void make_safe() {
  drive_low(kValvePin);
  drive_low(kMotorIn1Pin);
  drive_low(kMotorIn2Pin);
}

}  // namespace hmpc::stm32h7::actuators
