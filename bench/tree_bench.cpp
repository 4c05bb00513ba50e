// shatter-bench-tree: the seed thesis's chapter 6.2 ("Testing Fragment Generation")
// measured again, side by side with a peer.
//
// Part 1, time against fragment count (seed 6.2.1 and 6.2.3, where the seed's
// builder failed at 2,048 fragments): a 1 x 1 x 1 box (12 triangles) cut into
// N = 2, 4, ..., 65,536 fragments with the thesis strategy, on 1 and on 2 threads,
// no further once a 1-thread build took longer than --stop-seconds.
//
// Part 2, the seed's meshes at 256 fragments (6.2.2): the box, an 800-triangle
// torus, the 1,520-triangle hollow egg shell and elephant.off (standing in for the
// Stanford bunny: organic, with protrusions), each with the thesis, balanced and
// axis strategies, 1 thread. The coefficient of variation of the fragment volumes
// (standard deviation / mean) measures the seed's "clusters of very small
// fragments".
//
// The peer: CGAL 5.5 PMP::clip(clip_volume(true)) on Surface_mesh<Epick>, replaying
// the very planes of shatter's 1-thread thesis tree. For each internal
// node in preorder, the peer's piece for that node is clipped on both sides of the
// node's plane (two copies, clipped by the plane and by its opposite, as
// shatter-bench-cut does), each side is split into connected components, and those
// are matched to the node's children on that side by nearest area-weighted surface
// centroid. A side whose clip returns false or throws, or whose component count
// differs from shatter's child count, ends the replay of those children's subtrees:
// counted, and their leaves reported missing. Each replay runs in a forked child
// process under a wall-clock limit (--peer-timeout) and an address-space limit,
// because after a few levels rounded points make CGAL's pieces degenerate and clip
// may then hang, explode or crash; a timeout or crash is reported as such, with the
// progress made before it.
//
// Timing: std::chrono::steady_clock. Shatter: around build_mesh_tree only, which
// includes validating and preparing the input, rounding and certifying every
// piece, mass properties, convex hulls and bonds, so shatter does more work than
// the peer; the tree is destroyed after the clock stops. Repeated until >= 3 runs
// and >= 0.3 s (a run longer than 2 s is not repeated); the median is reported. The
// peer: the sum of its clip and split_connected_components calls only (copies,
// matching and checks are outside), a single run. The machine is shared and noisy:
// read the ratios peer/shatter measured in the same run, not the absolute times.
//
// Checks, outside every clock: every shatter leaf through validate_mesh (closed,
// oriented, manifold, positive volume, no self-intersection, no zero-area
// triangle); the 2-thread tree's fingerprint against the 1-thread tree's (they must
// be byte-identical); every peer leaf piece through is_closed, does_self_intersect
// and volume > 0.

#include <CLI/CLI.hpp>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "bench_support.hpp"
#include "command_line.hpp"
#include "csv.hpp"
#include "shatter/generators/corpus.hpp"
#include "shatter/generators/solids.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/mesh.hpp"
#include "shatter/kernel/validate.hpp"
#include "shatter/meshtree/build.hpp"
#include "shatter/meshtree/stats.hpp"
#include "shatter/meshtree/tree.hpp"

