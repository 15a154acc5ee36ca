// hmpc-forearm-plant: the HIL plant node. The forearm in Simbody (simbody_forearm.hpp), stepped
// at 1 ms, on a SocketCAN interface with the board's protocol: each step it sends a Sensor
// frame (theta, theta', P, with optional noise, transport delay and faults) and applies the
// board's latest valid ActuatorCommand. Two ways to pace it:
//   real time (default)  a 1 kHz CLOCK_MONOTONIC timer; the board runs on its own timer.
//                        Reports the real-time factor and the steps that missed their tick.
//   --lockstep           after each Sensor frame a Sync (never faulted: it stands for the
//                        board's own clock), then the step waits until the board has answered
//                        with its ActuatorCommand; with --wait-host, every 10th step also waits
//                        for the host's heartbeat, so the three programs run deterministically.
// At the end it prints a summary of key=value pairs, including the joint's range and whether
// it stayed within the mechanical stops.
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
#include <random>
#include <string>
#include <vector>

#include "../simbody_forearm.hpp"
#include "hmpc/platform/linux/bus_program.hpp"
#include "hmpc/platform/linux/frame_faults.hpp"
#include "options.hpp"

namespace {

using namespace hmpc::hil;
using namespace hmpc::hil::plant_node;
using hmpc::platform::FaultAction;
using hmpc::platform::FaultCounters;
using hmpc::platform::FaultInjector;
namespace proto = hmpc::forearm_protocol;
using hmpc::platform::CanFrame;
using hmpc::platform::CanResult;
using hmpc::platform::CanStatus;
using hmpc::platform::describe;
using hmpc::platform::monotonic_seconds;
using hmpc::platform::SocketCan;

constexpr const char* kProgram = "hmpc-forearm-plant";
constexpr int kHeartbeatPeriodTicks = 10;  // the host's ModeCommand period (protocol)
constexpr double kBoardTimeoutS = 5;       // lock-step: no answer to a Sync this long -> fail
// Heartbeats missed in a row (each waited for --host-timeout) before the plant stops waiting
// for the host: a lost heartbeat costs one timeout, a host that went away only a few.
constexpr int kHostMissesBeforeGivingUp = 3;
// How far the joint may pass a stop before the run counts as having left its limits: the
// stops' compression when the vented arm falls onto them from the top of the range (~0.03 rad,
// forearm.hpp) with a margin.
constexpr double kStopTolerance = 0.05;  // rad

struct Summary {
  std::uint64_t steps = 0;
  std::uint64_t sensor_frames = 0, syncs = 0;
  std::uint64_t actuator_commands = 0, rejected_commands = 0;
  std::uint64_t host_heartbeats = 0;
  std::uint64_t deadline_misses = 0;  // real time: steps taken after their tick had passed
  std::uint64_t host_waits_timed_out = 0;
  std::uint64_t commands_dropped = 0;  // --drop-commands-percent
  std::uint64_t interface_down = 0;    // Sensor frames not sent: the interface was down
  bool host_given_up = false;
  double theta_min = 1e9, theta_max = -1e9;
  double wall_s = 0;
};

// The plant, its bus and its log: one simulated millisecond per step().
class PlantNode {
 public:
  PlantNode(const Options& options, SimbodyForearm& plant, SocketCan& can, std::FILE* log)
      : options_(options), plant_(plant), can_(can), log_(log), sender_(options.node),
        from_board_(options.node), faults_(options.sensor_faults),
        noise_random_(options.sensor_faults.seed ^ 0x5eed5eedULL),
        command_loss_random_(options.sensor_faults.seed ^ 0xc0de105eULL),
        delayed_(std::size_t(options.sensor_delay_ms) + 1) {
    for (auto& reading : delayed_) reading = plant_.state();
  }

  // Sends this step's Sensor frame (and Sync, in lock-step). False when the bus fails.
  bool send_sensor(std::string& error) {
    const double t = plant_.time();
    if (options_.die_at_s >= 0 && t >= options_.die_at_s) ::raise(SIGKILL);
    delayed_[head_] = measured(plant_.state());
    head_ = (head_ + 1) % delayed_.size();
    const ForearmPlantState& reading = delayed_[head_];  // the oldest: sensor_delay_ms ago
    proto::Frame frame;
    const proto::SensorSample sample{float(reading.theta), float(reading.theta_dot),
                                     float(reading.pressure_bar / 10), 0};  // bar -> MPa
    if (sender_.encode(sample, frame) == proto::EncodeResult::kOk &&
        faults_.apply(t, frame) == FaultAction::kPass) {
      if (!send(frame, error)) return false;
      ++summary_.sensor_frames;
    }
    if (options_.lockstep) {
      const CanResult sent = hmpc::platform::send_message(
          can_, sender_, proto::Sync{std::uint32_t(summary_.steps), 0});
      if (!sent.ok()) {
        error = "sending Sync failed: " + describe(sent);
        return false;
      }
      ++summary_.syncs;
    }
    return true;
  }

