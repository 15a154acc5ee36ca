// The one conversion between the protocol's frame (forearm_protocol::Frame, independent of any
// operating system) and the SocketCAN wrapper's (platform::CanFrame, which carries SocketCAN's
// flag bits in its id). Used by the Linux board and by the tests that talk to it on vcan.
#pragma once

#include <algorithm>
#include <cstring>

#include "hmpc/platform/linux/socketcan.hpp"
#include "hmpc/protocol/forearm_protocol.hpp"

namespace hmpc::linux_board {

inline platform::CanFrame to_can_frame(const forearm_protocol::Frame& frame) {
  platform::CanFrame out{};
  out.id = frame.id & platform::kCanStandardIdMask;
  out.dlc = std::min<std::uint8_t>(frame.dlc, 8);
  std::memcpy(out.data, frame.data.data(), sizeof out.data);
  return out;
}

// False for frames the protocol never uses (extended or remote): their low 11 bits could
// otherwise pass for one of its standard identifiers.
inline bool to_protocol_frame(const platform::CanFrame& frame, forearm_protocol::Frame& out) {
  if ((frame.id & (platform::kCanExtendedId | platform::kCanRemoteRequest)) != 0) return false;
  out.id = frame.id & platform::kCanStandardIdMask;
  out.dlc = frame.dlc;
  std::memcpy(out.data.data(), frame.data, out.data.size());
  return true;
}

}  // namespace hmpc::linux_board
