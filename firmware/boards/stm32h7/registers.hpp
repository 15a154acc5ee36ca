// STM32H743 core-domain registers used by this board, defined from RM0433 (Rev 7) and the
// ARMv7-M Architecture Reference Manual. Only what the board needs; each block is a volatile
// struct at its base address, with the reference manual's register names and offsets checked
// by static_assert. The FDCAN block is private to fdcan.cpp.
#pragma once

#include <cstddef>
#include <cstdint>

namespace hmpc::stm32h7 {

using Reg = volatile std::uint32_t;

// RCC (RM0433, RCC register map), base 0x5802 4400. The xxxENR registers are the
// CPU-independent aliases at 0x0D4..0x0F4 (not the C1_ copies at 0x130+).
struct Rcc {
  Reg CR;            // 0x000 clock control: HSION/HSIRDY/HSIDIV, PLL1ON/PLL1RDY
  Reg HSICFGR;       // 0x004
  Reg CRRCR;         // 0x008
  Reg CSICFGR;       // 0x00C
  Reg CFGR;          // 0x010 system clock switch SW/SWS
  Reg reserved0;     // 0x014
  Reg D1CFGR;        // 0x018 D1CPRE, HPRE, D1PPRE
  Reg D2CFGR;        // 0x01C D2PPRE1, D2PPRE2
  Reg D3CFGR;        // 0x020 D3PPRE
  Reg reserved1;     // 0x024
  Reg PLLCKSELR;     // 0x028 PLLSRC, DIVM1..3
  Reg PLLCFGR;       // 0x02C PLLxFRACEN/VCOSEL/RGE, DIVyxEN
  Reg PLL1DIVR;      // 0x030 DIVN1, DIVP1, DIVQ1, DIVR1
  Reg PLL1FRACR;     // 0x034
  Reg PLL2DIVR;      // 0x038
  Reg PLL2FRACR;     // 0x03C
  Reg PLL3DIVR;      // 0x040
  Reg PLL3FRACR;     // 0x044
  Reg reserved2;     // 0x048
  Reg D1CCIPR;       // 0x04C
  Reg D2CCIP1R;      // 0x050 FDCANSEL among others
  Reg D2CCIP2R;      // 0x054
  Reg D3CCIPR;       // 0x058
  Reg reserved3;     // 0x05C
  Reg CIER;          // 0x060
  Reg CIFR;          // 0x064
  Reg CICR;          // 0x068
  Reg reserved4;     // 0x06C
  Reg BDCR;          // 0x070
  Reg CSR;           // 0x074
  Reg reserved5;     // 0x078
  Reg AHB3RSTR;      // 0x07C
  Reg AHB1RSTR;      // 0x080
  Reg AHB2RSTR;      // 0x084
  Reg AHB4RSTR;      // 0x088
  Reg APB3RSTR;      // 0x08C
  Reg APB1LRSTR;     // 0x090
  Reg APB1HRSTR;     // 0x094 FDCANRST
  Reg APB2RSTR;      // 0x098
  Reg APB4RSTR;      // 0x09C
  Reg GCR;           // 0x0A0
  Reg reserved6;     // 0x0A4
  Reg D3AMR;         // 0x0A8
  Reg reserved7[9];  // 0x0AC..0x0CC
  Reg RSR;           // 0x0D0
  Reg AHB3ENR;       // 0x0D4
  Reg AHB1ENR;       // 0x0D8
  Reg AHB2ENR;       // 0x0DC
  Reg AHB4ENR;       // 0x0E0 GPIOxEN
  Reg APB3ENR;       // 0x0E4
  Reg APB1LENR;      // 0x0E8 TIMxEN for TIM2..7
  Reg APB1HENR;      // 0x0EC FDCANEN
  Reg APB2ENR;       // 0x0F0
  Reg APB4ENR;       // 0x0F4
};
static_assert(offsetof(Rcc, PLLCKSELR) == 0x028);
static_assert(offsetof(Rcc, D2CCIP1R) == 0x050);
static_assert(offsetof(Rcc, APB1HRSTR) == 0x094);
static_assert(offsetof(Rcc, RSR) == 0x0D0);
static_assert(offsetof(Rcc, AHB4ENR) == 0x0E0);
static_assert(offsetof(Rcc, APB1HENR) == 0x0EC);
static_assert(offsetof(Rcc, APB4ENR) == 0x0F4);

namespace rcc {
inline constexpr std::uint32_t kCrHsiRdy = 1u << 2;
inline constexpr std::uint32_t kCrHsiDivMask = 3u << 3;
inline constexpr std::uint32_t kCrHsiDivF = 1u << 5;  // the HSIDIV ratio has taken effect
inline constexpr std::uint32_t kCrPll1On = 1u << 24;
inline constexpr std::uint32_t kCrPll1Rdy = 1u << 25;
inline constexpr std::uint32_t kCfgrSwMask = 7u << 0;
inline constexpr std::uint32_t kCfgrSwPll1 = 3u << 0;
inline constexpr std::uint32_t kCfgrSwsMask = 7u << 3;
inline constexpr std::uint32_t kCfgrSwsPll1 = 3u << 3;
inline constexpr std::uint32_t kAhb4EnrGpioEn0 = 1u << 0;  // GPIOAEN; port n is bit n
inline constexpr std::uint32_t kApb1LenrTim3En = 1u << 1;
inline constexpr std::uint32_t kApb1LenrTim4En = 1u << 2;
inline constexpr std::uint32_t kApb1HenrFdcanEn = 1u << 8;
inline constexpr std::uint32_t kApb1HrstrFdcanRst = 1u << 8;
inline constexpr std::uint32_t kD2ccip1rFdcanSelShift = 28;
inline constexpr std::uint32_t kD2ccip1rFdcanSelMask = 3u << kD2ccip1rFdcanSelShift;
}  // namespace rcc

// PWR (RM0433, PWR register map), base 0x5802 4800.
struct Pwr {
  Reg CR1;        // 0x00
  Reg CSR1;       // 0x04 ACTVOSRDY, ACTVOS
  Reg CR2;        // 0x08
  Reg CR3;        // 0x0C supply configuration: BYPASS, LDOEN, SCUEN
  Reg CPUCR;      // 0x10
  Reg reserved0;  // 0x14
  Reg D3CR;       // 0x18 VOS, VOSRDY
};
static_assert(offsetof(Pwr, CR3) == 0x0C);
static_assert(offsetof(Pwr, D3CR) == 0x18);

namespace pwr {
inline constexpr std::uint32_t kCr3Bypass = 1u << 0;
inline constexpr std::uint32_t kCr3LdoEn = 1u << 1;
inline constexpr std::uint32_t kCr3ScuEn = 1u << 2;
inline constexpr std::uint32_t kCsr1ActVosRdy = 1u << 13;
inline constexpr std::uint32_t kD3crVosRdy = 1u << 13;
inline constexpr std::uint32_t kD3crVosShift = 14;
inline constexpr std::uint32_t kD3crVosMask = 3u << kD3crVosShift;
inline constexpr std::uint32_t kVosScale1 = 3u;  // VOS = 0b11: scale 1, up to 400 MHz
}  // namespace pwr

// Embedded flash interface (RM0433, FLASH register map), base 0x5200 2000: only FLASH_ACR.
struct Flash {
  Reg ACR;  // 0x00 LATENCY[3:0], WRHIGHFREQ[5:4]
};
namespace flash {
inline constexpr std::uint32_t kAcrLatencyMask = 0xFu;
inline constexpr std::uint32_t kAcrWrHighFreqShift = 4;
inline constexpr std::uint32_t kAcrWrHighFreqMask = 3u << kAcrWrHighFreqShift;
}  // namespace flash

// GPIO port (RM0433, GPIO register map), port A at 0x5802 0000, one port every 0x400.
struct Gpio {
  Reg MODER;    // 0x00 2 bits per pin: 00 input, 01 output, 10 alternate function, 11 analog
  Reg OTYPER;   // 0x04 0 push-pull
  Reg OSPEEDR;  // 0x08 2 bits per pin
  Reg PUPDR;    // 0x0C 2 bits per pin: 01 pull-up
  Reg IDR;      // 0x10
  Reg ODR;      // 0x14
  Reg BSRR;     // 0x18
  Reg LCKR;     // 0x1C
  Reg AFR[2];   // 0x20 AFRL (pins 0..7), 0x24 AFRH (pins 8..15), 4 bits per pin
};
static_assert(offsetof(Gpio, AFR) == 0x20);

// Ports A..K; the index is also the port's RCC_AHB4ENR enable bit.
enum class Port : std::uint8_t { A, B, C, D, E, F, G, H, I, J, K };

struct Pin {
  Port port;
  std::uint8_t number;  // 0..15
};

// SysTick (ARMv7-M B3.3) and the system control block's cache maintenance (B2.2, B3.2).
struct SysTick {
  Reg CSR;  // 0xE000E010 ENABLE, TICKINT, CLKSOURCE
  Reg RVR;  // 0xE000E014 reload value, 24 bits
  Reg CVR;  // 0xE000E018 current value
};
namespace scb {
inline Reg& reg(std::uint32_t address) { return *reinterpret_cast<Reg*>(address); }
inline Reg& CCR() { return reg(0xE000ED14); }      // IC (bit 17), DC (bit 16)
inline Reg& CCSIDR() { return reg(0xE000ED80); }   // geometry of the cache CSSELR selects
inline Reg& CSSELR() { return reg(0xE000ED84); }   // 0: level 1 data cache
inline Reg& ICIALLU() { return reg(0xE000EF50); }  // invalidate the whole instruction cache
inline Reg& DCISW() { return reg(0xE000EF60); }    // invalidate one data cache line by set/way
inline constexpr std::uint32_t kCcrDc = 1u << 16;
inline constexpr std::uint32_t kCcrIc = 1u << 17;
}  // namespace scb

// Data watchpoint and trace unit's cycle counter (ARMv7-M C1.8). The Cortex-M7 DWT has a
// software lock: LAR must be written with the key before CTRL accepts writes.
namespace dwt {
inline Reg& DEMCR() { return scb::reg(0xE000EDFC); }  // TRCENA (bit 24) powers the DWT
inline Reg& CTRL() { return scb::reg(0xE0001000); }   // CYCCNTENA (bit 0)
inline Reg& CYCCNT() { return scb::reg(0xE0001004); }
inline Reg& LAR() { return scb::reg(0xE0001FB0); }
inline constexpr std::uint32_t kDemcrTrcEna = 1u << 24;
inline constexpr std::uint32_t kCtrlCycCntEna = 1u << 0;
inline constexpr std::uint32_t kLarUnlockKey = 0xC5ACCE55u;
}  // namespace dwt

// General-purpose timer (RM0433, TIM2/TIM3/TIM4/TIM5 register map): TIM3 at 0x4000 0400, TIM4
// at 0x4000 0800.
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
  Reg CCR[4];     // 0x34..0x40 CCR1..CCR4
};
static_assert(offsetof(Timer, CCER) == 0x20 && offsetof(Timer, CCR) == 0x34 &&
              sizeof(Timer) == 0x44);

