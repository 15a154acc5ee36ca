// FDCAN1 of the STM32H743 (RM0433, FDCAN: a Bosch M_CAN core) at register level, in
// classic CAN mode: 11-bit identifiers, 8-byte frames, nominal bit rate only (no FD, no
// bit-rate switching).
//
// Polled, no interrupts: the application drains the RX FIFO and services the error state
// every millisecond. The RX FIFO holds 32 frames: 3.6 ms of a bus saturated with 8-byte
// frames at 1 Mbit/s (111 us or more each); over 20 ms of what the forearm protocol sends to
// one node (sensor every 1 ms, trajectory every 4 ms, heartbeat every 10 ms), so an MPC step
// that delays a poll loses nothing; over 4 ms of what a 4-joint board hears with its sensors
// on the same bus in the HIL (7 frames per ms), and that board has no background work to delay
// the 1 ms drain. Overflows are counted (IR.RF0L), never silent.
#pragma once

#include <cstdint>

#include "clock.hpp"
#include "hmpc/protocol/codec.hpp"
#include "registers.hpp"

namespace hmpc::stm32h7 {

using protocol::Frame;

// Nominal bit timing in time quanta (tq): a bit is 1 (sync) + tseg1 + tseg2 tq, sampled after
// 1 + tseg1. FDCAN_NBTP holds each value minus one: NBRP 1..512, NTSEG1 2..256 tq,
// NTSEG2 2..128 tq, NSJW 1..128 tq (RM0433, FDCAN_NBTP).
struct BitTiming {
  std::uint32_t prescaler = 0;  // kernel clock cycles per tq
  std::uint32_t tseg1 = 0;      // propagation + phase segment 1
  std::uint32_t tseg2 = 0;      // phase segment 2
  std::uint32_t sjw = 0;        // resynchronisation jump width

