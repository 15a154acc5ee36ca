// hmpc-humanoid-host: the humanoid's host controller and CAN master (hmpc/host/humanoid_host.hpp)
// on the robot bus: it brings up the two leg boards and the torso IMU, has the boards zero their
// encoders and hold the posture under their PID, estimates the robot's state from the IMU's and
// the boards' frames, and after --hold-seconds runs the Coarse-Fast MPC in the real robot's
// setting (Sec. 2.7.3), streaming its torques to the boards. Paced by a 1 kHz timer, or in HIL
// lock-step by the plant's Sync frames on the I/O bus (the host's clock; nothing else is read
// there). Both buses are logged in candump -l format; at the end a summary of key=value pairs.
// With --dds-domain it speaks DDS the ROS 2 way (hmpc/dds/humanoid_dds.hpp).
#include <poll.h>
#include <signal.h>
#include <sys/timerfd.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "hmpc/cli/arguments.hpp"
#include "hmpc/dds/humanoid_dds.hpp"
#include "hmpc/host/humanoid_host.hpp"
#include "hmpc/host/humanoid_replay.hpp"
#include "hmpc/humanoid/motion.hpp"
#include "hmpc/platform/linux/bus_program.hpp"
#include "hmpc/platform/linux/candump_log.hpp"
#include "hmpc/platform/linux/frame_faults.hpp"

