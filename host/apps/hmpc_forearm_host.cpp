// hmpc-forearm-host: the host forearm controller. Drives one forearm board over CAN
// (ForearmCanMaster: heartbeat, mode and strategy, target trajectory streaming), logs what the
// board reports, and bridges to Cyclone DDS with ROS 2's types (hmpc/dds/forearm_dds.hpp):
// publishes the board's joint state, MPC telemetry and diagnostics, takes validated mode
// commands and target trajectories from operators (hmpc-forearm-cli, any ROS 2 node), and
// holds the arm when the commander running it falls silent.
//
// Paced in real time by a 1 kHz timer, or in HIL lock-step by the plant's Sync frames (one
// host tick per simulated millisecond). A scripted session (--run) asks for idle with faults
// cleared, then hold, then run with the given strategy and target, then hold again; without
// it the board stays idle until a DDS command arrives. The scripted target is any of
// hmpc/trajectory/joint_target.hpp's shapes or a CSV file, checked against the joint's range
// and speed before the bus is opened. Fault injection on the host's frames
// (--drop-percent, --corrupt-percent, --silence-at, --stop-heartbeat-at) exercises the board's
// defences. At the end: a summary of key=value pairs.
#include <poll.h>
#include <signal.h>
#include <sys/signalfd.h>
#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "hmpc/cli/arguments.hpp"
#include "hmpc/dds/forearm_dds.hpp"
#include "hmpc/host/forearm_can_master.hpp"
#include "hmpc/models/forearm_target_range.hpp"
#include "hmpc/platform/linux/bus_program.hpp"
#include "hmpc/platform/linux/frame_faults.hpp"