  constexpr std::uint32_t tq_per_bit() const { return 1 + tseg1 + tseg2; }
  constexpr std::uint32_t sample_point_permille() const {
    return tq_per_bit() == 0 ? 0 : 1000 * (1 + tseg1) / tq_per_bit();
  }
  constexpr std::uint32_t bit_rate(std::uint32_t kernel_hz) const {
    return prescaler == 0 ? 0 : kernel_hz / (prescaler * tq_per_bit());
  }
  // The clock error each node may have (CAN oscillator tolerance conditions, with TSEG2 as
  // the smaller phase segment): min(SJW / (20 bit), TSEG2 / (2 (13 bit - TSEG2))), in ppm.
  constexpr std::uint32_t oscillator_tolerance_ppm() const {
    const std::uint64_t bit = tq_per_bit();
    if (bit == 0) return 0;
    const std::uint64_t resync = 1'000'000ull * sjw / (20 * bit);
    const std::uint64_t phase = 1'000'000ull * tseg2 / (2 * (13 * bit - tseg2));
    return static_cast<std::uint32_t>(resync < phase ? resync : phase);
  }
  constexpr bool valid() const {
    return prescaler >= 1 && prescaler <= 512 && tseg1 >= 2 && tseg1 <= 256 && tseg2 >= 2 &&
           tseg2 <= 128 && sjw >= 1 && sjw <= 128 && sjw <= tseg2 && sjw <= tseg1;
  }
  // The FDCAN_NBTP value: NSJW[31:25], NBRP[24:16], NTSEG1[15:8], NTSEG2[6:0].
  constexpr std::uint32_t nbtp() const {
    return ((sjw - 1) << 25) | ((prescaler - 1) << 16) | ((tseg1 - 1) << 8) | (tseg2 - 1);
  }
};

// The smallest prescaler that divides the kernel clock into a whole number of tq per bit
// (at least 8, for a sample point placeable to within 12.5 %), phase segment 2 rounded to the
// requested sample point and the widest jump width (SJW = phase segment 2, CiA 601-3).
// Returns an invalid timing (prescaler 0) if the bit rate cannot be met exactly.
constexpr BitTiming nominal_bit_timing(std::uint32_t kernel_hz, std::uint32_t bit_rate,
                                       std::uint32_t sample_point_permille) {
  for (std::uint32_t prescaler = 1; prescaler <= 512; ++prescaler) {
    if (kernel_hz % (prescaler * bit_rate) != 0) continue;
    const std::uint32_t tq = kernel_hz / (prescaler * bit_rate);
    if (tq < 8) break;
    BitTiming t;
    t.prescaler = prescaler;
    t.tseg2 = (tq * (1000 - sample_point_permille) + 500) / 1000;
    t.tseg1 = tq - 1 - t.tseg2;
    t.sjw = t.tseg2 < 128 ? t.tseg2 : 128;
    if (t.valid()) return t;
  }
  return BitTiming{};
}

inline constexpr std::uint32_t kSamplePointPermille = 800;
inline constexpr BitTiming k1MbitTiming =
    nominal_bit_timing(clock::kFdcanKernelHz, 1'000'000, kSamplePointPermille);
inline constexpr BitTiming k500kbitTiming =
    nominal_bit_timing(clock::kFdcanKernelHz, 500'000, kSamplePointPermille);
// 80 MHz kernel clock: 1 Mbit/s = 80 tq of 12.5 ns (1 + 63 + 16), SJW 16, sample point 80 %;
// 500 kbit/s = 160 tq of 12.5 ns (1 + 127 + 32), SJW 32, sample point 80 %. Both tolerate
// 0.78 % clock error per node.
static_assert(k1MbitTiming.valid() && k1MbitTiming.prescaler == 1 && k1MbitTiming.tseg1 == 63 &&
              k1MbitTiming.tseg2 == 16 && k1MbitTiming.sjw == 16);
static_assert(k1MbitTiming.bit_rate(clock::kFdcanKernelHz) == 1'000'000 &&
              k1MbitTiming.sample_point_permille() == 800 &&
              k1MbitTiming.oscillator_tolerance_ppm() == 7812);
static_assert(k500kbitTiming.valid() && k500kbitTiming.prescaler == 1 &&
              k500kbitTiming.tseg1 == 127 && k500kbitTiming.tseg2 == 32 &&
              k500kbitTiming.sjw == 32);
static_assert(k500kbitTiming.bit_rate(clock::kFdcanKernelHz) == 500'000 &&
              k500kbitTiming.sample_point_permille() == 800 &&
              k500kbitTiming.oscillator_tolerance_ppm() == 7812);

// The 10 KB message RAM shared by FDCAN1 and FDCAN2 (RM0433, FDCAN message RAM), FDCAN1's
// part laid out from its start, in this one place:
//   0x000  1 standard ID filter element             4 bytes
//   0x004  RX FIFO 0, 32 elements of 16 bytes     512 bytes
//   0x204  TX FIFO, 16 elements of 16 bytes       256 bytes
//   0x304  end (FDCAN2, if ever used, starts here; no extended filters, RX FIFO 1, dedicated
//          RX/TX buffers or TX event FIFO)
// Offsets are bytes from the RAM's base, which is what the start-address fields
// (SIDFC.FLSSA, RXF0C.F0SA, TXBC.TBSA: word addresses in bits [15:2]) take.
struct MessageRam {
  static constexpr std::uint32_t kBase = 0x4000AC00;
  static constexpr std::uint32_t kSizeBytes = 10 * 1024;
  // RX and TX elements: two header words, then an 8-byte data field (RXESC/TXESC = 0b000).
  static constexpr std::uint32_t kElementBytes = 16;
  static constexpr std::uint32_t kStandardFilterBytes = 4;  // one word per filter element

  // One range filter per accepted range (protocol::accepted_ids: the node's block and the
  // bus-wide frames).
  static constexpr std::uint32_t kStandardFilters = protocol::kMaxAcceptedRanges;
  static constexpr std::uint32_t kRxFifo0Elements = 32;
  static constexpr std::uint32_t kTxFifoElements = 16;

  static constexpr std::uint32_t kStandardFilterOffset = 0x000;
  static constexpr std::uint32_t kRxFifo0Offset =
      kStandardFilterOffset + kStandardFilterBytes * kStandardFilters;
  static constexpr std::uint32_t kTxFifoOffset = kRxFifo0Offset + kElementBytes * kRxFifo0Elements;
  static constexpr std::uint32_t kEndOffset = kTxFifoOffset + kElementBytes * kTxFifoElements;

  // Hardware limits: 128 standard filters, 64 RX FIFO elements, 32 TX buffers.
  static_assert(kStandardFilters <= 128 && kRxFifo0Elements <= 64 && kTxFifoElements <= 32);
  static_assert(kEndOffset <= kSizeBytes);
  static_assert(kRxFifo0Offset == 0x020 && kTxFifoOffset == 0x220 && kEndOffset == 0x320);
};

// FDCAN kernel clock source, the RCC_D2CCIP1R.FDCANSEL encoding.
enum class FdcanKernelClock : std::uint32_t { kHse = 0, kPll1Q = 1, kPll2Q = 2 };

struct FdcanConfig {
  // The default assumes clock.cpp's tree: PLL1Q at 80 MHz from HSI.
  FdcanKernelClock kernel_clock = FdcanKernelClock::kPll1Q;
  std::uint32_t kernel_clock_hz = clock::kFdcanKernelHz;
  BitTiming timing = k1MbitTiming;
  // FDCAN1 is alternate function 9 on four pin pairs (STM32H743 datasheet, AF mapping):
  // RX/TX = PD0/PD1 (default), PA11/PA12, PB8/PB9, PH14/PH13.
  Pin rx{Port::D, 0};
  Pin tx{Port::D, 1};
  // Accepted identifiers (protocol::accepted_ids of the board's protocol and node); everything
  // else, extended and remote frames included, is rejected by the hardware filter.
  protocol::AcceptedIds accept{};
};

struct FdcanStatus {
  bool bus_off = false;         // PSR.BO: the controller has left the bus
  bool error_passive = false;   // PSR.EP: an error counter is above 127
  bool error_warning = false;   // PSR.EW: an error counter has reached 96
  std::uint8_t tx_errors = 0;   // ECR.TEC
  std::uint8_t rx_errors = 0;   // ECR.REC (128 when ECR.RP says receive error passive)
  std::uint8_t last_error = 0;  // PSR.LEC: 0 none, 1 stuff, 2 form, 3 ack, 4 bit1, 5 bit0,
                                // 6 CRC, 7 no change since the last read
};

struct FdcanCounters {
  std::uint32_t rx_overflows = 0;  // IR.RF0L events: the full RX FIFO dropped frames
  std::uint32_t tx_full = 0;       // send() calls refused because the TX FIFO was full
  std::uint32_t bus_off_events = 0;
  std::uint32_t bus_off_recoveries = 0;  // restarts after kBusOffRestartDelayMs
};

class Fdcan {
 public:
  enum class InitResult : std::uint8_t {
    kOk,
    kBadTiming,     // FdcanConfig::timing is outside the NBTP ranges
    kBadPins,       // not one of FDCAN1's AF9 pin pairs
    kBadFilters,    // no accepted range, or one outside the standard identifiers
    kInitTimeout,   // CCCR.INIT never read back as set
    kStartTimeout,  // CCCR.INIT never read back as cleared: is the kernel clock running?
  };

  // A bus-off node waits this long before rejoining (the controller then also waits for
  // 128 x 11 recessive bits): a persistently failing node does not flood the bus with errors.
  static constexpr std::uint32_t kBusOffRestartDelayMs = 100;

  InitResult init(const FdcanConfig& config);

  // Queues a frame in the TX FIFO; false if the FIFO is full or the frame is not a classic
  // CAN data frame (identifier above 0x7FF, DLC above 8).
  bool send(const Frame& frame);
  // Takes the oldest frame from RX FIFO 0; false if it is empty.
  bool receive(Frame& frame);

  // Reads the error state (PSR, ECR), counts RX overflows and bus-off events, and restarts
  // the controller kBusOffRestartDelayMs after a bus-off. Call every millisecond.
  FdcanStatus poll(std::uint32_t now_ms);
  const FdcanCounters& counters() const { return counters_; }

  // Leaves the bus at once (CCCR.INIT): pending frames stay unsent. For fatal errors: safe
  // to call in any state, before init() too.
  static void stop();

 private:
  FdcanCounters counters_{};
  bool awaiting_restart_ = false;
  std::uint32_t bus_off_since_ms_ = 0;
};

}  // namespace hmpc::stm32h7
