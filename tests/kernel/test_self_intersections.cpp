// The grid self-intersection finder against the box-tree finder it replaced and,
// on small inputs, against every pair decided by CGAL alone (no filter): the same
// pairs on seeded solids, intersecting pairs of solids, pinched copies, lattice
// soups full of coplanar, touching and shared-vertex triangles, and meshes with a
// few long triangles (the finder's box-tree side path); and its parallel path on
// 1, 2 and 4 threads against its one-thread result. The same for the finder
// of the pairs with a tested triangle among chosen members.

#include <catch2/catch.hpp>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "shatter/generators/corpus.hpp"
#include "shatter/generators/solids.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/self_intersections.hpp"
#include "shatter/kernel/self_intersections_detail.hpp"
#include "support/pair_reference.hpp"
#include "support/sanitizers.hpp"

using namespace shatter;

namespace {

using K = CGAL::Epick;

K::Point_3 point(const Vec3& p) { return {p.x, p.y, p.z}; }

// CGAL PMP's pair semantics with CGAL's exact predicates alone: the oracle for
// triangles_intersect's filters.
bool reference_intersect(const std::vector<Vec3>& positions, const Triangle& a, const Triangle& b) {
  return test::pmp_pair_intersects<K>(a, b, [&](VertexIndex v) { return point(positions[v]); });
}

std::vector<TrianglePair> brute_force_pairs(const Mesh& mesh) {
  std::vector<TrianglePair> pairs;
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    for (std::size_t j = i + 1; j < mesh.triangles.size(); ++j) {
      if (reference_intersect(mesh.positions, mesh.triangles[i], mesh.triangles[j])) pairs.emplace_back(i, j);
    }
  }
  return pairs;
}

bool has_collinear_triangle(const Mesh& mesh) {
  for (const Triangle& t : mesh.triangles) {
    if (CGAL::collinear(point(mesh.positions[t[0]]), point(mesh.positions[t[1]]), point(mesh.positions[t[2]]))) {
      return true;
    }
  }
  return false;
}

// A soup of triangles over a small pool of lattice points: coplanar overlaps,
// touching corners and edges, shared vertices and edges, and repeated
// triangles, all decided exactly. Collinear triangles are redrawn.
Mesh lattice_soup(std::mt19937_64& random, int points, int triangles, int lattice, double spacing) {
  std::uniform_int_distribution<int> coordinate(0, lattice);
  Mesh mesh;
  for (int i = 0; i < points; ++i) {
    mesh.positions.push_back({coordinate(random) * spacing, coordinate(random) * spacing, coordinate(random) * spacing});
  }
  std::uniform_int_distribution<VertexIndex> index(0, static_cast<VertexIndex>(points - 1));
  while (static_cast<int>(mesh.triangles.size()) < triangles) {
    const Triangle t{index(random), index(random), index(random)};
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
    if (CGAL::collinear(point(mesh.positions[t[0]]), point(mesh.positions[t[1]]), point(mesh.positions[t[2]]))) continue;
    mesh.triangles.push_back(t);
  }
  mesh.surfaces.assign(mesh.triangles.size(), 0);
  return mesh;
}

// Every vertex moved to the nearest multiple of `step`: faces of a smooth solid
// become nearly or exactly coplanar with their neighbours.
Mesh snapped(Mesh mesh, double step) {
  for (Vec3& p : mesh.positions) p = {std::round(p.x / step) * step, std::round(p.y / step) * step, std::round(p.z / step) * step};
  return mesh;
}

void check_same_pairs(const std::string& name, const Mesh& mesh, bool brute_force) {
  INFO(name << ": " << mesh.triangles.size() << " triangles");
  const std::vector<TrianglePair> grid = self_intersecting_pairs(mesh.positions, mesh.triangles);
  const std::vector<TrianglePair> tree = self_intersecting_pairs_by_box_tree(mesh.positions, mesh.triangles);
  CHECK(grid == tree);
  if (brute_force) CHECK(grid == brute_force_pairs(mesh));
  // The parallel path (blocks far smaller than the public 16,384 triangles, so
  // that these meshes span several) on 1, 2 and 4 threads: the same pairs.
  // Four threads even on a machine with fewer cores (TBB otherwise caps the workers, and warns).
  const tbb::global_control workers(tbb::global_control::max_allowed_parallelism, 4);
  for (const int threads : {1, 2, 4}) {
    for (const std::size_t block : {std::size_t{7}, std::size_t{64}}) {
      INFO(threads << " threads, blocks of " << block);
      tbb::task_arena arena(threads);
      const std::vector<TrianglePair> split = arena.execute(
          [&] { return detail::self_intersecting_pairs_in_blocks(mesh.positions, mesh.triangles, block); });
      CHECK(split == grid);
    }
  }
}

