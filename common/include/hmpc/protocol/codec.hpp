// The CAN codec every board protocol shares: frames, identifiers, end-to-end protection, bit
// packing of signals and their checks, rolling counters, a receiver and a sender, and bus-load
// arithmetic. A protocol is a description (frame and signal tables, identifier layout; see
// Description below) in its own header: forearm_protocol.hpp, joint_protocol.hpp. Each has a
// DBC for cantools or SavvyCAN, kept in agreement with its tables by tests/unit/dbc_test.cpp.
//
// Bus: classic CAN, 11-bit identifiers, every frame 8 data bytes.
//
// Identifiers: frame_id(type, node) = base + stride * node + FrameSpec::id_offset, node
// 0..max_node; a bus-wide frame (FrameSpec::bus_wide: an emergency stop, a time sync) has the
// fixed identifier id_offset for every node, below every node's range so that it wins
// arbitration. Inside a node the order of the offsets is the priority.
//
// End-to-end protection, the same in every frame:
//   byte 0       checksum: CRC-8/AUTOSAR (polynomial 0x2F, initial value 0xFF, final XOR 0xFF,
//                not reflected; check value 0xDF for "123456789") over the identifier as two
//                bytes, little-endian, then data bytes 1..7. Covering the identifier means a
//                frame cannot be taken for another node's or another frame type's.
//   byte 1 [3:0] rolling counter 0..15, one sequence per frame type and sender (Sender below).
//                A receiver (CounterTracker) accepts the first counter it sees, then only
//                advances of 1..7 modulo 16: 0 is a repeated frame, 8..15 is an old or
//                reordered one. Stale frames whose own counters run on by 1, three in a row,
//                are a sender that restarted (its counters from 0) or lost more than 7 in a
//                row: the receiver takes the third and follows them. A frozen sender repeating
//                its frame stays stale. A receiver forgets a frame type
//                (CounterTracker::reset) when that frame times out.
// Frames to the host carry the same protection, so the host can reject corrupt telemetry too.
//
// Signals are little-endian (Intel, DBC "@1"); start bits count from bit 0 of byte 0. Bits
// no signal covers are sent as zero and ignored on receipt (the checksum still covers them).
//
// Physical values are float: every scaled signal has at most 24 bits, which float holds
// exactly, and the same float arithmetic on the host, the HIL and a Cortex-M4 without a
// double-precision FPU produces the same frames bit for bit.
//
// A protocol's message is a plain struct per frame type with a static visit() that names the
// signal of every field; the codec and the compile-time check that each struct covers exactly
// its frame's signals use it.
//
// Nothing here allocates, throws, calls virtual functions or prints.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string_view>
#include <type_traits>

