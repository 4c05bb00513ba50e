#pragma once
// Projection of points in (or near) a plane to 2D, by dropping the coordinate of
// the plane normal's largest component. Dropping a coordinate is exact, and the
// two kept axes are ordered so that counter-clockwise seen from +n stays
// counter-clockwise in 2D: orientation tests in the projection are exact
// orientation tests in the plane.
//
// Not installed (kernel/internal/): its users are the library's own sources
// (caps, bonds, the rounding) and the tests. The projection of CGAL's exact
// points is projection_exact.hpp's, apart so that a source projecting doubles
// does not parse CGAL's Epeck headers.

#include <cmath>

#include "shatter/kernel/predicates.hpp"

namespace shatter {

/// An orthonormal basis (u, v) of a plane with u x v = n / |n|: cap UVs are
/// coordinates in it, and u is the caps' tangent. Rounded; it only places
/// attributes, never decides geometry.
struct PlaneBasis {
  Vec3 normal, u, v;

  explicit PlaneBasis(const Plane& plane) : normal(normalized(plane.normal)) {
    const Vec3 a{std::fabs(normal.x), std::fabs(normal.y), std::fabs(normal.z)};
    const Vec3 least = a.x <= a.y && a.x <= a.z ? Vec3{1, 0, 0} : a.y <= a.z ? Vec3{0, 1, 0} : Vec3{0, 0, 1};
    u = normalized(cross(least, normal));
    v = cross(normal, u);
  }
};

struct PlaneProjection {
  int u_axis = 0;
  int v_axis = 1;

  /// The projection for a plane with a non-zero normal.
  static PlaneProjection of(const Plane& plane) {
    const double ax = std::fabs(plane.normal.x), ay = std::fabs(plane.normal.y),
                 az = std::fabs(plane.normal.z);
    // (u, v, dropped) is a right-handed cyclic permutation of the axes when the
    // dropped component is positive; a negative one swaps u and v.
    if (az >= ax && az >= ay) return plane.normal.z > 0 ? PlaneProjection{0, 1} : PlaneProjection{1, 0};
    if (ax >= ay) return plane.normal.x > 0 ? PlaneProjection{1, 2} : PlaneProjection{2, 1};
    return plane.normal.y > 0 ? PlaneProjection{2, 0} : PlaneProjection{0, 2};
  }

  Vec2 operator()(const Vec3& p) const { return {p[u_axis], p[v_axis]}; }
};

/// Orientation of triangle (a, b, c) seen from the +n side of the projection's
/// plane: positive when counter-clockwise. Exact.
inline Sign orientation_in_projection(const PlaneProjection& proj, const Vec3& a, const Vec3& b,
                                      const Vec3& c) {
  return orient2d(proj(a), proj(b), proj(c));
}

}  // namespace shatter
