#pragma once
// `shatter export <file.shatter> --out <folder|file.glb|file.html> [--format off|obj|ply|stl|glb|html]
// [--nodes leaves|all|depth:K]`: a .shatter mesh tree as mesh files, one GLB, or
// one self-contained viewer page.

#include <CLI/CLI.hpp>

#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "shatter/kernel/io.hpp"
#include "shatter/formats/export.hpp"
#include "shatter/meshtree/tree.hpp"
#include "command.hpp"
#include "output_transaction.hpp"

namespace shatter::cli {

struct ExportArgs {
  std::string input;
  std::string out;
  /// off, obj, ply, stl, glb or html; empty: glb when --out ends in .glb, html
  /// when it ends in .html or .htm, else off.
  std::string format;
  /// "leaves", "all" or "depth:K" (parse_node_selection); empty: "all" for
  /// html, "leaves" otherwise.
  std::string nodes;
  /// html only: the mesh file the tree was built from, drawn beside its root
  /// on the page (as `view --original`); empty: none.
  std::string original;
};

/// Declares the `export` subcommand on `app`.
Command add_export_command(CLI::App& app);

/// Reads the tree and writes the selected nodes: one mesh file per node into the
/// --out folder (created if missing; leaf-0000.off, ... for leaves,
/// node-00012.off, ... otherwise), one GLB file, or one HTML page holding the
/// viewer and that GLB (self_contained_viewer_page; its folder created if
/// missing). All files or none (OutputTransaction). Prints what it wrote on
/// stdout. Returns 0.
/// With --original (html only), the page also holds that file and its defects
/// (read_original_input, original_json), as `view --original` serves them.
/// Throws UsageError for a bad --format or --nodes, a --format that contradicts
/// the --out extension (or glb or html while --out names an existing folder),
/// html in a build without the viewer, or --original with another format or
/// with --nodes that leave the root out, before reading; CorruptFileError or
/// IoError from reading the tree; IoError or InvalidMeshError from
/// read_original_input (nothing written); IoError from writing.
int run_export(const ExportArgs& args);

/// Writes the mesh of every node in `nodes` into `folder` (created if missing)
/// as `format`, named by mesh_file_name, through `output`, and returns the paths
/// in the order of `nodes`: what `export` writes into a folder, and `fracture
/// --export` for the leaves. Every name is made before anything is written.
/// Throws std::invalid_argument as mesh_file_name does, IoError from writing.
std::vector<std::filesystem::path> write_node_mesh_files(OutputTransaction& output, const MeshTree& tree,
                                                         std::span<const NodeIndex> nodes,
                                                         const std::filesystem::path& folder, MeshFormat format,
                                                         FileNaming naming);

}  // namespace shatter::cli
