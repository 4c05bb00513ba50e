#pragma once
// The `fracture`, `export` and `info` subcommands, which make or read a .shatter
// mesh tree. main.cpp registers them (add_*_command), runs the parsed one (run_*)
// and maps exceptions to exit codes: CommandUsageError -> 2; CorruptFileError,
// InvalidMeshError and UnsupportedGeometryError -> 3; IoError -> 4; anything
// else -> 1.

#include <CLI/CLI.hpp>

#include <cstdint>
#include <stdexcept>
#include <string>

namespace shatter {

/// A usage problem a command finds after CLI11 has parsed its flags (a value
/// that CLI11 cannot check, or flags that contradict each other): exit code 2.
struct CommandUsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// `shatter fracture <mesh> --fragments N [--seed S] [--strategy thesis|balanced|axis]
/// [--kernel fast|exact] [--threads T] [--interior-uv-scale X]
/// [--allow-self-intersections] --out <file.shatter> [--export <folder>
/// [--format off|obj|ply|stl]] [--json]`
struct FractureArgs {
  std::string mesh;
  std::uint32_t fragments = 0;
  std::uint64_t seed = 1;
  std::string strategy = "thesis";
  std::string kernel = "plane";
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
  /// Repair the mesh first (repair_mesh), printing each change (cli/repair_option.hpp).
  bool repair = false;
};

/// Declares the `fracture` subcommand on `app`, its arguments bound to `args`;
/// returns it so the caller can ask whether it was parsed.
CLI::App* add_fracture_command(CLI::App& app, FractureArgs& args);

/// Reads and validates the mesh, builds its mesh tree (build_mesh_tree), writes
/// the .shatter file and, with --export, one mesh file per leaf (leaf-0000.off,
/// ...), then prints a summary on stdout (JSON with --json). While a long build
/// runs and stderr is a terminal, a progress bar is drawn on stderr and erased
/// afterwards; otherwise nothing goes to stderr. Returns 0.
/// All outputs or none: every file is written atomically, and on any failure the
/// files and folders this run created are removed before the error propagates.
/// Throws CommandUsageError for --format without --export; InvalidMeshError for a
/// mesh that is not a valid solid (named by its path); UnsupportedGeometryError
/// when the builder cannot cut a fragment; IoError from reading or writing.
int run_fracture(const FractureArgs& args);

/// `shatter export <file.shatter> --out <folder|file.glb> [--format off|obj|ply|stl|glb]
/// [--nodes leaves|all|depth:K]`
struct ExportArgs {
  std::string input;
  std::string out;
  /// off, obj, ply, stl or glb; empty: glb when --out ends in .glb, else off.
  std::string format;
  /// "leaves", "all" or "depth:K" (parse_node_selection).
  std::string nodes = "leaves";
};

/// Declares the `export` subcommand on `app`, its arguments bound to `args`;
/// returns it so the caller can ask whether it was parsed.
CLI::App* add_export_command(CLI::App& app, ExportArgs& args);

/// Reads the tree and writes the selected nodes: one mesh file per node into the
/// --out folder (leaf-0000.off, ... for leaves; node-00012.off, ... otherwise; all
/// files or none), or one GLB file. Prints what it wrote on stdout. Returns 0.
/// Throws CommandUsageError for a bad --format or --nodes, or --format naming a
/// mesh format while --out ends in .glb (or glb while it names an existing
/// folder); CorruptFileError / IoError from reading the tree; IoError from writing.
int run_export(const ExportArgs& args);

/// `shatter info <file.shatter> [--json]`
struct InfoArgs {
  std::string input;
  bool json = false;
  bool compare_bond_rules = false;  ///< also count the seed's bounding-box bonds against the true ones
};

/// Declares the `info` subcommand on `app`, its arguments bound to `args`;
/// returns it so the caller can ask whether it was parsed.
CLI::App* add_info_command(CLI::App& app, InfoArgs& args);

/// Reads the tree and prints its statistics (tree_stats) and build options, as
/// text or, with --json, as one JSON object. Returns 0. Throws CorruptFileError or
/// IoError from reading the tree.
int run_info(const InfoArgs& args);

}  // namespace shatter
