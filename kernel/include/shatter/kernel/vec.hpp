#pragma once
// Small value types shared by every layer: double vectors, planes and signs.
// Nothing here decides geometry; exact decisions live in predicates.hpp.

#include <cmath>
#include <cstdint>

namespace shatter {

struct Vec2 {
  double x = 0, y = 0;
  friend bool operator==(const Vec2&, const Vec2&) = default;  // bitwise-style storage equality, never a geometric test
};

struct Vec3 {
  double x = 0, y = 0, z = 0;

  double operator[](int axis) const { return axis == 0 ? x : axis == 1 ? y : z; }
  friend Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
  friend Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
  friend Vec3 operator-(Vec3 a) { return {-a.x, -a.y, -a.z}; }
  friend Vec3 operator*(Vec3 a, double s) { return {a.x * s, a.y * s, a.z * s}; }
  friend Vec3 operator*(double s, Vec3 a) { return a * s; }
  friend bool operator==(const Vec3&, const Vec3&) = default;  // storage equality (welding), see DESIGN.md
};

/// Tangent with handedness in w, as glTF stores it.
struct Vec4 {
  double x = 0, y = 0, z = 0, w = 1;
  friend bool operator==(const Vec4&, const Vec4&) = default;
};

inline double dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double norm(Vec3 a) { return std::sqrt(dot(a, a)); }
/// Unit vector along a; a zero vector stays zero (callers never divide by it).
inline Vec3 normalized(Vec3 a) {
  const double n = norm(a);
  return n > 0 ? a * (1.0 / n) : a;
}
inline bool is_finite(Vec3 a) { return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z); }

/// Exact sign of a quantity: the answer of every predicate in shatter.
enum class Sign : std::int8_t { negative = -1, zero = 0, positive = 1 };

inline Sign flip(Sign s) { return static_cast<Sign>(-static_cast<int>(s)); }

/// The plane n·x + d = 0, held as the four doubles the user gave. The plane is
/// exactly the set these doubles describe: n need not be unit length, and nothing
/// is normalised, so predicates against it stay exact.
struct Plane {
  Vec3 normal;
  double offset = 0;
};

/// The point of `plane` over (u, v) in the plane's projection along `axis`
/// (0, 1, 2 for x, y, z): coordinate (axis + 1) % 3 is u, (axis + 2) % 3 is v,
/// and coordinate `axis` is -(d + n_i u + n_j v) / n_axis, evaluated in doubles in
/// that order, so every caller gets the same bits (the bonds' centroids are made
/// by it, and the .shatter file stores only their u and v).
/// Precondition: axis in 0..2; a zero or non-finite n_axis gives a non-finite
/// coordinate, nothing else.
inline Vec3 point_on_plane_over(const Plane& plane, int axis, double u, double v) {
  const int i = (axis + 1) % 3, j = (axis + 2) % 3;
  const double n[3] = {plane.normal.x, plane.normal.y, plane.normal.z};
  double xyz[3] = {0, 0, 0};
  xyz[i] = u;
  xyz[j] = v;
  xyz[axis] = -(plane.offset + n[i] * u + n[j] * v) / n[axis];
  return {xyz[0], xyz[1], xyz[2]};
}

}  // namespace shatter
