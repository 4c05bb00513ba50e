#include "fracture.hpp"

#include <nlohmann/json.hpp>
#include <tbb/task_arena.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <atomic>
#include <cctype>
#include <charconv>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <string_view>
#include <vector>

#include "shatter/kernel/error.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/meshtree/build.hpp"
#include "shatter/meshtree/packed_node.hpp"
#include "shatter/meshtree/sites.hpp"
#include "shatter/meshtree/voronoi.hpp"
#include "shatter/formats/export.hpp"
#include "shatter/formats/file.hpp"
#include "shatter/meshtree/stats.hpp"
#include "shatter/meshtree/tree.hpp"
#include "errors.hpp"
#include "export.hpp"
#include "input.hpp"
#include "output_transaction.hpp"
#include "tree_stats_json.hpp"
#include "json_text.hpp"

namespace shatter::cli {

namespace {

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;
using Clock = std::chrono::steady_clock;

// CLI11 reads "-1" into an unsigned option as its two's complement (a seed of
// 2^64 - 1), so signs and anything but decimal digits are refused before it does.
CLI::Validator whole_number() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        if (parse_whole_number(text)) return {};
        return "'" + text + "' is not a whole number (decimal digits only)";
      },
      "", "whole number");
}

bool is_cell_pattern(const FractureArgs& args) { return args.pattern != "planes"; }

// A number as the shortest text that reads back to it.
std::string shortest(double value) {
  char text[32];
  const auto result = std::to_chars(text, text + sizeof text, value);
  return std::string(text, result.ptr);
}

// How a cell pattern's sites are made, as its options spell it
// (TreeRecipe::pattern): printable ASCII, at most 1024 bytes.
std::string pattern_text(const FractureArgs& args) {
  const std::string& p = args.pattern;
  std::string text = p;
  if (p == "voronoi") text += " --sites " + std::to_string(args.sites);
  if (p == "clustered") {
    text += " --clusters " + std::to_string(args.clusters) + " --sites-per-cluster " + std::to_string(args.sites_per_cluster) +
            " --cluster-radius " + shortest(args.cluster_radius);
  }
  if (p == "radial") {
    text += " --rings " + std::to_string(args.rings) + " --sectors " + std::to_string(args.sectors) +
            (args.centre.empty() ? std::string() : " --centre " + args.centre) + " --direction " + args.direction +
            (args.radius > 0 ? " --radius " + shortest(args.radius) : std::string()) + " --variability " +
            shortest(args.variability);
  }
  if (p == "grid" || p == "brick") {
    text += " --cells " + args.cells + " --offset " + shortest(args.offset) + " --jitter " + shortest(args.jitter);
  }
  if (p == "sites") text += " --sites-file " + args.sites_file;
  if (p != "sites") text += " --seed " + std::to_string(args.seed);
  for (char& c : text) {
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) > 0x7E) c = '?';
  }
  if (text.size() > 1024) text.resize(1024);
  return text;
}

TreeRecipe tree_recipe_of(const FractureArgs& args) {
  TreeRecipe recipe = tree_recipe_from(is_cell_pattern(args) ? 1 : args.fragments, args.seed, args.strategy, "--");
  if (is_cell_pattern(args)) {
    recipe.strategy = Strategy::voronoi;
    recipe.pattern = pattern_text(args);
  }
  recipe.interior_uv_scale = args.interior_uv_scale;
  recipe.allow_self_intersections = args.allow_self_intersections;
  return recipe;
}

// "x,y,z" as three finite doubles; UsageError naming the flag otherwise.
Vec3 parse_triple(const std::string& text, const std::string& flag) {
  double values[3];
  const char* at = text.data();
  const char* end = text.data() + text.size();
  for (int i = 0; i < 3; ++i) {
    if (at < end && *at == '+') ++at;
    const auto [next, error] = std::from_chars(at, end, values[i]);
    const bool separator_ok = i < 2 ? (next < end && *next == ',') : next == end;
    if (error != std::errc() || !std::isfinite(values[i]) || !separator_ok) {
      throw UsageError(flag + " must be three finite numbers x,y,z, got '" + text + "'");
    }
    at = next + (i < 2 ? 1 : 0);
  }
  return {values[0], values[1], values[2]};
}

