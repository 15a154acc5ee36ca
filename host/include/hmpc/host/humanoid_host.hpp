// The humanoid's host controller (thesis Sec. 2.7), independent of the bus: it brings the robot
// up over the CAN master (humanoid_can_master.hpp), estimates its state from the IMU's and the
// boards' frames only (the invariant EKF, hmpc/estimation/biped_state_estimator.hpp), and runs
// the Coarse-Fast MPC in the real robot's setting (Sec. 2.7.3), whose plans it streams to the
// boards as torque references. Time is the host's tick (1 ms): real time, or the HIL plant's
// Sync frames in lock-step; the same frames at the same ticks give the same outputs, so a
// recorded bus replays into it (hmpc-humanoid-host --replay).
//
//   waiting   until every board (protocol version, four joints) and the IMU are heard; the
//             boards asked for idle with faults cleared
//   zeroing   zero_encoders in idle (the robot stands in its zero posture), until every joint
//             reports zeroed
//   holding   the boards hold the posture under their PID (Sec. 2.7.3: "the robot first holds
//             its posture"); the estimator starts from the first rest_seconds of it
//   mpc       after hold_seconds (the thesis: 10 s) or when an operator says run, the MPC's
//             plans as torque references, the boards in run; an operator's hold takes the robot
//             back to holding, where it stays until run
//   safe      the boards hold their posture (an estimate lost, three failed solves in a row) or
//             are in fault (an E-stop, a board's fault): no more references
//
// Every 12 ms (Sec. 2.7.3's sampling) a solve starts from the estimate at that tick; its plan
// takes effect after the solve's compute time, rounded up to whole ticks, as it would in real
// time: wall time where the host runs natively, or the time the host's own machine would take,
// from the solver's work counters through a model calibrated natively (kHostComputeModel), where
// wall time means nothing (the vcan guest runs about 15 times slower). Until then the previous
// plan goes on.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "hmpc/estimation/biped_state_estimator.hpp"
#include "hmpc/host/humanoid_can_master.hpp"
#include "hmpc/humanoid/coarse_fast.hpp"
#include "hmpc/humanoid/problem.hpp"
#include "hmpc/mpc/compute_model.hpp"

namespace hmpc::host {

enum class HostPhase { kWaiting, kZeroing, kHolding, kMpc, kSafe };
const char* name_of(HostPhase phase);

// Where a solve's compute time comes from.
enum class SolveTime { kWall, kModel };

// This machine natively, 2 threads, seconds per unit of the MPC's work in the real robot's
// timing (fitted by humanoid_mpc_bench --real-robot, which prints the model against measured
// solves): what the host charges a solve where wall time means nothing.
extern const ComputeCostModel kHostComputeModel;

struct HumanoidHostConfig {
  HumanoidMasterConfig master{};
  double bring_up_timeout_s = 5;  // waiting and zeroing, each
  double hold_seconds = 10;       // under the boards' PID before the MPC (Sec. 2.7.3)
  double rest_seconds = 0.5;      // of the hold, the estimator's start (ClosedLoopConfig's)
  humanoid::CoarseFastTiming timing = humanoid::kRealRobotTiming;
  // The MPC's model settings (its step is the timing's); e.g. its friction's slip velocity
  // (ProblemConfig::model_slip_velocity, the lever State estimation measured).
  humanoid::ProblemConfig problem{};
  int threads = 2;
  bool truncate = false;  // stop a solve at the sampling period by wall clock (real time)
  SolveTime solve_time = SolveTime::kWall;
  // The motion's clock runs from the MPC's start; paused, it stays at 0 until resume_motion()
  // or set_task() (a task that starts on a command: the squat).
  bool motion_paused = false;
  double fail_solver_at_s = -1;  // test hook: every solve from then on counts as failed
};

// One solve, as logged.
struct SolveRecord {
  std::uint32_t tick = 0;            // started at
  std::uint32_t estimate_tick = 0;   // the IMU reading its estimate took last came at
  std::uint32_t effective_tick = 0;  // its plan took effect at
  double wall_ms = 0, charged_ms = 0;
  int upper_iterations = 0, fast_iterations = 0;
  bool usable = false;
  double motion_time = 0;  // s, the motion's clock
};

// The plan of the last usable solve over the upper layer's horizon (one upper step apart from
// the solve's state), as an operator sees it.
struct PlannedMotion {
  std::array<humanoid::StateVector, humanoid::kCoarseHorizon + 1> states{};
  std::array<humanoid::JointVector, humanoid::kCoarseHorizon> torques{};
  double cost = 0;
  SolveStatus status = SolveStatus::kInvalidInput;
  SolveRecord solve;
  std::uint32_t sequence = 0;  // usable solves so far; 0: none yet
};

// An operator's task for the MPC (Sec. 2.7.3's): hold the hip at `height`, or squat from there
// `depth` deep each `period` (the squat of motion.hpp), from when it is set. The hip's
// horizontal position stays where the MPC began.
struct HipTask {
  bool squat = false;
  double height = 0;  // m
  double depth = 0;   // m
  double period = 0;  // s
};

class HumanoidHost {
 public:
  // Throws std::invalid_argument for a motion the biped cannot run or a timing that is not
  // valid.
  HumanoidHost(const HumanoidHostConfig& config, const humanoid::Motion& task);
  ~HumanoidHost();
  HumanoidHost(const HumanoidHost&) = delete;
  HumanoidHost& operator=(const HumanoidHost&) = delete;

