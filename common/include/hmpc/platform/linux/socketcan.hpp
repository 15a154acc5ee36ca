// A raw SocketCAN socket (PF_CAN, SOCK_RAW, CAN_RAW) bound to one interface by name: a real
// controller (can0) or the virtual bus (vcan0) alike. RAII, move-only, no exceptions: every
// operation returns a CanResult, a status plus the errno behind it. Nothing allocates and
// send/receive make one or two system calls with the kernel frame on the stack, so both may
// sit in a real-time loop. Linux only.
#pragma once

#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <ctime>

namespace hmpc::platform {

// Flag bits in CanFrame::id, at the positions SocketCAN uses (so frames convert by copying).
inline constexpr std::uint32_t kCanExtendedId = CAN_EFF_FLAG;  // 29-bit identifier
inline constexpr std::uint32_t kCanRemoteRequest = CAN_RTR_FLAG;
inline constexpr std::uint32_t kCanStandardIdMask = CAN_SFF_MASK;
inline constexpr std::uint32_t kCanExtendedIdMask = CAN_EFF_MASK;

// A classic CAN frame: an 11-bit identifier, or a 29-bit one with kCanExtendedId set.
struct CanFrame {
  std::uint32_t id;
  std::uint8_t dlc;  // payload length in bytes, 0..8
  std::uint8_t data[8];
};

// A frame passes when (frame.id & mask) == (id & mask), flag bits included.
struct CanFilter {
  std::uint32_t id;
  std::uint32_t mask;

  // Exactly this identifier: standard and extended ids never alias, remote requests are out.
  static constexpr CanFilter exact(std::uint32_t id) {
    const std::uint32_t id_bits =
        (id & kCanExtendedId) != 0 ? kCanExtendedIdMask : kCanStandardIdMask;
    return {id, id_bits | kCanExtendedId | kCanRemoteRequest};
  }
};

enum class CanStatus {
  kOk,
  kTimeout,            // receive: nothing arrived in time (not an error)
  kWouldBlock,         // send on a non-blocking socket whose queue is full
  kTransmitQueueFull,  // the interface's transmit queue is full (ENOBUFS): retry later
  kNoCanSupport,       // the kernel has no SocketCAN (modules can, can-raw not loaded)
  kNoSuchInterface,    // no network interface by that name (or it went away)
  kNotCanInterface,    // the interface exists but is not a CAN interface
  kInterfaceDown,      // the interface is administratively down
  kInvalidArgument,    // bad name, identifier, length or filter count; nothing was done
  kNotOpen,            // the socket is not open
  kSystemError,        // anything else: see CanResult::error_number
};

constexpr const char* to_string(CanStatus status) {
  switch (status) {
    case CanStatus::kOk: return "ok";
    case CanStatus::kTimeout: return "timed out";
    case CanStatus::kWouldBlock: return "would block";
    case CanStatus::kTransmitQueueFull: return "transmit queue full";
    case CanStatus::kNoCanSupport: return "no SocketCAN in this kernel";
    case CanStatus::kNoSuchInterface: return "no such interface";
    case CanStatus::kNotCanInterface: return "not a CAN interface";
    case CanStatus::kInterfaceDown: return "interface down";
    case CanStatus::kInvalidArgument: return "invalid argument";
    case CanStatus::kNotOpen: return "socket not open";
    case CanStatus::kSystemError: return "system error";
  }
  return "unknown status";
}

struct CanResult {
  CanStatus status = CanStatus::kOk;
  int error_number = 0;  // the errno behind the status, 0 when none was involved

  constexpr bool ok() const { return status == CanStatus::kOk; }
};

class SocketCan {
 public:
  // Negative: receive waits until a frame arrives.
  static constexpr std::chrono::microseconds kWaitForever{-1};

  SocketCan() = default;
  ~SocketCan() { close(); }
  SocketCan(const SocketCan&) = delete;
  SocketCan& operator=(const SocketCan&) = delete;
  SocketCan(SocketCan&& other) noexcept : fd_(other.fd_) { other.fd_ = -1; }
  SocketCan& operator=(SocketCan&& other) noexcept {
    if (this != &other) {
      close();
      fd_ = other.fd_;
      other.fd_ = -1;
    }
    return *this;
  }

