// The hydraulic joint board application (firmware/app/joint_board.hpp) driven directly, without
// a bus: a host (joint_protocol::Sender) sends heartbeats, torque references, gains and the
// E-stop; a plant, each joint a hydraulic actuator (models/hydraulic_joint.hpp) swinging a
// pendulum, integrated by RK4 at 20 us, sends the I/O frames (encoder, load cell, chamber
// pressures) before every tick and applies the ValveDrive the board sends back. Board frames
// are decoded by a host-side Receiver, so every one of them must pass the protocol's checks.
#include "joint_board.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <memory>

#include "hmpc/models/hydraulic_pendulum.hpp"

namespace {

namespace proto = hmpc::joint_protocol;
namespace hy = hmpc::hydraulic;
using Board = hmpc::firmware::JointBoard<double>;
using proto::BoardMode;
using proto::RequestedMode;

constexpr proto::NodeId kNode = 2;
constexpr int kHeartbeatPeriodTicks = 10;  // the protocol's ModeCommand period
// The plant's encoders read the joint angle plus a mounting offset that zeroing must find.
constexpr double kMountingOffset = 0.3;

// One joint: the actuator driving a shank-sized link that hangs under gravity
// (models/hydraulic_pendulum.hpp), theta = 0 hanging.
struct JointPlant {
  hy::JointActuatorParameters<double> actuator{};
  hy::PendulumLoad<double> load = hy::PendulumLoad<double>::shank();
  hy::PendulumState<double> x = hy::torque_free_rest(actuator);
  bool locked = false;  // the link clamped, as on a torque test stand

  double theta() const { return x.theta; }
  double omega() const { return x.omega; }
  double torque() const { return hy::joint_torque(actuator, x.actuator, x.omega); }
  double gravity_torque(double theta) const { return load.gravity_torque(theta); }
  void step(double u, double dt) { hy::step_pendulum(actuator, load, x, u, dt, 50, locked); }
};

struct StepOptions {
  bool heartbeat = true;   // the host's ModeCommand every 10 ms
  bool sensors = true;     // the plant's I/O frames every tick
  bool references = true;  // the host's TorqueReference every control period, if streaming
};

class Rig {
 public:
  explicit Rig(std::size_t joints = 2, const Board::Config& board_config = config(2))
      : board_(std::make_unique<Board>(with_joints(board_config, joints))), joints_(joints) {}

  static Board::Config config(std::size_t joints) {
    Board::Config c;
    c.node = kNode;
    c.joints = joints;
    return c;
  }
  static Board::Config with_joints(Board::Config c, std::size_t joints) {
    c.joints = joints;
    return c;
  }

  Board& board() { return *board_; }
  JointPlant& plant(std::size_t j) { return plant_[j]; }
  std::uint64_t ticks() const { return tick_; }
  const proto::RejectCounters& board_frame_rejects() const { return from_board_.rejects; }
  const proto::BoardStatus& last_status() const { return status_; }
  const proto::EncoderOffset& last_offset_report() const { return offset_report_; }

  // ---- host ----
  void command(RequestedMode mode, bool clear_faults = false, bool zero_encoders = false) {
    requested_ = {};
    requested_.mode = mode;
    requested_.clear_faults = clear_faults;
    requested_.zero_encoders = zero_encoders;
    send_heartbeat();
    requested_.zero_encoders = false;  // a zeroing request is one heartbeat
  }
  void send_heartbeat() {
    proto::ModeCommand m = requested_;
    m.host_time_us = std::uint32_t(tick_ * 1000);
    deliver(encode(host_, m));
  }
  void deliver(const proto::Frame& frame) { board_->on_frame(frame); }
  template <class Message>
  proto::Frame encode(proto::Sender& sender, const Message& m) {
    proto::Frame f;
    EXPECT_EQ(sender.encode(m, f), proto::EncodeResult::kOk);
    return f;
  }
  proto::Sender& host() { return host_; }

