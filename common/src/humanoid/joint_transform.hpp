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
// Each entry is computed on its own, so which entries share a packet is free: the packets here
// pair entries whose left-out terms are the same, two forces or two columns of C at once for
// X^T, two rows at once for A X.
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

// The pattern of a joint from its axis and origin, as the model gives them.
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
// The first entry of X's column col that the pattern keeps (every pattern keeps the diagonal).
constexpr int first_nonzero_row(Pattern p, int col) {
  int row = 0;
  while (!nonzero(p, row, col)) ++row;
  return row;
}

// Two doubles in one register (SSE2 or NEON): Eigen's own packet operations, so that the lanes
// round exactly as the dense expressions' packets do.
using Packet = Eigen::internal::Packet2d;

// X's entries, each on both lanes of a packet.
using Broadcast = Packet[6][6];

// a + b where either term may be absent (an exact zero in the dense sum).
template <bool HasA, bool HasB>
EIGEN_ALWAYS_INLINE Packet sum_of(const Packet& a, const Packet& b) {
  if constexpr (HasA && HasB) return Eigen::internal::padd(a, b);
  if constexpr (HasA && !HasB) return a;
  if constexpr (!HasA) return b;
}

// Sum over k of X(k, I) y_k in the two-lane order above, for two vectors y at once (the two lanes
// of y[k]): both lanes share X's column I, so the terms left out are the same in both.
template <int Index, int I>
EIGEN_ALWAYS_INLINE Packet transposed_row_times(const Broadcast& X, const Packet (&y)[6]) {
  constexpr Pattern p = pattern_at(Index);
  constexpr bool n0 = nonzero(p, 0, I), n1 = nonzero(p, 1, I), n2 = nonzero(p, 2, I);
  constexpr bool n3 = nonzero(p, 3, I), n4 = nonzero(p, 4, I), n5 = nonzero(p, 5, I);
  const auto term = [&](int k) { return Eigen::internal::pmul(X[k][I], y[k]); };
  constexpr bool n24 = n2 || n4, n35 = n3 || n5;
  const Packet even = sum_of<n0, n24>(term(0), sum_of<n2, n4>(term(2), term(4)));
  const Packet odd = sum_of<n1, n35>(term(1), sum_of<n3, n5>(term(3), term(5)));
  constexpr bool has_even = n0 || n24, has_odd = n1 || n35;
  return sum_of<has_even, has_odd>(even, odd);
}

// Rows P, P + 1 of column J of A X: sum over k of A(P.., k) X(k, J), left to right; a[k] holds
// (A(P, k), A(P + 1, k)).
template <int Index, int J, int... K>
EIGEN_ALWAYS_INLINE Packet times_column(const Packet (&a)[6], const Broadcast& X,
                                        std::integer_sequence<int, K...>) {
  constexpr Pattern p = pattern_at(Index);
  constexpr int first = first_nonzero_row(p, J);
  Packet sum = Eigen::internal::pmul(a[first], X[first][J]);
  ((K > first && nonzero(p, K, J)
        ? (sum = Eigen::internal::padd(sum, Eigen::internal::pmul(a[K], X[K][J])), 0)
        : 0),
   ...);
  return sum;
}

// Forces as columns, stored by rows, so that two forces' entries k are one packet.
template <int Columns>
using Forces = Eigen::Matrix<double, 6, Columns, Eigen::RowMajor>;

// Carrying a body's composite inertia C and the forces that reach it (columns of F) across its
// joint to its parent: parent = start + X^T C X (Featherstone Table 6.2, start being the
// parent's own inertia or its composite so far), F = X^T F. One call per body, so that a
// pattern's products are dispatched once.

