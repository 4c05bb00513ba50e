// The exact side-of-plane predicate against a GMP rational reference, on
// adversarial queries: points on or within a few ulps of the plane.

#include <catch2/catch.hpp>

#include <gmpxx.h>

#include <array>
#include <cmath>
#include <optional>
#include <vector>

#include "shatter/generators/random.hpp"
#include "shatter/kernel/exact.hpp"
#include "shatter/kernel/integer_orient.hpp"
#include "shatter/kernel/predicates.hpp"
#include "support/orient_reference.hpp"

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
  // Points of one piece share a scale: the integer stage takes most of those.
  if (integer_orient_available) CHECK(counters.orient3d_integer * 2 > counters.orient3d_expansion);
  CHECK(counters.orient3d_gmp == 0);
  CHECK(counters.orient3d_full * 100 < counters.orient3d_expansion);
}

namespace {

// A coordinate of a column built below: zero, or an odd integer of up to
// `width` bits at an offset from the column's base exponent that keeps it
// within `spread` bits of that base.
double column_coordinate(Random& random, int base, int spread) {
  if (random.index(8) == 0) return 0;
  const int width = 1 + static_cast<int>(random.index(static_cast<std::size_t>(std::min(53, spread))));
  const int offset = static_cast<int>(random.index(static_cast<std::size_t>(spread - width + 1)));
  const std::uint64_t odd = ((random.next() >> (64 - width)) | (std::uint64_t{1} << (width - 1))) | 1;
  const double magnitude = std::ldexp(static_cast<double>(odd), base + offset);
  return random.index(2) == 0 ? magnitude : -magnitude;
}

}  // namespace

// The integer stage on its own, where the filter would never send most of these
// queries: coordinates whose columns spread over 1 to 64 bits at exponents from
// -290 to 230, exactly coplanar and collinear sets among them. It answers
// exactly when every column spreads over at most 61 bits, and then agrees with
// the rationals; its 192-bit sums meet carries, borrows and both signs.
TEST_CASE("orient3d's integer stage agrees with exact rationals, and answers exactly within its range") {
  std::size_t declined = 0, zero = 0, positive = 0, negative = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    Random random(seed);
    for (int i = 0; i < 2000; ++i) {
      std::array<std::array<double, 4>, 3> columns;
      for (auto& column : columns) {
        const int base = static_cast<int>(random.index(520)) - 290;
        // Mostly at the edge of the range (59 to 64 bits), else anywhere below it.
        const int spread = random.index(2) == 0 ? 59 + static_cast<int>(random.index(6)) : 1 + static_cast<int>(random.index(61));
        for (double& v : column) v = column_coordinate(random, base, spread);
      }
      const auto point = [&](int k) { return Vec3{columns[0][k], columns[1][k], columns[2][k]}; };
      std::array<Vec3, 4> p{point(0), point(1), point(2), point(3)};
      switch (random.index(4)) {
        case 0: p[2] = p[0]; break;                      // a repeated point
        case 1: p[3].z = p[2].z = p[1].z = p[0].z; break;  // four points in a plane z = constant
        default: break;
      }
      const bool in_range = integer_orient_available && column_spread({p[0].x, p[1].x, p[2].x, p[3].x}) <= 61 &&
                            column_spread({p[0].y, p[1].y, p[2].y, p[3].y}) <= 61 &&
                            column_spread({p[0].z, p[1].z, p[2].z, p[3].z}) <= 61;
      const std::optional<int> sign = orient3d_by_integers(p[0], p[1], p[2], p[3]);
      INFO("seed " << seed << " query " << i);
      REQUIRE(sign.has_value() == in_range);
      if (!sign) {
        ++declined;
        continue;
      }
      REQUIRE(*sign == shewchuk_sign(reference_orient3d(p[0], p[1], p[2], p[3])));
      (*sign == 0 ? zero : *sign > 0 ? positive : negative) += 1;
    }
  }
  CHECK(declined > 400);
  if (integer_orient_available) {
    CHECK(zero > 1000);
    CHECK(positive > 1000);
    CHECK(negative > 1000);
  }
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

