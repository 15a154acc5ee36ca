// The humanoid's DDS topics on the generic layer: the host controller's state as the standard
// messages, and the checks of what comes in before it reaches the controller.
#include "hmpc/dds/humanoid_dds.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <utility>

#include "hmpc/dds/bridge.hpp"
#include "hmpc/dds/endpoint.hpp"
#include "hmpc/humanoid/model.hpp"
#include "hmpc/ioc/weights.hpp"
#include "hmpc/protocol/joint_protocol.hpp"

namespace hmpc::dds {

namespace {

namespace hm = hmpc::humanoid;
namespace jp = hmpc::joint_protocol;
using host::HostPhase;
using host::HumanoidHost;

constexpr double kMaxWeight = 1e6;  // see humanoid_weight_limits()

struct Topics {
  explicit Topics(const std::string& ns)
      : joint_states(ns + "/joint_states"), imu(ns + "/imu"), odometry(ns + "/odometry"),
        plan(ns + "/plan"), command(ns + "/command"), task(ns + "/task"),
        cost_weights(ns + "/cost_weights") {}
  std::string joint_states, imu, odometry, plan, command, task, cost_weights;
  std::string diagnostics = "/diagnostics";
};

// Eigen's fixed matrices into a message's row-major covariance.
template <class Matrix, std::size_t N>
void put_row_major(const Matrix& m, double (&out)[N]) {
  static_assert(N == Matrix::RowsAtCompileTime * Matrix::ColsAtCompileTime);
  for (int r = 0; r < m.rows(); ++r)
    for (int c = 0; c < m.cols(); ++c) out[r * m.cols() + c] = m(r, c);
}

hm::Matrix3 skew(const hm::Vector3& a) {
  hm::Matrix3 s;
  s << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
  return s;
}

// The filter's error is right-invariant (invariant_ekf.hpp): R_hat = exp(phi) R,
// p_hat = p + xi_p + phi x p, v_hat = v + xi_v + phi x v to first order. So the world-frame
// pose error is (xi_p - [p]x phi, phi), and the torso-frame velocity error R^T xi_v; the angular
// velocity's is the gyroscope bias's (omega = gyro - b_g). Indices: phi 0, xi_v 3, xi_p 6, b_g 15.
Eigen::Matrix<double, 6, 6> pose_covariance(const estimation::Covariance& p,
                                            const hm::Vector3& position) {
  Eigen::Matrix<double, 6, estimation::kErrorSize> j = decltype(j)::Zero();
  j.block<3, 3>(0, 0) = -skew(position);
  j.block<3, 3>(0, 6).setIdentity();
  j.block<3, 3>(3, 0).setIdentity();
  return j * p * j.transpose();
}
Eigen::Matrix<double, 6, 6> twist_covariance(const estimation::Covariance& p,
                                             const hm::Matrix3& torso_to_world) {
  Eigen::Matrix<double, 6, estimation::kErrorSize> j = decltype(j)::Zero();
  j.block<3, 3>(0, 3) = torso_to_world.transpose();
  j.block<3, 3>(3, 15) = -hm::Matrix3::Identity();
  return j * p * j.transpose();
}

msg::Pose pose_of(const hm::StateVector& x) {
  msg::Pose pose{};
  pose.position = {x[0], x[1], x[2]};
  pose.orientation = {x[4], x[5], x[6], x[3]};  // q is (w, x, y, z); ROS's (x, y, z, w)
  return pose;
}
// The model's v is the torso's spatial velocity in torso coordinates (model.hpp); the plan
// gives it in the world frame, like the poses.
msg::Twist twist_of(const hm::StateVector& x) {
  const Eigen::Quaterniond q(x[3], x[4], x[5], x[6]);
  const hm::Matrix3 r = q.normalized().toRotationMatrix();
  const hm::Vector3 w = r * x.segment<3>(hm::kConfigurationSize);
  const hm::Vector3 v = r * x.segment<3>(hm::kConfigurationSize + 3);
  msg::Twist twist{};
  twist.linear = {v.x(), v.y(), v.z()};
  twist.angular = {w.x(), w.y(), w.z()};
  return twist;
}

// What the diagnostics report, compared raw every publish and written out only when it changed
// or is due.
struct DiagnosticsState {
  HostPhase phase = HostPhase::kWaiting;
  estimation::Trust trust = estimation::Trust::kLost;
  bool bring_up_failed = false;
  std::uint64_t rejected = 0, silences = 0;

