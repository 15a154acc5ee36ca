#include "hmpc/humanoid/model.hpp"

#include <Eigen/Geometry>

namespace hmpc::humanoid {
namespace {

struct MassPoint {
  double mass;
  Vector3 com;
  Matrix3 inertia;  // about com
};

// Principal central inertia of a segment of length `length` from de Leva's radii of gyration;
// `sagittal`, `transverse`, `longitudinal` name the body axes (0 = x, 1 = y, 2 = z) they lie on.
Matrix3 segment_inertia(const Segment& s, double mass, double length, int sagittal, int transverse,
                        int longitudinal) {
  Matrix3 inertia = Matrix3::Zero();
  const auto square = [](double r) { return r * r; };
  inertia(sagittal, sagittal) = mass * square(s.gyration_sagittal * length);
  inertia(transverse, transverse) = mass * square(s.gyration_transverse * length);
  inertia(longitudinal, longitudinal) = mass * square(s.gyration_longitudinal * length);
  return inertia;
}

// Rigidly joined parts as one body: combined CoM, and central inertia by the parallel-axis
// theorem, I = sum(I_k + m_k ((d.d) 1 - d d^T)), d the part's CoM from the combined CoM.
template <std::size_t N>
MassPoint lump(const std::array<MassPoint, N>& parts) {
  MassPoint sum{0.0, Vector3::Zero(), Matrix3::Zero()};
  for (const auto& part : parts) {
    sum.mass += part.mass;
    sum.com += part.mass * part.com;
  }
  sum.com /= sum.mass;
  for (const auto& part : parts) {
    const Vector3 d = part.com - sum.com;
    sum.inertia +=
        part.inertia + part.mass * (d.squaredNorm() * Matrix3::Identity() - d * d.transpose());
  }
  return sum;
}

}  // namespace

template <int ArmJoints>
BasicModel<ArmJoints>::BasicModel(const Parameters& p) {
  using D = Dimensions<ArmJoints>;
  const double scale = p.stature / p.reference_stature;
  const double fraction_sum =
      p.head.mass_fraction + p.trunk.mass_fraction +
      2.0 * (p.upper_arm.mass_fraction + p.forearm.mass_fraction + p.hand.mass_fraction +
             p.thigh.mass_fraction + p.shank.mass_fraction + p.foot.mass_fraction);
  const auto mass = [&](const Segment& s) { return p.body_mass * s.mass_fraction / fraction_sum; };
  const auto length = [&](const Segment& s) { return scale * s.reference_length; };

  const double head = length(p.head), trunk = length(p.trunk), thigh = length(p.thigh),
               shank = length(p.shank), foot = length(p.foot);
  const double upper_arm = length(p.upper_arm), forearm = length(p.forearm);
  const double ankle_height = p.stature - (head + trunk + thigh + shank);
  const double mid_hip_height = ankle_height + shank + thigh;

  // Vertical segments in anatomical position: sagittal axis x, transverse y, longitudinal z.
  const auto vertical = [&](const Segment& s, double top_z, double y) {
    const double m = mass(s), l = length(s);
    return MassPoint{m, Vector3(0.0, y, top_z - s.com_from_proximal * l),
                     segment_inertia(s, m, l, 0, 1, 2)};
  };

  // Torso: trunk (proximal end cervicale, on top), head (proximal end vertex), arms hanging
  // from the shoulder joint centres; the reaching variant's right arm is its own body.
  const double shoulder_z = p.shoulder_height * p.stature - mid_hip_height;
  const double shoulder_y = 0.5 * p.shoulder_width * p.stature;
  const auto arm_parts = [&](double y) {
    return std::array<MassPoint, 3>{vertical(p.upper_arm, shoulder_z, y),
                                    vertical(p.forearm, shoulder_z - upper_arm, y),
                                    vertical(p.hand, shoulder_z - upper_arm - forearm, y)};
  };
  const std::array<MassPoint, 3> left_arm = arm_parts(shoulder_y),
                                 right_arm = arm_parts(-shoulder_y);
  std::array<MassPoint, 8 - 3 * ArmJoints> torso_parts{vertical(p.trunk, trunk, 0.0),
                                                       vertical(p.head, trunk + head, 0.0)};
  for (int k = 0; k < 3; ++k) torso_parts[2 + k] = left_arm[k];
  if constexpr (ArmJoints == 0) {
    // cppcheck-suppress containerOutOfBounds ; it also reads this branch for the arm's 5 parts
    for (int k = 0; k < 3; ++k) torso_parts[5 + k] = right_arm[k];
  }
  const MassPoint torso = lump(torso_parts);
  bodies[0].mass = torso.mass;
  bodies[0].com = torso.com;
  bodies[0].inertia = torso.inertia;

  for (int leg = 0; leg < 2; ++leg) {
    const double side = leg == 0 ? 1.0 : -1.0;  // left leg on +y
    Body& hip = bodies[body_of(leg, kHipAbduction)];
    hip.parent = 0;
    hip.axis = Vector3(side, 0.0, 0.0);  // positive angle abducts either leg
    hip.joint_origin = Vector3(0.0, side * 0.5 * p.hip_joint_spacing * p.stature, 0.0);

    Body& thigh_body = bodies[body_of(leg, kHipFlexion)];
    thigh_body.parent = body_of(leg, kHipAbduction);
    thigh_body.axis = -Vector3::UnitY();  // flexion swings the knee forward
    const MassPoint thigh_part = vertical(p.thigh, 0.0, 0.0);
    thigh_body.mass = thigh_part.mass;
    thigh_body.com = thigh_part.com;
    thigh_body.inertia = thigh_part.inertia;

    Body& shank_body = bodies[body_of(leg, kKnee)];
    shank_body.parent = body_of(leg, kHipFlexion);
    shank_body.axis = Vector3::UnitY();  // flexion swings the foot backward
    shank_body.joint_origin = Vector3(0.0, 0.0, -thigh);
    const MassPoint shank_part = vertical(p.shank, 0.0, 0.0);
    shank_body.mass = shank_part.mass;
    shank_body.com = shank_part.com;
    shank_body.inertia = shank_part.inertia;

    // Foot: long axis x (de Leva's longitudinal), transverse y, the remaining (sagittal) z.
    Body& foot_body = bodies[body_of(leg, kAnkle)];
    foot_body.parent = body_of(leg, kKnee);
    foot_body.axis = -Vector3::UnitY();  // dorsiflexion lifts the toes
    foot_body.joint_origin = Vector3(0.0, 0.0, -shank);
    foot_body.mass = mass(p.foot);
    foot_body.com = Vector3((p.foot.com_from_proximal - p.heel_behind_ankle) * foot, 0.0,
                            -(1.0 - p.foot_com_height) * ankle_height);
    foot_body.inertia = segment_inertia(p.foot, foot_body.mass, foot, 2, 1, 0);
  }

  if constexpr (ArmJoints == 1) {
    // Arm coordinates: origin at the shoulder joint centre, hanging along -z at zero angle.
    Body& arm = bodies[D::kArmBody];
    arm.parent = 0;
    arm.axis = -Vector3::UnitY();  // flexion raises the arm forward
    arm.joint_origin = Vector3(0.0, -shoulder_y, shoulder_z);
    std::array<MassPoint, 3> parts = right_arm;
    for (MassPoint& part : parts) part.com -= arm.joint_origin;
    const MassPoint lumped = lump(parts);
    arm.mass = lumped.mass;
    arm.com = lumped.com;
    arm.inertia = lumped.inertia;
    hand = parts[2].com;  // the hand segment's centre of mass: the palm
  }

  gravity = Vector3(0.0, 0.0, -p.gravity);
  vertex = Vector3(0.0, 0.0, trunk + head);
  imu = Vector3(0.0, 0.0, p.imu_above_hip * p.stature);
  sole_height = ankle_height;
  for (int leg = 0; leg < 2; ++leg) {
    for (int j = 0; j < kJointsPerLeg; ++j) {
      joint_lower[leg * kJointsPerLeg + j] = p.joint_lower[j];
      joint_upper[leg * kJointsPerLeg + j] = p.joint_upper[j];
      torque_limit[leg * kJointsPerLeg + j] = p.torque_limit[j];
      armature[leg * kJointsPerLeg + j] = p.armature[j];
    }
  }
  if constexpr (ArmJoints == 1) {
    joint_lower[D::kArmJoint] = p.arm_lower;
    joint_upper[D::kArmJoint] = p.arm_upper;
    torque_limit[D::kArmJoint] = p.arm_torque_limit;
    armature[D::kArmJoint] = p.arm_armature;
  }
}

template <int ArmJoints>
double BasicModel<ArmJoints>::total_mass() const {
  double m = 0.0;
  for (const auto& b : bodies) m += b.mass;
  return m;
}

template struct BasicModel<0>;
template struct BasicModel<1>;

}  // namespace hmpc::humanoid
