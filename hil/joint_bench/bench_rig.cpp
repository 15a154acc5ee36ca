// hmpc-joint-bench: the one-joint HIL bench of the hydraulic joint board. It plays everything
// around the board under test (hmpc-joint-board), each on its own bus, as a test stand would:
//   plant  (I/O bus, vcan1)    the Simbody hydraulic joint swinging a leg (simbody_joint.hpp):
//                              every 1 ms its encoder, load cell and chamber pressures, then a
//                              Sync; it applies the board's ValveDrive
//   host   (robot bus, vcan0)  heartbeats (zeroing, hold, run), torque references every 6 ms
//                              (a step, a sinusoid or a chirp), gains; it reads the board's
//                              telemetry; fault injection: silence, an E-stop, bad references
// In lock-step (--lockstep) each millisecond waits for the board's ValveDrive, so a run is
// deterministic; in real time a 1 kHz timer paces both roles. At the end it prints key=value
// figures: the RMS torque error (the plant's true torque against the reference) over the
// measurement window, and the latencies of the fault reactions in ticks.
#include <poll.h>
#include <sys/timerfd.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <random>
#include <stdexcept>
#include <string>

#include "hmpc/cli/arguments.hpp"
#include "hmpc/platform/linux/bus_program.hpp"
#include "hmpc/platform/linux/frame_faults.hpp"
#include "hmpc/protocol/joint_protocol.hpp"
#include "simbody_joint.hpp"

