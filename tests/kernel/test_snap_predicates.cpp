// The exact tests on rounded positions that snap rounding's repairs ask
// (shatter/kernel/snap_predicates.hpp), each against GMP rationals computed
// another way, on random inputs and on inputs at or a few ulps from the
// boundary of the answer.

#include <catch2/catch.hpp>

#include <gmpxx.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "shatter/generators/random.hpp"
#include "shatter/kernel/snap_predicates.hpp"

using namespace shatter;
using namespace shatter::test;

namespace {

double ulps_away(double x, int k) {
  for (int i = 0; i < std::abs(k); ++i) x = std::nextafter(x, k > 0 ? INFINITY : -INFINITY);
  return x;
}

Vec3 ulps_away(const Vec3& p, int kx, int ky, int kz) {
  return {ulps_away(p.x, kx), ulps_away(p.y, ky), ulps_away(p.z, kz)};
}

std::array<mpq_class, 3> exact(const Vec3& p) { return {mpq_class(p.x), mpq_class(p.y), mpq_class(p.z)}; }

mpq_class dot(const std::array<mpq_class, 3>& u, const std::array<mpq_class, 3>& w) {
  return u[0] * w[0] + u[1] * w[1] + u[2] * w[2];
}

std::array<mpq_class, 3> minus(const std::array<mpq_class, 3>& u, const std::array<mpq_class, 3>& w) {
  return {u[0] - w[0], u[1] - w[1], u[2] - w[2]};
}

mpq_class ratio(long numerator, long denominator) {
  mpq_class q(numerator, denominator);
  q.canonicalize();
  return q;
}

Sign sign_of(const mpq_class& x) { return sgn(x) < 0 ? Sign::negative : sgn(x) > 0 ? Sign::positive : Sign::zero; }

// A length of the kind round_solid asks with: an L1 rounding move (a sum of
// differences between doubles and a rational) times a power of two, or a
// rational no double holds.
mpq_class random_reach(Random& random, double magnitude) {
  const auto odd = static_cast<long>(2 * random.index(1 << 20) + 1);
  const mpq_class fraction = random.index(2) == 0 ? ratio(odd, 3L << 20) : ratio(odd, 1L << 21);
  return mpq_class(magnitude) * fraction;
}

}  // namespace

TEST_CASE("CoordinateReach: within the reach exactly, at the reach, ulps around it, huge and subnormal") {
  std::size_t within = 0, queries = 0;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    Random random(seed);
    for (int i = 0; i < 300; ++i) {
      const double magnitude = std::ldexp(1.0, int(random.index(2000)) - 1000);
      const double a = random.uniform(-1, 1) * magnitude;
      const mpq_class reach = random_reach(random, magnitude * 0x1p-40);
      // b at a + reach (rounded), and ulps either side; a reach equal to the
      // difference exactly, and the next rational below it.
      const double step = reach.get_d();
      for (int k = -3; k <= 3; ++k) {
        const double b = ulps_away(i % 2 == 0 ? a + step : a - step, k);
        if (!std::isfinite(b)) continue;
        const mpq_class gap = abs(mpq_class(b) - a);
        const mpq_class just_below = gap - gap / mpq_class(mpz_class(1) << 60);
        for (const mpq_class& r : {reach, gap, just_below}) {
          const bool expected = gap <= r;
          const CoordinateReach near(r);
          REQUIRE(near.within(a, b) == expected);
          REQUIRE(near.within(b, a) == expected);
          within += expected, ++queries;
        }
      }
    }
  }
  // Subnormal differences and reaches: the doubles' step there is 2^-1074.
  const double tiny = std::ldexp(1.0, -1074);
  for (int k = 0; k < 8; ++k) {
    for (int r = 0; r < 16; ++r) {
      const mpq_class reach = ratio(r, 4) / mpq_class(mpz_class(1) << 1074);
      REQUIRE(CoordinateReach(reach).within(k * tiny, 0.0) == (mpq_class(k) <= ratio(r, 4)));
      ++queries;
    }
  }
  CHECK(within > queries / 4);
  CHECK(queries - within > queries / 4);
}

