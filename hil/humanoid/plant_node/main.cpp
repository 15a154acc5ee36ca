// hmpc-humanoid-plant: the humanoid HIL plant node. The biped in Simbody with hydraulic legs
// (hydraulic_humanoid.hpp), stepped at 1 ms, wired as the robot is (hmpc/humanoid/
// hydraulic_legs.hpp): each leg's joint board (nodes 0 and 1) gets its four joints' encoder,
// velocity and load cell and their chamber pressures on the HIL's I/O bus every step, then a
// Sync; the plant applies each board's latest ValveDrive. The torso IMU (node 2) sends its mean
// reading of the last 6 ms on the robot bus, as the host reads it. Two ways to pace it:
//   real time (default)  a 1 kHz CLOCK_MONOTONIC timer; reports its real-time factor and the
//                        steps that missed their tick.
//   --lockstep           the step waits until both boards have answered the Sync with their
//                        ValveDrive; with --wait-host, once the host is heard, also for its
//                        heartbeat every 10 ms and its torque references every 6 ms.
// A board that does not answer within --host-timeout is stepped without (its valve drivers
// centre its valves after 5 ms without a command, as a driver's watchdog does): a board may
// restart. At the end it prints a summary of key=value pairs.
#include <poll.h>
#include <signal.h>
#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>

#include "hmpc/humanoid/hydraulic_legs.hpp"
#include "hmpc/humanoid/sensors.hpp"
#include "hmpc/humanoid/stance.hpp"
#include "hmpc/platform/linux/bus_program.hpp"
#include "hmpc/protocol/joint_protocol.hpp"
#include "options.hpp"

namespace {

using namespace hmpc::hil;
using namespace hmpc::hil::humanoid_plant;
namespace proto = hmpc::joint_protocol;
namespace hm = hmpc::humanoid;
using hmpc::platform::CanFrame;
using hmpc::platform::CanResult;
using hmpc::platform::CanStatus;
using hmpc::platform::describe;
using hmpc::platform::FaultAction;
using hmpc::platform::FaultInjector;
using hmpc::platform::monotonic_seconds;
using hmpc::platform::SocketCan;

constexpr const char* kProgram = "hmpc-humanoid-plant";
constexpr int kBoards = hm::kLegBoards;
constexpr int kHeartbeatPeriodTicks = 10;  // the host's ModeCommand period (protocol)
constexpr int kReferencePeriodTicks = 6;   // its TorqueReference period (protocol)
constexpr int kImuPeriodTicks = 6;         // the IMU's frames (protocol)
// A valve driver centres its valve when its board's commands stop for this long (our choice:
// five missed 1 ms commands, the boards' own sensor timeout).
constexpr int kValveDriverTimeoutTicks = 5;
// Host misses in a row (each waited for --host-timeout) before the plant stops waiting for it.
constexpr int kHostMissesBeforeGivingUp = 3;
// Encoder mounting offsets drawn within +-this (rad): zeroing must find them.
constexpr double kMountingOffsetRange = 0.3;

struct Summary {
  std::uint64_t steps = 0, syncs = 0, sensor_frames = 0, imu_frames = 0;
  std::uint64_t valve_drives = 0, rejected_frames = 0;
  std::uint64_t board_waits_timed_out = 0, valves_centred_by_drivers = 0;
  std::uint64_t host_heartbeats = 0, host_references = 0, host_waits_timed_out = 0;
  std::uint64_t deadline_misses = 0, interface_down = 0;
  bool host_given_up = false;
  double min_height = 1e9, max_tilt = 0;  // torso origin height [m], tilt from upright [rad]
  double wall_s = 0;
};

class PlantNode {
 public:
  PlantNode(const Options& o, SimbodyHydraulicHumanoid& plant, const hm::BasicState<0>& start,
            SocketCan& robot, SocketCan& io, std::FILE* log)
      : o_(o), plant_(plant), robot_(robot), io_(io), log_(log),
        sensors_(plant.model(), sensor_config(o)), imu_sender_(proto::NodeId(hm::kImuNode)),
        imu_faults_(o.imu_faults), sensor_faults_(o.sensor_faults), noise_(o.seed ^ 0x6e6f6973ULL) {
    for (int b = 0; b < kBoards; ++b) {
      board_sender_[std::size_t(b)] = proto::Sender(proto::NodeId(b));
      from_board_[std::size_t(b)] = proto::Receiver(proto::NodeId(b));
    }
    std::mt19937_64 mounting(o.seed ^ 0x6d6f756eULL);
    std::uniform_real_distribution<double> offset(-kMountingOffsetRange, kMountingOffsetRange);
    for (double& m : mounting_) m = o.mounting_offsets ? offset(mounting) : 0.0;
    sensors_.start_at_rest(start.q);
    reading_ = sensors_.measure(start.q, start.v, hm::Velocity::Zero());
  }

