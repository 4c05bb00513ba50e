// shatter-bench-plane: the project's performance targets (issue item 7) measured
// on the plane kernel, one thread, every row with its peers in the same run.
//
// Rows: the unit cube [-0.5,0.5]^3 (12 triangles) cut into 256, 65,536 and 2^20 =
// 1,048,576 fragments; knot1.off (tests/data/corpus, 6,400 triangles) subdivided by edge
// midpoints until it has >= 50,000 triangles (each triangle into 4, flat: 6,400 ->
// 25,600 -> 102,400) and fandisk.off from the test corpus
// subdivided once (12,946 -> 51,784 triangles, the solid the targets were set on),
// each cut into 256 and 65,536 fragments. Midpoint subdivision makes coplanar
// triangles, and the plane kernel merges coplanar edge-connected triangles of a
// mesh without attributes back into polygon faces (solid_from_mesh): the plane
// kernel cuts fewer input faces than the mesh has triangles, the column "plane
// faces" says how many (a midpoint that rounds off its edge keeps its triangles apart).
//
// shatter: build_mesh_tree with Strategy::thesis, seed 1 (--seed),
// threads = 1. The clock (std::chrono::steady_clock) runs around build_mesh_tree
// only: validating the input (with self-intersections), the cuts and mass
// properties, with every piece rounded to a certified valid double mesh as it is
// cut ("cut", BuildReport::cutting_seconds), the convex hulls of every node
// ("hulls") and the bonds
// ("bonds"); "other" is the rest of the total (the input check, with
// self-intersections, and the bookkeeping between the phases).
// Every run is a fresh forked child process, so every build starts from the same
// heap; the tree is destroyed after the clock stops. Runs are repeated until >= 3
// runs and >= 0.3 s (a run longer than 10 s is not repeated); every figure is the
// median over the runs (phases each their own median).
//   - µs/split (all levels) = median cut seconds / internal nodes (every split of
//     the tree, the top levels' big nodes included).
//   - µs/split (last level) = (cut seconds to N - cut seconds to N/2) / (internal
//     nodes to N - internal nodes to N/2): the marginal cost of the splits that
//     take the tree from N/2 to N fragments, i.e. the deepest level's splits (the
//     builder does not report per-level time, so this is a second build to N/2,
//     timed the same way; with the same seeds the N/2 tree is the top of the N
//     tree, up to where a cut leaves more than two pieces and shares differ).
//   - ns/output triangle = median total seconds / triangles of every node's mesh
//     (internal nodes included: the tree stores them all).
//   - peak MB = VmHWM of the child right after build_mesh_tree returned (tree
//     alive), first run; it includes the resident set inherited from the bench
//     (its VmRSS before the build, "baseline" in the CSV, a few MB after
//     malloc_trim), and the caption says how much that was at most.
//   - invalid leaves: validate_mesh (closed, oriented, manifold, positive volume,
//     no zero-area triangle, no self-intersection) on every leaf of the first run's
//     tree, outside the clock (or, with --validate-sample M, M evenly spaced leaves).
//
// Peer 1, Manifold 3.5.4 (npm manifold-3d, WebAssembly under Node, single thread):
// bench/peers/manifold/fracture.mjs --json, the same method (random plane through
// each piece's volume centroid, every connected component re-split, until N
// pieces), same seed, not the same planes (see that folder's README.md). Its time
// is its own (performance.now() around the fracture loop, after loading); median
// of --repeat 3 (1 above 65,536), within --manifold-timeout per repeat; its peak
// memory is the node process's ru_maxrss. The mesh goes to it through a temporary
// OFF file (shortest round-trip decimals: the same doubles). When node or
// node_modules is missing its cells say "not available".
//
// Peer 2, CGAL 5.5 PMP::clip(clip_volume(true)) on Surface_mesh<Epick>, replaying
// the very planes of the first run's tree (bench_support: replay_with_cgal_isolated,
// as shatter-bench-tree does) in a forked child with a wall-clock limit
// (--peer-timeout) and an address-space limit, for rows up to --cgal-max; its time
// is the sum of its clip and split_connected_components calls; a timeout is
// reported with the progress made.
//
// The machine is shared (2 cores): read the ratios measured in the same run.

#include <fcntl.h>
#include <malloc.h>
#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "bench_support.hpp"
#include "command_line.hpp"
#include "csv.hpp"
#include "shatter/generators/corpus.hpp"
#include "shatter/generators/solids.hpp"
#include "shatter/kernel/certify.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/mesh.hpp"
#include "shatter/kernel/validate.hpp"
#include "shatter/meshtree/build.hpp"
#include "shatter/cut/plane_input.hpp"
#include "shatter/meshtree/stats.hpp"
#include "shatter/meshtree/tree.hpp"

namespace {

using shatter::bench::CsvWriter;
using shatter::bench::csv_number;
using shatter::bench::fixed;
using shatter::bench::fork_flushed;
using shatter::bench::not_measured;
using shatter::bench::PeerResult;
using shatter::bench::ratio_text;
using shatter::bench::seconds_between;
using shatter::bench::seconds_text;
using shatter::bench::subdivide_midpoints;
using shatter::bench::wait_for_child;
using shatter::bench::with_thousands;
using shatter::bench::write_all;
using Clock = std::chrono::steady_clock;
using Json = nlohmann::json;
namespace fs = std::filesystem;

// ---------------------------------------------------------------------------
// Options.

struct Options {
  bool quick = false;
  std::optional<fs::path> csv;
  std::string rows;  ///< empty: the default rows
  std::optional<std::uint32_t> max_fragments;
  std::uint64_t seed = 1;
  fs::path mesh_dir = shatter::test::mesh_dir();
  fs::path knot = shatter::test::mesh_dir() / "knot1.off";
  fs::path manifold_script = SHATTER_SOURCE_DIR "/bench/peers/manifold/fracture.mjs";
  std::string node = "node";
  fs::path shatter_exe = SHATTER_EXE;  ///< the command timed end to end
  bool no_end_to_end = false;
  bool two_threads = false;  ///< also time `fracture --threads 2` against 1 thread, paired
  double manifold_timeout = 300;
  std::optional<int> manifold_repeat;
  bool no_manifold = false;
  double peer_timeout = 60;
  std::uint64_t peer_memory_mb = 8192;
  std::uint32_t cgal_max = 65536;
  bool no_cgal = false;
  bool no_peers = false;
  bool no_validate = false;
  std::uint32_t validate_sample = 0;  ///< 0: every leaf
  bool no_last_level = false;
  double no_repeat_seconds = 10;
};

struct Repeat {
  int min_runs = 3;
  double min_total_seconds = 0.3;
  int max_runs = 1000;
  double no_repeat_seconds = 10;
};

// ---------------------------------------------------------------------------
// Small helpers.

std::string number_text(double v, int digits) { return std::isnan(v) ? "–" : fixed(v, digits); }

double median_of(const std::vector<double>& v) { return shatter::bench::median(v, not_measured); }

/// A field of /proc/self/status in kB ("VmHWM", "VmRSS"); 0 when absent.
std::uint64_t proc_status_kb(const std::string& field) {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind(field + ":", 0) != 0) continue;
    std::istringstream in(line.substr(field.size() + 1));
    std::uint64_t kb = 0;
    in >> kb;
    return kb;
  }
  return 0;
}