namespace {

namespace proto = hmpc::forearm_protocol;
using hmpc::host::ForearmCanMaster;
using hmpc::platform::CanFrame;
using hmpc::platform::CanResult;
using hmpc::platform::CanStatus;
using hmpc::platform::describe;
using hmpc::platform::monotonic_seconds;
using hmpc::platform::SocketCan;

constexpr const char* kProgram = "hmpc-forearm-host";
constexpr double kDegree = M_PI / 180;
// Scripted session: idle with faults cleared, hold from kHoldAt, run from --run-at.
constexpr double kHoldAt = 0.05;  // s
// A step's default speed: about the 188 deg/s peak of the thesis's 1 Hz +-30 deg sinusoid, a
// target every strategy tracks (Sec. 3.4).
constexpr double kDefaultStepRate = M_PI;  // rad/s

struct Options {
  std::string interface = "vcan0";
  proto::NodeId node = 0;
  bool lockstep = false;
  double duration_s = 0;  // host seconds; 0: until SIGINT/SIGTERM
  bool scripted = false;
  proto::Strategy strategy = proto::Strategy::kTwoStage;
  hmpc::trajectory::TargetSpec target = [] {
    hmpc::trajectory::TargetSpec t;
    t.step_rate = kDefaultStepRate;
    return t;
  }();
  std::vector<hmpc::trajectory::TrajectoryPoint> target_points;  // checked, for every shape
  double run_at_s = 0.3, run_for_s = 10;
  long dds_domain = -1;  // < 0: no DDS
  bool dds_loopback = false;
  hmpc::platform::FaultConfig faults{};
  double stop_heartbeat_at_s = -1;
  double die_at_s = -1;  // test hook: SIGKILL to itself at this host time; < 0: never
  std::string log_path;
};

void print_usage(std::FILE* out) {
  std::fprintf(
      out,
      "usage: hmpc-forearm-host [--interface IFACE] [--node N] [--lockstep] [--duration S]\n"
      "         [--run STRATEGY [--target SHAPE] [--amplitude-deg A] [--frequency HZ]\n"
      "          [--offset-deg D] [--chirp-to HZ] [--step-at S] [--step-rate-deg-s R]\n"
      "          [--target-file FILE] [--run-at S] [--run-for S]] [--dds-domain ID "
      "[--dds-loopback]]\n"
      "         [--drop-percent P] [--corrupt-percent P] [--silence-at S] [--silence-ms MS]\n"
      "         [--stop-heartbeat-at S] [--die-at S] [--seed N] [--log FILE]\n"
      "  --interface IFACE     SocketCAN interface (default vcan0)\n"
      "  --node N              board node id 0..15 (default 0)\n"
      "  --lockstep            one host tick per Sync frame of the HIL plant (default: 1 kHz "
      "timer)\n"
      "  --duration S          stop after S s of host time (default: until SIGINT/SIGTERM)\n"
      "  --run STRATEGY        scripted session: idle, hold at %.2f s, run STRATEGY from --run-at\n"
      "                        for --run-for s, then hold; STRATEGY: fine_4ms fine_8ms\n"
      "                        coarse_20ms coarse_40ms two_stage pam_only\n"
      "  --target SHAPE        the run's target, from its start t = 0 (default sine):\n"
      "                        sine   offset + amplitude sin(2 pi f t)\n"
      "                        step   offset until --step-at, then to offset + amplitude at\n"
      "                               --step-rate-deg-s\n"
      "                        ramp   straight lines between offset +- amplitude, a triangle\n"
      "                               wave of frequency f\n"
      "                        chirp  a sinusoid whose frequency sweeps linearly from f to\n"
      "                               --chirp-to over --run-for\n"
      "                        file   the points of --target-file\n"
      "  --amplitude-deg A     deg, -57..57 (default 30)\n"
      "  --frequency HZ        f, 0..5 (default 1)\n"
      "  --offset-deg D        deg, -57..57 (default 0)\n"
      "  --chirp-to HZ         the chirp's final frequency, 0..5 (default 2)\n"
      "  --step-at S           s from the run's start (default 1)\n"
      "  --step-rate-deg-s R   the step's speed, deg/s, 1..573 (default %.0f)\n"
      "  --target-file FILE    CSV lines time_s,position_rad[,velocity_rad_s] (cubic Hermite\n"
      "                        between points that give velocities, linear otherwise); implies\n"
      "                        --target file\n"
      "                        Every target must stay within the joint's range and speed\n"
      "                        (the board's software limits, %g rad/s), checked before start.\n"
      "  --run-at S, --run-for S  (default 0.3 and 10)\n"
      "  --dds-domain ID       bridge to Cyclone DDS on this domain: state and telemetry out,\n"
      "                        commands in (hmpc-forearm-cli)\n"
      "  --dds-loopback        DDS on 127.0.0.1 only, without multicast\n"
      "  --drop-percent P, --corrupt-percent P, --silence-at S, --silence-ms MS, --seed N\n"
      "                        faults on the host's frames to the board\n"
      "  --stop-heartbeat-at S the host stops sending heartbeats at S (a dead host)\n"
      "  --die-at S            test hook: the host kills itself with SIGKILL at S (a crash)\n"
      "  --log FILE            CSV of every SolveTelemetry report (4 ms)\n"
      "Exit status: 0 at the end of --duration or on SIGINT/SIGTERM; 1 when the bus, DDS or\n"
      "the log fails; 2 for bad arguments.\n",
      kHoldAt, kDefaultStepRate / kDegree, hmpc::forearm::kMaxTargetSpeed);
}

hmpc::cli::ParseOutcome parse(int argc, char** argv, Options& o, std::string& error) {
  hmpc::cli::OptionParser p;
  p.interface("--interface", o.interface);
  p.integer("--node", 0, proto::kMaxNodeId, o.node);
  p.flag("--lockstep", o.lockstep);
  p.number("--duration", 1e-3, 1e6, "a number of seconds in [0.001, 1e6]", o.duration_s);
  p.text("--run", [&](const std::string& v) -> std::string {
    std::uint32_t value = 0;
    if (!proto::value_of(proto::kStrategyValues, v, value))
      return hmpc::cli::bad_value("--run",
                                  "one of fine_4ms fine_8ms coarse_20ms coarse_40ms "
                                  "two_stage pam_only",
                                  v);
    o.strategy = proto::Strategy(value);
    o.scripted = true;
    return {};
  });
  hmpc::trajectory::TargetSpec& target = o.target;
  p.text("--target", [&](const std::string& v) -> std::string {
    if (!hmpc::trajectory::shape_of(v, target.shape))
      return hmpc::cli::bad_value("--target", "one of sine step ramp chirp file", v);
    return {};
  });
  p.number("--amplitude-deg", -57, 57, "an amplitude in [-57, 57] deg", target.amplitude, kDegree);
  p.number("--frequency", 0, 5, "a frequency in [0, 5] Hz", target.frequency_hz);
  p.number("--offset-deg", -57, 57, "an offset in [-57, 57] deg", target.offset, kDegree);
  p.number("--chirp-to", 0, 5, "a frequency in [0, 5] Hz", target.chirp_end_hz);
  p.number("--step-at", 0, 1e5, "a time in [0, 1e5] s", target.step_at_s);
  p.number("--step-rate-deg-s", 1, 573, "a speed in [1, 573] deg/s", target.step_rate, kDegree);
  bool file_given = false;
  p.text("--target-file", [&](const std::string& v) -> std::string {
    if (v.empty()) return "--target-file needs a file name";
    target.file = v;
    file_given = true;
    return {};
  });
  p.number("--run-at", kHoldAt + 0.05, 1e5, "a time in [0.1, 1e5] s", o.run_at_s);
  p.number("--run-for", 0.001, 1e5, "a duration in [0.001, 1e5] s", o.run_for_s);
  p.integer("--dds-domain", 0, 230, o.dds_domain);
  p.flag("--dds-loopback", o.dds_loopback);
  p.number("--drop-percent", 0, 100, "a percentage in [0, 100]", o.faults.drop_fraction, 0.01);
  p.number("--corrupt-percent", 0, 100, "a percentage in [0, 100]", o.faults.corrupt_fraction,
           0.01);
  double silence_at = -1, silence_ms = 100;
  p.number("--silence-at", 0, 1e6, "a time in [0, 1e6] s", silence_at);
  p.number("--silence-ms", 1, 1e6, "a duration in [1, 1e6] ms", silence_ms);
  p.number("--stop-heartbeat-at", 0, 1e6, "a time in [0, 1e6] s", o.stop_heartbeat_at_s);
  p.number("--die-at", 0, 1e6, "a time in [0, 1e6] s", o.die_at_s);
  p.integer("--seed", 0, 2147483647L, o.faults.seed);
  p.text("--log", [&](const std::string& v) -> std::string {
    if (v.empty()) return "--log needs a file name";
    o.log_path = v;
    return {};
  });
  const auto outcome = p.parse(argc, argv, error);
  if (outcome != hmpc::cli::ParseOutcome::kRun) return outcome;
  o.faults.silence_start_s = silence_at;
  o.faults.silence_duration_s = silence_at >= 0 ? silence_ms * 1e-3 : 0;
  if (file_given && target.shape != hmpc::trajectory::TargetShape::kSine &&
      target.shape != hmpc::trajectory::TargetShape::kFile) {
    error = "--target-file goes with --target file";
    return hmpc::cli::ParseOutcome::kError;
  }
  if (file_given) target.shape = hmpc::trajectory::TargetShape::kFile;
  if (target.shape == hmpc::trajectory::TargetShape::kFile && !file_given) {
    error = "--target file needs --target-file";
    return hmpc::cli::ParseOutcome::kError;
  }
  // The board faults past its software limits (firmware BoardConfig): the target stays inside,
  // and within a speed the joint can follow.
  // A sinusoid streams in closed form for as long as it runs: its first period shows all it asks.
  const bool sine = target.shape == hmpc::trajectory::TargetShape::kSine;
  target.duration_s = !sine                     ? o.run_for_s
                      : target.frequency_hz > 0 ? std::min(o.run_for_s, 1 / target.frequency_hz)
                                                : hmpc::trajectory::kSampleSpacingS;
  std::string why;
  if (o.scripted &&
      !hmpc::trajectory::make_points(target, hmpc::forearm::target_range(),
                                     hmpc::dds::kMaxTrajectoryPoints, o.target_points, why)) {
    error = "invalid target: " + why;
    return hmpc::cli::ParseOutcome::kError;
  }
  if (o.dds_loopback && o.dds_domain < 0) {
    error = "--dds-loopback needs --dds-domain";
    return hmpc::cli::ParseOutcome::kError;
  }
  return outcome;
}

// Solve times as reported (whole microseconds, 16 bits): counted per value in a table made once,
// so a session of any length keeps exact max and median without growing or allocating.
class SolveTimeHistogram {
 public:
  SolveTimeHistogram() : counts_(65536, 0) {}
  void add(std::uint16_t us) {
    ++counts_[us];
    ++total_;
  }
  std::uint64_t size() const { return total_; }
  double max() const {
    for (std::size_t us = counts_.size(); us-- > 0;)
      if (counts_[us] > 0) return double(us);
    return 0;
  }
  // The element at index size/2 of the sorted times (the upper median).
  double median() const {
    std::uint64_t seen = 0;
    for (std::size_t us = 0; us < counts_.size(); ++us) {
      seen += counts_[us];
      if (seen > total_ / 2) return double(us);
    }
    return 0;
  }

