#pragma once
// `shatter info <file.shatter> [--json] [--compare-bond-rules] [--check] [--nodes leaves|all|depth:K]`:
// what a mesh tree holds and how it was made, and on request whether it holds together.

#include <CLI/CLI.hpp>

#include <string>

#include "command.hpp"

namespace shatter::cli {

struct InfoArgs {
  std::string input;
  bool json = false;
  bool compare_bond_rules = false;  ///< also count the seed's bounding-box bonds against the true ones
  /// Also describe these nodes, one by one (node_json.hpp): "leaves", "all" or
  /// "depth:K" as `export --nodes` takes them; empty: none.
  std::string nodes;
  /// Also check every node's geometry (validate_tree with geometry), before
  /// printing anything.
  bool check = false;
};

/// Declares the `info` subcommand on `app`.
Command add_info_command(CLI::App& app);

/// Reads the tree and prints its statistics (tree_stats), the shatter version
/// that built it when the file records one, and its build options, as text or,
/// with --json, as one JSON object ("shatter_version" is null when the file
/// records none). With --check, first runs validate_tree with its geometry
/// checks (the reader has checked the structure and computed the caches of every
/// file it reads) and adds a "check: valid" line, or "check": "valid" in JSON.
/// With --nodes, also each selected node (JSON: "node_details", as nodes_json
/// gives them; text: one line each). Returns 0. Throws UsageError for a bad
/// --nodes (before reading), CorruptFileError or IoError from reading the tree,
/// and CorruptFileError naming the part and index at fault ("<file>: invalid
/// tree: <part> <index>: ...") when the check fails; nothing is printed then.
int run_info(const InfoArgs& args);

}  // namespace shatter::cli
