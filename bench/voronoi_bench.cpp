// shatter-bench-voronoi: Voronoi cells -> fragments (meshtree/voronoi.hpp) of the
// cube, curved corpus meshes and fandisk subdivided to 52k triangles at
// 10^2 .. 10^4 sites (10^5 with --max-sites): seconds, cells per second,
// fragments that fail validate_mesh as written, and the volume error of the
// meshes as written; the seconds of it spent gluing the
// internal nodes, their count, the tree's depth and the sets left unglued. One
// thread unless --threads says otherwise. A benchmark, not a test: it prints what
// it measured.
// With --manifold, Manifold (npm manifold-3d, bench/peers/manifold/voronoi.mjs)
// cuts the same cells in the same run: this writes the cells shatter cuts
// (voronoi_cell_planes: the same quantized sites, Delaunay neighbours and exact
// bisectors) to a file, and the peer trims the input by each cell's planes and
// splits the result into components. voro++, the cell peer, is not among
// this machine's Debian packages; the cells here are shatter's, and computing
// them is not part of the peer's time (it is part of shatter's).
//
//   shatter-bench-voronoi [--quick] [--max-sites N] [--threads T] [--manifold] [--repeat R]

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <unistd.h>

#include "shatter/generators/corpus.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/validate.hpp"
#include "shatter/meshtree/sites.hpp"
#include "shatter/meshtree/voronoi.hpp"
#include "bench_support.hpp"

using namespace shatter;
namespace fs = std::filesystem;