 private:
  std::vector<std::uint32_t> counts_;
  std::uint64_t total_ = 0;
};

// The host: master, bus, faults, DDS and log, one tick per host millisecond.
class Host {
 public:
  Host(const Options& o, SocketCan& can, hmpc::dds::ForearmDdsBridge* dds, std::FILE* log)
      : o_(o), can_(can), dds_(dds), log_(log), master_({o.node}), sender_(o.node),
        sync_receiver_(o.node), faults_(o.faults) {
    trajectory_.reserve(hmpc::dds::kMaxTrajectoryPoints + 1);
  }

  // One host tick at host time t: the script or DDS commands, then the frames due.
  bool tick(double t, std::string& error) {
    now_s_ = t;
    if (o_.die_at_s >= 0 && t >= o_.die_at_s) ::raise(SIGKILL);
    if (o_.scripted) script(t);
    if (dds_) dds_->poll(dds_handlers_);
    const bool heartbeat = !(o_.stop_heartbeat_at_s >= 0 && t >= o_.stop_heartbeat_at_s);
    bool ok = true;
    master_.tick(t, heartbeat, [&](const auto& message) {
      proto::Frame frame;
      if (sender_.encode(message, frame) != proto::EncodeResult::kOk) return;
      const std::uint64_t corrupted_before = faults_.counters().corrupted;
      if (faults_.apply(t, frame) == hmpc::platform::FaultAction::kDrop) return;
      const CanResult sent = can_.send(hmpc::platform::to_can_frame(frame));
      if (sent.ok()) {
        ++frames_sent_;
        if constexpr (std::is_same_v<std::decay_t<decltype(message)>, proto::ModeCommand>) {
          if (faults_.counters().corrupted == corrupted_before) on_intact_heartbeat(message, t);
        }
      } else if (sent.status == CanStatus::kInterfaceDown) {
        ++interface_down_;  // the bus went away: keep ticking, it may come back
      } else if (sent.status != CanStatus::kWouldBlock &&
                 sent.status != CanStatus::kTransmitQueueFull) {
        error = "sending failed: " + describe(sent);
        ok = false;
      }
    });
    return ok;
  }