  // The torque references streamed from now on: reference(joint, t, the joint's plant), which
  // lets a test's host close a loop of its own around the board.
  using Reference = std::function<double(std::size_t, double, const JointPlant&)>;
  void stream(Reference reference) { reference_ = std::move(reference); }
  void send_reference(const std::array<float, proto::kMaxJointsPerBoard>& tau) {
    proto::TorqueReference r;
    r.tau = tau;
    deliver(encode(host_, r));
  }

  // Zeroes the encoders with the joints where they are (the zero posture the config states:
  // 0, hanging) and asks for mode.
  void zero_and_enter(RequestedMode mode) {
    run(20);
    command(RequestedMode::kIdle, false, true);
    run(10);
    command(mode);
  }

  // ---- one millisecond of host, plant and board ----
  void step(StepOptions options = {}) {
    if (options.heartbeat && tick_ % kHeartbeatPeriodTicks == 0) send_heartbeat();
    const int period = board_->config().control_period_ticks;
    if (options.references && reference_ && tick_ % std::uint64_t(period) == 0) {
      std::array<float, proto::kMaxJointsPerBoard> tau{};
      for (std::size_t j = 0; j < joints_; ++j) {
        tau[j] = float(reference_(j, 1e-3 * double(tick_), plant_[j]));
      }
      send_reference(tau);
    }
    if (options.sensors) send_sensors();
    board_->tick();
    collect_board_frames();
    for (std::size_t j = 0; j < joints_; ++j) plant_[j].step(last_drive_.u[j], 1e-3);
    ++tick_;
  }
  void run(int ticks, StepOptions options = {}) {
    for (int i = 0; i < ticks; ++i) step(options);
  }

 private:
  void send_sensors() {
    for (std::size_t j = 0; j < joints_; ++j) {
      const JointPlant& p = plant_[j];
      send_joint_sensor(j, float(p.theta() + kMountingOffset), float(p.omega()), float(p.torque()));
    }
    for (std::size_t first = 0; first < joints_; first += 2) {
      std::array<float, 2> p_a{}, p_b{};
      // Pressure sensors read 0..32 MPa and saturate beyond (the model has no cavitation
      // floor: a joint locked in motion can swing a chamber below zero gauge).
      const auto sensor = [](double pascal) { return float(std::clamp(pascal * 1e-6, 0.0, 32.0)); };
      for (std::size_t i = 0; i < 2 && first + i < joints_; ++i) {
        p_a[i] = sensor(plant_[first + i].x.actuator.pressure_a);
        p_b[i] = sensor(plant_[first + i].x.actuator.pressure_b);
      }
      if (first == 0) {
        proto::ChamberPressures01 m;
        m.p_a = p_a;
        m.p_b = p_b;
        deliver(encode(plant_sender_, m));
      } else {
        proto::ChamberPressures23 m;
        m.p_a = p_a;
        m.p_b = p_b;
        deliver(encode(plant_sender_, m));
      }
    }
  }
  void send_joint_sensor(std::size_t j, float theta, float omega, float tau) {
    switch (j) {
      case 0: deliver(encode(plant_sender_, proto::JointSensor<0>{theta, omega, tau, 0})); break;
      case 1: deliver(encode(plant_sender_, proto::JointSensor<1>{theta, omega, tau, 0})); break;
      case 2: deliver(encode(plant_sender_, proto::JointSensor<2>{theta, omega, tau, 0})); break;
      default: deliver(encode(plant_sender_, proto::JointSensor<3>{theta, omega, tau, 0})); break;
    }
  }
  void collect_board_frames() {
    proto::Frame f;
    while (board_->pop_frame(f)) {
      proto::FrameType type{};
      proto::NodeId node = 0;
      ASSERT_TRUE(proto::identify(f.id, type, node));
      ASSERT_EQ(node, kNode);
      switch (type) {
        case proto::FrameType::kValveDrive: from_board_.decode(f, last_drive_); break;
        case proto::FrameType::kBoardStatus: from_board_.decode(f, status_); break;
        case proto::FrameType::kEncoderOffset: from_board_.decode(f, offset_report_); break;
        case proto::FrameType::kValveCommands: {
          proto::ValveCommands v;
          from_board_.decode(f, v);
          break;
        }
        case proto::FrameType::kJointState0: {
          proto::JointState<0> s;
          from_board_.decode(f, s);
          break;
        }
        case proto::FrameType::kJointState1: {
          proto::JointState<1> s;
          from_board_.decode(f, s);
          break;
        }
        default: ADD_FAILURE() << "unexpected board frame 0x" << std::hex << f.id;
      }
    }
  }