// intersecting_pairs_with against its box-tree reference and, on small meshes,
// against the brute force's pairs restricted to the members with a tested one,
// for a random choice of members and of tested triangles at the given densities.
std::size_t check_same_pairs_with(const std::string& name, const Mesh& mesh, std::mt19937_64& random,
                                  double member_share, double tested_share, bool brute_force) {
  std::bernoulli_distribution member(member_share), test(tested_share);
  std::vector<std::uint32_t> members;
  std::vector<std::uint8_t> tested(mesh.triangles.size(), 0);
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    tested[t] = test(random);  // flags outside the members must be ignored
    if (member(random)) members.push_back(t);
  }
  INFO(name << ": " << mesh.triangles.size() << " triangles, " << members.size() << " members, tested share "
            << tested_share);
  const std::vector<TrianglePair> grid = intersecting_pairs_with(mesh.positions, mesh.triangles, members, tested);
  CHECK(grid == intersecting_pairs_with_by_box_tree(mesh.positions, mesh.triangles, members, tested));
  // With groups whose inner pairs are skipped: both skip the same pairs.
  std::vector<std::uint32_t> embedded(mesh.triangles.size());
  for (std::uint32_t& g : embedded) g = random() % 4 == 0 ? no_embedded_group : static_cast<std::uint32_t>(random() % 3);
  const std::vector<TrianglePair> grouped =
      intersecting_pairs_with(mesh.positions, mesh.triangles, members, tested, embedded);
  CHECK(grouped == intersecting_pairs_with_by_box_tree(mesh.positions, mesh.triangles, members, tested, embedded));
  for (const TrianglePair& p : grouped) {
    CHECK((embedded[p.first] != embedded[p.second] || embedded[p.first] == no_embedded_group));
  }
  if (brute_force) {
    std::vector<std::uint8_t> is_member(mesh.triangles.size(), 0);
    for (const std::uint32_t t : members) is_member[t] = 1;
    std::vector<TrianglePair> expected;
    for (const TrianglePair& p : brute_force_pairs(mesh)) {
      if (is_member[p.first] && is_member[p.second] && (tested[p.first] || tested[p.second])) expected.push_back(p);
    }
    CHECK(grid == expected);
  }
  return grid.size();
}

// A fine solid crossed by `count` long random triangles, and one more long one
// sharing a vertex with the solid: the side path for boxes spanning many cells.
Mesh crossed_by_long_triangles(std::mt19937_64& random, int count, int slices = 30, int stacks = 20) {
  std::uniform_real_distribution<double> unit(-1, 1);
  Mesh crossed = test::ellipsoid({0, 0, 0}, {1, 1, 1}, slices, stacks);
  const auto base = static_cast<VertexIndex>(crossed.positions.size());
  for (int k = 0; k < count; ++k) {
    for (int c = 0; c < 3; ++c) crossed.positions.push_back({2 * unit(random), 2 * unit(random), 2 * unit(random)});
    crossed.triangles.push_back({base + 3 * k, base + 3 * k + 1, base + 3 * k + 2});
  }
  crossed.triangles.push_back({0, base, base + 4});
  crossed.surfaces.resize(crossed.triangles.size(), 0);
  return crossed;
}

}  // namespace