namespace hmpc::protocol {

// ---------------------------------------------------------------------------------------
// Frame, nodes, identifiers

// A classic CAN data frame, independent of any operating system's CAN headers.
struct Frame {
  std::uint32_t id = 0;  // 11-bit standard identifier
  std::uint8_t dlc = 0;  // data length code, 0..8
  std::array<std::uint8_t, 8> data{};
};

using NodeId = std::uint8_t;

// How a protocol lays out its identifiers (see the top of this file).
struct IdLayout {
  std::uint32_t base = 0;
  std::uint32_t node_stride = 0;
  NodeId max_node = 0;
};

// The bus participants; the DBC's BU_ nodes.
enum class Endpoint : std::uint8_t { kHost, kBoard, kPlant, kImu };

constexpr const char* to_string(Endpoint endpoint) {
  switch (endpoint) {
    case Endpoint::kHost: return "HOST";
    case Endpoint::kBoard: return "BOARD";
    case Endpoint::kPlant: return "PLANT";
    case Endpoint::kImu: return "IMU";
  }
  return "?";
}

template <class FrameType>
struct FrameSpec {
  FrameType type;
  const char* name;         // DBC message name
  std::uint16_t id_offset;  // added to the node's base id; the identifier itself if bus_wide
  std::uint8_t dlc;         // bytes
  Endpoint sender;
  Endpoint receiver;
  std::uint16_t cycle_time_ms;  // nominal period; 0: sent when the value changes
  bool bus_wide;                // one identifier for every node
};

// ---------------------------------------------------------------------------------------
// Enumerated signal values

struct EnumValue {
  std::uint32_t value;
  const char* name;  // DBC VAL_ description
};

// The DBC's name of an enumerated signal value, or "?".
template <std::size_t N>
constexpr const char* value_name(const EnumValue (&values)[N], std::uint32_t value) {
  for (const auto& v : values)
    if (v.value == value) return v.name;
  return "?";
}

// The value of an enumerated signal by its DBC name (as the programs' command lines take them);
// false for an unknown name.
template <std::size_t N>
constexpr bool value_of(const EnumValue (&values)[N], std::string_view name, std::uint32_t& out) {
  for (const auto& v : values) {
    if (name == v.name) {
      out = v.value;
      return true;
    }
  }
  return false;
}

struct EnumValueList {
  const EnumValue* values = nullptr;
  std::uint8_t count = 0;
};

template <std::size_t N>
constexpr EnumValueList values_of(const EnumValue (&values)[N]) {
  return {values, static_cast<std::uint8_t>(N)};
}

// ---------------------------------------------------------------------------------------
// Signals

enum class SignalKind : std::uint8_t {
  kChecksum,     // CRC-8 of the frame, computed by the codec
  kCounter,      // rolling counter 0..15
  kPhysical,     // scaled quantity: physical = raw * factor + offset, a float field
  kInteger,      // unscaled count, time or bit set, an unsigned integer field
  kMode,         // a requested or reported mode; other values decode as kUnknownMode
  kEnumeration,  // another enumeration; other values decode as kUnknownEnum
};

enum class ByteOrder : std::uint8_t { kLittleEndian };  // DBC "@1"; the only one used

template <class Signal, class FrameType>
struct SignalSpec {
  Signal signal;
  FrameType frame;
  const char* name;  // DBC signal name, unique within its frame
  std::uint8_t start_bit;
  std::uint8_t length;  // bits
  ByteOrder byte_order;
  bool is_signed;  // two's complement
  double factor;
  double offset;
  double min;  // physical range; both ends lie on the raw grid
  double max;
  const char* unit;
  SignalKind kind;
  EnumValueList values;  // kMode and kEnumeration only
};

// ---------------------------------------------------------------------------------------
// Protocol descriptions
//
// A protocol's header defines, in its own namespace, enums FrameType and Signal (values 0..n-1
// in table order), the tables kFrames and kSignals, and a Description:
//   struct Description {
//     using FrameType = ...;  using Signal = ...;
//     static constexpr IdLayout kIds{...};
//     static constexpr const auto& kFrames = ...;  static constexpr const auto& kSignals = ...;
//   };
//   constexpr Description protocol_of(FrameType);  constexpr Description protocol_of(Signal);
// protocol_of, found by argument-dependent lookup, tells the codec which description a frame
// type, a signal or a message (through Message::kType) belongs to.

template <class E>
using DescriptionOf = decltype(protocol_of(E{}));

template <class E, class P = DescriptionOf<E>>
constexpr std::size_t index_of(E e) {
  return static_cast<std::size_t>(e);
}

template <class P>
constexpr std::size_t frame_type_count() {
  return std::extent_v<std::remove_reference_t<decltype(P::kFrames)>>;
}

template <class P>
constexpr std::size_t signal_count() {
  return std::extent_v<std::remove_reference_t<decltype(P::kSignals)>>;
}

template <class FrameType, class P = DescriptionOf<FrameType>>
constexpr const auto& frame_spec(FrameType type) {
  return P::kFrames[index_of(type)];
}

template <class Signal, class P = DescriptionOf<Signal>>
constexpr const auto& signal_spec(Signal signal) {
  return P::kSignals[index_of(signal)];
}

// Precondition: node <= P::kIds.max_node.
template <class FrameType, class P = DescriptionOf<FrameType>>
constexpr std::uint32_t frame_id(FrameType type, NodeId node) {
  const auto& spec = frame_spec(type);
  return spec.bus_wide ? spec.id_offset
                       : P::kIds.base + P::kIds.node_stride * node + spec.id_offset;
}

// The frame type and node an identifier belongs to (node 0 for a bus-wide frame); false for
// identifiers of no frame of the protocol.
template <class FrameType, class P = DescriptionOf<FrameType>>
constexpr bool identify(std::uint32_t id, FrameType& type, NodeId& node) {
  for (const auto& spec : P::kFrames) {
    if (spec.bus_wide && spec.id_offset == id) {
      type = spec.type;
      node = 0;
      return true;
    }
  }
  if (id < P::kIds.base || id >= P::kIds.base + P::kIds.node_stride * (P::kIds.max_node + 1u)) {
    return false;
  }
  const std::uint32_t offset = (id - P::kIds.base) % P::kIds.node_stride;
  for (const auto& spec : P::kFrames) {
    if (!spec.bus_wide && spec.id_offset == offset) {
      type = spec.type;
      node = static_cast<NodeId>((id - P::kIds.base) / P::kIds.node_stride);
      return true;
    }
  }
  return false;
}

// The standard identifiers one node hears, as ranges: its node's block (every frame type of
// the node, whoever sends it) and each bus-wide frame. Acceptance filters (a SocketCAN socket's,
// a CAN controller's) are set from these, so a board's filter is never restated by hand.
struct IdRange {
  std::uint32_t first = 0, last = 0;  // inclusive
};
inline constexpr std::size_t kMaxAcceptedRanges = 8;
struct AcceptedIds {
  std::array<IdRange, kMaxAcceptedRanges> ranges{};
  std::size_t count = 0;
};

// Precondition: node <= P::kIds.max_node.
template <class P>
constexpr AcceptedIds accepted_ids(NodeId node) {
  AcceptedIds out;
  const std::uint32_t first = P::kIds.base + P::kIds.node_stride * node;
  out.ranges[out.count++] = {first, first + P::kIds.node_stride - 1};
  for (const auto& spec : P::kFrames) {
    if (spec.bus_wide) out.ranges[out.count++] = {spec.id_offset, spec.id_offset};
  }
  return out;
}

// Half away from zero. Not std::lround, which is not constexpr; the one number it rounds
// otherwise (0.5 less an ulp, which + 0.5 carries to 1) is immaterial at a signal's resolution.
constexpr std::int64_t round_half_away(double x) {
  // NOLINTNEXTLINE(bugprone-incorrect-roundings)
  return x < 0 ? -static_cast<std::int64_t>(-x + 0.5) : static_cast<std::int64_t>(x + 0.5);
}
// Raw value of a physical value that lies on the signal's grid.
template <class S, class F>
constexpr std::int64_t raw_of(const SignalSpec<S, F>& spec, double physical) {
  return round_half_away((physical - spec.offset) / spec.factor);
}
template <class S, class F>
constexpr std::int64_t raw_min(const SignalSpec<S, F>& spec) {
  return raw_of(spec, spec.min);
}
template <class S, class F>
constexpr std::int64_t raw_max(const SignalSpec<S, F>& spec) {
  return raw_of(spec, spec.max);
}

// ---------------------------------------------------------------------------------------
// Results

enum class EncodeResult : std::uint8_t {
  kOk,
  kInvalidNode,  // node id above the protocol's largest
  kNotFinite,    // a physical value is NaN or infinite
  kOutOfRange,   // a value outside its signal's [min, max], or a counter above 15
  kUnknownMode,  // a mode value with no meaning in this frame
  kUnknownEnum,  // another enumeration's value with no meaning
};

// Decoded values come from integers, so they are always finite: kNotFinite is encode-only.
enum class DecodeResult : std::uint8_t {
  kOk,
  kWrongId,       // not this frame type of this node
  kWrongLength,   // DLC is not the frame's
  kBadChecksum,   // CRC-8 mismatch: corrupt frame
  kStaleCounter,  // rolling counter repeated or gone backwards
  kOutOfRange,    // a raw value outside its signal's range
  kUnknownMode,   // a mode value with no meaning in this frame
  kUnknownEnum,   // another enumeration's value with no meaning
};

constexpr const char* to_string(EncodeResult result) {
  switch (result) {
    case EncodeResult::kOk: return "ok";
    case EncodeResult::kInvalidNode: return "invalid-node";
    case EncodeResult::kNotFinite: return "not-finite";
    case EncodeResult::kOutOfRange: return "out-of-range";
    case EncodeResult::kUnknownMode: return "unknown-mode";
    case EncodeResult::kUnknownEnum: return "unknown-enum";
  }
  return "?";
}

constexpr const char* to_string(DecodeResult result) {
  switch (result) {
    case DecodeResult::kOk: return "ok";
    case DecodeResult::kWrongId: return "wrong-id";
    case DecodeResult::kWrongLength: return "wrong-length";
    case DecodeResult::kBadChecksum: return "bad-checksum";
    case DecodeResult::kStaleCounter: return "stale-counter";
    case DecodeResult::kOutOfRange: return "out-of-range";
    case DecodeResult::kUnknownMode: return "unknown-mode";
    case DecodeResult::kUnknownEnum: return "unknown-enum";
  }
  return "?";
}

// ---------------------------------------------------------------------------------------
// Checksum

inline constexpr std::size_t kChecksumByte = 0;

constexpr std::uint8_t crc8_autosar_update(std::uint8_t crc, std::uint8_t byte) {
  crc = static_cast<std::uint8_t>(crc ^ byte);
  for (int bit = 0; bit < 8; ++bit) {
    const unsigned shifted = static_cast<unsigned>(crc) << 1;
    crc = static_cast<std::uint8_t>((crc & 0x80u) ? shifted ^ 0x2Fu : shifted);
  }
  return crc;
}

constexpr std::uint8_t crc8_autosar(const std::uint8_t* bytes, std::size_t count) {
  std::uint8_t crc = 0xFF;
  for (std::size_t i = 0; i < count; ++i) crc = crc8_autosar_update(crc, bytes[i]);
  return static_cast<std::uint8_t>(crc ^ 0xFFu);
}

// The checksum a frame must carry in byte kChecksumByte (over its id and the other bytes).
constexpr std::uint8_t frame_checksum(const Frame& frame) {
  std::uint8_t crc = 0xFF;
  crc = crc8_autosar_update(crc, static_cast<std::uint8_t>(frame.id & 0xFFu));
  crc = crc8_autosar_update(crc, static_cast<std::uint8_t>((frame.id >> 8) & 0xFFu));
  for (std::size_t i = 0; i < frame.data.size(); ++i) {
    if (i != kChecksumByte) crc = crc8_autosar_update(crc, frame.data[i]);
  }
  return static_cast<std::uint8_t>(crc ^ 0xFFu);
}

// ---------------------------------------------------------------------------------------
// Codec internals

namespace detail {

constexpr std::uint64_t low_bits(unsigned length) {
  return length >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << length) - 1;
}

template <class S, class F>
constexpr std::uint64_t bits_of(const SignalSpec<S, F>& spec) {
  return low_bits(spec.length) << spec.start_bit;
}

// The table in the form the codec uses at run time: float scaling, so no double arithmetic
// reaches a single-precision FPU.
struct CodecSpec {
  std::uint8_t start_bit = 0;
  std::uint8_t length = 0;
  bool is_signed = false;
  SignalKind kind = SignalKind::kInteger;
  float factor = 1;
  float offset = 0;
  float min = 0;
  float max = 0;
  std::int64_t raw_min = 0;
  std::int64_t raw_max = 0;
  EnumValueList values;
};

template <class P>
constexpr std::array<CodecSpec, signal_count<P>()> make_codec_specs() {
  std::array<CodecSpec, signal_count<P>()> specs{};
  for (std::size_t i = 0; i < signal_count<P>(); ++i) {
    const auto& s = P::kSignals[i];
    specs[i] = CodecSpec{s.start_bit,
                         s.length,
                         s.is_signed,
                         s.kind,
                         static_cast<float>(s.factor),
                         static_cast<float>(s.offset),
                         static_cast<float>(s.min),
                         static_cast<float>(s.max),
                         raw_min(s),
                         raw_max(s),
                         s.values};
  }
  return specs;
}
template <class P>
inline constexpr std::array<CodecSpec, signal_count<P>()> kCodecSpecs = make_codec_specs<P>();

template <class Signal>
constexpr const CodecSpec& codec_spec(Signal signal) {
  using P = DescriptionOf<Signal>;
  const auto& specs = kCodecSpecs<P>;
  return specs[index_of(signal)];
}

constexpr std::uint64_t payload_of(const Frame& frame) {
  std::uint64_t payload = 0;
  for (std::size_t i = 0; i < frame.data.size(); ++i) {
    payload |= static_cast<std::uint64_t>(frame.data[i]) << (8 * i);
  }
  return payload;
}

constexpr std::int64_t extract_raw(std::uint64_t payload, const CodecSpec& spec) {
  const std::uint64_t bits = (payload >> spec.start_bit) & low_bits(spec.length);
  const bool negative = spec.is_signed && ((bits >> (spec.length - 1)) & 1u);
  return negative ? static_cast<std::int64_t>(bits) -
                        static_cast<std::int64_t>(std::uint64_t{1} << spec.length)
                  : static_cast<std::int64_t>(bits);
}

constexpr void insert_raw(std::uint64_t& payload, const CodecSpec& spec, std::int64_t raw) {
  payload |= (static_cast<std::uint64_t>(raw) & low_bits(spec.length)) << spec.start_bit;
}

enum class Violation : std::uint8_t { kNone, kOutOfRange, kUnknownMode, kUnknownEnum };

constexpr Violation check_integer(const CodecSpec& spec, std::int64_t raw) {
  if (spec.kind == SignalKind::kMode || spec.kind == SignalKind::kEnumeration) {
    for (std::uint8_t i = 0; i < spec.values.count; ++i) {
      if (static_cast<std::int64_t>(spec.values.values[i].value) == raw) return Violation::kNone;
    }
    return spec.kind == SignalKind::kMode ? Violation::kUnknownMode : Violation::kUnknownEnum;
  }
  return raw < spec.raw_min || raw > spec.raw_max ? Violation::kOutOfRange : Violation::kNone;
}

constexpr EncodeResult to_encode_result(Violation violation) {
  switch (violation) {
    case Violation::kNone: return EncodeResult::kOk;
    case Violation::kOutOfRange: return EncodeResult::kOutOfRange;
    case Violation::kUnknownMode: return EncodeResult::kUnknownMode;
    case Violation::kUnknownEnum: return EncodeResult::kUnknownEnum;
  }
  return EncodeResult::kOutOfRange;
}

constexpr DecodeResult to_decode_result(Violation violation) {
  switch (violation) {
    case Violation::kNone: return DecodeResult::kOk;
    case Violation::kOutOfRange: return DecodeResult::kOutOfRange;
    case Violation::kUnknownMode: return DecodeResult::kUnknownMode;
    case Violation::kUnknownEnum: return DecodeResult::kUnknownEnum;
  }
  return DecodeResult::kOutOfRange;
}

template <class T>
constexpr std::int64_t integer_value(T value) {
  if constexpr (std::is_enum_v<T>) {
    return static_cast<std::int64_t>(static_cast<std::underlying_type_t<T>>(value));
  } else {
    return static_cast<std::int64_t>(value);
  }
}

// round_half_away's rounding in float, for the encoder on a single-precision board. The
// caller has bounded x to the signal's raw range, at most 24 bits for physical signals, so
// int32 holds it.
inline std::int32_t round_float(float x) {
  // NOLINTNEXTLINE(bugprone-incorrect-roundings)
  return x < 0 ? -static_cast<std::int32_t>(-x + 0.5f) : static_cast<std::int32_t>(x + 0.5f);
}

struct SignalWriter {
  std::uint64_t payload = 0;
  EncodeResult result = EncodeResult::kOk;

