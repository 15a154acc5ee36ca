// Fuzz target for the checks every incoming DDS sample passes before the host acts on it
// (hmpc/dds/validation.hpp). A deserialised sample can hold any bit pattern in any field and
// any sequence length, so the input bytes build, in turn:
// - a ModeCommand (raw mode, stamp and a strategy from a table that includes near misses): an
//   accepted one has a known mode and strategy;
// - a JointTrajectory on the forearm's limits (names from a small table, 0..16 points whose
//   time, positions and velocities are raw words): an accepted one names the one joint once,
//   its times start at 0 or later and strictly increase with nanoseconds below 1e9, every
//   number is finite, and its interpolant, sampled densely, stays inside the joint's range and
//   speed;
// - a TaskCommand (a task and 0..4 parameters from tables with near misses, raw values,
//   sometimes one value too many or too few; CostWeights share its checks): an accepted one
//   names a known task and only its parameters, once each, every value inside its range.
// A rejection always says why.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "hmpc/dds/forearm_dds.hpp"
#include "hmpc/dds/validation.hpp"
#include "hmpc/trajectory/joint_trajectory.hpp"

namespace {

namespace dds = hmpc::dds;
namespace msg = hmpc::dds::msg;
namespace proto = hmpc::forearm_protocol;

constexpr std::size_t kMaxPoints = 16;
constexpr double kNow = 1.8e9;
const char* const kNames[] = {"elbow", "wrist", "", "Elbow"};
const char* const kStrategies[] = {"two_stage", "pam_only",    "fine_4ms",  "two_stage ",
                                   "",          "coarse_20ms", "Two_stage", "fine_8ms"};

[[noreturn]] void fail(const char* what) {
  std::fprintf(stderr, "DDS sample fuzz: %s\n", what);
  std::abort();
}

// Reads the input front to back; zeros once it runs out.
class Reader {
 public:
  Reader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  template <class T>
  T take() {
    T value{};
    std::uint8_t raw[sizeof(T)] = {};
    for (std::size_t i = 0; i < sizeof(T) && at_ < size_; ++i) raw[i] = data_[at_++];
    std::memcpy(&value, raw, sizeof(T));
    return value;
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t at_ = 0;
};

void check_trajectory(Reader& in) {
  const char* names[3];
  const std::size_t name_count = in.take<std::uint8_t>() % 3;
  for (std::size_t i = 0; i < name_count; ++i) names[i] = kNames[in.take<std::uint8_t>() % 4];
  const std::size_t count = in.take<std::uint8_t>() % (kMaxPoints + 1);
  double positions[kMaxPoints][2], velocities[kMaxPoints][2];
  msg::JointTrajectoryPoint points[kMaxPoints]{};
  for (std::size_t k = 0; k < count; ++k) {
    const auto shape = in.take<std::uint8_t>();
    points[k].time_from_start.sec = in.take<std::int32_t>() % 8;  // small: times can increase
    points[k].time_from_start.nanosec = in.take<std::uint32_t>();
    if (shape & 0x80) points[k].time_from_start.nanosec %= 1000000000u;
    const std::size_t np = shape & 3, nv = (shape >> 2) & 3;
    for (std::size_t i = 0; i < np % 3; ++i) positions[k][i] = in.take<double>();
    for (std::size_t i = 0; i < nv % 3; ++i) velocities[k][i] = in.take<double>();
    points[k].positions = dds::borrow(positions[k], np % 3);
    points[k].velocities = dds::borrow(velocities[k], nv % 3);
  }
  msg::JointTrajectory t{};
  t.joint_names = dds::borrow(names, name_count);
  t.points = dds::borrow<decltype(t.points)>(points, count);
  const dds::JointLimits& joint = dds::forearm_joint_limits();
  const dds::Verdict v =
      dds::validate(t, &joint, 1, dds::TrajectoryLimits{kMaxPoints, 600.0}, kNow, {});
  if (!v.ok) {
    if (v.detail.empty()) fail("rejected a trajectory without a reason");
    return;
  }
  if (name_count != 1 || std::strcmp(names[0], dds::kJointName) != 0) {
    fail("accepted a trajectory not of the joint");
  }
  if (count == 0) fail("accepted no points");
  std::vector<hmpc::trajectory::TrajectoryPoint> accepted;
  for (std::size_t k = 0; k < count; ++k) {
    const msg::JointTrajectoryPoint& p = points[k];
    if (p.time_from_start.nanosec >= 1000000000u) fail("accepted a nanosec of a second or more");
    if (p.positions._length != 1) fail("accepted a point without its one position");
    if (p.velocities._length > 1) fail("accepted two velocities for one joint");
    const double time = dds::to_seconds(p.time_from_start);
    if (time < 0 || (k > 0 && !(time > accepted.back().time_s))) {
      fail("accepted times that do not start at 0 or later and increase");
    }
    const double q = p.positions._buffer[0];
    if (!std::isfinite(q) || q < joint.min_position || q > joint.max_position) {
      fail("accepted a position that is not finite or out of the joint's range");
    }
    const bool has_velocity = p.velocities._length == 1;
    const double qd = has_velocity ? p.velocities._buffer[0] : 0;
    if (!std::isfinite(qd) || std::abs(qd) > joint.max_speed) {
      fail("accepted a velocity that is not finite or too fast");
    }
    accepted.push_back({time, q, qd, has_velocity});
  }
  hmpc::trajectory::JointTrajectoryTarget target(kMaxPoints);
  if (!target.assign(accepted.data(), accepted.size())) fail("an accepted trajectory did not fit");
  constexpr int kSamples = 64;
  const double tolerance = 1e-9 * (1 + joint.max_position - joint.min_position);
  for (std::size_t k = 1; k < accepted.size(); ++k) {
    const double t0 = accepted[k - 1].time_s, t1 = accepted[k].time_s;
    double previous = target.position(t0);
    for (int i = 1; i <= kSamples; ++i) {
      const double t = t0 + (t1 - t0) * i / kSamples;
      const double q = target.position(t);
      if (!(q >= joint.min_position - tolerance && q <= joint.max_position + tolerance)) {
        fail("accepted a trajectory whose interpolant leaves the joint's range");
      }
      // A chord's slope is the mean of the interpolant's speed over it.
      if (std::abs(q - previous) >
          joint.max_speed * (t1 - t0) / kSamples * (1 + 1e-9) + tolerance) {
        fail("accepted a trajectory whose interpolant is too fast");
      }
      previous = q;
    }
  }
}

void check_command(Reader& in) {
  msg::ModeCommand c{};
  c.mode = in.take<std::uint8_t>();
  c.header.stamp.sec = in.take<std::int32_t>();
  c.header.stamp.nanosec = in.take<std::uint32_t>();
  const auto pick = in.take<std::uint8_t>();
  if (pick & 0x10) c.header.stamp = {0, 0};
  c.strategy = dds::borrow(kStrategies[pick % 8]);
  const char* known[std::size(proto::kStrategyValues)];
  for (std::size_t i = 0; i < std::size(known); ++i) known[i] = proto::kStrategyValues[i].name;
  const dds::Verdict v = dds::validate(c, known, std::size(known), kNow, {});
  if (!v.ok) {
    if (v.detail.empty()) fail("rejected a command without a reason");
    return;
  }
  if (c.mode < 1 || c.mode > 3) fail("accepted an unknown mode");
  std::uint32_t value = 0;
  if (!proto::value_of(proto::kStrategyValues, c.strategy, value)) {
    fail("accepted an unknown strategy");
  }
  if (c.header.stamp.nanosec >= 1000000000u) fail("accepted a stamp's nanosec of a second");
}

// Tasks as a humanoid would take them; the names drawn include near misses and another task's.
const dds::NamedRange kSquat[] = {{"hip_height", 0.4, 0.9}, {"period", 1.0, 10.0}};
const dds::NamedRange kWalk[] = {{"speed", 0.0, 0.5}};
const dds::TaskSpec kTasks[] = {{"stand", nullptr, 0}, {"squat", kSquat, 2}, {"walk", kWalk, 1}};
const char* const kTaskNames[] = {"stand", "squat", "walk", "Squat", "", "walk ", "jump", "squat"};
const char* const kParameterNames[] = {"hip_height", "period", "speed", "Period"};

void check_task(Reader& in) {
  msg::TaskCommand c{};
  const auto pick = in.take<std::uint8_t>();
  c.task = dds::borrow(kTaskNames[pick % 8]);
  const char* names[4];
  double values[4];
  const std::size_t name_count = (pick >> 3) % 5;
  const std::size_t value_count = (pick & 0x80) ? (name_count + 1) % 5 : name_count;
  for (std::size_t i = 0; i < name_count; ++i)
    names[i] = kParameterNames[in.take<std::uint8_t>() % 4];
  for (std::size_t i = 0; i < value_count; ++i) values[i] = in.take<double>();
  c.parameter_names = dds::borrow(names, name_count);
  c.parameter_values = dds::borrow(values, value_count);
  const dds::Verdict v = dds::validate(c, kTasks, std::size(kTasks), kNow, {});
  if (!v.ok) {
    if (v.detail.empty()) fail("rejected a task without a reason");
    return;
  }
  const dds::TaskSpec* task = nullptr;
  for (const auto& t : kTasks) {
    if (std::strcmp(t.name, c.task) == 0) task = &t;
  }
  if (task == nullptr) fail("accepted an unknown task");
  if (value_count != name_count) fail("accepted parameters with values of another count");
  for (std::size_t i = 0; i < name_count; ++i) {
    const dds::NamedRange* range = nullptr;
    for (std::size_t k = 0; k < task->parameter_count; ++k) {
      if (std::strcmp(task->parameters[k].name, names[i]) == 0) range = &task->parameters[k];
    }
    if (range == nullptr) fail("accepted a parameter the task does not take");
    for (std::size_t j = 0; j < i; ++j) {
      if (std::strcmp(names[i], names[j]) == 0) fail("accepted a parameter named twice");
    }
    if (!(values[i] >= range->min && values[i] <= range->max)) {
      fail("accepted a parameter outside its range");
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Reader in(data, size);
  check_command(in);
  check_trajectory(in);
  check_task(in);
  return 0;
}

#ifdef HMPC_FUZZ_REPLAY
#include "fuzz_replay.hpp"

namespace {
void put(hmpc::fuzz::Bytes& b, const void* p, std::size_t n) {
  const auto* bytes = static_cast<const std::uint8_t*>(p);
  b.insert(b.end(), bytes, bytes + n);
}
}  // namespace

// Seeds: a good command, a good trajectory of 1..8 points at 0.1 s, each point with a
// position and (alternately) a velocity, and a squat with both parameters, with the special
// doubles a sender may put in (as the trajectory's last position and the squat's period).
int main(int argc, char** argv) {
  using hmpc::fuzz::Bytes;
  std::vector<Bytes> seeds;
  const double specials[] = {0.0, 0.5, -1.0, 1.6, -0.0, 1e300, NAN, INFINITY, 5e-324};
  for (std::size_t n = 1; n <= 8; ++n) {
    for (double special : specials) {
      Bytes b{3, 0, 0, 0, 0, 0, 0, 0, 0, 0x10};  // run, unstamped, two_stage
      b.push_back(1);                            // one name
      b.push_back(0);                            // "elbow"
      b.push_back(std::uint8_t(n));
      for (std::size_t k = 0; k < n; ++k) {
        const bool velocity = k % 2 == 0;
        b.push_back(std::uint8_t(0x80 | 1 | (velocity ? 4 : 0)));
        const std::int32_t sec = 0;
        const std::uint32_t nanosec = std::uint32_t(100000000u * k);
        put(b, &sec, 4);
        put(b, &nanosec, 4);
        const double q = k + 1 == n ? special : 0.05 * double(k);
        put(b, &q, 8);
        if (velocity) {
          const double qd = 0.5;
          put(b, &qd, 8);
        }
      }
      b.push_back(1 | (2 << 3));  // squat, two parameters
      b.push_back(0);             // hip_height
      b.push_back(1);             // period
      const double hip_height = 0.7;
      put(b, &hip_height, 8);
      put(b, &special, 8);
      seeds.push_back(b);
    }
  }
  return hmpc::fuzz::replay(argc, argv, "dds_sample_fuzz_replay", seeds, 100, 2000);
}
#endif
