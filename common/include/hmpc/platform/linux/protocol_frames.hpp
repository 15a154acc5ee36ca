// The forearm protocol on a SocketCAN interface: the one conversion between the protocol's
// frame (forearm_protocol::Frame, independent of any operating system) and the SocketCAN
// wrapper's (platform::CanFrame, which carries SocketCAN's flag bits in its id), and sending
// an encoded message. Used by the Linux board, the HIL plant node, the host controller and the
// tests that talk to them on vcan.
#pragma once

#include <algorithm>
#include <cstring>

#include "hmpc/platform/linux/socketcan.hpp"
#include "hmpc/protocol/forearm_protocol.hpp"

namespace hmpc::platform {

inline CanFrame to_can_frame(const forearm_protocol::Frame& frame) {
  CanFrame out{};
  out.id = frame.id & kCanStandardIdMask;
  out.dlc = std::min<std::uint8_t>(frame.dlc, 8);
  std::memcpy(out.data, frame.data.data(), sizeof out.data);
  return out;
}

// False for frames the protocol never uses (extended or remote): their low 11 bits could
// otherwise pass for one of its standard identifiers.
inline bool to_protocol_frame(const CanFrame& frame, forearm_protocol::Frame& out) {
  if ((frame.id & (kCanExtendedId | kCanRemoteRequest)) != 0) return false;
  out.id = frame.id & kCanStandardIdMask;
  out.dlc = frame.dlc;
  std::memcpy(out.data.data(), frame.data, out.data.size());
  return true;
}

// Only the frames of one node (all its frame types): the kernel filters the rest.
inline CanFilter node_filter(forearm_protocol::NodeId node) {
  return {forearm_protocol::frame_id(forearm_protocol::FrameType::kModeCommand, node),
          (kCanStandardIdMask & ~(forearm_protocol::kNodeIdStride - 1)) | kCanExtendedId |
              kCanRemoteRequest};
}

// Encodes `message` with the sender's next counter and sends it. An encoding failure (a value
// out of its signal's range) sends nothing and reports kInvalidArgument.
template <class Message>
CanResult send_message(SocketCan& can, forearm_protocol::Sender& sender, const Message& message) {
  forearm_protocol::Frame frame;
  if (sender.encode(message, frame) != forearm_protocol::EncodeResult::kOk) {
    return {CanStatus::kInvalidArgument, 0};
  }
  return can.send(to_can_frame(frame));
}

}  // namespace hmpc::platform
