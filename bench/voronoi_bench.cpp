// shatter-bench-voronoi: Voronoi cells -> fragments (meshtree/voronoi.hpp) of the
// cube and curved corpus meshes at 10^2 .. 10^4 sites (10^5 with --max-sites):
// seconds, cells per second, fragments that fail validate_mesh as written, and
// the volume error of the meshes as written; the seconds of it spent gluing the
// internal nodes, their count, the tree's depth and the sets left unglued. One thread unless --threads says
// otherwise. A benchmark, not a test: it prints what it measured.
// No peer runs beside it yet (voro++ is not among this machine's Debian packages).
//
//   shatter-bench-voronoi [--quick] [--max-sites N] [--threads T]

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "shatter/generators/corpus.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/validate.hpp"
#include "shatter/meshtree/sites.hpp"
#include "shatter/meshtree/voronoi.hpp"

using namespace shatter;

int main(int argc, char** argv) {
  bool quick = false;
  std::size_t max_sites = 10000;
  unsigned threads = 1;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--quick") {
      quick = true;
    } else if (arg == "--max-sites" && i + 1 < argc) {
      max_sites = std::strtoull(argv[++i], nullptr, 10);
    } else if (arg == "--threads" && i + 1 < argc) {
      threads = static_cast<unsigned>(std::strtoul(argv[++i], nullptr, 10));
    } else {
      std::fprintf(stderr, "usage: shatter-bench-voronoi [--quick] [--max-sites N] [--threads T]\n");
      return 2;
    }
  }
  const std::vector<std::string> meshes = quick ? std::vector<std::string>{"cube.off"}
                                                : std::vector<std::string>{"cube.off", "elephant.off", "knot1.off", "fandisk.off"};
  std::printf("%-14s %9s %7s %9s %9s %10s %8s %14s %8s %8s %6s %8s\n", "mesh", "triangles", "sites", "fragments", "seconds",
              "cells/s", "invalid", "volume error", "glue s", "internal", "depth", "unglued");
  for (const std::string& name : meshes) {
    const Mesh mesh = read_mesh(test::mesh_dir() / name);
    for (std::size_t sites_count = 100; sites_count <= (quick ? 100 : max_sites); sites_count *= 10) {
      const std::vector<Vec3> sites = uniform_sites(mesh, static_cast<std::uint32_t>(sites_count), 1);
      TreeRecipe recipe;
      recipe.strategy = Strategy::voronoi;
      BuildRunOptions run;
      run.threads = threads;
      const auto start = std::chrono::steady_clock::now();
      VoronoiReport report;
      const MeshTree tree = build_voronoi_tree(mesh, sites, recipe, run, &report);
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      std::size_t invalid = 0;
      double volume = 0;
      std::uint32_t depth = 0;
      for (const MeshTreeNode& node : tree.nodes) depth = std::max(depth, node.depth);
      for (LeafIndex leaf = 0; leaf < tree.leaf_count(); ++leaf) {
        if (!validate_mesh(tree.leaf(leaf).mesh).valid()) ++invalid;
        volume += tree.leaf(leaf).mass.volume;
      }
      const double error = std::fabs(volume - tree.nodes[0].mass.volume) / tree.nodes[0].mass.volume;
      std::printf("%-14s %9zu %7zu %9zu %9.3f %10.0f %8zu %14.3g %8.3f %8zu %6u %8zu\n", name.c_str(), mesh.triangles.size(),
                  sites_count, tree.leaf_count(), seconds, static_cast<double>(sites_count) / seconds, invalid, error,
                  report.seconds_glue, tree.nodes.size() - tree.leaf_count(), depth, report.sets_unglued);
      std::fflush(stdout);
    }
  }
  return 0;
}
