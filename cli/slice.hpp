#pragma once
// `shatter slice <mesh> --plane nx,ny,nz,d --out <folder> [--allow-self-intersections] [--format off|obj|ply|stl] [--interior-uv-scale X]
// [--repair] [--json]`: one plane cut, one file per resulting solid.

#include <CLI/CLI.hpp>

#include <string>

#include "command.hpp"

namespace shatter::cli {

struct SliceArgs {
  std::string mesh;
  std::string plane;  ///< "nx,ny,nz,d", parsed by run_slice
  bool allow_self_intersections = false;
  std::string out;  ///< the folder of the pieces
  std::string format = "off";
  double interior_uv_scale = 1.0;
  bool json = false;
  bool repair = false;
};

/// Declares the `slice` subcommand on `app`.
Command add_slice_command(CLI::App& app);

/// Reads the mesh and checks it once (read_valid_solid), cuts it by the plane
/// (cut_mesh_by_plane: exact, each piece rounded once and certified) and writes
/// one file per solid into the --out folder (created if missing): below-0.off,
/// ..., above-0.off, ..., or the whole mesh as one piece when the plane misses
/// it. All files or none (OutputTransaction). Prints the pieces with their
/// triangles and volumes on stdout (JSON with --json). Returns 0.
/// Throws UsageError for a --plane that is not four finite numbers with a
/// non-zero normal, or an unknown --format (before reading); what
/// read_valid_solid throws; UnsupportedGeometryError when a piece cannot be
/// rounded to a valid mesh (before writing); IoError from writing.
int run_slice(const SliceArgs& args);

}  // namespace shatter::cli
