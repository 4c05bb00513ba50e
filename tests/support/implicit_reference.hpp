#pragma once
// An exact evaluation of the plane kernel's points and planes, written apart
// from kernel/src/implicit.cpp (which evaluates over CGAL::Mpzf): GMP rationals,
// straight from the definitions in kernel/implicit.hpp. The kernel's predicate
// tests compare against it, and the split's tests use it to find the points on a
// cut plane and their exact coordinates without trusting the kernel under test.

#include <catch2/catch.hpp>

#include <gmpxx.h>

#include "shatter/kernel/implicit.hpp"
#include "shatter/kernel/vec.hpp"

namespace shatter::test {

struct Q3 {
  mpq_class x, y, z;
};
struct Q4 {
  mpq_class a, b, c, d;
};

inline Q3 q3(const Vec3& p) { return {mpq_class(p.x), mpq_class(p.y), mpq_class(p.z)}; }
inline Q3 sub(const Q3& a, const Q3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Q3 crossq(const Q3& a, const Q3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline mpq_class dotq(const Q3& a, const Q3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

inline Q4 reference_plane(const PlaneSet& set, PlaneRef plane) {
  if (plane.is_cut()) {
    const Plane& p = set.cuts[plane.index()];
    return {mpq_class(p.normal.x), mpq_class(p.normal.y), mpq_class(p.normal.z), mpq_class(p.offset)};
  }
  const auto& idx = set.inputs[plane.index()];
  const Q3 p0 = q3(set.points[idx[0]]), p1 = q3(set.points[idx[1]]), p2 = q3(set.points[idx[2]]);
  const Q3 n = crossq(sub(p1, p0), sub(p2, p0));
  return {n.x, n.y, n.z, -dotq(n, p0)};
}

// The point's rational coordinates.
inline Q3 reference_point(const PlaneSet& set, const PointDef& def) {
  if (def.kind == PointKind::input) return q3(set.points[def.a]);
  if (def.kind == PointKind::segment_plane) {
    const Q3 p = q3(set.points[def.a]), q = q3(set.points[def.b]);
    const Q4 h = reference_plane(set, def.planes[0]);
    const Q3 n{h.a, h.b, h.c};
    const mpq_class at_p = dotq(n, p) + h.d, at_q = dotq(n, q) + h.d;
    const mpq_class t = at_p / (at_p - at_q);  // p + t (q - p)
    return {p.x + t * (q.x - p.x), p.y + t * (q.y - p.y), p.z + t * (q.z - p.z)};
  }
  // Three planes: Cramer's rule.
  Q4 h[3];
  for (int k = 0; k < 3; ++k) h[k] = reference_plane(set, def.planes[k]);
  auto det3 = [](const mpq_class m[3][3]) -> mpq_class {
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  };
  mpq_class a[3][3] = {{h[0].a, h[0].b, h[0].c}, {h[1].a, h[1].b, h[1].c}, {h[2].a, h[2].b, h[2].c}};
  const mpq_class rhs[3] = {-h[0].d, -h[1].d, -h[2].d};
  const mpq_class det = det3(a);
  REQUIRE(det != 0);
  Q3 x;
  mpq_class* out[3] = {&x.x, &x.y, &x.z};
  for (int col = 0; col < 3; ++col) {
    mpq_class m[3][3];
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) m[r][c] = c == col ? rhs[r] : a[r][c];
    }
    *out[col] = det3(m) / det;
  }
  return x;
}

inline Sign sign_of(const mpq_class& v) { return sgn(v) < 0 ? Sign::negative : sgn(v) > 0 ? Sign::positive : Sign::zero; }

inline Sign reference_side(const PlaneSet& set, PlaneRef plane, const PointDef& def) {
  const Q4 h = reference_plane(set, plane);
  const Q3 p = reference_point(set, def);
  return sign_of(h.a * p.x + h.b * p.y + h.c * p.z + h.d);
}

}  // namespace shatter::test