  // Tick k's frames: each board's sensors on the I/O bus, the IMU's every 6 ms on the robot
  // bus, then the Sync (never faulted: it stands for the boards' clocks). False when a bus
  // fails.
  bool send_tick(std::uint64_t k, std::string& error) {
    const double t = plant_.time();
    if (o_.die_at_s >= 0 && t >= o_.die_at_s) ::raise(SIGKILL);
    const hm::JointVector tau = plant_.joint_torques();
    const auto actuators = plant_.actuators();
    for (int b = 0; b < kBoards; ++b) {
      proto::Sender& sender = board_sender_[std::size_t(b)];
      if (!send_joint_sensors(sender, b, tau, std::make_index_sequence<hm::kJointsPerBoard>{}, t,
                              error)) {
        return false;
      }
      proto::ChamberPressures01 p01;
      proto::ChamberPressures23 p23;
      for (int c = 0; c < 2; ++c) {
        const auto& low = actuators[std::size_t(hm::joint_of(b, c))];
        const auto& high = actuators[std::size_t(hm::joint_of(b, c + 2))];
        p01.p_a[std::size_t(c)] = pressure(low.pressure_a);
        p01.p_b[std::size_t(c)] = pressure(low.pressure_b);
        p23.p_a[std::size_t(c)] = pressure(high.pressure_a);
        p23.p_b[std::size_t(c)] = pressure(high.pressure_b);
      }
      if (!send_faulted(io_, sender, p01, sensor_faults_, t, error) ||
          !send_faulted(io_, sender, p23, sensor_faults_, t, error)) {
        return false;
      }
    }
    imu_sum_angular_ += reading_.imu.angular_velocity;
    imu_sum_force_ += reading_.imu.specific_force;
    if (++imu_samples_ == kImuPeriodTicks) {
      proto::ImuAngularVelocity gyro;
      proto::ImuLinearAcceleration accel;
      for (int i = 0; i < 3; ++i) {
        gyro.omega[std::size_t(i)] =
            float(std::clamp(imu_sum_angular_[i] / kImuPeriodTicks, -32.0, 32.0));
        accel.specific_force[std::size_t(i)] =
            float(std::clamp(imu_sum_force_[i] / kImuPeriodTicks, -160.0, 160.0));
      }
      imu_sum_angular_.setZero();
      imu_sum_force_.setZero();
      imu_samples_ = 0;
      if (!send_faulted(robot_, imu_sender_, gyro, imu_faults_, t, error) ||
          !send_faulted(robot_, imu_sender_, accel, imu_faults_, t, error)) {
        return false;
      }
      summary_.imu_frames += 2;
    }
    const CanResult sent =
        hmpc::platform::send_message(io_, sync_sender_, proto::Sync{std::uint32_t(k), 0});
    if (!sent.ok() && sent.status != CanStatus::kInterfaceDown) {
      error = "sending Sync failed: " + describe(sent);
      return false;
    }
    ++summary_.syncs;
    return true;
  }

  // One received frame: a board's ValveDrive (validated: a rejected one leaves the valves as
  // they were), or the host's heartbeat or torque reference to board 0.
  enum class Received { kOther, kValveDrive, kHeartbeat, kReference };
  Received take(const CanFrame& raw, bool from_io, int& board) {
    hmpc::protocol::Frame frame;
    proto::FrameType type{};
    proto::NodeId node = 0;
    if (!hmpc::platform::to_protocol_frame(raw, frame) || !proto::identify(frame.id, type, node) ||
        node >= kBoards) {
      return Received::kOther;
    }
    board = int(node);
    if (from_io && type == proto::FrameType::kValveDrive) {
      proto::ValveDrive drive;
      if (from_board_[node].decode(frame, drive) != proto::DecodeResult::kOk) {
        ++summary_.rejected_frames;
        return Received::kValveDrive;  // a step's answer, even when garbled
      }
      for (int c = 0; c < hm::kJointsPerBoard; ++c) {
        valves_[hm::joint_of(int(node), c)] = double(drive.u[std::size_t(c)]);
      }
      last_drive_step_[node] = summary_.steps;
      ++summary_.valve_drives;
      return Received::kValveDrive;
    }
    if (!from_io && type == proto::FrameType::kModeCommand) {
      if (node == 0) ++summary_.host_heartbeats;
      return node == 0 ? Received::kHeartbeat : Received::kOther;
    }
    if (!from_io && type == proto::FrameType::kTorqueReference) {
      ++summary_.host_references;
      return Received::kReference;
    }
    return Received::kOther;
  }

