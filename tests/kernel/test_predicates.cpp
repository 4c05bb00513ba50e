// The exact side-of-plane predicate against a GMP rational reference, on
// adversarial queries: points on or within a few ulps of the plane.

#include <catch2/catch.hpp>

#include <gmpxx.h>

#include <cmath>

#include "shatter/generators/random.hpp"
#include "shatter/kernel/exact.hpp"
#include "shatter/kernel/predicates.hpp"

using namespace shatter;
using namespace shatter::test;

namespace {

Sign reference_side(const Plane& plane, Vec3 p) {
  const mpq_class v = mpq_class(plane.normal.x) * p.x + mpq_class(plane.normal.y) * p.y +
                      mpq_class(plane.normal.z) * p.z + mpq_class(plane.offset);
  return sgn(v) < 0 ? Sign::negative : sgn(v) > 0 ? Sign::positive : Sign::zero;
}

double ulps_away(double x, int k) {
  for (int i = 0; i < std::abs(k); ++i) x = std::nextafter(x, k > 0 ? INFINITY : -INFINITY);
  return x;
}

}  // namespace

TEST_CASE("side_of_plane agrees with exact rationals within a few ulps of the plane") {
  Random random(2026);
  predicate_counters() = {};
  std::size_t queries = 0, on_plane = 0;
  for (int i = 0; i < 20000; ++i) {
    // Scales from 1e-9 to 1e9, centres far from the origin.
    const double scale = std::pow(10.0, random.uniform(-9, 9));
    const Vec3 centre = random.direction() * (scale * random.uniform(0, 1e3));
    const Vec3 n = random.direction() * std::pow(2.0, random.uniform(-20, 20));
    const Vec3 p = centre + random.direction() * scale;
    const Plane plane{n, -dot(n, p)};  // through p up to rounding of d
    for (int k = -3; k <= 3; ++k) {
      const Vec3 q{ulps_away(p.x, k), ulps_away(p.y, -k), ulps_away(p.z, k / 2)};
      const Sign expected = reference_side(plane, q);
      REQUIRE(side_of_plane(plane, q) == expected);
      on_plane += expected == Sign::zero;
      ++queries;
    }
  }
  // Exactly representable planes through lattice points: exact zeros.
  for (int i = 0; i < 20000; ++i) {
    const Vec3 n{double(random.index(7)) - 3, double(random.index(7)) - 3, double(random.index(5)) + 1};
    const Vec3 p{std::ldexp(double(random.index(1 << 20)), -10), std::ldexp(double(random.index(1 << 20)), -10),
                 std::ldexp(double(random.index(1 << 20)), -10)};
    const Plane plane{n, -(n.x * p.x + n.y * p.y + n.z * p.z)};  // exact: small integers times dyadics
    REQUIRE(side_of_plane(plane, p) == Sign::zero);
    REQUIRE(side_of_plane(plane, Vec3{p.x, p.y, ulps_away(p.z, 1)}) == Sign::positive);
    REQUIRE(side_of_plane(plane, Vec3{p.x, p.y, ulps_away(p.z, -1)}) == Sign::negative);
    queries += 3;
    ++on_plane;
  }
  const PredicateCounters& counters = predicate_counters();
  CHECK(counters.side_of_plane_calls == queries);
  // The filter must decide most of these near-plane queries without GMP, yet
  // every exact zero has to reach the exact path.
  CHECK(counters.side_of_plane_exact >= on_plane);
  CHECK(counters.side_of_plane_exact < counters.side_of_plane_calls);
}

TEST_CASE("side_of_plane is exact where products underflow or overflow") {
  const Plane tiny{{1e-200, 0, 0}, 0};
  CHECK(side_of_plane(tiny, Vec3{1e-200, 0, 0}) == Sign::positive);  // product 1e-400 underflows in double
  CHECK(side_of_plane(tiny, Vec3{-1e-200, 0, 0}) == Sign::negative);
  const Plane huge{{1e200, 1e200, 0}, 0};
  CHECK(side_of_plane(huge, Vec3{1e200, -1e200, 0}) == Sign::zero);  // inf - inf in double
  CHECK(side_of_plane(huge, Vec3{1e200, std::nextafter(-1e200, 0.0), 0}) == Sign::positive);
}

TEST_CASE("exact points: side and rounding") {
  const Plane plane{{1, 0, 0}, -0.5};
  const ExactPoint a(0, 0, 0), b(1, 3, 0);
  const CrossingExact c = crossing_point(plane, a, b);
  CHECK(side_of_plane(plane, c.point) == Sign::zero);
  CHECK(to_vec3(c.point) == Vec3{0.5, 1.5, 0});
  // 1/3 rounds to the nearest double, not towards zero.
  const ExactPoint third(ExactKernel::FT(1) / 3, 0, 0);
  CHECK(to_vec3(third).x == 1.0 / 3.0);
}
