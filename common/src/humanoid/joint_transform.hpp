// Products with a revolute joint's motion transform X = [E 0; -E r^ E] (spatial.hpp) that skip
// the entries of X that are exactly zero for every joint angle, and that otherwise add the same
// products in the same order as Eigen's dense 6x6 expressions. A skipped product is an exact
// (signed) zero, and adding an exact zero to a sum leaves its value unchanged, so the results
// are the dense expressions' to the last bit, not merely to round-off: the closed loops built on
// the dynamics are chaotic at the level of round-off, and a faster CRBA must not move them.
//
// Which entries are zero depends on the joint: E = R(axis, q)^T about a coordinate axis has
// zeros wherever exactly one index is the axis (Eigen's AngleAxis writes them as products with
// the axis's zero components), and E r^ has zeros where r's components are zero. The pattern is
// a template parameter, chosen per body at construction; a general axis takes the dense pattern.
//
// The two orders reproduced (Eigen 3.4, without fused multiply-add):
// - X^T times a column (the coefficient-based product of a transposed matrix is a dot product
//   per entry, reduced in two lanes of even and odd terms): (t0 + (t2 + t4)) + (t1 + (t3 + t5)).
// - A matrix times X (column-major packets over rows): t0 + t1 + ... + t5, left to right.
#pragma once

#include <Eigen/Core>
#include <array>
#include <utility>

#include "hmpc/humanoid/spatial.hpp"

