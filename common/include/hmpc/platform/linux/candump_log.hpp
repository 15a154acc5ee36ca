// CAN traffic logs in candump's "-l" format, one frame per line:
//   (1436509052.249713) vcan0 2A1#0011223344556677
// the time in seconds with six decimals, the interface, the identifier in hex (three digits for a
// standard one) and the data bytes in hex. can-utils' canplayer replays such a file onto a bus;
// read_candump_line() parses one back. Lines are flushed as written, so a log is complete up to
// a crash.
#pragma once

#include <cctype>
#include <cerrno>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include "hmpc/platform/linux/socketcan.hpp"

namespace hmpc::platform {

// A frame as candump -l writes it after the interface, "ID#DATA": the identifier in hex (three
// digits for a standard one), the data bytes in hex. `out` holds the longest.
inline void format_candump_frame(const CanFrame& frame, char (&out)[32]) {
  int n = std::snprintf(out, sizeof out, "%03" PRIX32 "#", frame.id);
  for (std::uint8_t i = 0; i < frame.dlc && i < 8; ++i) {
    n += std::snprintf(out + n, sizeof out - std::size_t(n), "%02X", frame.data[i]);
  }
}

class CandumpLog {
 public:
  CandumpLog() = default;
  ~CandumpLog() { close(); }
  CandumpLog(const CandumpLog&) = delete;
  CandumpLog& operator=(const CandumpLog&) = delete;

  // False with `error` set when the file cannot be written.
  bool open(const std::string& path, std::string& error) {
    file_ = std::fopen(path.c_str(), "w");
    if (!file_) {
      error = "cannot write the CAN log '" + path + "': " + std::strerror(errno);
      return false;
    }
    std::setvbuf(file_, nullptr, _IOLBF, 0);
    return true;
  }
  bool is_open() const { return file_ != nullptr; }
  // False when the file could not be closed (written) completely.
  bool close() {
    if (!file_) return true;
    const bool ok = std::fclose(file_) == 0;
    file_ = nullptr;
    return ok;
  }

  void write(double time_s, const char* interface, const CanFrame& frame) {
    if (!file_) return;
    const double whole = std::floor(time_s);
    char text[32];
    format_candump_frame(frame, text);
    std::fprintf(file_, "(%010.0f.%06ld) %s %s\n", whole,
                 std::lround((time_s - whole) * 1e6) % 1000000, interface, text);
  }

 private:
  std::FILE* file_ = nullptr;
};

// One line of a candump -l log; false (and nothing changed) for a line that is not one.
inline bool read_candump_line(const std::string& line, double& time_s, std::string& interface,
                              CanFrame& frame) {
  double t = 0;
  char name[32] = {};
  char payload[64] = {};
  if (std::sscanf(line.c_str(), "(%lf) %31s %63s", &t, name, payload) != 3) return false;
  const char* hash = std::strchr(payload, '#');
  if (!hash || hash == payload || hash - payload > 3) return false;
  CanFrame f{};
  std::uint32_t id = 0;
  for (const char* c = payload; c < hash; ++c) {
    if (!std::isxdigit(static_cast<unsigned char>(*c))) return false;
    id = id * 16 + std::uint32_t(std::isdigit(static_cast<unsigned char>(*c))
                                     ? *c - '0'
                                     : std::toupper(static_cast<unsigned char>(*c)) - 'A' + 10);
  }
  const char* data = hash + 1;
  const std::size_t digits = std::strlen(data);
  if (digits % 2 != 0 || digits > 16) return false;
  for (std::size_t i = 0; i < digits; ++i) {
    if (!std::isxdigit(static_cast<unsigned char>(data[i]))) return false;
  }
  f.id = id;
  f.dlc = std::uint8_t(digits / 2);
  for (std::size_t i = 0; i < f.dlc; ++i) {
    unsigned byte = 0;
    std::sscanf(data + 2 * i, "%2x", &byte);
    f.data[i] = std::uint8_t(byte);
  }
  time_s = t;
  interface = name;
  frame = f;
  return true;
}

}  // namespace hmpc::platform
