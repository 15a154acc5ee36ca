// What a ROS 2 machine would receive: each message type goes through a real Cyclone DDS writer
// and reader (loopback, domain 90), and the serialised bytes the reader got are compared with an
// encoding written here from the ROS 2 definitions, field by field, by the rules of plain
// little-endian CDR (XCDR1) that rmw_cyclonedds uses: a 4-byte encapsulation header 00 01 00 00,
// then each primitive aligned to its own size (8 for float64) from the end of the header,
// strings as uint32 length with the NUL, then the bytes and the NUL, sequences as a uint32
// count then the elements, fixed arrays as their elements alone, nested structs inline.
#include <dds/dds.h>
#include <dds/ddsi/ddsi_serdata.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "hmpc/dds/endpoint.hpp"
#include "hmpc/dds/messages.hpp"
#include "hmpc/dds/participant.hpp"

namespace {

namespace dds = hmpc::dds;
namespace msg = hmpc::dds::msg;

constexpr std::uint32_t kDomain = 90;  // no other test uses it

// The expected payload, written from the definitions.
class Cdr {
 public:
  Cdr() : bytes_{0x00, 0x01, 0x00, 0x00} {}  // CDR_LE, options 0

  Cdr& u8(std::uint8_t v) { return put(&v, 1); }
  Cdr& u16(std::uint16_t v) { return put(&v, 2); }
  Cdr& i32(std::int32_t v) { return put(&v, 4); }
  Cdr& u32(std::uint32_t v) { return put(&v, 4); }
  Cdr& f64(double v) { return put(&v, 8); }
  Cdr& boolean(bool v) { return u8(v ? 1 : 0); }
  Cdr& str(const std::string& s) {
    u32(static_cast<std::uint32_t>(s.size() + 1));
    for (char c : s) bytes_.push_back(static_cast<std::uint8_t>(c));
    bytes_.push_back(0);
    return *this;
  }
  Cdr& f64s(const std::vector<double>& v) {  // sequence<double>
    u32(static_cast<std::uint32_t>(v.size()));
    for (double x : v) f64(x);
    return *this;
  }
  Cdr& strs(const std::vector<std::string>& v) {  // sequence<string>
    u32(static_cast<std::uint32_t>(v.size()));
    for (const auto& s : v) str(s);
    return *this;
  }
  Cdr& header(std::int32_t sec, std::uint32_t nanosec, const std::string& frame) {
    return i32(sec).u32(nanosec).str(frame);
  }
  const std::vector<std::uint8_t>& bytes() const { return bytes_; }