  template <class Signal>
  void operator()(Signal signal, float value) {
    if (result != EncodeResult::kOk) return;
    const CodecSpec& spec = codec_spec(signal);
    if (!std::isfinite(value)) {
      result = EncodeResult::kNotFinite;
      return;
    }
    if (value < spec.min || value > spec.max) {
      result = EncodeResult::kOutOfRange;
      return;
    }
    std::int64_t raw = round_float((value - spec.offset) / spec.factor);
    // Float rounding next to a range end must not step off the raw range.
    raw = raw < spec.raw_min ? spec.raw_min : raw > spec.raw_max ? spec.raw_max : raw;
    insert_raw(payload, spec, raw);
  }

  template <class Signal, class T, std::enable_if_t<!std::is_floating_point_v<T>, int> = 0>
  void operator()(Signal signal, T value) {
    if (result != EncodeResult::kOk) return;
    const CodecSpec& spec = codec_spec(signal);
    const std::int64_t raw = integer_value(value);
    result = to_encode_result(check_integer(spec, raw));
    if (result == EncodeResult::kOk) insert_raw(payload, spec, raw);
  }
};

struct SignalReader {
  std::uint64_t payload = 0;
  DecodeResult result = DecodeResult::kOk;

  template <class Signal>
  void operator()(Signal signal, float& value) {
    if (result != DecodeResult::kOk) return;
    const CodecSpec& spec = codec_spec(signal);
    const std::int64_t raw = extract_raw(payload, spec);
    if (raw < spec.raw_min || raw > spec.raw_max) {
      result = DecodeResult::kOutOfRange;
      return;
    }
    const float physical = static_cast<float>(raw) * spec.factor + spec.offset;
    // Float rounding at a range end must not step outside [min, max] either.
    value = physical < spec.min ? spec.min : physical > spec.max ? spec.max : physical;
  }