  bool operator==(const DiagnosticsState& o) const {
    return phase == o.phase && trust == o.trust && bring_up_failed == o.bring_up_failed &&
           rejected == o.rejected && silences == o.silences;
  }
};

// A task's parameters not named: the hip where the motion the controller runs starts, and its
// squat if it has one, else the thesis's slow squat (4 s) as deep as the limits allow.
host::HipTask default_task(const hm::Motion& motion, const HumanoidTaskLimits& limits) {
  host::HipTask task;
  task.height = motion.phases[0].height;
  task.depth = limits.depth.max;
  task.period = 4.0;
  for (int k = 0; k < motion.phase_count; ++k) {
    const hm::Phase& phase = motion.phases[std::size_t(k)];
    if (phase.squat_period > 0) {
      task.depth = phase.squat_depth;
      task.period = phase.squat_period;
    }
  }
  return task;
}

}  // namespace

const std::array<NamedRange, kHumanoidWeightCount>& humanoid_weight_limits() {
  static const std::array<NamedRange, kHumanoidWeightCount> limits = [] {
    std::array<NamedRange, kHumanoidWeightCount> l{};
    for (int k = 0; k < ioc::kWeightCount; ++k)
      l[std::size_t(k)] = {ioc::kWeightNames[k], 0, kMaxWeight};
    l[13] = {"w_position", 0, kMaxWeight};
    l[14] = {"w_joint_velocity", 0, kMaxWeight};
    l[15] = {"w_torque_change", 0, kMaxWeight};
    return l;
  }();
  return limits;
}

HumanoidTaskLimits HumanoidTaskLimits::around(double start_height) {
  return {{"height", start_height - 0.02, start_height + 0.01},
          {"depth", 0.005, 0.02},
          {"period", 2.0, 20.0}};
}

// ------------------------------------------------------------------------ bridge

struct HumanoidDdsBridge::Impl {
  Impl(std::uint32_t domain_id, const HumanoidTaskLimits& limits, const std::string& config,
       const std::string& ns, double command_deadline_s)
      : ros_namespace(ns), topics(ns), participant(domain_id, config),
        task_limits(limits), stand_parameters{limits.height}, squat_parameters{limits.height,
                                                                               limits.depth,
                                                                               limits.period},
        tasks{TaskSpec{"stand", stand_parameters.data(), stand_parameters.size()},
              TaskSpec{"squat", squat_parameters.data(), squat_parameters.size()}},
        joint_states(participant, topics.joint_states, Qos::state()),
        imu(participant, topics.imu, Qos::sensor_data()),
        odometry(participant, topics.odometry, Qos::state()),
        plan(participant, topics.plan, Qos::state()),
        diagnostics(participant, topics.diagnostics, Qos::state()),
        commands(participant, topics.command, Qos::command(command_deadline_s)),
        task_commands(participant, topics.task, Qos::state()),
        weights(participant, topics.cost_weights, Qos::state()),
        diagnostic_name(ns.substr(1) + "/controller") {
    // The IMU frames carry means over their period of 1 kHz samples: the variance of such a
    // mean is the white noise's density squared over the period (the BMI088's, imu.hpp).
    const sensors::ImuConfig bmi = sensors::bmi088();
    const double period =
        1e-3 * double(jp::frame_spec(jp::FrameType::kImuAngularVelocity).cycle_time_ms);
    gyro_variance = bmi.gyroscope.noise_density * bmi.gyroscope.noise_density / period;
    accel_variance = bmi.accelerometer.noise_density * bmi.accelerometer.noise_density / period;
  }

  void reject(const char* what, const Verdict& verdict) {
    log_rejection(rejects, "hmpc-humanoid-dds", ros_namespace, what, verdict);
  }