namespace {

namespace proto = hmpc::joint_protocol;
namespace hy = hmpc::hydraulic;
using hmpc::platform::CanFrame;
using hmpc::platform::CanResult;
using hmpc::platform::CanStatus;
using hmpc::platform::describe;
using hmpc::platform::monotonic_seconds;
using hmpc::platform::SocketCan;

constexpr const char* kProgram = "hmpc-joint-bench";
constexpr double kBoardTimeoutS = 5;  // lock-step: no ValveDrive this long -> fail
// The plant's encoder reads the joint angle plus this mounting offset, which the board's
// zeroing must find.
constexpr double kMountingOffset = 0.25;
// Sensor noise at --noise 1 (standard deviations): a 16-bit encoder's least step, a velocity
// estimate's jitter, 0.5 % of a 100 N·m load cell, 0.1 % of a 25 MPa pressure transducer.
constexpr double kNoiseTheta = 1e-4, kNoiseOmega = 5e-3, kNoiseTorque = 0.5, kNoisePressure = 2.5e4;

enum class Profile { kStep, kSine, kChirp };

struct Options {
  std::string robot_interface = "vcan0";
  std::string io_interface = "vcan1";
  proto::NodeId node = 0;
  bool lockstep = false;
  double duration_s = 6;
  Profile profile = Profile::kSine;
  double amplitude = 20;      // N·m
  double frequency = 2;       // Hz; the chirp's start
  double chirp_to = 6;        // Hz, the chirp's end (at the end of the run)
  double run_at_s = 1.0;      // the host asks for run; references start a period before
  double measure_from_s = 2;  // the RMS window's start
  double swing = 0;           // rad: the leg starts there, at rest, and swings when released
  hmpc::hil::JointMismatch mismatch{};
  double noise = 0;  // multiplies the noise above
  std::uint64_t seed = 1;
  hmpc::platform::FaultConfig sensor_faults{};
  double stop_heartbeat_at_s = -1;  // the host falls silent from then on
  double estop_at_s = -1;
  double bad_references_at_s = -1;  // out of range, replayed and stale-counter references
  std::string log_path;
};

void print_usage(std::FILE* out) {
  std::fprintf(
      out,
      "usage: hmpc-joint-bench [--robot-interface IFACE] [--io-interface IFACE] [--node N]\n"
      "                        [--lockstep] [--duration S] [--profile step|sine|chirp]\n"
      "                        [--amplitude NM] [--frequency HZ] [--chirp-to HZ] [--run-at S]\n"
      "                        [--measure-from S] [--swing RAD] [--mismatch-load F]\n"
      "                        [--mismatch-bulk-modulus F] [--mismatch-valve-gain F]\n"
      "                        [--mismatch-friction F] [--noise F] [--seed N]\n"
      "                        [--drop-sensor F] [--corrupt-sensor F] [--stop-heartbeat-at S]\n"
      "                        [--estop-at S] [--bad-references-at S] [--log FILE]\n"
      "  --robot-interface IFACE  the robot bus, host <-> board (default vcan0)\n"
      "  --io-interface IFACE     the HIL's I/O bus, plant <-> board (default vcan1)\n"
      "  --node N                 the board's node id, 0..15 (default 0)\n"
      "  --lockstep               wait for the board's ValveDrive every 1 ms (deterministic)\n"
      "  --duration S             simulated seconds (default 6)\n"
      "  --profile P              torque reference: a step to the amplitude, a sinusoid, or a\n"
      "                           chirp from --frequency to --chirp-to (default sine)\n"
      "  --amplitude NM           N·m, 0..60 (default 20)\n"
      "  --frequency HZ           0.1..20 (default 2)\n"
      "  --run-at S               when the host asks for run (default 1; zeroing at 0.2 s,\n"
      "                           hold at 0.5 s)\n"
      "  --measure-from S         start of the RMS window (default 2)\n"
      "  --swing RAD              the leg's initial angle, released at rest (default 0)\n"
      "  --mismatch-* F           plant/nominal factors in [0.5, 2]: load (mass and inertia),\n"
      "                           bulk modulus, valve flow gain, seal friction\n"
      "  --noise F                sensor noise, F times the rig's reference levels (default 0)\n"
      "  --drop-sensor F, --corrupt-sensor F\n"
      "                           share of the plant's sensor frames lost or with a bit flipped\n"
      "  --stop-heartbeat-at S    the host falls silent (heartbeat and references) from then on\n"
      "  --estop-at S             the host sends an E-stop\n"
      "  --bad-references-at S    the host sends a reference beyond the joint's torque limit, a\n"
      "                           replayed frame and one with its counter stepped back\n"
      "  --log FILE               CSV, one row per ms\n");
}

hmpc::cli::ParseOutcome parse(int argc, char** argv, Options& o, std::string& error) {
  hmpc::cli::OptionParser p;
  p.interface("--robot-interface", o.robot_interface);
  p.interface("--io-interface", o.io_interface);
  p.integer("--node", 0, proto::kIds.max_node, o.node);
  p.flag("--lockstep", o.lockstep);
  p.number("--duration", 0.01, 3600, "seconds in [0.01, 3600]", o.duration_s);
  p.text("--profile", [&o](const std::string& v) -> std::string {
    if (v == "step")
      o.profile = Profile::kStep;
    else if (v == "sine")
      o.profile = Profile::kSine;
    else if (v == "chirp")
      o.profile = Profile::kChirp;
    else
      return hmpc::cli::bad_value("--profile", "step, sine or chirp", v);
    return {};
  });
  p.number("--amplitude", 0, 60, "N·m in [0, 60]", o.amplitude);
  p.number("--frequency", 0.1, 20, "Hz in [0.1, 20]", o.frequency);
  p.number("--chirp-to", 0.1, 20, "Hz in [0.1, 20]", o.chirp_to);
  p.number("--run-at", 0.6, 3600, "seconds in [0.6, 3600]", o.run_at_s);
  p.number("--measure-from", 0, 3600, "seconds in [0, 3600]", o.measure_from_s);
  p.number("--swing", -1, 1, "radians in [-1, 1]", o.swing);
  p.number("--mismatch-load", 0.5, 2, "a factor in [0.5, 2]", o.mismatch.load_scale);
  p.number("--mismatch-bulk-modulus", 0.5, 2, "a factor in [0.5, 2]",
           o.mismatch.bulk_modulus_scale);
  p.number("--mismatch-valve-gain", 0.5, 2, "a factor in [0.5, 2]",
           o.mismatch.valve_flow_gain_scale);
  p.number("--mismatch-friction", 0.5, 2, "a factor in [0.5, 2]", o.mismatch.friction_scale);
  p.number("--noise", 0, 10, "a factor in [0, 10]", o.noise);
  p.integer("--seed", 0, 1L << 30, o.seed);
  p.number("--drop-sensor", 0, 1, "a fraction in [0, 1]", o.sensor_faults.drop_fraction);
  p.number("--corrupt-sensor", 0, 1, "a fraction in [0, 1]", o.sensor_faults.corrupt_fraction);
  p.number("--stop-heartbeat-at", 0, 3600, "seconds in [0, 3600]", o.stop_heartbeat_at_s);
  p.number("--estop-at", 0, 3600, "seconds in [0, 3600]", o.estop_at_s);
  p.number("--bad-references-at", 0, 3600, "seconds in [0, 3600]", o.bad_references_at_s);
  p.text("--log", [&o](const std::string& v) -> std::string {
    if (v.empty()) return "--log needs a file name";
    o.log_path = v;
    return {};
  });
  const auto outcome = p.parse(argc, argv, error);
  if (outcome == hmpc::cli::ParseOutcome::kRun && o.io_interface == o.robot_interface) {
    error =
        "--io-interface must differ from --robot-interface (the robot bus carries no plant "
        "frames)";
    return hmpc::cli::ParseOutcome::kError;
  }
  o.sensor_faults.seed = o.seed;
  return outcome;
}

struct Figures {
  std::uint64_t ticks = 0;
  double squared_error = 0;
  std::uint64_t measured = 0;
  double max_abs_omega = 0, max_abs_error = 0;
  std::int64_t last_heartbeat_tick = -1;
  // The last tick with a valve open: the valves are centred for good from the next one on
  // (a valve command can round to exactly 0 in the frame now and then before that).
  std::int64_t last_open_tick = -1;
  std::int64_t estop_tick = -1;
  std::uint64_t board_frames = 0, rejected_board_frames = 0;
  proto::BoardStatus status{};
  bool status_seen = false;
  proto::EncoderOffset offset{};
};

class Rig {
 public:
  Rig(const Options& o, SocketCan& robot, SocketCan& io)
      : o_(o), robot_(robot), io_(io),
        plant_(hy::JointActuatorParameters<double>{}, hy::PendulumLoad<double>::leg(), o.mismatch,
               initial(o)),
        host_(o.node), plant_sender_(o.node), from_board_(o.node), io_from_board_(o.node),
        faults_(o.sensor_faults), noise_rng_(o.seed) {}

