// Spatial (6-D) algebra of Featherstone's "Rigid Body Dynamics Algorithms" (2008, Ch. 2), in
// Plücker coordinates with the angular part first: motion vectors (omega, v_origin) and force
// vectors (moment about the origin, force). Shared by the dynamics and its derivatives, whose
// inner loops call these small functions hundreds of times per call: they are forced inline.
#pragma once

#include <Eigen/Core>

namespace hmpc::humanoid::spatial {

using Vector3 = Eigen::Vector3d;
using Matrix3 = Eigen::Matrix3d;
using Vector6 = Eigen::Matrix<double, 6, 1>;
using Matrix6 = Eigen::Matrix<double, 6, 6>;

EIGEN_ALWAYS_INLINE Matrix3 skew(const Vector3& x) {
  Matrix3 s;
  s << 0.0, -x.z(), x.y(), x.z(), 0.0, -x.x(), -x.y(), x.x(), 0.0;
  return s;
}

// Motion transform from frame A to frame B, B rotated by E (A to B coordinates) and with
// origin r in A coordinates: X = [E 0; -E r^ E].
inline Matrix6 motion_transform(const Matrix3& E, const Vector3& r) {
  Matrix6 X;
  X.topLeftCorner<3, 3>() = E;
  X.topRightCorner<3, 3>().setZero();
  X.bottomLeftCorner<3, 3>() = -E * skew(r);
  X.bottomRightCorner<3, 3>() = E;
  return X;
}

// a x b of the 3-vectors starting at a[i] and b[j], written out (Eigen's formula, so the same
// numbers): Eigen's cross on 3-blocks of 6-vectors is a call the compiler does not inline.
EIGEN_ALWAYS_INLINE Vector3 cross3(const Vector6& a, int i, const Vector6& b, int j) {
  return Vector3(a[i + 1] * b[j + 2] - a[i + 2] * b[j + 1], a[i + 2] * b[j] - a[i] * b[j + 2],
                 a[i] * b[j + 1] - a[i + 1] * b[j]);
}

// Cross products for motion (v x m, crm) and force (v x* f, crf = -crm^T).
EIGEN_ALWAYS_INLINE Vector6 cross_motion(const Vector6& v, const Vector6& m) {
  Vector6 out;
  out.head<3>() = cross3(v, 0, m, 0);
  out.tail<3>() = cross3(v, 0, m, 3) + cross3(v, 3, m, 0);
  return out;
}
EIGEN_ALWAYS_INLINE Vector6 cross_force(const Vector6& v, const Vector6& f) {
  Vector6 out;
  out.head<3>() = cross3(v, 0, f, 0) + cross3(v, 3, f, 3);
  out.tail<3>() = cross3(v, 0, f, 3);
  return out;
}

// Spatial inertia about the body origin from mass, CoM c and central inertia:
// [I_c + m c^ c^T, m c^; m c^T, m 1].
inline Matrix6 spatial_inertia(double m, const Vector3& c, const Matrix3& inertia_com) {
  const Matrix3 cx = skew(c);
  Matrix6 I;
  I.topLeftCorner<3, 3>() = inertia_com + m * cx * cx.transpose();
  I.topRightCorner<3, 3>() = m * cx;
  I.bottomLeftCorner<3, 3>() = m * cx.transpose();
  I.bottomRightCorner<3, 3>() = m * Matrix3::Identity();
  return I;
}

}  // namespace hmpc::humanoid::spatial