  // Takes one received frame: the board's ActuatorCommand (validated: a rejected one leaves
  // the previous command applied) or the host's heartbeat. Returns which it was.
  enum class Received { kOther, kActuatorCommand, kHeartbeat };
  Received take(const CanFrame& raw) {
    proto::Frame frame;
    proto::FrameType type;
    proto::NodeId node;
    if (!hmpc::platform::to_protocol_frame(raw, frame) || !proto::identify(frame.id, type, node) ||
        node != options_.node) {
      return Received::kOther;
    }
    if (type == proto::FrameType::kModeCommand) {
      ++summary_.host_heartbeats;
      return Received::kHeartbeat;
    }
    if (type != proto::FrameType::kActuatorCommand) return Received::kOther;
    if (options_.drop_commands_fraction > 0 &&
        uniform_(command_loss_random_) < options_.drop_commands_fraction) {
      ++summary_.commands_dropped;  // lost on the way: the actuators keep the last command
      return Received::kActuatorCommand;
    }
    proto::ActuatorCommand command;
    if (from_board_.decode(frame, command) == proto::DecodeResult::kOk) {
      command_ = command;
      ++summary_.actuator_commands;
    } else {
      ++summary_.rejected_commands;
    }
    return Received::kActuatorCommand;  // a step's answer, even when garbled
  }

  // Advances the plant 1 ms under the latest command and logs the step.
  void step() {
    plant_.step(command_.v_p, command_.v_m);
    const ForearmPlantState x = plant_.state();
    summary_.theta_min = std::min(summary_.theta_min, x.theta);
    summary_.theta_max = std::max(summary_.theta_max, x.theta);
    ++summary_.steps;
    if (log_) {
      std::fprintf(log_, "%.3f,%.6f,%.6f,%.6f,%.5f,%.5f,%.5f,%.5f\n", plant_.time(), x.theta,
                   x.theta_dot, x.pressure_bar, plant_.applied_v_p(), plant_.applied_v_m(),
                   plant_.pam_torque(), plant_.motor_torque());
    }
  }

  Summary& summary() { return summary_; }
  const FaultCounters& faults() const { return faults_.counters(); }

 private:
  ForearmPlantState measured(ForearmPlantState x) {
    if (options_.noise_scale > 0) {
      const SensorNoise sigma;
      x.theta += options_.noise_scale * sigma.theta * gaussian_(noise_random_);
      x.theta_dot += options_.noise_scale * sigma.theta_dot * gaussian_(noise_random_);
      x.pressure_bar += options_.noise_scale * sigma.pressure_bar * gaussian_(noise_random_);
      x.pressure_bar = std::max(0.0, x.pressure_bar);
    }
    return x;
  }

  bool send(const proto::Frame& frame, std::string& error) {
    const CanResult sent = can_.send(hmpc::platform::to_can_frame(frame));
    if (sent.ok()) return true;
    if (sent.status == CanStatus::kInterfaceDown) {  // the bus went away: the board will notice
      ++summary_.interface_down;
      return true;
    }
    error = "sending a Sensor frame failed: " + describe(sent);
    return false;
  }