namespace {

// A lattice frame around an integer axis d: e1 = a lattice vector perpendicular
// to d, e2 = d x e1, so (e1, e2, d) is right-handed and x e1 + y e2 + t d turns
// counter-clockwise seen from +d as the angle of (x, y) grows. Every point built
// from small integers times a dyadic scale is exact in doubles.
struct Frame {
  Vec3 origin, d, e1, e2;
  Vec3 at(double x, double y, double t, double scale) const {
    return origin + (e1 * x + e2 * y + d * t) * scale;
  }
};

Frame lattice_frame(Random& random) {
  const auto small = [&] { return double(random.index(7)) - 3; };
  Vec3 d;
  while (d.x == 0 && d.y == 0 && d.z == 0) d = {small(), small(), small()};
  // A vector perpendicular to d: d x (a non-parallel lattice vector).
  Vec3 helper{1, 0, 0};
  if (cross(d, helper).x == 0 && cross(d, helper).y == 0 && cross(d, helper).z == 0) helper = {0, 1, 0};
  const Vec3 e1 = cross(d, helper);
  return {Vec3{double(random.index(64)), double(random.index(64)), double(random.index(64))}, d, e1, cross(d, e1)};
}

// The quarter-turn class and exact comparison of the angles of integer (x, y).
bool angle_less(const std::pair<long, long>& p, const std::pair<long, long>& q) {
  const auto half = [](const std::pair<long, long>& v) { return v.second > 0 || (v.second == 0 && v.first > 0) ? 0 : 1; };
  if (half(p) != half(q)) return half(p) < half(q);
  return p.first * q.second - p.second * q.first > 0;
}

}  // namespace

TEST_CASE("coplanar_orientation tells the sides of a line in a plane, exactly, in any plane") {
  std::size_t same = 0, opposite = 0, on = 0;
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    Random random(seed);
    for (int i = 0; i < 200; ++i) {
      const Frame f = lattice_frame(random);
      const double scale = std::ldexp(1.0, int(random.index(60)) - 30);
      // Points of the plane spanned by e1 and d (t = 0 of e2), in plane coordinates.
      const auto coordinate = [&] { return double(random.index(41)) - 20; };
      const double px = coordinate(), pt = coordinate(), qx = coordinate(), qt = coordinate();
      const double rx = coordinate(), rt = coordinate();
      // Every fourth s on the line pq itself.
      const double sx = i % 4 == 0 ? 2 * qx - px : coordinate(), st = i % 4 == 0 ? 2 * qt - pt : coordinate();
      const auto cross2 = [](double ax, double at, double bx, double bt) { return ax * bt - at * bx; };
      const double r_side = cross2(qx - px, qt - pt, rx - px, rt - pt);
      if (r_side == 0) continue;  // p, q, r collinear: outside the precondition
      const double s_side = cross2(qx - px, qt - pt, sx - px, st - pt);
      const Sign expected = s_side == 0 ? Sign::zero : (r_side > 0) == (s_side > 0) ? Sign::positive : Sign::negative;
      const Vec3 p = f.at(px, 0, pt, scale), q = f.at(qx, 0, qt, scale), r = f.at(rx, 0, rt, scale),
                 s = f.at(sx, 0, st, scale);
      REQUIRE(orient3d(p, q, r, s) == Sign::zero);  // the test's own premise
      REQUIRE(coplanar_orientation(p, q, r, s) == expected);
      same += expected == Sign::positive, opposite += expected == Sign::negative, on += expected == Sign::zero;
    }
  }
  CHECK(same > 1000);
  CHECK(opposite > 1000);
  CHECK(on > 1000);
}