namespace {

namespace hm = hmpc::humanoid;
namespace jp = hmpc::joint_protocol;
using hmpc::host::HostPhase;
using hmpc::host::HumanoidHost;
using hmpc::host::HumanoidHostConfig;
using hmpc::platform::CanFrame;
using hmpc::platform::CanResult;
using hmpc::platform::CanStatus;
using hmpc::platform::describe;
using hmpc::platform::monotonic_seconds;
using hmpc::platform::SocketCan;

constexpr const char* kProgram = "hmpc-humanoid-host";

struct Options {
  std::string interface = "vcan0";
  std::string io_interface;  // lock-step: the plant's Sync; empty without
  bool lockstep = false;
  double duration_s = 0;  // host seconds; 0: until SIGINT/SIGTERM
  std::string motion = "hip-hold";
  HumanoidHostConfig host{};
  double resume_at_s = -1;  // a paused motion's clock started at this host time
  std::string log_dir;
  hmpc::platform::FaultConfig send_faults{}, receive_faults{};
  double corrupt_at_s = -1, corrupt_s = 0.05;  // a burst of corrupted frames sent
  double estop_at_s = -1;
  double die_at_s = -1;
  std::string replay;    // a lock-step run's robot bus log to replay, offline
  long dds_domain = -1;  // < 0: no DDS
  bool dds_loopback = false;
};

void print_usage(std::FILE* out) {
  std::fprintf(
      out,
      "usage: hmpc-humanoid-host [--interface IFACE] [--io-interface IFACE] [--lockstep]\n"
      "         [--duration S] [--motion NAME|FILE] [--hold-seconds S] [--paused]\n"
      "         [--resume-at S] [--solve-time wall|model] [--threads N] [--truncate]\n"
      "         [--model-slip-velocity V] [--replay FILE]\n"
      "         [--log-dir DIR] [--drop-percent P] [--corrupt-at S] [--corrupt-ms MS]\n"
      "         [--seed N] [--estop-at S] [--fail-solver-at S] [--die-at S]\n"
      "         [--dds-domain ID [--dds-loopback]]\n"
      "  --interface IFACE     the robot bus (default vcan0)\n"
      "  --io-interface IFACE  HIL: the I/O bus, whose Sync frames are the host's clock in\n"
      "                        lock-step, logged beside the robot bus\n"
      "  --lockstep            one host tick per Sync of the plant (needs --io-interface)\n"
      "  --duration S          stop after S s of host time (default: until SIGINT/SIGTERM)\n"
      "  --motion NAME|FILE    the MPC's task: a motion shipped in " HMPC_HUMANOID_MOTIONS
      "\n"
      "                        (hip-hold, hip-squat, II-walking, ...) or a .motion file\n"
      "                        (default hip-hold)\n"
      "  --hold-seconds S      the boards' PID holds the posture this long before the MPC\n"
      "                        (default 10, Sec. 2.7.3's)\n"
      "  --paused              the motion's clock stays at 0 until --resume-at\n"
      "  --resume-at S         host time at which a paused motion's clock starts\n"
      "  --solve-time wall|model\n"
      "                        a plan takes effect after its solve's wall time, or the time this\n"
      "                        machine takes for the solver's work natively (the model; for the\n"
      "                        QEMU guest) (default wall)\n"
      "  --threads N           linearisation threads, 1..8 (default 2)\n"
      "  --truncate            stop a solve at the 12 ms sampling period by wall clock\n"
      "  --model-slip-velocity V\n"
      "                        the slip velocity of the MPC's friction law [m/s], 0.001..1\n"
      "                        (default: the plant's contact's, 0.01)\n"
      "  --log-dir DIR         created if missing: robot_bus.log and io_bus.log (candump -l),\n"
      "                        solves.csv and estimate.csv\n"
      "  --drop-percent P      share of the robot bus's frames the host loses, sent and received\n"
      "  --corrupt-at S, --corrupt-ms MS\n"
      "                        every frame the host sends in that window has a bit flipped\n"
      "  --seed N              of the losses (default 1)\n"
      "  --estop-at S          the host sends the bus-wide E-stop at S\n"
      "  --fail-solver-at S    test hook: every solve from S on counts as failed\n"
      "  --die-at S            test hook: SIGKILL to itself at S\n"
      "  --dds-domain ID       Cyclone DDS on this domain (0..230), the ROS 2 way: joints, IMU,\n"
      "                        odometry, plans and diagnostics out; mode, task and cost-weight\n"
      "                        commands in (topics under /hmpc/humanoid)\n"
      "  --dds-loopback        DDS on 127.0.0.1 only, without multicast\n"
      "  --replay FILE         offline: a lock-step run's robot_bus.log into the host, on the\n"
      "                        ticks it came, each frame the host sends compared with the run's;\n"
      "                        give the run's options (motion, hold, paused, resume, slip\n"
      "                        velocity); plans charged by the model (the run's must have been)\n"
      "Exit status: 0 at the end of --duration or on SIGINT/SIGTERM; 1 when a bus or a log\n"
      "fails; 2 for bad arguments; 3 when the robot could not be brought up; 4 when a replay\n"
      "differs from its run.\n");
}

hmpc::cli::ParseOutcome parse(int argc, char** argv, Options& o, std::string& error) {
  hmpc::cli::OptionParser p;
  p.interface("--interface", o.interface);
  p.interface("--io-interface", o.io_interface);
  p.flag("--lockstep", o.lockstep);
  p.number("--duration", 1e-3, hmpc::cli::kMaxDurationS, "seconds in [0.001, 1e6]", o.duration_s);
  p.text("--motion", [&o](const std::string& v) -> std::string {
    if (v.empty()) return "--motion needs a name or a file";
    o.motion = v;
    return {};
  });
  p.number("--hold-seconds", 0.6, 3600, "seconds in [0.6, 3600]", o.host.hold_seconds);
  p.flag("--paused", o.host.motion_paused);
  p.number("--resume-at", 0, hmpc::cli::kMaxDurationS, "seconds in [0, 1e6]", o.resume_at_s);
  p.text("--solve-time", [&o](const std::string& v) -> std::string {
    if (v == "wall") {
      o.host.solve_time = hmpc::host::SolveTime::kWall;
    } else if (v == "model") {
      o.host.solve_time = hmpc::host::SolveTime::kModel;
    } else {
      return hmpc::cli::bad_value("--solve-time", "wall or model", v);
    }
    return {};
  });
  p.integer("--threads", 1, 8, o.host.threads);
  p.flag("--truncate", o.host.truncate);
  p.number("--model-slip-velocity", 0.001, 1.0, "m/s in 0.001..1",
           o.host.problem.model_slip_velocity);
  p.text("--log-dir", [&o](const std::string& v) -> std::string {
    if (v.empty()) return "--log-dir needs a directory";
    o.log_dir = v;
    return {};
  });
  double drop = 0, corrupt_at = -1, corrupt_ms = 50;
  p.number("--drop-percent", 0, 100, "a percentage in [0, 100]", drop);
  p.number("--corrupt-at", 0, hmpc::cli::kMaxDurationS, "seconds in [0, 1e6]", corrupt_at);
  p.number("--corrupt-ms", 1, 1e6, "milliseconds in [1, 1e6]", corrupt_ms);
  std::uint64_t seed = 1;
  p.integer("--seed", 0, 1L << 30, seed);
  p.number("--estop-at", 0, hmpc::cli::kMaxDurationS, "seconds in [0, 1e6]", o.estop_at_s);
  p.number("--fail-solver-at", 0, hmpc::cli::kMaxDurationS, "seconds in [0, 1e6]",
           o.host.fail_solver_at_s);
  p.number("--die-at", 0, hmpc::cli::kMaxDurationS, "seconds in [0, 1e6]", o.die_at_s);
  p.text("--replay", [&o](const std::string& v) -> std::string {
    if (v.empty()) return "--replay needs a log file";
    o.replay = v;
    return {};
  });
  p.integer("--dds-domain", 0, 230, o.dds_domain);
  p.flag("--dds-loopback", o.dds_loopback);
  const auto outcome = p.parse(argc, argv, error);
  if (outcome != hmpc::cli::ParseOutcome::kRun) return outcome;
  if (o.dds_loopback && o.dds_domain < 0) {
    error = "--dds-loopback needs --dds-domain";
    return hmpc::cli::ParseOutcome::kError;
  }
  if (!o.replay.empty() && o.dds_domain >= 0) {
    error = "--replay runs offline: no --dds-domain";
    return hmpc::cli::ParseOutcome::kError;
  }
  if (o.lockstep && o.io_interface.empty()) {
    error = "--lockstep needs --io-interface (the plant's Sync frames are the host's clock)";
    return hmpc::cli::ParseOutcome::kError;
  }
  // A replay is exact only with the plans charged by the model, which the log alone decides.
  if (!o.replay.empty()) o.host.solve_time = hmpc::host::SolveTime::kModel;
  if (o.resume_at_s >= 0 && !o.host.motion_paused) {
    error = "--resume-at goes with --paused";
    return hmpc::cli::ParseOutcome::kError;
  }
  o.send_faults.drop_fraction = o.receive_faults.drop_fraction = drop / 100;
  o.send_faults.seed = seed;
  o.receive_faults.seed = seed ^ 0x7265637644ULL;
  o.corrupt_at_s = corrupt_at;
  o.corrupt_s = corrupt_ms / 1000;
  return outcome;
}

// The program around the controller: the buses, the faults injected on the host's side, the
// logs, one tick per host millisecond.
class Program {
 public:
  Program(const Options& o, HumanoidHost& host, SocketCan& robot, SocketCan* io,
          hmpc::dds::HumanoidDdsBridge* dds)
      : o_(o), host_(host), robot_(robot), io_(io), dds_(dds), send_faults_(o.send_faults),
        receive_faults_(o.receive_faults), corrupt_(o.send_faults.seed ^ 0xb17f11bULL) {}