  // A frame from the robot bus, at host tick `tick`.
  void on_frame(const jp::Frame& frame, std::uint32_t tick);
  // Host tick `tick`: the controller's step, then the master's frames due, to
  // send(const jp::Frame&). `heartbeat_enabled` false withholds every frame but the E-stop (a
  // host whose loop has died, for tests).
  template <class Send>
  void tick(std::uint32_t tick, bool heartbeat_enabled, Send&& send) {
    step(tick);
    master_.tick(tick, heartbeat_enabled, send);
  }

  // Commands (operator, DDS): the bus-wide E-stop; back to the boards' posture hold (until
  // run); from holding to the MPC now (once the estimator runs); the paused motion's clock
  // started.
  void estop();
  void hold();
  void run();
  void resume_motion();
  // From the next solve on (between solves): a new task, its clock starting now; the cost's
  // weights (e.g. learned by inverse optimal control).
  void set_task(const HipTask& task);
  void set_weights(const humanoid::CostWeights& weights);
  // The motion the MPC pursues, with the operator's task and weights.
  const humanoid::Motion& task() const { return task_; }
  // Simulation only: the MPC solves from *state (the plant's truth) instead of the estimate,
  // which still runs; nullptr restores the estimate. To tell what the estimator does to an
  // outcome from what the rest of the chain does (as hmpc-humanoid --estimator truth).
  void solve_from(const humanoid::BasicState<0>* state) { solve_from_ = state; }

  const HumanoidHostConfig& config() const { return config_; }
  HostPhase phase() const { return phase_; }
  // Why the host is in kSafe, or why bring-up failed; empty otherwise.
  const std::string& reason() const { return reason_; }
  // The tick the host went to its safe phase (valid once it has).
  std::uint32_t safe_tick() const { return safe_tick_; }
  bool bring_up_failed() const { return bring_up_failed_; }
  const HumanoidCanMaster& master() const { return master_; }
  const estimation::BipedStateEstimator& estimator() const { return estimator_; }
  bool estimating() const { return estimator_started_; }
  // The solves so far (reserved once for the session's length).
  const std::vector<SolveRecord>& solves() const { return solves_; }
  // Ticks from a solve's start to its plan's effect, largest so far.
  std::uint32_t largest_delay_ticks() const { return largest_delay_; }
  const PlannedMotion& last_plan() const { return plan_; }
  double motion_time(std::uint32_t tick) const;

 private:
  void step(std::uint32_t tick);
  void estimate(std::uint32_t tick);
  void solve(std::uint32_t tick);
  void to_safe(const char* reason, bool hold_posture);
  humanoid::JointVector plan_torque(std::uint32_t tick) const;

  struct Mpc;
  HumanoidHostConfig config_;
  HumanoidCanMaster master_;
  estimation::BipedStateEstimator estimator_;
  std::unique_ptr<Mpc> mpc_;
  humanoid::Motion task_;
  HostPhase phase_ = HostPhase::kWaiting;
  std::string reason_;
  bool bring_up_failed_ = false;
  std::uint32_t phase_tick_ = 0;  // when the phase began
  std::uint32_t safe_tick_ = 0;
  std::uint32_t last_tick_ = 0;
  bool estimator_started_ = false;
  std::uint32_t last_imu_tick_ = 0;
  bool have_imu_ = false;
  std::uint32_t mpc_start_tick_ = 0;
  bool motion_paused_ = false;
  std::uint32_t motion_start_tick_ = 0;
  bool task_changed_ = false;  // the cost takes task_ at the next solve
  bool run_asked_ = false;     // an operator's run, until the MPC starts
  bool held_ = false;          // an operator's hold: no MPC until run
  PlannedMotion plan_;
  int failed_solves_ = 0;
  const humanoid::BasicState<0>* solve_from_ = nullptr;
  std::vector<SolveRecord> solves_;
  std::uint32_t largest_delay_ = 0;
};

}  // namespace hmpc::host