namespace {

struct PeerResult {
  double seconds = NAN;  ///< median of its repeats
  std::size_t fragments = 0, bad = 0;
  double volume_error = NAN;
  std::string failure;  ///< empty when it ran
};

/// Writes the cells' planes in the format voronoi.mjs reads (shortest
/// round-trip decimals, so the peer gets the same doubles).
void write_cells(const fs::path& path, const VoronoiCellPlanes& cells) {
  std::ofstream out(path);
  out << "cells " << cells.cells.size() << '\n';
  char line[160];
  for (const std::vector<Plane>& planes : cells.cells) {
    out << "cell " << planes.size() << '\n';
    for (const Plane& p : planes) {
      std::snprintf(line, sizeof line, "%.17g %.17g %.17g %.17g\n", p.normal.x, p.normal.y, p.normal.z, p.offset);
      out << line;
    }
  }
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

/// Runs the peer on `mesh_file` and `cells_file`; its one JSON object read from stdout.
PeerResult run_manifold(const fs::path& mesh_file, const fs::path& cells_file, int repeat, const fs::path& scratch) {
  PeerResult result;
  const fs::path script = fs::path(SHATTER_SOURCE_DIR) / "bench/peers/manifold/voronoi.mjs";
  if (!fs::exists(script.parent_path() / "node_modules" / "manifold-3d")) {
    result.failure = "manifold-3d not installed (npm ci in " + script.parent_path().string() + ")";
    return result;
  }
  const fs::path errors = scratch / "peer-stderr.txt";
  const std::string command = "node '" + script.string() + "' --mesh '" + mesh_file.string() + "' --cells '" +
                              cells_file.string() + "' --repeat " + std::to_string(repeat) + " --json 2>'" +
                              errors.string() + "'";
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) {
    result.failure = "cannot start node";
    return result;
  }
  std::string out;
  char buffer[4096];
  for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0;) out.append(buffer, n);
  const int status = ::pclose(pipe);
  if (status != 0) {
    std::ifstream err(errors);
    std::string first;
    std::getline(err, first);
    result.failure = "exit status " + std::to_string(status) + (first.empty() ? "" : ": " + first);
    return result;
  }
  try {
    const nlohmann::json j = nlohmann::json::parse(out);
    result.seconds = j.at("seconds").at("median");
    result.fragments = j.at("fragments");
    result.bad = j.at("bad_pieces");
    result.volume_error = std::fabs(j.at("volume_relative_error").get<double>());
  } catch (const std::exception& e) {
    result.failure = std::string("unreadable output: ") + e.what();
  }
  return result;
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false, manifold = false;
  std::size_t max_sites = 10000;
  unsigned threads = 1;
  int repeat = 1;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--quick") {
      quick = true;
    } else if (arg == "--manifold") {
      manifold = true;
    } else if (arg == "--max-sites" && i + 1 < argc) {
      max_sites = std::strtoull(argv[++i], nullptr, 10);
    } else if (arg == "--threads" && i + 1 < argc) {
      threads = static_cast<unsigned>(std::strtoul(argv[++i], nullptr, 10));
    } else if (arg == "--repeat" && i + 1 < argc) {
      repeat = std::max(1, std::atoi(argv[++i]));
    } else {
      std::fprintf(stderr,
                   "usage: shatter-bench-voronoi [--quick] [--max-sites N] [--threads T] [--manifold] [--repeat R]\n"
                   "  --manifold  also time Manifold (bench/peers/manifold/voronoi.mjs, needs node and npm ci there)\n"
                   "              cutting the same cells, and print the ratio of its seconds to shatter's\n"
                   "  --repeat R  run each row R times (shatter and the peer) and report the medians\n");
      return 2;
    }
  }
  // "fandiskx4.off": fandisk.off subdivided once by edge midpoints (51,784
  // triangles), the size of issue 22's target (10^4 fragments of a 50k-triangle
  // solid in 2 s on one thread).
  const std::vector<std::string> meshes =
      quick ? std::vector<std::string>{"cube.off"}
            : std::vector<std::string>{"cube.off", "elephant.off", "knot1.off", "fandisk.off", "fandiskx4.off"};
  const fs::path scratch = fs::temp_directory_path() / ("shatter-bench-voronoi-" + std::to_string(::getpid()));
  if (manifold) fs::create_directories(scratch);
  std::printf("%-14s %9s %7s %9s %9s %10s %8s %14s %8s %8s %6s %8s %9s", "mesh", "triangles", "sites", "fragments", "seconds",
              "cells/s", "invalid", "volume error", "glue s", "internal", "depth", "unglued", "assembled");
  if (manifold) std::printf(" %10s %10s %10s %8s", "manifold s", "m. frags", "m. vol err", "ratio");
  std::printf("\n");
  for (const std::string& name : meshes) {
    const bool subdivided = name == "fandiskx4.off";
    fs::path mesh_file = test::mesh_dir() / (subdivided ? "fandisk.off" : name);
    const Mesh mesh = subdivided ? bench::subdivide_midpoints(read_mesh(mesh_file)) : read_mesh(mesh_file);
    if (subdivided && manifold) {
      // The peer reads the mesh from a file.
      mesh_file = scratch / "fandiskx4.off";
      write_mesh(mesh, mesh_file, MeshFormat::off);
    }
    for (std::size_t sites_count = 100; sites_count <= (quick ? 100 : max_sites); sites_count *= 10) {
      const std::vector<Vec3> sites = uniform_sites(mesh, static_cast<std::uint32_t>(sites_count), 1);
      TreeRecipe recipe;
      recipe.strategy = Strategy::voronoi;
      BuildRunOptions run;
      run.threads = threads;
      std::vector<double> times;
      MeshTree tree;
      VoronoiReport report;
      for (int r = 0; r < repeat; ++r) {
        const auto start = std::chrono::steady_clock::now();
        tree = build_voronoi_tree(mesh, sites, recipe, run, &report);
        times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
      }
      std::sort(times.begin(), times.end());
      const double seconds = times[times.size() / 2];
      std::size_t invalid = 0;
      double volume = 0;
      std::uint32_t depth = 0;
      for (const MeshTreeNode& node : tree.nodes) depth = std::max(depth, node.depth);
      for (LeafIndex leaf = 0; leaf < tree.leaf_count(); ++leaf) {
        if (!validate_mesh(tree.leaf(leaf).mesh).valid()) ++invalid;
        volume += tree.leaf(leaf).mass.volume;
      }
      const double error = std::fabs(volume - tree.nodes[0].mass.volume) / tree.nodes[0].mass.volume;
      std::printf("%-14s %9zu %7zu %9zu %9.3f %10.0f %8zu %14.3g %8.3f %8zu %6u %8zu %9zu", name.c_str(), mesh.triangles.size(),
                  sites_count, tree.leaf_count(), seconds, static_cast<double>(sites_count) / seconds, invalid, error,
                  report.seconds_glue, tree.nodes.size() - tree.leaf_count(), depth, report.sets_unglued,
                  report.cells_assembled);
      if (manifold) {
        const fs::path cells_file = scratch / "cells.txt";
        write_cells(cells_file, voronoi_cell_planes(mesh, sites));
        const PeerResult peer = run_manifold(mesh_file, cells_file, repeat, scratch);
        if (peer.failure.empty()) {
          std::printf(" %10.3f %10zu %10.3g %7.1fx", peer.seconds, peer.fragments, peer.volume_error, peer.seconds / seconds);
          if (peer.bad > 0) std::printf(" (%zu bad)", peer.bad);
        } else {
          std::printf(" manifold: %s", peer.failure.c_str());
        }
      }
      std::printf("\n");
      std::fflush(stdout);
    }
  }
  if (manifold) fs::remove_all(scratch);
  return 0;
}
