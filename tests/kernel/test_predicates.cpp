// The exact side-of-plane predicate against a GMP rational reference, on
// adversarial queries: points on or within a few ulps of the plane.

#include <catch2/catch.hpp>

#include <gmpxx.h>

#include <cmath>
#include <optional>

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

// --- orient3d -----------------------------------------------------------------

namespace {

// det[b - a, c - a, d - a] in rationals, exact for any finite double.
Sign reference_orient3d(Vec3 a, Vec3 b, Vec3 c, Vec3 d) {
  const mpq_class m[3][3] = {{mpq_class(b.x) - a.x, mpq_class(b.y) - a.y, mpq_class(b.z) - a.z},
                             {mpq_class(c.x) - a.x, mpq_class(c.y) - a.y, mpq_class(c.z) - a.z},
                             {mpq_class(d.x) - a.x, mpq_class(d.y) - a.y, mpq_class(d.z) - a.z}};
  const mpq_class det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                        m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                        m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  return sgn(det) < 0 ? Sign::negative : sgn(det) > 0 ? Sign::positive : Sign::zero;
}

// orient3d against the reference, and against itself with the points permuted
// (an odd permutation flips the sign): the filter and the exact stage see the
// differences taken from another point then.
void require_orient3d(Vec3 a, Vec3 b, Vec3 c, Vec3 d) {
  const Sign expected = reference_orient3d(a, b, c, d);
  INFO("a " << a.x << ' ' << a.y << ' ' << a.z << ", b " << b.x << ' ' << b.y << ' ' << b.z << ", c " << c.x << ' '
            << c.y << ' ' << c.z << ", d " << d.x << ' ' << d.y << ' ' << d.z);
  REQUIRE(orient3d(a, b, c, d) == expected);
  REQUIRE(orient3d(b, a, c, d) == flip(expected));
  REQUIRE(orient3d(d, b, c, a) == flip(expected));
  REQUIRE(orient3d(b, c, d, a) == flip(expected));
  // The filter alone: right whenever it answers, and silent on coplanar points.
  const std::optional<Sign> quick = orient3d_if_clear(a, b, c, d);
  if (quick) REQUIRE(*quick == expected);
  if (expected == Sign::zero) REQUIRE_FALSE(quick.has_value());
}

Vec3 ulps_away(Vec3 p, int kx, int ky, int kz) { return {ulps_away(p.x, kx), ulps_away(p.y, ky), ulps_away(p.z, kz)}; }

}  // namespace

TEST_CASE("orient3d agrees with exact rationals on random, nearly coplanar and coplanar points") {
  predicate_counters() = {};
  std::size_t queries = 0, coplanar = 0;
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    Random random(seed);
    for (int i = 0; i < 500; ++i) {
      // Pieces from 1e-9 to 1e9 across, often far from the origin compared with their size.
      const double scale = std::pow(10.0, random.uniform(-9, 9));
      const Vec3 centre = random.direction() * (scale * random.uniform(0, 1e4) * double(random.index(2)));
      const auto point = [&] { return centre + random.direction() * (scale * random.uniform()); };
      // Random: almost never coplanar, decided by the filter.
      require_orient3d(point(), point(), point(), point());
      // Nearly coplanar: points of a plane, rounded (as cut caps are).
      const Vec3 o = point(), u = random.direction() * scale, v = random.direction() * scale;
      const auto on_plane = [&] { return o + u * random.uniform(-1, 1) + v * random.uniform(-1, 1); };
      const Vec3 a = on_plane(), b = on_plane(), c = on_plane(), d = on_plane();
      require_orient3d(a, b, c, d);
      // ... and moved by an ulp or two.
      require_orient3d(a, b, c, ulps_away(d, int(random.index(5)) - 2, int(random.index(5)) - 2, 1));
      // Exactly coplanar: z = (p x + q y) / 8 + r with small integers p, q and
      // dyadic x, y, all exact in double, at every scale.
      const double p = double(random.index(9)) - 4, q = double(random.index(9)) - 4;
      const double step = std::ldexp(1.0, int(random.index(80)) - 40), r = std::ldexp(double(random.index(1 << 20)), -12);
      const auto exact = [&] {
        const double x = step * double(random.index(1 << 20)), y = step * double(random.index(1 << 20));
        return Vec3{x, y, (p * x + q * y) / 8 + r * step};
      };
      const Vec3 e0 = exact(), e1 = exact(), e2 = exact(), e3 = exact();
      REQUIRE(reference_orient3d(e0, e1, e2, e3) == Sign::zero);  // the test's own premise
      require_orient3d(e0, e1, e2, e3);
      require_orient3d(e0, e1, e2, ulps_away(e3, 0, 0, int(random.index(2)) * 2 - 1));
      // Collinear and repeated points.
      require_orient3d(e0, e1, e0 + (e1 - e0) * 2, e2);
      require_orient3d(e0, e1, e1, e2);
      queries += 7;
      coplanar += 4;
    }
  }
  const PredicateCounters& counters = predicate_counters();
  CHECK(counters.orient3d_calls == 4 * queries);
  // Every exact zero needs the exact stage; in this range it is never GMP. The
  // exact zeros here have exactly subtracting coordinates, and the rounded
  // planes' points are not exactly coplanar, so the adaptive stages settle
  // nearly all of it without multiplying out the full expansion.
  CHECK(counters.orient3d_expansion >= 4 * coplanar);
  CHECK(counters.orient3d_gmp == 0);
  CHECK(counters.orient3d_full * 100 < counters.orient3d_expansion);
}

