// hmpc-forearm-board: the forearm actuator board (firmware/app/forearm_board.hpp) on Linux over
// SocketCAN: can0 on a robot, vcan0 in the HIL. Two ways to pace it:
//   real time (default)  a 1 kHz CLOCK_MONOTONIC timerfd ticks the board, each tick after
//                        draining the socket; the MPC runs when due, against its wall-clock
//                        deadline. Expirations that find the loop still busy are counted as
//                        timer overruns and their ticks caught up at once, so the tick count,
//                        the board's only clock, keeps real time for its watchdogs.
//   --lockstep (HIL)     each valid Sync frame from the plant (sent after that millisecond's
//                        Sensor frame) is one tick and the MPC has no deadline: a run is
//                        deterministic, however fast the machine. With --emulate-target the
//                        board charges each solve the target's compute time instead.
// A tick's frames are sent as soon as it ends, before the MPC step, as a board whose control
// interrupt preempts the solver would. On SIGINT, SIGTERM or the end of --duration the board
// sends a last ActuatorCommand with the safe outputs and prints a summary of key=value pairs.
// The board lives in static storage; once the loop runs nothing is allocated (counted and
// reported as heap_allocations_in_loop).
#include <poll.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/signalfd.h>
#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>

#include "forearm_board.hpp"
#include "hmpc/platform/linux/bus_program.hpp"
#include "hmpc/platform/linux/heap_monitor.hpp"
#include "hmpc/platform/linux/socketcan.hpp"
#include "options.hpp"
#include "tick_log.hpp"

namespace {

using namespace hmpc::linux_board;
namespace proto = hmpc::forearm_protocol;
using hmpc::platform::CanFrame;
using hmpc::platform::CanResult;
using hmpc::platform::CanStatus;
using hmpc::platform::describe;
using hmpc::platform::monotonic_seconds;
using hmpc::platform::SocketCan;
using hmpc::platform::to_can_frame;
using hmpc::platform::to_protocol_frame;
namespace heap_monitor = hmpc::platform::heap_monitor;
using Board = hmpc::firmware::ForearmBoard<double>;

constexpr const char* kProgram = "hmpc-forearm-board";
constexpr long kTickNs = 1'000'000;
// Frames taken from the socket per wake-up: a flooded bus must not starve the tick.
constexpr int kMaxFramesPerDrain = 64;

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

enum class StopReason { kSignal, kDuration, kBusError, kSystemError };

// What ended the loop when it was not asked to end.
struct LoopFailure {
  CanResult receive;      // kBusError
  const char* call = "";  // kSystemError: the system call that failed, with its errno
  int error_number = 0;

  StopReason system_error(const char* failed_call) {
    call = failed_call;
    error_number = errno;
    return StopReason::kSystemError;
  }
};

struct LoopStats {
  std::uint64_t ticks = 0;
  std::uint64_t timer_overruns = 0;  // expirations of the 1 kHz timer found while still busy
  std::uint64_t transmit_failures = 0;
  std::uint64_t interface_down = 0;  // receives that found the interface down
  double max_busy_s = 0;             // longest wake-up: ticks, frames and the MPC step
  double max_wakeup_latency_s = 0;   // latest wake-up after its timer expiration
};

// The board with its bus: delivers received frames, ticks, sends what the board yields.
class BoardLoop {
 public:
  BoardLoop(Board& board, const Board::Config& config, SocketCan& can, TickLog& log)
      : board_(board), can_(can), node_(config.node), safe_{config.safe_v_p, config.safe_v_m},
        log_(log), safe_sender_(config.node) {}

  // Passes a received frame to the board. True when it was a Sync the board accepted: in
  // lock-step, the plant's cue for one tick.
  bool deliver(const CanFrame& can_frame) {
    proto::Frame frame;
    if (!to_protocol_frame(can_frame, frame)) return false;
    const std::uint32_t syncs_before = board_.counters().syncs;
    board_.on_frame(frame);
    return board_.counters().syncs != syncs_before;
  }