  template <class Signal, class T, std::enable_if_t<!std::is_floating_point_v<T>, int> = 0>
  void operator()(Signal signal, T& value) {
    if (result != DecodeResult::kOk) return;
    const CodecSpec& spec = codec_spec(signal);
    const std::int64_t raw = extract_raw(payload, spec);
    result = to_decode_result(check_integer(spec, raw));
    if (result == DecodeResult::kOk) value = static_cast<T>(raw);
  }
};

// ---------------------------------------------------------------------------------------
// Compile-time checks of a description's tables and of its messages' visit().

template <class P>
constexpr bool signals_are_indexed() {
  for (std::size_t i = 0; i < signal_count<P>(); ++i) {
    if (index_of(P::kSignals[i].signal) != i) return false;
  }
  return true;
}

// Frames in table order, 8 bytes, node frames at distinct offsets below the stride, bus-wide
// ones at distinct identifiers below every node's (so they win arbitration).
template <class P>
constexpr bool frames_are_indexed_with_distinct_ids() {
  for (std::size_t i = 0; i < frame_type_count<P>(); ++i) {
    const auto& f = P::kFrames[i];
    if (index_of(f.type) != i || f.dlc != 8) return false;
    if (f.bus_wide ? f.id_offset >= P::kIds.base : f.id_offset >= P::kIds.node_stride) {
      return false;
    }
    for (std::size_t j = 0; j < i; ++j) {
      const auto& g = P::kFrames[j];
      if (g.bus_wide == f.bus_wide && g.id_offset == f.id_offset) return false;
    }
  }
  std::size_t bus_wide = 0;
  for (const auto& f : P::kFrames) bus_wide += f.bus_wide ? 1 : 0;
  // A node's block is one mask filter (a power-of-two stride from an aligned base), and the
  // node's acceptance fits accepted_ids().
  const bool aligned_blocks = P::kIds.node_stride > 0 &&
                              (P::kIds.node_stride & (P::kIds.node_stride - 1)) == 0 &&
                              P::kIds.base % P::kIds.node_stride == 0;
  return aligned_blocks && bus_wide + 1 <= kMaxAcceptedRanges &&
         P::kIds.base + P::kIds.node_stride * (P::kIds.max_node + 1u) <= 0x800;
}

constexpr double magnitude(double x) { return x < 0 ? -x : x; }

template <class S, class F>
constexpr bool on_grid(const SignalSpec<S, F>& s, double physical) {
  const double back = static_cast<double>(raw_of(s, physical)) * s.factor + s.offset;
  return magnitude(back - physical) <= 1e-9 * (magnitude(physical) > 1 ? magnitude(physical) : 1);
}

template <class S, class F>
constexpr bool signal_is_well_formed(const SignalSpec<S, F>& s) {
  if (s.byte_order != ByteOrder::kLittleEndian) return false;
  if (s.length < 1 || s.length > 32 || s.start_bit + s.length > 8 * frame_spec(s.frame).dlc) {
    return false;
  }
  if (!(s.factor > 0) || s.min > s.max || !on_grid(s, s.min) || !on_grid(s, s.max)) return false;
  const std::int64_t lowest = s.is_signed ? -(std::int64_t{1} << (s.length - 1)) : 0;
  const std::int64_t highest =
      s.is_signed ? (std::int64_t{1} << (s.length - 1)) - 1 : (std::int64_t{1} << s.length) - 1;
  if (raw_min(s) < lowest || raw_max(s) > highest) return false;
  const bool integer_kind = s.kind != SignalKind::kPhysical;
  // Integer kinds are unscaled and unsigned; physical ones fit a float mantissa exactly.
  if (integer_kind && (s.is_signed || s.factor != 1 || s.offset != 0)) return false;
  if (!integer_kind && s.length > 24) return false;
  const bool enumerated = s.kind == SignalKind::kMode || s.kind == SignalKind::kEnumeration;
  if (enumerated != (s.values.count > 0)) return false;
  for (std::uint8_t i = 0; i < s.values.count; ++i) {
    const double v = s.values.values[i].value;
    if (v < s.min || v > s.max) return false;
  }
  if (s.kind == SignalKind::kChecksum) {
    return s.start_bit == 8 * kChecksumByte && s.length == 8;
  }
  if (s.kind == SignalKind::kCounter) return s.length == 4 && s.min == 0 && s.max == 15;
  return true;
}

template <class P>
constexpr bool signals_are_well_formed() {
  for (const auto& s : P::kSignals) {
    if (!signal_is_well_formed(s)) return false;
  }
  return true;
}

// Per frame: no two signals share a bit, one checksum, one counter.
template <class P>
constexpr bool frames_are_well_formed() {
  for (const auto& frame : P::kFrames) {
    std::uint64_t used = 0;
    int checksums = 0;
    int counters = 0;
    for (const auto& s : P::kSignals) {
      if (s.frame != frame.type) continue;
      if (used & bits_of(s)) return false;
      used |= bits_of(s);
      checksums += s.kind == SignalKind::kChecksum;
      counters += s.kind == SignalKind::kCounter;
    }
    if (checksums != 1 || counters != 1) return false;
  }
  return true;
}

// Records what visit() names and whether each field's type suits its signal.
template <class P>
struct VisitAudit {
  std::array<bool, signal_count<P>()> visited{};
  bool consistent = true;