TEST_CASE("the grid finder finds the box tree's pairs, and every pair CGAL alone finds, on seeded meshes",
          "[validate][self-intersection]") {
  std::mt19937_64 random(20261203);
  std::uniform_real_distribution<double> unit(-1, 1);
  std::size_t meshes_with_pairs = 0, pairs_found = 0;
  const auto run = [&](const std::string& name, const Mesh& mesh, bool brute_force) {
    if (has_collinear_triangle(mesh)) return;  // outside the precondition
    check_same_pairs(name, mesh, brute_force);
    const std::size_t found = self_intersecting_pairs(mesh.positions, mesh.triangles).size();
    pairs_found += found;
    meshes_with_pairs += found > 0;
  };
  // 40 seeds; 14 under the sanitizers (46 s there at 40, on a clean clone of fe3da8d).
  const int seeds = static_cast<int>(test::sized(40, 14));
  for (int seed = 0; seed < seeds; ++seed) {
    const std::string tag = " #" + std::to_string(seed);
    // Two solids placed to overlap, touch or miss.
    const Mesh a = test::ellipsoid({0, 0, 0}, {1, 0.8 + 0.2 * unit(random), 0.7}, 8 + seed % 5, 6 + seed % 3);
    const Mesh b = test::torus(0.9, 0.3 + 0.1 * unit(random), 9 + seed % 4, 6);
    const Vec3 shift{unit(random), unit(random), unit(random)};
    run("ellipsoid and torus" + tag, test::merge({a, test::transformed(b, 1.0, shift)}), true);
    // Boxes sharing face planes: coplanar overlapping and touching faces.
    const double s = 0.5 + 0.5 * (seed % 3);
    run("boxes on shared planes" + tag,
        test::merge({test::grid_box({0, 0, 0}, {1, 1, 1}, 1 + seed % 3), test::box({s, 0, 0}, {s + 1, 1, 1}),
                     test::box({0.25, 0.25, 1}, {0.75, 0.75, 1.5})}),
        true);
    // A solid snapped to a coarse lattice: nearly and exactly coplanar neighbours.
    run("snapped ellipsoid" + tag, snapped(test::ellipsoid({0.1, 0, 0}, {1, 1, 1}, 12, 9), 1.0 / (4 + seed % 8)), true);
    // A solid touching a copy of itself at one shared vertex (a pinch, by index).
    {
      Mesh pinch = test::ellipsoid({0, 0, 0}, {1, 1, 1}, 7, 5);
      const Mesh copy = test::transformed(pinch, 1.0, {2, 0, 0});
      const VertexIndex shared = static_cast<VertexIndex>(random() % pinch.positions.size());
      const auto offset = static_cast<VertexIndex>(pinch.positions.size());
      pinch.positions.insert(pinch.positions.end(), copy.positions.begin(), copy.positions.end());
      for (Triangle t : copy.triangles) {
        for (VertexIndex& v : t) v = v == shared ? shared : v + offset;
        pinch.triangles.push_back(t);
      }
      pinch.surfaces.resize(pinch.triangles.size(), 0);
      run("pinched copies" + tag, pinch, true);
    }
    // Lattice soups: every degenerate contact a small lattice allows.
    run("lattice soup" + tag, lattice_soup(random, 12 + seed, 40 + 5 * seed, 3, 1.0), true);
    run("fine lattice soup" + tag, lattice_soup(random, 60, 150, 6 + seed % 5, 0.125), true);
    run("long triangles" + tag, crossed_by_long_triangles(random, 3), seed % 8 == 0);
  }
  // The properties were exercised on real intersections, not only on clean meshes.
  CHECK(meshes_with_pairs > test::sized(100, 35));
  CHECK(pairs_found > test::sized(1000, 350));
}

TEST_CASE("the grid finder agrees with the box tree on the corpus", "[validate][self-intersection][corpus]") {
  std::size_t meshes = 0;
  for (const auto& list : {test::valid_meshes(), test::self_intersecting_meshes()}) {
    for (const auto& path : list) {
      const Mesh mesh = read_mesh(path);
      if (has_collinear_triangle(mesh)) continue;
      check_same_pairs(path.filename().string(), mesh, false);
      ++meshes;
    }
  }
  CHECK(meshes >= 10);
}