std::array<std::uint32_t, 3> parse_cells(const std::string& text) {
  std::array<std::uint32_t, 3> cells{};
  std::size_t at = 0;
  for (int i = 0; i < 3; ++i) {
    const std::size_t comma = i < 2 ? text.find(',', at) : text.size();
    const std::optional<std::uint64_t> value =
        comma == std::string::npos ? std::nullopt : parse_whole_number(std::string_view(text).substr(at, comma - at));
    if (!value || *value < 1 || *value > 1024) {
      throw UsageError("--cells must be three whole numbers NX,NY,NZ from 1 to 1024, got '" + text + "'");
    }
    cells[i] = static_cast<std::uint32_t>(*value);
    at = comma + 1;
  }
  return cells;
}

// The most sites a pattern may make (--sites' range, and every other pattern's).
constexpr std::uint64_t max_pattern_sites = 10'000'000;

// What each cell pattern needs, checked before the mesh is read.
void check_pattern_flags(const FractureArgs& args) {
  const std::string& p = args.pattern;
  if (p == "planes") {
    if (args.fragments == 0) throw UsageError("--fragments is required with --pattern planes (the default)");
    return;
  }
  if (args.fragments != 0) throw UsageError("--fragments is for --pattern planes; --pattern " + p + " takes its sites from its own options");
  const auto need = [&](bool given, const char* flag) {
    if (!given) throw UsageError(std::string("--pattern ") + p + " needs " + flag);
  };
  if (p == "voronoi") need(args.sites > 0, "--sites N");
  if (p == "clustered") {
    need(args.clusters > 0, "--clusters C");
    need(args.sites_per_cluster > 0, "--sites-per-cluster K");
    need(args.cluster_radius > 0, "--cluster-radius R");
  }
  if (p == "radial") {
    need(args.rings > 0, "--rings R");
    need(args.sectors > 0, "--sectors S");
    if (!args.centre.empty()) parse_triple(args.centre, "--centre");
    const Vec3 d = parse_triple(args.direction, "--direction");
    if (d.x == 0 && d.y == 0 && d.z == 0) throw UsageError("--direction must not be 0,0,0");
  }
  std::uint64_t site_count = 0;  // what the pattern would draw
  if (p == "clustered") site_count = std::uint64_t{args.clusters} * args.sites_per_cluster;
  if (p == "radial") site_count = std::uint64_t{args.rings} * args.sectors + 1;
  if (p == "grid" || p == "brick") {
    need(!args.cells.empty(), "--cells NX,NY,NZ");
    const std::array<std::uint32_t, 3> cells = parse_cells(args.cells);
    site_count = std::uint64_t{cells[0]} * cells[1] * cells[2];
  }
  // Every pattern within --sites' own limit: 1024^3 grid cells or 10^6 clusters
  // of 10^6 sites were accepted and ran out of memory (an internal error, or
  // the kernel's OOM killer; found by a probe, 2026-12-07).
  if (site_count > max_pattern_sites) {
    throw UsageError("--pattern " + p + " would make " + std::to_string(site_count) + " sites, more than " +
                     std::to_string(max_pattern_sites) + " (the limit of --sites)");
  }
  if (p == "sites") need(!args.sites_file.empty(), "--sites-file F");
}

