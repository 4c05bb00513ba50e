#include "shatter/runtime/transform.hpp"

#include <cmath>

namespace shatter::runtime {

Vec3 rotate(const Quaternion& q, Vec3 v) {
  // v + 2w (u x v) + 2 u x (u x v), u the vector part: two cross products
  // instead of building the matrix.
  const Vec3 u{q.x, q.y, q.z};
  const Vec3 t = cross(u, v) * 2.0;
  return v + t * q.w + cross(u, t);
}

Quaternion multiply(const Quaternion& a, const Quaternion& b) {
  return {a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
          a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x, a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}

Quaternion conjugate(const Quaternion& q) { return {q.w, -q.x, -q.y, -q.z}; }

Quaternion axis_angle(Vec3 axis, double radians) {
  const double length = norm(axis);
  if (length == 0) return {};
  const double s = std::sin(radians / 2) / length;
  return {std::cos(radians / 2), axis.x * s, axis.y * s, axis.z * s};
}

Quaternion quaternion_of(const Matrix3& m) {
  // Shepperd's method: take the square root of the largest of the four
  // candidates, so nothing is divided by a small number.
  const double trace = m[0] + m[4] + m[8];
  Quaternion q;
  if (trace >= m[0] && trace >= m[4] && trace >= m[8]) {
    const double r = std::sqrt(1 + trace);
    q = {r / 2, (m[7] - m[5]) / (2 * r), (m[2] - m[6]) / (2 * r), (m[3] - m[1]) / (2 * r)};
  } else if (m[0] >= m[4] && m[0] >= m[8]) {
    const double r = std::sqrt(1 + m[0] - m[4] - m[8]);
    q = {(m[7] - m[5]) / (2 * r), r / 2, (m[1] + m[3]) / (2 * r), (m[2] + m[6]) / (2 * r)};
  } else if (m[4] >= m[8]) {
    const double r = std::sqrt(1 - m[0] + m[4] - m[8]);
    q = {(m[2] - m[6]) / (2 * r), (m[1] + m[3]) / (2 * r), r / 2, (m[5] + m[7]) / (2 * r)};
  } else {
    const double r = std::sqrt(1 - m[0] - m[4] + m[8]);
    q = {(m[3] - m[1]) / (2 * r), (m[2] + m[6]) / (2 * r), (m[5] + m[7]) / (2 * r), r / 2};
  }
  if (q.w < 0) q = {-q.w, -q.x, -q.y, -q.z};
  const double length = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  return {q.w / length, q.x / length, q.y / length, q.z / length};
}

Matrix3 matrix_of(const Quaternion& q) {
  const double xx = q.x * q.x, yy = q.y * q.y, zz = q.z * q.z;
  const double xy = q.x * q.y, xz = q.x * q.z, yz = q.y * q.z;
  const double wx = q.w * q.x, wy = q.w * q.y, wz = q.w * q.z;
  return {1 - 2 * (yy + zz), 2 * (xy - wz),     2 * (xz + wy),  //
          2 * (xy + wz),     1 - 2 * (xx + zz), 2 * (yz - wx),  //
          2 * (xz - wy),     2 * (yz + wx),     1 - 2 * (xx + yy)};
}

Vec3 apply(const RigidTransform& t, Vec3 p) { return rotate(t.rotation, p) + t.translation; }

RigidTransform compose(const RigidTransform& a, const RigidTransform& b) {
  return {apply(a, b.translation), multiply(a.rotation, b.rotation)};
}

RigidTransform inverse(const RigidTransform& t) {
  const Quaternion back = conjugate(t.rotation);
  return {-rotate(back, t.translation), back};
}

}  // namespace shatter::runtime