template <int Index>
struct Structured {
  // Appends X^T f for the first count columns f of forces to parent_forces after its first
  // parent_count columns.
  template <int Columns>
  static void carry_to_parent(Matrix6& parent, const Matrix6& start, const Matrix6& X,
                              const Matrix6& C, const Forces<Columns>& forces, int count,
                              Forces<Columns>& parent_forces, int parent_count) {
    namespace ei = Eigen::internal;
    constexpr auto rows = std::make_integer_sequence<int, 6>{};
    Broadcast x;  // the entries that are not zero
    broadcast(X, x, std::make_integer_sequence<int, 36>{});
    // Forces two at a time, lanes (f_c, f_c+1); an odd last one on both lanes.
    for (int c = 0; c < count; c += 2) {
      Packet f[6];
      if (c + 1 < count) {
        for (int k = 0; k < 6; ++k) f[k] = ei::ploadu<Packet>(&forces(k, c));
        transposed_into<false, Columns>(x, f, &parent_forces(0, parent_count + c), rows);
      } else {
        for (int k = 0; k < 6; ++k) f[k] = ei::pset1<Packet>(forces(k, c));
        transposed_into<true, Columns>(x, f, &parent_forces(0, parent_count + c), rows);
      }
    }
    // X^T C by rows, lanes (C(k, j), C(k, j + 1)) (2 x 2 blocks of C transposed), then each 2 x
    // 2 block of the product transposed back: a[q][k] holds (X^T C)(2q, k) and (2q + 1, k).
    Packet c_pairs[3][6];
    for (int j = 0; j < 3; ++j) {
      for (int k = 0; k < 6; k += 2) {
        transpose_block(ei::ploadu<Packet>(&C(k, 2 * j)), ei::ploadu<Packet>(&C(k, 2 * j + 1)),
                        c_pairs[j][k], c_pairs[j][k + 1]);
      }
    }
    Packet a[3][6];
    row_pairs(x, c_pairs, a, std::make_integer_sequence<int, 3>{});
    // parent = start + (X^T C) X by columns, lanes (rows P, P + 1).
    add_columns(parent, start, a, x, rows);
  }

 private:
  template <int... E>
  static EIGEN_ALWAYS_INLINE void broadcast(const Matrix6& X, Broadcast& x,
                                            std::integer_sequence<int, E...>) {
    constexpr Pattern p = pattern_at(Index);
    ((nonzero(p, E / 6, E % 6)
          ? (x[E / 6][E % 6] = Eigen::internal::pset1<Packet>(X(E / 6, E % 6)), 0)
          : 0),
     ...);
  }
  // out points at entry (0, c) of a row-major 6 x Columns matrix: rows I, columns c and c + 1
  // (only c if Single).
  template <bool Single, int Columns, int... I>
  static EIGEN_ALWAYS_INLINE void transposed_into(const Broadcast& X, const Packet (&f)[6],
                                                  double* out, std::integer_sequence<int, I...>) {
    if constexpr (Single) {
      ((out[I * Columns] = Eigen::internal::pfirst(transposed_row_times<Index, I>(X, f))), ...);
    } else {
      (Eigen::internal::pstoreu(out + I * Columns, transposed_row_times<Index, I>(X, f)), ...);
    }
  }
  template <int... Q>
  static EIGEN_ALWAYS_INLINE void row_pairs(const Broadcast& X, const Packet (&c_pairs)[3][6],
                                            Packet (&a)[3][6], std::integer_sequence<int, Q...>) {
    for (int j = 0; j < 3; ++j) {
      (transpose_block(transposed_row_times<Index, 2 * Q>(X, c_pairs[j]),
                       transposed_row_times<Index, 2 * Q + 1>(X, c_pairs[j]), a[Q][2 * j],
                       a[Q][2 * j + 1]),
       ...);
    }
  }
  // Eigen's own 2 x 2 packet transpose. Its block type takes the packet, a vector type, as a
  // template argument, on which GCC warns that the type's attributes are ignored; Eigen's own
  // headers silence the same warning for the same use.
  static EIGEN_ALWAYS_INLINE void transpose_block(const Packet& upper, const Packet& lower,
                                                  Packet& left, Packet& right) {
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wignored-attributes"
    Eigen::internal::PacketBlock<Packet, 2> block;
#pragma GCC diagnostic pop
    block.packet[0] = upper;
    block.packet[1] = lower;
    Eigen::internal::ptranspose(block);
    left = block.packet[0];
    right = block.packet[1];
  }
  template <int... J>
  static EIGEN_ALWAYS_INLINE void add_columns(Matrix6& parent, const Matrix6& start,
                                              const Packet (&a)[3][6], const Broadcast& X,
                                              std::integer_sequence<int, J...> rows) {
    for (int q = 0; q < 3; ++q) {
      (Eigen::internal::pstoreu(
           &parent(2 * q, J),
           Eigen::internal::padd(Eigen::internal::ploadu<Packet>(&start(2 * q, J)),
                                 times_column<Index, J>(a[q], X, rows))),
       ...);
    }
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
CarryToParent<Columns> carry_for(int pattern_index) {
  static constexpr std::array<CarryToParent<Columns>, kPatterns> table =
      carry_table<Columns>(std::make_integer_sequence<int, kPatterns>{});
  return table[pattern_index];
}

}  // namespace hmpc::humanoid::joint_transform