// The pattern's sites for `mesh` (a valid solid).
std::vector<Vec3> pattern_sites(const FractureArgs& args, const Mesh& mesh) {
  const std::string& p = args.pattern;
  if (p == "voronoi") return uniform_sites(mesh, args.sites, args.seed);
  if (p == "clustered") return clustered_sites(mesh, args.clusters, args.sites_per_cluster, args.cluster_radius, args.seed);
  if (p == "grid" || p == "brick") return grid_sites(mesh, parse_cells(args.cells), p == "brick", args.offset, args.jitter, args.seed);
  if (p == "sites") {
    std::vector<Vec3> sites = read_sites_file(args.sites_file);
    if (sites.size() > max_pattern_sites) {
      throw UsageError("--sites-file " + args.sites_file + " holds " + std::to_string(sites.size()) + " sites, more than " +
                       std::to_string(max_pattern_sites) + " (the limit of --sites)");
    }
    return sites;
  }
  // radial: about the box's centre and half its diagonal unless given
  Vec3 lo = mesh.positions.front(), hi = lo;
  for (const Vec3& q : mesh.positions) {
    lo = {std::min(lo.x, q.x), std::min(lo.y, q.y), std::min(lo.z, q.z)};
    hi = {std::max(hi.x, q.x), std::max(hi.y, q.y), std::max(hi.z, q.z)};
  }
  const Vec3 centre = args.centre.empty() ? (lo + hi) * 0.5 : parse_triple(args.centre, "--centre");
  const double radius = args.radius > 0 ? args.radius : 0.5 * norm(hi - lo);
  return radial_sites(centre, parse_triple(args.direction, "--direction"), args.rings, args.sectors, radius,
                      args.variability, args.seed);
}

// The format of the leaf export, nullopt for no export. Checked before the mesh is
// read, so a usage mistake costs nothing.
std::optional<MeshFormat> leaf_export_format(const FractureArgs& args) {
  if (args.export_folder.empty()) {
    if (!args.format.empty()) throw UsageError("--format " + args.format + " needs --export <folder>");
    return std::nullopt;
  }
  if (args.format.empty()) return MeshFormat::off;
  const std::optional<MeshFormat> format = parse_mesh_format(args.format);
  if (!format) throw UsageError("--format must be off, obj, ply or stl, got '" + args.format + "'");
  return format;
}

// Before this long, no bar: most builds finish sooner, and a flash is noise. The
// environment variable SHATTER_PROGRESS_DELAY_MS changes it (0: draw from the first
// leaf), so a test of the bar does not depend on how fast the machine builds.
std::chrono::milliseconds progress_bar_delay() {
  constexpr std::chrono::milliseconds default_delay{500};
  const char* text = std::getenv("SHATTER_PROGRESS_DELAY_MS");
  if (text == nullptr) return default_delay;
  const std::optional<std::uint64_t> ms = parse_whole_number(text);
  if (!ms || *ms > 3'600'000) {
    throw UsageError(std::string("SHATTER_PROGRESS_DELAY_MS='") + text +
                     "' is not a whole number of milliseconds up to an hour");
  }
  return std::chrono::milliseconds(*ms);
}

// Draws "fracturing [#####.....] 37/64 leaves, 2.1 s" on stderr while a build runs,
// when stderr is a terminal and the build has run for `delay` (a short build, or
// output captured to a file, gets nothing). The builder reports finished leaves
// from its worker threads; a report that finds another thread drawing, or comes
// within the redraw interval, only records the count, so reports stay cheap and
// never wait. The destructor erases the bar, so the summary or an `error:` line
// starts on a clean line.
class LeafProgressBar {
 public:
  LeafProgressBar(std::uint32_t target_leaves, std::chrono::milliseconds delay)
      : enabled_(::isatty(STDERR_FILENO) == 1),
        target_(std::max<std::uint32_t>(target_leaves, 1)),
        next_draw_(start_ + delay) {}

  LeafProgressBar(const LeafProgressBar&) = delete;
  LeafProgressBar& operator=(const LeafProgressBar&) = delete;

  ~LeafProgressBar() {
    const std::lock_guard lock(mutex_);
    if (drawn_width_ > 0) std::fprintf(stderr, "\r%*s\r", static_cast<int>(drawn_width_), "");
    std::fflush(stderr);
  }

  /// The callback to hand to the builder: empty when no bar will be drawn, so the
  /// builder does not even call it.
  LeafProgressFn callback() {
    if (!enabled_) return {};
    return [this](std::size_t leaves_done) { report(leaves_done); };
  }

 private:
  static constexpr std::chrono::milliseconds redraw_interval{100};
  static constexpr int bar_width = 30;

