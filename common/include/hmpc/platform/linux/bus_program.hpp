// Start-up and shutdown pieces shared by the Linux programs on the boards' buses (the boards,
// the HIL plant nodes, the host controllers): the clock, stop signals as a descriptor the loops
// poll, one node's frames on a SocketCAN interface, CSV logs, and error text.
#pragma once

#include <signal.h>
#include <sys/signalfd.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>

#include "hmpc/platform/linux/protocol_frames.hpp"
#include "hmpc/platform/linux/socketcan.hpp"

namespace hmpc::platform {

// Owns a file descriptor (a timer, a signal descriptor): closed when it goes.
class FileDescriptor {
 public:
  explicit FileDescriptor(int fd) : fd_(fd) {}
  ~FileDescriptor() {
    if (fd_ >= 0) ::close(fd_);
  }
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
  int get() const { return fd_; }

 private:
  int fd_;
};

inline double monotonic_seconds() {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return double(now.tv_sec) + 1e-9 * double(now.tv_nsec);
}

inline std::string describe(const CanResult& result) {
  std::string text = to_string(result.status);
  if (result.error_number != 0)
    text += std::string(" (") + std::strerror(result.error_number) + ")";
  return text;
}

// Blocks SIGINT and SIGTERM and returns a descriptor they can be read from, so a loop ends
// between its steps, never inside one; -1 with `error` set on failure.
inline int stop_signal_descriptor(std::string& error) {
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  if (::sigprocmask(SIG_BLOCK, &stop_signals, nullptr) < 0) {
    error = std::string("cannot block SIGINT/SIGTERM: ") + std::strerror(errno);
    return -1;
  }
  const int fd = ::signalfd(-1, &stop_signals, SFD_CLOEXEC);
  if (fd < 0) error = std::string("signalfd: ") + std::strerror(errno);
  return fd;
}

// Opens `interface` for the frames of one node of protocol P only, and P's bus-wide ones (a
// busy bus then costs the kernel's filter, not the program's loop); `error` names the interface
// and the reason on failure.
template <class P>
bool open_node_bus(SocketCan& can, const std::string& interface, protocol::NodeId node,
                   bool non_blocking, std::string& error) {
  CanResult opened = can.open(interface.c_str());
  CanFilter filters[kMaxFilters];
  const int count = node_filters<P>(node, filters);
  if (opened.ok()) opened = can.set_filters(filters, std::size_t(count));
  if (opened.ok() && non_blocking) opened = can.set_non_blocking(true);
  if (!opened.ok()) error = "cannot open CAN interface '" + interface + "': " + describe(opened);
  return opened.ok();
}

// A CSV log with its header line; nullptr with `error` set when it cannot be written.
inline std::FILE* open_csv_log(const std::string& path, const char* header, std::string& error) {
  std::FILE* log = std::fopen(path.c_str(), "w");
  if (!log) {
    error = "cannot write the log '" + path + "': " + std::strerror(errno);
    return nullptr;
  }
  // Line-buffered: every row written before the program dies, even by SIGKILL, is in the file.
  std::setvbuf(log, nullptr, _IOLBF, 0);
  std::fprintf(log, "%s\n", header);
  return log;
}

}  // namespace hmpc::platform