namespace {

using shatter::bench::CsvWriter;
using shatter::bench::fixed;
using shatter::bench::not_measured;
using shatter::bench::ratio_text;
using shatter::bench::seconds_between;
using shatter::bench::PeerResult;
using shatter::bench::seconds_text;
using shatter::bench::with_thousands;
using Clock = std::chrono::steady_clock;
using shatter::MeshTree;
using shatter::NodeIndex;
using shatter::Strategy;

// ---------------------------------------------------------------------------
// Options.

struct Options {
  std::filesystem::path mesh_dir = shatter::test::mesh_dir();
  std::optional<std::filesystem::path> csv;
  std::uint64_t seed = 1;
  bool quick = false;
  bool validate = true;
  bool peer = true;
  bool scaling = true;
  bool meshes = true;
  std::optional<std::uint32_t> max_fragments, mesh_fragments, peer_max;
  std::optional<std::filesystem::path> dump_invalid;
  double stop_seconds = 300;
  std::optional<double> peer_timeout;
  std::uint64_t peer_memory_mb = 8192;
};

/// The options with --quick's smaller defaults applied.
struct Plan {
  Options options;
  std::uint32_t max_fragments = 65536;
  std::uint32_t mesh_fragments = 256;
  std::uint32_t peer_max = 4096;
  double peer_timeout = 60;
  int min_runs = 3;
  double min_total_seconds = 0.3;
  int max_runs = 1000;
  double no_repeat_seconds = 2.0;  ///< a run longer than this is not repeated
};

Plan make_plan(const Options& options) {
  Plan plan;
  plan.options = options;
  const bool q = options.quick;
  plan.max_fragments = options.max_fragments.value_or(q ? 32 : 65536);
  plan.mesh_fragments = options.mesh_fragments.value_or(q ? 8 : 256);
  plan.peer_max = options.peer_max.value_or(q ? 16 : 4096);
  plan.peer_timeout = options.peer_timeout.value_or(q ? 30 : 60);
  if (q) {
    plan.min_runs = 1;
    plan.min_total_seconds = 0;
  }
  return plan;
}

// ---------------------------------------------------------------------------
// Small helpers.

/// `digits` significant digits, exponent form only for tiny values (a sliver fragment).
std::string significant(double value, int digits) {
  if (std::isnan(value)) return "–";
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*g", digits, value);
  return buffer;
}

/// 64-bit FNV-1a over raw bytes: a fingerprint to compare two trees, not a hash
/// for tables.
class Fingerprint {
 public:
  void add_bytes(const void* data, std::size_t size) {
    const auto* bytes = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < size; ++i) {
      state_ ^= bytes[i];
      state_ *= 0x100000001B3ull;
    }
  }
  template <class T>
  void add(const T& value) {
    add_bytes(&value, sizeof value);
  }
  template <class T>
  void add_vector(const std::vector<T>& values) {
    add(values.size());
    add_bytes(values.data(), values.size() * sizeof(T));
  }
  std::uint64_t value() const { return state_; }

 private:
  std::uint64_t state_ = 0xCBF29CE484222325ull;
};

// ---------------------------------------------------------------------------
// Shatter's side: the leaves of one tree.

struct LeafSummary {
  long invalid = -1;          ///< leaves failing validate_mesh; -1 = not checked
  std::string first_invalid;  ///< which leaf and why, for the note
  NodeIndex first_invalid_node = shatter::no_node;
  double volume_cv = not_measured;
  double smallest_over_mean = not_measured;
  std::uint32_t max_depth = 0;
  std::uint64_t fingerprint = 0;
};

std::uint64_t tree_fingerprint(const MeshTree& tree) {
  Fingerprint f;
  f.add(tree.nodes.size());
  for (NodeIndex k = 0; k < tree.nodes.size(); ++k) {
    const shatter::MeshTreeNode& node = tree.nodes[k];
    f.add_vector(node.mesh->positions);
    f.add_vector(node.mesh->triangles);
    f.add_vector(node.mesh->surfaces);
    f.add(node.parent);
    f.add(tree.cut_planes[k]);
  }
  f.add_vector(tree.leaf_nodes);
  f.add(tree.bonds.size());
  return f.value();
}

LeafSummary summarize_leaves(const MeshTree& tree, bool validate) {
  LeafSummary summary;
  summary.fingerprint = tree_fingerprint(tree);
  const shatter::TreeStats stats = shatter::tree_stats(tree);
  summary.max_depth = stats.max_depth;
  if (stats.leaf_count > 0 && stats.fragment_volume.mean > 0) {
    summary.volume_cv = stats.fragment_volume.coefficient_of_variation;
    summary.smallest_over_mean = stats.fragment_volume.min / stats.fragment_volume.mean;
  }
  const std::size_t count = tree.leaf_count();
  if (!validate) return summary;
  summary.invalid = 0;
  for (std::size_t i = 0; i < count; ++i) {
    const NodeIndex node = tree.leaf_nodes[i];
    const auto report = shatter::validate_mesh(tree.nodes[node].mesh);
    if (report.valid()) continue;
    if (summary.invalid++ > 0) continue;
    summary.first_invalid_node = node;
    summary.first_invalid = "leaf " + std::to_string(i) + " (node " + std::to_string(node) + ", depth " +
                            std::to_string(tree.nodes[node].depth) + "): " + report.summary();
  }
  return summary;
}

