// FDCAN1 register-level driver (RM0433, FDCAN). See fdcan.hpp for the configuration it sets.
#include "fdcan.hpp"

#include <cstddef>

namespace hmpc::stm32h7 {
namespace {

// FDCAN1 registers (RM0433, FDCAN register map), base 0x4000 A000.
struct FdcanRegs {
  Reg CREL;          // 0x000 core release
  Reg ENDN;          // 0x004 endianness test value
  Reg reserved0;     // 0x008
  Reg DBTP;          // 0x00C data bit timing (FD only, unused)
  Reg TEST;          // 0x010
  Reg RWD;           // 0x014 RAM watchdog
  Reg CCCR;          // 0x018 CC control
  Reg NBTP;          // 0x01C nominal bit timing and prescaler
  Reg TSCC;          // 0x020
  Reg TSCV;          // 0x024
  Reg TOCC;          // 0x028
  Reg TOCV;          // 0x02C
  Reg reserved1[4];  // 0x030..0x03C
  Reg ECR;           // 0x040 error counter
  Reg PSR;           // 0x044 protocol status
  Reg TDCR;          // 0x048
  Reg reserved2;     // 0x04C
  Reg IR;            // 0x050 interrupt (flags, cleared by writing 1)
  Reg IE;            // 0x054
  Reg ILS;           // 0x058
  Reg ILE;           // 0x05C
  Reg reserved3[8];  // 0x060..0x07C
  Reg GFC;           // 0x080 global filter configuration
  Reg SIDFC;         // 0x084 standard ID filter configuration
  Reg XIDFC;         // 0x088 extended ID filter configuration
  Reg reserved4;     // 0x08C
  Reg XIDAM;         // 0x090
  Reg HPMS;          // 0x094
  Reg NDAT1;         // 0x098
  Reg NDAT2;         // 0x09C
  Reg RXF0C;         // 0x0A0 RX FIFO 0 configuration
  Reg RXF0S;         // 0x0A4 RX FIFO 0 status
  Reg RXF0A;         // 0x0A8 RX FIFO 0 acknowledge
  Reg RXBC;          // 0x0AC RX buffer configuration
  Reg RXF1C;         // 0x0B0
  Reg RXF1S;         // 0x0B4
  Reg RXF1A;         // 0x0B8
  Reg RXESC;         // 0x0BC RX buffer/FIFO element size configuration
  Reg TXBC;          // 0x0C0 TX buffer configuration
  Reg TXFQS;         // 0x0C4 TX FIFO/queue status
  Reg TXESC;         // 0x0C8 TX buffer element size configuration
  Reg TXBRP;         // 0x0CC TX buffer request pending
  Reg TXBAR;         // 0x0D0 TX buffer add request
  Reg TXBCR;         // 0x0D4 TX buffer cancellation request
  Reg TXBTO;         // 0x0D8
  Reg TXBCF;         // 0x0DC
  Reg TXBTIE;        // 0x0E0
  Reg TXBCIE;        // 0x0E4
  Reg reserved5[2];  // 0x0E8..0x0EC
  Reg TXEFC;         // 0x0F0 TX event FIFO configuration
};
static_assert(offsetof(FdcanRegs, CCCR) == 0x018);
static_assert(offsetof(FdcanRegs, ECR) == 0x040);
static_assert(offsetof(FdcanRegs, IR) == 0x050);
static_assert(offsetof(FdcanRegs, GFC) == 0x080);
static_assert(offsetof(FdcanRegs, RXF0C) == 0x0A0);
static_assert(offsetof(FdcanRegs, RXESC) == 0x0BC);
static_assert(offsetof(FdcanRegs, TXBC) == 0x0C0);
static_assert(offsetof(FdcanRegs, TXBAR) == 0x0D0);
static_assert(offsetof(FdcanRegs, TXEFC) == 0x0F0);

FdcanRegs& fdcan1() { return *reinterpret_cast<FdcanRegs*>(0x4000A000); }

// Clock calibration unit configuration, FDCAN_CCU_CCFG (RM0433, FDCAN clock calibration
// unit): shared by both instances, writable only while FDCAN1 has CCCR.INIT and CCCR.CCE set.
Reg& ccu_ccfg() { return *reinterpret_cast<Reg*>(0x4000A804); }
constexpr std::uint32_t kCcfgBypassCalibration = 1u << 6;  // BCC; CDIV[19:16] = 0: divide by 1

// CCCR
constexpr std::uint32_t kCccrInit = 1u << 0;
constexpr std::uint32_t kCccrCce = 1u << 1;
// IR
constexpr std::uint32_t kIrRxFifo0Lost = 1u << 3;  // RF0L
// PSR
constexpr std::uint32_t kPsrLecMask = 0x7u;
constexpr std::uint32_t kPsrErrorPassive = 1u << 5;  // EP
constexpr std::uint32_t kPsrErrorWarning = 1u << 6;  // EW
constexpr std::uint32_t kPsrBusOff = 1u << 7;        // BO
// GFC: non-matching standard and extended frames rejected (ANFS = ANFE = 0b10), remote
// frames of both formats rejected (RRFS, RRFE).
constexpr std::uint32_t kGfcRejectAllElse = (2u << 4) | (2u << 2) | (1u << 1) | (1u << 0);
// RXF0S
constexpr std::uint32_t kRxf0sFillLevelMask = 0x7Fu;  // F0FL[6:0]
constexpr std::uint32_t kRxf0sGetIndexShift = 8;      // F0GI[13:8]
// TXFQS
constexpr std::uint32_t kTxfqsFull = 1u << 21;     // TFQF
constexpr std::uint32_t kTxfqsPutIndexShift = 16;  // TFQPI[20:16]
// Message RAM element headers (RM0433, RX FIFO and TX buffer elements): word 0 holds
// the identifier (a standard one in [28:18]) with XTD (30) and RTR (29); word 1 holds the DLC
// in [19:16] (TX: FDF, BRS, EFC all 0 for a classic frame without TX events).
constexpr std::uint32_t kStandardIdShift = 18;
constexpr std::uint32_t kDlcShift = 16;
// Standard filter element: SFT[31:30] = 0b00 range SFID1..SFID2, SFEC[29:27] = 0b001 store in
// RX FIFO 0, SFID1[26:16], SFID2[10:0].
constexpr std::uint32_t standard_range_filter(std::uint32_t first, std::uint32_t last) {
  return (0u << 30) | (1u << 27) | (first << 16) | last;
}

constexpr bool filters_valid(const protocol::AcceptedIds& accept) {
  if (accept.count == 0 || accept.count > MessageRam::kStandardFilters) return false;
  for (std::size_t i = 0; i < accept.count; ++i) {
    if (accept.ranges[i].first > accept.ranges[i].last || accept.ranges[i].last > 0x7FFu) {
      return false;
    }
  }
  return true;
}

// INIT crosses into the kernel clock domain: a write is visible only once synchronised, and
// the next write must wait for it (RM0433, FDCAN_CCCR.INIT).
constexpr std::uint32_t kInitPollLimit = 100'000;
bool set_init(FdcanRegs& can, bool init) {
  can.CCCR = init ? (can.CCCR | kCccrInit) : (can.CCCR & ~(kCccrInit | kCccrCce));
  for (std::uint32_t i = 0; i < kInitPollLimit; ++i)
    if (((can.CCCR & kCccrInit) != 0) == init) return true;
  return false;
}

Reg* message_ram_word(std::uint32_t offset) {
  return reinterpret_cast<Reg*>(MessageRam::kBase + offset);
}

bool is_fdcan1_pin_pair(Pin rx, Pin tx) {
  struct PinPair {
    Pin rx, tx;
  };
  constexpr PinPair kPairs[] = {{{Port::D, 0}, {Port::D, 1}},
                                {{Port::A, 11}, {Port::A, 12}},
                                {{Port::B, 8}, {Port::B, 9}},
                                {{Port::H, 14}, {Port::H, 13}}};
  for (const PinPair& pair : kPairs)
    if (pair.rx.port == rx.port && pair.rx.number == rx.number && pair.tx.port == tx.port &&
        pair.tx.number == tx.number)
      return true;
  return false;
}
constexpr std::uint32_t kFdcan1AlternateFunction = 9;

}  // namespace

Fdcan::InitResult Fdcan::init(const FdcanConfig& config) {
  if (!config.timing.valid()) return InitResult::kBadTiming;
  if (!is_fdcan1_pin_pair(config.rx, config.tx)) return InitResult::kBadPins;
  if (!filters_valid(config.accept)) return InitResult::kBadFilters;

  // Kernel clock, bus clock, then a reset pulse so no state of an earlier run survives.
  Rcc& rcc = rcc_regs();
  rcc.D2CCIP1R = (rcc.D2CCIP1R & ~rcc::kD2ccip1rFdcanSelMask) |
                 (static_cast<std::uint32_t>(config.kernel_clock) << rcc::kD2ccip1rFdcanSelShift);
  rcc.APB1HENR = rcc.APB1HENR | rcc::kApb1HenrFdcanEn;
  (void)rcc.APB1HENR;
  rcc.APB1HRSTR = rcc.APB1HRSTR | rcc::kApb1HrstrFdcanRst;
  rcc.APB1HRSTR = rcc.APB1HRSTR & ~rcc::kApb1HrstrFdcanRst;

  // RX pulled up: with no transceiver attached the controller sees a recessive, idle bus.
  configure_alternate_function(config.rx, kFdcan1AlternateFunction, /*pull_up=*/true);
  configure_alternate_function(config.tx, kFdcan1AlternateFunction, /*pull_up=*/false);

  FdcanRegs& can = fdcan1();
  if (!set_init(can, true)) return InitResult::kInitTimeout;
  can.CCCR = can.CCCR | kCccrCce;  // protected configuration registers writable

  ccu_ccfg() = kCcfgBypassCalibration;  // the kernel clock drives the bit timing directly
  // Classic CAN (FDOE = BRSE = 0), automatic retransmission (DAR = 0), no test, monitoring
  // or restricted mode.
  can.CCCR = kCccrInit | kCccrCce;
  can.NBTP = config.timing.nbtp();

  for (std::uint32_t offset = 0; offset < MessageRam::kEndOffset; offset += 4)
    *message_ram_word(offset) = 0;
  for (std::size_t i = 0; i < config.accept.count; ++i) {
    const protocol::IdRange& r = config.accept.ranges[i];
    *message_ram_word(MessageRam::kStandardFilterOffset +
                      MessageRam::kStandardFilterBytes * std::uint32_t(i)) =
        standard_range_filter(r.first, r.last);
  }

  can.GFC = kGfcRejectAllElse;
  can.SIDFC =
      MessageRam::kStandardFilterOffset | (std::uint32_t(config.accept.count) << 16);  // LSS
  can.XIDFC = 0;
  // Blocking FIFO (F0OM = 0): when full, new frames are dropped and counted, so the frames
  // being read are never overwritten under the reader.
  can.RXF0C = MessageRam::kRxFifo0Offset | (MessageRam::kRxFifo0Elements << 16);  // F0S
  can.RXF1C = 0;
  can.RXBC = 0;
  can.RXESC = 0;  // 8-byte data fields
  can.TXESC = 0;
  // TX FIFO mode (TFQM = 0): frames leave in the order they were queued.
  can.TXBC = MessageRam::kTxFifoOffset | (MessageRam::kTxFifoElements << 24);  // TFQS
  can.TXEFC = 0;
  can.IE = 0;
  can.ILE = 0;
  can.IR = 0xFFFFFFFFu;

  counters_ = FdcanCounters{};
  awaiting_restart_ = false;
  // Once INIT clears, the controller joins after 11 recessive bits.
  return set_init(can, false) ? InitResult::kOk : InitResult::kStartTimeout;
}

bool Fdcan::send(const Frame& frame) {
  if (frame.id > 0x7FFu || frame.dlc > 8) return false;
  FdcanRegs& can = fdcan1();
  const std::uint32_t status = can.TXFQS;
  if ((status & kTxfqsFull) != 0) {
    ++counters_.tx_full;
    return false;
  }
  const std::uint32_t put = (status >> kTxfqsPutIndexShift) & 0x1Fu;
  Reg* element = message_ram_word(MessageRam::kTxFifoOffset + put * MessageRam::kElementBytes);
  // The message RAM takes 32-bit accesses; data byte 0 is bits [7:0] of the first data word.
  element[0] = frame.id << kStandardIdShift;
  element[1] = static_cast<std::uint32_t>(frame.dlc) << kDlcShift;
  for (std::size_t word = 0; word < 2; ++word) {
    std::uint32_t value = 0;
    for (std::size_t byte = 0; byte < 4; ++byte)
      value |= static_cast<std::uint32_t>(frame.data[4 * word + byte]) << (8 * byte);
    element[2 + word] = value;
  }
  // Device memory keeps the element writes ahead of this request.
  can.TXBAR = 1u << put;
  return true;
}

bool Fdcan::receive(Frame& frame) {
  FdcanRegs& can = fdcan1();
  const std::uint32_t status = can.RXF0S;
  if ((status & kRxf0sFillLevelMask) == 0) return false;
  const std::uint32_t get = (status >> kRxf0sGetIndexShift) & 0x3Fu;
  const Reg* element =
      message_ram_word(MessageRam::kRxFifo0Offset + get * MessageRam::kElementBytes);
  frame.id = (element[0] >> kStandardIdShift) & 0x7FFu;
  const std::uint32_t dlc = (element[1] >> kDlcShift) & 0xFu;
  frame.dlc = static_cast<std::uint8_t>(dlc > 8 ? 8 : dlc);  // classic CAN: DLC 9..15 = 8 bytes
  for (std::size_t word = 0; word < 2; ++word) {
    const std::uint32_t value = element[2 + word];
    for (std::size_t byte = 0; byte < 4; ++byte)
      frame.data[4 * word + byte] = static_cast<std::uint8_t>(value >> (8 * byte));
  }
  can.RXF0A = get;  // frees the element and advances the get index
  return true;
}

FdcanStatus Fdcan::poll(std::uint32_t now_ms) {
  FdcanRegs& can = fdcan1();
  if ((can.IR & kIrRxFifo0Lost) != 0) {
    can.IR = kIrRxFifo0Lost;
    ++counters_.rx_overflows;
  }

  const std::uint32_t psr = can.PSR;  // reading resets LEC to 7
  const std::uint32_t ecr = can.ECR;
  FdcanStatus status;
  status.bus_off = (psr & kPsrBusOff) != 0;
  status.error_passive = (psr & kPsrErrorPassive) != 0;
  status.error_warning = (psr & kPsrErrorWarning) != 0;
  status.last_error = static_cast<std::uint8_t>(psr & kPsrLecMask);
  status.tx_errors = static_cast<std::uint8_t>(ecr & 0xFFu);
  status.rx_errors = static_cast<std::uint8_t>((ecr >> 8) & 0x7Fu);

  // Entering bus-off sets CCCR.INIT; the restart clears it, after which PSR.BO stays set
  // until the controller has seen 128 x 11 recessive bits. INIT set again means a new bus-off.
  const bool stopped_by_bus_off = status.bus_off && (can.CCCR & kCccrInit) != 0;
  if (stopped_by_bus_off && !awaiting_restart_) {
    awaiting_restart_ = true;
    bus_off_since_ms_ = now_ms;
    ++counters_.bus_off_events;
  } else if (stopped_by_bus_off && now_ms - bus_off_since_ms_ >= kBusOffRestartDelayMs) {
    // Frames queued before the bus-off would reach the bus stale: cancel them.
    can.TXBCR = (1u << MessageRam::kTxFifoElements) - 1;
    if (set_init(can, false)) {
      awaiting_restart_ = false;
      ++counters_.bus_off_recoveries;
    }
  }
  return status;
}

void Fdcan::stop() {
  // Before init() the block has no bus clock and there is nothing to stop.
  if ((rcc_regs().APB1HENR & rcc::kApb1HenrFdcanEn) != 0) (void)set_init(fdcan1(), true);
}

}  // namespace hmpc::stm32h7
