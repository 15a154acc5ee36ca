// The forearm board application (firmware/app/forearm_board.hpp) driven directly, without a
// bus: a host (proto::Sender) sends heartbeats, commands and trajectory samples; a plant,
// Eq. 3.1 on hmpc::forearm::integrate at 1 ms, sends a Sensor frame before every tick and
// applies the ActuatorCommand the board sends back. Board frames are decoded by a host-side
// Receiver, so every one of them must pass the protocol's checks too.
#include "forearm_board.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "hmpc/models/forearm.hpp"
#include "hmpc/models/forearm_solvers.hpp"

namespace {

namespace proto = hmpc::forearm_protocol;
using Board = hmpc::firmware::ForearmBoard<double>;
using proto::BoardMode;
using proto::RequestedMode;
using proto::Strategy;

constexpr proto::NodeId kNode = 3;
constexpr int kHeartbeatPeriodTicks = 10;  // the protocol's ModeCommand period
constexpr double kAmplitude = 30 * M_PI / 180;
constexpr double kFrequencyHz = 0.5;
constexpr std::uint32_t kSamplePeriodUs = 4000;  // TrajectorySample period (protocol)
constexpr std::uint32_t kStreamLeadUs = 300000;  // samples sent ahead: > the 200 ms horizon

// Hold-mode gains the host sends at start-up: the board's defaults, sent so that every test
// also goes through the Gains frame.
constexpr proto::Gains kHoldGains{10.0f, 10.0f, 2.0f, 0.0f, 0};

// A wall clock that advances 10 ms every time it is read: every MPC step overruns its 3.5 ms.
double g_fake_seconds = 0;
double slow_clock() { return g_fake_seconds += 0.010; }

struct StepOptions {
  bool heartbeat = true;  // the host's ModeCommand every 10 ms
  bool sensor = true;     // the plant's Sensor frame every tick
  // Latency of the heartbeat in ticks, as f(tick it was sent): it is stamped when sent and
  // reaches the board that many ticks later.
  int (*heartbeat_delay)(std::uint64_t tick) = nullptr;
};

class Rig {
 public:
  // cppcheck-suppress passedByValue ; a function pointer, which cppcheck takes for a class
  explicit Rig(double theta0 = 0.0, Board::WallClock clock = nullptr,
               const Board::Config& board_config = config(),
               const hmpc::forearm::Parameters<double>& plant = {})
      : params_(plant), board_(std::make_unique<Board>(board_config, clock)),
        x_(theta0, 0.0, hmpc::forearm::equilibrium_pressure(params_, theta0)) {
    deliver(encode(host_, kHoldGains));
  }

  static Board::Config config() {
    Board::Config c;
    c.node = kNode;
    return c;
  }

  Board& board() { return *board_; }
  const Eigen::Vector3d& plant() const { return x_; }
  std::uint64_t steps() const { return tick_; }
  double now_s() const { return 1e-3 * double(tick_); }
  std::uint32_t now_us() const { return std::uint32_t(tick_ * 1000); }

  // ---- host ----
  // Sets what the heartbeat asks for and sends it now.
  void command(RequestedMode mode, Strategy strategy = Strategy::kTwoStage,
               bool clear_faults = false) {
    requested_ = {mode, strategy, clear_faults, 0, 0};
    send_heartbeat();
  }
  void send_heartbeat() {
    proto::ModeCommand m = requested_;
    m.host_time_us = now_us();
    deliver(encode(host_, m));
  }
  proto::Frame encode_command(RequestedMode mode, Strategy strategy = Strategy::kTwoStage) {
    return encode(host_, proto::ModeCommand{mode, strategy, false, now_us(), 0});
  }
  void deliver(const proto::Frame& frame) { board_->on_frame(frame); }
  template <class Message>
  void send_from_host(const Message& message) {
    deliver(encode(host_, message));
  }
  std::uint8_t last_host_counter() const {
    const std::uint8_t next = host_.next_counter[proto::index_of(proto::FrameType::kModeCommand)];
    return std::uint8_t((next + proto::kCounterModulo - 1) % proto::kCounterModulo);
  }

  // Streams theta_d(t) = offset + A sin(2 pi f (t - t0)) ahead of time from now on.
  void stream_sinusoid(double amplitude = kAmplitude, double frequency_hz = kFrequencyHz,
                       double offset = 0) {
    amplitude_ = amplitude;
    frequency_hz_ = frequency_hz;
    offset_ = offset;
    streaming_ = true;
    stream_start_us_ = now_us();
    next_sample_us_ = stream_start_us_;
  }
  double theta_d(double t) const {
    return offset_ +
           amplitude_ * std::sin(2 * M_PI * frequency_hz_ * (t - 1e-6 * stream_start_us_));
  }