  bool open_logs(std::string& error) {
    if (o_.log_dir.empty()) return true;
    std::error_code made;
    std::filesystem::create_directories(o_.log_dir, made);
    if (made) {
      error = "cannot create the log directory '" + o_.log_dir + "': " + made.message();
      return false;
    }
    if (!robot_log_.open(o_.log_dir + "/robot_bus.log", error)) return false;
    if (io_ && !io_log_.open(o_.log_dir + "/io_bus.log", error)) return false;
    solves_ = hmpc::platform::open_csv_log(
        o_.log_dir + "/solves.csv",
        "tick,motion_time_s,wall_ms,charged_ms,effective_tick,upper_iterations,fast_iterations,"
        "usable,estimate_tick",
        error);
    if (!solves_) return false;
    estimate_ = hmpc::platform::open_csv_log(
        o_.log_dir + "/estimate.csv",
        "time_s,phase,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz,trust,tau_ref_0,tau_ref_1,tau_ref_2,"
        "tau_ref_3,tau_ref_4,tau_ref_5,tau_ref_6,tau_ref_7",
        error);
    return estimate_ != nullptr;
  }
  bool close_logs() {
    bool ok = robot_log_.close() && io_log_.close();
    for (std::FILE* f : {solves_, estimate_}) {
      if (f && std::fclose(f) != 0) ok = false;
    }
    solves_ = estimate_ = nullptr;
    return ok;
  }