 private:
  Cdr& put(const void* v, std::size_t size) {
    // Little-endian machine assumed: the test's own check below.
    while ((bytes_.size() - 4) % size != 0) bytes_.push_back(0);
    const auto* p = static_cast<const std::uint8_t*>(v);
    bytes_.insert(bytes_.end(), p, p + size);
    return *this;
  }
  std::vector<std::uint8_t> bytes_;
};

std::string hex(const std::vector<std::uint8_t>& b) {
  std::string s;
  char cell[4];
  for (std::size_t i = 0; i < b.size(); ++i) {
    std::snprintf(cell, sizeof cell, "%02x%c", b[i], i % 16 == 15 ? '\n' : ' ');
    s += cell;
  }
  return s;
}

class RosWireFormat : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const std::uint16_t one = 1;
    std::uint8_t first = 0;
    std::memcpy(&first, &one, 1);
    ASSERT_EQ(first, 1) << "these expectations are written for a little-endian host";
  }

  // Writes message on a fresh topic and returns the bytes a reader received.
  template <class Message>
  std::vector<std::uint8_t> round_trip(const Message& message, const std::string& ros_name,
                                       const std::string& type_name) {
    const dds::Writer<Message> writer(participant_, ros_name, dds::Qos::state());
    const dds::Reader<Message> reader(participant_, ros_name, dds::Qos::state());
    char name[256];
    EXPECT_GT(dds_get_name(dds_get_topic(writer.handle()), name, sizeof name), 0);
    EXPECT_EQ(std::string(name), "rt" + ros_name);
    EXPECT_GT(dds_get_type_name(dds_get_topic(writer.handle()), name, sizeof name), 0);
    EXPECT_EQ(std::string(name), type_name);
    EXPECT_TRUE(writer.wait_for_reader(10));
    EXPECT_TRUE(writer.write(message));
    EXPECT_TRUE(reader.wait(10));
    ddsi_serdata* data = nullptr;
    dds_sample_info_t info{};
    std::vector<std::uint8_t> bytes;
    if (dds_takecdr(reader.handle(), &data, 1, &info, DDS_ANY_STATE) != 1) {
      ADD_FAILURE() << "no sample on " << ros_name;
      return bytes;
    }
    bytes.resize(ddsi_serdata_size(data));
    ddsi_serdata_to_ser(data, 0, bytes.size(), bytes.data());
    ddsi_serdata_unref(data);
    return bytes;
  }

  // The bytes must be the expected ones; trailing padding to a multiple of 4 is allowed, with
  // its length in the options' low two bits (DDS-XTypes 7.6.3.1.2) or left at zero.
  static void expect_bytes(const std::vector<std::uint8_t>& got, const Cdr& expected) {
    const std::vector<std::uint8_t>& want = expected.bytes();
    ASSERT_GE(got.size(), want.size()) << "got:\n" << hex(got) << "\nwant:\n" << hex(want);
    ASSERT_LT(got.size(), want.size() + 4);
    std::vector<std::uint8_t> head(got.begin(), got.begin() + long(want.size()));
    const std::size_t padding = got.size() - want.size();
    const std::uint8_t options = got[3] & 0x03;
    EXPECT_TRUE(options == 0 || options == padding) << int(options) << " " << padding;
    head[3] = static_cast<std::uint8_t>(head[3] & ~0x03);
    EXPECT_EQ(head, want) << "got:\n" << hex(got) << "\nwant:\n" << hex(want);
  }

  dds::Participant participant_{kDomain, dds::loopback_config()};
};

TEST_F(RosWireFormat, JointState) {
  const char* names[] = {"left_hip", "elbow"};
  const double position[] = {0.25, -1.5};
  const double velocity[] = {3.0, 4.0};
  msg::JointState m{};
  m.header.stamp = {1700000000, 123456789};
  m.header.frame_id = dds::borrow("base");
  m.name = dds::borrow(names, 2);
  m.position = dds::borrow(position, 2);
  m.velocity = dds::borrow(velocity, 2);
  m.effort = dds::borrow(static_cast<const double*>(nullptr), 0);
  Cdr want;
  want.header(1700000000, 123456789, "base")
      .strs({"left_hip", "elbow"})
      .f64s({0.25, -1.5})
      .f64s({3.0, 4.0})
      .f64s({});
  expect_bytes(round_trip(m, "/hmpc/test/joint_states", "sensor_msgs::msg::dds_::JointState_"),
               want);
}

TEST_F(RosWireFormat, Imu) {
  msg::Imu m{};
  m.header.stamp = {-2, 5};
  m.header.frame_id = dds::borrow("imu");
  m.orientation = {0.1, 0.2, 0.3, 0.9};
  m.angular_velocity = {1.5, -2.5, 3.5};
  m.linear_acceleration = {0.0, 0.5, 9.81};
  Cdr want;
  want.header(-2, 5, "imu").f64(0.1).f64(0.2).f64(0.3).f64(0.9);
  for (int i = 0; i < 9; ++i) {
    m.orientation_covariance[i] = i == 0 ? -1.0 : 0.0;
    want.f64(m.orientation_covariance[i]);
  }
  want.f64(1.5).f64(-2.5).f64(3.5);
  for (int i = 0; i < 9; ++i) {
    m.angular_velocity_covariance[i] = 0.01 * i;
    want.f64(0.01 * i);
  }
  want.f64(0.0).f64(0.5).f64(9.81);
  for (int i = 0; i < 9; ++i) {
    m.linear_acceleration_covariance[i] = -0.5 * i;
    want.f64(-0.5 * i);
  }
  expect_bytes(round_trip(m, "/hmpc/test/imu", "sensor_msgs::msg::dds_::Imu_"), want);
}