  // One 1 kHz tick, its log row and its frames; true when the MPC step is due.
  bool tick(double wall_time_s) {
    board_.tick();
    ++stats_.ticks;
    const auto& out = board_.outputs();
    log_.record({board_.ticks(), float(wall_time_s), board_.mode(), board_.faults(),
                 board_.strategy(), float(out.v_p), float(out.v_m), board_.heartbeat_age(),
                 board_.sensor_age()});
    proto::Frame frame;
    while (board_.pop_frame(frame)) transmit(frame);
    return board_.mpc_due();
  }

  // The last word to the actuators: valve vented, motor off. It continues the board's
  // ActuatorCommand counter so the plant accepts it. A full queue is retried for 100 ms.
  bool send_safe_outputs() {
    proto::Frame frame;
    if (safe_sender_.encode(proto::ActuatorCommand{float(safe_.v_p), float(safe_.v_m), 0}, frame) !=
        proto::EncodeResult::kOk) {
      return false;
    }
    for (int attempt = 0; attempt < 100; ++attempt) {
      const CanResult result = can_.send(to_can_frame(frame));
      if (result.ok()) return true;
      if (result.status != CanStatus::kWouldBlock &&
          result.status != CanStatus::kTransmitQueueFull) {
        break;
      }
      ::usleep(1000);
    }
    return false;
  }

  LoopStats& stats() { return stats_; }

 private:
  void transmit(const proto::Frame& frame) {
    if (!can_.send(to_can_frame(frame)).ok()) {
      ++stats_.transmit_failures;  // lost, counted; the next tick sends fresh values
      return;
    }
    proto::ActuatorCommand sent;
    if (proto::decode(frame, node_, sent) == proto::DecodeResult::kOk) {
      safe_sender_.next_counter[proto::index_of(proto::FrameType::kActuatorCommand)] =
          std::uint8_t((sent.counter + 1) % proto::kCounterModulo);
    }
  }

