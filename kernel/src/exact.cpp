#include "shatter/kernel/exact.hpp"

#include <gmpxx.h>
#include <algorithm>
#include <mpfr.h>


namespace shatter {
namespace {

using FT = ExactKernel::FT;

FT plane_value(const Plane& plane, const ExactPoint& p) {
  return FT(plane.normal.x) * p.x() + FT(plane.normal.y) * p.y() + FT(plane.normal.z) * p.z() +
         FT(plane.offset);
}

// The exact crossing of segment (a, b) with the plane, built as one lazy CGAL
// construction so its exact value is computed only if a predicate needs it.
ExactPoint exact_plane_segment_crossing(const Plane& plane, const ExactPoint& a, const ExactPoint& b) {
  const ExactKernel::Plane_3 cgal_plane(plane.normal.x, plane.normal.y, plane.normal.z, plane.offset);
  const auto result = CGAL::intersection(cgal_plane, ExactKernel::Segment_3(a, b));
  // The precondition (strictly opposite sides) makes the intersection one point.
  return *boost::get<ExactPoint>(&*result);
}

// Epeck's exact number is gmpxx's mpq_class when CGAL is built with gmpxx (as the
// CGAL::CGAL target is here) and boost::multiprecision's GMP rational otherwise;
// both wrap an mpq_t.
mpq_srcptr raw_rational(const mpq_class& q) { return q.get_mpq_t(); }
template <class Rational>
auto raw_rational(const Rational& q) -> decltype(q.backend().data()) {
  return q.backend().data();
}

}  // namespace

double round_to_double(const FT& value) {
  // MPFR rounds the rational correctly; a plain double cast would truncate.
  mpfr_t rounded;
  mpfr_init2(rounded, 53);
  mpfr_set_q(rounded, raw_rational(CGAL::exact(value)), MPFR_RNDN);
  const double result = mpfr_get_d(rounded, MPFR_RNDN);
  mpfr_clear(rounded);
  return result;
}

Vec3 to_vec3(const ExactPoint& p) {
  return {round_to_double(p.x()), round_to_double(p.y()), round_to_double(p.z())};
}

ExactMesh to_exact(const Mesh& mesh) {
  ExactMesh exact;
  exact.positions.reserve(mesh.positions.size());
  for (const Vec3& p : mesh.positions) exact.positions.emplace_back(p.x, p.y, p.z);
  exact.triangles = mesh.triangles;
  exact.surfaces = mesh.surfaces;
  exact.corners = mesh.corners;
  return exact;
}

Mesh to_fast(const ExactMesh& mesh) {
  Mesh fast;
  fast.positions.reserve(mesh.positions.size());
  for (const ExactPoint& p : mesh.positions) fast.positions.push_back(to_vec3(p));
  fast.triangles = mesh.triangles;
  fast.surfaces = mesh.surfaces;
  fast.corners = mesh.corners;
  return fast;
}

Sign side_of_plane(const Plane& plane, const ExactPoint& p) {
  // CGAL::sign on a lazy number decides on its interval first and computes the
  // exact rational only when the interval straddles zero.
  const CGAL::Sign s = CGAL::sign(plane_value(plane, p));
  return s == CGAL::NEGATIVE ? Sign::negative : s == CGAL::POSITIVE ? Sign::positive : Sign::zero;
}

CrossingVec3 crossing_point(const Plane& plane, const Vec3& a, const Vec3& b) {
  const double value_a = dot(plane.normal, a) + plane.offset;
  const double value_b = dot(plane.normal, b) + plane.offset;
  // Both values are non-zero with opposite signs in exact arithmetic; rounding can
  // push a tiny one to zero or across, so clamp t into [0, 1] (the point then
  // stays on the segment's bounding box, never outside it). The quotient is taken
  // only where it lies in [-1, 1]: past that it clamps to an end, and dividing
  // there could overflow, or make a NaN of 0 / 0 (both values rounded to zero).
  const double denominator = value_a - value_b;
  double t = 0;
  if (std::fabs(value_a) <= std::fabs(denominator) && denominator != 0) {
    t = value_a / denominator;
    if (!(t >= 0)) t = 0;
    if (t > 1) t = 1;
  } else if (value_a != 0) {
    // The end the quotient clamps to, by its sign (x / +0 is +-infinity by x's).
    t = (value_a > 0) == !(denominator < 0) ? 1 : 0;
  }
  return {a + (b - a) * t, t};
}

CrossingExact crossing_point(const Plane& plane, const ExactPoint& a, const ExactPoint& b) {
  ExactPoint point = exact_plane_segment_crossing(plane, a, b);
  // t only interpolates attributes, so the interval approximations serve; rounding
  // exactly here would force every lazy crossing to be evaluated in rationals.
  auto approx = [](const ExactPoint& p) {
    return Vec3{CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z())};
  };
  const Vec3 approx_a = approx(a), ab = approx(b) - approx_a;
  const double length_squared = dot(ab, ab);
  const double t = length_squared > 0 ? dot(approx(point) - approx_a, ab) / length_squared : 0.5;
  return {std::move(point), std::clamp(t, 0.0, 1.0)};
}

ExactPoint exact_crossing_point(const Plane& plane, const Vec3& a, const Vec3& b) {
  return exact_plane_segment_crossing(plane, ExactPoint(a.x, a.y, a.z), ExactPoint(b.x, b.y, b.z));
}

}  // namespace shatter