/// Reads `fd` to its end.
std::string read_all(int fd) {
  std::string out;
  char buffer[65536];
  for (;;) {
    const ssize_t n = ::read(fd, buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    out.append(buffer, static_cast<std::size_t>(n));
  }
  return out;
}

std::string signal_text(int status) {
  return "signal " + std::to_string(WTERMSIG(status)) + " (" + ::strsignal(WTERMSIG(status)) + ")";
}

// ---------------------------------------------------------------------------
// Inputs.

struct Input {
  std::string key;           ///< used in row ids: cube, knot1x16, fandiskx4
  std::string name;          ///< for the tables
  std::string origin;        ///< where it comes from, for the notes
  shatter::Mesh mesh;
  std::size_t plane_faces = 0;  ///< faces of the plane kernel's input solid (coplanar triangles merged)
  bool available = false;
  std::string missing;  ///< why not, if not
};

Input make_cube() {
  Input in;
  in.key = "cube";
  in.name = "cube";
  in.origin = "[-0.5,0.5]^3, 12 triangles";
  in.mesh = shatter::test::box({-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5});
  in.available = true;
  return in;
}

/// `path` subdivided until it has at least `min_triangles` triangles.
Input make_subdivided(const std::string& stem, const fs::path& path, std::size_t min_triangles) {
  Input in;
  in.key = stem;
  if (!fs::exists(path)) {
    in.name = stem;
    in.missing = path.string() + " not found";
    return in;
  }
  shatter::Mesh mesh = shatter::read_mesh(path);
  const std::size_t original = mesh.triangle_count();
  int levels = 0;
  while (mesh.triangle_count() < min_triangles) {
    mesh = subdivide_midpoints(mesh);
    ++levels;
  }
  const int factor = 1 << (2 * levels);
  if (levels == 0) {
    in.name = path.filename().string();
    in.origin = path.filename().string() + " as it is (test corpus)";
  } else {
    in.key = stem + "x" + std::to_string(factor);
    in.name = path.filename().string() + " ×" + std::to_string(factor);
    in.origin = path.filename().string() + " (" + with_thousands(original) + " triangles) subdivided " +
                std::to_string(levels) + "× by edge midpoints";
  }
  in.mesh = std::move(mesh);
  in.available = true;
  return in;
}

// ---------------------------------------------------------------------------
// shatter: one build in a forked child.

/// What one run measured (the first run also checks its tree and runs the CGAL replay).
struct BuildRun {
  bool ok = false;
  std::string error;
  double seconds = not_measured;
  shatter::BuildReport report;
  std::size_t leaves = 0, nodes = 0;
  std::uint32_t max_depth = 0;
  std::uint64_t node_triangles = 0, leaf_triangles = 0;
  double peak_mb = not_measured, baseline_mb = not_measured;
  // First run only.
  long invalid = -1;  ///< -1: not checked
  std::size_t validated = 0;
  std::string first_invalid;
  double validate_seconds = not_measured;
  std::optional<PeerResult> cgal;
};

struct ChildTasks {
  bool validate = false;
  std::uint32_t validate_sample = 0;
  bool cgal = false;
  shatter::bench::ReplayLimits cgal_limits;
};

Json peer_to_json(const PeerResult& p) {
  return Json{{"status", static_cast<int>(p.status)},
              {"clip_seconds", std::isnan(p.clip_seconds) ? Json(nullptr) : Json(p.clip_seconds)},
              {"internal_nodes", p.internal_nodes},
              {"nodes_done", p.nodes_done},
              {"failed_clips", p.failed_clips},
              {"threw", p.threw},
              {"mismatches", p.mismatches},
              {"missing", p.missing},
              {"pieces", p.pieces},
              {"invalid", p.invalid},
              {"clipping_finished", p.clipping_finished},
              {"detail", p.detail}};
}

PeerResult peer_from_json(const Json& j) {
  PeerResult p;
  p.status = static_cast<PeerResult::Status>(j.at("status").get<int>());
  p.clip_seconds = j.at("clip_seconds").is_null() ? not_measured : j.at("clip_seconds").get<double>();
  p.internal_nodes = j.at("internal_nodes");
  p.nodes_done = j.at("nodes_done");
  p.failed_clips = j.at("failed_clips");
  p.threw = j.at("threw");
  p.mismatches = j.at("mismatches");
  p.missing = j.at("missing");
  p.pieces = j.at("pieces");
  p.invalid = j.at("invalid");
  p.clipping_finished = j.at("clipping_finished");
  p.detail = j.at("detail");
  return p;
}

/// Runs in the child: builds, measures, checks; returns the JSON the parent reads.
/// Builds on one thread: the benchmark times the builder's own work, not its scaling.
Json build_in_child(const shatter::Mesh& mesh, const shatter::TreeRecipe& recipe, const ChildTasks& tasks) {
  Json out;
  const std::uint64_t baseline_kb = proc_status_kb("VmRSS");
  shatter::BuildReport report;
  shatter::reset_certify_counts();
  const auto t0 = Clock::now();
  // Lean, as `shatter fracture` builds it (cli/fracture.cpp): nodes packed as
  // they finish, the tree a user's command makes. The full tree, every node
  // keeping its arrays, took 1.6x as long for cube -> 65,536 (2.59 s against
  // 1.61, 2026-12-06), and no command builds it.
  const shatter::MeshTree tree =
      shatter::build_mesh_tree(mesh, recipe, {.threads = 1, .report = &report, .lean = true});
  const double seconds = seconds_between(t0, Clock::now());
  // How the non-convex pieces were certified (progress on stderr, outside the clock).
  const shatter::CertifyCounts certified = shatter::certify_counts();
  std::fprintf(stderr, "  certificates: %llu non-convex pieces, %llu star-shaped, %llu to the full check\n",
               static_cast<unsigned long long>(certified.attempts), static_cast<unsigned long long>(certified.star),
               static_cast<unsigned long long>(certified.declined));
  const std::uint64_t peak_kb = proc_status_kb("VmHWM");

  // Packed nodes are read through NodeShapes, outside the clock.
  shatter::NodeShapes shapes(tree);
  std::uint64_t node_triangles = 0, leaf_triangles = 0;
  for (shatter::NodeIndex k = 0; k < tree.nodes.size(); ++k) {
    const std::size_t triangles = shapes.mesh(k).triangle_count();
    node_triangles += triangles;
    if (tree.nodes[k].is_leaf()) leaf_triangles += triangles;
  }
  std::uint32_t max_depth = 0;
  for (const auto& node : tree.nodes) max_depth = std::max(max_depth, node.depth);
  out["seconds"] = seconds;
  out["cutting"] = report.cutting_seconds;
  out["hull"] = report.hull_seconds;
  out["bond"] = report.bond_seconds;
  out["missed"] = report.planes_missed;
  out["rejected"] = report.planes_rejected;
  out["leaves"] = tree.leaf_count();
  out["nodes"] = tree.nodes.size();
  out["max_depth"] = max_depth;
  out["node_triangles"] = node_triangles;
  out["leaf_triangles"] = leaf_triangles;
  out["peak_kb"] = peak_kb;
  out["baseline_kb"] = baseline_kb;

  if (tasks.validate) {
    const auto v0 = Clock::now();
    const std::size_t leaves = tree.leaf_count();
    const std::size_t count =
        tasks.validate_sample > 0 && leaves > tasks.validate_sample ? tasks.validate_sample : leaves;
    long invalid = 0;
    std::string first;
    for (std::size_t k = 0; k < count; ++k) {
      // Evenly spaced over the leaf order when sampling; every leaf otherwise.
      const std::size_t i = count == leaves ? k : static_cast<std::size_t>((static_cast<std::uint64_t>(k) * leaves) / count);
      const shatter::NodeIndex node = tree.leaf_nodes[i];
      const auto check = shatter::validate_mesh(shapes.mesh(node));
      if (check.valid()) continue;
      if (invalid++ == 0)
        first = "leaf " + std::to_string(i) + " (node " + std::to_string(node) + ", depth " +
                std::to_string(tree.nodes[node].depth) + "): " + check.summary();
    }
    out["validated"] = count;
    out["invalid"] = invalid;
    out["first_invalid"] = first;
    out["validate_seconds"] = seconds_between(v0, Clock::now());
  }
  if (tasks.cgal) {
    PeerResult peer;
    try {
      peer = shatter::bench::replay_with_cgal_isolated(tree, mesh, tasks.cgal_limits);
    } catch (const std::exception& e) {  // pipe or fork failed: the peer's problem
      peer.status = PeerResult::Status::error;
      peer.detail = e.what();
    }
    out["cgal"] = peer_to_json(peer);
  }
  return out;
}

BuildRun run_build(const shatter::Mesh& mesh, const shatter::TreeRecipe& recipe, const ChildTasks& tasks) {
  // Hand freed heap back first, so the child's inherited resident set (part of
  // its VmHWM) is little more than the inputs.
  ::malloc_trim(0);
  int fds[2];
  if (::pipe(fds) != 0) throw std::runtime_error(std::string("pipe failed: ") + std::strerror(errno));
  const pid_t pid = fork_flushed();
  if (pid == 0) {
    ::close(fds[0]);
    Json out;
    try {
      out = build_in_child(mesh, recipe, tasks);
      out["ok"] = true;
    } catch (const std::exception& e) {
      out = Json{{"ok", false}, {"error", e.what()}};
    } catch (...) {
      out = Json{{"ok", false}, {"error", "unknown exception"}};
    }
    write_all(fds[1], out.dump());
    ::close(fds[1]);
    ::_exit(0);  // no destructors of the parent's state
  }
  ::close(fds[1]);
  const std::string text = read_all(fds[0]);
  ::close(fds[0]);
  const int status = wait_for_child(pid);
  BuildRun run;
  if (WIFSIGNALED(status)) {
    run.error = "the build's process died: " + signal_text(status);
    return run;
  }
  Json j;
  try {
    j = Json::parse(text);
  } catch (const std::exception&) {
    run.error = "the build's process sent no result (exit status " + std::to_string(WEXITSTATUS(status)) + ")";
    return run;
  }
  if (!j.at("ok").get<bool>()) {
    run.error = j.at("error").get<std::string>();
    return run;
  }
  run.ok = true;
  run.seconds = j.at("seconds");
  run.report.cutting_seconds = j.at("cutting");
  run.report.hull_seconds = j.at("hull");
  run.report.bond_seconds = j.at("bond");
  run.report.planes_missed = j.at("missed");
  run.report.planes_rejected = j.at("rejected");
  run.leaves = j.at("leaves");
  run.nodes = j.at("nodes");
  run.max_depth = j.at("max_depth");
  run.node_triangles = j.at("node_triangles");
  run.leaf_triangles = j.at("leaf_triangles");
  run.peak_mb = j.at("peak_kb").get<double>() / 1024.0;
  run.baseline_mb = j.at("baseline_kb").get<double>() / 1024.0;
  if (j.contains("validated")) {
    run.validated = j.at("validated");
    run.invalid = j.at("invalid");
    run.first_invalid = j.at("first_invalid");
    run.validate_seconds = j.at("validate_seconds");
  }
  if (j.contains("cgal")) run.cgal = peer_from_json(j.at("cgal"));
  return run;
}

/// A build timed over repeated runs; the first run's tree is checked.
struct Timed {
  bool ok = false;
  std::string error;
  BuildRun first;
  int runs = 0;
  double seconds = not_measured, cutting = not_measured, hull = not_measured,
         bond = not_measured;
  // The median of each run's rest (total less the three phases): the phases'
  // medians come from different runs, so subtracting them could go below zero.
  double other_seconds = not_measured;

  std::size_t internal_nodes() const { return first.nodes - first.leaves; }
  double other() const { return other_seconds; }
};

Timed time_build(const shatter::Mesh& mesh, std::uint32_t fragments, std::uint64_t seed, const Repeat& repeat,
                 const ChildTasks& first_tasks) {
  shatter::TreeRecipe recipe;
  recipe.fragments = fragments;
  recipe.seed = seed;
  recipe.strategy = shatter::Strategy::thesis;
  Timed timed;
  std::vector<double> total, cutting, hull, bond, other;
  double sum = 0;
  for (int run = 0; run < repeat.max_runs; ++run) {
    BuildRun r = run_build(mesh, recipe, run == 0 ? first_tasks : ChildTasks{});
    if (!r.ok) {
      timed.error = r.error;
      if (run == 0) return timed;
      break;
    }
    total.push_back(r.seconds);
    cutting.push_back(r.report.cutting_seconds);
    hull.push_back(r.report.hull_seconds);
    bond.push_back(r.report.bond_seconds);
    other.push_back(r.seconds - r.report.cutting_seconds - r.report.hull_seconds - r.report.bond_seconds);
    sum += r.seconds;
    if (run == 0) timed.first = std::move(r);
    if (run < 3) std::cerr << " " << seconds_text(total.back()) << std::flush;
    if (total.back() > repeat.no_repeat_seconds) break;
    if (static_cast<int>(total.size()) >= repeat.min_runs && sum >= repeat.min_total_seconds) break;
  }
  timed.ok = true;
  timed.runs = static_cast<int>(total.size());
  if (timed.runs > 3) std::cerr << " ... (" << timed.runs << " runs, median " << seconds_text(median_of(total)) << ")";
  timed.seconds = median_of(total);
  timed.cutting = median_of(cutting);
  timed.hull = median_of(hull);
  timed.bond = median_of(bond);
  timed.other_seconds = median_of(other);
  return timed;
}

// ---------------------------------------------------------------------------
// Manifold: fracture.mjs in a child process.

struct ManifoldResult {
  enum class Status { not_run, unavailable, ok, timeout, failed } status = Status::not_run;
  std::string detail;
  int repeat = 0;
  double seconds = not_measured;  ///< median of its repeats
  std::vector<double> runs;
  std::uint64_t pieces = 0, triangles = 0, bad_pieces = 0, rounds = 0;
  double peak_rss_mb = not_measured;  ///< its own sampling (process.memoryUsage.rss)
  double maxrss_mb = not_measured;    ///< the node process's ru_maxrss (wait4)
  double wall_seconds = not_measured; ///< the node process's whole life, loading included
  double wasm_mb = not_measured;      ///< WASM linear memory after the last repeat
  double volume_error = not_measured;
  std::string version, node_version;

  bool ok() const { return status == Status::ok; }
  std::string status_name() const {
    switch (status) {
      case Status::not_run: return "not run";
      case Status::unavailable: return "not available";
      case Status::ok: return "ok";
      case Status::timeout: return "timeout";
      case Status::failed: return "failed";
    }
    return "?";
  }
};

/// `name` as an executable: itself when it holds a '/', else found on PATH.
std::optional<fs::path> find_executable(const std::string& name) {
  if (name.find('/') != std::string::npos) {
    if (::access(name.c_str(), X_OK) == 0) return fs::path(name);
    return std::nullopt;
  }
  const char* path = std::getenv("PATH");
  std::istringstream dirs(path ? path : "");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    if (dir.empty()) continue;
    const fs::path candidate = fs::path(dir) / name;
    if (::access(candidate.c_str(), X_OK) == 0) return candidate;
  }
  return std::nullopt;
}

