// System clock configuration (RM0433: PWR voltage scaling, FLASH read latency, RCC PLL and
// system clock switch) and the SysTick millisecond tick.
#include "clock.hpp"

#include "registers.hpp"

namespace hmpc::stm32h7::clock {
namespace {

// At 64 MHz a poll takes a few cycles: 10^6 polls is well over any documented settling time
// (PLL lock and voltage scaling take tens of microseconds).
constexpr std::uint32_t kPollLimit = 1'000'000;

template <typename Ready>
bool wait_until(Ready ready) {
  for (std::uint32_t i = 0; i < kPollLimit; ++i)
    if (ready()) return true;
  return false;
}

// RM0433, table of flash wait states and programming delay: an AXI clock of 185..210 MHz at
// voltage scale 1 needs 2 wait states and the programming delay WRHIGHFREQ = 0b10.
constexpr std::uint32_t kFlashWaitStates = 2;
constexpr std::uint32_t kFlashProgrammingDelay = 2;
static_assert(kAhbHz > 185'000'000 && kAhbHz <= 210'000'000,
              "re-read the RM0433 flash latency table for the new AXI clock");

// D1CFGR.HPRE = 0b1000 (/2); D1PPRE, D2PPRE1/2, D3PPRE = 0b100 (/2); D1CPRE = 0 (/1).
constexpr std::uint32_t kAhbDivideBy2 = 0b1000;
constexpr std::uint32_t kApbDivideBy2 = 0b100;

volatile std::uint32_t g_milliseconds = 0;

}  // namespace

Status configure_system_clock() {
  Pwr& pwr = pwr_regs();
  Rcc& rcc = rcc_regs();
  Flash& flash = flash_regs();

  // Supply configuration (RM0433, PWR): the H743 has no SMPS; its core is fed by the LDO.
  // PWR_CR3 accepts one write after power-on, and voltage scaling waits for it.
  pwr.CR3 = (pwr.CR3 & ~(pwr::kCr3ScuEn | pwr::kCr3LdoEn | pwr::kCr3Bypass)) | pwr::kCr3LdoEn;
  if (!wait_until([&] { return (pwr.CSR1 & pwr::kCsr1ActVosRdy) != 0; }))
    return Status::kSupplyNotReady;

  // Voltage scale 1 before any clock above the reset scale's limits.
  pwr.D3CR = (pwr.D3CR & ~pwr::kD3crVosMask) | (pwr::kVosScale1 << pwr::kD3crVosShift);
  (void)pwr.D3CR;  // read back: VOSRDY is valid only after the write reached the PWR block
  if (!wait_until([&] { return (pwr.D3CR & pwr::kD3crVosRdy) != 0; }))
    return Status::kVoltageNotReady;

  // A debugger restart or a boot loader may have left PLL1 driving the core: return to HSI
  // /1 and stop PLL1 before reprogramming it (its dividers are writable only while off).
  rcc.CFGR = rcc.CFGR & ~rcc::kCfgrSwMask;  // SW = 0: HSI
  if (!wait_until([&] { return (rcc.CFGR & rcc::kCfgrSwsMask) == 0; }))
    return Status::kSwitchNotDone;
  rcc.CR = rcc.CR & ~rcc::kCrHsiDivMask;  // HSIDIV = /1: 64 MHz
  rcc.CR = rcc.CR & ~rcc::kCrPll1On;
  constexpr std::uint32_t kHsiSettled = rcc::kCrHsiRdy | rcc::kCrHsiDivF;
  if (!wait_until([&] { return (rcc.CR & (rcc::kCrPll1Rdy | kHsiSettled)) == kHsiSettled; }))
    return Status::kPllNotStopped;

  // More wait states before the faster clock, confirmed by reading back (RM0433, FLASH_ACR).
  flash.ACR = (flash.ACR & ~(flash::kAcrLatencyMask | flash::kAcrWrHighFreqMask)) |
              kFlashWaitStates | (kFlashProgrammingDelay << flash::kAcrWrHighFreqShift);
  if ((flash.ACR & flash::kAcrLatencyMask) != kFlashWaitStates) return Status::kFlashLatency;

  // PLL1 from HSI: PLLSRC = 0 (HSI), DIVM1; input range 8..16 MHz (PLL1RGE = 0b11), wide VCO,
  // integer mode; outputs P (system) and Q (FDCAN) enabled, R unused and off.
  rcc.PLLCKSELR = (rcc.PLLCKSELR & ~((0x3Fu << 4) | 0x3u)) | (kPll1InputDivider << 4);
  rcc.PLLCFGR = (rcc.PLLCFGR & ~(0xFu | (0x7u << 16))) | (0x3u << 2) | (1u << 16) | (1u << 17);
  rcc.PLL1FRACR = 0;
  rcc.PLL1DIVR =
      (kPll1Multiplier - 1) | ((kPll1PDivider - 1) << 9) | ((kPll1QDivider - 1) << 16) | (1u << 24);
  rcc.CR = rcc.CR | rcc::kCrPll1On;
  if (!wait_until([&] { return (rcc.CR & rcc::kCrPll1Rdy) != 0; })) return Status::kPllNotLocked;

  // Bus prescalers before the switch, so no bus ever runs above its limit.
  rcc.D1CFGR = (rcc.D1CFGR & ~0xF7Fu) | kAhbDivideBy2 | (kApbDivideBy2 << 4);
  rcc.D2CFGR = (rcc.D2CFGR & ~0x770u) | (kApbDivideBy2 << 4) | (kApbDivideBy2 << 8);
  rcc.D3CFGR = (rcc.D3CFGR & ~0x70u) | (kApbDivideBy2 << 4);

  rcc.CFGR = (rcc.CFGR & ~rcc::kCfgrSwMask) | rcc::kCfgrSwPll1;
  if (!wait_until([&] { return (rcc.CFGR & rcc::kCfgrSwsMask) == rcc::kCfgrSwsPll1; }))
    return Status::kSwitchNotDone;
  return Status::kOk;
}

void start_millisecond_tick() {
  constexpr std::uint32_t kReload = kCpuHz / 1000 - 1;
  static_assert(kCpuHz % 1000 == 0 && kReload <= 0xFFFFFFu, "SysTick reload is 24 bits");
  SysTick& systick = systick_regs();
  systick.RVR = kReload;
  systick.CVR = 0;
  systick.CSR = 0x7;  // ENABLE | TICKINT | CLKSOURCE = processor clock
}

std::uint32_t milliseconds() { return g_milliseconds; }

void start_cycle_counter() {
  dwt::DEMCR() = dwt::DEMCR() | dwt::kDemcrTrcEna;
  dwt::LAR() = dwt::kLarUnlockKey;
  dwt::CYCCNT() = 0;
  dwt::CTRL() = dwt::CTRL() | dwt::kCtrlCycCntEna;
}

double seconds() {
  static std::uint32_t last_count = 0;
  static std::uint32_t wraps = 0;
  const std::uint32_t count = dwt::CYCCNT();
  if (count < last_count) ++wraps;
  last_count = count;
  return (double(wraps) * 4294967296.0 + double(count)) / double(kCpuHz);
}

}  // namespace hmpc::stm32h7::clock

extern "C" void SysTick_Handler() {
  hmpc::stm32h7::clock::g_milliseconds = hmpc::stm32h7::clock::g_milliseconds + 1;
}