  // A frame from the bus. Returns true for the plant's Sync (a lock-step host tick).
  bool on_frame(const CanFrame& raw, std::uint32_t& sync_tick) {
    ++frames_received_;
    proto::Frame frame;
    if (!hmpc::platform::to_protocol_frame(raw, frame)) return false;
    proto::FrameType type;
    proto::NodeId node;
    if (proto::identify(frame.id, type, node) && node == o_.node) {
      if (type == proto::FrameType::kSync) {
        proto::Sync sync;
        if (sync_receiver_.decode(frame, sync) != proto::DecodeResult::kOk) return false;
        sync_tick = sync.tick;
        return true;
      }
      if (type != proto::FrameType::kSensor && type != proto::FrameType::kActuatorCommand)
        ++board_report_frames_;
    }
    if (master_.on_frame(frame)) on_telemetry();
    return false;
  }

  void note_interface_down() { ++interface_down_; }

  void print_summary(double wall_s) const {
    const auto& r = master_.report();
    const auto& f = faults_.counters();
    // Bus load at 1 Mbit/s, worst-case bit stuffing (as forearm_protocol::bus_load): all frames
    // this node's traffic put on the bus, and the host-board part alone (the real robot's).
    const double seconds = std::max(now_s_, 1e-3);
    const double all_frames = double(frames_received_ + frames_sent_);
    const double robot_frames = double(board_report_frames_ + frames_sent_);
    std::printf(
        "%s: summary host_seconds=%.3f wall_seconds=%.3f run_start_s=%.3f run_end_s=%.3f "
        "frames_sent=%llu frames_received=%llu bus_load_hil_1mbit=%.4f bus_load_robot_1mbit=%.4f "
        "board_mode=%s board_faults=0x%02x board_strategy=%s board_rejected_frames=%u "
        "board_watchdog_trips=%u board_solver_failures=%u board_overruns=%u "
        "telemetry_frames=%llu solves=%llu solve_time_max_us=%.0f solve_time_median_us=%.0f "
        "host_rejected_frames=%u frames_dropped=%llu frames_corrupted=%llu frames_silenced=%llu "
        "dds_commands=%llu dds_trajectories=%llu dds_weights=%llu dds_rejected=%llu dds_rejects=%s "
        "dds_commander_silences=%llu heartbeat_max_gap_ms=%.0f "
        "last_heartbeat_s=%.3f interface_down=%llu\n",
        kProgram, now_s_, wall_s, run_start_s_, run_stop_s_,
        static_cast<unsigned long long>(frames_sent_),
        static_cast<unsigned long long>(frames_received_),
        all_frames * proto::kWorstCaseFrameBits / (seconds * 1e6),
        robot_frames * proto::kWorstCaseFrameBits / (seconds * 1e6),
        proto::value_name(proto::kBoardModeValues, std::uint32_t(r.status.mode)),
        unsigned(r.status.faults),
        proto::value_name(proto::kStrategyValues, std::uint32_t(r.status.strategy)),
        unsigned(r.status.rejected_frames), unsigned(r.status.watchdog_trips),
        unsigned(r.status.solver_failures), unsigned(r.status.overruns),
        static_cast<unsigned long long>(r.telemetry_frames),
        static_cast<unsigned long long>(solve_times_.size()), solve_times_.max(),
        solve_times_.median(), master_.rejects().total(),
        static_cast<unsigned long long>(f.dropped), static_cast<unsigned long long>(f.corrupted),
        static_cast<unsigned long long>(f.silenced), static_cast<unsigned long long>(dds_commands_),
        static_cast<unsigned long long>(dds_trajectories_),
        static_cast<unsigned long long>(dds_weights_),
        static_cast<unsigned long long>(dds_ ? dds_->rejects().total() : 0),
        dds_ ? dds_->rejects().summary().c_str() : "none",
        static_cast<unsigned long long>(dds_ ? dds_->commander_silences() : 0),
        heartbeat_max_gap_s_ * 1e3, last_heartbeat_s_,
        static_cast<unsigned long long>(interface_down_));
  }

