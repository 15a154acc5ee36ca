// The humanoid's host controller (hmpc/host/humanoid_host.hpp) on DDS, the ROS 2 way: the
// joints, the IMU, the estimate as odometry with its covariance, the MPC's plans and the
// controller's diagnostics out; mode commands, tasks and cost weights in, each checked before it
// reaches the controller.
//
// Topics, under a namespace <ns> (default /hmpc/humanoid; "rt" + name on the wire):
//   <ns>/joint_states  sensor_msgs/JointState           state QoS    out, every 4 ms
//   <ns>/imu           sensor_msgs/Imu                  sensor data  out, each IMU reading (6 ms)
//   <ns>/odometry      nav_msgs/Odometry                state QoS    out, every 4 ms
//   <ns>/plan          hmpc_msgs/MpcPlan                state QoS    out, each usable solve
//   /diagnostics       diagnostic_msgs/DiagnosticArray  state QoS    out, on change and at 1 Hz
//   <ns>/command       hmpc_msgs/ModeCommand            command QoS  in
//   <ns>/task          hmpc_msgs/TaskCommand            state QoS    in
//   <ns>/cost_weights  hmpc_msgs/CostWeights            state QoS    in
// (QoS profiles: hmpc/dds/participant.hpp.) Joints by kLegJointNames (left_HAA ... right_AFE).
//
// ModeCommand (strategy "coarse_fast"): idle is the bus-wide E-stop (the boards' valves safe; the
// host stays safe), hold hands the robot back to its boards' posture hold, run starts the MPC
// from the hold. A commander who sent run must repeat its command within kCommandDeadlineS, as
// for the forearm: when it falls silent the robot goes back to the hold. Without a commander
// the controller runs as configured (the MPC after its hold time).
// TaskCommand: "stand" (hold the hip at `height`) or "squat" (a sinusoid from `height`, `depth`
// deep each `period`), Sec. 2.7.3's tasks, taking effect at the next solve; a task is a set
// point, sent once (the ModeCommand's deadline already watches the operator).
// CostWeights: any of the MPC's upper-layer weights by their motion-file names (the 13 that
// inverse optimal control learns, kHumanoidCostWeightsTopic, and Sec. 2.7.3's w_position,
// w_joint_velocity, w_torque_change), adopted at the next solve.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "hmpc/dds/participant.hpp"
#include "hmpc/dds/validation.hpp"
#include "hmpc/host/humanoid_host.hpp"

namespace hmpc::dds {

inline constexpr const char* kHumanoidNamespace = "/hmpc/humanoid";
// The controller's one way of running, as ModeCommand names it.
inline constexpr const char* kHumanoidStrategy = "coarse_fast";
// Publishing joint states and odometry every 4 host ticks: 250 Hz, as the forearm's state.
inline constexpr std::uint32_t kHumanoidStatePeriodTicks = 4;

// The weights a CostWeights message may set: each non-negative (the cost of Eq. 4.3 is a sum of
// weighted squares) and at most 1e6, a hundred times the largest a shipped motion uses
// (w_height 1e4): beyond, the iLQR's Hessian would be too badly conditioned to trust.
inline constexpr std::size_t kHumanoidWeightCount = 16;
const std::array<NamedRange, kHumanoidWeightCount>& humanoid_weight_limits();

// The hip-height range of the tasks, from the height the motion starts at: at most 2 cm below
// (hip-squat.motion's depth: its ankles then stay 1 degree off their dorsiflexion stops, 3 cm
// reaches them) and 1 cm above (the knees stay bent). A squat's depth 5 mm to 2 cm within that,
// its period 2 to 20 s (the thesis's slow squat: 4 s).
struct HumanoidTaskLimits {
  NamedRange height, depth, period;
  static HumanoidTaskLimits around(double start_height);
};

class HumanoidDdsBridge {
 public:
  // `task_limits` from the motion the host runs (HumanoidTaskLimits::around its start height).
  // `config` as for Participant; std::invalid_argument for a bad namespace, std::runtime_error
  // when DDS fails. `command_deadline_s`: longer only where a host's tick may take longer than
  // kCommandDeadlineS of wall time (tests under sanitizers); a commander must offer it.
  HumanoidDdsBridge(std::uint32_t domain_id, const HumanoidTaskLimits& task_limits,
                    const std::string& config = {}, const std::string& ros_namespace = {},
                    double command_deadline_s = kCommandDeadlineS);
  ~HumanoidDdsBridge();
  HumanoidDdsBridge(const HumanoidDdsBridge&) = delete;
  HumanoidDdsBridge& operator=(const HumanoidDdsBridge&) = delete;

  // What is due at host tick `tick` (after the host's tick): joint states and odometry every
  // kHumanoidStatePeriodTicks, a new IMU reading, a new plan, diagnostics that changed. False if
  // DDS refused a sample.
  bool publish(const host::HumanoidHost& host, std::uint32_t tick);
  // Takes every pending command; the valid ones act on `host` (between its ticks), the others
  // are counted by reason and logged to stderr, one line each.
  void poll(host::HumanoidHost& host);

  const RejectCounters& rejects() const;
  std::uint64_t commands() const;  // accepted, of each kind
  std::uint64_t tasks() const;
  std::uint64_t weights() const;
  std::uint64_t commander_silences() const;
  const std::string& ros_namespace() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace hmpc::dds
