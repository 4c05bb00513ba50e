#pragma once
// Rigid transforms for the runtime's public API: a rotation as a unit quaternion
// and a translation, in doubles. The runtime's own types, so no user of it needs
// Bullet's or Eigen's.

#include <array>

#include "shatter/kernel/vec.hpp"

namespace shatter::runtime {

/// A rotation as a unit quaternion w + xi + yj + zk (glTF stores it as x, y, z, w).
struct Quaternion {
  double w = 1, x = 0, y = 0, z = 0;
  friend bool operator==(const Quaternion&, const Quaternion&) = default;
};

/// Row-major 3x3 matrix.
using Matrix3 = std::array<double, 9>;

/// The rotation of `v` by `q`. Precondition: q is of unit length (not checked).
Vec3 rotate(const Quaternion& q, Vec3 v);
/// The product a * b: rotating by it rotates by b first, then by a.
Quaternion multiply(const Quaternion& a, const Quaternion& b);
/// The inverse rotation of a unit quaternion.
Quaternion conjugate(const Quaternion& q);
/// The rotation by `radians` about `axis` (any non-zero length; a zero axis gives
/// the identity).
Quaternion axis_angle(Vec3 axis, double radians);
/// The unit quaternion of a proper rotation matrix (orthonormal, determinant +1),
/// with w >= 0. Precondition: `rotation` is such a matrix up to rounding.
Quaternion quaternion_of(const Matrix3& rotation);
/// The rotation matrix of a unit quaternion.
Matrix3 matrix_of(const Quaternion& q);

/// x -> rotation(x) + translation.
struct RigidTransform {
  Vec3 translation;
  Quaternion rotation;
  friend bool operator==(const RigidTransform&, const RigidTransform&) = default;
};

/// `t` applied to the point `p`.
Vec3 apply(const RigidTransform& t, Vec3 p);
/// a after b: apply(compose(a, b), p) == apply(a, apply(b, p)).
RigidTransform compose(const RigidTransform& a, const RigidTransform& b);
/// The transform undoing `t`.
RigidTransform inverse(const RigidTransform& t);

}  // namespace shatter::runtime