/// Why Manifold cannot run, or empty when it can.
std::string manifold_unavailable(const Options& o) {
  if (!find_executable(o.node)) return "node not found";
  if (!fs::exists(o.manifold_script)) return o.manifold_script.string() + " not found";
  if (!fs::exists(o.manifold_script.parent_path() / "node_modules" / "manifold-3d" / "package.json"))
    return "manifold-3d not installed (run npm ci in " + o.manifold_script.parent_path().string() + ")";
  return {};
}

ManifoldResult run_manifold(const Options& o, const fs::path& off, std::uint32_t fragments, int repeat) {
  ManifoldResult result;
  result.repeat = repeat;
  const fs::path node = *find_executable(o.node);
  std::vector<std::string> args{node.string()};
  // The WASM heap is capped at 4 GiB whatever this says; the JS heap of a million
  // pieces' handles may need more than Node's default.
  if (fragments > 65536) args.push_back("--max-old-space-size=16384");
  for (const std::string& a : {o.manifold_script.string(), std::string("--mesh"), off.string(), std::string("--fragments"),
                               std::to_string(fragments), std::string("--seed"), std::to_string(o.seed),
                               std::string("--repeat"), std::to_string(repeat), std::string("--json")})
    args.push_back(a);

  int out_pipe[2], err_pipe[2];
  if (::pipe(out_pipe) != 0 || ::pipe(err_pipe) != 0)
    throw std::runtime_error(std::string("pipe failed: ") + std::strerror(errno));
  const pid_t pid = fork_flushed();
  if (pid == 0) {
    ::dup2(out_pipe[1], 1);
    ::dup2(err_pipe[1], 2);
    ::close(out_pipe[0]);
    ::close(out_pipe[1]);
    ::close(err_pipe[0]);
    ::close(err_pipe[1]);
    const int devnull = ::open("/dev/null", O_RDONLY);
    if (devnull >= 0) ::dup2(devnull, 0);
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  const auto started = Clock::now();
  ::close(out_pipe[1]);
  ::close(err_pipe[1]);
  std::string out, err;
  // The limit is per repeat: the process gets --manifold-timeout times its repeats.
  const double limit = o.manifold_timeout * repeat;
  const auto deadline =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(limit));
  bool timed_out = false;
  int open_fds = 2;
  pollfd watch[2] = {{out_pipe[0], POLLIN, 0}, {err_pipe[0], POLLIN, 0}};
  while (open_fds > 0) {
    const double remaining = seconds_between(Clock::now(), deadline);
    if (remaining <= 0) {
      timed_out = true;
      break;
    }
    const int ready = ::poll(watch, 2, static_cast<int>(std::min(remaining * 1000.0, 1000.0)) + 1);
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0) continue;
    for (int k = 0; k < 2; ++k) {
      if (watch[k].fd < 0 || !(watch[k].revents & (POLLIN | POLLHUP | POLLERR))) continue;
      char buffer[65536];
      const ssize_t n = ::read(watch[k].fd, buffer, sizeof buffer);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        ::close(watch[k].fd);
        watch[k].fd = -1;
        --open_fds;
        continue;
      }
      (k == 0 ? out : err).append(buffer, static_cast<std::size_t>(n));
    }
  }
  if (timed_out) ::kill(pid, SIGKILL);
  for (auto& w : watch)
    if (w.fd >= 0) ::close(w.fd);
  int status = 0;
  rusage usage{};
  while (::wait4(pid, &status, 0, &usage) < 0 && errno == EINTR) {
  }
  result.maxrss_mb = static_cast<double>(usage.ru_maxrss) / 1024.0;  // kB on Linux
  result.wall_seconds = seconds_between(started, Clock::now());
  auto last_line = [](std::string text) {
    while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
    const auto at = text.find_last_of('\n');
    return at == std::string::npos ? text : text.substr(at + 1);
  };
  if (timed_out) {
    result.status = ManifoldResult::Status::timeout;
    result.detail = "no result within " + fixed(limit, 0) + " s (" + std::to_string(repeat) + " × --manifold-timeout)";
    return result;
  }
  if (WIFSIGNALED(status) || WEXITSTATUS(status) != 0) {
    result.status = ManifoldResult::Status::failed;
    result.detail = (WIFSIGNALED(status) ? signal_text(status) : "exit " + std::to_string(WEXITSTATUS(status))) +
                    " after " + seconds_text(result.wall_seconds) + " s, peak RSS " + fixed(result.maxrss_mb, 0) +
                    " MB" + (err.empty() ? "" : ": " + last_line(err));
    return result;
  }
  try {
    const Json j = Json::parse(out);
    result.seconds = j.at("seconds").at("median");
    result.runs = j.at("seconds").at("runs").get<std::vector<double>>();
    result.pieces = j.at("pieces");
    result.triangles = j.at("total_triangles");
    result.bad_pieces = j.at("bad_pieces");
    result.rounds = j.at("rounds");
    result.peak_rss_mb = j.at("peak_rss_mb");
    const auto& wasm = j.at("wasm_memory_mb_after_each_repeat");
    if (!wasm.empty()) result.wasm_mb = wasm.back();
    result.volume_error = j.at("volume_relative_error");
    result.version = j.at("manifold_3d_version");
    result.node_version = j.at("node_version");
    result.status = ManifoldResult::Status::ok;
    if (result.pieces < fragments) result.detail = "only " + std::to_string(result.pieces) + " pieces";
    if (result.bad_pieces > 0)
      result.detail += (result.detail.empty() ? "" : "; ") + std::to_string(result.bad_pieces) + " bad pieces";
  } catch (const std::exception& e) {
    result.status = ManifoldResult::Status::failed;
    result.detail = std::string("unreadable output: ") + e.what();
  }
  return result;
}

