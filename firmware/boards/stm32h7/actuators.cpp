// TIM4 PWM for the valve and motor bridge; the wiring is assumed, see actuators.hpp.
#include "actuators.hpp"

#include <cstddef>
#include <limits>

#include "registers.hpp"

namespace hmpc::stm32h7::actuators {
namespace {

// General-purpose timer registers (RM0433, TIM2/TIM3/TIM4/TIM5), TIM4 at 0x4000 0800.
struct Timer {
  Reg CR1;        // 0x00 CEN (bit 0), ARPE (bit 7)
  Reg CR2;        // 0x04
  Reg SMCR;       // 0x08
  Reg DIER;       // 0x0C
  Reg SR;         // 0x10
  Reg EGR;        // 0x14 UG (bit 0)
  Reg CCMR1;      // 0x18 OC1M[6:4], OC1PE (3); OC2M[14:12], OC2PE (11)
  Reg CCMR2;      // 0x1C the same for channels 3 and 4
  Reg CCER;       // 0x20 CCxE at bit 4 (x - 1)
  Reg CNT;        // 0x24
  Reg PSC;        // 0x28
  Reg ARR;        // 0x2C
  Reg reserved0;  // 0x30
  Reg CCR1;       // 0x34
  Reg CCR2;       // 0x38
  Reg CCR3;       // 0x3C
  Reg CCR4;       // 0x40
};
static_assert(offsetof(Timer, CCER) == 0x20 && offsetof(Timer, CCR1) == 0x34 &&
              offsetof(Timer, CCR4) == 0x40);
Timer& tim4() { return *reinterpret_cast<Timer*>(0x40000800); }

constexpr Pin kValvePin{Port::D, 12};
constexpr Pin kMotorIn1Pin{Port::D, 14};
constexpr Pin kMotorIn2Pin{Port::D, 15};
constexpr std::uint32_t kTim4AlternateFunction = 2;

// PWM mode 1 (OCxM = 0b110: output high while CNT < CCRx) with preload (OCxPE).
constexpr std::uint32_t kPwmMode1WithPreload = (6u << 4) | (1u << 3);

}  // namespace

// The mapping at its corners: half scale, clamping, both motor directions, NaN and infinity.
static_assert(compare_values(2.5, 0.0).valve == kPwmPeriod / 2);
static_assert(compare_values(7.0, 0.0).valve == kPwmPeriod && compare_values(-1.0, 0.0).valve == 0);
static_assert(compare_values(0.0, 6.0).motor_in1 == kPwmPeriod / 2 &&
              compare_values(0.0, 6.0).motor_in2 == 0);
static_assert(compare_values(0.0, -6.0).motor_in2 == kPwmPeriod / 2 &&
              compare_values(0.0, -6.0).motor_in1 == 0);
static_assert(compare_values(std::numeric_limits<double>::quiet_NaN(),
                             std::numeric_limits<double>::quiet_NaN())
                      .valve == 0 &&
              compare_values(0.0, std::numeric_limits<double>::quiet_NaN()).motor_in1 == 0 &&
              compare_values(0.0, std::numeric_limits<double>::quiet_NaN()).motor_in2 == 0);
static_assert(compare_values(0.0, -std::numeric_limits<double>::infinity()).motor_in2 ==
              kPwmPeriod);

void init() {
  Rcc& rcc = rcc_regs();
  rcc.APB1LENR = rcc.APB1LENR | rcc::kApb1LenrTim4En;
  (void)rcc.APB1LENR;
  Timer& t = tim4();
  t.CR1 = 0;
  t.PSC = 0;
  t.ARR = kPwmPeriod - 1;
  t.CCR1 = 0;
  t.CCR3 = 0;
  t.CCR4 = 0;
  t.CCMR1 = kPwmMode1WithPreload;                                // channel 1
  t.CCMR2 = kPwmMode1WithPreload | (kPwmMode1WithPreload << 8);  // channels 3 and 4
  t.CCER = (1u << 0) | (1u << 8) | (1u << 12);                   // CC1E, CC3E, CC4E active high
  t.CR1 = 1u << 7;  // ARPE: period and duties change only at an update, never mid-period
  t.EGR = 1u;       // UG: load the preloaded registers now
  t.CR1 = t.CR1 | 1u;
  // Pins last: they leave their reset state (input) only once the timer drives them low.
  configure_alternate_function(kValvePin, kTim4AlternateFunction, false);
  configure_alternate_function(kMotorIn1Pin, kTim4AlternateFunction, false);
  configure_alternate_function(kMotorIn2Pin, kTim4AlternateFunction, false);
}

void apply(double valve_volts, double motor_volts) {
  const Compare c = compare_values(valve_volts, motor_volts);
  Timer& t = tim4();
  t.CCR1 = c.valve;
  t.CCR3 = c.motor_in1;
  t.CCR4 = c.motor_in2;
}

void make_safe() {
  drive_low(kValvePin);
  drive_low(kMotorIn1Pin);
  drive_low(kMotorIn2Pin);
}

}  // namespace hmpc::stm32h7::actuators
