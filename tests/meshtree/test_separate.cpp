// Solid separation (meshtree/separate.hpp), seen through the full cut: a cavity
// stays with the shell around it, and an island in a cavity becomes a solid of
// its own.

#include <catch2/catch.hpp>

#include "shatter/meshtree/cut.hpp"
#include "support/checks.hpp"
#include "support/generators.hpp"

using namespace shatter;
using namespace shatter::test;

TEST_CASE("a hollow egg cut above its cavity keeps the cavity with the outer shell") {
  const Mesh egg = hollow_egg();
  // The cavity reaches z = 1.1; the outer shell z = 1.35.
  const auto top_off = cut_mesh(egg, {{0, 0, 1}, -1.2});
  REQUIRE(top_off.above.size() == 1);
  REQUIRE(top_off.below.size() == 1);
  CHECK(top_off.below[0].triangles.size() > top_off.above[0].triangles.size());
  CHECK(solid_problem(top_off.below[0]) == "");
  // Through the middle: two bowls, each capped by an annulus (two loops).
  const auto halves = cut_mesh(egg, {{0, 0, 1}, 0.013});
  CHECK(halves.below.size() == 1);
  CHECK(halves.above.size() == 1);
  CHECK(halves.cap_loops == 2);
  CHECK(halves.cap_method == CapMethod::cdt);
}

TEST_CASE("nested shells: the island separates from the shell around its cavity") {
  const Mesh nested = nested_shells_with_island();
  const auto result = cut_mesh(nested, {{1, 0.01, 0.02}, -2.0});
  // Each side: the outer shell's half (open cavity now part of its surface) and
  // the island's half.
  CHECK(result.below.size() == 2);
  CHECK(result.above.size() == 2);
  CHECK(result.cap_loops == 3);  // outer boundary, cavity hole, island
  // A cut that misses the cavity: the whole inner structure stays in one solid
  // on one side, with the island as a separate solid inside the cavity.
  const auto side = cut_mesh(nested, {{1, 0, 0}, -0.5});
  CHECK(side.below.size() == 1);
  CHECK(side.above.size() == 2);
}