  // A frame from the robot bus (time_s: the host's clock, for the log).
  void on_robot_frame(const CanFrame& raw, double time_s) {
    robot_log_.write(time_s, o_.interface.c_str(), raw);
    hmpc::protocol::Frame frame;
    if (!hmpc::platform::to_protocol_frame(raw, frame)) return;
    if (receive_faults_.apply(time_s, frame) == hmpc::platform::FaultAction::kDrop) return;
    host_.on_frame(frame, tick_);
  }
  // A frame from the I/O bus: logged; true for a valid Sync (its tick in `sync_tick`).
  bool on_io_frame(const CanFrame& raw, double time_s, std::uint32_t& sync_tick) {
    io_log_.write(time_s, o_.io_interface.c_str(), raw);
    hmpc::protocol::Frame frame;
    jp::FrameType type{};
    jp::NodeId node = 0;
    if (!hmpc::platform::to_protocol_frame(raw, frame) || !jp::identify(frame.id, type, node) ||
        type != jp::FrameType::kSync) {
      return false;
    }
    jp::Sync sync;
    if (sync_receiver_.decode(frame, sync) != jp::DecodeResult::kOk) return false;
    sync_tick = sync.tick;
    return true;
  }

  // Host tick `tick`: the test hooks, the controller, its frames out.
  void tick(std::uint32_t tick) {
    tick_ = tick;
    const double t = 1e-3 * double(tick);
    if (o_.die_at_s >= 0 && t >= o_.die_at_s) ::raise(SIGKILL);
    if (o_.estop_at_s >= 0 && !estop_sent_ && t >= o_.estop_at_s) {
      host_.estop();
      estop_sent_ = true;
    }
    if (o_.resume_at_s >= 0 && t >= o_.resume_at_s) host_.resume_motion();
    if (dds_) dds_->poll(host_);
    host_.tick(tick, true, [&](const jp::Frame& f) { send(f, t); });
    if (dds_ && !dds_->publish(host_, tick)) ++dds_refused_;
    log_tick(tick, t);
  }

  void note_interface_down() { ++interface_down_; }
  std::uint64_t sent() const { return sent_; }
  std::uint64_t interface_down() const { return interface_down_; }
  std::uint64_t transmit_failures() const { return transmit_failures_; }
  std::uint64_t corrupted() const { return corrupted_; }
  const hmpc::platform::FaultCounters& send_faults() const { return send_faults_.counters(); }
  const hmpc::platform::FaultCounters& receive_faults() const { return receive_faults_.counters(); }
  std::uint32_t current_tick() const { return tick_; }
  std::uint64_t dds_refused() const { return dds_refused_; }

 private:
  void send(jp::Frame frame, double t) {
    if (send_faults_.apply(t, frame) == hmpc::platform::FaultAction::kDrop) return;
    if (o_.corrupt_at_s >= 0 && t >= o_.corrupt_at_s && t < o_.corrupt_at_s + o_.corrupt_s) {
      const std::uint32_t bit = std::uint32_t(corrupt_() % 64u);
      frame.data[bit / 8] = std::uint8_t(frame.data[bit / 8] ^ (1u << (bit % 8)));
      ++corrupted_;
    }
    const CanFrame raw = hmpc::platform::to_can_frame(frame);
    robot_log_.write(t, o_.interface.c_str(), raw);
    const CanResult r = robot_.send(raw);
    if (r.ok()) {
      ++sent_;
    } else if (r.status == CanStatus::kInterfaceDown) {
      ++interface_down_;
    } else {
      ++transmit_failures_;
    }
  }

  // The controller's state, every 6 ms (the IMU's period), and each solve as it is made.
  void log_tick(std::uint32_t tick, double t) {
    const auto& solves = host_.solves();
    for (; solves_ && logged_solves_ < solves.size(); ++logged_solves_) {
      const hmpc::host::SolveRecord& r = solves[logged_solves_];
      std::fprintf(solves_, "%u,%.3f,%.3f,%.3f,%u,%d,%d,%d,%u\n", r.tick, r.motion_time, r.wall_ms,
                   r.charged_ms, r.effective_tick, r.upper_iterations, r.fast_iterations,
                   r.usable ? 1 : 0, r.estimate_tick);
    }
    if (!estimate_ || tick % 6 != 0) return;
    const hm::BasicState<0> x = host_.estimator().state();
    const auto& e = host_.estimator().filter().estimate();
    std::fprintf(estimate_, "%.3f,%s", t, hmpc::host::name_of(host_.phase()));
    if (host_.estimating()) {
      for (int i = 0; i < 7; ++i) std::fprintf(estimate_, ",%.5f", x.q[i]);
      for (int i = 0; i < 3; ++i) std::fprintf(estimate_, ",%.5f", e.velocity[i]);
      for (int i = 0; i < 3; ++i) std::fprintf(estimate_, ",%.5f", e.angular_velocity[i]);
      std::fprintf(estimate_, ",%s", hmpc::estimation::to_string(e.trust));
    } else {
      std::fprintf(estimate_, ",,,,,,,,,,,,,,");
    }
    const hm::JointVector& tau = host_.master().references();
    for (int j = 0; j < hm::kJoints; ++j) std::fprintf(estimate_, ",%.3f", tau[j]);
    std::fputc('\n', estimate_);
  }