namespace hmpc::humanoid::joint_transform {

using spatial::Matrix3;
using spatial::Matrix6;
using spatial::Vector3;
using spatial::Vector6;

// A joint's zero pattern: the coordinate axis it turns about (-1: none, E is dense) and which of
// its origin's components r are non-zero (bit m for component m).
struct Pattern {
  int axis;
  int origin_mask;
};
constexpr int kPatterns = 4 * 8;
constexpr int index_of(Pattern p) { return (p.axis + 1) * 8 + p.origin_mask; }
constexpr Pattern pattern_at(int index) { return {index / 8 - 1, index % 8}; }

// The pattern of a joint from its axis (a unit vector) and origin.
inline Pattern pattern_of(const Vector3& axis, const Vector3& origin) {
  int coordinate = -1;
  for (int m = 0; m < 3; ++m) {
    if (axis[m] != 0.0 && axis[(m + 1) % 3] == 0.0 && axis[(m + 2) % 3] == 0.0) coordinate = m;
  }
  int mask = 0;
  for (int m = 0; m < 3; ++m) mask |= origin[m] != 0.0 ? 1 << m : 0;
  return {coordinate, mask};
}

constexpr bool rotation_nonzero(Pattern p, int row, int col) {
  return p.axis < 0 || row == col || (row != p.axis && col != p.axis);
}
// r^ (spatial::skew): entry (k, j), k != j, is +-r of the third index.
constexpr bool skew_nonzero(Pattern p, int k, int j) {
  return k != j && ((p.origin_mask >> (3 - k - j)) & 1) != 0;
}
// -E r^, the lower-left block.
constexpr bool shift_nonzero(Pattern p, int row, int col) {
  for (int k = 0; k < 3; ++k) {
    if (rotation_nonzero(p, row, k) && skew_nonzero(p, k, col)) return true;
  }
  return false;
}
// X's entry (row, col).
constexpr bool nonzero(Pattern p, int row, int col) {
  if (row < 3) return col < 3 && rotation_nonzero(p, row, col);
  return col < 3 ? shift_nonzero(p, row - 3, col) : rotation_nonzero(p, row - 3, col - 3);
}
// The first non-zero entry of X's column col (its diagonal is never zero).
constexpr int first_nonzero_row(Pattern p, int col) {
  int row = 0;
  while (!nonzero(p, row, col)) ++row;
  return row;
}

// a + b where either term may be absent (an exact zero in the dense sum).
template <bool HasA, bool HasB>
EIGEN_ALWAYS_INLINE Eigen::Vector2d sum_of(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  if constexpr (HasA && HasB) return a + b;
  if constexpr (HasA && !HasB) return a;
  if constexpr (!HasA) return b;
}

// Rows P and P + 1 of X^T y, each row's sum over k of X(k, I) y_k in the two-lane order above;
// the rows are two lanes of one packet. A term is left out where it is zero in both rows, and
// kept where it is zero in one: adding an exact zero does not change a sum either.
template <int Index, int P, class Column>
EIGEN_ALWAYS_INLINE Eigen::Vector2d transposed_rows_times(const Matrix6& Xt, const Column& y) {
  constexpr Pattern p = pattern_at(Index);
  constexpr bool n0 = nonzero(p, 0, P) || nonzero(p, 0, P + 1);
  constexpr bool n1 = nonzero(p, 1, P) || nonzero(p, 1, P + 1);
  constexpr bool n2 = nonzero(p, 2, P) || nonzero(p, 2, P + 1);
  constexpr bool n3 = nonzero(p, 3, P) || nonzero(p, 3, P + 1);
  constexpr bool n4 = nonzero(p, 4, P) || nonzero(p, 4, P + 1);
  constexpr bool n5 = nonzero(p, 5, P) || nonzero(p, 5, P + 1);
  Eigen::Vector2d t[6];
  for (int k = 0; k < 6; ++k) t[k] = Xt.col(k).template segment<2>(P) * y[k];
  constexpr bool n24 = n2 || n4, n35 = n3 || n5;
  const Eigen::Vector2d even = sum_of<n0, n24>(t[0], sum_of<n2, n4>(t[2], t[4]));
  const Eigen::Vector2d odd = sum_of<n1, n35>(t[1], sum_of<n3, n5>(t[3], t[5]));
  constexpr bool has_even = n0 || n24, has_odd = n1 || n35;
  return sum_of<has_even, has_odd>(even, odd);
}

// X^T y, from Xt = X^T.
template <int Index, class Column, class Out>
EIGEN_ALWAYS_INLINE void transposed_times(const Matrix6& Xt, const Column& y, Out&& out) {
  out.template segment<2>(0) = transposed_rows_times<Index, 0>(Xt, y);
  out.template segment<2>(2) = transposed_rows_times<Index, 2>(Xt, y);
  out.template segment<2>(4) = transposed_rows_times<Index, 4>(Xt, y);
}

// Column J of A X: sum over k of A.col(k) X(k, J), left to right.
template <int Index, int J, int... K>
EIGEN_ALWAYS_INLINE Vector6 times_column(const Matrix6& A, const Matrix6& X,
                                         std::integer_sequence<int, K...>) {
  constexpr Pattern p = pattern_at(Index);
  constexpr int first = first_nonzero_row(p, J);
  Vector6 sum = A.col(first) * X(first, J);
  ((K > first && nonzero(p, K, J) ? (sum += A.col(K) * X(K, J), 0) : 0), ...);
  return sum;
}

// Carrying a body's composite inertia C and the forces that reach it (columns of F) across its
// joint to its parent: parent = start + X^T C X (Featherstone Table 6.2, start being the
// parent's own inertia or its composite so far), F = X^T F. One call per body, so that a
// pattern's products are dispatched once.
template <int Columns>
using Forces = Eigen::Matrix<double, 6, Columns>;

template <int Index>
struct Structured {
  // Appends X^T f for the first count columns f of forces to parent_forces after its first
  // parent_count columns.
  // Flattened: Eigen's small assignments inside are otherwise left as calls in a large unit.
  template <int Columns>
  [[gnu::flatten]] static void carry_to_parent(Matrix6& parent, const Matrix6& start,
                                               const Matrix6& X, const Matrix6& C,
                                               const Forces<Columns>& forces, int count,
                                               Forces<Columns>& parent_forces, int parent_count) {
    constexpr auto rows = std::make_integer_sequence<int, 6>{};
    const Matrix6 Xt = X.transpose();
    for (int c = 0; c < count; ++c) {
      transposed_times<Index>(Xt, forces.col(c), parent_forces.col(parent_count + c));
    }
    Matrix6 XtC;
    for (int j = 0; j < 6; ++j) transposed_times<Index>(Xt, C.col(j), XtC.col(j));
    add_columns(parent, start, XtC, X, rows);
  }

 private:
  template <int... J>
  static EIGEN_ALWAYS_INLINE void add_columns(Matrix6& parent, const Matrix6& start,
                                              const Matrix6& A, const Matrix6& X,
                                              std::integer_sequence<int, J...> rows) {
    ((parent.col(J) = start.col(J) + times_column<Index, J>(A, X, rows)), ...);
  }
};

// The instances for every pattern, indexed by index_of().
template <int Columns>
using CarryToParent = void (*)(Matrix6& parent, const Matrix6& start, const Matrix6& X,
                               const Matrix6& C, const Forces<Columns>& forces, int count,
                               Forces<Columns>& parent_forces, int parent_count);
template <int Columns, int... Index>
constexpr std::array<CarryToParent<Columns>, kPatterns> carry_table(
    std::integer_sequence<int, Index...>) {
  return {{&Structured<Index>::template carry_to_parent<Columns>...}};
}
template <int Columns>
inline constexpr std::array<CarryToParent<Columns>, kPatterns> kCarryToParent =
    carry_table<Columns>(std::make_integer_sequence<int, kPatterns>{});

}  // namespace hmpc::humanoid::joint_transform