  // Advances the plant 1 ms under the latest valve commands, reads its sensors and logs.
  void step() {
    hm::JointVector u = valves_;
    for (int b = 0; b < kBoards; ++b) {
      if (summary_.steps - last_drive_step_[std::size_t(b)] < kValveDriverTimeoutTicks) continue;
      for (int c = 0; c < hm::kJointsPerBoard; ++c) u[hm::joint_of(b, c)] = 0.0;
      ++summary_.valves_centred_by_drivers;
    }
    plant_.step(u);
    ++summary_.steps;
    const hm::BasicState<0> x = plant_.state();
    reading_ = sensors_.measure(x.q, x.v, plant_.acceleration());
    summary_.min_height = std::min(summary_.min_height, x.q[2]);
    const Eigen::Quaterniond attitude(x.q[3], x.q[4], x.q[5], x.q[6]);
    const double up = (attitude.normalized() * hm::Vector3::UnitZ()).z();
    summary_.max_tilt = std::max(summary_.max_tilt, std::acos(std::clamp(up, -1.0, 1.0)));
    if (log_) write_log(x, u);
  }

  Summary& summary() { return summary_; }
  const hmpc::platform::FaultCounters& imu_faults() const { return imu_faults_.counters(); }
  const hmpc::platform::FaultCounters& sensor_faults() const { return sensor_faults_.counters(); }
  const std::array<double, hm::kJoints>& mounting() const { return mounting_; }

 private:
  static hm::SensorConfig sensor_config(const Options& o) {
    hm::SensorConfig c;
    c.seed = o.seed;
    return c;
  }

  float pressure(double pascal) {
    // Transducers read 0..32 MPa and saturate beyond (the model has no cavitation floor).
    return float(std::clamp((pascal + noise(SensorNoise{}.pressure)) * 1e-6, 0.0, 32.0));
  }
  double noise(double sigma) {
    return o_.noise_scale > 0 ? o_.noise_scale * sigma * gaussian_(noise_) : 0.0;
  }

  template <std::size_t... kChannels>
  bool send_joint_sensors(proto::Sender& sender, int board, const hm::JointVector& tau,
                          std::index_sequence<kChannels...>, double t, std::string& error) {
    return (send_joint_sensor<kChannels>(sender, board, tau, t, error) && ...);
  }
  template <std::size_t kChannel>
  bool send_joint_sensor(proto::Sender& sender, int board, const hm::JointVector& tau, double t,
                         std::string& error) {
    const int j = hm::joint_of(board, int(kChannel));
    proto::JointSensor<kChannel> s;
    s.theta = float(std::clamp(reading_.angles[j] + mounting_[std::size_t(j)], -3.1416, 3.1416));
    s.theta_dot = float(std::clamp(reading_.rates[j], -20.0, 20.0));
    s.tau = float(std::clamp(tau[j] + noise(SensorNoise{}.torque), -200.0, 200.0));
    return send_faulted(io_, sender, s, sensor_faults_, t, error);
  }

  template <class Message>
  bool send_faulted(SocketCan& bus, proto::Sender& sender, const Message& m, FaultInjector& faults,
                    double t, std::string& error) {
    hmpc::protocol::Frame f;
    if (sender.encode(m, f) != proto::EncodeResult::kOk) return true;  // out of range: not sent
    if (faults.apply(t, f) == FaultAction::kDrop) return true;
    const CanResult sent = bus.send(hmpc::platform::to_can_frame(f));
    if (sent.ok()) {
      if (&bus == &io_) ++summary_.sensor_frames;
      return true;
    }
    if (sent.status == CanStatus::kInterfaceDown) {  // the bus went away: the boards notice
      ++summary_.interface_down;
      return true;
    }
    error = "sending a frame failed: " + describe(sent);
    return false;
  }

