// The Linux/SocketCAN board runtime around any board application (firmware/app): can0 on a
// robot, vcan0 in the HIL. Two ways to pace it:
//   real time (default)  a 1 kHz CLOCK_MONOTONIC timerfd ticks the board, each tick after
//                        draining the socket; background work (the forearm's MPC) runs when
//                        due. Expirations that find the loop still busy are counted as timer
//                        overruns and their ticks caught up at once, so the tick count, the
//                        board's only clock, keeps real time for its watchdogs.
//   lock-step (HIL)      each valid Sync frame from the plant (sent after that millisecond's
//                        sensor frames) is one tick: a run is deterministic, however fast the
//                        machine.
// A tick's frames are sent as soon as it ends, before background work, as a board whose
// control interrupt preempts it would. The application's Support struct (in its main) names
// the board, its log row, its background work and its final safe command:
//   using Board, Description, SafeMessage, Row;  static constexpr const char* kCsvHeader;
//   static Row log_row(const Board&, float wall_time_s);  static void write_row(FILE*, const Row&);
//   static bool work_due(const Board&);  static void run_work(Board&);
//   static void on_late_ticks(Board&);  // real time: this wake-up catches up missed ticks
#pragma once

#include <poll.h>
#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>

#include "hmpc/platform/linux/bus_program.hpp"
#include "hmpc/platform/linux/socketcan.hpp"
#include "hmpc/protocol/codec.hpp"
#include "tick_log.hpp"

namespace hmpc::linux_board {

using hmpc::platform::CanFrame;
using hmpc::platform::CanResult;
using hmpc::platform::CanStatus;
using hmpc::platform::monotonic_seconds;
using hmpc::platform::SocketCan;
using hmpc::platform::to_can_frame;
using hmpc::platform::to_protocol_frame;

inline constexpr long kTickNs = 1'000'000;
// Frames taken from the socket per wake-up: a flooded bus must not starve the tick.
inline constexpr int kMaxFramesPerDrain = 64;

using hmpc::platform::FileDescriptor;

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
  double max_busy_s = 0;             // longest wake-up: ticks, frames and background work
  double max_wakeup_latency_s = 0;   // latest wake-up after its timer expiration
};

// The board with its bus: delivers received frames, ticks, sends what the board yields.
template <class Support>
class BoardLoop {
 public:
  using Board = typename Support::Board;
  using Description = typename Support::Description;
  using SafeMessage = typename Support::SafeMessage;

  // `io`: the HIL's I/O bus, where the frames to and from the plant go; nullptr when they
  // share the robot bus (the forearm's HIL) or there is no plant (a robot).
  BoardLoop(Board& board, protocol::NodeId node, const SafeMessage& safe, SocketCan& robot,
            SocketCan* io, TickLog<Support>& log)
      : board_(board), robot_(robot), io_(io), node_(node), safe_(safe), log_(log),
        safe_sender_(node) {}

  // The sockets to listen on: the robot bus, and the I/O bus if it is another.
  int bus_count() const { return io_ ? 2 : 1; }
  SocketCan& bus(int i) { return i == 0 ? robot_ : *io_; }

  // Passes a received frame to the board. True when it was a Sync the board accepted: in
  // lock-step, the plant's cue for one tick.
  bool deliver(const CanFrame& can_frame) {
    protocol::Frame frame;
    if (!to_protocol_frame(can_frame, frame)) return false;
    const std::uint32_t syncs_before = board_.syncs();
    board_.on_frame(frame);
    return board_.syncs() != syncs_before;
  }

  // One 1 kHz tick, its log row and its frames; true when the application's background work
  // (the forearm's MPC step) is due.
  bool tick(double wall_time_s) {
    board_.tick();
    ++stats_.ticks;
    log_.record(Support::log_row(board_, float(wall_time_s)));
    protocol::Frame frame;
    while (board_.pop_frame(frame)) transmit(frame);
    return Support::work_due(board_);
  }

