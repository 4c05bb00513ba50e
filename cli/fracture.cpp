#include "fracture.hpp"

#include <nlohmann/json.hpp>
#include <unistd.h>

#include <algorithm>
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
#include "shatter/formats/export.hpp"
#include "shatter/formats/file.hpp"
#include "shatter/meshtree/stats.hpp"
#include "shatter/meshtree/tree.hpp"
#include "errors.hpp"
#include "export.hpp"
#include "input.hpp"
#include "output_transaction.hpp"
#include "tree_stats_json.hpp"

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

TreeRecipe tree_recipe_of(const FractureArgs& args) {
  TreeRecipe recipe = tree_recipe_from(args.fragments, args.seed, args.strategy, "--");
  recipe.interior_uv_scale = args.interior_uv_scale;
  recipe.allow_self_intersections = args.allow_self_intersections;
  return recipe;
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
  if (!strategy_value) {
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
                      "give more than two pieces, so the count may pass N")
      ->required()
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

int run_fracture(const FractureArgs& args) {
  // Every usage check comes before reading the mesh and building.
  FractureOutcome outcome;
  outcome.export_format = leaf_export_format(args);
  const TreeRecipe recipe = tree_recipe_of(args);
  const std::chrono::milliseconds progress_delay = progress_bar_delay();
  if (recipe.fragments < 1) throw UsageError("--fragments must be at least 1");
  if (std::error_code unknown; fs::is_directory(args.out, unknown)) {
    throw UsageError("--out " + args.out + " is a folder; it names the .shatter file to write");
  }

  InputMesh input = read_valid_solid(args.mesh, args.repair, args.allow_self_intersections);
  outcome.repair = std::move(input.repair);

  MeshTree tree;
  const Clock::time_point start = Clock::now();
  {
    LeafProgressBar progress_bar(recipe.fragments, progress_delay);
    const BuildRunOptions run{.threads = args.threads,
                              // read_valid_solid made the full check: the builder need not repeat it
                              .input_validated = true,
                              .progress = progress_bar.callback(),
                              // the tree is only written, summed up and exported
                              // below: what the build can recompute goes early
                              .lean = true};
    try {
      tree = build_mesh_tree(input.mesh, recipe, run);
    } catch (const UnsupportedGeometryError& e) {
      throw UnsupportedGeometryError("cannot fracture " + args.mesh + ": " + e.what());
    }
  }
  outcome.build_seconds = std::chrono::duration<double>(Clock::now() - start).count();

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
  output.write_file_in_pieces(args.out, [&](const ByteSink& sink) { write_shatter(tree, sink); });
  output.commit();

  const TreeStats stats = tree_stats(tree);
  if (args.json) {
    std::cout << fracture_json(args, recipe, stats, outcome).dump(2) << '\n';
  } else {
    print_fracture_text(args, recipe, stats, outcome);
  }
  return static_cast<int>(ExitCode::ok);
}

}  // namespace shatter::cli
