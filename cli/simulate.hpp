#pragma once
// The `simulate` subcommand: a .shatter mesh tree as a breakable object in a
// headless Bullet scene (runtime/), with a per-step summary, every break, and an
// optional animated glTF recording. Failures map to exit codes in errors.hpp as
// for every command.

#include <CLI/CLI.hpp>

#include <cstdint>
#include <string>

#include "shatter/runtime/scenes.hpp"
#include "shatter/runtime/shapes.hpp"
#include "shatter/runtime/world.hpp"
#include "command.hpp"

namespace shatter::cli {

/// `shatter simulate <file.shatter> --scene drop|shoot|wall [options]`; every
/// default is the runtime's (BreakableParameters, SceneOptions, WorldOptions).
struct SimulateArgs {
  std::string input;
  std::string scene = "drop";
  std::uint64_t steps = 360;
  runtime::WorldOptions world;
  runtime::ShapeOptions shapes;
  /// Geometry of the scene and, in `parameters`, the material and damage model;
  /// the enum fields are set from the strings below.
  runtime::SceneOptions scene_options;
  std::string bonds = "discrete";
  std::string impulse = "applied";
  std::string method = "incremental";
  bool no_sleep = false;
  bool json = false;
  std::uint64_t print_every = 1;
  std::string record;
  std::uint32_t record_every = 1;
};

/// Declares the `simulate` subcommand on `app`.
Command add_simulate_command(CLI::App& app);

/// Reads the tree (refusing a damaged file as `info` does), sets up the scene,
/// runs `steps` fixed steps and prints a summary every `print_every` steps and
/// every break event (JSON with --json: every step). With --record, writes the
/// run as an animated GLB after the last step, through an OutputTransaction
/// (nothing is written, no folder left, if any step fails). Returns 0. Throws
/// UsageError for options the runtime refuses, CorruptFileError or IoError from
/// reading the tree, InvalidMeshError for a tree the runtime cannot simulate,
/// IoError from writing the recording. Output depends only on the arguments and the file:
/// the same inputs give the same bytes.
int run_simulate(const SimulateArgs& args);

}  // namespace shatter::cli