TEST_CASE("order_around_line orders points by their angle about a line, and refuses equal angles") {
  std::size_t ordered = 0, refused = 0;
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    Random random(seed);
    for (int i = 0; i < 100; ++i) {
      const Frame f = lattice_frame(random);
      const double scale = std::ldexp(1.0, int(random.index(60)) - 30);
      const Vec3 a = f.at(0, 0, double(random.index(5)) - 2, scale);
      const Vec3 b = f.at(0, 0, double(random.index(5)) + 3, scale);  // b - a along +d
      // Directions (x, y) with distinct angles, at any height t along the line.
      std::vector<std::pair<long, long>> directions;
      const std::size_t k = 2 + random.index(7);
      while (directions.size() < k) {
        const std::pair<long, long> v{long(random.index(21)) - 10, long(random.index(21)) - 10};
        if (v.first == 0 && v.second == 0) continue;
        bool repeated = false;
        for (const auto& w : directions) repeated |= v.first * w.second == v.second * w.first && (v.first * w.first + v.second * w.second) > 0;
        if (!repeated) directions.push_back(v);
      }
      std::vector<Vec3> around;
      for (const auto& v : directions) {
        around.push_back(f.at(double(v.first), double(v.second), double(random.index(9)) - 4, scale));
      }
      // The expected order: by angle, starting at around[0].
      std::vector<std::size_t> expected(k);
      for (std::size_t j = 0; j < k; ++j) expected[j] = j;
      std::sort(expected.begin(), expected.end(),
                [&](std::size_t x, std::size_t y) { return angle_less(directions[x], directions[y]); });
      std::rotate(expected.begin(), std::find(expected.begin(), expected.end(), std::size_t{0}), expected.end());
      const std::optional<std::vector<std::size_t>> order = order_around_line(a, b, around);
      REQUIRE(order.has_value());
      REQUIRE(*order == expected);
      // Turned the other way round the line, the order reverses (after the first).
      const std::optional<std::vector<std::size_t>> reversed = order_around_line(b, a, around);
      REQUIRE(reversed.has_value());
      std::vector<std::size_t> back(expected.rbegin(), expected.rend() - 1);
      back.insert(back.begin(), 0);
      REQUIRE(*reversed == back);
      ++ordered;
      // A second point in the half-plane of one of them: equal angles, no order.
      const std::size_t twin = random.index(k);
      around.push_back(f.at(double(2 * directions[twin].first), double(2 * directions[twin].second), 1, scale));
      REQUIRE_FALSE(order_around_line(a, b, around).has_value());
      // A point on the line has no angle.
      around.back() = f.at(0, 0, 7, scale);
      REQUIRE_FALSE(order_around_line(a, b, around).has_value());
      ++refused;
    }
  }
  CHECK(ordered == 4000);
  CHECK(refused == 4000);
}

// --- collinear, strictly_inside_segment, strictly_inside_triangle ------------

namespace {

std::array<mpq_class, 3> exact_difference(Vec3 p, Vec3 q) {
  return {mpq_class(p.x) - q.x, mpq_class(p.y) - q.y, mpq_class(p.z) - q.z};
}

// (b - a) x (c - a) = 0, in rationals.
bool reference_collinear(Vec3 a, Vec3 b, Vec3 c) {
  const auto u = exact_difference(b, a), w = exact_difference(c, a);
  return u[1] * w[2] == u[2] * w[1] && u[2] * w[0] == u[0] * w[2] && u[0] * w[1] == u[1] * w[0];
}

// Collinear and strictly between along the line: (p - a).(b - a) > 0 and
// (p - b).(a - b) > 0, in rationals (a different route from the predicate's).
bool reference_inside_segment(Vec3 a, Vec3 b, Vec3 p) {
  if (!reference_collinear(a, b, p)) return false;
  const auto ap = exact_difference(p, a), ab = exact_difference(b, a), bp = exact_difference(p, b);
  const mpq_class from_a = ap[0] * ab[0] + ap[1] * ab[1] + ap[2] * ab[2];
  const mpq_class from_b = -(bp[0] * ab[0] + bp[1] * ab[1] + bp[2] * ab[2]);
  return sgn(from_a) > 0 && sgn(from_b) > 0;
}

int reference_turn(Vec2 a, Vec2 b, Vec2 c) {
  return sgn((mpq_class(b.x) - a.x) * (mpq_class(c.y) - a.y) - (mpq_class(b.y) - a.y) * (mpq_class(c.x) - a.x));
}

bool reference_inside_triangle(Vec2 a, Vec2 b, Vec2 c, Vec2 p) {
  const int s0 = reference_turn(a, b, p), s1 = reference_turn(b, c, p), s2 = reference_turn(c, a, p);
  return s0 != 0 && s0 == s1 && s1 == s2;
}

}  // namespace