inline Rcc& rcc_regs() { return *reinterpret_cast<Rcc*>(0x58024400); }
inline Pwr& pwr_regs() { return *reinterpret_cast<Pwr*>(0x58024800); }
inline Flash& flash_regs() { return *reinterpret_cast<Flash*>(0x52002000); }
inline Timer& tim3_regs() { return *reinterpret_cast<Timer*>(0x40000400); }
inline Timer& tim4_regs() { return *reinterpret_cast<Timer*>(0x40000800); }
inline SysTick& systick_regs() { return *reinterpret_cast<SysTick*>(0xE000E010); }
inline Gpio& gpio_regs(Port port) {
  return *reinterpret_cast<Gpio*>(0x58020000u + 0x400u * static_cast<std::uint32_t>(port));
}

// Enables a port's clock and puts one pin in alternate function `af`: push-pull, high speed
// (RM0433, GPIO alternate functions), optional pull-up.
void configure_alternate_function(Pin pin, std::uint32_t af, bool pull_up);
// Drives a pin low as a plain push-pull output: the safe state of an actuator line, which
// holds whatever the peripheral that owned the pin is doing.
void drive_low(Pin pin);

// Data and instruction barriers: a register write takes effect before what follows.
inline void dsb() { __asm__ volatile("dsb 0xF" ::: "memory"); }
inline void isb() { __asm__ volatile("isb 0xF" ::: "memory"); }

}  // namespace hmpc::stm32h7
