// GPIO set-up shared by the CAN and actuator pins (RM0433, GPIO).
#include "registers.hpp"

namespace hmpc::stm32h7 {
namespace {

Gpio& enable_port(Port port) {
  Rcc& rcc = rcc_regs();
  rcc.AHB4ENR = rcc.AHB4ENR | (rcc::kAhb4EnrGpioEn0 << static_cast<std::uint32_t>(port));
  (void)rcc.AHB4ENR;  // read back: the clock is running before the first port access
  return gpio_regs(port);
}

void set_field(Reg& reg, std::uint32_t shift, std::uint32_t width, std::uint32_t value) {
  const std::uint32_t mask = ((1u << width) - 1u) << shift;
  reg = (reg & ~mask) | ((value << shift) & mask);
}

}  // namespace

void configure_alternate_function(Pin pin, std::uint32_t af, bool pull_up) {
  Gpio& gpio = enable_port(pin.port);
  const std::uint32_t n = pin.number;
  // Function first, mode last: the pin never drives another alternate function.
  set_field(gpio.AFR[n / 8], 4 * (n % 8), 4, af);
  set_field(gpio.OTYPER, n, 1, 0);       // push-pull
  set_field(gpio.OSPEEDR, 2 * n, 2, 2);  // high speed: clean edges at 1 Mbit/s and 20 kHz PWM
  set_field(gpio.PUPDR, 2 * n, 2, pull_up ? 1 : 0);
  set_field(gpio.MODER, 2 * n, 2, 2);  // alternate function
}

void drive_low(Pin pin) {
  Gpio& gpio = enable_port(pin.port);
  const std::uint32_t n = pin.number;
  gpio.BSRR = 1u << (n + 16);  // output latch low before the pin becomes an output
  set_field(gpio.OTYPER, n, 1, 0);
  set_field(gpio.MODER, 2 * n, 2, 1);  // general-purpose output
}

}  // namespace hmpc::stm32h7