// ---------------------------------------------------------------------------
// Rows.

struct RowSpec {
  std::string input;  ///< Input::key prefix: cube, knot1, fandisk
  std::uint32_t fragments = 0;
};

/// `shatter fracture` as a user runs it, timed from outside: read, check, build,
/// write (one thread), median wall seconds of its runs.
struct EndToEnd {
  bool ok = false;
  std::string why;  ///< why not run, or how it failed
  double seconds = not_measured;
  int runs = 0;
  double peak_mb = not_measured;  ///< largest ru_maxrss over the runs
  std::uintmax_t file_bytes = 0;
};

/// `shatter fracture` on 2 threads against 1, run in turn (1, 2, 1, 2, ...) so
/// that the ratio of each pair sees the same machine.
struct ThreadPair {
  bool ok = false;
  std::string why;  ///< why not run, or how it failed
  double one_seconds = not_measured, two_seconds = not_measured;  ///< medians
  double speedup = not_measured;  ///< median over the pairs of 1-thread seconds / 2-thread seconds
  int pairs = 0;
  bool identical = false;  ///< every pair's two files equal byte for byte
};

struct Row {
  std::string id;
  const Input* input = nullptr;
  std::uint32_t fragments = 0;
  Timed full;
  EndToEnd command;
  ThreadPair threads;
  std::optional<Timed> half;  ///< the build to N/2, for the last level's splits
  ManifoldResult manifold;
  std::string cgal_skipped;   ///< why the CGAL replay was not run, if not
  bool failed = false;
  std::string note;

  void add_note(const std::string& text) { note += (note.empty() ? "" : "; ") + text; }
  const std::optional<PeerResult>& cgal() const { return full.first.cgal; }
  double us_per_split_all() const {
    return full.ok && full.internal_nodes() > 0 ? full.cutting * 1e6 / static_cast<double>(full.internal_nodes())
                                                : not_measured;
  }
  double us_per_split_last() const {
    if (!full.ok || !half || !half->ok || full.internal_nodes() <= half->internal_nodes()) return not_measured;
    return (full.cutting - half->cutting) * 1e6 / static_cast<double>(full.internal_nodes() - half->internal_nodes());
  }
  double ns_per_triangle() const {
    return full.ok && full.first.node_triangles > 0 ? full.seconds * 1e9 / static_cast<double>(full.first.node_triangles)
                                                     : not_measured;
  }
  double manifold_ratio() const { return manifold.ok() && full.ok ? manifold.seconds / full.seconds : not_measured; }
  double manifold_ratio_end_to_end() const {
    return manifold.ok() && command.ok ? manifold.seconds / command.seconds : not_measured;
  }
  double leaf_triangles_over_manifold() const {
    return manifold.ok() && full.ok && manifold.triangles > 0
               ? static_cast<double>(full.first.leaf_triangles) / static_cast<double>(manifold.triangles)
               : not_measured;
  }
  double cgal_ratio() const { return cgal() && full.ok ? cgal()->comparable_seconds() / full.seconds : not_measured; }
  double cgal_ratio_to_cutting() const {
    return cgal() && full.ok ? cgal()->comparable_seconds() / full.cutting : not_measured;
  }
};

const std::vector<RowSpec> default_rows = {
    {"cube", 256},       {"cube", 65536},      {"cube", 1u << 20},   {"elephant", 256}, {"elephant", 4096},
    {"blobby", 256},     {"blobby", 4096},     {"fandisk", 256},     {"fandisk", 4096}, {"fandisk", 65536},
    {"knot1", 256},      {"knot1", 65536}};

/// The rows --rows selects: comma-separated row ids (cube-65536, knot1x16-256) or
/// input names (cube, knot1x16, knot1, fandiskx4, fandisk) meaning all their rows.
std::vector<RowSpec> select_rows(const std::string& list) {
  if (list.empty() || list == "all") return default_rows;
  std::vector<RowSpec> rows;
  std::istringstream in(list);
  std::string item;
  // "knot1", "knot1x16" -> "knot1": a prefix, optionally followed by x and digits.
  auto input_of = [](const std::string& name) -> std::optional<std::string> {
    for (const std::string prefix : {"cube", "knot1", "fandisk", "elephant", "blobby"}) {
      if (name == prefix) return prefix;
      if (name.rfind(prefix + "x", 0) == 0 && name.size() > prefix.size() + 1 &&
          name.find_first_not_of("0123456789", prefix.size() + 1) == std::string::npos)
        return prefix;
    }
    return std::nullopt;
  };
  while (std::getline(in, item, ',')) {
    if (item.empty()) continue;
    std::optional<std::string> whole = input_of(item);
    if (whole) {
      for (const RowSpec& r : default_rows)
        if (r.input == *whole) rows.push_back(r);
      continue;
    }
    const auto dash = item.rfind('-');
    std::optional<std::string> name = dash == std::string::npos ? std::nullopt : input_of(item.substr(0, dash));
    std::uint64_t n = 0;
    try {
      std::size_t used = 0;
      if (name) n = std::stoull(item.substr(dash + 1), &used);
      if (name && used != item.size() - dash - 1) n = 0;
    } catch (const std::exception&) {
      n = 0;
    }
    if (!name || n < 1 || n > (1u << 22))
      throw std::runtime_error("--rows: unknown row '" + item +
                               "' (want cube, elephant, blobbyx4, fandiskx4, knot1x16, or one of them with -N, e.g. cube-65536)");
    rows.push_back({*name, static_cast<std::uint32_t>(n)});
  }
  return rows;
}

const Input* input_for(const std::string& prefix, const std::vector<Input>& inputs) {
  for (const Input& i : inputs)
    if (i.key.rfind(prefix, 0) == 0) return &i;
  return nullptr;
}

/// Writes every input a Manifold row needs to a temporary OFF file, once.
class OffFiles {
 public:
  ~OffFiles() {
    std::error_code ignored;
    for (const auto& [key, path] : paths_) fs::remove(path, ignored);
  }
  fs::path get(const Input& input) {
    const auto it = paths_.find(input.key);
    if (it != paths_.end()) return it->second;
    const fs::path path =
        fs::temp_directory_path() / ("shatter-bench-plane-" + std::to_string(::getpid()) + "-" + input.key + ".off");
    shatter::write_mesh(input.mesh, path, shatter::MeshFormat::off);
    paths_[input.key] = path;
    return path;
  }

 private:
  std::map<std::string, fs::path> paths_;
};

/// One run of `shatter fracture OFF --fragments N --seed S --threads T --out OUT`
/// as a child process, its wall clock taken around the whole process.
struct FractureRun {
  bool ok = false;
  std::string why;  ///< how it failed
  double seconds = not_measured;
  double peak_mb = not_measured;  ///< the child's ru_maxrss
};

FractureRun run_fracture(const Options& o, const fs::path& off, std::uint32_t fragments, int threads, const fs::path& out) {
  FractureRun run;
  std::vector<std::string> args{o.shatter_exe.string(), "fracture",   off.string(),   "--fragments",
                                std::to_string(fragments), "--seed", std::to_string(o.seed), "--threads",
                                std::to_string(threads),    "--out",  out.string()};
  const auto started = Clock::now();
  const pid_t pid = fork_flushed();
  if (pid == 0) {
    const int devnull = ::open("/dev/null", O_RDWR);
    if (devnull >= 0) {
      ::dup2(devnull, 0);
      ::dup2(devnull, 1);
      ::dup2(devnull, 2);
    }
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  int status = 0;
  rusage usage{};
  while (::wait4(pid, &status, 0, &usage) < 0 && errno == EINTR) {
  }
  run.seconds = seconds_between(started, Clock::now());
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    run.why = "shatter fracture --threads " + std::to_string(threads) + " failed (" +
              (WIFEXITED(status) ? "exit " + std::to_string(WEXITSTATUS(status))
                                 : "signal " + std::to_string(WTERMSIG(status))) + ")";
    return run;
  }
  run.ok = true;
  run.peak_mb = static_cast<double>(usage.ru_maxrss) / 1024.0;
  return run;
}

fs::path temporary_output(const std::string& tag) {
  return fs::temp_directory_path() / ("shatter-bench-plane-" + std::to_string(::getpid()) + tag + ".shatter");
}

/// Runs `shatter fracture` on 1 thread until `repeat` is met; the file it wrote
/// is measured and removed.
EndToEnd time_fracture_command(const Options& o, const fs::path& off, std::uint32_t fragments,
                               const Repeat& repeat) {
  EndToEnd result;
  if (::access(o.shatter_exe.c_str(), X_OK) != 0) {
    result.why = o.shatter_exe.string() + " not found";
    return result;
  }
  const fs::path out = temporary_output("");
  std::vector<double> times;
  double total = 0, peak_mb = 0;
  std::error_code ignored;
  while (static_cast<int>(times.size()) < repeat.max_runs) {
    const FractureRun run = run_fracture(o, off, fragments, 1, out);
    if (!run.ok) {
      result.why = run.why;
      fs::remove(out, ignored);
      return result;
    }
    peak_mb = std::max(peak_mb, run.peak_mb);
    std::error_code size_error;
    result.file_bytes = fs::file_size(out, size_error);
    times.push_back(run.seconds);
    total += run.seconds;
    if (run.seconds > repeat.no_repeat_seconds) break;
    if (static_cast<int>(times.size()) >= repeat.min_runs && total >= repeat.min_total_seconds) break;
  }
  fs::remove(out, ignored);
  result.ok = true;
  result.peak_mb = peak_mb;
  result.runs = static_cast<int>(times.size());
  result.seconds = median_of(times);
  return result;
}