// ---------------------------------------------------------------------------
// The peer: CGAL clip replaying a tree's planes.

/// The CGAL replay (bench_support) under this run's limits.
PeerResult run_peer_isolated(const MeshTree& tree, const shatter::Mesh& input, const Plan& plan) {
  return shatter::bench::replay_with_cgal_isolated(
      tree, input, {plan.peer_timeout, plan.options.peer_memory_mb, plan.options.validate});
}

// ---------------------------------------------------------------------------
// One measurement: a CSV row.

struct NamedInput {
  std::string name;
  shatter::Mesh mesh;
};

struct Row {
  std::string section;
  std::string mesh;
  std::size_t triangles = 0;
  Strategy strategy = Strategy::thesis;
  unsigned threads = 1;
  std::uint32_t fragments = 0;
  bool built = false;
  std::size_t leaves = 0, nodes = 0;
  int runs = 0;
  double seconds = not_measured;
  /// Where the first run's time went (cutting, hulls, bonds) and its redrawn planes.
  shatter::BuildReport report;
  LeafSummary leaf_summary;
  /// The peer's replay of this tree (1-thread rows only).
  std::optional<PeerResult> peer;
  bool failed = false;  ///< the build threw, a leaf is invalid, or thread counts disagree
  std::string note;

  double us_per_cut() const {
    return nodes > leaves ? seconds * 1e6 / static_cast<double>(nodes - leaves) : not_measured;
  }
  double peer_ratio() const { return peer ? peer->comparable_seconds() / seconds : not_measured; }
  /// The peer only cuts: its time against shatter's cutting phase alone.
  double peer_ratio_to_cutting() const {
    return peer && report.cutting_seconds > 0 ? peer->comparable_seconds() / report.cutting_seconds : not_measured;
  }
  /// "cut / hulls / bonds" seconds of the first run.
  std::string phases() const {
    if (!built) return "–";
    return seconds_text(report.cutting_seconds) + " / " + seconds_text(report.hull_seconds) + " / " +
           seconds_text(report.bond_seconds);
  }
  std::string redrawn() const {
    if (!built) return "–";
    return std::to_string(report.planes_missed) + "/" + std::to_string(report.planes_rejected);
  }
  void add_note(const std::string& text) { note += (note.empty() ? "" : "; ") + text; }
};

/// Writes the first invalid leaf and its parent, named so the build can be repeated.
void dump_first_invalid(const std::filesystem::path& dir, const Row& row, const MeshTree& tree, std::uint64_t seed) {
  const NodeIndex leaf = row.leaf_summary.first_invalid_node;
  if (leaf == shatter::no_node) return;
  std::filesystem::create_directories(dir);
  const std::string stem = row.mesh + "-" + std::string(shatter::strategy_name(row.strategy)) + "-N" +
                           std::to_string(row.fragments) + "-seed" + std::to_string(seed) + "-node" +
                           std::to_string(leaf);
  shatter::write_mesh(tree.nodes[leaf].mesh, dir / (stem + ".off"), shatter::MeshFormat::off);
  const NodeIndex parent = tree.nodes[leaf].parent;
  if (parent != shatter::no_node)
    shatter::write_mesh(tree.nodes[parent].mesh, dir / (stem + "-parent" + std::to_string(parent) + ".off"),
                        shatter::MeshFormat::off);
}