 private:
  void script(double t) {
    if (t < kHoldAt) {
      master_.request(proto::RequestedMode::kIdle, o_.strategy, t == 0);
    } else if (t < o_.run_at_s) {
      master_.request(proto::RequestedMode::kHold, o_.strategy);
    } else if (t < o_.run_at_s + o_.run_for_s) {
      if (!master_.streaming()) {
        // The sinusoid in closed form (exact at every sample); other shapes as their points.
        const hmpc::trajectory::TargetSpec& target = o_.target;
        if (target.shape == hmpc::trajectory::TargetShape::kSine) {
          master_.stream_sinusoid(target.amplitude, target.frequency_hz, target.offset, t);
        } else {
          master_.stream_trajectory(o_.target_points.data(), o_.target_points.size(), t, t);
        }
        run_start_s_ = t;
      }
      master_.request(proto::RequestedMode::kRun, o_.strategy);
    } else if (master_.streaming()) {
      master_.stop_streaming();
      master_.request(proto::RequestedMode::kHold, o_.strategy);
      run_stop_s_ = t;
    }
  }

  // Repeated commands (a commander's heartbeat) are logged when they change something.
  void on_command(const hmpc::dds::ModeCommandSample& c) {
    ++dds_commands_;
    if (c.mode != master_.requested_mode() || c.strategy != master_.requested_strategy() ||
        c.clear_faults) {
      std::fprintf(stderr, "%s: DDS command %u at %.3f s: %s %s%s\n", kProgram,
                   unsigned(c.sequence_number), now_s_,
                   proto::value_name(proto::kRequestedModeValues, std::uint32_t(c.mode)),
                   proto::value_name(proto::kStrategyValues, std::uint32_t(c.strategy)),
                   c.clear_faults ? ", clearing faults" : "");
    }
    if (c.mode == proto::RequestedMode::kRun && master_.requested_mode() != c.mode) {
      run_start_s_ = now_s_;
    }
    master_.request(c.mode, c.strategy, c.clear_faults);
    // Idle and hold drop the target; run without one holds the present angle (the board holds
    // where it is when it has no samples).
    if (c.mode != proto::RequestedMode::kRun) master_.stop_streaming();
  }