  const Options& o_;
  HumanoidHost& host_;
  SocketCan& robot_;
  SocketCan* io_;
  hmpc::dds::HumanoidDdsBridge* dds_;
  hmpc::platform::FaultInjector send_faults_, receive_faults_;
  std::mt19937_64 corrupt_;
  jp::Receiver sync_receiver_{0};
  hmpc::platform::CandumpLog robot_log_, io_log_;
  std::FILE* solves_ = nullptr;
  std::FILE* estimate_ = nullptr;
  std::size_t logged_solves_ = 0;
  std::uint32_t tick_ = 0;
  bool estop_sent_ = false;
  std::uint64_t sent_ = 0, interface_down_ = 0, transmit_failures_ = 0, corrupted_ = 0;
  std::uint64_t dds_refused_ = 0;
};

enum class End { kDone, kSignal, kFailure, kBringUp };

// Takes every frame waiting on `bus`; false on a receive error other than the interface down.
template <class Take>
bool drain(SocketCan& bus, Program& program, Take&& take, std::string& error) {
  for (;;) {
    CanFrame raw;
    const CanResult r = bus.receive(raw, std::chrono::microseconds(0));
    if (r.status == CanStatus::kTimeout) return true;
    if (r.status == CanStatus::kInterfaceDown) {
      program.note_interface_down();
      return true;
    }
    if (!r.ok()) {
      error = "receiving failed: " + describe(r);
      return false;
    }
    if (!take(raw)) return true;
  }
}

End run(const Options& o, Program& program, HumanoidHost& host, SocketCan& robot, SocketCan* io,
        int signal_fd, std::string& error) {
  const hmpc::platform::FileDescriptor timer(
      o.lockstep ? -1 : ::timerfd_create(CLOCK_MONOTONIC, TFD_CLOEXEC));
  if (!o.lockstep) {
    const itimerspec every_ms{{0, 1'000'000}, {0, 1'000'000}};
    if (timer.get() < 0 || ::timerfd_settime(timer.get(), 0, &every_ms, nullptr) < 0) {
      error = std::string("timerfd: ") + std::strerror(errno);
      return End::kFailure;
    }
  }
  const double started = monotonic_seconds();
  // The host's clock for the logs: ticks in lock-step, seconds since the start in real time.
  std::uint32_t ticks = 0;
  const auto now = [&] {
    return o.lockstep ? 1e-3 * double(ticks) : monotonic_seconds() - started;
  };
  const auto due = [&](std::uint32_t tick) {
    return o.duration_s <= 0 || 1e-3 * double(tick) < o.duration_s;
  };
  pollfd fds[4] = {{signal_fd, POLLIN, 0},
                   {robot.native_handle(), POLLIN, 0},
                   {io ? io->native_handle() : -1, POLLIN, 0},
                   {timer.get(), POLLIN, 0}};
  while (due(ticks)) {
    if (::poll(fds, 4, -1) < 0) {
      if (errno == EINTR) continue;
      error = std::string("poll: ") + std::strerror(errno);
      return End::kFailure;
    }
    if (fds[0].revents & POLLIN) return End::kSignal;
    // The robot bus first: a tick acts on what arrived before its Sync.
    if (!drain(
            robot, program,
            [&](const CanFrame& f) {
              program.on_robot_frame(f, now());
              return true;
            },
            error)) {
      return End::kFailure;
    }
    if (io) {
      const bool ok = drain(
          *io, program,
          [&](const CanFrame& f) {
            std::uint32_t sync_tick = 0;
            if (!program.on_io_frame(f, now(), sync_tick) || !o.lockstep) return true;
            ticks = sync_tick;
            if (!due(ticks)) return false;
            // Frames of this tick that came on the robot bus meanwhile are taken first.
            drain(
                robot, program,
                [&](const CanFrame& r) {
                  program.on_robot_frame(r, now());
                  return true;
                },
                error);
            program.tick(ticks);
            ++ticks;
            return true;
          },
          error);
      if (!ok) return End::kFailure;
    }
    if (!o.lockstep && (fds[3].revents & POLLIN)) {
      std::uint64_t expirations = 0;
      if (::read(timer.get(), &expirations, sizeof expirations) != sizeof expirations) continue;
      for (std::uint64_t i = 0; i < expirations && due(ticks); ++i, ++ticks) program.tick(ticks);
    }
    if (host.bring_up_failed()) return End::kBringUp;
  }
  return End::kDone;
}

}  // namespace

