#pragma once
// `shatter fracture <mesh> --fragments N --out <file.shatter> [--seed S]
// [--strategy thesis|balanced|axis] [--pattern planes|voronoi|clustered|radial|grid|brick|sites
// [pattern options]] [--threads T]
// [--interior-uv-scale X] [--allow-self-intersections] [--repair]
// [--export <folder> [--format off|obj|ply|stl]] [--json]`: the mesh tree of a
// solid, written as a .shatter file.

#include <CLI/CLI.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "command.hpp"
#include "shatter/meshtree/build.hpp"

namespace shatter::cli {

struct FractureArgs {
  std::string mesh;
  std::uint32_t fragments = 0;
  std::uint64_t seed = 1;
  std::string strategy = "thesis";
  /// 0: one worker per hardware thread. Never changes the tree.
  unsigned threads = 0;
  double interior_uv_scale = 1.0;
  bool allow_self_intersections = false;
  std::string out;
  /// Folder for one mesh file per leaf; empty: no export.
  std::string export_folder;
  /// off, obj, ply or stl; empty: off. Only meaningful with export_folder.
  std::string format;
  bool json = false;
  /// Repair the mesh first (read_valid_solid), printing each change.
  bool repair = false;
  /// planes (the recursive planes of --strategy), or a Voronoi site pattern:
  /// voronoi, clustered, radial, grid, brick, sites (voronoi.hpp, sites.hpp).
  std::string pattern = "planes";
  std::uint32_t sites = 0;              ///< voronoi: sites uniform in the volume
  std::uint32_t clusters = 0;           ///< clustered
  std::uint32_t sites_per_cluster = 0;  ///< clustered
  double cluster_radius = 0;            ///< clustered, mesh units
  std::string centre;                   ///< radial: "x,y,z"; empty: the bounding box's centre
  std::string direction = "0,0,1";      ///< radial: "x,y,z"
  std::uint32_t rings = 0, sectors = 0; ///< radial
  double radius = 0;                    ///< radial, mesh units; 0: half the box diagonal
  double variability = 0;               ///< radial, 0 to 1
  std::string cells;                    ///< grid, brick: "NX,NY,NZ"
  double offset = 0;                    ///< grid, brick: fraction of a cell
  double jitter = 0;                    ///< grid, brick: 0 to 1
  std::string sites_file;               ///< sites
};

/// A whole number in decimal digits only (no sign, no space, at most 2^64 - 1);
/// nullopt for anything else. The flags and the viewer's fracture requests both
/// read numbers through it, so "-1" never becomes 2^64 - 1.
std::optional<std::uint64_t> parse_whole_number(std::string_view text);

/// The tree's recipe from what a user typed (fracture's flags, the viewer's
/// fracture request), checked alike: fragments from 1 to 2^32 - 1, the strategy
/// by the names the library prints; the other fields keep TreeRecipe's
/// defaults. Throws UsageError naming the field as `field_prefix` + its name
/// ("--" for flags, "" for the page's fields).
TreeRecipe tree_recipe_from(std::uint64_t fragments, std::uint64_t seed, std::string_view strategy,
                            std::string_view field_prefix);

/// Declares the `fracture` subcommand on `app`.
Command add_fracture_command(CLI::App& app);

/// Reads the mesh and checks it once (read_valid_solid; the builder is told,
/// BuildRunOptions::input_validated), builds its mesh tree (build_mesh_tree),
/// writes the .shatter file and, with --export, one mesh file per leaf
/// (leaf-0000.off, ..., as `export --nodes leaves` writes them), then prints a
/// summary on stdout (JSON with --json). While a long build runs and stderr is a
/// terminal, a progress bar is drawn on stderr and erased afterwards; otherwise
/// nothing goes to stderr. Returns 0.
/// All outputs or none (OutputTransaction): the leaf files first, the .shatter
/// file last, and on any failure everything this run created is removed.
/// Throws UsageError for --format without --export, or an --out that is a
/// folder (before reading the mesh); what read_valid_solid throws;
/// UnsupportedGeometryError "cannot fracture <mesh>: ..." when the builder cannot
/// cut a fragment; IoError from writing.
int run_fracture(const FractureArgs& args);

}  // namespace shatter::cli
