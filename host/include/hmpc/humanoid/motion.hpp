// A humanoid motion: the cost weights of thesis Sec. 4.3.1 (Eqs. 4.24-4.30) and Eq. 2.52, and
// the phase schedule of the base targets (attitude a, height p_z, velocity v) of Tables
// 2.2-2.3, read from a motion file (host/humanoid/motions/*.motion).
//
// File format (UTF-8 text, one setting per line):
//   - '#' starts a comment; blank lines are ignored.
//   - The first other line is the version line, exactly `hmpc-humanoid-motion 1`.
//   - `[motion]`, `[weights]` and `[phase]` start sections; `[phase]` may repeat, once per
//     phase, in order of start time. Other lines are `key = value`.
//   - Values are numbers; vectors are numbers separated by spaces. A number may end in `pi`
//     (`1.5pi`, `-pi`, `pi`) to mean that multiple of pi.
//   [motion]   duration  simulated length [s] (> 0)
//              chair     `none`, or the chair's seat (motion IV): height, then the x range
//                        from x_min to x_max (world) [m]
//              gait      `none`, or a stepping schedule (Gait below): period [s], swing
//                        height [m], swing fraction of the period (0 < fraction <= 1)
//              model_substep  (optional) the sub-step of the MPC's model [s],
//                        0 < h <= kMaxModelSubstep; without it, ProblemConfig::max_substep's
//   [weights]  w_HAA w_HFE w_KFE w_AFE   W_control of Eq. 4.24, per joint of each leg
//              w_q1 w_q2 w_q3 w_q4       W_attitude of Eq. 4.25 (vector part, scalar part)
//              w_height                  Eq. 4.26
//              w_vx w_vy w_vz            W_velocity of Eq. 4.27
//              w_alpha w_beta            Eqs. 4.28, 4.29
//              w_omega_x w_omega_y w_omega_z   W_omega of Eq. 4.30
//              w_fast w_fast_control     lower layer: Eq. 2.52 and its control cost
//              w_foot                    foot heights (Gait below; not in the thesis)
//              w_position                (optional, 0 without it) the base point's horizontal
//                                        position held where the motion starts (Sec. 2.7.3)
//              w_joint_velocity          (optional, 0 without it) the leg joints' rates
//                                        (Sec. 2.7.3)
//              w_torque_change           (optional, 0 without it) the change of the torques
//                                        from one input to the next (Sec. 2.7.3)
//   [phase]    start     phase start time [s]; the first phase starts at 0, later ones
//                        strictly later than the one before
//              attitude  roll phi, pitch theta, yaw xi [rad]
//              height    p_z [m]
//              velocity  v_x v_y v_z [m/s]
//              squat     (optional) a sinusoidal height, the thesis's slow squat (Sec. 2.7.3):
//                        depth [m] and period [s] (> 0); the height target is then
//                        p_z(t) = height - depth (1 - cos(2 pi (t - start) / period)) / 2,
//                        down from `height` and back each period, starting at rest, and its
//                        rate is added to v_z
//   [reach]    (optional, at most once) whole-body reaching, Eq. 2.53: the motion runs on the
//              robot with a right arm (n = 31, model.hpp)
//              target    p_reach, world [m]
//              start     time the reaching term switches on [s] (>= 0)
//              w_reach   Eq. 2.53's weight
//              w_SFE     W_control of Eq. 4.24 for the shoulder joint
// Every key but model_substep, w_position, w_joint_velocity, w_torque_change and squat is
// required exactly once per section; weights are finite and >= 0. Any error throws
// MotionFileError naming the file, the line and the key.
#pragma once

#include <Eigen/Core>
#include <array>
#include <iosfwd>
#include <stdexcept>
#include <string>

