// Fuzz target for the decoders of both board protocols (forearm and joint). Input bytes become
// frames, 11 bytes each (identifier, 2 bytes little-endian, masked to 11 bits; DLC byte; 8 data
// bytes, zero-padded), and every frame goes to every decoder of each protocol through that
// protocol's receiver of the node its identifier names, so counter tracking sees sequences and
// wrong-id rejects are exercised too. Properties of
// every frame a decoder accepts: each value is finite, inside its signal's [min, max] and, for
// enumerations, a listed value; it encodes again and decodes to the same values. Every decode is
// accepted or counted as exactly one reject.
//
// Built as a libFuzzer binary with clang (HMPC_BUILD_FUZZERS), and with HMPC_FUZZ_REPLAY as a
// plain program that runs the same entry point on a fixed-seed corpus of random inputs and
// bit-flipped valid frames, so every CI run checks the properties (tests/fuzz/CMakeLists.txt).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "hmpc/protocol/forearm_protocol.hpp"
#include "hmpc/protocol/joint_protocol.hpp"

namespace {

namespace protocol = hmpc::protocol;
using protocol::DecodeResult;
using protocol::EncodeResult;
using protocol::Frame;
using protocol::NodeId;
namespace detail = protocol::detail;

constexpr std::size_t kBytesPerFrame = 11;

[[noreturn]] void fail(const char* what, const Frame& frame, const char* signal) {
  std::fprintf(stderr, "protocol fuzz: %s (signal %s) in frame id 0x%03x dlc %u data", what, signal,
               static_cast<unsigned>(frame.id), static_cast<unsigned>(frame.dlc));
  for (const std::uint8_t byte : frame.data) std::fprintf(stderr, " %02x", byte);
  std::fprintf(stderr, "\n");
  std::abort();
}

// Checks each decoded value against the signal table.
struct CheckValues {
  const Frame* frame;

  template <class Signal>
  void operator()(Signal signal, const float& value) const {
    const auto& s = signal_spec(signal);
    if (!std::isfinite(value)) fail("non-finite value accepted", *frame, s.name);
    if (value < static_cast<float>(s.min) || value > static_cast<float>(s.max)) {
      fail("out-of-range value accepted", *frame, s.name);
    }
  }
  template <class Signal, class T, std::enable_if_t<!std::is_floating_point_v<T>, int> = 0>
  void operator()(Signal signal, const T& value) const {
    const auto& s = signal_spec(signal);
    const std::int64_t raw = detail::integer_value(value);
    if (raw < raw_min(s) || raw > raw_max(s)) fail("out-of-range integer accepted", *frame, s.name);
    if (s.values.count == 0) return;
    for (std::uint8_t i = 0; i < s.values.count; ++i) {
      if (s.values.values[i].value == static_cast<std::uint32_t>(raw)) return;
    }
    fail("unlisted enumerator accepted", *frame, s.name);
  }
};

// Every value of a message by signal, to compare two messages.
template <class P>
struct Values {
  std::array<double, protocol::signal_count<P>()> by_signal{};