TEST_F(RosWireFormat, Odometry) {
  msg::Odometry m{};
  m.header.stamp = {7, 999999999};
  m.header.frame_id = dds::borrow("odom");
  m.child_frame_id = dds::borrow("base_link");
  m.pose.pose.position = {1.0, 2.0, 0.9};
  m.pose.pose.orientation = {0.0, 0.0, 0.38268343236, 0.92387953251};
  m.twist.twist.linear = {0.3, -0.1, 0.0};
  m.twist.twist.angular = {0.0, 0.02, 0.5};
  Cdr want;
  want.header(7, 999999999, "odom").str("base_link");
  want.f64(1.0).f64(2.0).f64(0.9).f64(0.0).f64(0.0).f64(0.38268343236).f64(0.92387953251);
  for (int i = 0; i < 36; ++i) {
    m.pose.covariance[i] = i % 7 == 0 ? 1e-4 * (i + 1) : 0.0;
    want.f64(m.pose.covariance[i]);
  }
  want.f64(0.3).f64(-0.1).f64(0.0).f64(0.0).f64(0.02).f64(0.5);
  for (int i = 0; i < 36; ++i) {
    m.twist.covariance[i] = 1e-3 * i;
    want.f64(1e-3 * i);
  }
  expect_bytes(round_trip(m, "/hmpc/test/odom", "nav_msgs::msg::dds_::Odometry_"), want);
}

TEST_F(RosWireFormat, JointTrajectory) {
  const char* names[] = {"elbow", "wrist"};
  const double p0[] = {0.0, 0.1};
  const double p1[] = {0.5, 0.6};
  const double v1[] = {1.0, -1.0};
  const double a1[] = {2.0, 3.0};
  const double e1[] = {4.5};
  msg::JointTrajectoryPoint points[2]{};
  points[0].positions = dds::borrow(p0, 2);
  points[0].time_from_start = {0, 0};
  points[1].positions = dds::borrow(p1, 2);
  points[1].velocities = dds::borrow(v1, 2);
  points[1].accelerations = dds::borrow(a1, 2);
  points[1].effort = dds::borrow(e1, 1);
  points[1].time_from_start = {1, 500000000};
  msg::JointTrajectory m{};
  m.header.stamp = {0, 0};
  m.header.frame_id = dds::borrow("");
  m.joint_names = dds::borrow(names, 2);
  m.points = dds::borrow<decltype(m.points)>(points, 2);
  Cdr want;
  want.header(0, 0, "").strs({"elbow", "wrist"}).u32(2);
  want.f64s({0.0, 0.1}).f64s({}).f64s({}).f64s({}).i32(0).u32(0);
  want.f64s({0.5, 0.6}).f64s({1.0, -1.0}).f64s({2.0, 3.0}).f64s({4.5}).i32(1).u32(500000000);
  expect_bytes(
      round_trip(m, "/hmpc/test/joint_trajectory", "trajectory_msgs::msg::dds_::JointTrajectory_"),
      want);
}

TEST_F(RosWireFormat, DiagnosticArray) {
  msg::KeyValue values[] = {{dds::borrow("mode"), dds::borrow("run")},
                            {dds::borrow("faults"), dds::borrow("0x00")}};
  msg::DiagnosticStatus status[2]{};
  status[0].level = 2;
  status[0].name = dds::borrow("hmpc/forearm_0/board");
  status[0].message = dds::borrow("fault");
  status[0].hardware_id = dds::borrow("forearm node 0");
  status[0].values = dds::borrow<decltype(status[0].values)>(values, 2);
  status[1].level = 0;
  status[1].name = dds::borrow("b");
  status[1].message = dds::borrow("");
  status[1].hardware_id = dds::borrow("hw");
  msg::DiagnosticArray m{};
  m.header.stamp = {42, 1};
  m.header.frame_id = dds::borrow("");
  m.status = dds::borrow<decltype(m.status)>(status, 2);
  Cdr want;
  want.header(42, 1, "").u32(2);
  want.u8(2).str("hmpc/forearm_0/board").str("fault").str("forearm node 0").u32(2);
  want.str("mode").str("run").str("faults").str("0x00");
  want.u8(0).str("b").str("").str("hw").u32(0);
  expect_bytes(round_trip(m, "/diagnostics", "diagnostic_msgs::msg::dds_::DiagnosticArray_"), want);
}