TEST_CASE("SegmentReach: exactly the points within reach of the open segment, a reach below an ulp included") {
  // The reach goes down to 2^-55 of the scale while the coordinates reach 1e3
  // times it, so the doubles' cross product often errs far beyond the reach:
  // there the floating-point rejection must stand aside (it once did not).
  std::size_t accepted = 0, accepted_beyond_doubles = 0, queries = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    Random random(seed);
    for (int i = 0; i < 200; ++i) {
      const double scale = std::ldexp(1.0, int(random.index(120)) - 60);
      const Vec3 centre = random.direction() * (scale * random.uniform(0, 1e3));
      const Vec3 a = centre + random.direction() * scale, b = centre + random.direction() * scale;
      const mpq_class reach = random_reach(random, scale * std::ldexp(1.0, -int(random.index(56))));
      const double r = reach.get_d();
      // Points along the segment (and beyond its ends), then pushed off the
      // line by about the reach, and by a few ulps.
      const double t = random.uniform(-0.25, 1.25);
      const Vec3 on = a + (b - a) * t;
      const Vec3 off = on + random.direction() * (r * random.uniform(0.5, 1.5));
      for (const Vec3& p : {on, off, ulps_away(on, 1, -1, 2), a, b, ulps_away(a, 0, 1, 0)}) {
        const auto A = exact(a), B = exact(b), P = exact(p);
        const auto ab = minus(B, A), ap = minus(P, A);
        const mpq_class length2 = dot(ab, ab), along = dot(ab, ap);
        // Distance to the line by Pythagoras: |ap|^2 - along^2 / |ab|^2 <= reach^2.
        const bool between = sgn(along) > 0 && along < length2;
        const bool expected = between && dot(ap, ap) * length2 - along * along <= reach * reach * length2;
        const bool answer = SegmentReach(reach).within(a, b, p);
        INFO("a " << a.x << ' ' << a.y << ' ' << a.z << ", b " << b.x << ' ' << b.y << ' ' << b.z << ", p " << p.x
                  << ' ' << p.y << ' ' << p.z << ", reach " << reach.get_d());
        REQUIRE(answer == expected);
        double far = 0;
        for (int k = 0; k < 3; ++k) far = std::max({far, std::fabs(p[k] - a[k]), std::fabs(b[k] - a[k])});
        accepted_beyond_doubles += answer && far > r * 0x1p49;
        accepted += answer, ++queries;
      }
      // Points exactly on the line through a and b along (1, 3, 5), a near the
      // origin and p, b far out (parameters of 50 bits, so every coordinate is a
      // double): the differences round, each component its own way, and the
      // doubles' cross product is far from the exact zero beside a small reach.
      const auto fifty_bits = [](double x) {
        const int e = std::ilogb(x);
        return std::ldexp(std::round(std::ldexp(x, 49 - e)), e - 49);
      };
      const double s_near = fifty_bits(scale * random.uniform(1e-6, 1e-5)),
                   s_mid = fifty_bits(scale * random.uniform(1, 2)), s_end = fifty_bits(scale * random.uniform(2.5, 4));
      const Vec3 near{s_near, 3 * s_near, 5 * s_near}, mid{s_mid, 3 * s_mid, 5 * s_mid},
          end{s_end, 3 * s_end, 5 * s_end};
      const bool answer = SegmentReach(reach).within(near, end, mid);
      INFO("exactly on the line at " << s_near << ", " << s_mid << ", " << s_end << " times (1, 3, 5), reach " << r);
      REQUIRE(answer);
      accepted_beyond_doubles += s_end > r * 0x1p49;
      accepted += answer, ++queries;
    }
  }
  CHECK(accepted > queries / 20);
  CHECK(queries - accepted > queries / 4);
  CHECK(accepted_beyond_doubles >= 20);
}