/// Builds repeatedly and times it; checks the first run's tree and, if asked,
/// replays it with the peer. `one_thread` is the same build on 1 thread, whose tree
/// this one must equal.
Row bench_build(const std::string& section, const NamedInput& input, Strategy strategy, unsigned threads,
                std::uint32_t fragments, const Plan& plan, bool with_peer, const Row* one_thread = nullptr) {
  Row row;
  row.section = section;
  row.mesh = input.name;
  row.triangles = input.mesh.triangle_count();
  row.strategy = strategy;
  row.threads = threads;
  row.fragments = fragments;

  shatter::TreeRecipe recipe;
  recipe.fragments = fragments;
  recipe.seed = plan.options.seed;
  recipe.strategy = strategy;

  std::cerr << section << ": " << input.name << " " << shatter::strategy_name(strategy) << " " << threads
            << " thread(s) N=" << fragments << " ..." << std::flush;
  std::vector<double> times;
  try {
    double total = 0;
    for (int run = 0; run < plan.max_runs; ++run) {
      const auto t0 = Clock::now();
      shatter::BuildReport report;
      const MeshTree tree = shatter::build_mesh_tree(input.mesh, recipe, {.threads = threads, .report = &report});
      const double seconds = seconds_between(t0, Clock::now());
      if (run == 0) row.report = report;
      times.push_back(seconds);
      total += seconds;
      if (run == 0) {
        row.built = true;
        row.leaves = tree.leaf_count();
        row.nodes = tree.nodes.size();
        if (row.leaves < fragments) {
          row.failed = true;
          row.add_note("only " + std::to_string(row.leaves) + " leaves");
        }
        const bool reuse = one_thread && one_thread->built && one_thread->leaf_summary.invalid >= 0;
        row.leaf_summary = summarize_leaves(tree, plan.options.validate && !reuse);
        if (one_thread && one_thread->built) {
          if (row.leaf_summary.fingerprint == one_thread->leaf_summary.fingerprint) {
            if (reuse) {
              row.leaf_summary.invalid = one_thread->leaf_summary.invalid;
              row.leaf_summary.first_invalid = one_thread->leaf_summary.first_invalid;
              row.leaf_summary.first_invalid_node = one_thread->leaf_summary.first_invalid_node;
            }
          } else {
            row.failed = true;
            row.add_note("tree differs from the 1-thread tree");
            if (reuse) row.leaf_summary = summarize_leaves(tree, plan.options.validate);
          }
        }
        if (row.leaf_summary.invalid > 0) {
          if (plan.options.dump_invalid) dump_first_invalid(*plan.options.dump_invalid, row, tree, plan.options.seed);
          row.failed = true;
          row.add_note(std::to_string(row.leaf_summary.invalid) + " invalid leaves, first " +
                       row.leaf_summary.first_invalid);
        }
        if (with_peer) {
          std::cerr << " [peer" << std::flush;
          try {
            row.peer = run_peer_isolated(tree, input.mesh, plan);
          } catch (const std::exception& e) {  // pipe or fork failed: the peer's problem, not shatter's
            row.peer = PeerResult{};
            row.peer->status = PeerResult::Status::error;
            row.peer->detail = e.what();
          }
          std::cerr << " " << row.peer->status_name() << " " << seconds_text(row.peer->clip_seconds) << " s]"
                    << std::flush;
        }
      }
      if (seconds > plan.no_repeat_seconds) break;
      if (static_cast<int>(times.size()) >= plan.min_runs && total >= plan.min_total_seconds) break;
    }
  } catch (const std::exception& e) {
    row.failed = true;
    row.add_note(std::string("build threw: ") + e.what());
  }
  row.runs = static_cast<int>(times.size());
  if (row.built) row.seconds = shatter::bench::median(times, not_measured);
  std::cerr << " " << seconds_text(row.seconds) << " s (" << row.runs << " runs)"
            << (row.failed ? " FAILED: " + row.note : "") << "\n";
  return row;
}

// ---------------------------------------------------------------------------
// The two sections.

shatter::Mesh seed_cube() { return shatter::test::box({-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5}); }

struct ScalingLine {
  std::uint32_t fragments = 0;
  Row one_thread, two_threads;
  std::string peer_skipped;  ///< why the peer did not run, if not
  std::string stopped_here;  ///< why no larger N was built, if so
};

std::vector<ScalingLine> run_scaling(const Plan& plan) {
  const NamedInput cube{"cube", seed_cube()};
  std::vector<ScalingLine> lines;
  std::string peer_stop;
  for (std::uint64_t n = 2; n <= plan.max_fragments; n *= 2) {
    ScalingLine line;
    line.fragments = static_cast<std::uint32_t>(n);
    const bool peer_wanted = plan.options.peer && n <= plan.peer_max;
    line.peer_skipped = !plan.options.peer ? "--no-peer" : !peer_wanted ? "above --peer-max" : peer_stop;
    line.one_thread =
        bench_build("scaling", cube, Strategy::thesis, 1, line.fragments, plan, peer_wanted && peer_stop.empty());
    if (line.one_thread.peer && line.one_thread.peer->status != PeerResult::Status::ok && peer_stop.empty())
      peer_stop = "peer " + line.one_thread.peer->status_name() + " at N=" + std::to_string(n);
    line.two_threads = bench_build("scaling", cube, Strategy::thesis, 2, line.fragments, plan, false, &line.one_thread);
    const bool stop = line.one_thread.seconds > plan.options.stop_seconds && n * 2 <= plan.max_fragments;
    if (stop)
      line.stopped_here = "no larger N: the 1-thread build took " + seconds_text(line.one_thread.seconds) +
                          " s, over --stop-seconds";
    lines.push_back(std::move(line));
    if (stop) {
      std::cerr << "scaling: " << lines.back().stopped_here << "\n";
      break;
    }
  }
  return lines;
}

