#pragma once
// `shatter validate <mesh> [--json] [--repair [--out <repaired mesh>]]`: is the
// mesh a closed, oriented 2-manifold solid, and if not, what is wrong with it.

#include <CLI/CLI.hpp>

#include <string>

#include "command.hpp"

namespace shatter::cli {

struct ValidateArgs {
  std::string mesh;
  bool json = false;
  bool repair = false;
  std::string out;  ///< with --repair: where to write the repaired mesh
};

/// Declares the `validate` subcommand on `app`.
Command add_validate_command(CLI::App& app);

/// Reads the mesh (repairing it with --repair), validates it once and prints the
/// report on stdout: one line for a valid mesh, else one line per defect with
/// its count and first element (JSON with --json, which adds volume and centroid
/// when valid). With --out, then writes the repaired mesh atomically. Returns 0.
/// Throws UsageError for --out without --repair or with an extension that names
/// no mesh format (before reading); what read_mesh throws; InvalidMeshError
/// "invalid mesh <path>: <summary>" after printing the report of an invalid
/// mesh (nothing written); IoError when --out cannot be written.
int run_validate(const ValidateArgs& args);

}  // namespace shatter::cli