  const Options& options_;
  SimbodyForearm& plant_;
  SocketCan& can_;
  std::FILE* log_;
  proto::Sender sender_;
  proto::Receiver from_board_;
  FaultInjector faults_;
  std::mt19937_64 noise_random_;
  std::normal_distribution<double> gaussian_{0.0, 1.0};
  std::mt19937_64 command_loss_random_;
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
  std::vector<ForearmPlantState> delayed_;  // ring of readings, sensor_delay_ms + 1 long
  std::size_t head_ = 0;
  proto::ActuatorCommand command_{};  // until the board speaks: valve closed at 0 V, motor off
  Summary summary_;
};

bool stop_requested(int signal_fd) {
  pollfd fd{signal_fd, POLLIN, 0};
  return ::poll(&fd, 1, 0) > 0;
}

// Receives frames until `done` says the awaited one came, or until the timeout.
template <class Done>
bool await(SocketCan& can, PlantNode& node, double timeout_s, Done&& done, std::string& error) {
  const double give_up = monotonic_seconds() + timeout_s;
  for (;;) {
    const double left = give_up - monotonic_seconds();
    if (left <= 0) return false;
    CanFrame raw;
    const CanResult r = can.receive(raw, std::chrono::microseconds(long(left * 1e6) + 1));
    if (r.status == CanStatus::kTimeout) return false;
    if (!r.ok()) {
      error = "receiving failed: " + describe(r);
      return false;
    }
    if (done(node.take(raw))) return true;
  }
}

enum class End { kDone, kSignal, kFailure };

End run_lockstep(const Options& o, SocketCan& can, PlantNode& node, int signal_fd,
                 std::string& error) {
  const std::uint64_t steps = std::uint64_t(std::llround(o.duration_s * 1e3));
  bool waiting_for_host = o.wait_host;
  int host_misses = 0;
  for (std::uint64_t k = 0; steps == 0 || k < steps; ++k) {
    if (stop_requested(signal_fd)) return End::kSignal;
    if (!node.send_sensor(error)) return End::kFailure;
    using R = PlantNode::Received;
    bool answered = false, host_seen = !(waiting_for_host && k % kHeartbeatPeriodTicks == 0);
    const auto note = [&](R r) {
      answered = answered || r == R::kActuatorCommand;
      host_seen = host_seen || r == R::kHeartbeat;
    };
    const auto board_answered = [&](R r) {
      note(r);
      return answered;
    };
    const auto host_heard = [&](R r) {
      note(r);
      return host_seen;
    };
    if (!await(can, node, kBoardTimeoutS, board_answered, error)) {
      if (error.empty()) {
        error = "the board did not answer Sync " + std::to_string(k) + " within " +
                std::to_string(int(kBoardTimeoutS)) + " s";
      }
      return End::kFailure;
    }
    if (!host_seen) {
      host_seen = await(can, node, o.host_timeout_s, host_heard, error);
      if (!error.empty()) return End::kFailure;
      if (!host_seen) ++node.summary().host_waits_timed_out;
    }
    if (waiting_for_host && k % kHeartbeatPeriodTicks == 0) {
      host_misses = host_seen ? 0 : host_misses + 1;
      if (host_misses == kHostMissesBeforeGivingUp) {
        std::fprintf(stderr,
                     "%s: no host heartbeat for %d periods (step %llu): no longer "
                     "waiting for the host\n",
                     kProgram, host_misses, static_cast<unsigned long long>(k));
        waiting_for_host = false;
        node.summary().host_given_up = true;
      }
    }
    node.step();
  }
  return End::kDone;
}

End run_real_time(const Options& o, SocketCan& can, PlantNode& node, int signal_fd,
                  std::string& error) {
  const int timer = ::timerfd_create(CLOCK_MONOTONIC, TFD_CLOEXEC);
  const itimerspec every_ms{{0, 1'000'000}, {0, 1'000'000}};
  if (timer < 0 || ::timerfd_settime(timer, 0, &every_ms, nullptr) < 0) {
    error = std::string("timerfd: ") + std::strerror(errno);
    if (timer >= 0) ::close(timer);
    return End::kFailure;
  }
  const std::uint64_t steps = std::uint64_t(std::llround(o.duration_s * 1e3));
  pollfd fds[3] = {{timer, POLLIN, 0}, {signal_fd, POLLIN, 0}, {can.native_handle(), POLLIN, 0}};
  End end = End::kDone;
  while (steps == 0 || node.summary().steps < steps) {
    if (::poll(fds, 3, -1) < 0) {
      if (errno == EINTR) continue;
      error = std::string("poll: ") + std::strerror(errno);
      end = End::kFailure;
      break;
    }
    if (fds[1].revents & POLLIN) {
      end = End::kSignal;
      break;
    }
    if (fds[2].revents & POLLIN) {
      CanFrame raw;
      while (can.receive(raw, std::chrono::microseconds(0)).ok()) node.take(raw);
    }
    if ((fds[0].revents & POLLIN) == 0) continue;
    std::uint64_t expirations = 0;
    if (::read(timer, &expirations, sizeof expirations) != sizeof expirations) continue;
    node.summary().deadline_misses += expirations - 1;
    for (std::uint64_t i = 0; i < expirations && (steps == 0 || node.summary().steps < steps);
         ++i) {
      node.step();
      if (!node.send_sensor(error)) {
        ::close(timer);
        return End::kFailure;
      }
    }
  }
  ::close(timer);
  return end;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  std::string error;
  const auto outcome = parse_options(argc, argv, options, error);
  if (outcome != hmpc::cli::ParseOutcome::kRun) {
    return hmpc::cli::exit_status(outcome, kProgram, error, print_usage);
  }

  const int signal_fd = hmpc::platform::stop_signal_descriptor(error);
  if (signal_fd < 0) {
    std::fprintf(stderr, "%s: %s\n", kProgram, error.c_str());
    return 1;
  }

  const hmpc::forearm::Parameters<double> model{};
  const ForearmPlantState initial{options.theta0, 0.0,
                                  hmpc::forearm::equilibrium_pressure(model, options.theta0)};
  std::unique_ptr<SimbodyForearm> plant;
  try {
    plant = std::make_unique<SimbodyForearm>(model, options.mismatch, initial);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", kProgram, e.what());
    return 2;
  }

  SocketCan can;
  if (!hmpc::platform::open_node_bus<proto::Description>(can, options.interface, options.node,
                                                         false, error)) {
    std::fprintf(stderr, "%s: %s\n", kProgram, error.c_str());
    return 1;
  }
  std::FILE* log = nullptr;
  if (!options.log_path.empty()) {
    log = hmpc::platform::open_csv_log(
        options.log_path,
        "time_s,theta_rad,theta_dot_rad_s,pressure_bar,v_p_V,v_m_V,tau_p_Nm,tau_m_Nm", error);
    if (!log) {
      std::fprintf(stderr, "%s: %s\n", kProgram, error.c_str());
      return 1;
    }
  }

  std::printf("%s: node %u on %s, %s, mismatch mass x%.3g friction x%.3g T_p x%.3g: ready\n",
              kProgram, unsigned(options.node), options.interface.c_str(),
              options.lockstep ? "lock-step" : "real time, 1 kHz", options.mismatch.mass_scale,
              options.mismatch.friction_scale, options.mismatch.pam_time_constant_scale);
  std::fflush(stdout);

  PlantNode node(options, *plant, can, log);
  const double start = monotonic_seconds();
  const End end = options.lockstep ? run_lockstep(options, can, node, signal_fd, error)
                                   : run_real_time(options, can, node, signal_fd, error);
  Summary& s = node.summary();
  s.wall_s = monotonic_seconds() - start;

  int status = 0;
  if (end == End::kFailure) {
    std::fprintf(stderr, "%s: %s\n", kProgram, error.c_str());
    status = 1;
  }
  if (log && (std::fclose(log) != 0)) {
    std::fprintf(stderr, "%s: writing the log '%s' failed\n", kProgram, options.log_path.c_str());
    status = 1;
  }
  const auto& p = plant->plant_parameters();
  const bool within_stops = s.steps == 0 || (s.theta_min >= p.stop_lower - kStopTolerance &&
                                             s.theta_max <= p.stop_upper + kStopTolerance);
  const FaultCounters& f = node.faults();
  const double sim_s = 1e-3 * double(s.steps);
  std::printf(
      "%s: summary steps=%llu sim_seconds=%.3f wall_seconds=%.3f real_time_factor=%.3f "
      "deadline_misses=%llu sensor_frames=%llu syncs=%llu sensor_dropped=%llu "
      "sensor_corrupted=%llu sensor_silenced=%llu actuator_commands=%llu rejected_commands=%llu "
      "host_heartbeats=%llu host_waits_timed_out=%llu host_given_up=%d plant_rejected_inputs=%llu "
      "commands_dropped=%llu interface_down=%llu "
      "theta_min=%.4f "
      "theta_max=%.4f within_stops=%d last_v_p=%g last_v_m=%g end=%s\n",
      kProgram, static_cast<unsigned long long>(s.steps), sim_s, s.wall_s,
      s.wall_s > 0 ? sim_s / s.wall_s : 0.0, static_cast<unsigned long long>(s.deadline_misses),
      static_cast<unsigned long long>(s.sensor_frames), static_cast<unsigned long long>(s.syncs),
      static_cast<unsigned long long>(f.dropped), static_cast<unsigned long long>(f.corrupted),
      static_cast<unsigned long long>(f.silenced),
      static_cast<unsigned long long>(s.actuator_commands),
      static_cast<unsigned long long>(s.rejected_commands),
      static_cast<unsigned long long>(s.host_heartbeats),
      static_cast<unsigned long long>(s.host_waits_timed_out), s.host_given_up ? 1 : 0,
      static_cast<unsigned long long>(plant->rejected_commands()),
      static_cast<unsigned long long>(s.commands_dropped),
      static_cast<unsigned long long>(s.interface_down), s.steps ? s.theta_min : 0.0,
      s.steps ? s.theta_max : 0.0, within_stops ? 1 : 0, plant->applied_v_p(), plant->applied_v_m(),
      end == End::kDone     ? "duration"
      : end == End::kSignal ? "signal"
                            : "failure");
  ::close(signal_fd);
  return status;
}