// --replay: the run's robot bus log into `host`, the run's program hooks on their ticks.
int replay(const Options& o, HumanoidHost& host) {
  std::ifstream log(o.replay);
  if (!log) {
    std::fprintf(stderr, "%s: cannot read %s\n", kProgram, o.replay.c_str());
    return 1;
  }
  bool estop_sent = false;
  const auto hooks = [&](std::uint32_t tick) {
    const double t = 1e-3 * double(tick);
    if (o.estop_at_s >= 0 && !estop_sent && t >= o.estop_at_s) {
      host.estop();
      estop_sent = true;
    }
    if (o.resume_at_s >= 0 && t >= o.resume_at_s) host.resume_motion();
  };
  hmpc::host::ReplayReport r;
  std::string error;
  if (!hmpc::host::replay_lockstep_log(log, host, r, error, hooks)) {
    std::fprintf(stderr, "%s: %s: %s\n", kProgram, o.replay.c_str(), error.c_str());
    return 1;
  }
  std::printf(
      "%s: summary replay ticks=%u heard=%llu sent=%llu run_sent=%llu mismatches=%llu "
      "first_mismatch_tick=%u first_mismatch=\"%s\" skipped_lines=%llu phase=%s solves=%zu\n",
      kProgram, r.ticks, static_cast<unsigned long long>(r.heard),
      static_cast<unsigned long long>(r.sent), static_cast<unsigned long long>(r.logged_sent),
      static_cast<unsigned long long>(r.mismatches), r.first_mismatch_tick,
      r.first_mismatch.c_str(), static_cast<unsigned long long>(r.skipped_lines),
      hmpc::host::name_of(host.phase()), host.solves().size());
  return r.mismatches == 0 ? 0 : 4;
}