  template <class Signal>
  constexpr void note(Signal signal) {
    if (visited[index_of(signal)]) consistent = false;
    visited[index_of(signal)] = true;
  }
  template <class Signal>
  constexpr void operator()(Signal signal, float&) {
    note(signal);
    if (signal_spec(signal).kind != SignalKind::kPhysical) consistent = false;
  }
  template <class Signal, class T, std::enable_if_t<!std::is_floating_point_v<T>, int> = 0>
  constexpr void operator()(Signal signal, T&) {
    note(signal);
    const auto& s = signal_spec(signal);
    using Stored = typename std::conditional_t<std::is_enum_v<T>, std::underlying_type<T>,
                                               std::common_type<T>>::type;
    if (s.kind == SignalKind::kPhysical || s.kind == SignalKind::kChecksum) consistent = false;
    if (static_cast<double>(std::numeric_limits<Stored>::max()) < s.max) consistent = false;
  }
};

// A message's visit() names every signal of its frame but the checksum, each once, each with a
// field of a type that suits it.
template <class Message>
constexpr bool visits_exactly_its_signals() {
  using P = DescriptionOf<std::remove_const_t<decltype(Message::kType)>>;
  Message message{};
  VisitAudit<P> audit{};
  Message::visit(message, audit);
  if (!audit.consistent) return false;
  for (std::size_t i = 0; i < signal_count<P>(); ++i) {
    const bool expected =
        P::kSignals[i].frame == Message::kType && P::kSignals[i].kind != SignalKind::kChecksum;
    if (audit.visited[i] != expected) return false;
  }
  return true;
}

}  // namespace detail

