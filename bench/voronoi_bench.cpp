// shatter-bench-voronoi: Voronoi cells -> fragments (meshtree/voronoi.hpp) of the
// cube, curved corpus meshes and fandisk subdivided to 52k triangles at
// 10^2 .. 10^4 sites (10^5 with --max-sites): seconds, cells per second,
// fragments that fail validate_mesh as written, and the volume error of the
// meshes as written; the seconds of it spent making the fragments (the sites
// quantized and triangulated, the cells cut or assembled, each fragment rounded
// and certified: VoronoiReport::seconds_cells) and gluing the internal nodes,
// their count, the tree's depth and the sets left unglued. One thread unless
// --threads says otherwise. A benchmark, not a test: it prints what it measured.
// With --manifold, Manifold (npm manifold-3d, bench/peers/manifold/voronoi.mjs)
// cuts cells in the same run: the peer trims the input by each cell's planes
// and splits the result into components. By default the cells are the ones
// shatter cuts (voronoi_cell_planes: the same quantized sites, Delaunay
// neighbours and exact bisectors), and computing them is not in the peer's
// time. With --voro they are voro++'s (Debian voro++-dev, the cell library the
// issue names), computed from the same sites in double precision, and the
// peer's time is voro++'s plus Manifold's: the pipeline of the tools that build
// cells and then intersect the mesh per cell. --voro alone times voro++'s cells.
// With --cgal, CGAL 5.5's PMP::clip on Surface_mesh<Epick> cuts the same cells
// (voro++'s with --voro), the input clipped by each cell as one closed mesh
// (bench_support.hpp, clip_cells_with_cgal_isolated), in a forked child under a
// time limit, since clip can hang or crash: "where it finishes", as the issue
// asks. Its time is added to voro++'s with --voro.
//
//   shatter-bench-voronoi [--quick] [--max-sites N] [--threads T] [--manifold] [--voro] [--cgal]
//                         [--cgal-timeout S] [--repeat R] [--meshes cube.off,elephant.off,...]

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <unistd.h>