  // Opens a socket bound to `interface_name` (closing any socket this object held). It
  // receives every frame on the bus except its own until set_filters says otherwise.
  CanResult open(const char* interface_name) {
    close();
    const std::size_t length = interface_name == nullptr ? 0 : ::strnlen(interface_name, IFNAMSIZ);
    if (length == 0 || length >= IFNAMSIZ) return {CanStatus::kInvalidArgument, 0};

    const int fd = ::socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC, CAN_RAW);
    if (fd < 0) {
      const int error = errno;
      const bool no_can = error == EAFNOSUPPORT || error == EPROTONOSUPPORT;
      return {no_can ? CanStatus::kNoCanSupport : CanStatus::kSystemError, error};
    }
    ifreq request{};
    std::memcpy(request.ifr_name, interface_name, length);
    if (::ioctl(fd, SIOCGIFINDEX, &request) < 0) {
      const int error = errno;
      ::close(fd);
      return {error == ENODEV ? CanStatus::kNoSuchInterface : CanStatus::kSystemError, error};
    }
    sockaddr_can address{};
    address.can_family = AF_CAN;
    address.can_ifindex = request.ifr_ifindex;
    if (::bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) < 0) {
      const int error = errno;
      ::close(fd);
      // The index lookup succeeded, so ENODEV here means the interface is not CAN.
      return {error == ENODEV ? CanStatus::kNotCanInterface : CanStatus::kSystemError, error};
    }
    fd_ = fd;
    return {};
  }

  void close() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }

  bool is_open() const { return fd_ >= 0; }

  // For poll/epoll alongside timers; the socket stays owned by this object.
  int native_handle() const { return fd_; }

  // Non-blocking: send returns kWouldBlock instead of waiting for room. receive always waits
  // at most its timeout, either way.
  CanResult set_non_blocking(bool non_blocking) {
    if (fd_ < 0) return {CanStatus::kNotOpen, 0};
    const int flags = ::fcntl(fd_, F_GETFL);
    if (flags < 0) return from_errno(errno);
    const int wanted = non_blocking ? (flags | O_NONBLOCK) : (flags & ~O_NONBLOCK);
    if (wanted != flags && ::fcntl(fd_, F_SETFL, wanted) < 0) return from_errno(errno);
    return {};
  }

  // Only frames matching at least one filter are received from now on; none with count 0.
  CanResult set_filters(const CanFilter* filters, std::size_t count) {
    if (fd_ < 0) return {CanStatus::kNotOpen, 0};
    if (count > CAN_RAW_FILTER_MAX || (count > 0 && filters == nullptr)) {
      return {CanStatus::kInvalidArgument, 0};
    }
    // The kernel reads CanFilter as its own can_filter: same two 32-bit fields, same order.
    static_assert(sizeof(CanFilter) == sizeof(can_filter));
    static_assert(offsetof(CanFilter, mask) == offsetof(can_filter, can_mask));
    const socklen_t size = static_cast<socklen_t>(count * sizeof(can_filter));
    if (::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_FILTER, count > 0 ? filters : nullptr, size) < 0) {
      return from_errno(errno);
    }
    return {};
  }

  // Back to receiving every frame.
  CanResult accept_all() {
    const CanFilter everything{0, 0};
    return set_filters(&everything, 1);
  }

  CanResult send(const CanFrame& frame) {
    if (fd_ < 0) return {CanStatus::kNotOpen, 0};
    if (!is_valid(frame)) return {CanStatus::kInvalidArgument, 0};
    can_frame raw{};
    raw.can_id = frame.id;
    raw.can_dlc = frame.dlc;
    std::memcpy(raw.data, frame.data, frame.dlc);
    for (;;) {
      const ssize_t written = ::send(fd_, &raw, sizeof raw, 0);
      if (written == static_cast<ssize_t>(sizeof raw)) return {};
      if (written >= 0) return {CanStatus::kSystemError, EIO};  // a raw CAN write is all or nothing
      if (errno != EINTR) return from_errno(errno);
    }
  }

  // Waits up to `timeout` for a frame (0: only take one already queued). kTimeout when none
  // came. Bytes past frame.dlc are zeroed.
  CanResult receive(CanFrame& frame, std::chrono::microseconds timeout = kWaitForever) {
    if (fd_ < 0) return {CanStatus::kNotOpen, 0};
    using Clock = std::chrono::steady_clock;
    const bool forever = timeout.count() < 0;
    const Clock::time_point deadline =
        Clock::now() +
        (forever ? Clock::duration::zero() : std::chrono::duration_cast<Clock::duration>(timeout));
    for (;;) {
      // A queued frame costs one system call: try before polling.
      can_frame raw;
      const ssize_t received = ::recv(fd_, &raw, sizeof raw, MSG_DONTWAIT);
      if (received == static_cast<ssize_t>(sizeof raw)) {
        frame.id = raw.can_id;
        frame.dlc = raw.can_dlc <= 8 ? raw.can_dlc : 8;
        std::memset(frame.data, 0, sizeof frame.data);
        std::memcpy(frame.data, raw.data, frame.dlc);
        return {};
      }
      if (received >= 0) return {CanStatus::kSystemError, EIO};  // CAN FD frames are not enabled
      if (errno == EINTR) continue;
      if (errno != EAGAIN && errno != EWOULDBLOCK) return from_errno(errno);

      timespec wait{};
      if (!forever) {
        const auto left =
            std::chrono::duration_cast<std::chrono::nanoseconds>(deadline - Clock::now());
        if (left.count() <= 0) return {CanStatus::kTimeout, 0};
        wait.tv_sec = static_cast<std::time_t>(left.count() / 1'000'000'000);
        wait.tv_nsec = static_cast<long>(left.count() % 1'000'000'000);
      }
      pollfd readable{fd_, POLLIN, 0};
      // Either way the loop decides: a frame is read, or the deadline is found to have passed.
      if (::ppoll(&readable, 1, forever ? nullptr : &wait, nullptr) < 0 && errno != EINTR) {
        return from_errno(errno);
      }
    }
  }

  static constexpr bool is_valid(const CanFrame& frame) {
    if (frame.dlc > 8 || (frame.id & CAN_ERR_FLAG) != 0) return false;
    const std::uint32_t identifier = frame.id & ~(kCanExtendedId | kCanRemoteRequest);
    const bool extended = (frame.id & kCanExtendedId) != 0;
    return identifier <= (extended ? kCanExtendedIdMask : kCanStandardIdMask);
  }

 private:
  static CanResult from_errno(int error) {
    switch (error) {
      case EAGAIN: return {CanStatus::kWouldBlock, error};
      case ENOBUFS: return {CanStatus::kTransmitQueueFull, error};
      case ENETDOWN: return {CanStatus::kInterfaceDown, error};
      case ENODEV:
      case ENXIO: return {CanStatus::kNoSuchInterface, error};
      default: return {CanStatus::kSystemError, error};
    }
  }

  int fd_ = -1;
};

}  // namespace hmpc::platform