  template <class Signal>
  void operator()(Signal signal, const float& value) {
    by_signal[index_of(signal)] = value;
  }
  template <class Signal, class T, std::enable_if_t<!std::is_floating_point_v<T>, int> = 0>
  void operator()(Signal signal, const T& value) {
    by_signal[index_of(signal)] = static_cast<double>(detail::integer_value(value));
  }
};

struct Tally {
  std::uint64_t decodes = 0;
  std::uint64_t accepted = 0;
};

Tally all_inputs;  // over every call, so a replay can show the properties were exercised

template <class Message, class P>
void try_decoder(protocol::Receiver<P>& receiver, const Frame& frame, Tally& tally) {
  Message message{};
  ++tally.decodes;
  if (receiver.decode(frame, message) != DecodeResult::kOk) return;
  ++tally.accepted;
  Message::visit(message, CheckValues{&frame});
  Frame again;
  if (protocol::encode(message, receiver.node, again) != EncodeResult::kOk) {
    fail("accepted message does not encode", frame, "-");
  }
  Message round{};
  if (protocol::decode(again, receiver.node, round) != DecodeResult::kOk) {
    fail("re-encoded message does not decode", frame, "-");
  }
  Values<P> before;
  Values<P> after;
  Message::visit(message, before);
  Message::visit(round, after);
  if (before.by_signal != after.by_signal) fail("re-encoding changed a value", frame, "-");
}

// One protocol's receivers, one per node, and the frames they took.
template <class P>
struct ProtocolUnderTest {
  std::array<protocol::Receiver<P>, P::kIds.max_node + 1u> receivers{};
  ProtocolUnderTest() {
    for (std::size_t node = 0; node < receivers.size(); ++node) {
      receivers[node].node = static_cast<NodeId>(node);
    }
  }