/// Whether two files hold the same bytes.
bool same_file_bytes(const fs::path& a, const fs::path& b) {
  std::ifstream in_a(a, std::ios::binary), in_b(b, std::ios::binary);
  if (!in_a || !in_b) return false;
  std::vector<char> block_a(1 << 16), block_b(1 << 16);
  while (true) {
    in_a.read(block_a.data(), static_cast<std::streamsize>(block_a.size()));
    in_b.read(block_b.data(), static_cast<std::streamsize>(block_b.size()));
    if (in_a.gcount() != in_b.gcount()) return false;
    if (!std::equal(block_a.begin(), block_a.begin() + in_a.gcount(), block_b.begin())) return false;
    if (in_a.gcount() == 0 || !in_a) return !in_b || in_b.peek() == EOF;
  }
}

/// `shatter fracture` on 1 and on 2 threads in turn, pairs until `repeat` is met
/// (counting pairs as runs, at least 3 pairs), each pair's files compared byte
/// for byte.
ThreadPair time_thread_pair(const Options& o, const fs::path& off, std::uint32_t fragments, const Repeat& repeat) {
  ThreadPair result;
  const fs::path one = temporary_output("-1"), two = temporary_output("-2");
  std::vector<double> one_times, two_times, ratios;
  double total = 0;
  bool identical = true;
  std::error_code ignored;
  while (static_cast<int>(ratios.size()) < repeat.max_runs) {
    const FractureRun a = run_fracture(o, off, fragments, 1, one);
    const FractureRun b = a.ok ? run_fracture(o, off, fragments, 2, two) : FractureRun{};
    if (!a.ok || !b.ok) {
      result.why = a.ok ? b.why : a.why;
      fs::remove(one, ignored);
      fs::remove(two, ignored);
      return result;
    }
    identical = identical && same_file_bytes(one, two);
    one_times.push_back(a.seconds);
    two_times.push_back(b.seconds);
    ratios.push_back(a.seconds / b.seconds);
    total += a.seconds + b.seconds;
    if (a.seconds > repeat.no_repeat_seconds) break;
    if (static_cast<int>(ratios.size()) >= std::max(3, repeat.min_runs) && total >= repeat.min_total_seconds) break;
  }
  fs::remove(one, ignored);
  fs::remove(two, ignored);
  result.ok = true;
  result.one_seconds = median_of(one_times);
  result.two_seconds = median_of(two_times);
  result.speedup = median_of(ratios);
  result.pairs = static_cast<int>(ratios.size());
  result.identical = identical;
  return result;
}

Row run_row(const RowSpec& spec, const Input& input, const Options& o, const Repeat& repeat, OffFiles& files) {
  Row row;
  row.input = &input;
  row.fragments = spec.fragments;
  row.id = input.key + "-" + std::to_string(spec.fragments);

  ChildTasks first;
  first.validate = !o.no_validate;
  first.validate_sample = o.validate_sample;
  const bool cgal_wanted = !o.no_peers && !o.no_cgal && spec.fragments <= o.cgal_max;
  first.cgal = cgal_wanted;
  first.cgal_limits = {o.peer_timeout, o.peer_memory_mb, !o.no_validate};
  row.cgal_skipped = o.no_peers || o.no_cgal ? "not run (--no-peers/--no-cgal)"
                     : !cgal_wanted         ? "not run (N above --cgal-max " + with_thousands(o.cgal_max) + ")"
                                            : "";

  std::cerr << row.id << ": shatter" << std::flush;
  row.full = time_build(input.mesh, spec.fragments, o.seed, repeat, first);
  if (!row.full.ok) {
    row.failed = true;
    row.add_note("build failed: " + row.full.error);
  } else {
    if (row.full.first.leaves < spec.fragments) {
      row.failed = true;
      row.add_note("only " + std::to_string(row.full.first.leaves) + " leaves");
    }
    if (row.full.first.invalid > 0) {
      row.failed = true;
      row.add_note(std::to_string(row.full.first.invalid) + " invalid leaves, first " + row.full.first.first_invalid);
    }
    if (!row.full.error.empty()) row.add_note("a repeat failed: " + row.full.error);
    if (row.full.first.cgal)
      std::cerr << " [CGAL " << row.full.first.cgal->status_name() << " "
                << seconds_text(row.full.first.cgal->clip_seconds) << " s]" << std::flush;
  }
  if (!o.no_last_level && spec.fragments >= 2 && row.full.ok) {
    std::cerr << "; to N/2" << std::flush;
    row.half = time_build(input.mesh, spec.fragments / 2, o.seed, repeat, ChildTasks{});
    if (!row.half->ok) row.add_note("build to N/2 failed: " + row.half->error);
  }
  if (o.no_end_to_end) {
    row.command.why = "not run (--no-end-to-end)";
  } else if (row.full.ok) {
    std::cerr << "; shatter fracture" << std::flush;
    row.command = time_fracture_command(o, files.get(input), spec.fragments, repeat);
    std::cerr << " " << (row.command.ok ? seconds_text(row.command.seconds) + " s" : row.command.why) << std::flush;
    if (!row.command.ok) {
      row.failed = true;
      row.add_note(row.command.why);
    }
  }
  if (!o.two_threads) {
    row.threads.why = "not run (no --two-threads)";
  } else if (o.no_end_to_end || !row.full.ok || !row.command.ok) {
    row.threads.why = "not run";
  } else {
    std::cerr << "; 1 vs 2 threads" << std::flush;
    row.threads = time_thread_pair(o, files.get(input), spec.fragments, repeat);
    std::cerr << " " << (row.threads.ok ? ratio_text(row.threads.speedup) + "x" : row.threads.why) << std::flush;
    if (!row.threads.ok) {
      row.failed = true;
      row.add_note(row.threads.why);
    } else if (!row.threads.identical) {
      row.failed = true;
      row.add_note("the 2-thread file differs from the 1-thread file");
    }
  }
  if (o.no_peers || o.no_manifold) {
    row.manifold.status = ManifoldResult::Status::not_run;
    row.manifold.detail = "--no-peers/--no-manifold";
  } else if (const std::string why = manifold_unavailable(o); !why.empty()) {
    row.manifold.status = ManifoldResult::Status::unavailable;
    row.manifold.detail = why;
  } else {
    const int r = o.manifold_repeat.value_or(o.quick ? 1 : spec.fragments <= 65536 ? 3 : 1);
    std::cerr << "; Manifold x" << r << std::flush;
    try {
      row.manifold = run_manifold(o, files.get(input), spec.fragments, r);
    } catch (const std::exception& e) {
      row.manifold.status = ManifoldResult::Status::failed;
      row.manifold.detail = e.what();
    }
    std::cerr << " " << row.manifold.status_name() << " " << seconds_text(row.manifold.seconds) << " s" << std::flush;
  }
  std::cerr << (row.failed ? " FAILED: " + row.note : "") << "\n";
  return row;
}

// ---------------------------------------------------------------------------
// The targets (issue item 7) and the native reference of the WASM peer.

/// Native Manifold 3.5 on these 2-core machines, as given to the project (seconds).
struct NativeFigure {
  std::string input_prefix;
  std::uint32_t fragments;
  double low, high;
};
const std::vector<NativeFigure> native_manifold = {
    {"cube", 256, 0.03, 0.05}, {"cube", 65536, 9.0, 10.5}, {"fandisk", 256, 1.05, 1.05}};

struct Verdict {
  std::string target, row, figure, verdict;
};

const Row* find_row(const std::vector<Row>& rows, const std::string& prefix, std::uint32_t n) {
  for (const Row& r : rows)
    if (r.input->key.rfind(prefix, 0) == 0 && r.fragments == n) return &r;
  return nullptr;
}

std::string time_verdict(double seconds, double limit) {
  if (std::isnan(seconds)) return "not measured";
  if (seconds <= limit) return "met";
  return "missed by " + seconds_text(seconds - limit) + " s (" + ratio_text(seconds / limit) + "× the target)";
}