  Board& board_;
  SocketCan& can_;
  proto::NodeId node_;
  hmpc::firmware::Outputs<double> safe_;
  TickLog& log_;
  proto::Sender safe_sender_;
  LoopStats stats_;
};

// Delivers up to kMaxFramesPerDrain queued frames, telling on_frame whether each was an
// accepted Sync. An interface that is down (a bus that went away) delivers nothing and is
// counted: the board keeps its clock and its watchdogs, which put it in its safe state, and
// hears the bus again when it comes back. False on any other receive error (in `failure`).
template <class OnFrame>
bool drain(SocketCan& can, BoardLoop& loop, OnFrame&& on_frame, LoopFailure& failure) {
  for (int i = 0; i < kMaxFramesPerDrain; ++i) {
    CanFrame frame;
    const CanResult result = can.receive(frame, std::chrono::microseconds(0));
    if (result.status == CanStatus::kTimeout) return true;
    if (result.status == CanStatus::kInterfaceDown) {
      ++loop.stats().interface_down;
      return true;
    }
    if (!result.ok()) {
      failure.receive = result;
      return false;
    }
    on_frame(loop.deliver(frame));
  }
  return true;
}

StopReason run_lockstep(Board& board, BoardLoop& loop, SocketCan& can, int signal_fd,
                        double start_s, double duration_s, LoopFailure& failure) {
  pollfd fds[2] = {{can.native_handle(), POLLIN, 0}, {signal_fd, POLLIN, 0}};
  for (;;) {
    int timeout_ms = -1;
    if (duration_s > 0) {
      const double left = start_s + duration_s - monotonic_seconds();
      if (left <= 0) return StopReason::kDuration;
      timeout_ms = int(std::ceil(left * 1e3));
    }
    if (::poll(fds, 2, timeout_ms) < 0) {
      if (errno == EINTR) continue;
      return failure.system_error("poll");
    }
    if (fds[1].revents & POLLIN) return StopReason::kSignal;
    if (fds[0].revents == 0) continue;
    const bool ok = drain(
        can, loop,
        [&](bool sync_accepted) {
          if (sync_accepted && loop.tick(monotonic_seconds() - start_s)) board.run_mpc();
        },
        failure);
    if (!ok) return StopReason::kBusError;
  }
}

StopReason run_real_time(Board& board, BoardLoop& loop, SocketCan& can, int signal_fd,
                         double start_s, double duration_s, LoopFailure& failure) {
  const FileDescriptor timer(::timerfd_create(CLOCK_MONOTONIC, TFD_CLOEXEC));
  if (timer.get() < 0) return failure.system_error("timerfd_create");
  const itimerspec every_tick{{0, kTickNs}, {0, kTickNs}};
  if (::timerfd_settime(timer.get(), 0, &every_tick, nullptr) < 0) {
    return failure.system_error("timerfd_settime");
  }
  const double timer_start_s = monotonic_seconds();
  const std::uint64_t duration_ticks = std::uint64_t(std::llround(duration_s * 1e3));
  std::uint64_t expirations_total = 0;
  LoopStats& stats = loop.stats();
  pollfd fds[2] = {{timer.get(), POLLIN, 0}, {signal_fd, POLLIN, 0}};
  for (;;) {
    if (::poll(fds, 2, -1) < 0) {
      if (errno == EINTR) continue;
      return failure.system_error("poll");
    }
    if (fds[1].revents & POLLIN) return StopReason::kSignal;
    if ((fds[0].revents & POLLIN) == 0) continue;
    std::uint64_t expirations = 0;
    if (::read(timer.get(), &expirations, sizeof expirations) != sizeof expirations) continue;
    const double woke_s = monotonic_seconds();
    // The earliest of these expirations was due at this time.
    const double due_s = timer_start_s + 1e-3 * double(expirations_total + 1);
    // A late wake-up catches up its ticks, but never past --duration.
    const std::uint64_t ticks = duration_ticks > 0
                                    ? std::min(expirations, duration_ticks - expirations_total)
                                    : expirations;
    expirations_total += ticks;
    stats.timer_overruns += expirations - 1;
    if (woke_s - due_s > stats.max_wakeup_latency_s) stats.max_wakeup_latency_s = woke_s - due_s;
    bool mpc_due = false;
    for (std::uint64_t i = 0; i < ticks; ++i) {
      if (!drain(
              can, loop, [](bool) {}, failure))
        return StopReason::kBusError;
      mpc_due = loop.tick(woke_s - start_s) || mpc_due;
    }
    if (mpc_due) board.run_mpc();
    const double busy_s = monotonic_seconds() - woke_s;
    if (busy_s > stats.max_busy_s) stats.max_busy_s = busy_s;
    if (duration_ticks > 0 && expirations_total >= duration_ticks) return StopReason::kDuration;
  }
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  std::string error;
  const auto outcome = parse_options(argc, argv, options, error);
  if (outcome != hmpc::cli::ParseOutcome::kRun) {
    return hmpc::cli::exit_status(outcome, kProgram, error, print_usage);
  }

  // SIGINT and SIGTERM are read from a descriptor the loop polls, so they end it between
  // ticks, never inside one.
  const FileDescriptor signals(hmpc::platform::stop_signal_descriptor(error));
  if (signals.get() < 0) {
    std::fprintf(stderr, "%s: %s\n", kProgram, error.c_str());
    return 1;
  }
  // Only this node's frames: the board ignores the rest anyway.
  SocketCan can;
  if (!hmpc::platform::open_node_bus(can, options.interface, options.node, true, error)) {
    std::fprintf(stderr, "%s: %s\n", kProgram, error.c_str());
    return 1;
  }

  TickLog log;
  if (!options.log_path.empty() &&
      !log.open(options.log_path, std::size_t(kLogMinutes) * 60 * 1000, error)) {
    std::fprintf(stderr, "%s: %s\n", kProgram, error.c_str());
    return 1;
  }

  Board::Config config;
  config.node = options.node;
  if (options.emulate_cortex_m7) config.emulated_target = &hmpc::forearm::kCortexM7ComputeModel;
  if (options.w_v > 0) config.weights.w_v = options.w_v;
  config.solver_failure_from_tick = std::uint32_t(std::lround(options.fail_solver_at_s * 1e3));
  // Lock-step has no deadline: the simulator, not this machine, decides how long a solve takes.
  static Board board(config, options.lockstep ? nullptr : &monotonic_seconds);
  BoardLoop loop(board, config, can, log);

  if (!options.lockstep && ::mlockall(MCL_CURRENT | MCL_FUTURE) < 0) {
    std::fprintf(stderr, "%s: note: mlockall failed (%s): page faults may delay ticks\n", kProgram,
                 std::strerror(errno));
  }
  std::printf("%s: node %u on %s, %s%s: ready\n", kProgram, unsigned(options.node),
              options.interface.c_str(), options.lockstep ? "lock-step" : "real time, 1 kHz",
              options.emulate_cortex_m7 ? ", emulating the Cortex-M7's compute time" : "");
  std::fflush(stdout);

  LoopFailure failure;
  const double start_s = monotonic_seconds();
  heap_monitor::arm();
  const StopReason reason =
      options.lockstep
          ? run_lockstep(board, loop, can, signals.get(), start_s, options.duration_s, failure)
          : run_real_time(board, loop, can, signals.get(), start_s, options.duration_s, failure);
  heap_monitor::disarm();
  const double elapsed_s = monotonic_seconds() - start_s;

  const bool safe_sent = loop.send_safe_outputs();
  if (!safe_sent) {
    std::fprintf(stderr, "%s: could not send the final safe ActuatorCommand on %s\n", kProgram,
                 options.interface.c_str());
  }

  int status = 0;
  switch (reason) {
    case StopReason::kSignal: {
      signalfd_siginfo info{};
      const bool known = ::read(signals.get(), &info, sizeof info) == sizeof info;
      std::printf("%s: stopped by %s\n", kProgram,
                  known && info.ssi_signo == SIGINT ? "SIGINT" : "SIGTERM");
      break;
    }
    case StopReason::kDuration:
      std::printf("%s: stopped after --duration %g s\n", kProgram, options.duration_s);
      break;
    case StopReason::kBusError:
      std::fprintf(stderr, "%s: receiving on %s failed: %s\n", kProgram, options.interface.c_str(),
                   describe(failure.receive).c_str());
      status = 1;
      break;
    case StopReason::kSystemError:
      std::fprintf(stderr, "%s: control loop failed: %s: %s\n", kProgram, failure.call,
                   std::strerror(failure.error_number));
      status = 1;
      break;
  }

  const LoopStats& stats = loop.stats();
  const hmpc::firmware::BoardCounters& c = board.counters();
  std::printf(
      "%s: summary ticks=%llu seconds=%.3f ticks_per_s=%.1f mode=%s faults=0x%02x "
      "mpc_steps=%u solver_failures=%u mpc_overruns=%u fallbacks=%u watchdog_trips=%u "
      "sensor_timeouts=%u refused_commands=%u rejected_frames=%u dropped_frames=%u "
      "transmit_failures=%llu interface_down=%llu timer_overruns=%llu max_busy_ms=%.3f "
      "max_wakeup_latency_ms=%.3f "
      "heap_allocations_in_loop=%llu safe_outputs_sent=%d heartbeat_timeout_ticks=%d "
      "sensor_timeout_ticks=%d\n",
      kProgram, static_cast<unsigned long long>(stats.ticks), elapsed_s,
      elapsed_s > 0 ? double(stats.ticks) / elapsed_s : 0.0,
      value_name(proto::kBoardModeValues, std::uint32_t(board.mode())), unsigned(board.faults()),
      c.mpc_steps, c.solver_failures, c.overruns, c.fallbacks, c.watchdog_trips, c.sensor_timeouts,
      c.refused_commands, board.rejects().total(), board.dropped_frames(),
      static_cast<unsigned long long>(stats.transmit_failures),
      static_cast<unsigned long long>(stats.interface_down),
      static_cast<unsigned long long>(stats.timer_overruns), stats.max_busy_s * 1e3,
      stats.max_wakeup_latency_s * 1e3,
      static_cast<unsigned long long>(heap_monitor::allocations()), safe_sent ? 1 : 0,
      config.heartbeat_timeout_ticks, config.sensor_timeout_ticks);
  if (log.is_open()) {
    if (log.dropped_rows() > 0) {
      std::printf("%s: log kept the last %d minutes (%llu earlier ticks not written)\n", kProgram,
                  kLogMinutes, static_cast<unsigned long long>(log.dropped_rows()));
    }
    if (!log.write_csv(error)) {
      std::fprintf(stderr, "%s: %s\n", kProgram, error.c_str());
      status = 1;
    }
  }
  return status;
}