TEST_F(RosWireFormat, OurModeCommandCostWeightsAndTelemetry) {
  msg::ModeCommand command{};
  command.header.stamp = {10, 20};
  command.header.frame_id = dds::borrow("");
  command.sequence_number = 77;
  command.mode = 3;
  command.strategy = dds::borrow("two_stage");
  command.clear_faults = true;
  Cdr want_command;
  want_command.header(10, 20, "").u32(77).u8(3).str("two_stage").boolean(true);
  expect_bytes(round_trip(command, "/hmpc/test/command", "hmpc_msgs::msg::dds_::ModeCommand_"),
               want_command);

  const char* names[] = {"q_theta", "r_motor"};
  const double values[] = {1000.0, 0.5};
  msg::CostWeights weights{};
  weights.header.frame_id = dds::borrow("");
  weights.names = dds::borrow(names, 2);
  weights.values = dds::borrow(values, 2);
  Cdr want_weights;
  want_weights.header(0, 0, "").strs({"q_theta", "r_motor"}).f64s({1000.0, 0.5});
  expect_bytes(round_trip(weights, "/hmpc/test/cost_weights", "hmpc_msgs::msg::dds_::CostWeights_"),
               want_weights);

  msg::ForearmTelemetry t{};
  t.header.stamp = {3, 4};
  t.header.frame_id = dds::borrow("");
  t.board_mode = 3;
  t.faults = 0x21;
  t.strategy = dds::borrow("fine_4ms");
  t.solve_status = 1;
  t.coarse_iterations = 300;
  t.fine_iterations = 2;
  t.solve_time_us = 1234;
  t.target_position = 0.5;
  t.tracking_error = -0.01;
  t.pressure = 4e5;
  t.valve_voltage = 1.5;
  t.motor_voltage = -2.0;
  t.muscle_torque = 3.25;
  t.motor_torque = 0.75;
  Cdr want_t;
  want_t.header(3, 4, "").u8(3).u8(0x21).str("fine_4ms").u8(1).u16(300).u16(2).u32(1234);
  want_t.f64(0.5).f64(-0.01).f64(4e5).f64(1.5).f64(-2.0).f64(3.25).f64(0.75);
  expect_bytes(round_trip(t, "/hmpc/test/telemetry", "hmpc_msgs::msg::dds_::ForearmTelemetry_"),
               want_t);
}