  // A target that starts later than now begins at the joint's present angle: that first
  // segment must respect the speed limit too.
  hmpc::dds::Verdict on_trajectory(const hmpc::dds::TrajectoryView& view) {
    const auto& limits = hmpc::dds::forearm_joint_limits();
    trajectory_.clear();
    if (view.points[0].time_s > 0) {
      trajectory_.push_back({0, double(master_.report().joint.theta), 0, false});
      const double speed =
          std::abs(view.points[0].position - trajectory_[0].position) / view.points[0].time_s;
      if (speed > limits.max_speed) {
        char detail[160];
        std::snprintf(detail, sizeof detail,
                      "reaching points[0] from the present angle %.3f rad takes %.2f rad/s, "
                      "beyond the joint's %.2f rad/s",
                      trajectory_[0].position, speed, limits.max_speed);
        return hmpc::dds::Verdict::reject(hmpc::dds::Rejection::kRateLimit, detail);
      }
    }
    trajectory_.insert(trajectory_.end(), view.points, view.points + view.count);
    const double t0 = now_s_ + view.start_delay_s;
    if (!master_.stream_trajectory(trajectory_.data(), trajectory_.size(), t0, now_s_)) {
      return hmpc::dds::Verdict::reject(hmpc::dds::Rejection::kTooLarge,
                                        "more points than the host holds");
    }
    ++dds_trajectories_;
    std::fprintf(stderr, "%s: DDS trajectory of %zu points over %.3f s at %.3f s\n", kProgram,
                 view.count, view.points[view.count - 1].time_s, now_s_);
    return hmpc::dds::Verdict::accept();
  }

  void on_weights(const proto::CostWeights& w) {
    ++dds_weights_;
    std::fprintf(stderr,
                 "%s: DDS cost weights at %.3f s (0 keeps the board's): w_theta %g w_p %g "
                 "w_tau %g w_v %g\n",
                 kProgram, now_s_, double(w.w_theta), double(w.w_p), double(w.w_tau),
                 double(w.w_v));
    master_.send_cost_weights(w);
  }

  // The commander of a run went silent: hold where the arm is.
  void on_commander_silent() {
    if (master_.requested_mode() != proto::RequestedMode::kRun) return;
    std::fprintf(stderr, "%s: commander silent at %.3f s: holding\n", kProgram, now_s_);
    master_.stop_streaming();
    master_.request(proto::RequestedMode::kHold, master_.requested_strategy());
    run_stop_s_ = now_s_;
  }

  // The last heartbeat that reached the bus intact, and the longest interval between such
  // heartbeats while the host asked for hold or run, the modes in which the board's heartbeat
  // watchdog runs: the board must fault exactly when that interval exceeds its timeout.
  void on_intact_heartbeat(const proto::ModeCommand& m, double t) {
    const bool active =
        m.mode == proto::RequestedMode::kHold || m.mode == proto::RequestedMode::kRun;
    if (active && last_active_heartbeat_s_ >= 0) {
      heartbeat_max_gap_s_ = std::max(heartbeat_max_gap_s_, t - last_active_heartbeat_s_);
    }
    last_active_heartbeat_s_ = active ? t : -1;
    last_heartbeat_s_ = t;
  }

