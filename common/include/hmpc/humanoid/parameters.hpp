// The one source of truth for the seven-link humanoid's physical parameters (thesis Sec. 2.5.1:
// a torso and three links per leg, height 1.59 m, mass 47.0 kg).
//
// Segment data: de Leva, P. (1996), "Adjustments to Zatsiorsky-Seluyanov's segment inertia
// parameters", J. Biomechanics 29(9), 1223-1230, female columns (mass fractions, centre-of-mass
// positions and radii of gyration referred to joint centres; mean segment lengths of the
// reference subject, stature 1.735 m). Lengths are scaled by stature / 1.735 m, masses by
// 47.0 kg. The torso link lumps head, trunk and both arms hanging at the sides (anatomical
// position); model.cpp combines them with the parallel-axis theorem.
// Where de Leva gives no number (hip and shoulder spacing, foot geometry below the ankle) the
// value is marked "choice" or taken from Drillis & Contini's body-height fractions as
// reproduced in Winter, D.A. (2009), "Biomechanics and Motor Control of Human Movement",
// 4th ed., Fig. 4.1.
#pragma once

#include <array>

namespace hmpc::humanoid {

// One row of de Leva's table. Radii of gyration are fractions of the segment length about the
// segment's principal axes: sagittal (antero-posterior), transverse (medio-lateral) and
// longitudinal (along the segment).
struct Segment {
  double mass_fraction;      // of total body mass
  double com_from_proximal;  // centre of mass, fraction of length from the proximal end
  double reference_length;   // [m] mean length of de Leva's female reference subject
  double gyration_sagittal;
  double gyration_transverse;
  double gyration_longitudinal;
};

// Joint order within one leg, the same for both legs (q and v list the left leg first).
enum LegJoint : int {
  kHipAbduction = 0,
  kHipFlexion = 1,
  kKnee = 2,
  kAnkle = 3,
  kJointsPerLeg = 4
};

struct Parameters {
  double stature = 1.59;             // [m] thesis Sec. 2.5.1
  double body_mass = 47.0;           // [kg] thesis Sec. 2.5.1
  double gravity = 9.81;             // [m/s^2]
  double reference_stature = 1.735;  // [m] de Leva (1996), female reference subject

  // de Leva (1996), female: {mass, CoM from proximal, length [m], r_sag, r_trans, r_long}.
  Segment head{0.0668, 0.4841, 0.2437, 0.271, 0.295, 0.261};       // vertex - cervicale
  Segment trunk{0.4257, 0.4964, 0.6148, 0.307, 0.292, 0.147};      // cervicale - mid-hip
  Segment upper_arm{0.0255, 0.5754, 0.2751, 0.278, 0.260, 0.148};  // shoulder - elbow centre
  Segment forearm{0.0138, 0.4559, 0.2643, 0.261, 0.257, 0.094};    // elbow - wrist centre
  Segment hand{0.0056, 0.7474, 0.0780, 0.531, 0.454, 0.335};       // wrist - 3rd metacarpale
  Segment thigh{0.1478, 0.3612, 0.3695, 0.369, 0.364, 0.162};      // hip - knee centre
  Segment shank{0.0481, 0.4416, 0.4323, 0.271, 0.267, 0.093};      // knee - lateral malleolus
  Segment foot{0.0129, 0.4014, 0.2283, 0.299, 0.279, 0.139};       // heel - toe tip
  // de Leva's mass fractions sum to 0.9999 (rounding); model.cpp divides by their sum so the
  // model's total mass is exactly body_mass.

  // Geometry de Leva does not give, as fractions of stature unless stated.
  double hip_joint_spacing = 0.10;  // choice: 0.159 m between hip joint centres (adult range
                                    // 0.15-0.18 m)
  double shoulder_height = 0.818;   // above the floor: Drillis & Contini (Winter Fig. 4.1)
  double shoulder_width = 0.259;    // biacromial: Drillis & Contini (Winter Fig. 4.1); the
                                    // shoulder joint centres are taken at this spacing
  double heel_behind_ankle = 0.22;  // choice: fraction of foot length from heel to ankle
  double foot_com_height = 0.5;     // choice: fraction of the ankle height above the sole
  // The ankle (lateral malleolus) height above the sole is what stature leaves after head,
  // trunk, thigh and shank: 0.0747 m in the reference subject (Winter's Fig. 4.1: 0.039 H =
  // 0.068 m), so the standing model is exactly `stature` tall.