std::vector<NamedInput> seed_meshes(const Plan& plan) {
  std::vector<NamedInput> inputs;
  inputs.push_back({"cube", seed_cube()});
  inputs.push_back({"torus-800", shatter::test::torus(1.0, 0.35, 20, 20)});
  inputs.push_back({"hollow-egg", shatter::test::hollow_egg()});
  const auto elephant = plan.options.mesh_dir / "elephant.off";
  if (!std::filesystem::exists(elephant)) throw std::runtime_error("mesh not found: " + elephant.string());
  inputs.push_back({"elephant.off", shatter::read_mesh(elephant)});
  return inputs;
}

std::vector<Row> run_meshes(const Plan& plan) {
  std::vector<Row> rows;
  for (const NamedInput& input : seed_meshes(plan)) {
    for (const Strategy strategy : {Strategy::thesis, Strategy::balanced, Strategy::axis}) {
      // One peer run per mesh: it replays planes, and the thesis strategy is the seed's.
      rows.push_back(bench_build("meshes", input, strategy, 1, plan.mesh_fragments, plan,
                                 plan.options.peer && strategy == Strategy::thesis));
    }
  }
  return rows;
}

// ---------------------------------------------------------------------------
// Output.

std::string invalid_text(const Row& row) {
  if (!row.built) return "–";
  return row.leaf_summary.invalid < 0 ? "n/c" : std::to_string(row.leaf_summary.invalid);
}

/// The peer table's cells of `row`'s replay, from "CGAL s" to "status", joined by " | ".
std::string peer_cells(const Row& row) {
  const PeerResult& p = *row.peer;
  const auto checked = [](long v) { return v < 0 ? std::string("n/c") : std::to_string(v); };
  return (p.status == PeerResult::Status::ok ? seconds_text(p.clip_seconds) : p.status_name()) + " | " +
         ratio_text(row.peer_ratio()) + " | " + ratio_text(row.peer_ratio_to_cutting()) + " | " +
         checked(p.pieces) + " | " + checked(p.invalid) + " | " + std::to_string(p.missing) + " | " +
         std::to_string(p.failed_clips) + "/" + std::to_string(p.threw) + " | " + std::to_string(p.mismatches) +
         " | " + p.status_name() + (p.detail.empty() ? "" : ": " + p.detail);
}

void print_scaling(std::ostream& out, const std::vector<ScalingLine>& lines) {
  out << "### Time against fragment count: cube (12 triangles), strategy thesis\n\n"
      << "| N | leaves | nodes | depth | 1 thread s | µs/cut | cut / hulls / bonds s | planes missed/rejected | "
         "2 threads s | speedup | invalid leaves | note |\n"
      << "|---:|---:|---:|---:|---:|---:|---|---|---:|---:|---:|---|\n";
  for (const auto& l : lines) {
    const Row& one = l.one_thread;
    const Row& two = l.two_threads;
    std::string note = one.note;
    // The 2-thread tree is the 1-thread tree (else its note says so): its note would repeat.
    if (!two.note.empty() && two.note != one.note) note += (note.empty() ? "" : "; ") + ("2 threads: " + two.note);
    out << "| " << with_thousands(l.fragments) << " | " << with_thousands(one.leaves) << " | "
        << with_thousands(one.nodes) << " | " << one.leaf_summary.max_depth << " | " << seconds_text(one.seconds)
        << " | " << ratio_text(one.us_per_cut()) << " | " << one.phases() << " | " << one.redrawn() << " | "
        << seconds_text(two.seconds) << " | " << ratio_text(one.seconds / two.seconds) << " | " << invalid_text(one)
        << " | " << note << " |\n";
  }
  if (!lines.empty() && !lines.back().stopped_here.empty()) out << "\n" << lines.back().stopped_here << ".\n";
  out << "\n### Peer: CGAL PMP clip replaying the same planes (1-thread tree)\n\n"
      << "| N | CGAL s | CGAL/shatter | CGAL/shatter cutting | pieces | invalid | missing | clips failed/threw | "
         "component mismatches | status |\n"
      << "|---:|---:|---:|---:|---:|---:|---:|---|---:|---|\n";
  for (const auto& l : lines) {
    if (!l.one_thread.peer) {
      if (!l.peer_skipped.empty() && l.peer_skipped != "above --peer-max" && l.peer_skipped != "--no-peer")
        out << "| " << with_thousands(l.fragments) << " | skipped | | | | | | | | " << l.peer_skipped << " |\n";
      continue;
    }
    out << "| " << with_thousands(l.fragments) << " | " << peer_cells(l.one_thread) << " |\n";
  }
}