namespace hmpc::humanoid {

struct CostWeights {
  std::array<double, 4> control{};                     // w_HAA, w_HFE, w_KFE, w_AFE (Eq. 4.32)
  Eigen::Vector4d attitude = Eigen::Vector4d::Zero();  // w_q1, w_q2, w_q3 (vector), w_q4
  double height = 0.0;
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();  // w_vx, w_vy, w_vz
  double alpha = 0.0, beta = 0.0;
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();  // w_omega_x, _y, _z
  double fast = 0.0, fast_control = 0.0;  // Eq. 2.52 and the deviation nu's weight
  double foot = 0.0;                      // foot heights (Gait)
  // The base point's horizontal position, held where the problem starts (BasicStateCost's
  // `initial`): Sec. 2.7.3's real-robot tasks "maintain [the] initial hip position", a position
  // target, where Sec. 4.3.1's terms hold only the base's height and velocity, so nothing else
  // holds the hip where it was.
  double position = 0.0;
  // The leg joints' rates, l = w |v_joints|^2: Sec. 2.7.3's state cost minimises "the linear and
  // angular velocities of the base link and the joints".
  double joint_velocity = 0.0;
  // The change of the torques, w |u_k - u_{k-1}|^2 over the plan with u_{-1} the torque applied
  // last (HumanoidProblem::set_applied_torque): Sec. 2.7.3's second control cost, "since sudden
  // jumps in the control inputs can cause undesired oscillations".
  double torque_change = 0.0;
  // Joint-angle tracking, l_joint = w_joint |q_joints - Phase::joints|^2 over the legs' joints:
  // the tracking MPC that reproduces a retargeted demonstration on the robot (Sec. 4.2.1,
  // hmpc/ioc/retargeting.hpp). Not in a motion file (always 0 there).
  double joint = 0.0;
};

// Foot heights (ours: the thesis has no such term). Sec. 2.6's costs alone never lift a foot
// to step within a 300 ms horizon: leaning into the target velocity is a local optimum, since a
// loaded foot has no gradient towards unloading; nor do they ask a foot to come back down
// after a disturbance or a landing, so hopping from foot to foot costs the planner almost
// nothing (both measured, see the motion files). So, as gait-scheduled MPCs do (e.g. MuJoCo
// MPC's locomotion tasks), each foot follows a height reference:
//   l_foot = w_foot sum (z_p - z_ref(t))^2,  z_ref = h sin(pi s) in a swing, else 0,
// over the foot's heel and toe (the centres of its sole's back and front edges), z_p their
// heights above the ground: both, so that a swinging sole stays level instead of dragging its
// toe (measured: with the ankle's height alone the swing foot scuffed the ground).
// Without a gait both feet are asked to stay down (a weak w_foot still lets a jump leave the
// ground). With one, s in [0, 1) is the progress through the swing; the left foot swings from
// the start of each period, the right from its middle. Where a foot lands is left to
// Eq. 4.28's alpha term, which asks for the base between the feet.
struct Gait {
  double period = 0.0;          // [s], a stride: one step of each foot; 0: no gait
  double swing_height = 0.0;    // h [m]
  double swing_fraction = 0.0;  // of the period each foot swings; > 0.5: flight phases
  // z_ref of `foot` (0 left, 1 right) at time t: 0 in its stance (or without a gait).
  double foot_height(double t, int foot) const;
};

// Whole-body reaching (Sec. 2.6.1, Eq. 2.53): l_reach = w_reach |p_reach - p_hand|^2 from
// `start` on, p_hand the hand's centre (Model::hand).
struct Reach {
  bool active = false;                               // the motion file has a [reach] section
  Eigen::Vector3d target = Eigen::Vector3d::Zero();  // p_reach [m]
  double start = 0.0;                                // [s]
  double weight = 0.0;                               // w_reach
  double control = 0.0;  // the shoulder torque's weight in W_control (Eq. 4.24)
};

struct Phase {
  double start = 0.0;                                  // [s]
  Eigen::Vector3d attitude = Eigen::Vector3d::Zero();  // roll, pitch, yaw [rad]
  double height = 0.0;                                 // [m]
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();  // [m/s]
  // The legs' joint angles for CostWeights::joint (left leg first, LegJoint order) [rad].
  std::array<double, 8> joints{};
  double squat_depth = 0.0, squat_period = 0.0;  // [m], [s]; period 0: no squat

  // The targets at time t (within this phase): height and velocity with the squat.
  double height_at(double t) const;
  Eigen::Vector3d velocity_at(double t) const;
};

// Fixed capacity, so a problem holds its motion by value without allocating. Table 2.3's
// longest schedule (VIII) has six phases; a demonstration's targets (hmpc/ioc/retargeting.hpp)
// have one phase per 30 ms coarse step: 128 hold 3.8 s (16 kB a motion).
constexpr int kMaxPhases = 128;

// The longest model sub-step a motion may ask for: semi-implicit Euler's stability bound
// omega h < 2 for the stiffest explicit mode, a foot on its soles at 195 rad/s (contact.hpp).
constexpr double kMaxModelSubstep = 0.01;

struct Motion {
  double duration = 0.0;
  double model_substep = 0.0;  // [s] the MPC model's sub-step; 0: ProblemConfig's default
  bool chair = false;
  double seat_height = 0.0, seat_x_min = 0.0, seat_x_max = 0.0;  // [m], when `chair`
  Gait gait;                                                     // period 0: none
  CostWeights weights;
  Reach reach;  // not active: the biped's motions I-VIII
  std::array<Phase, kMaxPhases> phases{};
  int phase_count = 0;

  // The phase in force at time t (the last one started at or before t; the first before 0).
  const Phase& phase_at(double t) const;
};

class MotionFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Reads a motion file; `source` names it in error messages.
Motion parse_motion(std::istream& in, const std::string& source);
Motion load_motion(const std::string& path);
// Writes `motion` in the file format above, every number to full precision (parse_motion reads
// it back exactly), after `comment` as '#' lines. Phase::joints and CostWeights::joint are not
// part of the format and are not written.
void write_motion(std::ostream& out, const Motion& motion, const std::string& comment);
// A command line's motion: a path (it has a '/' or ends in .motion) as it is, else the name of
// a file shipped in `shipped_dir` (e.g. "V-low-jump").
std::string motion_path(const std::string& name_or_path, const std::string& shipped_dir);

// Unit quaternion (w, x, y, z) of the attitude a = (roll phi, pitch theta, yaw xi), rotations
// counterclockwise about x, y, z (Sec. 2.6.1) composed as R = R_z(xi) R_y(theta) R_x(phi).
// From half angles, without folding angles into (-pi, pi]: a = (0, 2 pi, 0) gives
// (-1, 0, 0, 0), the quaternion a body reaches after one full flip, which is how Eq. 4.25
// tells motion VIII's flips apart (the quaternion has period 4 pi).
Eigen::Vector4d attitude_quaternion(const Eigen::Vector3d& attitude);

}  // namespace hmpc::humanoid
