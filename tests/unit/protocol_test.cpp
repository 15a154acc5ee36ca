// The CAN codec over both board protocols (forearm and joint): identifiers, checksum, round
// trips of every frame of each, and rejection (and counting) of every malformed frame class.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <initializer_list>
#include <iterator>
#include <limits>
#include <random>
#include <string>
#include <utility>

#include "hmpc/protocol/forearm_protocol.hpp"
#include "hmpc/protocol/joint_protocol.hpp"

namespace {

using namespace hmpc::forearm_protocol;
namespace jp = hmpc::joint_protocol;
using hmpc::protocol::MessageDescription;
using hmpc::protocol::signal_count;

template <class A, class B>
struct BothLists;
template <class... A, class... B>
struct BothLists<hmpc::protocol::MessageList<A...>, hmpc::protocol::MessageList<B...>> {
  using type = ::testing::Types<A..., B...>;
};
// Every message of both protocols.
using MessageTypes = BothLists<Messages, jp::Messages>::type;

// Sets every field to the point `fraction` of the way through its signal's range (for
// enumerations: through the list of values). Physical values move `nudge` resolution steps
// further, staying in range, so they fall between grid points.
struct FillAt {
  double fraction = 0;
  double nudge = 0;

  template <class AnySignal>
  void operator()(AnySignal signal, float& value) const {
    const auto& s = signal_spec(signal);
    const double x = s.min + fraction * (s.max - s.min) + nudge * s.factor;
    value = static_cast<float>(x < s.min ? s.min : x > s.max ? s.max : x);
  }
  template <class AnySignal, class T, std::enable_if_t<!std::is_floating_point_v<T>, int> = 0>
  void operator()(AnySignal signal, T& value) const {
    const auto& s = signal_spec(signal);
    if (s.values.count > 0) {
      const auto i = static_cast<std::size_t>(std::lround(fraction * (s.values.count - 1)));
      value = static_cast<T>(s.values.values[i].value);
    } else {
      value = static_cast<T>(raw_min(s) +
                             std::llround(fraction * static_cast<double>(raw_max(s) - raw_min(s))));
    }
  }
};

// Sets every field to a uniformly drawn value of its signal.
struct FillRandom {
  std::mt19937_64* rng;

  template <class AnySignal>
  void operator()(AnySignal signal, float& value) const {
    const auto& s = signal_spec(signal);
    value = static_cast<float>(std::uniform_real_distribution<double>(s.min, s.max)(*rng));
  }
  template <class AnySignal, class T, std::enable_if_t<!std::is_floating_point_v<T>, int> = 0>
  void operator()(AnySignal signal, T& value) const {
    const auto& s = signal_spec(signal);
    if (s.values.count > 0) {
      std::uniform_int_distribution<int> pick(0, s.values.count - 1);
      value = static_cast<T>(s.values.values[pick(*rng)].value);
    } else {
      value =
          static_cast<T>(std::uniform_int_distribution<std::int64_t>(raw_min(s), raw_max(s))(*rng));
    }
  }
};

// Every field's value by signal, so two messages can be compared signal by signal.
template <class P>
struct Snapshot {
  std::array<double, signal_count<P>()> value{};

  template <class AnySignal>
  void operator()(AnySignal signal, const float& v) {
    value[index_of(signal)] = v;
  }
  template <class AnySignal, class T, std::enable_if_t<!std::is_floating_point_v<T>, int> = 0>
  void operator()(AnySignal signal, const T& v) {
    value[index_of(signal)] = static_cast<double>(detail::integer_value(v));
  }
};

template <class Message>
Snapshot<MessageDescription<Message>> snapshot(const Message& message) {
  Snapshot<MessageDescription<Message>> s;
  Message::visit(message, s);
  return s;
}

// Sets the n-th float field (in visit order) to a given value.
template <class AnySignal>
struct SetNthFloat {
  int n;
  float to;
  int seen = 0;
  AnySignal hit{};

