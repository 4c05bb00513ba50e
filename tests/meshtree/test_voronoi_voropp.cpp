// Voronoi fragments against voro++ (Debian voro++-dev), a Voronoi library that
// shares no code with shatter and computes in doubles. The cube is convex, so
// each cell meets it in one piece, and with voro++'s container the cube itself
// the fragments are exactly voro++'s cells: every fragment's volume is its cell's
// volume, and the bonds are voro++'s pairs of neighbouring cells, with their
// faces' areas. Both are compared within what voro++'s doubles can be off
// (1e-12 on a cube of side 2), over uniform sites, a regular and a jittered
// lattice and sites all in one plane; shatter's exactness itself is tested in
// test_voronoi (volumes summing exactly, bonds against an exact brute force).
// Built only where CMake finds voro++ (tests/meshtree/CMakeLists.txt).

#include <catch2/catch.hpp>
#include <voro++/voro++.hh>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include "shatter/generators/corpus.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/meshtree/build.hpp"
#include "shatter/meshtree/sites.hpp"
#include "shatter/meshtree/voronoi.hpp"

using namespace shatter;

namespace {

// The largest differences measured when this was written: 2.5e-16 in a volume,
// 7.1e-16 in an area.
constexpr double tolerance = 1e-12;

struct VoroppCell {
  double volume = 0;
  std::map<std::uint32_t, double> neighbour_area;  ///< by neighbouring site, the shared face's area
};

// voro++'s cells of `sites` in the box [lo, hi] (its walls are the box's faces).
std::vector<VoroppCell> voropp_cells(const std::vector<Vec3>& sites, const Vec3& lo, const Vec3& hi) {
  const int blocks = std::max(1, static_cast<int>(std::cbrt(static_cast<double>(sites.size()) / 5)));
  voro::container container(lo.x, hi.x, lo.y, hi.y, lo.z, hi.z, blocks, blocks, blocks, false, false, false, 8);
  for (std::size_t i = 0; i < sites.size(); ++i) container.put(static_cast<int>(i), sites[i].x, sites[i].y, sites[i].z);
  std::vector<VoroppCell> cells(sites.size());
  voro::c_loop_all loop(container);
  voro::voronoicell_neighbor cell;
  std::vector<int> neighbours;
  std::vector<double> areas;
  if (loop.start()) {
    do {
      REQUIRE(container.compute_cell(cell, loop));
      VoroppCell& out = cells[static_cast<std::size_t>(loop.pid())];
      out.volume = cell.volume();
      cell.neighbors(neighbours);
      cell.face_areas(areas);
      for (std::size_t f = 0; f < neighbours.size(); ++f) {
        if (neighbours[f] >= 0) out.neighbour_area[static_cast<std::uint32_t>(neighbours[f])] += areas[f];
      }
    } while (loop.inc());
  }
  return cells;
}

}  // namespace

TEST_CASE("the cube's Voronoi fragments are voro++'s cells: volumes and bonds", "[voronoi][voro++]") {
  const Mesh cube = read_mesh(test::mesh_dir() / "cube.off");
  Vec3 lo = cube.positions.front(), hi = lo;
  for (const Vec3& p : cube.positions) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  std::size_t volumes = 0, bonds = 0, expected_volumes = 0;
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    // Uniform sites; a regular lattice (cells meeting eight at a point: diagonal
    // neighbours touch along an edge or at a point, with no bond) and a
    // jittered one; sites all in one plane (the radial pattern: prisms through
    // the cube).
    std::vector<std::pair<const char*, std::vector<Vec3>>> site_sets{
        {"uniform", uniform_sites(cube, 40, seed)},
        {"uniform", uniform_sites(cube, 250, seed)},
        {"jittered grid", grid_sites(cube, {6, 5, 4}, false, 0.0, 0.3, seed)},
        {"radial", radial_sites({0.1, -0.05, 0}, {0.2, 0.1, 1}, 3, 7, 0.6, 0.4, seed)}};
    if (seed == 1) site_sets.push_back({"regular grid", grid_sites(cube, {5, 4, 3}, false, 0.0, 0.0, seed)});
    for (const auto& [pattern, given] : site_sets) {
      // The sites the cells are made of (quantized onto the bisector-exact grid).
      const std::vector<Vec3> sites = voronoi_cell_planes(cube, given).quantized.sites;
      TreeRecipe recipe;
      recipe.strategy = Strategy::voronoi;
      BuildRunOptions run;
      run.threads = 1;
      const MeshTree tree = build_voronoi_tree(cube, given, recipe, run);
      const std::vector<VoroppCell> cells = voropp_cells(sites, lo, hi);
      INFO("seed " << seed << ", " << pattern << ", " << sites.size() << " sites");
      REQUIRE(tree.leaf_count() == sites.size());
      expected_volumes += sites.size();

      // Each fragment's site: the one nearest its centroid, which lies inside
      // its convex cell. Every site has one fragment, of its cell's volume.
      std::vector<std::uint32_t> site_of_leaf(tree.leaf_count());
      std::vector<int> fragments_of_site(sites.size(), 0);
      for (LeafIndex leaf = 0; leaf < tree.leaf_count(); ++leaf) {
        const Vec3 c = tree.leaf(leaf).mass.centroid;
        std::uint32_t nearest = 0;
        for (std::uint32_t s = 1; s < sites.size(); ++s) {
          if (dot(sites[s] - c, sites[s] - c) < dot(sites[nearest] - c, sites[nearest] - c)) nearest = s;
        }
        site_of_leaf[leaf] = nearest;
        ++fragments_of_site[nearest];
        CHECK(std::fabs(tree.leaf(leaf).mass.volume - cells[nearest].volume) <= tolerance);
        ++volumes;
      }
      CHECK(std::count(fragments_of_site.begin(), fragments_of_site.end(), 1) == static_cast<long>(sites.size()));

      // The bonds are voro++'s neighbour pairs, with their faces' areas; a face
      // of voro++ too small to tell from its rounding may be missing either way.
      std::map<std::pair<std::uint32_t, std::uint32_t>, double> ours;
      for (const Bond& bond : tree.bonds) {
        std::uint32_t a = site_of_leaf[bond.first], b = site_of_leaf[bond.second];
        if (a > b) std::swap(a, b);
        ours[{a, b}] += bond.area;
      }
      for (std::uint32_t a = 0; a < sites.size(); ++a) {
        for (const auto& [b, area] : cells[a].neighbour_area) {
          if (b <= a) continue;
          const auto found = ours.find({a, b});
          INFO("sites " << a << " and " << b << ": voro++'s face " << area);
          if (found == ours.end()) {
            CHECK(area <= tolerance);
            continue;
          }
          CHECK(std::fabs(found->second - area) <= tolerance);
          ++bonds;
        }
      }
      for (const auto& [pair, area] : ours) {
        const auto& theirs = cells[pair.first].neighbour_area;
        INFO("sites " << pair.first << " and " << pair.second << ": our bond " << area);
        if (theirs.find(pair.second) == theirs.end()) CHECK(area <= tolerance);
      }
    }
  }
  CHECK(volumes == expected_volumes);
  CHECK(bonds > 5000);
}