  bool publish_state(const HumanoidHost& host, const msg::Time& stamp) {
    const host::RobotReadings& r = host.master().readings();
    bool ok = joint_states.write(joint_state(stamp, hm::kLegJointNames.data(), r.angle.data(),
                                             r.rate.data(), r.torque.data(), hm::kLegJoints));
    if (!host.estimating()) return ok;
    const estimation::InvariantEkf& filter = host.estimator().filter();
    const estimation::BaseEstimate e = filter.estimate();
    const hm::Matrix3 rotation = e.orientation.toRotationMatrix();
    const hm::Vector3 body_velocity = rotation.transpose() * e.velocity;
    msg::Odometry odom{};
    odom.header.stamp = stamp;
    odom.header.frame_id = borrow("odom");
    odom.child_frame_id = borrow("torso");
    odom.pose.pose.position = {e.position.x(), e.position.y(), e.position.z()};
    odom.pose.pose.orientation = {e.orientation.x(), e.orientation.y(), e.orientation.z(),
                                  e.orientation.w()};
    put_row_major(pose_covariance(filter.covariance(), e.position), odom.pose.covariance);
    odom.twist.twist.linear = {body_velocity.x(), body_velocity.y(), body_velocity.z()};
    odom.twist.twist.angular = {e.angular_velocity.x(), e.angular_velocity.y(),
                                e.angular_velocity.z()};
    put_row_major(twist_covariance(filter.covariance(), rotation), odom.twist.covariance);
    return odometry.write(odom) && ok;
  }

  bool publish_imu(const host::RobotReadings& r, const msg::Time& stamp) {
    msg::Imu m{};
    m.header.stamp = stamp;
    m.header.frame_id = borrow("imu");
    m.orientation = {0, 0, 0, 1};
    m.orientation_covariance[0] = -1;  // ROS's mark for "no orientation": the IMU sends none
    m.angular_velocity = {r.angular_velocity.x(), r.angular_velocity.y(), r.angular_velocity.z()};
    m.linear_acceleration = {r.specific_force.x(), r.specific_force.y(), r.specific_force.z()};
    for (int i = 0; i < 3; ++i) {
      m.angular_velocity_covariance[4 * i] = gyro_variance;
      m.linear_acceleration_covariance[4 * i] = accel_variance;
    }
    return imu.write(m);
  }

  bool publish_plan(const HumanoidHost& host, const msg::Time& stamp) {
    const host::PlannedMotion& p = host.last_plan();
    constexpr std::size_t kPoints = hm::kCoarseHorizon + 1;
    std::array<msg::JointTrajectoryPoint, kPoints> points{};
    std::array<msg::Pose, kPoints> poses{};
    std::array<msg::Twist, kPoints> twists{};
    std::array<std::array<double, hm::kLegJoints>, kPoints> positions{}, velocities{}, efforts{};
    for (std::size_t k = 0; k < kPoints; ++k) {
      const hm::StateVector& x = p.states[k];
      const hm::JointVector& tau = p.torques[std::min(k, std::size_t(hm::kCoarseHorizon - 1))];
      for (int j = 0; j < hm::kLegJoints; ++j) {
        positions[k][std::size_t(j)] = x[7 + j];
        velocities[k][std::size_t(j)] = x[hm::kConfigurationSize + hm::kBaseDofs + j];
        efforts[k][std::size_t(j)] = tau[j];
      }
      points[k].positions = borrow(positions[k].data(), hm::kLegJoints);
      points[k].velocities = borrow(velocities[k].data(), hm::kLegJoints);
      points[k].effort = borrow(efforts[k].data(), hm::kLegJoints);
      points[k].time_from_start = from_seconds<msg::Duration>(double(k) * upper_step_s);
      poses[k] = pose_of(x);
      twists[k] = twist_of(x);
    }
    msg::MpcPlan m{};
    m.header.stamp = stamp;
    m.header.frame_id = borrow("odom");
    m.sequence_number = p.sequence;
    m.controller = borrow(kHumanoidStrategy);
    m.solve_status = static_cast<std::uint8_t>(p.status);
    m.iterations = static_cast<std::uint16_t>(p.solve.upper_iterations);
    m.lower_iterations = static_cast<std::uint16_t>(p.solve.fast_iterations);
    m.solve_time_us = static_cast<std::uint32_t>(std::lround(1e3 * p.solve.charged_ms));
    m.cost = p.cost;
    m.joints.header = m.header;
    m.joints.joint_names = borrow(hm::kLegJointNames.data(), hm::kLegJoints);
    m.joints.points = borrow<decltype(m.joints.points)>(points.data(), kPoints);
    m.base_poses = borrow<decltype(m.base_poses)>(poses.data(), kPoints);
    m.base_twists = borrow<decltype(m.base_twists)>(twists.data(), kPoints);
    return plan.write(m);
  }