  void report(std::size_t leaves_done) {
    // Reports can arrive out of order from several threads: keep the largest.
    std::size_t seen = most_done_.load(std::memory_order_relaxed);
    while (seen < leaves_done && !most_done_.compare_exchange_weak(seen, leaves_done, std::memory_order_relaxed)) {
    }
    const std::unique_lock lock(mutex_, std::try_to_lock);
    if (!lock.owns_lock()) return;
    const Clock::time_point now = Clock::now();
    if (now < next_draw_) return;
    next_draw_ = now + redraw_interval;
    draw(most_done_.load(std::memory_order_relaxed), now);
  }

  void draw(std::size_t leaves_done, Clock::time_point now) {
    // A cut can split a node into more than two solids, so the count may pass
    // the target; the bar stops at full.
    const double fraction = std::min(1.0, static_cast<double>(leaves_done) / target_);
    const int filled = static_cast<int>(fraction * bar_width);
    char bar[bar_width + 1];
    for (int i = 0; i < bar_width; ++i) bar[i] = i < filled ? '#' : '.';
    bar[bar_width] = '\0';
    const double seconds = std::chrono::duration<double>(now - start_).count();
    const int width = std::fprintf(stderr, "\rfracturing [%s] %zu/%u leaves, %.1f s", bar, leaves_done,
                                   static_cast<unsigned>(target_), seconds);
    // Pad over the rest of a longer earlier line (fprintf counts the '\r' too).
    const std::size_t written = width > 1 ? static_cast<std::size_t>(width - 1) : 0;
    if (written < drawn_width_) std::fprintf(stderr, "%*s", static_cast<int>(drawn_width_ - written), "");
    drawn_width_ = std::max(drawn_width_, written);
    std::fflush(stderr);
  }

  const bool enabled_;
  const std::uint32_t target_;
  const Clock::time_point start_ = Clock::now();
  std::atomic<std::size_t> most_done_{0};
  std::mutex mutex_;
  Clock::time_point next_draw_;  // guarded by mutex_
  std::size_t drawn_width_ = 0;   // guarded by mutex_
};

struct FractureOutcome {
  double build_seconds = 0;
  std::optional<MeshFormat> export_format;
  std::vector<fs::path> exported;
  std::optional<RepairReport> repair;  ///< set with --repair
};

json fracture_json(const FractureArgs& args, const TreeRecipe& recipe, const TreeStats& stats,
                   const FractureOutcome& outcome) {
  json out{{"input", args.mesh}, {"output", args.out}, {"fragments_requested", recipe.fragments}};
  json options_out = recipe_json(recipe);
  options_out["threads"] = args.threads;  // as asked (0: all cores); never changes the tree
  append_stats_json(out, options_out, stats);
  out["seconds"] = outcome.build_seconds;
  if (outcome.export_format) {
    json files = json::array();
    for (const fs::path& path : outcome.exported) files.push_back(path.filename().string());
    out["export"] = {{"folder", args.export_folder}, {"format", format_name(*outcome.export_format)}, {"files", files}};
  } else {
    out["export"] = nullptr;
  }
  if (outcome.repair) add_repair_json(out, *outcome.repair);
  return out;
}

// Seconds to the hundredth: finer is noise for a human reader.
std::string seconds_text(double seconds) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2f", seconds);
  return text;
}

void print_fracture_text(const FractureArgs& args, const TreeRecipe& recipe, const TreeStats& stats,
                         const FractureOutcome& outcome) {
  const VolumeSpread& volume = stats.fragment_volume;
  std::cout << args.mesh << ": " << stats.leaf_count << " fragments (" << recipe.fragments << " asked) in a tree of "
            << stats.node_count << " nodes, depth " << stats.max_depth << ", " << stats.bond_count
            << " bonds (total area " << stats.total_bond_area << "); built in "
            << seconds_text(outcome.build_seconds) << " s\n"
            << "  strategy " << strategy_name(recipe.strategy) << ", seed " << recipe.seed << '\n'
            << "  fragment volume: min " << volume.min << ", median " << volume.median << ", max " << volume.max
            << ", coefficient of variation " << volume.coefficient_of_variation << '\n'
            << "  wrote " << args.out << '\n';
  if (outcome.export_format) {
    std::cout << "  wrote " << outcome.exported.size() << " " << format_name(*outcome.export_format)
              << " file(s) to " << args.export_folder;
    if (!outcome.exported.empty()) {
      std::cout << ": " << outcome.exported.front().filename().string();
      if (outcome.exported.size() > 1) std::cout << " ... " << outcome.exported.back().filename().string();
    }
    std::cout << '\n';
  }
}

}  // namespace