  // ---- one millisecond of host, plant and board ----
  void step(StepOptions options) {
    if (options.heartbeat && tick_ % kHeartbeatPeriodTicks == 0) {
      if (options.heartbeat_delay) {
        proto::ModeCommand m = requested_;
        m.host_time_us = now_us();
        delayed_heartbeat_ = encode(host_, m);
        heartbeat_due_ = tick_ + std::uint64_t(options.heartbeat_delay(tick_));
        heartbeat_pending_ = true;
      } else {
        send_heartbeat();
      }
    }
    if (heartbeat_pending_ && tick_ >= heartbeat_due_) {
      deliver(delayed_heartbeat_);
      heartbeat_pending_ = false;
    }
    while (streaming_ && next_sample_us_ <= now_us() + kStreamLeadUs) {
      deliver(encode(host_, proto::TrajectorySample{float(theta_d(1e-6 * next_sample_us_)),
                                                    next_sample_us_, 0}));
      next_sample_us_ += kSamplePeriodUs;
    }
    if (options.sensor) {
      deliver(encode(plant_, proto::SensorSample{float(x_(0)), float(x_(1)), float(x_(2) / 10),
                                                 0}));  // bar -> MPa
    }
    board_->tick();
    if (board_->mpc_due()) board_->run_mpc();
    collect_board_frames();
    // Eq. 3.1's input order: u = [v_m, v_p].
    x_ = hmpc::forearm::integrate(params_, x_,
                                  Eigen::Vector2d(last_command_.v_m, last_command_.v_p), 1e-3);
    ++tick_;
  }
  void run(int ticks, StepOptions options = {}) {
    for (int i = 0; i < ticks; ++i) step(options);
  }

  // ---- what the board sent ----
  const proto::ActuatorCommand& last_command() const { return last_command_; }
  const proto::BoardStatus& last_status() const { return last_status_; }
  int actuator_commands() const { return actuator_commands_; }
  int status_frames() const { return status_frames_; }
  const proto::RejectCounters& board_frame_rejects() const { return from_board_.rejects; }

 private:
  template <class Message>
  static proto::Frame encode(proto::Sender& sender, const Message& m) {
    proto::Frame f;
    EXPECT_EQ(sender.encode(m, f), proto::EncodeResult::kOk);
    return f;
  }

  void collect_board_frames() {
    proto::Frame f;
    while (board_->pop_frame(f)) {
      proto::FrameType type;
      proto::NodeId node;
      ASSERT_TRUE(proto::identify(f.id, type, node));
      ASSERT_EQ(node, kNode);
      if (type == proto::FrameType::kActuatorCommand) {
        ASSERT_EQ(from_board_.decode(f, last_command_), proto::DecodeResult::kOk);
        ++actuator_commands_;
      } else if (type == proto::FrameType::kBoardStatus) {
        ASSERT_EQ(from_board_.decode(f, last_status_), proto::DecodeResult::kOk);
        ++status_frames_;
      }
    }
  }