TEST_CASE("the grid finder of pairs with a tested triangle finds the box tree's pairs, on seeded meshes",
          "[validate][self-intersection]") {
  std::mt19937_64 random(20261204);
  std::uniform_real_distribution<double> unit(-1, 1);
  std::size_t meshes_with_pairs = 0, pairs_found = 0, checked = 0;
  const auto run = [&](const std::string& name, const Mesh& mesh, bool brute_force) {
    if (has_collinear_triangle(mesh)) return;  // outside the precondition
    // Every member tested, a few tested (validate_mesh_against's case: a cut's
    // new triangles among the trusted ones), a subset of members, none tested.
    for (const auto& [member_share, tested_share] :
         {std::pair{1.0, 1.0}, std::pair{1.0, 0.1}, std::pair{0.7, 0.3}, std::pair{1.0, 0.02}, std::pair{0.8, 0.0}}) {
      const std::size_t found = check_same_pairs_with(name, mesh, random, member_share, tested_share, brute_force);
      pairs_found += found;
      meshes_with_pairs += found > 0;
      ++checked;
    }
  };
  for (int seed = 0; seed < 30; ++seed) {
    const std::string tag = " #" + std::to_string(seed);
    const Mesh a = test::ellipsoid({0, 0, 0}, {1, 0.8 + 0.2 * unit(random), 0.7}, 8 + seed % 5, 6 + seed % 3);
    const Mesh b = test::torus(0.9, 0.3 + 0.1 * unit(random), 9 + seed % 4, 6);
    const Vec3 shift{unit(random), unit(random), unit(random)};
    run("ellipsoid and torus" + tag, test::merge({a, test::transformed(b, 1.0, shift)}), seed % 4 == 0);
    const double s = 0.5 + 0.5 * (seed % 3);
    run("boxes on shared planes" + tag,
        test::merge({test::grid_box({0, 0, 0}, {1, 1, 1}, 1 + seed % 3), test::box({s, 0, 0}, {s + 1, 1, 1}),
                     test::box({0.25, 0.25, 1}, {0.75, 0.75, 1.5})}),
        true);
    run("snapped ellipsoid" + tag, snapped(test::ellipsoid({0.1, 0, 0}, {1, 1, 1}, 12, 9), 1.0 / (4 + seed % 8)),
        seed % 4 == 0);
    run("lattice soup" + tag, lattice_soup(random, 12 + seed, 40 + 5 * seed, 3, 1.0), true);
    run("fine lattice soup" + tag, lattice_soup(random, 60, 150, 6 + seed % 5, 0.125), true);
    // Long triangles (compared with every member's box, as a cut's few are),
    // tested or not as the draw falls; and, every tenth seed (the first alone
    // under the sanitizers), enough of them among enough members to go to the
    // box tree (64 x 19,000 box tests).
    run("long triangles" + tag, crossed_by_long_triangles(random, 4), false);
    if (seed % static_cast<int>(test::sized(10, 30)) == 0) {
      run("many long triangles" + tag, crossed_by_long_triangles(random, 64, 120, 80), false);
    }
  }
  // Real intersections were found (860 draws, 540 with pairs, 286,403 pairs).
  CHECK(checked >= 800);
  CHECK(meshes_with_pairs > 400);
  CHECK(pairs_found > 100000);
}

TEST_CASE("the grid finder of pairs with a tested triangle agrees with the box tree on the corpus",
          "[validate][self-intersection][corpus]") {
  std::mt19937_64 random(7);
  std::size_t meshes = 0;
  for (const auto& list : {test::valid_meshes(), test::self_intersecting_meshes()}) {
    for (const auto& path : list) {
      const Mesh mesh = read_mesh(path);
      if (has_collinear_triangle(mesh)) continue;
      check_same_pairs_with(path.filename().string(), mesh, random, 1.0, 0.05, false);
      check_same_pairs_with(path.filename().string(), mesh, random, 0.5, 0.5, false);
      ++meshes;
    }
  }
  CHECK(meshes >= 10);
}

namespace {

// A height field over the lattice cells (i, j) of an n x n square that `keep`
// accepts, two triangles per cell, counter-clockwise seen from +z: corners
// jittered in x and y by up to `jitter` cells (beyond about half a cell some
// triangles flip and the projection folds) and in z by up to `height`.
Mesh jittered_sheet(std::mt19937_64& random, int n, double jitter, double height, auto&& keep) {
  std::uniform_real_distribution<double> unit(-1, 1);
  Mesh mesh;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) mesh.positions.push_back({i + jitter * unit(random), j + jitter * unit(random), height * unit(random)});
  }
  const auto at = [&](int i, int j) { return static_cast<VertexIndex>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      if (!keep(i, j)) continue;
      if ((i + j) % 2 == 0) {
        mesh.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
        mesh.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
      } else {
        mesh.triangles.push_back({at(i, j), at(i + 1, j), at(i, j + 1)});
        mesh.triangles.push_back({at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
      }
    }
  }
  mesh.surfaces.assign(mesh.triangles.size(), 0);
  return mesh;
}

// Whether any two triangles of the mesh intersect, by CGAL alone.
bool any_pair_intersects(const Mesh& mesh) {
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    for (std::size_t j = i + 1; j < mesh.triangles.size(); ++j) {
      if (reference_intersect(mesh.positions, mesh.triangles[i], mesh.triangles[j])) return true;
    }
  }
  return false;
}

}  // namespace