  static hy::PendulumState<double> initial(const Options& o) {
    hy::PendulumState<double> x = hy::torque_free_rest(hy::JointActuatorParameters<double>{});
    x.theta = o.swing;
    return x;
  }

  double reference(double t) const {
    const double since = t - o_.run_at_s;
    if (since < 0) return 0;
    switch (o_.profile) {
      case Profile::kStep: return o_.amplitude;
      case Profile::kSine: return o_.amplitude * std::sin(2 * M_PI * o_.frequency * since);
      case Profile::kChirp: {
        // Linear chirp from frequency to chirp_to over the rest of the run.
        const double span = std::max(o_.duration_s - o_.run_at_s, 1e-3);
        const double rate = (o_.chirp_to - o_.frequency) / span;
        return o_.amplitude *
               std::sin(2 * M_PI * (o_.frequency * since + 0.5 * rate * since * since));
      }
    }
    return 0;
  }

  // The host's and the plant's frames of tick k. False when a bus fails.
  bool send_tick(std::uint64_t k, std::string& error) {
    const double t = 1e-3 * double(k);
    const bool silent = o_.stop_heartbeat_at_s >= 0 && t >= o_.stop_heartbeat_at_s;
    if (!silent && k % 10 == 0) {
      proto::ModeCommand m;
      m.mode = t >= o_.run_at_s ? proto::RequestedMode::kRun
               : t >= 0.5       ? proto::RequestedMode::kHold
                                : proto::RequestedMode::kIdle;
      m.zero_encoders = k == 200;
      m.host_time_us = std::uint32_t(k * 1000);
      if (!send(robot_, host_, m, error)) return false;
      figures_.last_heartbeat_tick = std::int64_t(k);
    }
    // References from a period before run is asked, so the board has a fresh one.
    if (!silent && k % 6 == 0 && t >= o_.run_at_s - 0.006) {
      proto::TorqueReference r;
      r.tau[0] = float(reference(t));
      if (!send_reference(r, error)) return false;
    }
    if (o_.estop_at_s >= 0 && figures_.estop_tick < 0 && t >= o_.estop_at_s) {
      if (!send(robot_, host_, proto::EStop{}, error)) return false;
      figures_.estop_tick = std::int64_t(k);
    }
    if (o_.bad_references_at_s >= 0 && !bad_sent_ && t >= o_.bad_references_at_s) {
      bad_sent_ = true;
      if (!send_bad_references(error)) return false;
    }
    return send_sensors(k, error);
  }