  std::unique_ptr<Board> board_;
  std::size_t joints_;
  std::array<JointPlant, proto::kMaxJointsPerBoard> plant_{};
  proto::Sender host_{kNode};
  proto::Sender plant_sender_{kNode};
  proto::Receiver from_board_{kNode};
  proto::ModeCommand requested_{};
  Reference reference_;
  proto::ValveDrive last_drive_{};
  proto::BoardStatus status_{};
  proto::EncoderOffset offset_report_{};
  std::uint64_t tick_ = 0;
};

double zero_torque(std::size_t, double, const JointPlant&) { return 0.0; }
Rig::Reference constant_torque(double tau) {
  return [tau](std::size_t, double, const JointPlant&) { return tau; };
}
// A host holding the link at `angle`: gravity compensation and a PD, from the plant's state (as
// a host would from the boards' JointState frames).
Rig::Reference host_holding_at(double angle) {
  return [angle](std::size_t, double, const JointPlant& p) {
    return p.gravity_torque(p.theta()) + 20 * (angle - p.theta()) - 4 * p.omega();
  };
}

// ---------------------------------------------------------------------------------------

TEST(JointBoard, BootsIntoIdleWithValvesCentredAndReportsItself) {
  Rig rig;
  rig.run(40);
  EXPECT_EQ(rig.board().mode(), BoardMode::kIdle);
  for (const double u : rig.board().valve_commands()) EXPECT_EQ(u, 0.0);
  EXPECT_EQ(rig.last_status().mode, BoardMode::kIdle);
  EXPECT_EQ(rig.last_status().joints, 2);
  EXPECT_EQ(rig.last_status().protocol_version, proto::kProtocolVersion);
  EXPECT_EQ(rig.board_frame_rejects().total(), 0u);
}

TEST(JointBoard, RefusesHoldAndRunBeforeZeroing) {
  Rig rig;
  rig.stream(zero_torque);
  rig.run(21);
  rig.command(RequestedMode::kHold);
  rig.run(1);
  EXPECT_EQ(rig.board().mode(), BoardMode::kIdle);
  rig.command(RequestedMode::kRun);
  rig.run(1);
  EXPECT_EQ(rig.board().mode(), BoardMode::kIdle);
  EXPECT_EQ(rig.board().counters().refused_commands, 2u);
  EXPECT_TRUE(rig.board().faults() & proto::fault::kNotZeroed);
}

// Zeroing takes each offset so that the present angle reads the zero posture; the offsets are
// reported, flagged as taken since boot.
TEST(JointBoard, ZeroingFindsTheMountingOffsetAndReportsIt) {
  Rig rig;
  rig.run(20);
  EXPECT_NEAR(rig.board().measurement(0).theta, kMountingOffset, 1e-3);  // stored offset 0
  rig.command(RequestedMode::kIdle, false, true);
  rig.run(300);
  EXPECT_TRUE(rig.board().zeroed());
  for (std::size_t j = 0; j < 2; ++j) {
    EXPECT_NEAR(rig.board().encoder_offset(j), kMountingOffset, 2e-4);  // the encoder's step
    EXPECT_NEAR(rig.board().measurement(j).theta, rig.plant(j).theta(), 2e-4);
  }
  EXPECT_TRUE(rig.last_offset_report().zeroed);
  EXPECT_NEAR(rig.last_offset_report().offset, kMountingOffset, 2e-4);
}

// Hold keeps each link where it was when hold began, against gravity, and takes the motion out
// of a link that was moving: entered while the host swings joint 0 up at about 1 rad/s. Valves
// merely centred would leave it ringing on the oil's stiffness (about 17 Hz, damped only by
// seal friction, a few thousandths of critical); the hold PID's damping brings it to rest.
TEST(JointBoard, HoldStopsAMovingLinkAndKeepsThePosture) {
  Rig rig;
  rig.plant(1).x.theta = 0.2;
  rig.stream(host_holding_at(0.4));
  rig.zero_and_enter(RequestedMode::kRun);
  while (rig.plant(0).omega() < 0.8 && rig.ticks() < 2000) rig.step();
  ASSERT_EQ(rig.board().mode(), BoardMode::kRun);
  ASSERT_GE(rig.plant(0).omega(), 0.8);
  rig.stream(nullptr);
  rig.command(RequestedMode::kHold);
  rig.run(1);
  ASSERT_EQ(rig.board().mode(), BoardMode::kHold);
  const double target_0 = rig.board().hold_target(0), start_1 = rig.plant(1).theta();
  rig.run(1500);
  EXPECT_EQ(rig.board().mode(), BoardMode::kHold);
  EXPECT_LT(std::abs(rig.plant(0).omega()), 0.01);
  // Within 5 mrad: up to 2.3 N·m of gravity on the 300 N·m/rad hold, the integral taking it.
  EXPECT_NEAR(rig.board().measurement(0).theta, target_0, 0.005);
  EXPECT_NEAR(rig.plant(1).theta(), start_1, 0.005);
}

// On a clamped link the torque follows a 20 N·m reference step: after the rate limit's 60 ms
// and a few crossover periods of the tuned loop (58 rad/s), the integral has taken out the
// friction-free error.
TEST(JointBoard, RunTracksATorqueStepOnAClampedLink) {
  Rig rig(1, Rig::config(1));
  rig.plant(0).locked = true;
  rig.stream(zero_torque);
  rig.zero_and_enter(RequestedMode::kRun);
  rig.run(100);
  ASSERT_EQ(rig.board().mode(), BoardMode::kRun);
  rig.stream(constant_torque(20.0));
  rig.run(500);
  EXPECT_EQ(rig.board().mode(), BoardMode::kRun);
  EXPECT_NEAR(rig.plant(0).torque(), 20.0, 0.5);
  rig.stream(constant_torque(-15.0));
  rig.run(500);
  EXPECT_NEAR(rig.plant(0).torque(), -15.0, 0.5);
}

// A reference beyond a joint's torque limit refuses the whole frame; a bad counter is rejected
// by the codec: neither changes what the loops follow.
TEST(JointBoard, OutOfRangeOrReplayedReferencesChangeNothing) {
  Rig rig(1, Rig::config(1));
  rig.stream(zero_torque);
  rig.zero_and_enter(RequestedMode::kRun);
  rig.run(200, {true, true, false});
  rig.send_reference({2.0f, 0, 0, 0});
  rig.run(5, {true, true, false});
  rig.send_reference({float(rig.board().config().joint[0].torque_limit + 1), 0, 0, 0});
  // The same frame again: a repeated counter.
  proto::Frame replay;
  proto::TorqueReference big;
  big.tau = {50.0f, 0, 0, 0};
  ASSERT_EQ(rig.host().encode(big, replay), proto::EncodeResult::kOk);
  replay.data[1] =
      static_cast<std::uint8_t>((replay.data[1] & 0xF0) | ((replay.data[1] - 1) & 0x0F));
  replay.data[0] = proto::frame_checksum(replay);
  rig.deliver(replay);
  rig.run(6, {true, true, false});
  EXPECT_EQ(rig.board().counters().refused_references, 1u);
  EXPECT_EQ(rig.board().rejects().stale_counter, 1u);
  EXPECT_EQ(rig.board().applied_references()[0], 2.0f);  // rate limit: 12 N·m per step
}

// The applied reference moves at most torque_rate_limit x T per control period.
TEST(JointBoard, ReferenceStepsAreRateLimited) {
  Rig rig(1, Rig::config(1));
  rig.stream(zero_torque);
  rig.zero_and_enter(RequestedMode::kRun);
  rig.run(200);
  rig.stream(constant_torque(50.0));
  const double per_step = rig.board().config().joint[0].torque_rate_limit * 0.006;
  double previous = rig.board().applied_references()[0];
  for (int period = 0; period < 8; ++period) {
    rig.run(6);
    const double now = rig.board().applied_references()[0];
    EXPECT_LE(now - previous, per_step + 1e-9);
    previous = now;
  }
  EXPECT_NEAR(previous, 50.0, 1e-9);  // 50 N·m in 5 periods of 12 N·m
}

// References stop while the heartbeat goes on: the board holds the posture it has, never the
// old torque, and returns to run when references flow again.
TEST(JointBoard, StaleReferenceHoldsThePostureThenRunResumes) {
  Rig rig(1, Rig::config(1));
  rig.stream(host_holding_at(0.4));
  rig.zero_and_enter(RequestedMode::kRun);
  rig.run(1500);
  ASSERT_EQ(rig.board().mode(), BoardMode::kRun);
  ASSERT_NEAR(rig.plant(0).theta(), 0.4, 0.05);
  rig.run(30, {true, true, false});
  EXPECT_EQ(rig.board().mode(), BoardMode::kHold);
  EXPECT_TRUE(rig.board().faults() & proto::fault::kStaleReference);
  EXPECT_EQ(rig.board().counters().stale_references, 1u);
  const double held = rig.board().hold_target(0);
  EXPECT_NEAR(held, rig.plant(0).theta(), 0.02);
  rig.run(1000, {true, true, false});
  EXPECT_EQ(rig.board().mode(), BoardMode::kHold);
  EXPECT_NEAR(rig.board().measurement(0).theta, held, 0.01);
  rig.run(30);  // references again; the heartbeat still asks for run
  EXPECT_EQ(rig.board().mode(), BoardMode::kRun);
}

// Heartbeat lost: the safe state at the timeout (30 ticks after the last heartbeat, five 6 ms
// control periods), valves centred from that tick on.
TEST(JointBoard, HeartbeatLossGoesSafeAtTheTimeout) {
  Rig rig(1, Rig::config(1));
  rig.stream(host_holding_at(0.3));
  rig.zero_and_enter(RequestedMode::kRun);
  rig.run(300);
  ASSERT_EQ(rig.board().mode(), BoardMode::kRun);
  while (rig.ticks() % kHeartbeatPeriodTicks != 0) rig.step();
  rig.step();  // this tick's heartbeat is the last
  int ticks_to_fault = 0;
  while (rig.board().mode() != BoardMode::kFault && ticks_to_fault < 200) {
    rig.step({false, true, true});
    ++ticks_to_fault;
  }
  // The heartbeat arrived before the tick that followed it: that tick is the first of the
  // timeout, and the tick after the timeout's last faults.
  EXPECT_EQ(ticks_to_fault, rig.board().config().heartbeat_timeout_ticks);
  EXPECT_TRUE(rig.board().faults() & proto::fault::kHeartbeatTimeout);
  for (const double u : rig.board().valve_commands()) EXPECT_EQ(u, 0.0);
}

// A valid E-stop faults the board in the tick it arrives, from any mode, and stays latched
// until an idle command with clear_faults.
TEST(JointBoard, EStopActsAtOnceAndLatches) {
  Rig rig(1, Rig::config(1));
  rig.stream(host_holding_at(0.3));
  rig.zero_and_enter(RequestedMode::kRun);
  rig.run(300);
  ASSERT_NE(rig.board().valve_commands()[0], 0.0);
  rig.deliver(rig.encode(rig.host(), proto::EStop{}));
  EXPECT_EQ(rig.board().mode(), BoardMode::kFault);
  EXPECT_EQ(rig.board().valve_commands()[0], 0.0);
  rig.run(100);  // the host keeps asking for run: refused
  EXPECT_EQ(rig.board().mode(), BoardMode::kFault);
  EXPECT_TRUE(rig.board().faults() & proto::fault::kEStop);
  rig.command(RequestedMode::kIdle, true);
  rig.run(1);
  EXPECT_EQ(rig.board().mode(), BoardMode::kIdle);
  EXPECT_EQ(rig.board().faults(), 0);
  EXPECT_EQ(rig.board().counters().estops, 1u);
}

TEST(JointBoard, SoftJointLimitAndPressureLimitFault) {
  Board::Config tight = Rig::config(1);
  tight.joint[0].theta_max = 0.2;
  Rig rig(1, tight);
  rig.stream(host_holding_at(0.5));  // a host that drives the joint past its soft limit
  rig.zero_and_enter(RequestedMode::kRun);
  rig.run(1500);
  EXPECT_EQ(rig.board().mode(), BoardMode::kFault);
  EXPECT_TRUE(rig.board().faults() & proto::fault::kJointLimit);
  EXPECT_LT(rig.plant(0).theta(), 0.3);  // stopped by the locked valves near the limit

  Board::Config low = Rig::config(1);
  low.joint[0].pressure_limit = 5e6;  // below the plant's 6 MPa rod-side pressure
  Rig pressure_rig(1, low);
  pressure_rig.zero_and_enter(RequestedMode::kHold);
  pressure_rig.run(2);
  EXPECT_EQ(pressure_rig.board().mode(), BoardMode::kFault);
  EXPECT_TRUE(pressure_rig.board().faults() & proto::fault::kPressureLimit);
}

TEST(JointBoard, GainsForAJointItLacksOrUnusableAreRefused) {
  Rig rig(1, Rig::config(1));
  rig.run(5);
  proto::TorqueGains gains;
  gains.joint = 1;
  gains.kp = 0.002f;
  rig.deliver(rig.encode(rig.host(), gains));
  gains.joint = 0;
  rig.deliver(rig.encode(rig.host(), gains));
  proto::HoldGains hold;
  hold.joint = 3;
  rig.deliver(rig.encode(rig.host(), hold));
  EXPECT_EQ(rig.board().counters().refused_gains, 2u);
  EXPECT_FLOAT_EQ(float(rig.board().config().joint[0].torque_loop.kp), 0.002f);
}

// Sensors silent in hold: the sensor watchdog faults the board.
TEST(JointBoard, SensorSilenceFaults) {
  Rig rig;
  rig.zero_and_enter(RequestedMode::kHold);
  rig.run(50);
  ASSERT_EQ(rig.board().mode(), BoardMode::kHold);
  rig.run(10, {true, false, true});
  EXPECT_EQ(rig.board().mode(), BoardMode::kFault);
  EXPECT_TRUE(rig.board().faults() & proto::fault::kSensorTimeout);
}

TEST(JointBoardConfig, DefaultsAreValidAndBadOnesAreNamed) {
  Board::Config c;
  EXPECT_EQ(c.check(), nullptr);
  c.joints = 5;
  EXPECT_NE(c.check(), nullptr);
  c = Board::Config{};
  c.control_period_ticks = 7;
  EXPECT_NE(c.check(), nullptr);
  c = Board::Config{};
  c.joint[1].theta_min = 1.0;
  c.joint[1].theta_max = -1.0;
  EXPECT_NE(c.check(), nullptr);
  c = Board::Config{};
  c.joint[0].torque_loop.kp = std::nan("");
  EXPECT_NE(c.check(), nullptr);
}

}  // namespace