// The messages of a protocol, one per frame type, for its compile-time check and for tests
// and tools that go over every frame.
template <class... Messages>
struct MessageList {};

// Everything the codec needs of a description and its messages, checked at compile time; each
// protocol header static_asserts it.
template <class P, class... Messages>
constexpr bool is_well_formed(MessageList<Messages...>) {
  return detail::signals_are_indexed<P>() && detail::frames_are_indexed_with_distinct_ids<P>() &&
         detail::signals_are_well_formed<P>() && detail::frames_are_well_formed<P>() &&
         sizeof...(Messages) == frame_type_count<P>() &&
         (detail::visits_exactly_its_signals<Messages>() && ...);
}

// ---------------------------------------------------------------------------------------
// Codec

template <class Message>
using MessageDescription = DescriptionOf<std::remove_const_t<decltype(Message::kType)>>;

// Encodes msg for node into out, counter included, checksum computed. On any error out is
// left untouched.
template <class Message>
EncodeResult encode(const Message& msg, NodeId node, Frame& out) {
  using P = MessageDescription<Message>;
  if (node > P::kIds.max_node) return EncodeResult::kInvalidNode;
  detail::SignalWriter writer;
  Message::visit(msg, writer);
  if (writer.result != EncodeResult::kOk) return writer.result;
  Frame frame;
  frame.id = frame_id(Message::kType, node);
  frame.dlc = frame_spec(Message::kType).dlc;
  for (std::size_t i = 0; i < frame.data.size(); ++i) {
    frame.data[i] = static_cast<std::uint8_t>(writer.payload >> (8 * i));
  }
  frame.data[kChecksumByte] = frame_checksum(frame);
  out = frame;
  return EncodeResult::kOk;
}

