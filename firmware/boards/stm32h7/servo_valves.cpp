// Sign-magnitude PWM for the servo-valve coils; the wiring is assumed, see servo_valves.hpp.
#include "servo_valves.hpp"

#include "pwm.hpp"
#include "registers.hpp"

namespace hmpc::stm32h7::servo_valves {
namespace {

constexpr std::array<Pin, kValves> kIn1Pins{
    {{Port::D, 12}, {Port::D, 13}, {Port::D, 14}, {Port::D, 15}}};
constexpr std::array<Pin, kValves> kIn2Pins{
    {{Port::C, 6}, {Port::C, 7}, {Port::C, 8}, {Port::C, 9}}};
constexpr std::uint32_t kTim3Tim4AlternateFunction = 2;
constexpr std::uint32_t kAllChannels = 0b1111;

}  // namespace

void init() {
  pwm::start(tim4_regs(), rcc::kApb1LenrTim4En, kAllChannels);
  pwm::start(tim3_regs(), rcc::kApb1LenrTim3En, kAllChannels);
  // Pins last: they leave their reset state (input) only once the timers drive them low.
  for (std::size_t j = 0; j < kValves; ++j) {
    configure_alternate_function(kIn1Pins[j], kTim3Tim4AlternateFunction, false);
    configure_alternate_function(kIn2Pins[j], kTim3Tim4AlternateFunction, false);
  }
}

void apply(const std::array<double, kValves>& u) {
  Timer& in1 = tim4_regs();
  Timer& in2 = tim3_regs();
  for (std::size_t j = 0; j < kValves; ++j) {
    const pwm::SignMagnitude drive = pwm::sign_magnitude(u[j]);
    in1.CCR[j] = drive.in1;
    in2.CCR[j] = drive.in2;
  }
}

void make_safe() {
  for (std::size_t j = 0; j < kValves; ++j) {
    drive_low(kIn1Pins[j]);
    drive_low(kIn2Pins[j]);
  }
}

}  // namespace hmpc::stm32h7::servo_valves