  // Frames from the board: the ValveDrive (true when one came) and its telemetry.
  bool take(const CanFrame& raw, bool from_io) {
    hmpc::protocol::Frame f;
    if (!hmpc::platform::to_protocol_frame(raw, f)) return false;
    proto::FrameType type{};
    proto::NodeId node = 0;
    if (!proto::identify(f.id, type, node) || node != o_.node) return false;
    ++figures_.board_frames;
    proto::Receiver& rx = from_io ? io_from_board_ : from_board_;
    bool ok = true;
    bool drive = false;
    switch (type) {
      case proto::FrameType::kValveDrive: {
        proto::ValveDrive d;
        ok = rx.decode(f, d) == proto::DecodeResult::kOk;
        if (ok) {
          u_ = double(d.u[0]);
          drive = true;
        }
        break;
      }
      case proto::FrameType::kBoardStatus:
        ok = rx.decode(f, figures_.status) == proto::DecodeResult::kOk;
        figures_.status_seen = figures_.status_seen || ok;
        break;
      case proto::FrameType::kEncoderOffset:
        ok = rx.decode(f, figures_.offset) == proto::DecodeResult::kOk;
        break;
      default: break;  // JointState, ValveCommands: the plant's truth is better here
    }
    if (!ok) ++figures_.rejected_board_frames;
    return drive;
  }

  // Applies the latest valve command for 1 ms and books the figures of tick k.
  void step(std::uint64_t k) {
    const double t = 1e-3 * double(k);
    plant_.step(u_);
    const hy::PendulumState<double> x = plant_.state();
    const double tau = plant_.torque();
    const double ref = reference(t);
    if (t >= o_.measure_from_s) {
      const double e = ref - tau;
      figures_.squared_error += e * e;
      figures_.max_abs_error = std::max(figures_.max_abs_error, std::abs(e));
      ++figures_.measured;
      figures_.max_abs_omega = std::max(figures_.max_abs_omega, std::abs(x.omega));
    }
    if (u_ != 0.0) figures_.last_open_tick = std::int64_t(k);
    if (log_) {
      std::fprintf(log_, "%.3f,%.4f,%.4f,%.5f,%.5f,%.5f,%.4f,%.4f,%s\n", t, ref, tau, x.theta,
                   x.omega, u_, x.actuator.pressure_a * 1e-6, x.actuator.pressure_b * 1e-6,
                   proto::value_name(proto::kBoardModeValues, std::uint32_t(figures_.status.mode)));
    }
    ++figures_.ticks;
  }

  void set_log(std::FILE* log) { log_ = log; }
  const Figures& figures() const { return figures_; }
  const hmpc::platform::FaultCounters& sensor_faults() const { return faults_.counters(); }

