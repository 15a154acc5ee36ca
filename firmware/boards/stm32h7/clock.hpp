// Clock tree of the board (RM0433, RCC), one place for every frequency the drivers derive from.
//
//   HSI 64 MHz --/4--> 16 MHz --PLL1 x50--> VCO 800 MHz --P /2--> sys_ck  400 MHz (CPU)
//                                                        --Q /10-> pll1_q_ck 80 MHz (FDCAN)
//   sys_ck --HPRE /2--> 200 MHz AXI/AHB --/2--> APB1..4 100 MHz (timers 200 MHz)
//
// The internal HSI oscillator needs no crystal, so the image runs on any STM32H743 board. It
// is an RC oscillator: the CAN bit timing tolerates 0.78 % clock error per node (fdcan.hpp),
// so check the HSI's accuracy over the board's temperature range in the datasheet. A board
// with a crystal should run PLL1 and FDCAN from HSE (FdcanConfig::kernel_clock); its
// frequency is board-specific, so this tree does not.
//
// 400 MHz at voltage scale 1 runs on both silicon revisions (rev Y: 400 MHz max; rev V:
// 480 MHz needs scale 0 with the overdrive, SYSCFG_PWRCR.ODEN, which this board skips for one
// sequence that is valid on every H743).
#pragma once

#include <cstdint>

namespace hmpc::stm32h7::clock {

inline constexpr std::uint32_t kHsiHz = 64'000'000;
inline constexpr std::uint32_t kPll1InputDivider = 4;  // DIVM1
inline constexpr std::uint32_t kPll1Multiplier = 50;   // DIVN1
inline constexpr std::uint32_t kPll1PDivider = 2;      // DIVP1 -> sys_ck
inline constexpr std::uint32_t kPll1QDivider = 10;     // DIVQ1 -> FDCAN kernel clock
inline constexpr std::uint32_t kPll1InputHz = kHsiHz / kPll1InputDivider;
inline constexpr std::uint32_t kPll1VcoHz = kPll1InputHz * kPll1Multiplier;
inline constexpr std::uint32_t kCpuHz = kPll1VcoHz / kPll1PDivider;
inline constexpr std::uint32_t kAhbHz = kCpuHz / 2;
inline constexpr std::uint32_t kApbHz = kAhbHz / 2;
// An APB prescaler other than 1 doubles the timers' clock (RM0433, RCC; RCC_CFGR.TIMPRE = 0).
inline constexpr std::uint32_t kApbTimerHz = 2 * kApbHz;
inline constexpr std::uint32_t kFdcanKernelHz = kPll1VcoHz / kPll1QDivider;

// RM0433, RCC PLLs: the PLL input range 8..16 MHz is PLL1RGE = 0b11; the wide VCO
// (PLL1VCOSEL = 0) spans 192..836 MHz; PLL1's P divider must be even.
static_assert(kPll1InputHz >= 8'000'000 && kPll1InputHz <= 16'000'000);
static_assert(kPll1VcoHz >= 192'000'000 && kPll1VcoHz <= 836'000'000);
static_assert(kPll1PDivider % 2 == 0);
// Datasheet limits at voltage scale 1 for both revisions: CPU 400, AHB 200, APB 100 MHz.
static_assert(kCpuHz <= 400'000'000 && kAhbHz <= 200'000'000 && kApbHz <= 100'000'000);
static_assert(kFdcanKernelHz == 80'000'000);

enum class Status : std::uint8_t {
  kOk,
  kSupplyNotReady,   // PWR_CSR1.ACTVOSRDY never set
  kVoltageNotReady,  // PWR_D3CR.VOSRDY never set after selecting scale 1
  kPllNotStopped,    // RCC_CR.PLL1RDY stayed set, or HSI not ready at /1
  kFlashLatency,     // FLASH_ACR did not take the new wait states
  kPllNotLocked,     // RCC_CR.PLL1RDY never set
  kSwitchNotDone,    // RCC_CFGR.SWS never reported the new system clock
};

// Supply, voltage scale, flash wait states, PLL1, bus prescalers, switch to PLL1. Called once
// at boot while interrupts are off; on failure the core keeps running from HSI 64 MHz and
// every frequency above is wrong, so the caller must not start the peripherals.
Status configure_system_clock();

// SysTick interrupt every millisecond from the CPU clock.
void start_millisecond_tick();
// Milliseconds since start_millisecond_tick(), wrapping after 49 days.
std::uint32_t milliseconds();

// Seconds from the CPU cycle counter (2.5 ns resolution), for solve deadlines and timing.
// The 32-bit counter wraps every 10.7 s; seconds() counts the wraps it sees, so it is always
// monotonic and exact over any interval shorter than a wrap (a solve's deadline); calls more
// than 10.7 s apart may lose whole wraps. Main-loop context only (not reentrant).
void start_cycle_counter();
double seconds();

}  // namespace hmpc::stm32h7::clock