std::vector<Verdict> judge(const std::vector<Row>& rows) {
  std::vector<Verdict> out;
  if (const Row* r = find_row(rows, "cube", 65536)) {
    out.push_back({"cube → 65,536 in ≤ 0.5 s, hulls, bonds and mass properties included", r->id,
                   seconds_text(r->full.seconds) + " s", time_verdict(r->full.seconds, 0.5)});
  }
  for (const std::string prefix : {"fandisk", "knot1"}) {
    if (const Row* r = find_row(rows, prefix, 256)) {
      out.push_back({"the ≥ 50k-triangle solid → 256 in ≤ 0.1 s", r->id + " (" + with_thousands(r->input->mesh.triangle_count()) +
                         " triangles)",
                     seconds_text(r->full.seconds) + " s", time_verdict(r->full.seconds, 0.1)});
    }
  }
  for (const std::string prefix : {"cube", "fandisk", "knot1"}) {
    const Row* r = find_row(rows, prefix, 65536);
    if (!r) continue;
    Verdict v{"≥ 20× faster than Manifold at 65,536 (same run, Manifold in WASM)", r->id, "", ""};
    const double ratio = r->manifold_ratio();
    if (std::isnan(ratio)) {
      v.figure = "–";
      v.verdict = "not measured (Manifold " + r->manifold.status_name() + ")";
    } else {
      v.figure = ratio_text(ratio) + "× (" + seconds_text(r->manifold.seconds) + " s / " + seconds_text(r->full.seconds) + " s)";
      v.verdict = ratio >= 20 ? "met" : "missed by a factor " + ratio_text(20 / ratio) + " (needs 20×)";
    }
    if (prefix == "cube") {
      // Against the native figure the project was given, too.
      const double native_ratio_low = 9.0 / r->full.seconds, native_ratio_high = 10.5 / r->full.seconds;
      if (r->full.ok)
        v.figure += "; against native 9–10.5 s: " + ratio_text(native_ratio_low) + "–" + ratio_text(native_ratio_high) + "×";
    }
    out.push_back(v);
  }
  if (const Row* r = find_row(rows, "cube", 1u << 20)) {
    Verdict v{"cube → 2^20 with zero invalid leaves, peak memory stated", r->id, "", ""};
    if (!r->full.ok) {
      v.figure = "–";
      v.verdict = "missed: " + r->note;
    } else {
      const BuildRun& f = r->full.first;
      v.figure = (f.invalid < 0 ? std::string("not validated") : with_thousands(static_cast<std::uint64_t>(f.invalid)) + " invalid of " +
                                                                    with_thousands(f.validated) + " validated") +
                 "; peak " + fixed(f.peak_mb, 0) + " MB; " + seconds_text(r->full.seconds) + " s";
      v.verdict = f.invalid == 0 ? (f.validated == f.leaves ? "met" : "met on the sample")
                  : f.invalid < 0 ? "not checked"
                                  : "missed by " + std::to_string(f.invalid) + " invalid leaves";
    }
    out.push_back(v);
  }
  for (const Row& r : rows) {
    if (!r.threads.ok) continue;
    const ThreadPair& t = r.threads;
    out.push_back({"2 threads ≥ 1.8× one thread end to end, same bytes", r.id,
                   ratio_text(t.speedup) + "× (" + seconds_text(t.one_seconds) + " s / " + seconds_text(t.two_seconds) +
                       " s)" + (t.identical ? "" : ", files differ"),
                   !t.identical        ? "missed: the files differ"
                   : t.speedup >= 1.8 ? "met"
                                      : "missed by a factor " + ratio_text(1.8 / t.speedup)});
  }
  if (const Row* r = find_row(rows, "cube", 65536)) {
    Verdict v{"leaves carry no more triangles than Manifold's (same run)", r->id, "", ""};
    if (!r->manifold.ok() || !r->full.ok) {
      v.figure = "–";
      v.verdict = "not measured (Manifold " + r->manifold.status_name() + ")";
    } else {
      const auto s = r->full.first.leaf_triangles, m = r->manifold.triangles;
      v.figure = with_thousands(s) + " vs " + with_thousands(m);
      v.verdict = s <= m ? "met (" + ratio_text(static_cast<double>(s) / static_cast<double>(m)) + "× Manifold's)"
                         : "missed by " + with_thousands(s - m) + " triangles (+" +
                               fixed(100.0 * static_cast<double>(s - m) / static_cast<double>(m), 1) + "%)";
    }
    out.push_back(v);
  }
  return out;
}

// ---------------------------------------------------------------------------
// Output.

std::string manifold_seconds_cell(const ManifoldResult& m) {
  if (m.ok()) return seconds_text(m.seconds);
  return m.status_name();
}

std::string cgal_cell(const Row& r) {
  if (!r.cgal()) return r.cgal_skipped.empty() ? "–" : "not run";
  const PeerResult& p = *r.cgal();
  if (p.status == PeerResult::Status::ok) return seconds_text(p.clip_seconds);
  return p.status_name();
}

std::string cgal_status(const Row& r) {
  if (!r.cgal()) return r.cgal_skipped;
  const PeerResult& p = *r.cgal();
  std::string text = p.status_name();
  if (p.status == PeerResult::Status::ok) {
    text += ": " + (p.pieces < 0 ? std::string("pieces not checked") : std::to_string(p.pieces) + " pieces, " +
                                                                            std::to_string(p.invalid) + " invalid");
    if (p.missing) text += ", " + std::to_string(p.missing) + " leaves missing";
    if (p.failed_clips || p.threw) text += ", clips failed/threw " + std::to_string(p.failed_clips) + "/" + std::to_string(p.threw);
    if (p.mismatches) text += ", " + std::to_string(p.mismatches) + " component mismatches";
  }
  if (!p.detail.empty()) text += ": " + p.detail;
  return text;
}

std::string invalid_cell(const Row& r) {
  if (!r.full.ok) return "–";
  const BuildRun& f = r.full.first;
  if (f.invalid < 0) return "n/c";
  std::string text = with_thousands(static_cast<std::uint64_t>(f.invalid));
  if (f.validated != f.leaves) text += " of " + with_thousands(f.validated) + " sampled";
  return text;
}