  // Every decoder of the protocol, through the receiver of the node the identifier names (any
  // one for identifiers of no frame of the protocol).
  template <class... Messages>
  void decode(const Frame& frame, Tally& tally, protocol::MessageList<Messages...>) {
    typename P::FrameType type{};
    NodeId node = 0;
    if (!identify(frame.id, type, node)) node = static_cast<NodeId>(frame.id % receivers.size());
    (try_decoder<Messages>(receivers[node], frame, tally), ...);
  }
  std::uint64_t rejected() const {
    std::uint64_t total = 0;
    for (const auto& receiver : receivers) total += receiver.rejects.total();
    return total;
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  ProtocolUnderTest<hmpc::forearm_protocol::Description> forearm;
  ProtocolUnderTest<hmpc::joint_protocol::Description> joint;
  Tally tally;
  for (std::size_t at = 0; at < size; at += kBytesPerFrame) {
    std::array<std::uint8_t, kBytesPerFrame> bytes{};
    for (std::size_t i = 0; i < kBytesPerFrame && at + i < size; ++i) bytes[i] = data[at + i];
    Frame frame;
    frame.id = (bytes[0] | (std::uint32_t{bytes[1]} << 8)) & 0x7FFu;
    frame.dlc = bytes[2];
    for (std::size_t i = 0; i < frame.data.size(); ++i) frame.data[i] = bytes[3 + i];
    forearm.decode(frame, tally, hmpc::forearm_protocol::Messages{});
    joint.decode(frame, tally, hmpc::joint_protocol::Messages{});
  }
  const std::uint64_t rejected = forearm.rejected() + joint.rejected();
  if (tally.accepted + rejected != tally.decodes) {
    std::fprintf(stderr, "protocol fuzz: %llu decodes, %llu accepted, %llu counted rejects\n",
                 static_cast<unsigned long long>(tally.decodes),
                 static_cast<unsigned long long>(tally.accepted),
                 static_cast<unsigned long long>(rejected));
    std::abort();
  }
  all_inputs.decodes += tally.decodes;
  all_inputs.accepted += tally.accepted;
  return 0;
}

#ifdef HMPC_FUZZ_REPLAY
#include <random>
#include <vector>

#include "fuzz_replay.hpp"

namespace {

// A frame the decoders of protocol P accept: random node and frame type, each signal a random
// valid raw value, correct checksum.
template <class P>
Frame random_valid_frame(std::mt19937_64& rng) {
  const auto& spec = P::kFrames[rng() % protocol::frame_type_count<P>()];
  std::uint64_t payload = 0;
  for (std::size_t i = 0; i < protocol::signal_count<P>(); ++i) {
    const auto& s = P::kSignals[i];
    if (s.frame != spec.type || s.kind == protocol::SignalKind::kChecksum) continue;
    const std::int64_t raw = s.values.count > 0 ? s.values.values[rng() % s.values.count].value
                                                : std::uniform_int_distribution<std::int64_t>(
                                                      raw_min(s), raw_max(s))(rng);
    detail::insert_raw(payload, detail::kCodecSpecs<P>[i], raw);
  }
  Frame frame;
  frame.id = frame_id(spec.type, static_cast<NodeId>(rng() % (P::kIds.max_node + 1u)));
  frame.dlc = spec.dlc;
  for (std::size_t i = 0; i < frame.data.size(); ++i)
    frame.data[i] = static_cast<std::uint8_t>(payload >> (8 * i));
  frame.data[protocol::kChecksumByte] = protocol::frame_checksum(frame);
  return frame;
}

// Either protocol's, at even odds.
Frame random_valid_frame(std::mt19937_64& rng) {
  return rng() % 2 ? random_valid_frame<hmpc::forearm_protocol::Description>(rng)
                   : random_valid_frame<hmpc::joint_protocol::Description>(rng);
}

std::vector<std::uint8_t> bytes_of(const Frame& frame) {
  std::vector<std::uint8_t> bytes(3 + frame.data.size());
  bytes[0] = static_cast<std::uint8_t>(frame.id);
  bytes[1] = static_cast<std::uint8_t>(frame.id >> 8);
  bytes[2] = frame.dlc;
  std::copy(frame.data.begin(), frame.data.end(), bytes.begin() + 3);
  return bytes;
}

}  // namespace

int main(int argc, char** argv) {
  constexpr int kRandomInputs = 100000;
  constexpr int kFlippedFrames = 100000;
  std::mt19937_64 rng(0x5eed'f0ea'4a11ull);
  if (argc > 1) {  // --write-corpus DIR: sequences of valid frames, the libFuzzer run's seeds
    std::vector<hmpc::fuzz::Bytes> seeds(32);
    for (hmpc::fuzz::Bytes& seed : seeds) {
      for (int f = 0; f < 4; ++f) {
        const std::vector<std::uint8_t> frame = bytes_of(random_valid_frame(rng));
        seed.insert(seed.end(), frame.begin(), frame.end());
      }
    }
    return hmpc::fuzz::replay(argc, argv, "protocol_fuzz_replay", seeds, 0, 0);
  }
  std::vector<std::uint8_t> input;
  for (int n = 0; n < kRandomInputs; ++n) {
    input.resize(rng() % (4 * kBytesPerFrame + 1));
    for (std::uint8_t& byte : input) byte = static_cast<std::uint8_t>(rng());
    LLVMFuzzerTestOneInput(input.data(), input.size());
  }
  // Valid frames with 1..3 flipped bits in identifier, DLC or data; sequences of up to four
  // frames of which the first is left intact, so accepted frames and counters are exercised.
  for (int n = 0; n < kFlippedFrames; ++n) {
    input.clear();
    const std::size_t frames = 1 + rng() % 4;
    for (std::size_t f = 0; f < frames; ++f) {
      std::vector<std::uint8_t> bytes = bytes_of(random_valid_frame(rng));
      const int flips = f == 0 ? 0 : 1 + static_cast<int>(rng() % 3);
      for (int i = 0; i < flips; ++i) {
        const std::size_t bit = rng() % (8 * bytes.size());
        bytes[bit / 8] = static_cast<std::uint8_t>(bytes[bit / 8] ^ (1u << (bit % 8)));
      }
      input.insert(input.end(), bytes.begin(), bytes.end());
    }
    LLVMFuzzerTestOneInput(input.data(), input.size());
  }
  std::printf(
      "protocol_fuzz_replay: %d random inputs and %d sequences of valid and bit-flipped "
      "frames: %llu decodes, %llu accepted, each finite, in range and re-encodable\n",
      kRandomInputs, kFlippedFrames, static_cast<unsigned long long>(all_inputs.decodes),
      static_cast<unsigned long long>(all_inputs.accepted));
  // Without accepted frames the properties would hold vacuously.
  return all_inputs.accepted > 0 ? 0 : 1;
}
#endif