  void operator()(AnySignal signal, float& value) {
    if (seen++ == n) {
      value = to;
      hit = signal;
    }
  }
  template <class T, std::enable_if_t<!std::is_floating_point_v<T>, int> = 0>
  void operator()(AnySignal, T&) {}
};
template <class Message>
using SetNthFloatOf = SetNthFloat<typename MessageDescription<Message>::Signal>;

template <class Message>
int float_field_count() {
  Message message{};
  SetNthFloatOf<Message> counter{-1, 0};
  Message::visit(message, counter);
  return counter.seen;
}

// Tolerance of a round trip: half a resolution step plus float rounding of the value.
template <class Spec>
double quantisation_bound(const Spec& s, double value) {
  return 0.5 * s.factor +
         4 * std::numeric_limits<float>::epsilon() * std::max(1.0, std::abs(value));
}

template <class Message>
void expect_round_trip(const Message& sent, NodeId node) {
  Frame frame;
  ASSERT_EQ(encode(sent, node, frame), EncodeResult::kOk);
  EXPECT_EQ(frame.id, frame_id(Message::kType, node));
  EXPECT_EQ(frame.dlc, 8);
  Message received{};
  ASSERT_EQ(decode(frame, node, received), DecodeResult::kOk);
  const auto a = snapshot(sent);
  const auto b = snapshot(received);
  for (const auto& s : MessageDescription<Message>::kSignals) {
    if (s.frame != Message::kType || s.kind == SignalKind::kChecksum) continue;
    const double in = a.value[index_of(s.signal)];
    const double out = b.value[index_of(s.signal)];
    if (s.kind == SignalKind::kPhysical) {
      EXPECT_LE(std::abs(out - in), quantisation_bound(s, in)) << s.name << " sent " << in;
      EXPECT_GE(out, static_cast<float>(s.min)) << s.name;
      EXPECT_LE(out, static_cast<float>(s.max)) << s.name;
    } else {
      EXPECT_EQ(out, in) << s.name;
    }
  }
}

// Overwrites one signal's raw bits and reseals the frame with a valid checksum.
template <class AnySignal>
void set_raw(Frame& frame, AnySignal signal, std::int64_t raw) {
  const detail::CodecSpec& spec = detail::codec_spec(signal);
  std::uint64_t payload =
      detail::payload_of(frame) & ~(detail::low_bits(spec.length) << spec.start_bit);
  detail::insert_raw(payload, spec, raw);
  for (std::size_t i = 0; i < 8; ++i) frame.data[i] = static_cast<std::uint8_t>(payload >> (8 * i));
  frame.data[kChecksumByte] = frame_checksum(frame);
}

template <class Message>
Frame valid_frame(NodeId node, std::uint8_t counter = 0) {
  Message message{};
  Message::visit(message, FillAt{0.5, 0});
  message.counter = counter;
  Frame frame;
  EXPECT_EQ(encode(message, node, frame), EncodeResult::kOk);
  return frame;
}

template <class Message>
bool accepts(const Frame& frame, NodeId node) {
  Message message;
  return decode(frame, node, message) == DecodeResult::kOk;
}

// Whether the decoder of the frame type and node its identifier names accepts it.
bool accepted_by_any(const Frame& frame) {
  FrameType type{};
  NodeId node = 0;
  if (!identify(frame.id, type, node)) return false;
  return accepts<ModeCommand>(frame, node) || accepts<SensorSample>(frame, node) ||
         accepts<ActuatorCommand>(frame, node) || accepts<TrajectorySample>(frame, node) ||
         accepts<BoardStatus>(frame, node) || accepts<JointState>(frame, node) ||
         accepts<ActuatorOutputs>(frame, node) || accepts<SolveTelemetry>(frame, node) ||
         accepts<Gains>(frame, node) || accepts<Sync>(frame, node);
}

// ---------------------------------------------------------------------------------------

TEST(ProtocolChecksum, IsCrc8AutosarByItsCheckValue) {
  const char* check = "123456789";
  EXPECT_EQ(crc8_autosar(reinterpret_cast<const std::uint8_t*>(check), std::strlen(check)), 0xDF);
}

// CRC-8/AUTOSAR has Hamming distance 4 at this length: every 1-, 2- and 3-bit error in the
// identifier or payload is caught. The CRC is linear, so one frame stands for all.
TEST(ProtocolChecksum, DetectsEveryOneToThreeBitErrorInIdAndPayload) {
  const Frame valid = valid_frame<SensorSample>(5);
  constexpr int kBits = 11 + 64;
  auto flip = [](Frame& f, int bit) {
    if (bit < 11) {
      f.id ^= 1u << bit;
    } else {
      f.data[(bit - 11) / 8] ^= static_cast<std::uint8_t>(1u << ((bit - 11) % 8));
    }
  };
  ASSERT_TRUE(accepted_by_any(valid));
  int patterns = 0;
  int undetected = 0;
  auto check = [&](std::initializer_list<int> bits) {
    Frame f = valid;
    for (const int bit : bits) flip(f, bit);
    undetected += accepted_by_any(f);
    ++patterns;
  };
  for (int a = 0; a < kBits; ++a) {
    check({a});
    for (int b = a + 1; b < kBits; ++b) {
      check({a, b});
      for (int c = b + 1; c < kBits; ++c) check({a, b, c});
    }
  }
  EXPECT_EQ(undetected, 0);
  EXPECT_EQ(patterns, 75 + 75 * 74 / 2 + 75 * 74 * 73 / 6);
}

TEST(ProtocolIds, NodeBasePlusFrameOffset) {
  EXPECT_EQ(frame_id(FrameType::kModeCommand, 0), 0x100u);
  EXPECT_EQ(frame_id(FrameType::kSensor, 0), 0x101u);
  EXPECT_EQ(frame_id(FrameType::kGains, 0), 0x108u);
  EXPECT_EQ(frame_id(FrameType::kModeCommand, 15), 0x1F0u);
  EXPECT_EQ(frame_id(FrameType::kGains, 15), 0x1F8u);
  for (NodeId node = 0; node <= kMaxNodeId; ++node) {
    for (const FrameSpec& spec : kFrames) {
      FrameType type{};
      NodeId found = 99;
      ASSERT_TRUE(identify(frame_id(spec.type, node), type, found));
      EXPECT_EQ(type, spec.type);
      EXPECT_EQ(found, node);
    }
  }
  FrameType type{};
  NodeId node = 0;
  EXPECT_FALSE(identify(0x0FF, type, node));
  EXPECT_TRUE(identify(0x10A, type, node));   // offset 10: CostWeights
  EXPECT_FALSE(identify(0x10B, type, node));  // offset 11: no frame
  EXPECT_FALSE(identify(0x200, type, node));
}

TEST(ProtocolLayout, SensorFrameBytes) {
  SensorSample sample;
  sample.theta = 1.0f;
  sample.theta_dot = -10.0f;
  sample.pressure = 0.8f;
  sample.counter = 3;
  Frame frame;
  ASSERT_EQ(encode(sample, 0, frame), EncodeResult::kOk);
  EXPECT_EQ(frame.id, 0x101u);
  // theta 10000 = 0x2710, theta_dot -10000 = 0xD8F0, pressure 40000 = 0x9C40, little-endian.
  const std::array<std::uint8_t, 9> covered = {0x01, 0x01, 0x03, 0x10, 0x27,
                                               0xF0, 0xD8, 0x40, 0x9C};
  const std::array<std::uint8_t, 8> expected = {
      crc8_autosar(covered.data(), covered.size()), 0x03, 0x10, 0x27, 0xF0, 0xD8, 0x40, 0x9C};
  EXPECT_EQ(frame.data, expected);
}

TEST(ProtocolLayout, ModeCommandBytes) {
  ModeCommand command;
  command.mode = RequestedMode::kRun;
  command.strategy = Strategy::kTwoStage;
  command.clear_faults = true;
  command.host_time_us = 0x12345678;
  command.counter = 5;
  Frame frame;
  ASSERT_EQ(encode(command, 2, frame), EncodeResult::kOk);
  EXPECT_EQ(frame.id, 0x120u);
  const std::array<std::uint8_t, 8> payload = {frame.data[0], 0x35, 0x14, 0x00,
                                               0x78,          0x56, 0x34, 0x12};
  EXPECT_EQ(frame.data, payload);
  EXPECT_EQ(frame.data[0], frame_checksum(frame));
}

// ---------------------------------------------------------------------------------------

template <class Message>
class ProtocolRoundTrip : public ::testing::Test {};
// Test names carry the frame's name rather than an index.
struct FrameName {
  template <class Message>
  static std::string GetName(int) {
    const bool forearm = std::is_same_v<MessageDescription<Message>, Description>;
    return std::string(forearm ? "Forearm" : "Joint") + frame_spec(Message::kType).name;
  }
};
TYPED_TEST_SUITE(ProtocolRoundTrip, MessageTypes, FrameName);

TYPED_TEST(ProtocolRoundTrip, RangeEndsAndInteriorPoints) {
  for (const double fraction : {0.0, 1.0, 0.5, 0.25, 0.731, 0.999}) {
    for (const double nudge : {0.0, 0.37, -0.5, 0.49}) {
      TypeParam message{};
      TypeParam::visit(message, FillAt{fraction, nudge});
      message.counter = static_cast<std::uint8_t>(std::lround(fraction * 15));
      SCOPED_TRACE(testing::Message() << "fraction " << fraction << " nudge " << nudge);
      expect_round_trip(message, 7);
    }
  }
}

TYPED_TEST(ProtocolRoundTrip, RandomValuesWithinHalfAStep) {
  std::mt19937_64 rng(17);
  for (int trial = 0; trial < 2000; ++trial) {
    TypeParam message{};
    TypeParam::visit(message, FillRandom{&rng});
    message.counter = static_cast<std::uint8_t>(trial % 16);
    expect_round_trip(message, static_cast<NodeId>(trial % 16));
    if (::testing::Test::HasFailure()) return;
  }
}

// NaN and infinities in any physical field: kNotFinite, and the output frame is untouched.
TYPED_TEST(ProtocolRoundTrip, EncodeRejectsNonFiniteValues) {
  const int fields = float_field_count<TypeParam>();
  for (int n = 0; n < fields; ++n) {
    for (const float bad :
         {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
          -std::numeric_limits<float>::infinity()}) {
      TypeParam message{};
      TypeParam::visit(message, FillAt{0.5, 0});
      SetNthFloatOf<TypeParam> set{n, bad};
      TypeParam::visit(message, set);
      Frame frame;
      frame.id = 0x7FF;
      frame.data.fill(0xAA);
      EXPECT_EQ(encode(message, 0, frame), EncodeResult::kNotFinite) << signal_spec(set.hit).name;
      EXPECT_EQ(frame.id, 0x7FFu);
      EXPECT_EQ(frame.data[3], 0xAA);
    }
  }
}

// One resolution step beyond either end of any physical field: kOutOfRange, frame untouched.
TYPED_TEST(ProtocolRoundTrip, EncodeRejectsOutOfRangeValues) {
  const int fields = float_field_count<TypeParam>();
  for (int n = 0; n < fields; ++n) {
    for (const bool above : {true, false}) {
      TypeParam message{};
      TypeParam::visit(message, FillAt{0.5, 0});
      SetNthFloatOf<TypeParam> find{n, 0};
      TypeParam::visit(message, find);
      const auto& s = signal_spec(find.hit);
      SetNthFloatOf<TypeParam> set{n,
                                   static_cast<float>(above ? s.max + s.factor : s.min - s.factor)};
      TypeParam::visit(message, set);
      Frame frame;
      frame.data.fill(0xAA);
      EXPECT_EQ(encode(message, 0, frame), EncodeResult::kOutOfRange)
          << s.name << (above ? " above" : " below");
      EXPECT_EQ(frame.data[0], 0xAA);
    }
  }
  TypeParam message{};
  message.counter = 16;
  Frame frame;
  EXPECT_EQ(encode(message, 0, frame), EncodeResult::kOutOfRange);
  message.counter = 0;
  const hmpc::protocol::IdLayout& ids = MessageDescription<TypeParam>::kIds;
  EXPECT_EQ(encode(message, ids.max_node + 1, frame), EncodeResult::kInvalidNode);
}

TEST(ProtocolEncode, RejectsUnknownEnumerators) {
  Frame frame;
  ModeCommand command;
  command.mode = static_cast<RequestedMode>(0);
  EXPECT_EQ(encode(command, 0, frame), EncodeResult::kUnknownMode);
  command.mode = static_cast<RequestedMode>(4);
  EXPECT_EQ(encode(command, 0, frame), EncodeResult::kUnknownMode);
  command.mode = RequestedMode::kHold;
  command.strategy = static_cast<Strategy>(6);
  EXPECT_EQ(encode(command, 0, frame), EncodeResult::kUnknownEnum);
  BoardStatus status;
  status.mode = static_cast<BoardMode>(5);
  EXPECT_EQ(encode(status, 0, frame), EncodeResult::kUnknownMode);
  SolveTelemetry telemetry;
  telemetry.status = static_cast<SolveStatusCode>(7);
  EXPECT_EQ(encode(telemetry, 0, frame), EncodeResult::kUnknownEnum);
}

// ---------------------------------------------------------------------------------------
// Malformed frames through a Receiver: each class rejected with its result and counted.

TEST(ProtocolRejects, WrongLength) {
  Receiver receiver{4};
  SensorSample out;
  for (const std::uint8_t dlc : {0, 7, 9, 15}) {
    Frame frame = valid_frame<SensorSample>(4);
    frame.dlc = dlc;
    EXPECT_EQ(receiver.decode(frame, out), DecodeResult::kWrongLength) << int{dlc};
  }
  EXPECT_EQ(receiver.rejects.wrong_length, 4u);
  EXPECT_EQ(receiver.rejects.total(), 4u);
}

TEST(ProtocolRejects, BadChecksum) {
  Receiver receiver{4};
  JointState out;
  Frame payload_bit = valid_frame<JointState>(4);
  payload_bit.data[5] ^= 0x10;
  EXPECT_EQ(receiver.decode(payload_bit, out), DecodeResult::kBadChecksum);
  Frame checksum_byte = valid_frame<JointState>(4);
  checksum_byte.data[kChecksumByte] ^= 0x01;
  EXPECT_EQ(receiver.decode(checksum_byte, out), DecodeResult::kBadChecksum);
  // Node 3's frame relabelled as node 4's: the checksum covers the identifier.
  Frame relabelled = valid_frame<JointState>(3);
  relabelled.id = frame_id(FrameType::kJointState, 4);
  EXPECT_EQ(receiver.decode(relabelled, out), DecodeResult::kBadChecksum);
  EXPECT_EQ(receiver.rejects.bad_checksum, 3u);
  EXPECT_EQ(receiver.rejects.total(), 3u);
}

TEST(ProtocolRejects, WrongId) {
  Receiver receiver{4};
  JointState joint;
  EXPECT_EQ(receiver.decode(valid_frame<SensorSample>(4), joint), DecodeResult::kWrongId);
  EXPECT_EQ(receiver.decode(valid_frame<JointState>(5), joint), DecodeResult::kWrongId);
  EXPECT_EQ(receiver.rejects.wrong_id, 2u);
  EXPECT_EQ(decode(valid_frame<JointState>(5), kMaxNodeId + 1, joint), DecodeResult::kWrongId);
}

TEST(ProtocolRejects, OutOfRangeRawValues) {
  Receiver receiver{1};
  SensorSample sensor;
  ActuatorOutputs outputs;
  Gains gains;
  const std::pair<Signal, std::int64_t> cases[] = {
      {Signal::kSensorTheta, 31417},      {Signal::kSensorTheta, -31417},
      {Signal::kSensorThetaDot, 20001},   {Signal::kSensorPressure, 40001},
      {Signal::kSensorPressure, 65535},   {Signal::kActuatorOutputsVm, -2001},
      {Signal::kActuatorOutputsVp, 4095}, {Signal::kActuatorOutputsTauM, 7501},
      {Signal::kGainsKp, 4001},           {Signal::kGainsLoadVelocity, 2047},
  };
  for (const auto& [signal, raw] : cases) {
    const FrameType type = signal_spec(signal).frame;
    Frame frame = type == FrameType::kSensor            ? valid_frame<SensorSample>(1)
                  : type == FrameType::kActuatorOutputs ? valid_frame<ActuatorOutputs>(1)
                                                        : valid_frame<Gains>(1);
    set_raw(frame, signal, raw);
    const DecodeResult result = type == FrameType::kSensor ? receiver.decode(frame, sensor)
                                : type == FrameType::kActuatorOutputs
                                    ? receiver.decode(frame, outputs)
                                    : receiver.decode(frame, gains);
    EXPECT_EQ(result, DecodeResult::kOutOfRange) << signal_spec(signal).name << " raw " << raw;
  }
  EXPECT_EQ(receiver.rejects.out_of_range, std::size(cases));
  // The range ends themselves are accepted.
  Frame frame = valid_frame<SensorSample>(1);
  set_raw(frame, Signal::kSensorTheta, -31416);
  set_raw(frame, Signal::kSensorPressure, 40000);
  ASSERT_EQ(decode(frame, 1, sensor), DecodeResult::kOk);
  EXPECT_FLOAT_EQ(sensor.theta, -3.1416f);
  EXPECT_FLOAT_EQ(sensor.pressure, 0.8f);
}

TEST(ProtocolRejects, UnknownModesAndEnumerators) {
  Receiver receiver{2};
  ModeCommand command;
  for (const std::int64_t raw : {0, 4, 15}) {
    Frame frame = valid_frame<ModeCommand>(2, static_cast<std::uint8_t>(raw));
    set_raw(frame, Signal::kModeCommandRequestedMode, raw);
    EXPECT_EQ(receiver.decode(frame, command), DecodeResult::kUnknownMode) << raw;
  }
  Frame strategy = valid_frame<ModeCommand>(2);
  set_raw(strategy, Signal::kModeCommandStrategy, 6);
  EXPECT_EQ(receiver.decode(strategy, command), DecodeResult::kUnknownEnum);
  BoardStatus status;
  Frame mode = valid_frame<BoardStatus>(2);
  set_raw(mode, Signal::kBoardStatusMode, 5);
  EXPECT_EQ(receiver.decode(mode, status), DecodeResult::kUnknownMode);
  SolveTelemetry telemetry;
  Frame solve = valid_frame<SolveTelemetry>(2);
  set_raw(solve, Signal::kSolveTelemetryStatus, 9);
  EXPECT_EQ(receiver.decode(solve, telemetry), DecodeResult::kUnknownEnum);
  EXPECT_EQ(receiver.rejects.unknown_mode, 4u);
  EXPECT_EQ(receiver.rejects.unknown_enum, 2u);
  EXPECT_EQ(receiver.rejects.total(), 6u);
}

// A rejected frame leaves the caller's message as it was.
TEST(ProtocolRejects, LeaveTheOutputUntouched) {
  Receiver receiver{0};
  SensorSample out;
  out.theta = 0.125f;
  out.counter = 9;
  Frame frame = valid_frame<SensorSample>(0);
  set_raw(frame, Signal::kSensorPressure, 50000);
  ASSERT_EQ(receiver.decode(frame, out), DecodeResult::kOutOfRange);
  EXPECT_EQ(out.theta, 0.125f);
  EXPECT_EQ(out.counter, 9);
}

// ---------------------------------------------------------------------------------------

TEST(ProtocolCounters, RepeatedAndSkippedBackCountersAreStale) {
  Receiver receiver{6};
  TrajectorySample out;
  auto send = [&](std::uint8_t counter) {
    return receiver.decode(valid_frame<TrajectorySample>(6, counter), out);
  };
  EXPECT_EQ(send(5), DecodeResult::kOk);             // first frame: any counter
  EXPECT_EQ(send(5), DecodeResult::kStaleCounter);   // repeated
  EXPECT_EQ(send(4), DecodeResult::kStaleCounter);   // one back
  EXPECT_EQ(send(13), DecodeResult::kStaleCounter);  // 8 ahead = 8 back
  EXPECT_EQ(send(6), DecodeResult::kOk);
  EXPECT_EQ(send(13), DecodeResult::kOk);  // 7 ahead: six frames lost
  EXPECT_EQ(send(0), DecodeResult::kOk);   // wraps modulo 16
  EXPECT_EQ(send(15), DecodeResult::kStaleCounter);
  EXPECT_EQ(receiver.rejects.stale_counter, 4u);
  EXPECT_EQ(receiver.rejects.total(), 4u);
  receiver.counters.reset(FrameType::kTrajectorySample);  // e.g. after a timeout
  EXPECT_EQ(send(15), DecodeResult::kOk);
}

// A sender that restarted counts from 0 again: stale to a receiver that heard it at 5, until
// three of its frames in a row run on by 1, the third taken. A sender repeating one frame (a
// frozen transmitter) never is, nor are stale frames whose counters jump about.
TEST(ProtocolCounters, ASenderThatRestartedIsFollowedAfterThreeFramesRunningOn) {
  Receiver receiver{6};
  TrajectorySample out;
  auto send = [&](std::uint8_t counter) {
    return receiver.decode(valid_frame<TrajectorySample>(6, counter), out);
  };
  EXPECT_EQ(send(4), DecodeResult::kOk);
  EXPECT_EQ(send(5), DecodeResult::kOk);
  EXPECT_EQ(send(0), DecodeResult::kStaleCounter);  // restarted: 5 back
  EXPECT_EQ(send(1), DecodeResult::kStaleCounter);
  EXPECT_EQ(send(2), DecodeResult::kOk);  // the third running on
  EXPECT_EQ(send(3), DecodeResult::kOk);
  EXPECT_EQ(send(3), DecodeResult::kStaleCounter);  // then repeats, as ever
  for (int i = 0; i < 20; ++i) EXPECT_EQ(send(3), DecodeResult::kStaleCounter);
  EXPECT_EQ(send(12), DecodeResult::kStaleCounter);  // 9 ahead
  EXPECT_EQ(send(14), DecodeResult::kStaleCounter);  // runs on by 2, not 1
  EXPECT_EQ(send(15), DecodeResult::kStaleCounter);
  EXPECT_EQ(send(0), DecodeResult::kOk);  // 14, 15, 0: three running on
  EXPECT_EQ(receiver.rejects.stale_counter, 26u);
}

TEST(ProtocolCounters, EachFrameTypeHasItsOwnSequence) {
  Receiver receiver{0};
  ModeCommand command;
  Gains gains;
  EXPECT_EQ(receiver.decode(valid_frame<ModeCommand>(0, 3), command), DecodeResult::kOk);
  EXPECT_EQ(receiver.decode(valid_frame<Gains>(0, 3), gains), DecodeResult::kOk);
  EXPECT_EQ(receiver.decode(valid_frame<ModeCommand>(0, 4), command), DecodeResult::kOk);
  EXPECT_EQ(receiver.decode(valid_frame<Gains>(0, 3), gains), DecodeResult::kStaleCounter);
  receiver.counters.reset_all();
  EXPECT_EQ(receiver.decode(valid_frame<Gains>(0, 3), gains), DecodeResult::kOk);
}

// A frame rejected for another reason does not move the tracker.
TEST(ProtocolCounters, RejectedFrameDoesNotAdvanceTheTracker) {
  Receiver receiver{0};
  SensorSample out;
  ASSERT_EQ(receiver.decode(valid_frame<SensorSample>(0, 1), out), DecodeResult::kOk);
  Frame corrupt = valid_frame<SensorSample>(0, 2);
  set_raw(corrupt, Signal::kSensorThetaDot, 30000);
  EXPECT_EQ(receiver.decode(corrupt, out), DecodeResult::kOutOfRange);
  EXPECT_EQ(receiver.decode(valid_frame<SensorSample>(0, 2), out), DecodeResult::kOk);
}

TEST(ProtocolCounters, SenderStampsAndWrapsPerFrameType) {
  Sender sender{9};
  Receiver receiver{9};
  ActuatorCommand command;
  command.v_p = 2.5f;
  Frame frame;
  for (int i = 0; i < 40; ++i) {
    ASSERT_EQ(sender.encode(command, frame), EncodeResult::kOk);
    ActuatorCommand out;
    ASSERT_EQ(receiver.decode(frame, out), DecodeResult::kOk) << i;
    EXPECT_EQ(out.counter, i % 16);
  }
  // A failed encode does not use up a counter value.
  command.v_m = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(sender.encode(command, frame), EncodeResult::kNotFinite);
  command.v_m = 0;
  ASSERT_EQ(sender.encode(command, frame), EncodeResult::kOk);
  ActuatorCommand out;
  EXPECT_EQ(receiver.decode(frame, out), DecodeResult::kOk);
  EXPECT_EQ(out.counter, 40 % 16);
  Frame gains;
  ASSERT_EQ(sender.encode(Gains{}, gains), EncodeResult::kOk);
  EXPECT_EQ(gains.data[1] & 0x0F, 0);
}

TEST(ProtocolCounters, RejectCountersCountEachClass) {
  RejectCounters counters;
  const DecodeResult all[] = {DecodeResult::kOk,           DecodeResult::kWrongId,
                              DecodeResult::kWrongLength,  DecodeResult::kBadChecksum,
                              DecodeResult::kStaleCounter, DecodeResult::kOutOfRange,
                              DecodeResult::kUnknownMode,  DecodeResult::kUnknownEnum};
  for (const DecodeResult r : all) counters.count(r);
  counters.count(DecodeResult::kBadChecksum);
  EXPECT_EQ(counters.wrong_id, 1u);
  EXPECT_EQ(counters.wrong_length, 1u);
  EXPECT_EQ(counters.bad_checksum, 2u);
  EXPECT_EQ(counters.stale_counter, 1u);
  EXPECT_EQ(counters.out_of_range, 1u);
  EXPECT_EQ(counters.unknown_mode, 1u);
  EXPECT_EQ(counters.unknown_enum, 1u);
  EXPECT_EQ(counters.total(), 8u);
}

// ---------------------------------------------------------------------------------------

// The bus load of each setup, robot and HIL: printed as a figure, the sum pinned.
TEST(ProtocolBusLoad, RobotAndHilSetups) {
  // Per second: robot 100 + 250 + 100 + 3 * 250 frames; HIL adds 3 * 1000 plant frames
  // (Sensor, ActuatorCommand, Sync).
  EXPECT_NEAR(bus_load(Setup::kRobot, 1'000'000), 1200.0 * 135 / 1e6, 1e-12);
  EXPECT_NEAR(bus_load(Setup::kHil, 1'000'000), 4200.0 * 135 / 1e6, 1e-12);
  for (const std::uint32_t bitrate : {500'000u, 1'000'000u}) {
    std::printf(
        "forearm protocol bus load at %u kbit/s, one board, worst-case stuffing: "
        "robot %.1f %%, HIL %.1f %%\n",
        bitrate / 1000, 100 * bus_load(Setup::kRobot, bitrate),
        100 * bus_load(Setup::kHil, bitrate));
  }
  // Below the ~70 % beyond which lower-priority frames on a classic CAN bus start to queue
  // for whole frame times: the HIL also fits a real 1 Mbit/s bus.
  EXPECT_LT(bus_load(Setup::kHil, 1'000'000), 0.7);
}

// ---------------------------------------------------------------------------------------
// The joint protocol's own layout: bus-wide frames, the wider node stride, per-joint frames.

TEST(JointProtocolIds, BusWideFramesAndNodeStride) {
  EXPECT_EQ(frame_id(jp::FrameType::kEStop, 0), 0x080u);
  EXPECT_EQ(frame_id(jp::FrameType::kEStop, 9), 0x080u);
  EXPECT_EQ(frame_id(jp::FrameType::kSync, 3), 0x081u);
  EXPECT_EQ(frame_id(jp::FrameType::kModeCommand, 0), 0x200u);
  EXPECT_EQ(frame_id(jp::FrameType::kValveDrive, 15), 0x3F6u);
  EXPECT_EQ(frame_id(jp::joint_frame(jp::FrameType::kJointState0, 3), 1), 0x228u);
  for (NodeId node = 0; node <= jp::kIds.max_node; ++node) {
    for (const jp::FrameSpec& spec : jp::kFrames) {
      jp::FrameType type{};
      NodeId found = 99;
      ASSERT_TRUE(identify(frame_id(spec.type, node), type, found));
      EXPECT_EQ(type, spec.type);
      EXPECT_EQ(found, spec.bus_wide ? 0 : node);
    }
  }
  jp::FrameType type{};
  NodeId node = 0;
  EXPECT_FALSE(identify(0x1FF, type, node));  // the forearm protocol's range
  EXPECT_FALSE(identify(0x20E, type, node));  // offset 0x0E: no frame
  EXPECT_FALSE(identify(0x400, type, node));
  EXPECT_FALSE(identify(0x082, type, node));
  // Neither protocol takes the other's frames for its own.
  FrameType forearm_type{};
  for (const jp::FrameSpec& spec : jp::kFrames) {
    EXPECT_FALSE(identify(frame_id(spec.type, 0), forearm_type, node)) << spec.name;
  }
}

// What a node's acceptance filter is set from: exactly the identifiers identify() gives that
// node (its own block and the bus-wide frames), none of another node's.
TEST(JointProtocolIds, AcceptedIdsAreTheNodesBlockAndTheBusWideFrames) {
  const hmpc::protocol::AcceptedIds accepted = hmpc::protocol::accepted_ids<jp::Description>(3);
  ASSERT_EQ(accepted.count, 3u);
  EXPECT_EQ(accepted.ranges[0].first, 0x260u);
  EXPECT_EQ(accepted.ranges[0].last, 0x27Fu);
  EXPECT_EQ(accepted.ranges[1].first, 0x080u);
  EXPECT_EQ(accepted.ranges[2].first, 0x081u);
  const auto accepts = [&](std::uint32_t id) {
    for (std::size_t i = 0; i < accepted.count; ++i) {
      if (id >= accepted.ranges[i].first && id <= accepted.ranges[i].last) return true;
    }
    return false;
  };
  for (std::uint32_t id = 0; id < 0x800; ++id) {
    jp::FrameType type{};
    NodeId node = 0;
    const bool ours = identify(id, type, node) && (node == 3 || jp::frame_spec(type).bus_wide);
    if (ours) {
      EXPECT_TRUE(accepts(id)) << std::hex << id;
    } else if (identify(id, type, node)) {
      EXPECT_FALSE(accepts(id)) << std::hex << id;  // another node's frame
    }
  }
  const hmpc::protocol::AcceptedIds forearm = hmpc::protocol::accepted_ids<Description>(2);
  ASSERT_EQ(forearm.count, 1u);  // the forearm protocol has no bus-wide frame
  EXPECT_EQ(forearm.ranges[0].first, 0x120u);
  EXPECT_EQ(forearm.ranges[0].last, 0x12Fu);
}

TEST(JointProtocolLayout, TorqueReferenceBytes) {
  jp::TorqueReference reference;
  reference.tau = {1.0f, -1.0f, 200.0f, -0.05f};
  reference.counter = 7;
  Frame frame;
  ASSERT_EQ(encode(reference, 1, frame), EncodeResult::kOk);
  EXPECT_EQ(frame.id, 0x221u);
  // 13-bit two's complement at 0.05 N.m from bit 12: 20, -20 (0x1FEC), 4000 (0xFA0), -1 (0x1FFF).
  const std::uint64_t expected_payload =
      (std::uint64_t{7} << 8) | (std::uint64_t{20} << 12) | (std::uint64_t{0x1FEC} << 25) |
      (std::uint64_t{0xFA0} << 38) | (std::uint64_t{0x1FFF} << 51);
  EXPECT_EQ(detail::payload_of(frame) & ~std::uint64_t{0xFF}, expected_payload);
  EXPECT_EQ(frame.data[kChecksumByte], frame_checksum(frame));
}

// An E-stop must say engage = 1: a zeroed payload, even with a valid checksum, stops nothing.
TEST(JointProtocolRejects, EStopWithoutEngageAndUnknownModes) {
  jp::Receiver receiver{2};
  jp::EStop stop;
  Frame frame = valid_frame<jp::EStop>(2);
  ASSERT_EQ(receiver.decode(frame, stop), DecodeResult::kOk);
  set_raw(frame, jp::Signal::kEStopEngage, 0);
  EXPECT_EQ(receiver.decode(frame, stop), DecodeResult::kOutOfRange);
  jp::ModeCommand command;
  Frame mode = valid_frame<jp::ModeCommand>(2);
  set_raw(mode, jp::Signal::kModeCommandRequestedMode, 0);
  EXPECT_EQ(receiver.decode(mode, command), DecodeResult::kUnknownMode);
  jp::BoardStatus status;
  Frame board_mode = valid_frame<jp::BoardStatus>(2);
  set_raw(board_mode, jp::Signal::kBoardStatusMode, 7);
  EXPECT_EQ(receiver.decode(board_mode, status), DecodeResult::kUnknownMode);
  EXPECT_EQ(receiver.rejects.total(), 3u);
}

TEST(JointProtocolRejects, OutOfRangeRawValues) {
  jp::Receiver receiver{1};
  const std::pair<jp::Signal, std::int64_t> cases[] = {
      {jp::Signal::kTorqueReferenceTau0, 4001},
      {jp::Signal::kTorqueReferenceTau3, -4001},
      {jp::Signal::kTorqueGainsJoint, 4},
      {jp::Signal::kTorqueGainsKp, 4001},
      {jp::Signal::kTorqueGainsLoadVelocity, -4001},
  };
  for (const auto& [signal, raw] : cases) {
    DecodeResult result{};
    if (signal_spec(signal).frame == jp::FrameType::kTorqueReference) {
      Frame frame = valid_frame<jp::TorqueReference>(1);
      set_raw(frame, signal, raw);
      jp::TorqueReference out;
      result = receiver.decode(frame, out);
    } else {
      Frame frame = valid_frame<jp::TorqueGains>(1);
      set_raw(frame, signal, raw);
      jp::TorqueGains out;
      result = receiver.decode(frame, out);
    }
    EXPECT_EQ(result, DecodeResult::kOutOfRange) << signal_spec(signal).name << " raw " << raw;
  }
  EXPECT_EQ(receiver.rejects.out_of_range, std::size(cases));
}

// Each joint slot is its own frame type with its own counter sequence.
TEST(JointProtocolCounters, EachJointSlotHasItsOwnSequence) {
  jp::Receiver receiver{0};
  jp::JointSensor<0> zero;
  jp::JointSensor<1> one;
  EXPECT_EQ(receiver.decode(valid_frame<jp::JointSensor<0>>(0, 5), zero), DecodeResult::kOk);
  EXPECT_EQ(receiver.decode(valid_frame<jp::JointSensor<1>>(0, 5), one), DecodeResult::kOk);
  EXPECT_EQ(receiver.decode(valid_frame<jp::JointSensor<0>>(0, 5), zero),
            DecodeResult::kStaleCounter);
  // A frame of slot 1 is not slot 0's.
  EXPECT_EQ(receiver.decode(valid_frame<jp::JointSensor<1>>(0, 6), zero), DecodeResult::kWrongId);
}

// The joint protocol's bus budget, per bus at 1 Mbit/s, worst-case stuffing: 2 boards of 4
// joints and the IMU (the humanoid's 8 leg joints). Counted by hand for the robot bus at 6 ms:
// per board a TorqueReference, 4 JointState and ValveCommands per period, ModeCommand every
// 10 ms, BoardStatus every 20 ms, EncoderOffset every 100 ms; the IMU's 3 frames per period.
TEST(JointProtocolBusLoad, RobotBusAtSixMillisecondsIsWithinFortyPercent) {
  const jp::BusLayout legs{2, 4, true, 6};
  const double robot_frames_per_second = 2 * (6 * 1000.0 / 6 + 100 + 50 + 10) + 3 * 1000.0 / 6;
  EXPECT_NEAR(jp::bus_load(jp::Bus::kRobot, 1'000'000, legs), robot_frames_per_second * 135 / 1e6,
              1e-12);
  // The I/O bus: per board 4 JointSensor, 2 ChamberPressures and ValveDrive every 1 ms, and
  // one Sync for all.
  EXPECT_NEAR(jp::bus_load(jp::Bus::kIo, 1'000'000, legs), (2 * 7 + 1) * 1000.0 * 135 / 1e6, 1e-12);
  EXPECT_LE(jp::bus_load(jp::Bus::kRobot, 1'000'000, legs), 0.40);
  // Fewer joints per board drop their frames.
  const jp::BusLayout one_joint{1, 1, false, 6};
  EXPECT_NEAR(jp::bus_load(jp::Bus::kRobot, 1'000'000, one_joint),
              (3 * 1000.0 / 6 + 100 + 50 + 10) * 135 / 1e6, 1e-12);
}

}  // namespace