TEST_CASE("orient3d_if_clear answers points in general position, and only what the filter proves") {
  std::size_t answered = 0, queries = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    Random random(seed);
    for (int i = 0; i < 500; ++i) {
      const auto point = [&] { return random.direction() * random.uniform(0.1, 10); };
      const Vec3 a = point(), b = point(), c = point(), d = point();
      ++queries;
      if (const std::optional<Sign> quick = orient3d_if_clear(a, b, c, d)) {
        ++answered;
        REQUIRE(*quick == reference_orient3d(a, b, c, d));
      }
    }
  }
  CHECK(answered * 100 >= queries * 99);
  // Beyond its range (2^300) it never answers: orient3d takes GMP there.
  const double huge = std::ldexp(1.0, 400);
  CHECK_FALSE(orient3d_if_clear({huge, 0, 0}, {0, huge, 0}, {0, 0, huge}, {0, 0, 0}).has_value());
}

TEST_CASE("orient3d is exact at huge and tiny magnitudes, and says when it needs GMP") {
  Random random(20261203);
  // Inside [2^-300, 2^300) (or zero): filter and expansions, no GMP, even where
  // the filter's products underflow (coordinates near 2^-300 multiply to 2^-900,
  // and differences of an ulp to below the normal range).
  predicate_counters() = {};
  for (const int exponent : {-299, -250, 0, 250, 297}) {
    for (int i = 0; i < 2000; ++i) {
      // Coordinates 1 to 4 times 2^exponent, and an ulp off: still in the range.
      const double s = std::ldexp(1.0, exponent);
      const auto lattice = [&] {
        return Vec3{double(1 + random.index(4)), double(1 + random.index(4)), double(1 + random.index(4))} * s;
      };
      const Vec3 a = lattice(), b = lattice(), c = lattice(), d = lattice();
      require_orient3d(a, b, c, d);
      require_orient3d(a, b, c, ulps_away(d, 1, 0, int(random.index(3)) - 1));
    }
  }
  CHECK(predicate_counters().orient3d_gmp == 0);
  CHECK(predicate_counters().orient3d_expansion > 0);
  // Outside it: GMP, still exact. Subnormal coordinates; coordinates whose
  // differences or products overflow a double.
  predicate_counters() = {};
  for (const int exponent : {-1074, -1060, -1000, -500, -301, 300, 400, 1000, 1020}) {
    for (int i = 0; i < 500; ++i) {
      const double s = std::ldexp(1.0, exponent);
      const auto lattice = [&] { return Vec3{double(random.index(4)) - 1.5, double(random.index(4)), double(random.index(4))} * s; };
      const Vec3 a = lattice(), b = lattice(), c = lattice(), d = lattice();
      require_orient3d(a, b, c, d);
      // A point from the safe range among huge or tiny ones.
      require_orient3d(a, b, c, Vec3{1, 0.5, -0.25});
    }
  }
  CHECK(predicate_counters().orient3d_gmp > 0);
  // Cancellation the double evaluation gets wrong: 1e200 - 1e200 is fine, but
  // these products overflow to infinity and their difference is NaN.
  CHECK(orient3d({0, 0, 0}, {1e300, 0, 0}, {0, 1e300, 0}, {0, 0, 1e300}) == Sign::positive);
  CHECK(orient3d({0, 0, 0}, {1e300, 1e300, 0}, {-1e300, -1e300, 0}, {0, 0, 1e300}) == Sign::zero);
  CHECK(orient3d({0, 0, 0}, {1e-320, 0, 0}, {0, 1e-320, 0}, {0, 0, 1e-320}) == Sign::positive);
  CHECK(orient3d({0, 0, 0}, {1e-320, 0, 0}, {0, 1e-320, 0}, {0, 0, -1e-320}) == Sign::negative);
}