void print_meshes(std::ostream& out, const std::vector<Row>& rows, std::uint32_t fragments) {
  out << "\n### The seed's meshes at " << with_thousands(fragments) << " fragments, 1 thread\n\n"
      << "| mesh | triangles | strategy | leaves | s | cut / hulls / bonds s | planes missed/rejected | "
         "volume CV | smallest/mean | invalid leaves | note |\n"
      << "|---|---:|---|---:|---:|---|---|---:|---:|---:|---|\n";
  for (const Row& r : rows) {
    out << "| " << r.mesh << " | " << with_thousands(r.triangles) << " | " << shatter::strategy_name(r.strategy)
        << " | " << with_thousands(r.leaves) << " | " << seconds_text(r.seconds) << " | " << r.phases() << " | "
        << r.redrawn() << " | "
        << (std::isnan(r.leaf_summary.volume_cv) ? "–" : fixed(r.leaf_summary.volume_cv, 3)) << " | "
        << significant(r.leaf_summary.smallest_over_mean, 3) << " | " << invalid_text(r) << " | " << r.note
        << " |\n";
  }
  bool any_peer = false;
  for (const Row& r : rows) any_peer = any_peer || r.peer.has_value();
  if (!any_peer) return;
  out << "\n### Peer on the seed's meshes: CGAL PMP clip replaying the thesis tree's planes\n\n"
      << "| mesh | CGAL s | CGAL/shatter | CGAL/shatter cutting | pieces | invalid | missing | clips failed/threw | "
         "component mismatches | status |\n"
      << "|---|---:|---:|---:|---:|---:|---:|---|---:|---|\n";
  for (const Row& r : rows) {
    if (r.peer) out << "| " << r.mesh << " | " << peer_cells(r) << " |\n";
  }
}

void write_csv(const std::filesystem::path& path, const std::vector<const Row*>& rows) {
  CsvWriter csv(
      "section,mesh,triangles,strategy,kernel,threads,fragments_requested,leaves,nodes,runs,seconds,us_per_cut,"
      "cutting_seconds,hull_seconds,bond_seconds,planes_missed,planes_rejected,max_depth,invalid_leaves,volume_cv,"
      "smallest_volume_over_mean,tree_fingerprint,peer_status,peer_seconds,peer_ratio,peer_nodes_done,"
      "peer_internal_nodes,peer_pieces,peer_invalid,peer_missing,peer_failed,peer_threw,peer_mismatches,failed,note");
  for (const Row* r : rows) {
    char fingerprint[17];
    std::snprintf(fingerprint, sizeof fingerprint, "%016llx",
                  static_cast<unsigned long long>(r->leaf_summary.fingerprint));
    csv.field(r->section).field(r->mesh).field(r->triangles).field(shatter::strategy_name(r->strategy));
    // The kernel column stays so these rows read apart from the retired kernels' in older CSVs.
    csv.field("plane").field(r->threads).field(r->fragments).field(r->leaves);
    csv.field(r->nodes).field(r->runs).field(r->seconds).field(r->us_per_cut());
    csv.field(r->built ? r->report.cutting_seconds : not_measured);
    csv.field(r->built ? r->report.hull_seconds : not_measured);
    csv.field(r->built ? r->report.bond_seconds : not_measured);
    csv.field_if(r->built, r->report.planes_missed).field_if(r->built, r->report.planes_rejected);
    csv.field(r->leaf_summary.max_depth).field_if(r->leaf_summary.invalid >= 0, r->leaf_summary.invalid);
    csv.field(r->leaf_summary.volume_cv).field(r->leaf_summary.smallest_over_mean);
    csv.field_if(r->built, std::string_view(fingerprint));
    if (r->peer) {
      const PeerResult& p = *r->peer;
      csv.field(p.status_name()).field(p.clip_seconds).field(r->peer_ratio()).field(p.nodes_done);
      csv.field(p.internal_nodes).field_if(p.pieces >= 0, p.pieces).field_if(p.invalid >= 0, p.invalid);
      csv.field(p.missing).field(p.failed_clips).field(p.threw).field(p.mismatches);
    } else {
      csv.field("not run").empty(10);
    }
    std::string note = r->note;
    if (r->peer && !r->peer->detail.empty()) note += (note.empty() ? "" : "; ") + ("peer: " + r->peer->detail);
    csv.field(r->failed).field(note);
    csv.end_row();
  }
  csv.save(path);
}