 private:
  template <class Message>
  bool send(SocketCan& bus, proto::Sender& sender, const Message& m, std::string& error) {
    const CanResult sent = hmpc::platform::send_message(bus, sender, m);
    if (!sent.ok()) {
      error = "sending failed: " + describe(sent);
      return false;
    }
    return true;
  }

  bool send_reference(const proto::TorqueReference& r, std::string& error) {
    hmpc::protocol::Frame f;
    if (host_.encode(r, f) != proto::EncodeResult::kOk) {
      error = "a reference did not encode";
      return false;
    }
    last_reference_ = f;
    const CanResult sent = robot_.send(hmpc::platform::to_can_frame(f));
    if (!sent.ok()) error = "sending failed: " + describe(sent);
    return sent.ok();
  }

  // A host gone wrong: a reference beyond the joint's 60 N·m limit (valid on the bus, refused
  // by the board), the last reference replayed (a repeated counter), and a reference with its
  // counter stepped back.
  bool send_bad_references(std::string& error) {
    proto::TorqueReference beyond;
    beyond.tau[0] = 150;
    if (!send_reference(beyond, error)) return false;
    if (!robot_.send(hmpc::platform::to_can_frame(last_reference_)).ok()) return false;
    hmpc::protocol::Frame back = last_reference_;
    back.data[1] = std::uint8_t((back.data[1] & 0xF0) | ((back.data[1] - 3) & 0x0F));
    back.data[0] = hmpc::protocol::frame_checksum(back);
    if (!robot_.send(hmpc::platform::to_can_frame(back)).ok()) return false;
    (void)error;
    return true;
  }

  double noisy(double value, double sigma) {
    if (o_.noise <= 0) return value;
    return value + std::normal_distribution<double>(0.0, o_.noise * sigma)(noise_rng_);
  }

  bool send_sensors(std::uint64_t k, std::string& error) {
    const hy::PendulumState<double> x = plant_.state();
    const double t = 1e-3 * double(k);
    proto::JointSensor<0> s;
    s.theta = float(std::clamp(noisy(x.theta + kMountingOffset, kNoiseTheta), -3.1416, 3.1416));
    s.theta_dot = float(std::clamp(noisy(x.omega, kNoiseOmega), -20.0, 20.0));
    s.tau = float(std::clamp(noisy(plant_.torque(), kNoiseTorque), -200.0, 200.0));
    proto::ChamberPressures01 p;
    // Transducers read 0..32 MPa and saturate beyond (the model has no cavitation floor).
    p.p_a[0] = float(std::clamp(noisy(x.actuator.pressure_a, kNoisePressure) * 1e-6, 0.0, 32.0));
    p.p_b[0] = float(std::clamp(noisy(x.actuator.pressure_b, kNoisePressure) * 1e-6, 0.0, 32.0));
    for (hmpc::protocol::Frame f : {encoded(s), encoded(p)}) {
      if (faults_.apply(t, f) == hmpc::platform::FaultAction::kDrop) continue;
      const CanResult sent = io_.send(hmpc::platform::to_can_frame(f));
      if (!sent.ok()) {
        error = "sending a sensor frame failed: " + describe(sent);
        return false;
      }
    }
    // The Sync is never faulted: it stands for the board's own clock.
    return send(io_, plant_sender_, proto::Sync{std::uint32_t(k), 0}, error);
  }

  template <class Message>
  hmpc::protocol::Frame encoded(const Message& m) {
    hmpc::protocol::Frame f;
    plant_sender_.encode(m, f);
    return f;
  }