  bool publish_diagnostics(const HumanoidHost& host, double now) {
    DiagnosticsState state;
    state.phase = host.phase();
    state.trust = host.estimating() ? host.estimator().filter().trust() : estimation::Trust::kLost;
    state.bring_up_failed = host.bring_up_failed();
    state.rejected = rejects.total();
    state.silences = commander.silences();
    if (now < next_diagnostics_s && state == last_diagnostics) return true;
    last_diagnostics = state;
    next_diagnostics_s = now + kDiagnosticsPeriodS;
    const std::string solves = std::to_string(host.solves().size());
    const std::string rejected = std::to_string(state.rejected);
    const std::string silent = std::to_string(state.silences);
    const std::array<std::pair<const char*, const char*>, 6> pairs = {{
        {"phase", host::name_of(state.phase)},
        {"estimate", host.estimating() ? estimation::to_string(state.trust) : "not started"},
        {"solves", solves.c_str()},
        {"dds_rejected", rejected.c_str()},
        {"commander_silences", silent.c_str()},
        {"reason", host.reason().c_str()},
    }};
    std::array<msg::KeyValue, pairs.size()> values{};
    for (std::size_t i = 0; i < values.size(); ++i) {
      values[i].key = borrow(pairs[i].first);
      values[i].value = borrow(pairs[i].second);
    }
    const bool safe = state.phase == HostPhase::kSafe;
    const std::string message =
        safe ? std::string("safe: ") + host.reason() : std::string(host::name_of(state.phase));
    return write_diagnostics(diagnostics, now,
                             safe ? DiagnosticLevel::kError : DiagnosticLevel::kOk,
                             diagnostic_name.c_str(), message.c_str(), "humanoid host controller",
                             values.data(), values.size());
  }

