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

// The frames of one node of protocol P (all its frame types) and P's bus-wide frames, as kernel
// filters: the kernel drops the rest. Returns how many of `out` it filled (at most kMaxFilters).
inline constexpr int kMaxFilters = 8;
template <class P>
int node_filters(protocol::NodeId node, CanFilter (&out)[kMaxFilters]) {
  constexpr std::uint32_t kFlags = kCanExtendedId | kCanRemoteRequest;  // must be clear
  int count = 0;
  out[count++] = {P::kIds.base + P::kIds.node_stride * node,
                  (kCanStandardIdMask & ~(P::kIds.node_stride - 1)) | kFlags};
  for (const auto& spec : P::kFrames) {
    if (spec.bus_wide && count < kMaxFilters) {
      out[count++] = {spec.id_offset, kCanStandardIdMask | kFlags};
    }
  }
  return count;
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