TEST_CASE("triangles_embed_in_projection certifies only groups no two of whose triangles intersect",
          "[validate][self-intersection]") {
  std::mt19937_64 random(20261204);
  std::size_t accepted = 0, declined = 0, declined_disjoint = 0;
  const auto run = [&](const std::string& name, const Mesh& mesh, int axis) {
    INFO(name << ": " << mesh.triangles.size() << " triangles, axis " << axis);
    std::vector<std::uint32_t> group(mesh.triangles.size());
    for (std::uint32_t t = 0; t < group.size(); ++t) group[t] = t;
    const bool certified = triangles_embed_in_projection(mesh.positions, mesh.triangles, group, axis);
    if (certified) {
      CHECK_FALSE(has_collinear_triangle(mesh));
      CHECK_FALSE(any_pair_intersects(mesh));
      ++accepted;
    } else {
      ++declined;
      if (!has_collinear_triangle(mesh) && !any_pair_intersects(mesh)) ++declined_disjoint;
    }
  };
  for (int seed = 0; seed < 60; ++seed) {
    const std::string tag = " #" + std::to_string(seed);
    const int n = 3 + seed % 6;
    const double jitter = seed % 3 == 0 ? 0.2 : seed % 3 == 1 ? 0.45 : 0.7;
    const auto all = [](int, int) { return true; };
    const auto ring = [n](int i, int j) { return !(i > 0 && j > 0 && i < n - 1 && j < n - 1); };  // a hole
    const auto blob = [&random](int, int) { return random() % 4 != 0; };  // holes, pinches, pieces
    run("sheet" + tag, jittered_sheet(random, n, jitter, 0.3, all), 2);
    run("flat sheet" + tag, jittered_sheet(random, n, jitter, 0.0, all), 2);
    run("ring" + tag, jittered_sheet(random, n, jitter, 0.3, ring), 2);
    run("blob" + tag, jittered_sheet(random, n, jitter, 0.3, blob), 2);
    // Seen from the side, the sheet's projection is flat or folded.
    run("sheet from the side" + tag, jittered_sheet(random, n, jitter, 0.3, all), seed % 2);
    {
      // Two sheets stacked (apart in z, or coplanar and overlapping): the
      // projection covers twice, so never certified.
      const Mesh sheet = jittered_sheet(random, n, 0.2, 0.1, all);
      run("stacked sheets" + tag, test::merge({sheet, test::transformed(sheet, 1.0, {0.3, 0.2, seed % 2 ? 1.0 : 0.0})}), 2);
    }
    {
      // Two sheets touching at one point through different vertices: the pair
      // there intersects (they share no vertex by index).
      Mesh a = jittered_sheet(random, n, 0.0, 0.0, all);
      const Mesh b = test::transformed(a, 1.0, {static_cast<double>(n), static_cast<double>(n), 0});
      run("sheets touching at a corner" + tag, test::merge({a, b}), 2);
      // The same sheets sharing that corner by index: a pinch, which intersects
      // nowhere; declined all the same (its boundary passes the corner twice).
      Mesh pinch = a;
      const auto offset = static_cast<VertexIndex>(a.positions.size());
      const VertexIndex corner = static_cast<VertexIndex>(n * (n + 1) + n);  // (n, n) of a; (0, 0) of b
      pinch.positions.insert(pinch.positions.end(), b.positions.begin(), b.positions.end());
      for (Triangle t : b.triangles) {
        for (VertexIndex& v : t) v = v == 0 ? corner : v + offset;
        pinch.triangles.push_back(t);
      }
      pinch.surfaces.resize(pinch.triangles.size(), 0);
      run("sheets pinched at a corner" + tag, pinch, 2);
    }
    {
      // A strip winding one and a half turns around the z axis, rising: no two
      // triangles meet in 3D, but its projection covers twice.
      Mesh spiral;
      const int steps = 12 + seed % 7;
      for (int k = 0; k <= steps; ++k) {
        const double angle = 3 * 3.14159265358979 * k / steps, rise = 0.1 * k;
        spiral.positions.push_back({std::cos(angle), std::sin(angle), rise});
        spiral.positions.push_back({2 * std::cos(angle), 2 * std::sin(angle), rise});
      }
      for (VertexIndex k = 0; k < static_cast<VertexIndex>(steps); ++k) {
        spiral.triangles.push_back({2 * k, 2 * k + 1, 2 * k + 3});
        spiral.triangles.push_back({2 * k, 2 * k + 3, 2 * k + 2});
      }
      spiral.surfaces.assign(spiral.triangles.size(), 0);
      run("spiral" + tag, spiral, 2);
    }
    // Random soups: almost always declined.
    run("lattice soup" + tag, lattice_soup(random, 10 + seed % 10, 6 + seed % 10, 3, 1.0), seed % 3);
  }
  // Both answers were exercised (106 certified, 494 declined, 261 of those with
  // no intersecting pair: the certificate is conservative, never wrong).
  CHECK(accepted > 80);
  CHECK(declined > 400);
  CHECK(declined_disjoint > 150);
}