  std::string ros_namespace;
  Topics topics;
  Participant participant;
  HumanoidTaskLimits task_limits;
  std::array<NamedRange, 1> stand_parameters;
  std::array<NamedRange, 3> squat_parameters;
  std::array<TaskSpec, 2> tasks;
  Writer<msg::JointState> joint_states;
  Writer<msg::Imu> imu;
  Writer<msg::Odometry> odometry;
  Writer<msg::MpcPlan> plan;
  Writer<msg::DiagnosticArray> diagnostics;
  Reader<msg::ModeCommand> commands;
  Reader<msg::TaskCommand> task_commands;
  Reader<msg::CostWeights> weights;
  std::string diagnostic_name;
  double gyro_variance = 0, accel_variance = 0;
  double upper_step_s = 0;
  RejectCounters rejects;
  DiagnosticsState last_diagnostics{};
  double next_diagnostics_s = 0;
  std::uint32_t last_imu_tick = 0;
  bool imu_published = false;
  std::uint32_t plan_sequence = 0;
  CommanderWatch commander;  // the writer of the last run is in charge
  std::uint64_t accepted_commands = 0, accepted_tasks = 0, accepted_weights = 0;
};

HumanoidDdsBridge::HumanoidDdsBridge(std::uint32_t domain_id, const HumanoidTaskLimits& limits,
                                     const std::string& config, const std::string& ros_namespace,
                                     double command_deadline_s)
    : impl_(std::make_unique<Impl>(domain_id, limits, config,
                                   namespace_or(ros_namespace, kHumanoidNamespace),
                                   command_deadline_s)) {}

HumanoidDdsBridge::~HumanoidDdsBridge() = default;

bool HumanoidDdsBridge::publish(const HumanoidHost& host, std::uint32_t tick) {
  Impl& d = *impl_;
  d.upper_step_s = host.config().timing.upper_step;
  const double now = unix_time_s();
  const msg::Time stamp = from_seconds<msg::Time>(now);
  bool ok = true;
  if (tick % kHumanoidStatePeriodTicks == 0) ok = d.publish_state(host, stamp) && ok;
  const host::RobotReadings& r = host.master().readings();
  if (r.imu_heard && r.gyro_tick == r.accel_tick &&
      (!d.imu_published || r.gyro_tick != d.last_imu_tick)) {
    d.imu_published = true;
    d.last_imu_tick = r.gyro_tick;
    ok = d.publish_imu(r, stamp) && ok;
  }
  if (host.last_plan().sequence != d.plan_sequence) {
    d.plan_sequence = host.last_plan().sequence;
    ok = d.publish_plan(host, stamp) && ok;
  }
  return d.publish_diagnostics(host, now) && ok;
}

void HumanoidDdsBridge::poll(HumanoidHost& host) {
  Impl& d = *impl_;
  const double now = unix_time_s();
  const StampPolicy stamps;
  d.commands.take([&](const msg::ModeCommand& c, const dds_sample_info_t& info) {
    const char* strategies[] = {kHumanoidStrategy};
    const Verdict v = validate(c, strategies, 1, now, stamps);
    if (!v.ok) return d.reject("ModeCommand", v);
    ++d.accepted_commands;
    switch (static_cast<CommandMode>(c.mode)) {
      case CommandMode::kIdle:
        d.commander.released();
        host.estop();
        break;
      case CommandMode::kHold:
        d.commander.released();
        host.hold();
        break;
      case CommandMode::kRun:
        d.commander.took_charge(info.publication_handle);
        host.run();
        break;
    }
  });
  d.task_commands.take([&](const msg::TaskCommand& c) {
    Verdict v = validate(c, d.tasks.data(), d.tasks.size(), now, stamps);
    if (!v.ok) return d.reject("TaskCommand", v);
    const bool squat = std::strcmp(c.task, "squat") == 0;
    host::HipTask task = default_task(host.task(), d.task_limits);
    task.squat = squat;
    for (std::uint32_t i = 0; i < c.parameter_names._length; ++i) {
      const char* name = c.parameter_names._buffer[i];
      const double value = c.parameter_values._buffer[i];
      if (std::strcmp(name, "height") == 0) task.height = value;
      if (std::strcmp(name, "depth") == 0) task.depth = value;
      if (std::strcmp(name, "period") == 0) task.period = value;
    }
    if (squat && task.height - task.depth < d.task_limits.height.min) {
      char detail[160];
      std::snprintf(detail, sizeof detail,
                    "a squat from %.4f m, %.4f m deep, goes below the lowest hip height %.4f m",
                    task.height, task.depth, d.task_limits.height.min);
      return d.reject("TaskCommand", Verdict::reject(Rejection::kOutOfRange, detail));
    }
    ++d.accepted_tasks;
    host.set_task(task);
  });
  d.weights.take([&](const msg::CostWeights& w) {
    const auto& limits = humanoid_weight_limits();
    const Verdict v = validate(w, limits.data(), limits.size(), now, stamps);
    if (!v.ok) return d.reject("CostWeights", v);
    hm::CostWeights out = host.task().weights;
    ioc::Weights learned = ioc::weights_of(out);
    for (std::uint32_t i = 0; i < w.names._length; ++i) {
      const char* name = w.names._buffer[i];
      const double value = w.values._buffer[i];
      for (int k = 0; k < ioc::kWeightCount; ++k) {
        if (std::strcmp(name, ioc::kWeightNames[k]) == 0) learned[k] = value;
      }
      if (std::strcmp(name, "w_position") == 0) out.position = value;
      if (std::strcmp(name, "w_joint_velocity") == 0) out.joint_velocity = value;
      if (std::strcmp(name, "w_torque_change") == 0) out.torque_change = value;
    }
    ++d.accepted_weights;
    host.set_weights(ioc::with_weights(out, learned));
  });
  // The commander who sent run fell silent: the robot goes back to its boards' hold.
  if (d.commander.fell_silent(d.commands)) {
    std::fprintf(stderr, "hmpc-humanoid-dds: %s: the commander fell silent; holding\n",
                 d.ros_namespace.c_str());
    host.hold();
  }
}

const RejectCounters& HumanoidDdsBridge::rejects() const { return impl_->rejects; }
std::uint64_t HumanoidDdsBridge::commands() const { return impl_->accepted_commands; }
std::uint64_t HumanoidDdsBridge::tasks() const { return impl_->accepted_tasks; }
std::uint64_t HumanoidDdsBridge::weights() const { return impl_->accepted_weights; }
std::uint64_t HumanoidDdsBridge::commander_silences() const { return impl_->commander.silences(); }
const std::string& HumanoidDdsBridge::ros_namespace() const { return impl_->ros_namespace; }

}  // namespace hmpc::dds