void print_tables(std::ostream& out, const std::vector<Row>& rows, const std::vector<Input>& inputs,
                  const std::vector<std::string>& skipped, const std::vector<Verdict>& verdicts) {
  out << "### Inputs\n\n| mesh | triangles | plane faces | origin |\n|---|---:|---:|---|\n";
  for (const Input& i : inputs) {
    if (!i.available) {
      out << "| " << i.name << " | – | – | not available: " << i.missing << " |\n";
      continue;
    }
    out << "| " << i.name << " | " << with_thousands(i.mesh.triangle_count()) << " | " << with_thousands(i.plane_faces)
        << " | " << i.origin << " |\n";
  }
  out << "\n\"plane faces\": the faces of the plane kernel's input solid. Midpoint subdivision makes coplanar\n"
         "triangles, and for a mesh without attributes the plane kernel merges edge-connected coplanar\n"
         "triangles (decided exactly) back into one polygon face; the 4 triangles of a subdivided one stay apart\n"
         "when a midpoint rounded off its edge.\n";
  for (const std::string& s : skipped) out << "\nRow skipped: " << s << ".\n";

  out << "\n### shatter, plane kernel, 1 thread\n\n"
      << "| row | input triangles | N | leaves | depth | runs | total s | cut / hulls / bonds / other s | "
         "µs/split (all levels) | µs/split (last level, Δ N/2→N) | output triangles (all nodes) | ns/output triangle | "
         "leaf triangles | per leaf | peak MB | invalid leaves | note |\n"
      << "|---|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---|\n";
  for (const Row& r : rows) {
    out << "| " << r.id << " | " << with_thousands(r.input->mesh.triangle_count()) << " | " << with_thousands(r.fragments)
        << " | ";
    if (!r.full.ok) {
      out << "– | – | – | – | – | – | – | – | – | – | – | – | – | " << invalid_cell(r) << " | " << r.note << " |\n";
      continue;
    }
    const BuildRun& f = r.full.first;
    out << with_thousands(f.leaves) << " | " << f.max_depth << " | " << r.full.runs << " | "
        << seconds_text(r.full.seconds) << " | " << seconds_text(r.full.cutting) << " / "
        << seconds_text(r.full.hull) << " / " << seconds_text(r.full.bond) << " / "
        << seconds_text(r.full.other()) << " | " << number_text(r.us_per_split_all(), 2) << " | "
        << number_text(r.us_per_split_last(), 2) << " | " << with_thousands(f.node_triangles) << " | "
        << number_text(r.ns_per_triangle(), 1) << " | " << with_thousands(f.leaf_triangles) << " | "
        << fixed(static_cast<double>(f.leaf_triangles) / static_cast<double>(std::max<std::size_t>(f.leaves, 1)), 1)
        << " | " << fixed(f.peak_mb, 0) << " | " << invalid_cell(r) << " | " << r.note << " |\n";
  }

  double baseline = 0;
  for (const Row& r : rows) {
    if (!r.full.ok) continue;
    baseline = std::max(baseline, r.full.first.baseline_mb);
  }
  out << "\nTimes are medians over the runs, each phase its own median"
      << " (\"cut\" includes rounding and certifying every piece, done as each is cut)"
      << ". µs/split (last level) is the marginal "
         "cut time of going from N/2 to N fragments (a second build to N/2) per extra split. Peak MB is the VmHWM of "
         "the build's own forked process, which inherited at most "
      << fixed(baseline, 1) << " MB resident from the bench.\n";
  out << "\n### Peers in the same run\n\n"
      << "| row | shatter build s | shatter fracture s (end to end) | Manifold s (WASM) | Manifold runs | "
         "Manifold/shatter build | Manifold/shatter end to end | .shatter MB | fracture peak MB | Manifold pieces | "
         "Manifold triangles | shatter leaf / Manifold triangles | Manifold peak RSS MB | CGAL clip s | CGAL/shatter | "
         "CGAL/shatter cut | CGAL replay |\n"
      << "|---|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n";
  for (const Row& r : rows) {
    const ManifoldResult& m = r.manifold;
    std::string runs;
    for (double s : m.runs) {
      if (!runs.empty()) runs += ' ';
      runs += seconds_text(s);
    }
    const EndToEnd& c = r.command;
    out << "| " << r.id << " | " << seconds_text(r.full.seconds) << " | "
        << (c.ok ? seconds_text(c.seconds) : c.why.empty() ? "–" : c.why) << " | " << manifold_seconds_cell(m)
        << (m.ok() || m.detail.empty() ? "" : ": " + m.detail) << " | " << (runs.empty() ? "–" : runs) << " | "
        << ratio_text(r.manifold_ratio()) << " | " << ratio_text(r.manifold_ratio_end_to_end()) << " | "
        << (c.ok ? fixed(static_cast<double>(c.file_bytes) / 1e6, 1) : "–") << " | "
        << (c.ok ? fixed(c.peak_mb, 0) : "–") << " | " << (m.ok() ? with_thousands(m.pieces) : "–") << " | "
        << (m.ok() ? with_thousands(m.triangles) : "–") << " | " << ratio_text(r.leaf_triangles_over_manifold()) << " | "
        << (m.ok() ? fixed(m.maxrss_mb, 0) : "–") << " | " << cgal_cell(r) << " | " << ratio_text(r.cgal_ratio())
        << " | " << ratio_text(r.cgal_ratio_to_cutting()) << " | " << cgal_status(r) << " |\n";
  }

  if (std::any_of(rows.begin(), rows.end(), [](const Row& r) { return r.threads.ok; })) {
    out << "\n### `shatter fracture` on 2 threads against 1 (--two-threads)\n\n"
        << "| row | pairs | 1 thread s | 2 threads s | speed-up (median of the pairs) | files identical |\n"
        << "|---|---:|---:|---:|---:|---|\n";
    for (const Row& r : rows) {
      const ThreadPair& t = r.threads;
      if (!t.ok) {
        out << "| " << r.id << " | – | – | – | – | " << t.why << " |\n";
        continue;
      }
      out << "| " << r.id << " | " << t.pairs << " | " << seconds_text(t.one_seconds) << " | "
          << seconds_text(t.two_seconds) << " | " << ratio_text(t.speedup) << " | " << (t.identical ? "yes" : "NO")
          << " |\n";
    }
    out << "\nThe two commands run in turn, 1 thread then 2, and each pair's ratio is taken before the median, so a "
           "drift in the machine's speed moves both sides of a ratio alike. Issue 18's target: at least 1.8, files "
           "identical.\n";
  }

  // The WASM caveat, with this run's figures against the native ones.
  std::string version;
  for (const Row& r : rows)
    if (r.manifold.ok()) version = "manifold-3d " + r.manifold.version + " on Node " + r.manifold.node_version;
  out << "\nManifold runs as WebAssembly (the npm build"
      << (version.empty() ? "" : ", " + version)
      << "; single-threaded, 32-bit heap of at most 4 GiB) under Node, not as native code; its time is its own "
         "fracture loop (median of its repeats), its peak RSS the node process's ru_maxrss. Native Manifold cannot "
         "be built here; the figures the project was given for native Manifold 3.5 on these 2-core machines, "
         "against this run's WASM medians:\n\n"
      << "| row | native Manifold 3.5 s (given) | WASM s (this run) | WASM / native |\n|---|---:|---:|---:|\n";
  bool any_native = false;
  for (const NativeFigure& n : native_manifold) {
    const Row* r = find_row(rows, n.input_prefix, n.fragments);
    if (!r) continue;
    any_native = true;
    const std::string native = n.low == n.high ? fixed(n.low, 2) : fixed(n.low, 2) + "–" + fixed(n.high, 2);
    std::string ratio = "–";
    if (r->manifold.ok()) {
      const double hi = r->manifold.seconds / n.low, lo = r->manifold.seconds / n.high;
      ratio = n.low == n.high ? ratio_text(lo) : ratio_text(lo) + "–" + ratio_text(hi);
    }
    out << "| " << r->id << " | " << native << " | " << manifold_seconds_cell(r->manifold) << " | " << ratio << " |\n";
  }
  if (!any_native) out << "| (no row with a native figure was run) | | | |\n";
  bool single = false;
  for (const Row& r : rows) single = single || (r.manifold.ok() && r.manifold.repeat == 1);
  if (single)
    out << "\nA Manifold time from a single repeat includes V8's warm-up (its first run is the slowest; see "
           "bench/peers/manifold/README.md).\n";
  out << "\nA WASM/native ratio near or below 1 means the WASM build is not slower than the native figures here, "
         "so Manifold/shatter is not inflated by WebAssembly; the estimate rests on figures measured outside this "
         "run.\n";

  out << "\n### Targets (issue item 7)\n\n| target | row | figure | verdict |\n|---|---|---|---|\n";
  for (const Verdict& v : verdicts)
    out << "| " << v.target << " | " << v.row << " | " << v.figure << " | " << v.verdict << " |\n";
  if (verdicts.empty()) out << "| (none of the targets' rows was run) | | | |\n";
}

void write_csv(const fs::path& path, const std::vector<Row>& rows, std::uint64_t seed) {
  CsvWriter csv(
      "row,mesh,input_triangles,plane_faces,kernel,strategy,threads,seed,fragments,leaves,nodes,max_depth,runs,"
      "seconds,cutting_seconds,hull_seconds,bond_seconds,other_seconds,planes_missed,"
      "planes_rejected,us_per_split_all_levels,half_fragments,half_runs,half_cutting_seconds,half_internal_nodes,"
      "us_per_split_last_level,node_triangles,leaf_triangles,ns_per_output_triangle,peak_rss_mb,baseline_rss_mb,"
      "validated_leaves,invalid_leaves,validate_seconds,manifold_status,manifold_repeat,manifold_seconds,"
      "manifold_runs,manifold_pieces,manifold_triangles,manifold_bad_pieces,manifold_maxrss_mb,"
      "manifold_wasm_heap_mb,manifold_over_shatter,leaf_triangles_over_manifold,cgal_status,cgal_seconds,"
      "cgal_over_shatter,cgal_over_cutting,cgal_nodes_done,cgal_internal_nodes,cgal_pieces,cgal_invalid,"
      "cgal_missing,fracture_seconds,fracture_runs,fracture_peak_rss_mb,shatter_file_bytes,"
      "manifold_over_fracture,two_thread_pairs,fracture_1_thread_seconds,fracture_2_threads_seconds,"
      "two_thread_speedup,two_thread_files_identical,failed,note");
  for (const Row& r : rows) {
    const BuildRun& f = r.full.first;
    const bool ok = r.full.ok;
    // A build that failed has no figures: its measured columns stay empty.
    auto n = [&](double v) { return ok ? v : not_measured; };
    csv.field(r.id).field(r.input->name).field(r.input->mesh.triangle_count()).field(r.input->plane_faces);
    csv.field("plane").field("thesis").field(1).field(seed).field(r.fragments);
    csv.field_if(ok, f.leaves).field_if(ok, f.nodes).field_if(ok, f.max_depth).field(r.full.runs);
    csv.field(n(r.full.seconds)).field(n(r.full.cutting)).field(n(r.full.hull)).field(n(r.full.bond));
    csv.field(n(r.full.other())).field_if(ok, f.report.planes_missed).field_if(ok, f.report.planes_rejected);
    csv.field(r.us_per_split_all());
    if (r.half && r.half->ok) {
      csv.field(r.fragments / 2).field(r.half->runs).field(r.half->cutting).field(r.half->internal_nodes());
    } else {
      csv.empty(4);
    }
    csv.field(r.us_per_split_last()).field_if(ok, f.node_triangles).field_if(ok, f.leaf_triangles);
    csv.field(r.ns_per_triangle()).field(n(f.peak_mb)).field(n(f.baseline_mb));
    csv.field_if(ok && f.invalid >= 0, f.validated).field_if(ok && f.invalid >= 0, f.invalid);
    csv.field(n(f.validate_seconds));
    const ManifoldResult& m = r.manifold;
    // Every repeat's seconds in one field, space-separated.
    std::string runs;
    for (double s : m.runs) {
      if (!runs.empty()) runs += ' ';
      runs += csv_number(s);
    }
    csv.field(m.status_name()).field_if(m.repeat != 0, m.repeat).field(m.seconds).field(runs);
    csv.field_if(m.ok(), m.pieces).field_if(m.ok(), m.triangles).field_if(m.ok(), m.bad_pieces);
    csv.field(m.ok() ? m.maxrss_mb : not_measured).field(m.wasm_mb);
    csv.field(r.manifold_ratio()).field(r.leaf_triangles_over_manifold());
    if (r.cgal()) {
      const PeerResult& p = *r.cgal();
      csv.field(p.status_name()).field(p.clip_seconds).field(r.cgal_ratio()).field(r.cgal_ratio_to_cutting());
      csv.field(p.nodes_done).field(p.internal_nodes).field_if(p.pieces >= 0, p.pieces);
      csv.field_if(p.invalid >= 0, p.invalid).field(p.missing);
    } else {
      csv.field("not run").empty(8);
    }
    const EndToEnd& c = r.command;
    csv.field(c.ok ? c.seconds : not_measured).field_if(c.ok, c.runs).field(c.ok ? c.peak_mb : not_measured);
    csv.field_if(c.ok, c.file_bytes).field(r.manifold_ratio_end_to_end());
    const ThreadPair& t = r.threads;
    csv.field_if(t.ok, t.pairs).field(t.one_seconds).field(t.two_seconds).field(t.speedup);
    if (t.ok) {
      csv.field(t.identical);
    } else {
      csv.empty(1);
    }
    std::string note = r.note;
    if (!m.ok() && !m.detail.empty()) note += (note.empty() ? "" : "; ") + ("Manifold: " + m.detail);
    if (m.ok() && !m.detail.empty()) note += (note.empty() ? "" : "; ") + ("Manifold: " + m.detail);
    if (r.cgal() && !r.cgal()->detail.empty()) note += (note.empty() ? "" : "; ") + ("CGAL: " + r.cgal()->detail);
    csv.field(r.failed).field(note);
    csv.end_row();
  }
  csv.save(path);
}