int main(int argc, char** argv) {
  Options options;
  std::string error;
  const auto outcome = parse(argc, argv, options, error);
  if (outcome != hmpc::cli::ParseOutcome::kRun) {
    return hmpc::cli::exit_status(outcome, kProgram, error, print_usage);
  }
  const hmpc::platform::FileDescriptor signals(hmpc::platform::stop_signal_descriptor(error));
  if (signals.get() < 0) {
    std::fprintf(stderr, "%s: %s\n", kProgram, error.c_str());
    return 1;
  }
  std::unique_ptr<HumanoidHost> host;
  hm::Motion motion;
  try {
    motion = hm::load_motion(hm::motion_path(options.motion, HMPC_HUMANOID_MOTIONS));
    host = std::make_unique<HumanoidHost>(options.host, motion);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", kProgram, e.what());
    return 2;
  }
  if (!options.replay.empty()) return replay(options, *host);
  // The robot bus: every frame (the boards' and the IMU's); the I/O bus: only listened to.
  SocketCan robot, io;
  for (auto [can, name] :
       {std::pair{&robot, &options.interface}, std::pair{&io, &options.io_interface}}) {
    if (name->empty()) continue;
    CanResult opened = can->open(name->c_str());
    if (opened.ok()) opened = can->set_non_blocking(true);
    if (!opened.ok()) {
      std::fprintf(stderr, "%s: cannot open CAN interface '%s': %s\n", kProgram, name->c_str(),
                   describe(opened).c_str());
      return 1;
    }
  }
  std::unique_ptr<hmpc::dds::HumanoidDdsBridge> dds;
  if (options.dds_domain >= 0) {
    try {
      dds = std::make_unique<hmpc::dds::HumanoidDdsBridge>(
          std::uint32_t(options.dds_domain),
          hmpc::dds::HumanoidTaskLimits::around(motion.phases[0].height),
          options.dds_loopback ? hmpc::dds::loopback_config() : std::string());
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s: DDS: %s\n", kProgram, e.what());
      return 1;
    }
  }
  Program program(options, *host, robot, options.io_interface.empty() ? nullptr : &io, dds.get());
  if (!program.open_logs(error)) {
    std::fprintf(stderr, "%s: %s\n", kProgram, error.c_str());
    return 1;
  }
  std::printf("%s: robot bus %s%s%s, %s, motion %s, MPC after %.2f s of hold: ready\n", kProgram,
              options.interface.c_str(), options.io_interface.empty() ? "" : ", I/O bus ",
              options.io_interface.c_str(), options.lockstep ? "lock-step" : "real time, 1 kHz",
              options.motion.c_str(), options.host.hold_seconds);
  std::fflush(stdout);
  const double started = monotonic_seconds();
  const End end = run(options, program, *host, robot, options.io_interface.empty() ? nullptr : &io,
                      signals.get(), error);
  const double wall_s = monotonic_seconds() - started;
  int status = 0;
  if (end == End::kFailure) {
    std::fprintf(stderr, "%s: %s\n", kProgram, error.c_str());
    status = 1;
  }
  if (end == End::kBringUp) {
    std::fprintf(stderr, "%s: the robot could not be brought up: %s\n", kProgram,
                 host->reason().c_str());
    status = 3;
  }
  if (!program.close_logs()) {
    std::fprintf(stderr, "%s: writing the logs in '%s' failed\n", kProgram,
                 options.log_dir.c_str());
    status = 1;
  }
  // Solve figures: the charged times (what took effect), largest, median, share over 12 ms.
  std::vector<double> charged;
  for (const auto& s : host->solves()) charged.push_back(s.charged_ms);
  std::sort(charged.begin(), charged.end());
  const double period_ms = 1e3 * options.host.timing.upper_step;
  const auto over =
      std::count_if(charged.begin(), charged.end(), [&](double c) { return c > period_ms; });
  const auto& m = host->master();
  std::printf(
      "%s: summary ticks=%u wall_seconds=%.3f phase=%s reason=\"%s\" solves=%zu "
      "largest_solve_ms=%.3f median_solve_ms=%.3f solves_over_period=%ld "
      "largest_delay_ticks=%u "
      "frames_sent=%llu rejected_frames=%llu sent_dropped=%llu received_dropped=%llu "
      "sent_corrupted=%llu interface_down=%llu transmit_failures=%llu board0_mode=%s "
      "board1_mode=%s board0_faults=0x%04x board1_faults=0x%04x imu_frames=%u "
      "dds_commands=%llu dds_tasks=%llu dds_weights=%llu dds_rejected=%llu dds_rejects=%s "
      "dds_commander_silences=%llu dds_refused=%llu\n",
      kProgram, program.current_tick(), wall_s, hmpc::host::name_of(host->phase()),
      host->reason().c_str(), charged.size(), charged.empty() ? 0.0 : charged.back(),
      charged.empty() ? 0.0 : charged[charged.size() / 2], long(over), host->largest_delay_ticks(),
      static_cast<unsigned long long>(program.sent()),
      static_cast<unsigned long long>(m.rejected_frames()),
      static_cast<unsigned long long>(program.send_faults().dropped),
      static_cast<unsigned long long>(program.receive_faults().dropped),
      static_cast<unsigned long long>(program.corrupted()),
      static_cast<unsigned long long>(program.interface_down()),
      static_cast<unsigned long long>(program.transmit_failures()),
      jp::value_name(jp::kBoardModeValues, std::uint32_t(m.board(0).status.mode)),
      jp::value_name(jp::kBoardModeValues, std::uint32_t(m.board(1).status.mode)),
      unsigned(m.board(0).status.faults), unsigned(m.board(1).status.faults),
      m.readings().imu_frames, static_cast<unsigned long long>(dds ? dds->commands() : 0),
      static_cast<unsigned long long>(dds ? dds->tasks() : 0),
      static_cast<unsigned long long>(dds ? dds->weights() : 0),
      static_cast<unsigned long long>(dds ? dds->rejects().total() : 0),
      dds ? dds->rejects().summary().c_str() : "none",
      static_cast<unsigned long long>(dds ? dds->commander_silences() : 0),
      static_cast<unsigned long long>(program.dds_refused()));
  return status;
}