#if SHATTER_WITH_VOROPP
#include <voro++/voro++.hh>
#endif

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
void write_cells(const fs::path& path, const std::vector<std::vector<Plane>>& cells) {
  std::ofstream out(path);
  out << "cells " << cells.size() << '\n';
  char line[160];
  for (const std::vector<Plane>& planes : cells) {
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

/// Cells computed by voro++ for the peer pipeline (--voro).
struct VoroCells {
  std::vector<std::vector<Plane>> cells;  ///< per site, its cell's planes, nearest first; each <= 0 inside
  double seconds = 0;                      ///< voro++'s time: the container, the cells and their faces read
  std::size_t failed = 0;                  ///< sites voro++ computed no cell for
  std::string failure;                     ///< why there are no cells (a build without voro++)
};

#if SHATTER_WITH_VOROPP
/// The Voronoi cells of `sites` by voro++: its container is the mesh's box
/// grown by a tenth (so every site is in it and the walls lie outside the
/// solid, whose faces on the walls are then left out: they cut nothing), with
/// about five sites per block, voro++'s advice for its grid. Each face of a cell
/// gives the plane through its first vertex with the face's normal, which
/// voro++ gives outward; the planes come nearest to the site first, as
/// voronoi_cell_planes orders its bisectors, so the peer trims in that order.
VoroCells voropp_cells(const Mesh& mesh, const std::vector<Vec3>& sites) {
  VoroCells result;
  const auto start = std::chrono::steady_clock::now();
  const auto [lo, hi] = bench::grown_box(mesh, 0.1);
  const Vec3 extent = hi - lo;
  const double block = std::cbrt(extent.x * extent.y * extent.z * 5 / static_cast<double>(sites.size()));
  const auto blocks = [&](double length) { return std::max(1, static_cast<int>(std::lround(length / block))); };
  voro::container container(lo.x, hi.x, lo.y, hi.y, lo.z, hi.z, blocks(extent.x), blocks(extent.y), blocks(extent.z),
                            false, false, false, 8);
  for (std::size_t i = 0; i < sites.size(); ++i) container.put(static_cast<int>(i), sites[i].x, sites[i].y, sites[i].z);
  result.cells.resize(sites.size());
  voro::c_loop_all loop(container);
  voro::voronoicell_neighbor cell;
  std::vector<int> neighbours, face_vertices;
  std::vector<double> normals, vertices;
  std::vector<std::pair<double, Plane>> planes;
  std::size_t computed = 0;
  if (loop.start()) {
    do {
      if (!container.compute_cell(cell, loop)) continue;
      ++computed;
      double x, y, z;
      loop.pos(x, y, z);
      const Vec3 site{x, y, z};
      cell.neighbors(neighbours);
      cell.normals(normals);
      cell.face_vertices(face_vertices);
      cell.vertices(x, y, z, vertices);
      planes.clear();
      std::size_t at = 0;  // face_vertices: per face, its vertex count, then its vertices
      for (std::size_t f = 0; f < neighbours.size(); ++f) {
        const auto first = static_cast<std::size_t>(face_vertices[at + 1]);
        at += static_cast<std::size_t>(face_vertices[at]) + 1;
        const Vec3 normal{normals[3 * f], normals[3 * f + 1], normals[3 * f + 2]};
        if (neighbours[f] < 0 || (normal.x == 0 && normal.y == 0 && normal.z == 0)) continue;  // a wall, a degenerate face
        const Vec3 corner{vertices[3 * first], vertices[3 * first + 1], vertices[3 * first + 2]};
        const Plane plane{normal, -dot(normal, corner)};
        planes.push_back({-(dot(normal, site) + plane.offset), plane});  // the site's distance to it
      }
      std::sort(planes.begin(), planes.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
      std::vector<Plane>& out = result.cells[static_cast<std::size_t>(loop.pid())];
      for (const auto& [distance, plane] : planes) out.push_back(plane);
    } while (loop.inc());
  }
  result.failed = sites.size() - computed;
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}
#else
VoroCells voropp_cells(const Mesh&, const std::vector<Vec3>&) {
  VoroCells result;
  result.failure = "this benchmark was built without voro++ (apt-get install voro++-dev, then configure again)";
  return result;
}
#endif

}  // namespace

int main(int argc, char** argv) {
  bool quick = false, manifold = false, voro = false, cgal = false;
  double cgal_timeout = 60;
  std::string only;  // --meshes: a comma-separated subset of the rows' meshes
  std::size_t max_sites = 10000;
  unsigned threads = 1;
  int repeat = 1;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--quick") {
      quick = true;
    } else if (arg == "--manifold") {
      manifold = true;
    } else if (arg == "--voro") {
      voro = true;
    } else if (arg == "--cgal") {
      cgal = true;
    } else if (arg == "--cgal-timeout" && i + 1 < argc && std::atof(argv[i + 1]) > 0) {
      cgal_timeout = std::atof(argv[++i]);
    } else if (arg == "--meshes" && i + 1 < argc) {
      only = argv[++i];
    } else if (arg == "--max-sites" && i + 1 < argc) {
      max_sites = std::strtoull(argv[++i], nullptr, 10);
    } else if (arg == "--threads" && i + 1 < argc) {
      threads = static_cast<unsigned>(std::strtoul(argv[++i], nullptr, 10));
    } else if (arg == "--repeat" && i + 1 < argc) {
      repeat = std::max(1, std::atoi(argv[++i]));
    } else {
      std::fprintf(stderr,
                   "usage: shatter-bench-voronoi [--quick] [--max-sites N] [--threads T] [--manifold] [--voro] [--cgal]\n"
                   "                             [--cgal-timeout S] [--repeat R]\n"
                   "                             [--meshes cube.off,elephant.off,knot1.off,fandisk.off,fandiskx4.off]\n"
                   "  --manifold  also time Manifold (bench/peers/manifold/voronoi.mjs, needs node and npm ci there)\n"
                   "              cutting the same cells, and print the ratio of its seconds (with --voro, voro++'s\n"
                   "              plus its) to shatter's\n"
                   "  --voro      the peer's cells from voro++ (voro++-dev), its seconds added to Manifold's;\n"
                   "              without --manifold, voro++'s cells alone are timed\n"
                   "  --cgal      also time CGAL 5.5 PMP::clip cutting the same cells (voro++'s with --voro), in a\n"
                   "              child process given --cgal-timeout seconds (default 60) a row; its fragments are\n"
                   "              checked (closed, no self-intersection, positive volume) after the clock\n"
                   "  --repeat R  run each row R times (shatter and the peer) and report the medians\n");
      return 2;
    }
  }
  // "fandiskx4.off": fandisk.off subdivided once by edge midpoints (51,784
  // triangles), the size of issue 22's target (10^4 fragments of a 50k-triangle
  // solid in 2 s on one thread).
  std::vector<std::string> meshes =
      quick ? std::vector<std::string>{"cube.off"}
            : std::vector<std::string>{"cube.off", "elephant.off", "knot1.off", "fandisk.off", "fandiskx4.off"};
  if (!only.empty()) {
    const std::string list = "," + only + ",";
    std::erase_if(meshes, [&](const std::string& name) { return list.find("," + name + ",") == std::string::npos; });
    if (meshes.empty()) {
      std::fprintf(stderr, "--meshes %s names none of cube.off, elephant.off, knot1.off, fandisk.off, fandiskx4.off\n",
                   only.c_str());
      return 2;
    }
  }
  const fs::path scratch = fs::temp_directory_path() / ("shatter-bench-voronoi-" + std::to_string(::getpid()));
  if (manifold) fs::create_directories(scratch);
  std::printf("%-14s %9s %7s %9s %9s %10s %8s %14s %8s %8s %8s %6s %8s %9s", "mesh", "triangles", "sites", "fragments",
              "seconds", "cells/s", "invalid", "volume error", "cells s", "glue s", "internal", "depth", "unglued",
              "assembled");
  if (voro) std::printf(" %9s %8s", "voro++ s", "v. cells");
  if (manifold) std::printf(" %10s %10s %10s %8s", "manifold s", "m. frags", "m. vol err", "ratio");
  if (cgal) std::printf(" %9s %8s %9s %10s %8s", "cgal s", "c. frags", "c. invalid", "c. vol err", "ratio");
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
      std::printf("%-14s %9zu %7zu %9zu %9.3f %10.0f %8zu %14.3g %8.3f %8.3f %8zu %6u %8zu %9zu", name.c_str(),
                  mesh.triangles.size(), sites_count, tree.leaf_count(), seconds, static_cast<double>(sites_count) / seconds,
                  invalid, error, report.seconds_cells, report.seconds_glue, tree.nodes.size() - tree.leaf_count(), depth,
                  report.sets_unglued, report.cells_assembled);
      double cell_seconds = 0;  // the peer's cells' time: voro++'s, or none (shatter's cells)
      std::vector<std::vector<Plane>> cells;
      if (voro) {
        std::vector<double> voro_times;
        VoroCells computed;
        for (int r = 0; r < repeat; ++r) {
          computed = voropp_cells(mesh, sites);
          voro_times.push_back(computed.seconds);
        }
        if (!computed.failure.empty()) {
          std::printf(" voro++: %s\n", computed.failure.c_str());
          return 1;
        }
        std::sort(voro_times.begin(), voro_times.end());
        cell_seconds = voro_times[voro_times.size() / 2];
        // Each site strictly inside its own cell, bounded by four planes or
        // more: what the faces were read as (outward normals, offsets through a
        // corner) must at least give that.
        std::size_t misread = 0;
        for (std::size_t i = 0; i < computed.cells.size(); ++i) {
          const std::vector<Plane>& planes = computed.cells[i];
          bool inside = planes.size() >= 4 || planes.empty();  // empty: a cell walls alone bound (one site)
          for (const Plane& plane : planes) inside = inside && dot(plane.normal, sites[i]) + plane.offset < 0;
          if (!inside) ++misread;
        }
        if (misread > 0) {
          std::printf(" voro++: %zu cells do not hold their site strictly inside\n", misread);
          return 1;
        }
        std::printf(" %9.3f %8zu", cell_seconds, sites.size() - computed.failed);
        cells = std::move(computed.cells);
      }
      // Without voro++, the peers cut shatter's cells, around its quantized sites.
      std::vector<Vec3> quantized_sites;
      std::span<const Vec3> cell_sites = sites;  // a point strictly inside each cell, for the CGAL peer
      if (!voro && (manifold || cgal)) {
        VoronoiCellPlanes shatter_cells = voronoi_cell_planes(mesh, sites);
        cells = std::move(shatter_cells.cells);
        quantized_sites = std::move(shatter_cells.quantized.sites);
        cell_sites = quantized_sites;
      }
      if (manifold) {
        const fs::path cells_file = scratch / "cells.txt";
        write_cells(cells_file, cells);
        const PeerResult peer = run_manifold(mesh_file, cells_file, repeat, scratch);
        if (peer.failure.empty()) {
          const double pipeline = cell_seconds + peer.seconds;
          std::printf(" %10.3f %10zu %10.3g %7.1fx", peer.seconds, peer.fragments, peer.volume_error, pipeline / seconds);
          if (peer.bad > 0) std::printf(" (%zu bad)", peer.bad);
        } else {
          std::printf(" manifold: %s", peer.failure.c_str());
        }
      }
      if (cgal) {
        bench::ReplayLimits limits;
        limits.timeout_seconds = cgal_timeout;
        const bench::CellClipResult peer = bench::clip_cells_with_cgal_isolated(mesh, cells, cell_sites, limits);
        if (peer.status == bench::PeerResult::Status::ok) {
          const double input_volume = tree.nodes[0].mass.volume;
          std::printf(" %9.3f %8zu %9ld %10.3g %7.1fx", peer.clip_seconds, peer.fragments, peer.invalid,
                      std::fabs(peer.volume - input_volume) / input_volume, (cell_seconds + peer.clip_seconds) / seconds);
          if (peer.failed_clips + peer.threw > 0) std::printf(" (%zu cells failed, %zu threw)", peer.failed_clips, peer.threw);
        } else {
          std::printf(" cgal: %s", peer.detail.c_str());
        }
      }
      std::printf("\n");
      std::fflush(stdout);
    }
  }
  if (manifold) fs::remove_all(scratch);
  return 0;
}
