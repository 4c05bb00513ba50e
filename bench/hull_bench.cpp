// shatter-bench-hulls: the convex hulls of a written tree's non-convex nodes,
// computed again from the points the builder gives them (a leaf's mesh
// vertices; an internal node's children's hull vertices, or a convex child's
// mesh vertices, as meshtree/src/tree_hulls.cpp does), on one thread, and
// compared with the hulls the file stores (bit for bit: any difference exits 1).
// Reports the points, the hull vertices, the seconds and the orient3d calls, how
// many the floating-point filter left to exact arithmetic, how many of those the
// integer stage decided, and how many the adaptive stages left to the full
// expansion: the figures behind quickhull's changes (README "Smaller costs of
// `fracture`"). A benchmark, not a test.
//
//   ./build/cli/shatter fracture MESH --fragments N --out t.shatter
//   ./build/bench/shatter-bench-hulls t.shatter [repetitions=3]

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <utility>
#include <vector>

#include "shatter/cut/hull.hpp"
#include "shatter/formats/file.hpp"
#include "shatter/kernel/predicates.hpp"
#include "shatter/meshtree/tree.hpp"

int main(int argc, char** argv) {
  if (argc < 2 || argc > 3 || (argc == 3 && std::atoi(argv[2]) <= 0)) {
    std::fprintf(stderr, "usage: shatter-bench-hulls FILE.shatter [repetitions > 0]\n");
    return 2;
  }
  const int repetitions = argc == 3 ? std::atoi(argv[2]) : 3;
  try {
    const shatter::MeshTree tree = shatter::read_shatter_file(argv[1]);
    shatter::NodeShapes shapes(tree);
    std::vector<std::vector<shatter::Vec3>> inputs;
    std::vector<const shatter::Mesh*> stored;
    for (shatter::NodeIndex v = 0; v < tree.nodes.size(); ++v) {
      const shatter::MeshTreeNode& node = tree.nodes[v];
      if (node.convex) continue;
      std::vector<shatter::Vec3> points;
      if (node.is_leaf()) {
        points = shapes.mesh(v).positions;
      } else {
        for (const shatter::NodeIndex c : node.children) {
          const shatter::Mesh& hull = tree.nodes[c].convex ? shapes.mesh(c) : *tree.nodes[c].hull;
          points.insert(points.end(), hull.positions.begin(), hull.positions.end());
        }
      }
      inputs.push_back(std::move(points));
      stored.push_back(&*node.hull);
    }
    std::size_t points = 0, hull_vertices = 0, differing = 0;
    shatter::predicate_counters() = {};
    const auto start = std::chrono::steady_clock::now();
    for (int r = 0; r < repetitions; ++r) {
      for (std::size_t i = 0; i < inputs.size(); ++i) {
        const shatter::Mesh hull = shatter::convex_hull_of_points(inputs[i]);
        if (r > 0) continue;
        points += inputs[i].size();
        hull_vertices += hull.positions.size();
        differing += hull.positions != stored[i]->positions || hull.triangles != stored[i]->triangles;
      }
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / repetitions;
    const shatter::PredicateCounters& counts = shatter::predicate_counters();
    std::printf("| hulls | points | hull vertices | seconds (mean of %d) | orient3d calls | past the filter | on integers | full expansion | differing from the file |\n"
                "|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n"
                "| %zu | %zu | %zu | %.3f | %llu | %llu | %llu | %llu | %zu |\n",
                repetitions, inputs.size(), points, hull_vertices, seconds,
                static_cast<unsigned long long>(counts.orient3d_calls / repetitions),
                static_cast<unsigned long long>(counts.orient3d_expansion / repetitions),
                static_cast<unsigned long long>(counts.orient3d_integer / repetitions),
                static_cast<unsigned long long>(counts.orient3d_full / repetitions), differing);
    return differing == 0 ? 0 : 1;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "shatter-bench-hulls: %s\n", error.what());
    return 1;
  }
}