// ---------------------------------------------------------------------------
// Command line.

/// Declares the command line: every option, its help and its checks, filling `options`.
void add_options(CLI::App& app, Options& options) {
  app.description(
      "shatter-bench-tree: the seed thesis's chapter 6.2 again: shatter::build_mesh_tree timed against the "
      "fragment count and on the thesis's meshes, with CGAL PMP clip replaying the same planes as the peer.");
  app.footer(
      "Sections:\n"
      "  scaling  a 1 x 1 x 1 box (12 triangles) cut into N = 2, 4, ..., --max-fragments fragments, strategy\n"
      "           thesis, on 1 and 2 threads. Per N: leaves, nodes, seconds (median of >= 3 runs and >= 0.3 s;\n"
      "           one run if > 2 s), microseconds per cut (per internal node), invalid leaves, and whether the\n"
      "           2-thread tree equals the 1-thread tree.\n"
      "  meshes   the box, an 800-triangle torus, the 1,520-triangle hollow egg and elephant.off cut into\n"
      "           --mesh-fragments fragments with the thesis, balanced and axis strategies, 1 thread: seconds,\n"
      "           leaves, coefficient of variation of the leaf volumes (std dev / mean), smallest leaf volume /\n"
      "           mean, invalid leaves.\n"
      "  peer     CGAL PMP::clip(clip_volume(true)), Surface_mesh<Epick>, replays the planes of the\n"
      "           1-thread thesis tree node by node (both sides of each plane, connected components matched to\n"
      "           shatter's children by nearest centroid), in a forked process with a time limit. Its time is\n"
      "           the sum of the clip and split calls. Reported: seconds, its ratio to shatter's whole build\n"
      "           and to shatter's cutting phase, leaf pieces that are not closed, self-intersect or have\n"
      "           volume <= 0 (invalid), leaves never produced (missing), clips that returned false (failed) or\n"
      "           threw, nodes whose component count differs from shatter's (mismatch), timeout or crash.\n"
      "\n"
      "Leaves are validated outside the clock (validate_mesh, with self-intersections).\n"
      "Exit status: 0 when every build succeeded and every shatter leaf is valid and the thread counts agree,\n"
      "2 when not (the peer's failures never count), 1 on a usage error or any other error.");
  constexpr std::uint32_t most_fragments = 1u << 22;
  const auto fragments = CLI::Range(1u, most_fragments);
  // Seconds must be a positive, finite number: "inf" would switch a limit off unseen.
  const CLI::Validator positive_seconds(
      [](const std::string& text) {
        char* end = nullptr;
        const double value = std::strtod(text.c_str(), &end);
        return !text.empty() && *end == '\0' && value > 0 && std::isfinite(value)
                   ? std::string()
                   : "wants a positive number of seconds, got '" + text + "'";
      },
      "SECONDS > 0");
  // CLI11 reads "-1" into an unsigned as 2^64 - 1; the old parser refused a sign.
  const CLI::Validator not_negative(
      [](const std::string& text) {
        return text.find('-') == std::string::npos ? std::string() : "wants a number >= 0, got '" + text + "'";
      },
      "");
  app.add_flag("--quick", options.quick,
               "Smoke run (CI): N up to 32, meshes at 8 fragments, peer up to 16, one run per measurement; "
               "a few seconds");
  app.add_option("--csv", options.csv, "Also write one CSV row per measurement to this file");
  app.add_option("--mesh-dir", options.mesh_dir, "Folder holding elephant.off")->capture_default_str();
  app.add_option("--seed", options.seed, "Root seed of every build")->check(not_negative)->capture_default_str();
  app.add_option_function<std::string>(
         "--section",
         [&options](const std::string& which) {
           options.scaling = which != "meshes";
           options.meshes = which != "scaling";
         },
         "Which sections to run: all (default), scaling or meshes")
      ->check(CLI::IsMember({"all", "scaling", "meshes"}));
  app.add_option("--max-fragments", options.max_fragments,
                 "Largest N of the scaling section (default 65536; 32 with --quick)")
      ->check(fragments);
  app.add_option("--stop-seconds", options.stop_seconds,
                 "End the scaling section once a 1-thread build took longer than this")
      ->check(positive_seconds)
      ->capture_default_str();
  app.add_option("--mesh-fragments", options.mesh_fragments,
                 "Fragments of the meshes section (default 256; 8 with --quick)")
      ->check(fragments);
  app.add_option("--peer-max", options.peer_max,
                 "Largest N of the scaling section replayed by the peer (default 4096; 16 with --quick); after a "
                 "peer timeout or crash no larger N is tried")
      ->check(fragments);
  app.add_option("--peer-timeout", options.peer_timeout,
                 "Wall-clock limit of one peer replay, seconds (default 60; 30 with --quick)")
      ->check(positive_seconds);
  app.add_option("--peer-memory-mb", options.peer_memory_mb, "Address space a peer replay may add, MB")
      ->check(not_negative & CLI::Range(std::uint64_t{64}, std::uint64_t{1} << 20))
      ->capture_default_str();
  app.add_flag_callback("--no-peer", [&options] { options.peer = false; }, "Skip the peer");
  app.add_flag_callback("--no-validate", [&options] { options.validate = false; },
                        "Skip the validity checks (leaves and peer pieces)");
  app.add_option("--dump-invalid", options.dump_invalid,
                 "Write the first invalid leaf of each build, and the node it was cut from, to this folder as "
                 "OFF files");
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  CLI::App app{"", "shatter-bench-tree"};
  add_options(app, options);
  if (const auto code = shatter::bench::parse_command_line(app, argc, argv, 1)) return *code;
  try {
    const Plan plan = make_plan(options);
    std::vector<ScalingLine> scaling;
    std::vector<Row> meshes;
    if (plan.options.scaling) scaling = run_scaling(plan);
    if (plan.options.meshes) meshes = run_meshes(plan);

    std::cout << "shatter-bench-tree: seed " << plan.options.seed << "; shatter time = build_mesh_tree (median of "
              << (plan.options.quick ? "1 run, --quick" : ">= 3 runs and >= 0.3 s, 1 run if > 2 s")
              << "); CGAL = PMP::clip(clip_volume(true)) + split_connected_components on Surface_mesh<Epick>, "
                 "1 run in a child process, limit "
              << fixed(plan.peer_timeout, 0) << " s; " << std::thread::hardware_concurrency()
              << " hardware threads.\n\n";
    if (!scaling.empty()) print_scaling(std::cout, scaling);
    if (!meshes.empty()) print_meshes(std::cout, meshes, plan.mesh_fragments);

    std::vector<const Row*> rows;
    for (const auto& l : scaling) {
      rows.push_back(&l.one_thread);
      rows.push_back(&l.two_threads);
    }
    for (const Row& r : meshes) rows.push_back(&r);
    if (plan.options.csv) write_csv(*plan.options.csv, rows);

    std::size_t failures = 0;
    for (const Row* r : rows) {
      if (!r->failed) continue;
      ++failures;
      std::cerr << "FAILED: " << r->mesh << " " << shatter::strategy_name(r->strategy) << " " << r->threads
                << " thread(s) N=" << r->fragments
                << " seed " << plan.options.seed << ": " << r->note << '\n';
    }
    return failures ? 2 : 0;
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << '\n';
    return 1;
  }
}
