#pragma once
// The single-precision vector, plane and ray arithmetic the seed's fragment modeller
// ran on: Unity's Vector3, Plane and Ray (seed thesis 4.1, "Unity's scripting interface
// contain useful classes such as a Vector class ... a Plane class"), reimplemented from
// their documented behaviour, one IEEE float operation at a time. This file is compiled
// with -ffp-contract=off (CMakeLists.txt) so that no multiply-add is fused: every
// product and sum rounds to float as it does in C# on SSE.

#include <cmath>

namespace seed_peer {

struct Vec3f {
  float x = 0, y = 0, z = 0;
};

inline Vec3f operator+(Vec3f a, Vec3f b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3f operator-(Vec3f a, Vec3f b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3f operator*(Vec3f a, float s) { return {a.x * s, a.y * s, a.z * s}; }
inline Vec3f operator/(Vec3f a, float s) { return {a.x / s, a.y / s, a.z / s}; }

/// Vector3.Dot: (x*x' + y*y') + z*z', left to right as C# evaluates it.
inline float dot(Vec3f a, Vec3f b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

/// Vector3.Cross.
inline Vec3f cross(Vec3f a, Vec3f b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

/// Vector3.magnitude: the correctly rounded float square root (Mathf.Sqrt goes
/// through a double, which rounds to the same float).
inline float magnitude(Vec3f a) { return std::sqrt(dot(a, a)); }

/// Vector3.Normalize: the zero vector when the magnitude is at most 1e-5 (Unity's
/// kEpsilon), else each component divided by the magnitude.
inline Vec3f normalized(Vec3f a) {
  const float m = magnitude(a);
  return m > 1e-5f ? a / m : Vec3f{};
}

/// Vector3 operator==: Unity compares positions approximately, true when the squared
/// distance is below 9.99999944e-11f (1e-5 squared, as a float). This is the equality
/// every "matches" and "in common" of the seed's chapter 4 goes through when it
/// compares Vector3 values; the thesis blames exactly it (6.2.3: "when the fragments
/// get too small Unity cannot properly compare vectors").
inline bool unity_equal(Vec3f a, Vec3f b) {
  const Vec3f d = a - b;
  return dot(d, d) < 9.99999944e-11f;
}

/// Bitwise-equal positions (the alternative --compare exact).
inline bool exactly_equal(Vec3f a, Vec3f b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

/// Unity's Plane: points p with dot(normal, p) + distance == 0. Plane(inNormal, inPoint)
/// normalizes the normal and sets distance = -dot(normal, inPoint).
struct PlaneF {
  Vec3f normal;
  float distance = 0;

  static PlaneF through(Vec3f in_normal, Vec3f in_point) {
    PlaneF p;
    p.normal = normalized(in_normal);
    p.distance = -dot(p.normal, in_point);
    return p;
  }
  /// Plane.GetSide: true on the positive side, strictly; a point on the plane is on
  /// the negative side.
  bool get_side(Vec3f p) const { return dot(normal, p) + distance > 0.0f; }

  /// Plane.Raycast along a Ray(origin, direction) (Ray normalizes its direction):
  /// enter = (-dot(origin, normal) - distance) / dot(direction, normal); the point
  /// is Ray.GetPoint(enter) = origin + direction * enter. Unity returns false (and
  /// enter 0) for a direction parallel to the plane (Mathf.Approximately(a, 0)) and
  /// false for enter <= 0; the seed's description ("perform a raytrace from S to
  /// P0 to find B0") has no use for the flag, so the point is taken either way.
  Vec3f raycast_point(Vec3f origin, Vec3f toward) const {
    const Vec3f direction = normalized(toward - origin);
    const float a = dot(direction, normal);
    const float num = -dot(origin, normal) - distance;
    const float enter = approximately_zero(a) ? 0.0f : num / a;
    return origin + direction * enter;
  }

 private:
  // Mathf.Approximately(a, 0): |a| < max(1e-6 * max(|a|, 0), 8 * float epsilon),
  // float epsilon being Unity's Mathf.Epsilon, the smallest subnormal.
  static bool approximately_zero(float a) {
    const float eps8 = 8.0f * 1.40129846e-45f;
    const float rel = 1e-6f * std::fabs(a);
    return std::fabs(a) < (rel > eps8 ? rel : eps8);
  }
};

}  // namespace seed_peer
