#pragma once
// Exact measures of the plane kernel's points and faces, computed apart from the
// kernel (implicit.cpp): planes from their defining doubles, points from their
// definitions, vector areas by the shoelace formula. The tests of the kernel's
// parts (tests/kernel, slicer, triangulate, meshtree) judge its output by these.
// Header-only.
//
// Two representations, for speed. Homogeneous coordinates (x, y, z, w) are
// polynomials in the input doubles (implicit.hpp's file comment gives them), so
// ring operations on CGAL::Mpzf (a binary floating-point integer) evaluate them
// exactly without the rationals' gcd at every step: sides of planes, turns,
// collinearity. Areas and volumes need the points themselves, as GMP rationals
// x / w; implicit_reference.hpp's Cramer's rule gives the same points another
// way, and the tests compare the two on a sample.

#include <CGAL/Mpzf.h>

#include <gmpxx.h>

#include <array>
#include <span>
#include <vector>

#include "shatter/kernel/solid.hpp"
#include "support/implicit_reference.hpp"

namespace shatter::test {

/// A plane's coefficients, exactly.
struct Z4 {
  CGAL::Mpzf a, b, c, d;
};
/// A point (x, y, z) / w, exactly.
struct H4 {
  CGAL::Mpzf x, y, z, w;
};

inline Z4 plane_z(const PlaneSet& set, PlaneRef plane) {
  using CGAL::Mpzf;
  if (plane.is_cut()) {
    const Plane& p = set.cuts[plane.index()];
    return {Mpzf(p.normal.x), Mpzf(p.normal.y), Mpzf(p.normal.z), Mpzf(p.offset)};
  }
  const auto& idx = set.inputs[plane.index()];
  const Vec3 &p0 = set.points[idx[0]], &p1 = set.points[idx[1]], &p2 = set.points[idx[2]];
  const Mpzf ux = Mpzf(p1.x) - Mpzf(p0.x), uy = Mpzf(p1.y) - Mpzf(p0.y), uz = Mpzf(p1.z) - Mpzf(p0.z);
  const Mpzf vx = Mpzf(p2.x) - Mpzf(p0.x), vy = Mpzf(p2.y) - Mpzf(p0.y), vz = Mpzf(p2.z) - Mpzf(p0.z);
  Z4 h{uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx, Mpzf(0)};
  h.d = -(h.a * Mpzf(p0.x) + h.b * Mpzf(p0.y) + h.c * Mpzf(p0.z));
  return h;
}

/// The homogeneous coordinates of a definition: (p, 1); (p P(q) - q P(p),
/// P(q) - P(p)) for the line through p and q met by P; and for three planes
/// (-(d_A n_B x n_C + d_B n_C x n_A + d_C n_A x n_B), det(n_A, n_B, n_C)).
inline H4 homogeneous(const PlaneSet& set, const PointDef& def) {
  using CGAL::Mpzf;
  if (def.kind == PointKind::input) {
    const Vec3& p = set.points[def.a];
    return {Mpzf(p.x), Mpzf(p.y), Mpzf(p.z), Mpzf(1)};
  }
  if (def.kind == PointKind::segment_plane) {
    const Z4 h = plane_z(set, def.planes[0]);
    const Vec3 &p = set.points[def.a], &q = set.points[def.b];
    const Mpzf px(p.x), py(p.y), pz(p.z), qx(q.x), qy(q.y), qz(q.z);
    const Mpzf at_p = h.a * px + h.b * py + h.c * pz + h.d, at_q = h.a * qx + h.b * qy + h.c * qz + h.d;
    return {px * at_q - qx * at_p, py * at_q - qy * at_p, pz * at_q - qz * at_p, at_q - at_p};
  }
  const Z4 a = plane_z(set, def.planes[0]), b = plane_z(set, def.planes[1]), c = plane_z(set, def.planes[2]);
  const auto cross = [](const Z4& u, const Z4& v) {
    return std::array<Mpzf, 3>{u.b * v.c - u.c * v.b, u.c * v.a - u.a * v.c, u.a * v.b - u.b * v.a};
  };
  const std::array<Mpzf, 3> bc = cross(b, c), ca = cross(c, a), ab = cross(a, b);
  H4 point{Mpzf(0), Mpzf(0), Mpzf(0), a.a * bc[0] + a.b * bc[1] + a.c * bc[2]};
  point.x = -(a.d * bc[0] + b.d * ca[0] + c.d * ab[0]);
  point.y = -(a.d * bc[1] + b.d * ca[1] + c.d * ab[1]);
  point.z = -(a.d * bc[2] + b.d * ca[2] + c.d * ab[2]);
  return point;
}

/// The exact sign of n·x + d at a point given homogeneously.
inline int side_of(const Z4& plane, const H4& p) {
  return static_cast<int>(CGAL::sign(plane.a * p.x + plane.b * p.y + plane.c * p.z + plane.d * p.w)) *
         static_cast<int>(CGAL::sign(p.w));
}

/// The turn a -> b -> c of points given homogeneously, seen from the side the
/// plane's normal points to (`reversed`: from the other side): the sign of
/// n · ((b - a) x (c - b)) = n · (a x b + b x c + c x a), times w_a w_b w_c to
/// clear the denominators.
inline int turn(const Z4& plane, bool reversed, const H4& a, const H4& b, const H4& c) {
  const auto cross_dot = [&](const H4& u, const H4& v) {
    return plane.a * (u.y * v.z - u.z * v.y) + plane.b * (u.z * v.x - u.x * v.z) + plane.c * (u.x * v.y - u.y * v.x);
  };
  const CGAL::Mpzf value = cross_dot(a, b) * c.w + cross_dot(b, c) * a.w + cross_dot(c, a) * b.w;
  const int sign = static_cast<int>(CGAL::sign(value)) * static_cast<int>(CGAL::sign(a.w)) *
                   static_cast<int>(CGAL::sign(b.w)) * static_cast<int>(CGAL::sign(c.w));
  return reversed ? -sign : sign;
}

/// Whether a point given homogeneously lies on the line through input points a, b.
inline bool on_line(const Vec3& a, const Vec3& b, const H4& p) {
  using CGAL::Mpzf;
  const Mpzf ax(a.x), ay(a.y), az(a.z);
  const Mpzf ux = Mpzf(b.x) - ax, uy = Mpzf(b.y) - ay, uz = Mpzf(b.z) - az;
  const Mpzf vx = p.x - ax * p.w, vy = p.y - ay * p.w, vz = p.z - az * p.w;  // (p - a) w
  return CGAL::sign(uy * vz - uz * vy) == CGAL::ZERO && CGAL::sign(uz * vx - ux * vz) == CGAL::ZERO &&
         CGAL::sign(ux * vy - uy * vx) == CGAL::ZERO;
}

/// The point as rationals.
inline Q3 rational(const H4& h) {
  const mpq_class w = static_cast<mpq_class>(h.w);
  return {static_cast<mpq_class>(h.x) / w, static_cast<mpq_class>(h.y) / w, static_cast<mpq_class>(h.z) / w};
}

/// Every definition's homogeneous coordinates.
inline std::vector<H4> homogeneous_points(const PlaneSet& set, std::span<const PointDef> defs) {
  std::vector<H4> points;
  points.reserve(defs.size());
  for (const PointDef& def : defs) points.push_back(homogeneous(set, def));
  return points;
}

/// Every definition's exact point.
inline std::vector<Q3> exact_points(const PlaneSet& set, std::span<const PointDef> defs) {
  std::vector<Q3> points;
  points.reserve(defs.size());
  for (const PointDef& def : defs) points.push_back(rational(homogeneous(set, def)));
  return points;
}

inline Q3 addq(const Q3& a, const Q3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Q3 negq(const Q3& a) { return {-a.x, -a.y, -a.z}; }
inline bool is_zero(const Q3& a) { return a.x == 0 && a.y == 0 && a.z == 0; }
inline bool equal(const Q3& a, const Q3& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

/// Twice the vector area of the closed polygon through `loop` (indices into
/// `points`): sum of p_i x p_(i+1). Its direction is the polygon's normal by the
/// right-hand rule; for a polygon with holes, add its loops'.
inline Q3 twice_vector_area(const std::vector<Q3>& points, std::span<const VertexIndex> loop) {
  Q3 sum{0, 0, 0};
  for (std::size_t i = 0; i < loop.size(); ++i) sum = addq(sum, crossq(points[loop[i]], points[loop[(i + 1) % loop.size()]]));
  return sum;
}

/// The coordinate of a plane's normal with the largest magnitude.
inline int dominant_axis(const Z4& plane) {
  const auto magnitude = [](const CGAL::Mpzf& x) { return CGAL::sign(x) == CGAL::NEGATIVE ? -x : x; };
  const CGAL::Mpzf m[3] = {magnitude(plane.a), magnitude(plane.b), magnitude(plane.c)};
  int axis = 0;
  for (int a = 1; a < 3; ++a) {
    if (m[a] > m[axis]) axis = a;
  }
  return axis;
}

/// Component `axis` of twice_vector_area: for polygons on one plane, whose
/// vector areas are all multiples of its normal, it decides equality and
/// orientation alone when the normal's component there is not zero, at a third
/// of the cost.
inline mpq_class cross_along(const Q3& a, const Q3& b, int axis) {
  const auto u = [axis](const Q3& p) -> const mpq_class& { return axis == 0 ? p.y : axis == 1 ? p.z : p.x; };
  const auto v = [axis](const Q3& p) -> const mpq_class& { return axis == 0 ? p.z : axis == 1 ? p.x : p.y; };
  return u(a) * v(b) - v(a) * u(b);
}
inline mpq_class twice_area_along(const std::vector<Q3>& points, std::span<const VertexIndex> loop, int axis) {
  mpq_class sum = 0;
  for (std::size_t i = 0; i < loop.size(); ++i) sum += cross_along(points[loop[i]], points[loop[(i + 1) % loop.size()]], axis);
  return sum;
}

/// The vertices of loop `l` of a face set's (or solid's) loops, in order.
inline std::vector<VertexIndex> loop_vertices(std::span<const SolidLoop> loops, std::span<const SolidCorner> corners,
                                              std::uint32_t l) {
  std::vector<VertexIndex> vertices;
  const SolidLoop& loop = loops[l];
  for (std::uint32_t i = 0; i < loop.corner_count; ++i) vertices.push_back(corners[loop.first_corner + i].vertex);
  return vertices;
}

/// Twice the vector area of a face (its loops, holes counted negative).
inline Q3 twice_face_area(const std::vector<Q3>& points, std::span<const SolidLoop> loops,
                          std::span<const SolidCorner> corners, const SolidFace& face) {
  Q3 sum{0, 0, 0};
  for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
    sum = addq(sum, twice_vector_area(points, loop_vertices(loops, corners, l)));
  }
  return sum;
}

/// The normal of a plane of the set, exactly (the cut's own coefficients, or
/// (p1 - p0) x (p2 - p0) of an input plane).
inline Q3 plane_normal(const PlaneSet& set, PlaneRef plane) {
  const Q4 h = reference_plane(set, plane);
  return {h.a, h.b, h.c};
}

/// The face's outward normal (the plane's, negated when the face is reversed).
inline Q3 outward_normal(const PlaneSet& set, const SolidFace& face) {
  const Q3 n = plane_normal(set, face.plane);
  return face.reversed ? negq(n) : n;
}

/// The exact sign of n·p + d for an exact point.
inline int side_of(const Q4& plane, const Q3& p) { return sgn(mpq_class(plane.a * p.x + plane.b * p.y + plane.c * p.z + plane.d)); }

}  // namespace shatter::test
