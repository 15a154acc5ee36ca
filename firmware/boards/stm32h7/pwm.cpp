#include "pwm.hpp"

#include <limits>

namespace hmpc::stm32h7::pwm {
namespace {

// PWM mode 1 (OCxM = 0b110: output high while CNT < CCRx) with preload (OCxPE), for the low
// channel of a CCMR register; the high one is 8 bits up.
constexpr std::uint32_t kPwmMode1WithPreload = (6u << 4) | (1u << 3);

}  // namespace

static_assert(sign_magnitude(0.5).in1 == kPeriod / 2 && sign_magnitude(0.5).in2 == 0);
static_assert(sign_magnitude(-2.0).in2 == kPeriod && sign_magnitude(-2.0).in1 == 0);
static_assert(sign_magnitude(std::numeric_limits<double>::quiet_NaN()).in1 == 0 &&
              sign_magnitude(std::numeric_limits<double>::quiet_NaN()).in2 == 0);

void start(Timer& t, std::uint32_t rcc_enable_bit, std::uint32_t channels) {
  Rcc& rcc = rcc_regs();
  rcc.APB1LENR = rcc.APB1LENR | rcc_enable_bit;
  (void)rcc.APB1LENR;  // read back: the timer's clock runs before its first register access
  t.CR1 = 0;
  t.PSC = 0;
  t.ARR = kPeriod - 1;
  std::uint32_t ccmr[2] = {0, 0};
  std::uint32_t ccer = 0;
  for (std::uint32_t c = 0; c < 4; ++c) {
    t.CCR[c] = 0;
    if ((channels & (1u << c)) == 0) continue;
    ccmr[c / 2] |= kPwmMode1WithPreload << (8 * (c % 2));
    ccer |= 1u << (4 * c);  // CCxE, active high
  }
  t.CCMR1 = ccmr[0];
  t.CCMR2 = ccmr[1];
  t.CCER = ccer;
  t.CR1 = 1u << 7;  // ARPE: period and duties change only at an update, never mid-period
  t.EGR = 1u;       // UG: load the preloaded registers now
  t.CR1 = t.CR1 | 1u;
}

}  // namespace hmpc::stm32h7::pwm
