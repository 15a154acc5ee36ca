// The board protocols on a SocketCAN interface: the one conversion between the codec's frame
// (protocol::Frame, independent of any operating system) and the SocketCAN wrapper's
// (platform::CanFrame, which carries SocketCAN's flag bits in its id), the kernel filters of
// one node, and sending an encoded message. Used by the Linux boards, the HIL plant nodes, the
// host controllers and the tests that talk to them on vcan.
#pragma once

#include <algorithm>
#include <cstring>

#include "hmpc/platform/linux/socketcan.hpp"
#include "hmpc/protocol/codec.hpp"

namespace hmpc::platform {

inline CanFrame to_can_frame(const protocol::Frame& frame) {
  CanFrame out{};
  out.id = frame.id & kCanStandardIdMask;
  out.dlc = std::min<std::uint8_t>(frame.dlc, 8);
  std::memcpy(out.data, frame.data.data(), sizeof out.data);
  return out;
}

// False for frames the protocol never uses (extended or remote): their low 11 bits could
// otherwise pass for one of its standard identifiers.
inline bool to_protocol_frame(const CanFrame& frame, protocol::Frame& out) {
  if ((frame.id & (kCanExtendedId | kCanRemoteRequest)) != 0) return false;
  out.id = frame.id & kCanStandardIdMask;
  out.dlc = frame.dlc;
  std::memcpy(out.data.data(), frame.data, out.data.size());
  return true;
}

// The frames one node of protocol P hears (protocol::accepted_ids: its block and the bus-wide
// frames) as kernel filters: the kernel drops the rest. Each range is an aligned power of two
// (the codec checks the layout), so one id/mask pair matches it exactly. Returns how many of
// `out` it filled.
inline constexpr int kMaxFilters = int(protocol::kMaxAcceptedRanges);
template <class P>
int node_filters(protocol::NodeId node, CanFilter (&out)[kMaxFilters]) {
  constexpr std::uint32_t kFlags = kCanExtendedId | kCanRemoteRequest;  // must be clear
  const protocol::AcceptedIds accepted = protocol::accepted_ids<P>(node);
  for (std::size_t i = 0; i < accepted.count; ++i) {
    const protocol::IdRange& r = accepted.ranges[i];
    out[i] = {r.first, (kCanStandardIdMask & ~(r.last - r.first)) | kFlags};
  }
  return int(accepted.count);
}

// Encodes `message` with the sender's next counter and sends it. An encoding failure (a value
// out of its signal's range) sends nothing and reports kInvalidArgument.
template <class Sender, class Message>
CanResult send_message(SocketCan& can, Sender& sender, const Message& message) {
  protocol::Frame frame;
  if (sender.encode(message, frame) != protocol::EncodeResult::kOk) {
    return {CanStatus::kInvalidArgument, 0};
  }
  return can.send(to_can_frame(frame));
}

}  // namespace hmpc::platform
