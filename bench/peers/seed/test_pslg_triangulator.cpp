// The seed peer's stand-in for Triangle (pslg_triangulator.hpp): the region it keeps
// is exactly the PSLG's inside (areas against the shoelace formula, exact on these
// small integer and half-integer coordinates), holes are eaten from their points
// and stop at segments so a polygon inside a hole survives, duplicates are merged,
// and the PSLGs Triangle would repair itself are refused with their reason.

#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "pslg_triangulator.hpp"

using seed_peer::Pslg;
using seed_peer::triangulate_pslg;

namespace {

// Twice the signed area of triangle t.
double twice_area(const Pslg& p, const std::array<int, 3>& t) {
  const auto& a = p.points[static_cast<std::size_t>(t[0])];
  const auto& b = p.points[static_cast<std::size_t>(t[1])];
  const auto& c = p.points[static_cast<std::size_t>(t[2])];
  return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

// Adds the closed loop through `corners` as points and segments.
void add_loop(Pslg& p, const std::vector<std::array<double, 2>>& corners) {
  const int first = static_cast<int>(p.points.size());
  const int n = static_cast<int>(corners.size());
  for (int k = 0; k < n; ++k) {
    p.points.push_back(corners[static_cast<std::size_t>(k)]);
    p.segments.push_back({first + k, first + (k + 1) % n});
  }
}

std::vector<std::array<double, 2>> square(double lo, double hi) { return {{lo, lo}, {hi, lo}, {hi, hi}, {lo, hi}}; }

// The kept area, every triangle counter-clockwise and not degenerate.
double kept_area(const Pslg& p, const seed_peer::PslgTriangulation& r) {
  double twice = 0;
  for (const auto& t : r.triangles) {
    const double a = twice_area(p, t);
    CHECK(a > 0);
    twice += a;
  }
  return twice / 2;
}

}  // namespace

TEST_CASE("a square with a hole holding an island keeps the ring and the island") {
  Pslg p;
  add_loop(p, square(0, 4));
  add_loop(p, square(1, 3));
  add_loop(p, square(1.5, 2.5));
  p.holes.push_back({1.2, 1.2});  // inside the hole, outside the island
  const auto r = triangulate_pslg(p);
  REQUIRE(r.ok);
  CHECK(kept_area(p, r) == 16 - 4 + 1);
  CHECK(r.triangles.size() == 8 + 2);  // the ring's 8 vertices in 8 triangles, the island's 2
}

TEST_CASE("without a hole point the hole is filled, as Triangle fills it") {
  Pslg p;
  add_loop(p, square(0, 4));
  add_loop(p, square(1, 3));
  const auto r = triangulate_pslg(p);
  REQUIRE(r.ok);
  CHECK(kept_area(p, r) == 16);
}

TEST_CASE("a comb-shaped polygon keeps exactly its inside") {
  Pslg p;
  std::vector<std::array<double, 2>> comb;
  for (int i = 0; i < 40; ++i) comb.push_back({double(i), i % 2 ? 5.0 : 1.0});
  comb.push_back({39, 0});
  comb.push_back({0, 0});
  add_loop(p, comb);
  double shoelace = 0;
  for (std::size_t i = 0; i < comb.size(); ++i) {
    const auto& a = comb[i];
    const auto& b = comb[(i + 1) % comb.size()];
    shoelace += a[0] * b[1] - a[1] * b[0];
  }
  const auto r = triangulate_pslg(p);
  REQUIRE(r.ok);
  CHECK(kept_area(p, r) == std::fabs(shoelace) / 2);
  CHECK(r.triangles.size() == comb.size() - 2);
}

TEST_CASE("a point repeated exactly is merged, a collinear boundary point kept") {
  Pslg p;
  p.points = {{0, 0}, {1, 0}, {2, 0}, {2, 2}, {0, 2}, {1, 0}};
  p.segments = {{0, 5}, {1, 2}, {2, 3}, {3, 4}, {4, 0}};  // the first segment ends at the copy of point 1
  const auto r = triangulate_pslg(p);
  REQUIRE(r.ok);
  CHECK(kept_area(p, r) == 4);
  CHECK(r.triangles.size() == 3);
  for (const auto& t : r.triangles)
    for (int v : t) CHECK(v != 5);  // triangles name the first copy
}

TEST_CASE("the PSLGs Triangle would repair are refused with their reason") {
  SECTION("two segments cross") {
    Pslg p;
    add_loop(p, {{0, 0}, {2, 2}, {2, 0}, {0, 2}});  // a bow tie
    const auto r = triangulate_pslg(p);
    CHECK_FALSE(r.ok);
    CHECK(r.error.find("cross") != std::string::npos);
  }
  SECTION("a segment passes through a point") {
    Pslg p;
    add_loop(p, square(0, 4));
    p.points.push_back({2, 0});  // on the bottom edge, not an end of it
    p.segments.push_back({4, 2});
    const auto r = triangulate_pslg(p);
    CHECK_FALSE(r.ok);
    CHECK(r.error.find("passes through") != std::string::npos);
  }
  SECTION("fewer than three points") {
    Pslg p;
    p.points = {{0, 0}, {1, 0}};
    p.segments = {{0, 1}, {1, 0}};
    CHECK_FALSE(triangulate_pslg(p).ok);
  }
}