  // Ranges of motion [rad], per LegJoint, for both legs: normal adult values of the American
  // Academy of Orthopaedic Surgeons (Greene & Heckman 1994). Positive = abduction, hip
  // flexion, knee flexion, ankle dorsiflexion (see model.hpp for the axes).
  std::array<double, kJointsPerLeg> joint_lower{-0.5236,   // hip adduction 30 deg
                                                -0.5236,   // hip extension 30 deg
                                                0.0,       // knee fully extended
                                                -0.8727};  // ankle plantarflexion 50 deg
  std::array<double, kJointsPerLeg> joint_upper{0.7854,    // hip abduction 45 deg
                                                2.0944,    // hip flexion 120 deg
                                                2.3562,    // knee flexion 135 deg
                                                0.3491};   // ankle dorsiflexion 20 deg

  // End stops at the range-of-motion limits, as in a human joint's ligaments and bone contact
  // (the thesis's model has none; without them the optimiser spun the light feet through
  // hundreds of radians and bent knees backwards). Beyond a limit by d, a one-sided spring
  // k s(d) with s the softplus w log(1 + exp(d / w)) and damping b sigma(d / w) q_dot, sigma the
  // logistic function: smooth, as gradient-based optimisation needs, and below 0.01 N m
  // 0.2 rad inside the range (at 1 rad/s). Choices: k = 2000 N m/rad holds a joint pushed by
  // its largest torque limit (150 N m) 0.075 rad (4 degrees) past its limit; b = 20 N m s/rad
  // damps the foot (3.5e-3 kg m^2 about the ankle) past critical and the whole leg about the
  // hip (~1.5 kg m^2) at 0.2 of critical; w = 0.02 rad rounds the corner. Stiffer or sharper
  // stops broke the MPC (measured on motion I, Coarse MPC, 2 s: k = 1e4 or w = 0.01 left the
  // iLQR at its 6-iteration cap every sample, the accumulated cost rising from 35 to
  // 3.3e3-1.3e4, the robot shuffling; k = 2000 with w = 0.02 leaves it at 35.3, as without
  // stops). The step map treats both terms linearly implicitly (step.hpp), so the stiffness
  // does not limit its sub-step.
  double stop_stiffness = 2000.0;  // [N m/rad]
  double stop_damping = 20.0;      // [N m s/rad]
  double stop_width = 0.02;        // [rad]

  // Reflected actuator inertia ("armature") of each joint [kg m^2], added to M's joint
  // diagonal (dynamics.hpp). The thesis's humanoid is a robot, whose geared joint motors add
  // their rotor inertia times the gear ratio squared; choice: 0.05 kg m^2 on every joint, a
  // rotor of 5.5e-5 kg m^2 through a 1:30 gear, the order of electric humanoid leg actuators
  // (MuJoCo's robot models give 0.01-0.1). Without it the foot (3.5e-3 kg m^2 about the ankle)
  // swings under its 100 N m limit from one end stop to the other within a 30 ms sample, which
  // the MPC's 5 ms sub-steps cannot predict: measured on a push-recovery run (motion I with
  // 0.5 m/s asked for 0.3 s, Coarse MPC), the 30 ms prediction of the joint rates erred by
  // 31.7 rad/s on average (203 at most) against the 1 ms simulator, and the robot hopped from
  // foot to foot; with 0.02 kg m^2 the error fell to 0.36 rad/s and it stood still, with
  // 0.05 kg m^2 to 0.34 rad/s, and motion IV sat and stood (it failed without).
  std::array<double, kJointsPerLeg> armature{0.05, 0.05, 0.05, 0.05};

  // Torque limits [N m], symmetric. The thesis gives none: choice of roughly 3 N m per kg of
  // body mass at the hip and knee (peak isometric human values for a 47 kg adult are of this
  // order), less for abduction and the ankle.
  std::array<double, kJointsPerLeg> torque_limit{100.0, 150.0, 150.0, 100.0};

  // The reaching variant's right arm (model.hpp): upper arm, forearm and hand as one rigid
  // body, elbow and wrist held straight, on a shoulder flexion joint (the thesis's arm has one
  // joint, Sec. 2.6.2, n = 31, and names none). Range: shoulder flexion 180 deg, extension
  // 60 deg (Greene & Heckman 1994, as the legs'). Torque limit (choice): 30 N m, five times
  // the 5.4 N m that holds the straight arm (2.1 kg, centre of mass 0.26 m from the shoulder)
  // horizontal. Armature as the legs' joints.
  double arm_lower = -1.0472;      // [rad] extension 60 deg
  double arm_upper = 3.1416;       // [rad] flexion 180 deg
  double arm_torque_limit = 30.0;  // [N m]
  double arm_armature = 0.05;      // [kg m^2]

  // The torso IMU (hmpc/sensors/imu.hpp), axes aligned with the torso frame, on the torso's
  // centre line this fraction of stature above the mid-hip point. Choice: 0.063 (0.10 m), in
  // the pelvis, where legged robots carry their IMU close to the floating base's origin so
  // that the lever arm's centripetal and tangential terms stay small.
  double imu_above_hip = 0.063;
};

}  // namespace hmpc::humanoid