  void on_telemetry() {
    const auto& r = master_.report();
    const bool running = r.status.mode == proto::BoardMode::kRun;
    if (running && r.telemetry.status != proto::SolveStatusCode::kNoSolve)
      solve_times_.add(r.telemetry.solve_time_us);
    const double theta_d = master_.streaming() ? master_.target_angle(now_s_) : NAN;
    if (log_) {
      std::fprintf(log_, "%.3f,%s,%s,%u,%.5f,%.5f,%.4f,%.4f,%.4f,%.4f,%u,%u,%u,%u\n", now_s_,
                   proto::value_name(proto::kBoardModeValues, std::uint32_t(r.status.mode)),
                   proto::value_name(proto::kStrategyValues, std::uint32_t(r.status.strategy)),
                   unsigned(r.status.faults), r.joint.theta, theta_d, r.outputs.v_p, r.outputs.v_m,
                   r.outputs.tau_p, r.outputs.tau_m, unsigned(r.telemetry.status),
                   unsigned(r.telemetry.coarse_iterations), unsigned(r.telemetry.fine_iterations),
                   unsigned(r.telemetry.solve_time_us));
    }
    if (dds_) {
      hmpc::dds::ForearmStateSample s;
      s.theta = r.joint.theta;
      s.theta_dot = r.joint.theta_dot;
      hmpc::dds::ForearmTelemetrySample& m = s.telemetry;
      m.mode = r.status.mode;
      m.faults = r.status.faults;
      m.strategy = r.status.strategy;
      m.solve_status = r.telemetry.status;
      m.coarse_iterations = r.telemetry.coarse_iterations;
      m.fine_iterations = r.telemetry.fine_iterations;
      m.solve_time_us = r.telemetry.solve_time_us;
      m.theta_d = std::isfinite(theta_d) ? theta_d : r.joint.theta;
      m.tracking_error = r.telemetry.tracking_error;
      m.pressure_pa = r.joint.pressure * 1e6;  // the protocol's MPa
      m.v_p = r.outputs.v_p;
      m.v_m = r.outputs.v_m;
      m.tau_p = r.outputs.tau_p;
      m.tau_m = r.outputs.tau_m;
      s.rejected_frames = r.status.rejected_frames;
      s.watchdog_trips = r.status.watchdog_trips;
      s.solver_failures = r.status.solver_failures;
      s.overruns = r.status.overruns;
      dds_->publish(s);
    }
  }

