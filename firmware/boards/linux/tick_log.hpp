// The --log CSV: one row per tick, kept in memory that is allocated and touched before the
// control loop (so recording neither allocates nor page-faults) and written out at exit. When
// the run is longer than the buffer, the oldest rows give way: the end of a run, where a fault
// would be, is what is kept.
#pragma once

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

namespace hmpc::linux_board {

// Rows and their CSV form are the application's (Support::Row, kCsvHeader, write_row).
template <class Support>
class TickLog {
 public:
  using Row = typename Support::Row;

  TickLog() = default;
  TickLog(const TickLog&) = delete;
  TickLog& operator=(const TickLog&) = delete;
  ~TickLog() {
    if (file_ != nullptr) std::fclose(file_);
  }

  // Creates the file now, so a bad path fails before the board starts.
  bool open(const std::string& path, std::size_t capacity, std::string& error) {
    file_ = std::fopen(path.c_str(), "w");
    if (file_ == nullptr) {
      error = "cannot create log file '" + path + "': " + std::strerror(errno);
      return false;
    }
    path_ = path;
    rows_.assign(capacity, Row{});
    return true;
  }

  bool is_open() const { return file_ != nullptr; }

  void record(const Row& row) {
    if (rows_.empty()) return;
    rows_[recorded_ % rows_.size()] = row;
    ++recorded_;
  }

  std::uint64_t dropped_rows() const {
    return recorded_ > rows_.size() ? recorded_ - rows_.size() : 0;
  }

  // Writes the kept rows, oldest first, and closes the file.
  bool write_csv(std::string& error) {
    if (file_ == nullptr) return true;
    std::fprintf(file_, "%s\n", Support::kCsvHeader);
    const std::uint64_t first = dropped_rows();
    for (std::uint64_t i = first; i < recorded_; ++i)
      Support::write_row(file_, rows_[i % rows_.size()]);
    const bool written = std::ferror(file_) == 0;
    const bool closed = std::fclose(file_) == 0;
    file_ = nullptr;
    if (!written || !closed) {
      error = "writing log file '" + path_ + "' failed";
      return false;
    }
    return true;
  }

 private:
  std::FILE* file_ = nullptr;
  std::string path_;
  std::vector<Row> rows_;
  std::uint64_t recorded_ = 0;
};

}  // namespace hmpc::linux_board