// Checks id, length, checksum and every signal's range; on kOk fills out (counter included,
// not checked against earlier frames: that is Receiver's job), otherwise leaves it untouched.
template <class Message>
DecodeResult decode(const Frame& frame, NodeId node, Message& out) {
  using P = MessageDescription<Message>;
  if (node > P::kIds.max_node || frame.id != frame_id(Message::kType, node)) {
    return DecodeResult::kWrongId;
  }
  if (frame.dlc != frame_spec(Message::kType).dlc) return DecodeResult::kWrongLength;
  if (frame.data[kChecksumByte] != frame_checksum(frame)) return DecodeResult::kBadChecksum;
  detail::SignalReader reader{detail::payload_of(frame)};
  Message decoded{};
  Message::visit(decoded, reader);
  if (reader.result == DecodeResult::kOk) out = decoded;
  return reader.result;
}

// ---------------------------------------------------------------------------------------
// Rolling counters and reject counting

inline constexpr std::uint8_t kCounterModulo = 16;
inline constexpr std::uint8_t kMaxCounterAdvance = 7;  // up to 6 lost frames in a row

// Validates the rolling counter of each frame type of protocol P from one sender.
template <class P>
class CounterTracker {
 public:
  using FrameType = typename P::FrameType;

  // kOk (and remembers counter) for the first frame of a type, an advance of
  // 1..kMaxCounterAdvance, or the kResyncStaleRun-th stale frame in a row whose counters run
  // on by 1; kStaleCounter for a repeat or a step back.
  constexpr DecodeResult accept(FrameType type, std::uint8_t counter) {
    const std::size_t i = index_of(type);
    if (synced_[i]) {
      const unsigned advance = step(last_[i], counter);
      if (advance == 0 || advance > kMaxCounterAdvance) {
        stale_run_[i] =
            stale_run_[i] > 0 && step(last_stale_[i], counter) == 1 ? stale_run_[i] + 1 : 1;
        last_stale_[i] = counter;
        if (stale_run_[i] < kResyncStaleRun) return DecodeResult::kStaleCounter;
      }
    }
    synced_[i] = true;
    last_[i] = counter;
    stale_run_[i] = 0;
    return DecodeResult::kOk;
  }
  constexpr void reset(FrameType type) { synced_[index_of(type)] = false; }
  constexpr void reset_all() { synced_ = {}; }