  const Options& o_;
  SocketCan& can_;
  hmpc::dds::ForearmDdsBridge* dds_;
  std::FILE* log_;
  ForearmCanMaster master_;
  proto::Sender sender_;
  proto::Receiver sync_receiver_;
  hmpc::platform::FaultInjector faults_;
  double now_s_ = 0;
  double run_start_s_ = -1, run_stop_s_ = -1;
  double last_active_heartbeat_s_ = -1, heartbeat_max_gap_s_ = 0, last_heartbeat_s_ = -1;
  std::uint64_t frames_sent_ = 0, frames_received_ = 0, board_report_frames_ = 0;
  std::uint64_t interface_down_ = 0;  // sends and receives that found the interface down
  std::uint64_t dds_commands_ = 0, dds_trajectories_ = 0, dds_weights_ = 0;
  std::vector<hmpc::trajectory::TrajectoryPoint> trajectory_;  // reserved: no allocation per target
  const hmpc::dds::ForearmDdsHandlers dds_handlers_{
      [this](const hmpc::dds::ModeCommandSample& c) { on_command(c); },
      [this](const hmpc::dds::TrajectoryView& v) { return on_trajectory(v); },
      [this] { on_commander_silent(); }, [this](const proto::CostWeights& w) { on_weights(w); }};
  SolveTimeHistogram solve_times_;
};

enum class End { kDone, kSignal, kFailure };

End run(const Options& o, SocketCan& can, Host& host, int signal_fd, std::string& error) {
  int timer = -1;
  if (!o.lockstep) {
    timer = ::timerfd_create(CLOCK_MONOTONIC, TFD_CLOEXEC);
    const itimerspec every_ms{{0, 1'000'000}, {0, 1'000'000}};
    if (timer < 0 || ::timerfd_settime(timer, 0, &every_ms, nullptr) < 0) {
      error = std::string("timerfd: ") + std::strerror(errno);
      return End::kFailure;
    }
  }
  pollfd fds[3] = {{can.native_handle(), POLLIN, 0}, {signal_fd, POLLIN, 0}, {timer, POLLIN, 0}};
  std::uint64_t ticks = 0;
  End end = End::kDone;
  const auto due = [&](std::uint64_t tick) {
    return o.duration_s <= 0 || tick * 1e-3 < o.duration_s;
  };
  while (due(ticks)) {
    if (::poll(fds, timer >= 0 ? 3 : 2, -1) < 0) {
      if (errno == EINTR) continue;
      error = std::string("poll: ") + std::strerror(errno);
      end = End::kFailure;
      break;
    }
    if (fds[1].revents & POLLIN) {
      end = End::kSignal;
      break;
    }
    if (fds[0].revents & POLLIN) {
      CanFrame raw;
      CanResult r;
      while ((r = can.receive(raw, std::chrono::microseconds(0))).ok()) {
        std::uint32_t sync_tick = 0;
        if (host.on_frame(raw, sync_tick) && o.lockstep) {
          ticks = sync_tick;
          if (!due(ticks)) break;
          if (!host.tick(1e-3 * double(sync_tick), error)) return End::kFailure;
          ++ticks;
        }
      }
      if (r.status == CanStatus::kInterfaceDown) {
        host.note_interface_down();
      } else if (r.status != CanStatus::kTimeout && !r.ok()) {
        error = "receiving failed: " + describe(r);
        end = End::kFailure;
        break;
      }
    }
    if (timer >= 0 && (fds[2].revents & POLLIN)) {
      std::uint64_t expirations = 0;
      if (::read(timer, &expirations, sizeof expirations) != sizeof expirations) continue;
      for (std::uint64_t i = 0; i < expirations && due(ticks); ++i, ++ticks) {
        if (!host.tick(1e-3 * double(ticks), error)) {
          end = End::kFailure;
          break;
        }
      }
      if (end == End::kFailure) break;
    }
  }
  if (timer >= 0) ::close(timer);
  return end;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  std::string error;
  const auto outcome = parse(argc, argv, options, error);
  if (outcome != hmpc::cli::ParseOutcome::kRun) {
    return hmpc::cli::exit_status(outcome, kProgram, error, print_usage);
  }

  const int signal_fd = hmpc::platform::stop_signal_descriptor(error);
  if (signal_fd < 0) {
    std::fprintf(stderr, "%s: %s\n", kProgram, error.c_str());
    return 1;
  }
  SocketCan can;
  if (!hmpc::platform::open_node_bus<hmpc::forearm_protocol::Description>(
          can, options.interface, options.node, true, error)) {
    std::fprintf(stderr, "%s: %s\n", kProgram, error.c_str());
    return 1;
  }

  std::unique_ptr<hmpc::dds::ForearmDdsBridge> dds;
  if (options.dds_domain >= 0) {
    try {
      dds = std::make_unique<hmpc::dds::ForearmDdsBridge>(
          std::uint32_t(options.dds_domain), options.node,
          options.dds_loopback ? hmpc::dds::loopback_config() : std::string());
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s: DDS: %s\n", kProgram, e.what());
      return 1;
    }
  }

  std::FILE* log = nullptr;
  if (!options.log_path.empty()) {
    log = hmpc::platform::open_csv_log(
        options.log_path,
        "time_s,mode,strategy,faults,theta_rad,theta_d_rad,v_p_V,v_m_V,tau_p_Nm,tau_m_Nm,"
        "solve_status,coarse_iterations,fine_iterations,solve_time_us",
        error);
    if (!log) {
      std::fprintf(stderr, "%s: %s\n", kProgram, error.c_str());
      return 1;
    }
  }

  std::printf("%s: node %u on %s, %s%s: ready\n", kProgram, unsigned(options.node),
              options.interface.c_str(), options.lockstep ? "lock-step" : "real time, 1 kHz",
              dds ? ", DDS bridge up" : "");
  std::fflush(stdout);

  Host host(options, can, dds.get(), log);
  const double start = monotonic_seconds();
  const End end = run(options, can, host, signal_fd, error);
  int status = 0;
  if (end == End::kFailure) {
    std::fprintf(stderr, "%s: %s\n", kProgram, error.c_str());
    status = 1;
  }
  if (log && std::fclose(log) != 0) {
    std::fprintf(stderr, "%s: writing the log '%s' failed\n", kProgram, options.log_path.c_str());
    status = 1;
  }
  host.print_summary(monotonic_seconds() - start);
  ::close(signal_fd);
  return status;
}
