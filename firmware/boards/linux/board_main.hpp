// What a Linux board program does around its application, written once: stop signals, the
// buses (this node's frames; the HIL's I/O bus where it is another interface), the --log, memory
// locking, the ready line, the loop (board_loop.hpp), the final safe command and the stop report.
// The application's main parses its options, builds its board and prints its summary.
#pragma once

#include <signal.h>
#include <sys/mman.h>
#include <sys/signalfd.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>

#include "board_loop.hpp"
#include "board_options.hpp"
#include "hmpc/platform/linux/heap_monitor.hpp"

namespace hmpc::linux_board {

struct RunResult {
  int status = 1;  // the program's exit status so far
  double elapsed_s = 0;
  LoopStats stats;
  bool safe_sent = false;
  std::uint64_t heap_allocations_in_loop = 0;
};

// Runs `board` on the options' interface until a stop signal, --duration or a failure, then
// sends the safe command. `mode_text` describes the pacing for the ready line. The board's
// log is written after `summary` (the application's key=value line) is printed.
template <class Support, class Summary>
int run_board(const char* program, const BoardOptions& options, typename Support::Board& board,
              const typename Support::SafeMessage& safe, const char* mode_text, Summary&& summary) {
  namespace heap_monitor = hmpc::platform::heap_monitor;
  std::string error;
  // SIGINT and SIGTERM are read from a descriptor the loop polls, so they end it between
  // ticks, never inside one.
  const FileDescriptor signals(hmpc::platform::stop_signal_descriptor(error));
  if (signals.get() < 0) {
    std::fprintf(stderr, "%s: %s\n", program, error.c_str());
    return 1;
  }
  // Only this node's frames: the board ignores the rest anyway.
  using Description = typename Support::Description;
  SocketCan robot, io;
  const bool separate_io =
      !options.io_interface.empty() && options.io_interface != options.interface;
  if (!hmpc::platform::open_node_bus<Description>(robot, options.interface, options.node, true,
                                                  error) ||
      (separate_io && !hmpc::platform::open_node_bus<Description>(io, options.io_interface,
                                                                  options.node, true, error))) {
    std::fprintf(stderr, "%s: %s\n", program, error.c_str());
    return 1;
  }
  TickLog<Support> log;
  if (!options.log_path.empty() &&
      !log.open(options.log_path, std::size_t(kLogMinutes) * 60 * 1000, error)) {
    std::fprintf(stderr, "%s: %s\n", program, error.c_str());
    return 1;
  }
  BoardLoop<Support> loop(board, options.node, safe, robot, separate_io ? &io : nullptr, log);
  if (!options.lockstep && ::mlockall(MCL_CURRENT | MCL_FUTURE) < 0) {
    std::fprintf(stderr, "%s: note: mlockall failed (%s): page faults may delay ticks\n", program,
                 std::strerror(errno));
  }
  std::printf("%s: node %u on %s%s%s, %s%s: ready\n", program, unsigned(options.node),
              options.interface.c_str(), separate_io ? " (I/O bus " : "",
              separate_io ? (options.io_interface + ")").c_str() : "",
              options.lockstep ? "lock-step" : "real time, 1 kHz", mode_text);
  std::fflush(stdout);

  LoopFailure failure;
  const double start_s = monotonic_seconds();
  heap_monitor::arm();
  const StopReason reason =
      options.lockstep
          ? run_lockstep(board, loop, signals.get(), start_s, options.duration_s, failure)
          : run_real_time(board, loop, signals.get(), start_s, options.duration_s, failure);
  heap_monitor::disarm();

  RunResult result;
  result.status = 0;
  result.elapsed_s = monotonic_seconds() - start_s;
  result.safe_sent = loop.send_safe_outputs();
  result.heap_allocations_in_loop = heap_monitor::allocations();
  if (!result.safe_sent) {
    std::fprintf(stderr, "%s: could not send the final safe command on %s\n", program,
                 options.interface.c_str());
  }
  switch (reason) {
    case StopReason::kSignal: {
      signalfd_siginfo info{};
      const bool known = ::read(signals.get(), &info, sizeof info) == sizeof info;
      std::printf("%s: stopped by %s\n", program,
                  known && info.ssi_signo == SIGINT ? "SIGINT" : "SIGTERM");
      break;
    }
    case StopReason::kDuration:
      std::printf("%s: stopped after --duration %g s\n", program, options.duration_s);
      break;
    case StopReason::kBusError:
      std::fprintf(stderr, "%s: receiving on %s failed: %s\n", program, options.interface.c_str(),
                   hmpc::platform::describe(failure.receive).c_str());
      result.status = 1;
      break;
    case StopReason::kSystemError:
      std::fprintf(stderr, "%s: control loop failed: %s: %s\n", program, failure.call,
                   std::strerror(failure.error_number));
      result.status = 1;
      break;
  }
  result.stats = loop.stats();
  summary(result);
  if (log.is_open()) {
    if (log.dropped_rows() > 0) {
      std::printf("%s: log kept the last %d minutes (%llu earlier ticks not written)\n", program,
                  kLogMinutes, static_cast<unsigned long long>(log.dropped_rows()));
    }
    if (!log.write_csv(error)) {
      std::fprintf(stderr, "%s: %s\n", program, error.c_str());
      result.status = 1;
    }
  }
  return result.status;
}

}  // namespace hmpc::linux_board
