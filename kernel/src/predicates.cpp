#include "shatter/kernel/predicates.hpp"

#include <gmpxx.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <cmath>

#include "shatter/kernel/fp_environment.hpp"

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

// The filter: the sign of n·p + d when the double evaluation proves it, else zero
// (undecided). Recursive summation of four terms, three of them rounded products,
// errs by at most gamma_4 * sum|term| (Higham, "Accuracy and Stability", eq. 3.5),
// with gamma_4 = 4u / (1 - 4u). The computed magnitude underestimates the true one
// by at most a factor (1 - gamma_4), and the product below rounds once more; 6u
// covers all three. NaN or overflow fails the comparison: undecided.
int filtered_sign(const Vec3& n, const Vec3& p, double offset) {
  const double value = n.x * p.x + n.y * p.y + n.z * p.z + offset;
  const double magnitude = std::fabs(n.x * p.x) + std::fabs(n.y * p.y) + std::fabs(n.z * p.z) + std::fabs(offset);
  const double bound = magnitude * (6 * unit_roundoff);
  if (magnitude >= smallest_safe_magnitude && std::fabs(value) > bound) return value > 0 ? 1 : -1;
  return 0;
}

// Below these no product or sum of the filter can overflow (2^500 * 2^500 * 3 +
// 2^1000 < 2^1023).
constexpr double largest_safe_factor = 0x1p500;
constexpr double largest_safe_offset = 0x1p1000;

}  // namespace

PredicateCounters& predicate_counters() {
  thread_local PredicateCounters counters;
  return counters;
}

Sign side_of_plane(const Plane& plane, Vec3 p) {
  PredicateCounters& counters = predicate_counters();
  ++counters.side_of_plane_calls;
  const Vec3 n = plane.normal;
  int sign = 0;
  if (std::fmax(std::fmax(std::fabs(n.x), std::fabs(n.y)), std::fabs(n.z)) < largest_safe_factor &&
      std::fmax(std::fmax(std::fabs(p.x), std::fabs(p.y)), std::fabs(p.z)) < largest_safe_factor &&
      std::fabs(plane.offset) < largest_safe_offset) {
    sign = filtered_sign(n, p, plane.offset);
  } else {
    // Here a product may overflow to infinity by design (the filter then defers
    // to the exact path): held, so a program that traps overflow is not stopped.
    const HeldFloatingPointEnvironment held;
    sign = filtered_sign(n, p, plane.offset);
  }
  if (sign != 0) return sign > 0 ? Sign::positive : Sign::negative;
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