// ---------------------------------------------------------------------------
// Command line (CLI11).

int parse(int argc, char** argv, Options& o) {
  CLI::App app{
      "shatter-bench-plane: the project's performance targets (issue item 7) on the plane kernel, 1 thread, "
      "each row with its peers in the same run: Manifold 3.5.4 (npm manifold-3d, WebAssembly under Node, "
      "bench/peers/manifold/fracture.mjs) and CGAL 5.5 PMP::clip replaying the same planes. Each row times "
      "build_mesh_tree in a forked process and the shatter fracture command end to end (read, check, build, "
      "write). Rows: cube -> 256, 65,536 and 2^20 fragments; curved meshes of the test corpus at about 5.7k, "
      "18k and 52k triangles: elephant.off (5,558) and blobby.off subdivided once (16,200) -> 256 and 4,096, "
      "fandisk.off subdivided once (51,784) -> 256, 4,096 and 65,536; knot1.off subdivided twice (102,400) "
      "-> 256 and 65,536. Prints Markdown tables "
      "(inputs, shatter, peers, targets) on stdout, progress on stderr. Exit status: 0 when every build "
      "succeeded with every checked leaf valid, 2 when not (peers and missed targets never count), 1 on errors.",
      "shatter-bench-plane"};
  app.add_flag("--quick", o.quick,
               "Smoke run for CI, seconds long: cube -> 256 only, one run per build, Manifold (1 repeat) "
               "and CGAL only when available");
  app.add_option("--csv", o.csv, "Also write one CSV row per table row to this file");
  app.add_option("--rows", o.rows,
                 "Comma-separated rows: ids (cube-256, cube-65536, cube-1048576, elephant-256, elephant-4096, "
                 "blobbyx4-256, blobbyx4-4096, fandiskx4-256, fandiskx4-4096, fandiskx4-65536, knot1x16-256, "
                 "knot1x16-65536; any N works, e.g. cube-4096) or mesh names (cube, elephant, blobbyx4, "
                 "fandiskx4, knot1x16) for all of theirs; default all");
  app.add_option("--max-fragments", o.max_fragments, "Drop the rows above N fragments")
      ->check(CLI::Range(1u, 1u << 22));
  app.add_option("--seed", o.seed, "Root seed of every build and of Manifold's stream")->capture_default_str();
  app.add_option("--mesh-dir", o.mesh_dir, "Folder holding fandisk.off (default: the test corpus; its rows are skipped without it)")
      ->capture_default_str();
  app.add_option("--knot", o.knot, "knot1.off (bundled)")->capture_default_str();
  app.add_option("--manifold-script", o.manifold_script, "Manifold's fracture.mjs (needs npm ci in its folder)")
      ->capture_default_str();
  app.add_option("--node", o.node, "The Node executable (a name looked up on PATH, or a path)")->capture_default_str();
  app.add_option("--manifold-timeout", o.manifold_timeout,
                 "Wall-clock limit of Manifold per repeat, seconds (its process gets this times its repeats)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--manifold-repeat", o.manifold_repeat,
                 "Manifold's --repeat (default 3 up to 65,536 fragments, 1 above; 1 with --quick)")
      ->check(CLI::Range(1, 100));
  app.add_flag("--no-manifold", o.no_manifold, "Skip Manifold");
  app.add_option("--shatter", o.shatter_exe, "The shatter executable timed end to end (fracture, 1 thread)")
      ->capture_default_str();
  app.add_flag("--no-end-to-end", o.no_end_to_end, "Skip timing the shatter fracture command");
  app.add_flag("--two-threads", o.two_threads,
               "Also run shatter fracture on 2 threads and on 1 in turn (at least 3 pairs; 1 with --quick), report the median "
               "speed-up of the pairs and whether each pair's files are identical byte for byte (a row whose files "
               "differ fails)");
  app.add_option("--peer-timeout", o.peer_timeout, "Wall-clock limit of one CGAL replay, seconds")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--peer-memory-mb", o.peer_memory_mb, "Address space a CGAL replay may add")
      ->check(CLI::Range(std::uint64_t{64}, std::uint64_t{1} << 20))
      ->capture_default_str();
  app.add_option("--cgal-max", o.cgal_max, "Largest N replayed by CGAL")->capture_default_str();
  app.add_flag("--no-cgal", o.no_cgal, "Skip the CGAL replay");
  app.add_flag("--no-peers", o.no_peers, "Skip both peers");
  app.add_flag("--no-validate", o.no_validate, "Skip validating the leaves (and CGAL's pieces)");
  app.add_option("--validate-sample", o.validate_sample,
                 "Validate only M evenly spaced leaves (leaf i*L/M) of a tree with more than M leaves; 0 = all")
      ->capture_default_str();
  app.add_flag("--no-last-level", o.no_last_level, "Skip the second build to N/2 (µs/split of the last level)");
  app.add_option("--no-repeat-seconds", o.no_repeat_seconds, "A build run longer than this is not repeated")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  return shatter::bench::parse_command_line(app, argc, argv, 1).value_or(-1);
}

/// The 1-minute load average (/proc/loadavg), to say how busy the shared machine was.
std::string load_average() {
  std::ifstream in("/proc/loadavg");
  std::string one;
  in >> one;
  return one.empty() ? "?" : one;
}

std::string today() {
  const std::time_t now = std::time(nullptr);
  char buffer[32];
  std::strftime(buffer, sizeof buffer, "%Y-%m-%d", std::localtime(&now));
  return buffer;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (const int code = parse(argc, argv, o); code >= 0) return code;
  try {
    Repeat repeat;
    repeat.no_repeat_seconds = o.no_repeat_seconds;
    if (o.quick) {
      repeat.min_runs = 1;
      repeat.min_total_seconds = 0;
      repeat.max_runs = 1;
      if (o.rows.empty()) o.rows = "cube-256";
    }

    const std::string load_at_start = load_average();
    std::vector<Input> inputs;
    inputs.push_back(make_cube());
    std::vector<RowSpec> specs = select_rows(o.rows);
    auto wanted = [&](const std::string& prefix) {
      return std::any_of(specs.begin(), specs.end(), [&](const RowSpec& r) {
        return r.input == prefix && (!o.max_fragments || r.fragments <= *o.max_fragments);
      });
    };
    if (wanted("knot1")) inputs.push_back(make_subdivided("knot1", o.knot, 50000));
    if (wanted("fandisk")) inputs.push_back(make_subdivided("fandisk", o.mesh_dir / "fandisk.off", 50000));
    // The sizes for curved meshes: about 5.7k, 18k and 52k triangles.
    if (wanted("elephant")) inputs.push_back(make_subdivided("elephant", o.mesh_dir / "elephant.off", 0));
    if (wanted("blobby")) inputs.push_back(make_subdivided("blobby", o.mesh_dir / "blobby.off", 16000));
    for (Input& i : inputs) {
      if (i.available) i.plane_faces = shatter::prepare_plane_input(i.mesh).geometry.planes.size();
    }
    if (!wanted("cube")) inputs.erase(inputs.begin());

    OffFiles files;
    std::vector<Row> rows;
    std::vector<std::string> skipped;
    for (const RowSpec& spec : specs) {
      if (o.max_fragments && spec.fragments > *o.max_fragments) continue;
      const Input* input = input_for(spec.input, inputs);
      if (!input || !input->available) {
        skipped.push_back(spec.input + "-" + std::to_string(spec.fragments) + " (" +
                          (input ? input->missing : std::string("no input")) + ")");
        std::cerr << skipped.back() << ": skipped\n";
        continue;
      }
      rows.push_back(run_row(spec, *input, o, repeat, files));
    }
    const std::vector<Verdict> verdicts = judge(rows);

    std::cout << "shatter-bench-plane, " << today() << ": seed " << o.seed
              << "; shatter = build_mesh_tree, plane kernel, thesis strategy, 1 thread, each run in a fresh forked "
                 "process, median of "
              << (o.quick ? "1 run (--quick)" : ">= 3 runs and >= 0.3 s (1 run if > " + fixed(o.no_repeat_seconds, 0) + " s)")
              << "; Manifold = fracture.mjs (WASM), same method and seed, not the same planes, timeout "
              << fixed(o.manifold_timeout, 0) << " s per repeat; CGAL = PMP::clip replaying shatter's planes, limit "
              << fixed(o.peer_timeout, 0) << " s; " << ::sysconf(_SC_NPROCESSORS_ONLN)
              << " hardware threads, shared: 1-minute load average " << load_at_start << " at the start, "
              << load_average() << " at the end; allocator: " << shatter::bench::allocator_description() << ".\n\n";
    print_tables(std::cout, rows, inputs, skipped, verdicts);
    if (o.csv) write_csv(*o.csv, rows, o.seed);

    int failures = 0;
    for (const Row& r : rows) {
      if (!r.failed) continue;
      ++failures;
      std::cerr << "FAILED: " << r.id << ": " << r.note << '\n';
    }
    return failures ? 2 : 0;
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << '\n';
    return 1;
  }
}