TEST_CASE("collinear and strictly_inside_segment agree with exact rationals on lines, near them and off them") {
  std::size_t on_line = 0, inside = 0, queries = 0;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    Random random(seed);
    for (int i = 0; i < 250; ++i) {
      const Frame f = lattice_frame(random);
      const double scale = std::ldexp(1.0, int(random.index(80)) - 40);
      // Points of one lattice line (exact: small integers times a power of two),
      // some of them coinciding, and the same points a few ulps off it.
      const auto on = [&] { return f.at(0, 0, double(random.index(9)) - 4, scale); };
      const Vec3 a = on(), b = i % 16 == 0 ? a : on(), p = on();
      const int k = int(random.index(5)) - 2;
      const Vec3 near{ulps_away(p.x, k), ulps_away(p.y, -k), ulps_away(p.z, k)};
      const Vec3 off = f.at(double(random.index(3)) - 1, double(random.index(3)) - 1, 1, scale);
      // Unrelated points at any scale, far from the origin.
      const Vec3 centre = random.direction() * (scale * random.uniform(0, 1e6));
      const Vec3 r0 = centre + random.direction() * scale, r1 = centre + random.direction() * scale;
      const std::vector<std::array<Vec3, 3>> cases{{a, b, p}, {a, b, near}, {a, b, off}, {r0, r1, centre},
                                                   {a, p, b},  {p, a, a}, {r0, r1, r0}};
      for (const auto& [x, y, z] : cases) {
        INFO("a " << x.x << ' ' << x.y << ' ' << x.z << ", b " << y.x << ' ' << y.y << ' ' << y.z << ", p " << z.x
                  << ' ' << z.y << ' ' << z.z);
        const bool line = reference_collinear(x, y, z);
        REQUIRE(collinear(x, y, z) == line);
        REQUIRE(collinear(z, x, y) == line);
        const bool between = reference_inside_segment(x, y, z);
        REQUIRE(strictly_inside_segment(x, y, z) == between);
        REQUIRE(strictly_inside_segment(y, x, z) == between);
        on_line += line, inside += between, ++queries;
      }
    }
  }
  // Both answers occur often: the property cannot pass by testing one side.
  CHECK(on_line > queries / 4);
  CHECK(inside > queries / 20);
  CHECK(queries - on_line > queries / 4);
}

TEST_CASE("strictly_inside_triangle agrees with exact rationals on edges, corners and ulps from them") {
  std::size_t inside = 0, queries = 0;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    Random random(seed);
    for (int i = 0; i < 250; ++i) {
      const double scale = std::ldexp(1.0, int(random.index(80)) - 40);
      const auto lattice = [&] {
        return Vec2{(double(random.index(17)) - 8) * scale, (double(random.index(17)) - 8) * scale};
      };
      const Vec2 a = lattice(), b = lattice(), c = lattice();
      // On an edge's line (a midpoint when it is a lattice point), a corner,
      // inside or not, and each a few ulps off.
      const Vec2 mid{(a.x + b.x) / 2, (a.y + b.y) / 2};
      const Vec2 candidates[] = {mid, a, lattice(), Vec2{(a.x + b.x + c.x) / 3, (a.y + b.y + c.y) / 3}};
      for (Vec2 p : candidates) {
        for (int k = -2; k <= 2; ++k) {
          const Vec2 q{ulps_away(p.x, k), ulps_away(p.y, k / 2)};
          const bool expected = reference_inside_triangle(a, b, c, q);
          REQUIRE(strictly_inside_triangle(a, b, c, q) == expected);
          REQUIRE(strictly_inside_triangle(b, c, a, q) == expected);
          REQUIRE(strictly_inside_triangle(c, b, a, q) == expected);  // either turn
          inside += expected, ++queries;
        }
      }
    }
  }
  CHECK(inside > queries / 10);
  CHECK(queries - inside > queries / 10);
}