std::optional<std::uint64_t> parse_whole_number(std::string_view text) {
  std::uint64_t value = 0;
  if (text.empty() || !std::all_of(text.begin(), text.end(), [](unsigned char c) { return std::isdigit(c); })) {
    return std::nullopt;
  }
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size()) return std::nullopt;
  return value;
}

TreeRecipe tree_recipe_from(std::uint64_t fragments, std::uint64_t seed, std::string_view strategy,
                            std::string_view field_prefix) {
  const std::string prefix(field_prefix);
  if (fragments < 1 || fragments > 0xFFFFFFFFu) {
    throw UsageError(prefix + "fragments must be a whole number from 1 to 4294967295");
  }
  const std::optional<Strategy> strategy_value = strategy_named(strategy);
  // Voronoi trees need their sites: --pattern, not a strategy.
  if (!strategy_value || *strategy_value == Strategy::voronoi) {
    throw UsageError(prefix + "strategy must be thesis, balanced or axis, got '" + std::string(strategy) + "'");
  }
  TreeRecipe recipe;
  recipe.fragments = static_cast<std::uint32_t>(fragments);
  recipe.seed = seed;
  recipe.strategy = *strategy_value;
  return recipe;
}

Command add_fracture_command(CLI::App& app) {
  auto args = std::make_shared<FractureArgs>();
  CLI::App* command = app.add_subcommand(
      "fracture",
      "Cut a closed mesh recursively into at least N fragments, keeping every level as a mesh tree with the bonds "
      "between touching fragments; write it as a .shatter file (read it with `info`, `export`), optionally also "
      "one mesh file per fragment. The same mesh and options give the same bytes, whatever --threads is.");
  command->add_option("mesh", args->mesh, "Mesh file (.off, .obj, .ply, .stl): a closed, oriented 2-manifold solid")
      ->required();
  command->add_option("--fragments", args->fragments,
                      "N >= 1: cut until there are at least N fragments (leaves); a cut of a concave solid can "
                      "give more than two pieces, so the count may pass N. Required with --pattern planes (the "
                      "default), refused with the others")
      ->check(whole_number())
      ->check(CLI::Range(std::uint32_t{1}, std::numeric_limits<std::uint32_t>::max()));
  command->add_option("--seed", args->seed, "Seed of the random planes (an unsigned 64-bit integer)")
      ->check(whole_number())
      ->capture_default_str();
  command->add_option("--strategy", args->strategy,
                      "thesis: random planes through each piece's volume centroid, its fragment budget shared "
                      "evenly among its pieces. balanced: random centroid planes, always cutting the largest "
                      "fragment next (evens out sizes). axis: planes across each piece's longest bounding-box axis "
                      "near the centroid, with jitter, budget shared by volume")
      ->check(CLI::IsMember({"thesis", "balanced", "axis"}))
      ->capture_default_str();
  command->add_option("--pattern", args->pattern,
                      "planes: recursive plane cuts (--fragments, --strategy). The others cut the solid into the "
                      "Voronoi cells of sites (exact shared bisector planes; a tree whose internal nodes are nearby "
                      "fragments glued along their shared cell faces, grouped by a k-d split of the sites): voronoi (--sites N uniform in the volume), clustered (--clusters, "
                      "--sites-per-cluster, --cluster-radius), radial (--rings, --sectors, --centre, --direction, "
                      "--radius, --variability), grid or brick (--cells, --offset, --jitter), sites (--sites-file). "
                      "Random draws use --seed; lengths are in the mesh's units")
      ->check(CLI::IsMember({"planes", "voronoi", "clustered", "radial", "grid", "brick", "sites"}))
      ->capture_default_str();
  command->add_option("--sites", args->sites, "voronoi: N >= 1 sites drawn uniformly in the solid's volume (exact point-in-solid)")
      ->check(whole_number())
      ->check(CLI::Range(std::uint32_t{1}, static_cast<std::uint32_t>(max_pattern_sites)));
  command->add_option("--clusters", args->clusters, "clustered: C >= 1 cluster centres drawn uniformly in the solid's volume")
      ->check(whole_number())
      ->check(CLI::Range(std::uint32_t{1}, std::uint32_t{1'000'000}));
  command->add_option("--sites-per-cluster", args->sites_per_cluster,
                      "clustered: K >= 1 sites per cluster, uniform in the ball of --cluster-radius about its centre")
      ->check(whole_number())
      ->check(CLI::Range(std::uint32_t{1}, std::uint32_t{1'000'000}));
  command->add_option("--cluster-radius", args->cluster_radius, "clustered: the clusters' radius, in mesh units (> 0)")
      ->check(CLI::PositiveNumber);
  command->add_option("--centre", args->centre,
                      "radial: the impact point x,y,z in mesh units (default: the centre of the bounding box)");
  command->add_option("--direction", args->direction,
                      "radial: the impact direction x,y,z (any length but zero); the sites lie in the plane through "
                      "--centre perpendicular to it, so the cells are prisms along it")
      ->capture_default_str();
  command->add_option("--rings", args->rings, "radial: R >= 1 rings of sites around the centre, crowding toward it")
      ->check(whole_number())
      ->check(CLI::Range(std::uint32_t{1}, std::uint32_t{10'000}));
  command->add_option("--sectors", args->sectors, "radial: S >= 1 sites per ring, evenly spaced in angle")
      ->check(whole_number())
      ->check(CLI::Range(std::uint32_t{1}, std::uint32_t{10'000}));
  command->add_option("--radius", args->radius,
                      "radial: the outer ring's radius in mesh units (default: half the bounding box's diagonal)")
      ->check(CLI::PositiveNumber);
  command->add_option("--variability", args->variability,
                      "radial: 0 to 1, how far each site moves at random, as a fraction of its ring spacing and "
                      "sector width (0: a regular pattern)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  command->add_option("--cells", args->cells,
                      "grid, brick: NX,NY,NZ cells over the bounding box (1 to 1024 each), one site at each cell's centre");
  command->add_option("--offset", args->offset,
                      "grid: the whole lattice shifts by this fraction of a cell along each axis; brick: every other "
                      "row (along y and z) shifts by it along x (0.5: a running bond). -1 to 1")
      ->check(CLI::Range(-1.0, 1.0))
      ->capture_default_str();
  command->add_option("--jitter", args->jitter,
                      "grid, brick: 0 to 1, each site moves at random by up to this fraction of half a cell per axis")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  command->add_option("--sites-file", args->sites_file,
                      "sites: a text file of sites, one \"x y z\" per line in mesh units ('#' starts a comment line); "
                      "a bad line is refused naming its line number");
  command->add_option("--threads", args->threads,
                      "Worker threads; 0 uses every hardware thread. Changes the speed only, never the output")
      ->check(whole_number())
      ->check(CLI::Range(0u, std::numeric_limits<unsigned>::max()))
      ->capture_default_str();
  command->add_option("--interior-uv-scale", args->interior_uv_scale,
                      "Cap UVs are the cap's plane coordinates times this (used when the mesh has UVs)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  command->add_flag("--allow-self-intersections", args->allow_self_intersections,
                    "Fracture a self-intersecting (or self-touching) mesh instead of refusing it; fragments are "
                    "closed and oriented, their embedding may overlap");
  command->add_option("--out", args->out,
                      "The .shatter file to write (its folder is created if missing); replaced atomically")
      ->required();
  command->add_option("--export", args->export_folder,
                      "Also write one mesh file per fragment into this folder (created if missing): leaf-0000.off, "
                      "leaf-0001.off, ... in leaf order, as `export --nodes leaves` would");
  command->add_option("--format", args->format,
                      "Format of the --export files: off, obj, ply (binary, doubles) or stl (ascii); default off. "
                      "Only with --export")
      ->check(CLI::IsMember({"off", "obj", "ply", "stl"}));
  command->add_flag("--json", args->json,
                    "Print the summary as JSON: fragments asked, leaves, nodes, depth, options, volumes, fragment "
                    "volume spread, bonds and their total area, build seconds, exported files");
  command->add_flag("--repair", args->repair,
                    repair_flag_help("The repaired mesh is fractured and stored as the tree's root (JSON: "
                                          "\"repair\" lists the changes)."));
  return {command, [args] { return run_fracture(*args); }};
}

namespace {
int run_fracture_here(const FractureArgs& args);
}  // namespace

// The whole command runs on --threads threads: the build makes its own arena
// of as many, and what comes before and after it (the input's check, the
// file's encoding) runs in parallel in this one, never on more.
int run_fracture(const FractureArgs& args) {
  tbb::task_arena arena(args.threads == 0 ? tbb::task_arena::automatic : static_cast<int>(args.threads));
  return arena.execute([&] { return run_fracture_here(args); });
}

namespace {

int run_fracture_here(const FractureArgs& args) {
  // Every usage check comes before reading the mesh and building.
  FractureOutcome outcome;
  outcome.export_format = leaf_export_format(args);
  check_pattern_flags(args);
  TreeRecipe recipe = tree_recipe_of(args);
  const std::chrono::milliseconds progress_delay = progress_bar_delay();
  if (std::error_code unknown; fs::is_directory(args.out, unknown)) {
    throw UsageError("--out " + args.out + " is a folder; it names the .shatter file to write");
  }

  // A plane build takes the input prepared beside its check; a cell build
  // prepares its own (build_voronoi_tree).
  std::optional<PreparedSolid> prepared;
  InputMesh input;
  if (is_cell_pattern(args)) {
    input = read_valid_solid(args.mesh, args.repair, args.allow_self_intersections);
  } else {
    prepared = read_prepared_solid(args.mesh, args.repair, args.allow_self_intersections);
    input = std::move(prepared->input);
  }
  outcome.repair = std::move(input.repair);

  std::vector<Vec3> sites;
  if (is_cell_pattern(args)) {
    sites = pattern_sites(args, input.mesh);
    recipe.fragments = static_cast<std::uint32_t>(std::min<std::size_t>(sites.size(), 0xFFFFFFFFu));
  }

  MeshTree tree;
  const Clock::time_point start = Clock::now();
  {
    LeafProgressBar progress_bar(recipe.fragments, progress_delay);
    const BuildRunOptions run{.threads = args.threads,
                              // the read made the full check: the builder need not repeat it
                              .input_validated = true,
                              .prepared = prepared ? &prepared->plane : nullptr,
                              .progress = progress_bar.callback(),
                              // the tree is only written, summed up and exported
                              // below: what the build can recompute goes early
                              .lean = true};
    try {
      tree = is_cell_pattern(args) ? build_voronoi_tree(input.mesh, sites, recipe, run) : build_mesh_tree(input.mesh, recipe, run);
    } catch (const UnsupportedGeometryError& e) {
      throw UnsupportedGeometryError("cannot fracture " + args.mesh + ": " + e.what());
    }
  }
  outcome.build_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  // The file says that its root is the repaired input, not the file as read.
  if (outcome.repair) tree.input_repair = *outcome.repair;

  // The .shatter file goes last: its rename is the run's point of no return.
  OutputTransaction output;
  if (outcome.export_format) {
    const NodeSelection leaves{NodeSelectionKind::leaves};
    outcome.exported = write_node_mesh_files(output, tree, select_nodes(tree, leaves), args.export_folder,
                                             *outcome.export_format, file_naming_for(leaves));
  }
  // From here the leaves are only written and summed up: packed too, the
  // tree keeps no node's arrays (the same bytes; README "Lean memory").
  pack_leaves(tree);
  if (const fs::path folder = fs::path(args.out).parent_path(); !folder.empty()) output.create_folder(folder);
  output.write_file_rewritable(args.out, [&](const RewritableSink& sink) { write_shatter(tree, sink); });
  output.commit();

  const TreeStats stats = tree_stats(tree);
  if (args.json) {
    std::cout << json_text(fracture_json(args, recipe, stats, outcome), 2) << '\n';
  } else {
    print_fracture_text(args, recipe, stats, outcome);
  }
  return static_cast<int>(ExitCode::ok);
}

}  // namespace

}  // namespace shatter::cli