  void write_log(const hm::BasicState<0>& x, const hm::JointVector& u) {
    const hm::JointVector tau = plant_.joint_torques();
    double left = 0, right = 0;
    const auto forces = plant_.sole_forces();
    for (int i = 0; i < hm::kSolePoints; ++i)
      (i < hm::kFootPoints ? left : right) += forces[std::size_t(i)].z();
    std::fprintf(log_, "%.3f", plant_.time());
    for (int i = 0; i < hm::kConfigurationSize; ++i) std::fprintf(log_, ",%.6f", x.q[i]);
    for (int i = 0; i < hm::kDofs; ++i) std::fprintf(log_, ",%.5f", x.v[i]);
    for (int j = 0; j < hm::kJoints; ++j) std::fprintf(log_, ",%.3f", tau[j]);
    for (int j = 0; j < hm::kJoints; ++j) std::fprintf(log_, ",%.4f", u[j]);
    std::fprintf(log_, ",%.2f,%.2f\n", left, right);
  }

  const Options& o_;
  SimbodyHydraulicHumanoid& plant_;
  SocketCan& robot_;
  SocketCan& io_;
  std::FILE* log_;
  hm::BipedSensors sensors_;
  hm::SensorReadings reading_;
  std::array<double, hm::kJoints> mounting_{};
  std::array<proto::Sender, kBoards> board_sender_{proto::Sender(0), proto::Sender(0)};
  std::array<proto::Receiver, kBoards> from_board_{proto::Receiver(0), proto::Receiver(0)};
  proto::Sender sync_sender_{0};
  proto::Sender imu_sender_;
  FaultInjector imu_faults_, sensor_faults_;
  std::mt19937_64 noise_;
  std::normal_distribution<double> gaussian_{0.0, 1.0};
  hm::Vector3 imu_sum_angular_ = hm::Vector3::Zero(), imu_sum_force_ = hm::Vector3::Zero();
  int imu_samples_ = 0;
  hm::JointVector valves_ = hm::JointVector::Zero();  // until the boards speak: centred
  std::array<std::uint64_t, kBoards> last_drive_step_{};
  Summary summary_;
};

bool stop_requested(int signal_fd) {
  pollfd fd{signal_fd, POLLIN, 0};
  return ::poll(&fd, 1, 0) > 0;
}

enum class End { kDone, kSignal, kFailure };

// Receives from both buses until `done` says so or the timeout passes; false on timeout (or a
// bus error, with `error` set).
template <class Done>
bool await(SocketCan& robot, SocketCan& io, PlantNode& node, double timeout_s, Done&& done,
           std::string& error) {
  pollfd fds[2] = {{io.native_handle(), POLLIN, 0}, {robot.native_handle(), POLLIN, 0}};
  const double give_up = monotonic_seconds() + timeout_s;
  for (;;) {
    for (int i = 0; i < 2; ++i) {
      SocketCan& bus = i == 0 ? io : robot;
      for (;;) {
        CanFrame raw;
        const CanResult r = bus.receive(raw, std::chrono::microseconds(0));
        if (r.status == CanStatus::kTimeout || r.status == CanStatus::kInterfaceDown) break;
        if (!r.ok()) {
          error = "receiving failed: " + describe(r);
          return false;
        }
        int board = -1;
        const PlantNode::Received received = node.take(raw, i == 0, board);
        if (done(received, board)) return true;
      }
    }
    const double left = give_up - monotonic_seconds();
    if (left <= 0) return false;
    if (::poll(fds, 2, int(std::ceil(left * 1e3))) < 0 && errno != EINTR) {
      error = std::string("poll: ") + std::strerror(errno);
      return false;
    }
  }
}

End run_lockstep(const Options& o, SocketCan& robot, SocketCan& io, PlantNode& node, int signal_fd,
                 std::string& error) {
  using R = PlantNode::Received;
  const std::uint64_t steps = std::uint64_t(std::llround(o.duration_s * 1e3));
  bool host_heard = false, references_heard = false, waiting_for_host = o.wait_host;
  int host_misses = 0;
  for (std::uint64_t k = 0; steps == 0 || k < steps; ++k) {
    if (stop_requested(signal_fd)) return End::kSignal;
    if (!node.send_tick(k, error)) return End::kFailure;
    // What this tick waits for: both boards' ValveDrive; the host's heartbeat and references
    // when they are due and the host has been heard.
    unsigned boards = 0;
    bool heartbeat = false;
    unsigned references = 0;
    const bool heartbeat_due = k % kHeartbeatPeriodTicks == 0;
    const bool references_due = k % kReferencePeriodTicks == 0;
    const auto note = [&](R r, int board) {
      if (r == R::kValveDrive) boards |= 1u << board;  // board is 0..kBoards-1 for these
      if (r == R::kHeartbeat) heartbeat = host_heard = true;
      if (r == R::kReference) {
        references |= 1u << board;
        references_heard = true;
      }
    };
    constexpr unsigned kAll = (1u << kBoards) - 1;
    const bool boards_answered = await(
        robot, io, node, o.host_timeout_s,
        [&](R r, int board) {
          note(r, board);
          return boards == kAll;
        },
        error);
    if (!error.empty()) return End::kFailure;
    if (!boards_answered) ++node.summary().board_waits_timed_out;
    if (waiting_for_host && host_heard) {
      const auto host_done = [&] {
        return (!heartbeat_due || heartbeat) &&
               (!references_due || !references_heard || references == kAll);
      };
      bool host_in = host_done() || await(
                                        robot, io, node, o.host_timeout_s,
                                        [&](R r, int board) {
                                          note(r, board);
                                          return host_done();
                                        },
                                        error);
      if (!error.empty()) return End::kFailure;
      if (heartbeat_due || references_due) {
        if (!host_in) ++node.summary().host_waits_timed_out;
        host_misses = host_in ? 0 : host_misses + 1;
        if (host_misses == kHostMissesBeforeGivingUp) {
          std::fprintf(stderr,
                       "%s: the host missed %d ticks it was due (step %llu): no longer "
                       "waiting for it\n",
                       kProgram, host_misses, static_cast<unsigned long long>(k));
          waiting_for_host = false;
          node.summary().host_given_up = true;
        }
      }
    }
    node.step();
  }
  return End::kDone;
}

End run_real_time(const Options& o, SocketCan& robot, SocketCan& io, PlantNode& node, int signal_fd,
                  std::string& error) {
  const hmpc::platform::FileDescriptor timer(::timerfd_create(CLOCK_MONOTONIC, TFD_CLOEXEC));
  const itimerspec every_ms{{0, 1'000'000}, {0, 1'000'000}};
  if (timer.get() < 0 || ::timerfd_settime(timer.get(), 0, &every_ms, nullptr) < 0) {
    error = std::string("timerfd: ") + std::strerror(errno);
    return End::kFailure;
  }
  const std::uint64_t steps = std::uint64_t(std::llround(o.duration_s * 1e3));
  pollfd fds[2] = {{timer.get(), POLLIN, 0}, {signal_fd, POLLIN, 0}};
  std::uint64_t k = 0;
  while (steps == 0 || k < steps) {
    if (::poll(fds, 2, -1) < 0) {
      if (errno == EINTR) continue;
      error = std::string("poll: ") + std::strerror(errno);
      return End::kFailure;
    }
    if (fds[1].revents & POLLIN) return End::kSignal;
    if ((fds[0].revents & POLLIN) == 0) continue;
    std::uint64_t expirations = 0;
    if (::read(timer.get(), &expirations, sizeof expirations) != sizeof expirations) continue;
    node.summary().deadline_misses += expirations - 1;
    for (std::uint64_t i = 0; i < expirations && (steps == 0 || k < steps); ++i, ++k) {
      await(
          robot, io, node, 0.0, [](PlantNode::Received, int) { return false; }, error);
      if (!error.empty()) return End::kFailure;
      if (!node.send_tick(k, error)) return End::kFailure;
      node.step();
    }
  }
  return End::kDone;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  std::string error;
  const auto outcome = parse_options(argc, argv, options, error);
  if (outcome != hmpc::cli::ParseOutcome::kRun) {
    return hmpc::cli::exit_status(outcome, kProgram, error, print_usage);
  }
  const hmpc::platform::FileDescriptor signals(hmpc::platform::stop_signal_descriptor(error));
  if (signals.get() < 0) {
    std::fprintf(stderr, "%s: %s\n", kProgram, error.c_str());
    return 1;
  }
  const hm::Parameters parameters;
  const hm::BasicState<0> start = hm::standing_stance(parameters, options.start_height);
  std::unique_ptr<SimbodyHydraulicHumanoid> plant;
  try {
    plant = std::make_unique<SimbodyHydraulicHumanoid>(parameters, hm::ContactParameters{},
                                                       options.mismatch, start);
    for (const Push& p : options.pushes) plant->push(p);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", kProgram, e.what());
    return 2;
  }
  // Every frame on both buses: the plant hears both boards and the host.
  SocketCan robot, io;
  for (auto [can, name] :
       {std::pair{&robot, &options.robot_interface}, std::pair{&io, &options.io_interface}}) {
    const CanResult opened = can->open(name->c_str());
    if (!opened.ok()) {
      std::fprintf(stderr, "%s: cannot open CAN interface '%s': %s\n", kProgram, name->c_str(),
                   describe(opened).c_str());
      return 1;
    }
  }
  std::FILE* log = nullptr;
  if (!options.log_path.empty()) {
    std::string header = "time_s,x,y,z,qw,qx,qy,qz";
    for (int j = 0; j < hm::kJoints; ++j) header += ",q" + std::to_string(j);
    header += ",wx,wy,wz,vx,vy,vz";
    for (int j = 0; j < hm::kJoints; ++j) header += ",qd" + std::to_string(j);
    for (int j = 0; j < hm::kJoints; ++j) header += ",tau" + std::to_string(j);
    for (int j = 0; j < hm::kJoints; ++j) header += ",u" + std::to_string(j);
    header += ",left_fz,right_fz";
    log = hmpc::platform::open_csv_log(options.log_path, header.c_str(), error);
    if (!log) {
      std::fprintf(stderr, "%s: %s\n", kProgram, error.c_str());
      return 1;
    }
  }
  PlantNode node(options, *plant, start, robot, io, log);
  std::printf("%s: robot bus %s, I/O bus %s, %s, standing at %.3f m, joints", kProgram,
              options.robot_interface.c_str(), options.io_interface.c_str(),
              options.lockstep ? "lock-step" : "real time, 1 kHz", options.start_height);
  for (int j = 0; j < hm::kJoints; ++j) std::printf(" %.4f", start.q[7 + j]);
  std::printf(": ready\n");
  std::fflush(stdout);

  const double started = monotonic_seconds();
  const End end = options.lockstep ? run_lockstep(options, robot, io, node, signals.get(), error)
                                   : run_real_time(options, robot, io, node, signals.get(), error);
  Summary& s = node.summary();
  s.wall_s = monotonic_seconds() - started;
  int status = 0;
  if (end == End::kFailure) {
    std::fprintf(stderr, "%s: %s\n", kProgram, error.c_str());
    status = 1;
  }
  if (log && std::fclose(log) != 0) {
    std::fprintf(stderr, "%s: writing the log '%s' failed\n", kProgram, options.log_path.c_str());
    status = 1;
  }
  const double sim_s = 1e-3 * double(s.steps);
  const hm::BasicState<0> x = plant->state();
  std::printf(
      "%s: summary steps=%llu sim_seconds=%.3f wall_seconds=%.3f real_time_factor=%.3f "
      "deadline_misses=%llu syncs=%llu sensor_frames=%llu imu_frames=%llu valve_drives=%llu "
      "rejected_frames=%llu board_waits_timed_out=%llu valves_centred_by_drivers=%llu "
      "host_heartbeats=%llu host_references=%llu host_waits_timed_out=%llu host_given_up=%d "
      "imu_dropped=%llu imu_silenced=%llu sensor_dropped=%llu sensor_corrupted=%llu "
      "interface_down=%llu plant_rejected_inputs=%llu min_height=%.4f max_tilt=%.4f "
      "final_height=%.4f end=%s\n",
      kProgram, static_cast<unsigned long long>(s.steps), sim_s, s.wall_s,
      s.wall_s > 0 ? sim_s / s.wall_s : 0.0, static_cast<unsigned long long>(s.deadline_misses),
      static_cast<unsigned long long>(s.syncs), static_cast<unsigned long long>(s.sensor_frames),
      static_cast<unsigned long long>(s.imu_frames),
      static_cast<unsigned long long>(s.valve_drives),
      static_cast<unsigned long long>(s.rejected_frames),
      static_cast<unsigned long long>(s.board_waits_timed_out),
      static_cast<unsigned long long>(s.valves_centred_by_drivers),
      static_cast<unsigned long long>(s.host_heartbeats),
      static_cast<unsigned long long>(s.host_references),
      static_cast<unsigned long long>(s.host_waits_timed_out), s.host_given_up ? 1 : 0,
      static_cast<unsigned long long>(node.imu_faults().dropped),
      static_cast<unsigned long long>(node.imu_faults().silenced),
      static_cast<unsigned long long>(node.sensor_faults().dropped),
      static_cast<unsigned long long>(node.sensor_faults().corrupted),
      static_cast<unsigned long long>(s.interface_down),
      static_cast<unsigned long long>(plant->rejected_commands()), s.steps ? s.min_height : x.q[2],
      s.max_tilt, x.q[2],
      end == End::kDone     ? "duration"
      : end == End::kSignal ? "signal"
                            : "failure");
  return status;
}
