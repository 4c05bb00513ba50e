#include "shatter/kernel/predicates.hpp"

#include <gmpxx.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <cmath>

namespace shatter {
namespace {

// Unit roundoff of IEEE double (round to nearest).
constexpr double unit_roundoff = 0x1p-53;

// Below this magnitude products may be subnormal and the relative error model of
// the filter no longer holds; such queries go to the exact path.
constexpr double smallest_safe_magnitude = 0x1p-960;

Sign sign_of(const mpq_class& value) {
  const int s = sgn(value);
  return s < 0 ? Sign::negative : s > 0 ? Sign::positive : Sign::zero;
}

Sign side_of_plane_exact(const Plane& plane, Vec3 p) {
  // mpq_class from a double is exact, so this is the real value of n·p + d.
  const mpq_class value = mpq_class(plane.normal.x) * mpq_class(p.x) +
                          mpq_class(plane.normal.y) * mpq_class(p.y) +
                          mpq_class(plane.normal.z) * mpq_class(p.z) + mpq_class(plane.offset);
  return sign_of(value);
}

}  // namespace

PredicateCounters& predicate_counters() {
  thread_local PredicateCounters counters;
  return counters;
}

Sign side_of_plane(const Plane& plane, Vec3 p) {
  PredicateCounters& counters = predicate_counters();
  ++counters.side_of_plane_calls;
  const Vec3 n = plane.normal;
  const double value = n.x * p.x + n.y * p.y + n.z * p.z + plane.offset;
  const double magnitude =
      std::fabs(n.x * p.x) + std::fabs(n.y * p.y) + std::fabs(n.z * p.z) + std::fabs(plane.offset);
  // Recursive summation of four terms, three of them rounded products, errs by at
  // most gamma_4 * sum|term| (Higham, "Accuracy and Stability", eq. 3.5), with
  // gamma_4 = 4u / (1 - 4u). The computed magnitude underestimates the true one by
  // at most a factor (1 - gamma_4), and the product below rounds once more; 6u
  // covers all three. NaN or overflow fails the comparison and goes exact.
  const double bound = magnitude * (6 * unit_roundoff);
  if (magnitude >= smallest_safe_magnitude && std::fabs(value) > bound) {
    return value > 0 ? Sign::positive : Sign::negative;
  }
  ++counters.side_of_plane_exact;
  return side_of_plane_exact(plane, p);
}

Sign orient2d(Vec2 a, Vec2 b, Vec2 c) {
  using Point = CGAL::Epick::Point_2;
  // CGAL's Epick orientation is exact for double input (static filter, then
  // interval arithmetic, then exact arithmetic).
  const CGAL::Orientation o = CGAL::orientation(Point(a.x, a.y), Point(b.x, b.y), Point(c.x, c.y));
  return o == CGAL::LEFT_TURN ? Sign::positive : o == CGAL::RIGHT_TURN ? Sign::negative : Sign::zero;
}

}  // namespace shatter