  // Three: two frames running on from a stale one could still be chance (1 in 16 each); a
  // restarted joint board's status (every 20 ms) is then heard within 60 ms, before the
  // 100 ms after which the host takes a board for silent.
  static constexpr std::uint8_t kResyncStaleRun = 3;

 private:
  static constexpr unsigned step(std::uint8_t from, std::uint8_t to) {
    return (unsigned{to} + kCounterModulo - from) % kCounterModulo;
  }
  std::array<std::uint8_t, frame_type_count<P>()> last_{};
  std::array<bool, frame_type_count<P>()> synced_{};  // a counter of the type has been accepted
  std::array<std::uint8_t, frame_type_count<P>()> last_stale_{};
  std::array<std::uint8_t, frame_type_count<P>()> stale_run_{};  // stale frames running on
};

struct RejectCounters {
  std::uint32_t wrong_id = 0;
  std::uint32_t wrong_length = 0;
  std::uint32_t bad_checksum = 0;
  std::uint32_t stale_counter = 0;
  std::uint32_t out_of_range = 0;
  std::uint32_t unknown_mode = 0;
  std::uint32_t unknown_enum = 0;

  constexpr void count(DecodeResult result) {
    switch (result) {
      case DecodeResult::kOk: break;
      case DecodeResult::kWrongId: ++wrong_id; break;
      case DecodeResult::kWrongLength: ++wrong_length; break;
      case DecodeResult::kBadChecksum: ++bad_checksum; break;
      case DecodeResult::kStaleCounter: ++stale_counter; break;
      case DecodeResult::kOutOfRange: ++out_of_range; break;
      case DecodeResult::kUnknownMode: ++unknown_mode; break;
      case DecodeResult::kUnknownEnum: ++unknown_enum; break;
    }
  }
  constexpr std::uint32_t total() const {
    return wrong_id + wrong_length + bad_checksum + stale_counter + out_of_range + unknown_mode +
           unknown_enum;
  }
};

// One node's inbound frames of protocol P from one sender: decodes, checks the rolling counter,
// counts rejects. A rejected frame leaves the tracker where it was. Call decode only with
// frames meant for this node (see identify); others count as kWrongId.
template <class P>
struct Receiver {
  NodeId node = 0;
  CounterTracker<P> counters;
  RejectCounters rejects;

  constexpr Receiver() = default;
  constexpr explicit Receiver(NodeId node_id) : node(node_id) {}

  template <class Message>
  DecodeResult decode(const Frame& frame, Message& out) {
    static_assert(std::is_same_v<MessageDescription<Message>, P>, "a message of another protocol");
    Message candidate{};
    DecodeResult result = protocol::decode(frame, node, candidate);
    if (result == DecodeResult::kOk) result = counters.accept(Message::kType, candidate.counter);
    if (result == DecodeResult::kOk) out = candidate;
    rejects.count(result);
    return result;
  }
};

// Stamps each frame type's rolling counter of protocol P; it advances only when a frame was
// encoded.
template <class P>
struct Sender {
  NodeId node = 0;
  std::array<std::uint8_t, frame_type_count<P>()> next_counter{};

  constexpr Sender() = default;
  constexpr explicit Sender(NodeId node_id) : node(node_id) {}

  template <class Message>
  EncodeResult encode(Message msg, Frame& out) {
    static_assert(std::is_same_v<MessageDescription<Message>, P>, "a message of another protocol");
    std::uint8_t& counter = next_counter[index_of(Message::kType)];
    msg.counter = counter;
    const EncodeResult result = protocol::encode(msg, node, out);
    if (result == EncodeResult::kOk) {
      counter = static_cast<std::uint8_t>((counter + 1) % kCounterModulo);
    }
    return result;
  }
};

// ---------------------------------------------------------------------------------------
// Bus load

// Worst-case bits of a classic data frame with an 11-bit id and 8 data bytes, interframe
// space included: 111 bits plus at most 24 stuff bits (8n + 47 + floor((34 + 8n - 1) / 4)).
inline constexpr std::uint32_t kWorstCaseFrameBits = 135;

// Bits per second of a frame sent `frames_per_period` times every `period_ms`, worst-case
// stuffing.
constexpr double frame_bits_per_second(double frames_per_period, double period_ms) {
  return kWorstCaseFrameBits * frames_per_period * 1000.0 / period_ms;
}

}  // namespace hmpc::protocol