  // The last word to the actuators: the application's safe outputs. It continues the board's
  // counter of that frame so the actuators accept it. A full queue is retried for 100 ms.
  bool send_safe_outputs() {
    protocol::Frame frame;
    if (safe_sender_.encode(safe_, frame) != protocol::EncodeResult::kOk) return false;
    for (int attempt = 0; attempt < 100; ++attempt) {
      const CanResult result = bus_for(frame).send(to_can_frame(frame));
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
  // Frames to or from the plant go on the I/O bus when there is one.
  SocketCan& bus_for(const protocol::Frame& frame) {
    typename Description::FrameType type{};
    protocol::NodeId node = 0;
    if (io_ == nullptr || !protocol::identify(frame.id, type, node)) return robot_;
    const auto& spec = protocol::frame_spec(type);
    const bool plant =
        spec.sender == protocol::Endpoint::kPlant || spec.receiver == protocol::Endpoint::kPlant;
    return plant ? *io_ : robot_;
  }

  void transmit(const protocol::Frame& frame) {
    if (!bus_for(frame).send(to_can_frame(frame)).ok()) {
      ++stats_.transmit_failures;  // lost, counted; the next tick sends fresh values
      return;
    }
    SafeMessage sent;
    if (protocol::decode(frame, node_, sent) == protocol::DecodeResult::kOk) {
      safe_sender_.next_counter[protocol::index_of(SafeMessage::kType)] =
          std::uint8_t((sent.counter + 1) % protocol::kCounterModulo);
    }
  }

  Board& board_;
  SocketCan& robot_;
  SocketCan* io_;
  protocol::NodeId node_;
  SafeMessage safe_;
  TickLog<Support>& log_;
  protocol::Sender<Description> safe_sender_;
  LoopStats stats_;
};

// Delivers up to kMaxFramesPerDrain queued frames, telling on_frame whether each was an
// accepted Sync. An interface that is down (a bus that went away) delivers nothing and is
// counted: the board keeps its clock and its watchdogs, which put it in its safe state, and
// hears the bus again when it comes back. False on any other receive error (in `failure`).
template <class Loop, class OnFrame>
bool drain(SocketCan& can, Loop& loop, OnFrame&& on_frame, LoopFailure& failure) {
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

// Lock-step: each valid Sync is one tick; the application's work runs after its tick.
template <class Support>
StopReason run_lockstep(typename Support::Board& board, BoardLoop<Support>& loop, int signal_fd,
                        double start_s, double duration_s, LoopFailure& failure) {
  const int buses = loop.bus_count();
  pollfd fds[3] = {{signal_fd, POLLIN, 0}, {loop.bus(0).native_handle(), POLLIN, 0}, {}};
  if (buses == 2) fds[2] = {loop.bus(1).native_handle(), POLLIN, 0};
  for (;;) {
    int timeout_ms = -1;
    if (duration_s > 0) {
      const double left = start_s + duration_s - monotonic_seconds();
      if (left <= 0) return StopReason::kDuration;
      timeout_ms = int(std::ceil(left * 1e3));
    }
    if (::poll(fds, nfds_t(1) + nfds_t(buses), timeout_ms) < 0) {
      if (errno == EINTR) continue;
      return failure.system_error("poll");
    }
    if (fds[0].revents & POLLIN) return StopReason::kSignal;
    for (int i = 0; i < buses; ++i) {
      if (fds[1 + i].revents == 0) continue;
      const bool ok = drain(
          loop.bus(i), loop,
          [&](bool sync_accepted) {
            if (sync_accepted && loop.tick(monotonic_seconds() - start_s)) {
              Support::run_work(board);
            }
          },
          failure);
      if (!ok) return StopReason::kBusError;
    }
  }
}

// Real time: a 1 kHz CLOCK_MONOTONIC timer ticks the board (see the top of this file).
template <class Support>
StopReason run_real_time(typename Support::Board& board, BoardLoop<Support>& loop, int signal_fd,
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
    if (expirations > 1) Support::on_late_ticks(board);
    if (woke_s - due_s > stats.max_wakeup_latency_s) stats.max_wakeup_latency_s = woke_s - due_s;
    bool work_due = false;
    for (std::uint64_t i = 0; i < ticks; ++i) {
      for (int b = 0; b < loop.bus_count(); ++b) {
        if (!drain(
                loop.bus(b), loop, [](bool) {}, failure))
          return StopReason::kBusError;
      }
      work_due = loop.tick(woke_s - start_s) || work_due;
    }
    if (work_due) Support::run_work(board);
    const double busy_s = monotonic_seconds() - woke_s;
    if (busy_s > stats.max_busy_s) stats.max_busy_s = busy_s;
    if (duration_ticks > 0 && expirations_total >= duration_ticks) return StopReason::kDuration;
  }
}

}  // namespace hmpc::linux_board