TEST_CASE("projects_strictly_inside_segment, compare_along_direction and compare_distance_to are exact") {
  std::size_t inside = 0, ties = 0, queries = 0;
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    Random random(seed);
    for (int i = 0; i < 100; ++i) {
      const double scale = std::ldexp(1.0, int(random.index(120)) - 60);
      // Lattice points (exact ties: projections onto one point, equal
      // distances), the same a few ulps off, and random points.
      const auto lattice = [&] {
        return Vec3{double(random.index(9)) - 4, double(random.index(9)) - 4, double(random.index(9)) - 4} * scale;
      };
      const Vec3 a = lattice(), b = i % 25 == 0 ? a : lattice();
      const Vec3 points[] = {lattice(), lattice(), ulps_away(lattice(), 1, 0, -1), a, b,
                             a + random.direction() * scale, (a + b) * 0.5};
      const auto A = exact(a), B = exact(b), AB = minus(B, A);
      for (const Vec3& p : points) {
        // Along: the parameter t = (p - a).(b - a) / |b - a|^2, strictly in (0, 1).
        const auto P = exact(p);
        bool expected = false;
        if (sgn(dot(AB, AB)) > 0) {
          const mpq_class t = dot(minus(P, A), AB) / dot(AB, AB);
          expected = sgn(t) > 0 && t < 1;
        }
        REQUIRE(projects_strictly_inside_segment(a, b, p) == expected);
        inside += expected;
        for (const Vec3& q : points) {
          // Order along a -> b: each parameter from a, compared.
          const auto Q = exact(q);
          const Sign along = sign_of(dot(minus(P, A), AB) - dot(minus(Q, A), AB));
          REQUIRE(compare_along_direction(a, b, p, q) == along);
          REQUIRE(compare_along_direction(a, b, q, p) == flip(along));
          // Distance from a, expanded: |p|^2 - 2 p.a - (|q|^2 - 2 q.a).
          const Sign nearer = sign_of(dot(P, P) - 2 * dot(P, A) - dot(Q, Q) + 2 * dot(Q, A));
          REQUIRE(compare_distance_to(a, p, q) == nearer);
          ties += along == Sign::zero && !(p == q);
          ++queries;
        }
      }
    }
  }
  CHECK(inside > 150);
  CHECK(ties > 150);
  CHECK(queries > 20000);
}

TEST_CASE("loops_orientation: the sign of the loops' signed area, holes and cancelling edges included") {
  std::size_t counter_clockwise = 0, clockwise = 0, flat = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    Random random(seed);
    for (int i = 0; i < 100; ++i) {
      const double scale = std::ldexp(1.0, int(random.index(120)) - 60);
      const int axis = int(random.index(3));
      const Projection projection{axis, random.index(2) == 1};
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      // Loops of lattice points in the kept axes, any height on the dropped one.
      std::vector<Vec3> positions;
      std::vector<std::vector<VertexIndex>> loops(1 + random.index(3));
      for (auto& loop : loops) {
        const std::size_t k = 3 + random.index(4);
        for (std::size_t j = 0; j < k; ++j) {
          double c[3];
          c[u] = (double(random.index(9)) - 4) * scale;
          c[v] = (double(random.index(9)) - 4) * scale;
          c[axis] = random.uniform(-1, 1);
          loop.push_back(static_cast<VertexIndex>(positions.size()));
          positions.push_back({c[0], c[1], c[2]});
        }
      }
      // Now and then a loop and its reverse: they cancel.
      if (i % 5 == 0) loops.emplace_back(loops.front().rbegin(), loops.front().rend());
      // Twice the area by trapezoids: -sum (q_u - p_u)(q_v + p_v).
      mpq_class twice = 0;
      for (const auto& loop : loops) {
        for (std::size_t j = 0; j < loop.size(); ++j) {
          const Vec3 &p = positions[loop[j]], &q = positions[loop[(j + 1) % loop.size()]];
          twice -= (mpq_class(q[u]) - p[u]) * (mpq_class(q[v]) + p[v]);
        }
      }
      const Sign expected = projection.flipped ? flip(sign_of(twice)) : sign_of(twice);
      REQUIRE(loops_orientation(positions, loops, projection) == expected);
      if (i % 5 == 0) {
        const std::vector<std::vector<VertexIndex>> cancelling{loops.front(), loops.back()};
        REQUIRE(loops_orientation(positions, cancelling, projection) == Sign::zero);
      }
      counter_clockwise += expected == Sign::positive, clockwise += expected == Sign::negative;
      flat += expected == Sign::zero;
    }
  }
  REQUIRE(loops_orientation({}, {}, Projection{}) == Sign::zero);
  CHECK(counter_clockwise > 500);
  CHECK(clockwise > 500);
  CHECK(flat > 10);
}