  hmpc::forearm::Parameters<double> params_{};
  std::unique_ptr<Board> board_;  // ~60 kB: one allocation, not on the stack
  Eigen::Vector3d x_;
  std::uint64_t tick_ = 0;
  proto::Sender host_{kNode};
  proto::Sender plant_{kNode};
  proto::Receiver from_board_{kNode};
  proto::ModeCommand requested_{RequestedMode::kIdle, Strategy::kTwoStage, false, 0, 0};
  bool streaming_ = false;
  double amplitude_ = kAmplitude, frequency_hz_ = kFrequencyHz, offset_ = 0;
  std::uint32_t stream_start_us_ = 0;
  std::uint32_t next_sample_us_ = 0;
  proto::ActuatorCommand last_command_{};
  proto::BoardStatus last_status_{};
  proto::Frame delayed_heartbeat_{};
  std::uint64_t heartbeat_due_ = 0;
  bool heartbeat_pending_ = false;
  int actuator_commands_ = 0;
  int status_frames_ = 0;
};

void expect_safe(const Rig& rig, const Board& board) {
  EXPECT_EQ(board.outputs().v_p, 0.0);
  EXPECT_EQ(board.outputs().v_m, 0.0);
  EXPECT_EQ(rig.last_command().v_p, 0.0f);
  EXPECT_EQ(rig.last_command().v_m, 0.0f);
}

TEST(ForearmBoard, BootsIntoIdleWithSafeOutputs) {
  Rig rig;
  Board& board = rig.board();
  EXPECT_EQ(board.mode(), BoardMode::kBoot);
  proto::Frame none;
  EXPECT_FALSE(board.pop_frame(none));

  rig.run(1, {false, false});
  EXPECT_EQ(board.mode(), BoardMode::kIdle);
  EXPECT_EQ(rig.actuator_commands(), 1);
  expect_safe(rig, board);

  rig.run(2 * kHeartbeatPeriodTicks);
  EXPECT_EQ(board.mode(), BoardMode::kIdle);
  EXPECT_EQ(rig.actuator_commands(), 1 + 2 * kHeartbeatPeriodTicks);  // one per tick
  EXPECT_EQ(rig.status_frames(), 2);                                  // one per 10 ms
  EXPECT_EQ(rig.last_status().mode, BoardMode::kIdle);
  EXPECT_EQ(rig.last_status().faults, 0);
  expect_safe(rig, board);
  EXPECT_EQ(rig.board_frame_rejects().total(), 0u);
}

TEST(ForearmBoard, HoldKeepsTheArmWhereItWas) {
  const double theta0 = 0.3;
  Rig rig(theta0);
  rig.run(20);
  rig.command(RequestedMode::kHold);
  EXPECT_EQ(rig.board().mode(), BoardMode::kHold);
  rig.run(2000);
  EXPECT_EQ(rig.board().mode(), BoardMode::kHold);
  EXPECT_EQ(rig.board().faults(), 0);
  EXPECT_LT(std::abs(rig.plant()(0) - theta0), 0.05) << "theta " << rig.plant()(0);
  EXPECT_GT(rig.last_command().v_p, 0.5f);  // the valve carries the arm's weight
  EXPECT_EQ(rig.last_command().v_m, 0.0f);  // hold is PAM only
  EXPECT_EQ(rig.last_status().mode, BoardMode::kHold);
}

TEST(ForearmBoard, IdleLetsTheArmSinkSoHoldIsWhatHoldsIt) {
  const double theta0 = 0.3;
  Rig rig(theta0);
  int ticks = 0;
  while (ticks < 2000 && std::abs(rig.plant()(0) - theta0) < 0.05) {
    rig.run(1);
    ++ticks;
  }
  EXPECT_LT(ticks, 2000) << "the vented PAM should not hold the arm";
  EXPECT_EQ(rig.board().mode(), BoardMode::kIdle);
}

TEST(ForearmBoard, RefusesHoldAndRunWithoutSensorData) {
  Rig rig;
  Board& board = rig.board();
  rig.run(20, {true, false});
  rig.command(RequestedMode::kHold);
  EXPECT_EQ(board.mode(), BoardMode::kIdle);
  rig.command(RequestedMode::kRun);
  EXPECT_EQ(board.mode(), BoardMode::kIdle);
  EXPECT_EQ(board.counters().refused_commands, 2u);

  // Readings that have gone stale (more than 5 ms old) count as none.
  rig.command(RequestedMode::kIdle);
  rig.run(20);
  rig.run(6, {true, false});
  rig.command(RequestedMode::kHold);
  EXPECT_EQ(board.mode(), BoardMode::kIdle);
  EXPECT_EQ(board.counters().refused_commands, 3u);
  rig.run(10, {true, false});
  expect_safe(rig, board);

  // Fresh readings again: the same command is honoured.
  rig.command(RequestedMode::kIdle);
  rig.run(2);
  rig.command(RequestedMode::kHold);
  EXPECT_EQ(board.mode(), BoardMode::kHold);
}

TEST(ForearmBoard, InvalidFramesAreRejectedCountedAndNotActedOn) {
  Rig rig;
  Board& board = rig.board();
  rig.run(20);
  ASSERT_EQ(board.mode(), BoardMode::kIdle);
  const proto::RejectCounters& rejects = board.rejects();

  // Each frame below asks for hold and the board could hold: only the defect stops it.
  proto::Frame f = rig.encode_command(RequestedMode::kHold);
  f.data[5] ^= 0x10;  // one flipped bit in host_time
  rig.deliver(f);
  EXPECT_EQ(rejects.bad_checksum, 1u);

  f = rig.encode_command(RequestedMode::kHold);
  f.dlc = 7;
  rig.deliver(f);
  EXPECT_EQ(rejects.wrong_length, 1u);

  // A repeat of the last accepted counter, whatever the payload.
  rig.command(RequestedMode::kIdle);
  proto::ModeCommand replay{RequestedMode::kHold, Strategy::kTwoStage, false, rig.now_us(),
                            rig.last_host_counter()};
  ASSERT_EQ(proto::encode(replay, kNode, f), proto::EncodeResult::kOk);
  rig.deliver(f);
  EXPECT_EQ(rejects.stale_counter, 1u);

  // Requested mode 0 and 7 with a correct checksum.
  for (std::uint8_t mode : {0, 7}) {
    f = rig.encode_command(RequestedMode::kHold);
    f.data[1] = std::uint8_t((f.data[1] & 0x0F) | (mode << 4));
    f.data[proto::kChecksumByte] = proto::frame_checksum(f);
    rig.deliver(f);
  }
  EXPECT_EQ(rejects.unknown_mode, 2u);

  // A strategy that does not exist, in a run command.
  f = rig.encode_command(RequestedMode::kRun);
  f.data[2] = std::uint8_t((f.data[2] & 0xF0) | 9);
  f.data[proto::kChecksumByte] = proto::frame_checksum(f);
  rig.deliver(f);
  EXPECT_EQ(rejects.unknown_enum, 1u);

  // A target angle beyond +-pi.
  proto::Sender trajectory_sender(kNode);
  ASSERT_EQ(trajectory_sender.encode(proto::TrajectorySample{0.5f, rig.now_us(), 0}, f),
            proto::EncodeResult::kOk);
  f.data[2] = 0xFF;
  f.data[3] = 0x7F;  // raw 32767 > 31416
  f.data[proto::kChecksumByte] = proto::frame_checksum(f);
  rig.deliver(f);
  EXPECT_EQ(rejects.out_of_range, 1u);

  // Another board's command: not this board's business, so neither acted on nor counted
  // (on a shared bus that would count every other node's traffic). Relabelled with this
  // node's id it fails the checksum, which covers the id.
  proto::Sender other_host(kNode + 1);
  ASSERT_EQ(
      other_host.encode(
          proto::ModeCommand{RequestedMode::kHold, Strategy::kTwoStage, false, rig.now_us(), 0}, f),
      proto::EncodeResult::kOk);
  rig.deliver(f);
  EXPECT_EQ(rejects.total(), 7u);
  f.id = proto::frame_id(proto::FrameType::kModeCommand, kNode);
  rig.deliver(f);
  EXPECT_EQ(rejects.bad_checksum, 2u);
  EXPECT_EQ(rejects.total(), 8u);

  EXPECT_EQ(board.mode(), BoardMode::kIdle);
  EXPECT_EQ(board.counters().refused_commands, 0u);
  rig.run(kHeartbeatPeriodTicks, {false, true});
  EXPECT_EQ(board.mode(), BoardMode::kIdle);
  expect_safe(rig, board);
  EXPECT_EQ(rig.last_status().rejected_frames, 8);

  // The rejected frames left the counter tracking intact: a valid command still works.
  rig.command(RequestedMode::kHold);
  EXPECT_EQ(board.mode(), BoardMode::kHold);
  EXPECT_EQ(rejects.total(), 8u);
}

TEST(ForearmBoard, HeartbeatLossFaultsToSafeOutputsWithinTwoPeriods) {
  Rig rig;
  Board& board = rig.board();
  rig.run(20);
  rig.command(RequestedMode::kHold);
  rig.run(95);
  ASSERT_EQ(board.mode(), BoardMode::kHold);
  const std::uint64_t last_heartbeat_step = rig.steps() - 5;  // heartbeats go every 10 steps

  while (board.mode() != BoardMode::kFault && rig.steps() < last_heartbeat_step + 100) {
    rig.run(1, {false, true});
  }
  ASSERT_EQ(board.mode(), BoardMode::kFault);
  const std::uint64_t fault_step = rig.steps() - 1;
  EXPECT_LE(fault_step - last_heartbeat_step, std::uint64_t(2 * kHeartbeatPeriodTicks));
  EXPECT_GT(fault_step - last_heartbeat_step, std::uint64_t(kHeartbeatPeriodTicks));
  expect_safe(rig, board);  // the very tick it faulted
  EXPECT_TRUE(board.faults() & proto::fault::kHeartbeatTimeout);
  EXPECT_EQ(board.counters().watchdog_trips, 1u);
  rig.run(kHeartbeatPeriodTicks, {false, true});
  EXPECT_EQ(rig.last_status().mode, BoardMode::kFault);
  EXPECT_TRUE(rig.last_status().faults & proto::fault::kHeartbeatTimeout);
  EXPECT_EQ(rig.last_status().watchdog_trips, 1);

  // The host is back, asking for run: the fault is latched, the command refused.
  rig.command(RequestedMode::kRun);
  rig.run(50);
  EXPECT_EQ(board.mode(), BoardMode::kFault);
  EXPECT_GE(board.counters().refused_commands, 1u);
  expect_safe(rig, board);
  // Idle alone does not clear it either.
  rig.command(RequestedMode::kIdle);
  rig.run(20);
  EXPECT_EQ(board.mode(), BoardMode::kFault);
  expect_safe(rig, board);
  // Idle with clear_faults does.
  rig.command(RequestedMode::kIdle, Strategy::kTwoStage, true);
  EXPECT_EQ(board.mode(), BoardMode::kIdle);
  EXPECT_EQ(board.faults(), 0);
  rig.command(RequestedMode::kHold);
  EXPECT_EQ(board.mode(), BoardMode::kHold);
}

// Root mean square of theta_d - theta while in run, after the first second.
struct Tracking {
  double sum_squares = 0;
  int samples = 0;
  double rms() const { return std::sqrt(sum_squares / samples); }
};

void run_tracking(Rig& rig, int ticks, Tracking* tracking) {
  for (int i = 0; i < ticks; ++i) {
    rig.run(1);
    ASSERT_EQ(rig.board().mode(), BoardMode::kRun) << "at " << rig.now_s() << " s";
    if (tracking != nullptr) {
      const double e = rig.theta_d(rig.now_s()) - rig.plant()(0);
      tracking->sum_squares += e * e;
      ++tracking->samples;
    }
  }
}

// Idle, hold, then run with a 0.5 Hz +-30 deg target streamed ahead.
void start_tracking(Rig& rig, Strategy strategy) {
  rig.run(20);
  rig.command(RequestedMode::kHold);
  rig.run(100);
  rig.stream_sinusoid();
  rig.command(RequestedMode::kRun, strategy);
  ASSERT_EQ(rig.board().mode(), BoardMode::kRun);
  ASSERT_EQ(rig.board().strategy(), strategy);
}

TEST(ForearmBoard, TwoStageRunTracksTheStreamedTrajectory) {
  Rig rig;
  start_tracking(rig, Strategy::kTwoStage);
  const std::uint32_t steps_before = rig.board().counters().mpc_steps;
  run_tracking(rig, 1000, nullptr);
  Tracking tracking;
  run_tracking(rig, 3000, &tracking);
  EXPECT_LT(tracking.rms(), 0.1);
  std::printf("two-stage on the board: RMS error %.4f rad over 3 s after the first second\n",
              tracking.rms());
  const auto& c = rig.board().counters();
  EXPECT_EQ(c.mpc_steps - steps_before, 1000u);  // every 4 ms
  EXPECT_EQ(c.overruns, 0u);                     // no wall clock: no deadline
  EXPECT_EQ(c.fallbacks, 0u);
  EXPECT_EQ(rig.board().faults(), 0);
  EXPECT_EQ(rig.last_status().mode, BoardMode::kRun);
  EXPECT_EQ(rig.last_status().strategy, Strategy::kTwoStage);
  EXPECT_NE(rig.last_command().v_m, 0.0f);  // the motor takes part
}

// Offset-free MPC on plants that differ from the board's model, each mismatch alone and all
// together (our choices: a payload of 30 % of the arm's mass, twice the friction, a valve 50 %
// slower): the Two-stage MPC holds a constant target at 0.3 rad. With the disturbance
// observer's estimate in its model and the torque penalty counted beyond the holding torque,
// the mean error over the last 2 s is at most 0.1 deg whatever the mismatch; the thesis's
// method, printed beside it, settles off the target by an amount that grows with the payload.
struct Mismatch {
  const char* name;
  double mass, friction, valve;
};
constexpr Mismatch kMismatches[] = {{"none", 1, 1, 1},
                                    {"payload +30 %", 1.3, 1, 1},
                                    {"friction x2", 1, 2, 1},
                                    {"valve 50 % slower", 1, 1, 1.5},
                                    {"all three", 1.3, 2, 1.5}};

// A rig whose plant has the mismatch, its board (offset-free or not) running the Two-stage MPC
// on theta_d = offset + A sin(2 pi f t) after 100 ms of hold.
std::unique_ptr<Rig> mismatched_run(const Mismatch& m, bool offset_free, double amplitude,
                                    double frequency_hz, double offset) {
  hmpc::forearm::Parameters<double> plant;
  plant.mass *= m.mass;
  plant.viscous_friction *= m.friction;
  plant.coulomb_friction *= m.friction;
  plant.T_p *= m.valve;
  Board::Config config = Rig::config();
  config.offset_free = offset_free;
  auto rig = std::make_unique<Rig>(0.0, nullptr, config, plant);
  rig->run(20);
  rig->command(RequestedMode::kHold);
  rig->run(100);
  rig->stream_sinusoid(amplitude, frequency_hz, offset);
  rig->command(RequestedMode::kRun, Strategy::kTwoStage);
  return rig;
}

double settled_error(const Mismatch& m, bool offset_free, double* estimate) {
  const std::unique_ptr<Rig> run = mismatched_run(m, offset_free, 0, 0, 0.3);
  Rig& rig = *run;
  run_tracking(rig, 2000, nullptr);
  double sum = 0;
  for (int i = 0; i < 2000; ++i) {
    rig.run(1);
    sum += std::abs(rig.plant()(0) - rig.theta_d(rig.now_s()));
  }
  *estimate = rig.board().disturbance_estimate();
  return sum / 2000;
}

TEST(ForearmBoard, OffsetFreeMpcHoldsAConstantTargetOnMismatchedPlants) {
  constexpr double kDeg = M_PI / 180;
  double thesis_none = 0, thesis_payload = 0;
  for (const Mismatch& m : kMismatches) {
    double d_free = 0, d_thesis = 0;
    const double e_free = settled_error(m, true, &d_free);
    const double e_thesis = settled_error(m, false, &d_thesis);
    std::printf(
        "%-18s mean |error| over the last 2 s: offset-free %.4f deg (estimate %.3f N m), "
        "thesis %.4f deg\n",
        m.name, e_free / kDeg, d_free, e_thesis / kDeg);
    EXPECT_LE(e_free, 0.1 * kDeg) << m.name;
    if (m.mass == 1 && m.friction == 1 && m.valve == 1) thesis_none = e_thesis;
    if (m.mass > 1 && m.friction == 1) thesis_payload = e_thesis;
  }
  EXPECT_GT(thesis_payload, thesis_none);  // without the estimate the payload shows
}

// The same plants tracking the thesis's +-30 deg sinusoids at 0.5 and 1 Hz (RMS error over
// 3 s after the first second), with the disturbance estimate and without, side by side: with
// it, the error is lower on every plant and grows less with the mismatch.
double sinusoid_rms(const Mismatch& m, bool offset_free, double frequency_hz) {
  const std::unique_ptr<Rig> run = mismatched_run(m, offset_free, kAmplitude, frequency_hz, 0);
  Rig& rig = *run;
  run_tracking(rig, 1000, nullptr);
  Tracking tracking;
  run_tracking(rig, 3000, &tracking);
  return tracking.rms();
}

TEST(ForearmBoard, OffsetFreeMpcTracksSinusoidsOnMismatchedPlants) {
  const auto& cases = kMismatches;
  constexpr double kDeg = M_PI / 180;
  for (const double f : {0.5, 1.0}) {
    double free_rms[5], thesis_rms[5];
    for (int i = 0; i < 5; ++i) {
      free_rms[i] = sinusoid_rms(cases[i], true, f);
      thesis_rms[i] = sinusoid_rms(cases[i], false, f);
      std::printf("%.1f Hz %-18s RMS error: offset-free %.3f deg, thesis %.3f deg\n", f,
                  cases[i].name, free_rms[i] / kDeg, thesis_rms[i] / kDeg);
      // The estimate removes the bias the thesis's model and torque penalty leave.
      EXPECT_LT(free_rms[i], thesis_rms[i]) << f << " Hz, " << cases[i].name;
    }
    // All three mismatches together cost the offset-free MPC less than they cost the thesis's.
    EXPECT_LT(free_rms[4] - free_rms[0], thesis_rms[4] - thesis_rms[0]) << f << " Hz";
  }
}

// The board's Two-stage with the terminal rate term (the board's --terminal-rate) on the
// thesis's +-30 deg at 1.8 Hz, RMS over 3 s after the first second, on the model's plant: the
// term reaches the board's MPC and lowers the error the thesis's cost leaves where the target
// outruns the valve.
TEST(ForearmBoard, TerminalRateTermLowersTheTwoStagesErrorAt1_8Hz) {
  double rms[2];
  for (int with_term = 0; with_term < 2; ++with_term) {
    Board::Config config = Rig::config();
    config.two_stage_terminal_rate = with_term == 1;
    Rig rig(0.0, nullptr, config);
    rig.run(20);
    rig.command(RequestedMode::kHold);
    rig.run(100);
    rig.stream_sinusoid(kAmplitude, 1.8, 0);
    rig.command(RequestedMode::kRun, Strategy::kTwoStage);
    run_tracking(rig, 1000, nullptr);
    Tracking tracking;
    run_tracking(rig, 3000, &tracking);
    rms[with_term] = tracking.rms();
  }
  std::printf("1.8 Hz RMS error: thesis %.2f deg, terminal rate term %.2f deg\n",
              rms[0] * 180 / M_PI, rms[1] * 180 / M_PI);
  EXPECT_LT(rms[1], rms[0]);
}

// A CostWeights frame in run: every strategy solves with the new weights from the next MPC
// step on, the weights sent as 0 unchanged; the run goes on.
TEST(ForearmBoard, CostWeightsAreAdoptedByEveryStrategyBeforeTheNextStep) {
  Rig rig;
  start_tracking(rig, Strategy::kTwoStage);
  run_tracking(rig, 100, nullptr);
  const hmpc::forearm::CostWeights<double> before{};
  rig.send_from_host(proto::CostWeights{80, 0, 0, 0.004f, 0});
  EXPECT_EQ(rig.board().solver_weights(Strategy::kTwoStage).w_theta, before.w_theta)
      << "not while the MPC may be solving";
  run_tracking(rig, 4, nullptr);
  for (const proto::EnumValue& s : proto::kStrategyValues) {
    const auto& w = rig.board().solver_weights(static_cast<Strategy>(s.value));
    EXPECT_EQ(w.w_theta, 80) << s.name;
    EXPECT_EQ(w.w_P, before.w_P) << s.name;
    EXPECT_EQ(w.w_tau, before.w_tau) << s.name;
    EXPECT_NEAR(w.w_v, 0.004, 1e-9) << s.name;
  }
  EXPECT_EQ(rig.board().counters().cost_weight_updates, 1u);
  run_tracking(rig, 500, nullptr);
  EXPECT_EQ(rig.board().faults(), 0);
}

TEST(ForearmBoard, SwitchesStrategyInRun) {
  Rig rig;
  start_tracking(rig, Strategy::kTwoStage);
  run_tracking(rig, 1500, nullptr);
  rig.command(RequestedMode::kRun, Strategy::kCoarse20ms);
  EXPECT_EQ(rig.board().mode(), BoardMode::kRun);
  EXPECT_EQ(rig.board().strategy(), Strategy::kCoarse20ms);
  Tracking tracking;
  run_tracking(rig, 2000, &tracking);
  EXPECT_LT(tracking.rms(), 0.1);
  EXPECT_EQ(rig.last_status().strategy, Strategy::kCoarse20ms);
  EXPECT_EQ(rig.board().faults(), 0);

  // PAM only: the motor is left out.
  rig.command(RequestedMode::kRun, Strategy::kPamOnly);
  run_tracking(rig, 500, nullptr);
  EXPECT_EQ(rig.board().strategy(), Strategy::kPamOnly);
  EXPECT_EQ(rig.last_command().v_m, 0.0f);
}

TEST(ForearmBoard, RepeatedOverrunsFallBackToHold) {
  Rig rig(0.0, &slow_clock);
  Board& board = rig.board();
  start_tracking(rig, Strategy::kTwoStage);
  const int max_bad = Rig::config().max_consecutive_bad_steps;
  rig.run(Board::kTicksPerMpcStep * max_bad);
  EXPECT_EQ(board.mode(), BoardMode::kHold);
  EXPECT_TRUE(board.faults() & proto::fault::kSolverFallback);
  EXPECT_EQ(board.counters().overruns, std::uint32_t(max_bad));
  EXPECT_EQ(board.counters().fallbacks, 1u);
  EXPECT_EQ(board.counters().mpc_steps, std::uint32_t(max_bad));
  // The host's heartbeat still asks for run: refused until the fallback bit is cleared.
  const std::uint32_t refused = board.counters().refused_commands;
  rig.run(3 * kHeartbeatPeriodTicks);
  EXPECT_EQ(rig.last_status().mode, BoardMode::kHold);
  EXPECT_GT(board.counters().refused_commands, refused);
  EXPECT_EQ(rig.last_status().overruns, max_bad);
  EXPECT_TRUE(rig.last_status().faults & proto::fault::kSolverFallback);
  // Hold keeps carrying the arm meanwhile.
  rig.run(500);
  EXPECT_EQ(board.mode(), BoardMode::kHold);
  EXPECT_LT(std::abs(rig.plant()(0)), 0.05);
  EXPECT_GT(rig.last_command().v_p, 0.5f);
}

// HIL lock-step emulation of the target's compute time: a solve charged 10 ms acts 10 ticks
// after it started, the previous output holding meanwhile; no step starts while one is
// pending, so steps come every 12 ticks (the next 4 ms boundary); each counts as an overrun
// but, as on the thesis's board, causes no fallback.
TEST(ForearmBoard, EmulatedTargetDelaysEachOutputByItsChargedComputeTime) {
  hmpc::ComputeCostModel ten_ms_per_solve{};
  ten_ms_per_solve.instructions_per_update = 4e6;
  ten_ms_per_solve.clock_hz = 400e6;
  Board::Config config = Rig::config();
  config.emulated_target = &ten_ms_per_solve;
  Rig rig(0.0, nullptr, config);
  Board& board = rig.board();
  start_tracking(rig, Strategy::kTwoStage);
  std::vector<std::uint64_t> step_ticks, change_ticks;
  float previous_v_m = rig.last_command().v_m;
  std::uint32_t steps = board.counters().mpc_steps;
  for (int i = 0; i < 240; ++i) {
    rig.run(1);
    if (board.counters().mpc_steps != steps) step_ticks.push_back(board.ticks());
    if (rig.last_command().v_m != previous_v_m) change_ticks.push_back(board.ticks());
    steps = board.counters().mpc_steps;
    previous_v_m = rig.last_command().v_m;
  }
  ASSERT_GE(step_ticks.size(), 19u);
  for (std::size_t i = 1; i < step_ticks.size(); ++i) {
    EXPECT_EQ(step_ticks[i] - step_ticks[i - 1], 12u) << "step " << i;
  }
  // The motor output changes only when a solve becomes ready, 10 ticks after it started.
  ASSERT_FALSE(change_ticks.empty());
  for (const std::uint64_t t : change_ticks) {
    EXPECT_NE(std::find(step_ticks.begin(), step_ticks.end(), t - 10), step_ticks.end())
        << "output changed at tick " << t << " with no solve started 10 ticks before";
  }
  EXPECT_EQ(board.counters().overruns, board.counters().mpc_steps);
  EXPECT_EQ(board.counters().fallbacks, 0u);
  EXPECT_EQ(board.mode(), BoardMode::kRun);
}

// Charged less than a tick, a solve acts at the next tick and steps keep their 4 ms period.
TEST(ForearmBoard, EmulatedFastTargetKeepsTheFourMillisecondPeriod) {
  hmpc::ComputeCostModel instant{};
  instant.clock_hz = 400e6;
  Board::Config config = Rig::config();
  config.emulated_target = &instant;
  Rig rig(0.0, nullptr, config);
  start_tracking(rig, Strategy::kTwoStage);
  const std::uint32_t before = rig.board().counters().mpc_steps;
  run_tracking(rig, 400, nullptr);
  EXPECT_EQ(rig.board().counters().mpc_steps - before, 100u);
  EXPECT_EQ(rig.board().counters().overruns, 0u);
}

// Heartbeats that arrive one or two ticks late (bus and scheduling jitter) must not move the
// board's idea of the host's trajectory clock: the same run with and without the jitter
// applies the same outputs at every tick.
TEST(ForearmBoard, HeartbeatLatencyJitterDoesNotMoveTheTargetClock) {
  const auto run = [](StepOptions options) {
    Rig rig;
    rig.run(20, options);
    rig.command(RequestedMode::kHold);
    rig.run(100, options);
    rig.stream_sinusoid();
    rig.command(RequestedMode::kRun, Strategy::kTwoStage);
    std::vector<float> v_m;
    for (int i = 0; i < 600; ++i) {
      rig.run(1, options);
      v_m.push_back(rig.last_command().v_m);
    }
    EXPECT_EQ(rig.board().mode(), BoardMode::kRun);
    return v_m;
  };
  StepOptions jittered;
  jittered.heartbeat_delay = [](std::uint64_t tick) { return int((tick / 10) % 3 == 1 ? 2 : 1); };
  StepOptions steady;
  steady.heartbeat_delay = [](std::uint64_t) { return 1; };
  const std::vector<float> a = run(steady), b = run(jittered);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a[i], b[i]) << "tick " << i;
}

}  // namespace