  const Options& o_;
  SocketCan& robot_;
  SocketCan& io_;
  hmpc::hil::SimbodyHydraulicJoint plant_;
  proto::Sender host_, plant_sender_;
  proto::Receiver from_board_, io_from_board_;
  hmpc::platform::FaultInjector faults_;
  std::mt19937_64 noise_rng_;
  hmpc::protocol::Frame last_reference_{};
  bool bad_sent_ = false;
  double u_ = 0;
  Figures figures_;
  std::FILE* log_ = nullptr;
};

bool stop_requested(int signal_fd) {
  pollfd fd{signal_fd, POLLIN, 0};
  return ::poll(&fd, 1, 0) > 0;
}

// Takes whatever both buses hold; true when a ValveDrive came (in `drive`).
bool drain(SocketCan& robot, SocketCan& io, Rig& rig, bool& drive, std::string& error) {
  for (SocketCan* bus : {&robot, &io}) {
    for (;;) {
      CanFrame raw;
      const CanResult r = bus->receive(raw, std::chrono::microseconds(0));
      if (r.status == CanStatus::kTimeout) break;
      if (!r.ok()) {
        error = "receiving failed: " + describe(r);
        return false;
      }
      drive = rig.take(raw, bus == &io) || drive;
    }
  }
  return true;
}

bool run_lockstep(const Options& o, SocketCan& robot, SocketCan& io, Rig& rig, int signal_fd,
                  std::string& error) {
  const std::uint64_t steps = std::uint64_t(std::llround(o.duration_s * 1e3));
  pollfd fds[2] = {{io.native_handle(), POLLIN, 0}, {robot.native_handle(), POLLIN, 0}};
  for (std::uint64_t k = 0; k < steps; ++k) {
    if (stop_requested(signal_fd)) return true;
    if (!rig.send_tick(k, error)) return false;
    bool drive = false;
    const double give_up = monotonic_seconds() + kBoardTimeoutS;
    while (!drive) {
      const double left = give_up - monotonic_seconds();
      if (left <= 0) {
        error = "the board sent no ValveDrive for Sync " + std::to_string(k) + " within " +
                std::to_string(int(kBoardTimeoutS)) + " s";
        return false;
      }
      if (::poll(fds, 2, int(std::ceil(left * 1e3))) < 0 && errno != EINTR) {
        error = std::string("poll: ") + std::strerror(errno);
        return false;
      }
      if (!drain(robot, io, rig, drive, error)) return false;
    }
    rig.step(k);
  }
  // The board's last telemetry.
  bool drive = false;
  ::usleep(20000);
  return drain(robot, io, rig, drive, error);
}

bool run_real_time(const Options& o, SocketCan& robot, SocketCan& io, Rig& rig, int signal_fd,
                   std::string& error) {
  const hmpc::platform::FileDescriptor timer(::timerfd_create(CLOCK_MONOTONIC, TFD_CLOEXEC));
  const itimerspec every_ms{{0, 1'000'000}, {0, 1'000'000}};
  if (timer.get() < 0 || ::timerfd_settime(timer.get(), 0, &every_ms, nullptr) < 0) {
    error = std::string("timerfd: ") + std::strerror(errno);
    return false;
  }
  const std::uint64_t steps = std::uint64_t(std::llround(o.duration_s * 1e3));
  std::uint64_t k = 0;
  while (k < steps) {
    if (stop_requested(signal_fd)) return true;
    std::uint64_t expirations = 0;
    if (::read(timer.get(), &expirations, sizeof expirations) != sizeof expirations) continue;
    for (std::uint64_t i = 0; i < expirations && k < steps; ++i, ++k) {
      bool drive = false;
      if (!drain(robot, io, rig, drive, error)) return false;
      if (!rig.send_tick(k, error)) return false;
      rig.step(k);
    }
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  std::string error;
  const auto outcome = parse(argc, argv, o, error);
  if (outcome != hmpc::cli::ParseOutcome::kRun) {
    return hmpc::cli::exit_status(outcome, kProgram, error, print_usage);
  }
  const hmpc::platform::FileDescriptor signals(hmpc::platform::stop_signal_descriptor(error));
  if (signals.get() < 0) {
    std::fprintf(stderr, "%s: %s\n", kProgram, error.c_str());
    return 1;
  }
  // The board's frames only, on both buses.
  SocketCan robot, io;
  if (!hmpc::platform::open_node_bus<proto::Description>(robot, o.robot_interface, o.node, false,
                                                         error) ||
      !hmpc::platform::open_node_bus<proto::Description>(io, o.io_interface, o.node, false,
                                                         error)) {
    std::fprintf(stderr, "%s: %s\n", kProgram, error.c_str());
    return 1;
  }
  std::FILE* log = nullptr;
  if (!o.log_path.empty()) {
    log = hmpc::platform::open_csv_log(
        o.log_path, "t,tau_ref,tau,theta,omega,u,p_a_mpa,p_b_mpa,board_mode", error);
    if (!log) {
      std::fprintf(stderr, "%s: %s\n", kProgram, error.c_str());
      return 1;
    }
  }
  try {
    Rig rig(o, robot, io);
    rig.set_log(log);
    std::printf("%s: board node %u, robot bus %s, I/O bus %s, %s: running\n", kProgram,
                unsigned(o.node), o.robot_interface.c_str(), o.io_interface.c_str(),
                o.lockstep ? "lock-step" : "real time");
    std::fflush(stdout);
    const bool ok = o.lockstep ? run_lockstep(o, robot, io, rig, signals.get(), error)
                               : run_real_time(o, robot, io, rig, signals.get(), error);
    if (log) std::fclose(log);
    if (!ok) {
      std::fprintf(stderr, "%s: %s\n", kProgram, error.c_str());
      return 1;
    }
    const Figures& f = rig.figures();
    const double rms = f.measured > 0 ? std::sqrt(f.squared_error / double(f.measured)) : 0.0;
    // Ticks from an event to the first of the valves centred for good; -1 without the event,
    // or when a valve was still open at the end.
    const std::int64_t centred_tick =
        f.last_open_tick + 1 < std::int64_t(f.ticks) ? f.last_open_tick + 1 : -1;
    const auto after = [centred_tick](std::int64_t from, bool happened) {
      return happened && from >= 0 && centred_tick >= from ? centred_tick - from : -1;
    };
    std::printf(
        "%s: summary ticks=%llu rms_torque_error=%.4f max_abs_torque_error=%.3f "
        "max_abs_omega=%.4f measured_ticks=%llu board_mode=%s board_faults=0x%04x "
        "board_rejected_frames=%u encoder_offset=%.4f zeroed=%d last_heartbeat_tick=%lld "
        "valves_centred_after_last_heartbeat_ticks=%lld estop_tick=%lld "
        "valves_centred_after_estop_ticks=%lld board_frames=%llu rejected_board_frames=%llu "
        "sensor_frames_dropped=%llu sensor_frames_corrupted=%llu\n",
        kProgram, static_cast<unsigned long long>(f.ticks), rms, f.max_abs_error, f.max_abs_omega,
        static_cast<unsigned long long>(f.measured),
        f.status_seen ? proto::value_name(proto::kBoardModeValues, std::uint32_t(f.status.mode))
                      : "unseen",
        unsigned(f.status.faults), unsigned(f.status.rejected_frames), double(f.offset.offset),
        f.offset.zeroed ? 1 : 0, static_cast<long long>(f.last_heartbeat_tick),
        static_cast<long long>(after(f.last_heartbeat_tick, o.stop_heartbeat_at_s >= 0)),
        static_cast<long long>(f.estop_tick),
        static_cast<long long>(after(f.estop_tick, f.estop_tick >= 0)),
        static_cast<unsigned long long>(f.board_frames),
        static_cast<unsigned long long>(f.rejected_board_frames),
        static_cast<unsigned long long>(rig.sensor_faults().dropped),
        static_cast<unsigned long long>(rig.sensor_faults().corrupted));
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "%s: %s\n", kProgram, e.what());
    return 2;
  }
  return 0;
}