TEST_F(RosWireFormat, OurMpcPlanAndTaskCommand) {
  const char* joints[] = {"left_hip", "left_knee"};
  const double q0[] = {0.1, -0.2}, v0[] = {0.0, 0.5}, tau0[] = {10.0, -20.0};
  const double q1[] = {0.15, -0.25}, v1[] = {1.0, -1.5}, tau1[] = {12.5, -18.0};
  msg::JointTrajectoryPoint points[2]{};
  points[0].positions = dds::borrow(q0, 2);
  points[0].velocities = dds::borrow(v0, 2);
  points[0].effort = dds::borrow(tau0, 2);
  points[0].time_from_start = {0, 0};
  points[1].positions = dds::borrow(q1, 2);
  points[1].velocities = dds::borrow(v1, 2);
  points[1].effort = dds::borrow(tau1, 2);
  points[1].time_from_start = {0, 30000000};
  const msg::Pose poses[] = {{{0.0, 0.0, 0.9}, {0.0, 0.0, 0.0, 1.0}},
                             {{0.01, 0.0, 0.89}, {0.0, 0.05, 0.0, 0.99875}}};
  const msg::Twist twists[] = {{{0.3, 0.0, -0.1}, {0.0, 0.2, 0.0}}};
  msg::MpcPlan plan{};
  plan.header.stamp = {5, 60000000};
  plan.header.frame_id = dds::borrow("world");
  plan.sequence_number = 9;
  plan.controller = dds::borrow("coarse_fast");
  plan.solve_status = 1;
  plan.iterations = 4;
  plan.lower_iterations = 2;
  plan.solve_time_us = 21000;
  plan.cost = 1234.5;
  plan.joints.header.frame_id = dds::borrow("");
  plan.joints.joint_names = dds::borrow(joints, 2);
  plan.joints.points = dds::borrow<decltype(plan.joints.points)>(points, 2);
  plan.base_poses = dds::borrow<decltype(plan.base_poses)>(poses, 2);
  plan.base_twists = dds::borrow<decltype(plan.base_twists)>(twists, 1);
  Cdr want_plan;
  want_plan.header(5, 60000000, "world").u32(9).str("coarse_fast").u8(1).u16(4).u16(2);
  want_plan.u32(21000).f64(1234.5);
  want_plan.header(0, 0, "").strs({"left_hip", "left_knee"}).u32(2);
  want_plan.f64s({0.1, -0.2}).f64s({0.0, 0.5}).f64s({}).f64s({10.0, -20.0}).i32(0).u32(0);
  want_plan.f64s({0.15, -0.25}).f64s({1.0, -1.5}).f64s({}).f64s({12.5, -18.0});
  want_plan.i32(0).u32(30000000);
  want_plan.u32(2).f64(0.0).f64(0.0).f64(0.9).f64(0.0).f64(0.0).f64(0.0).f64(1.0);
  want_plan.f64(0.01).f64(0.0).f64(0.89).f64(0.0).f64(0.05).f64(0.0).f64(0.99875);
  want_plan.u32(1).f64(0.3).f64(0.0).f64(-0.1).f64(0.0).f64(0.2).f64(0.0);
  expect_bytes(round_trip(plan, "/hmpc/test/plan", "hmpc_msgs::msg::dds_::MpcPlan_"), want_plan);

  const char* names[] = {"hip_height"};
  const double values[] = {0.7};
  msg::TaskCommand task{};
  task.header.stamp = {11, 12};
  task.header.frame_id = dds::borrow("");
  task.sequence_number = 3;
  task.task = dds::borrow("squat");
  task.parameter_names = dds::borrow(names, 1);
  task.parameter_values = dds::borrow(values, 1);
  Cdr want_task;
  want_task.header(11, 12, "").u32(3).str("squat").strs({"hip_height"}).f64s({0.7});
  expect_bytes(round_trip(task, "/hmpc/test/task", "hmpc_msgs::msg::dds_::TaskCommand_"),
               want_task);
}

TEST(RosNames, TopicNamesFollowRos2) {
  EXPECT_EQ(dds::dds_topic_name("/hmpc/forearm_0/joint_states"), "rt/hmpc/forearm_0/joint_states");
  EXPECT_EQ(dds::dds_topic_name("/diagnostics"), "rt/diagnostics");
  for (const char* bad : {"", "/", "joint_states", "/a//b", "/a/", "/0a", "/a b", "/a-b"}) {
    EXPECT_THROW(dds::dds_topic_name(bad), std::invalid_argument) << bad;
  }
}

TEST(RosNames, TimeFromSecondsKeepsNanosecondsInRange) {
  const auto t = dds::from_seconds<msg::Time>(1.25);
  EXPECT_EQ(t.sec, 1);
  EXPECT_EQ(t.nanosec, 250000000u);
  const auto n = dds::from_seconds<msg::Time>(-0.25);
  EXPECT_EQ(n.sec, -1);
  EXPECT_EQ(n.nanosec, 750000000u);
  const auto r = dds::from_seconds<msg::Duration>(2.9999999999);
  EXPECT_EQ(r.sec, 3);
  EXPECT_EQ(r.nanosec, 0u);
  EXPECT_DOUBLE_EQ(dds::to_seconds(dds::from_seconds<msg::Time>(123.456)), 123.456);
}

}  // namespace
