#pragma once
// `shatter view <file.shatter|file.glb> [--port P]`: serves the viewer and the
// file on 127.0.0.1 only, prints the address, and stops on Ctrl-C (SIGINT) or
// SIGTERM. For a .shatter file the page also gets the editor panel, which
// fractures the tree's root solid again on the server.

#include <CLI/CLI.hpp>

#include <cstdint>
#include <string>

#include "command.hpp"

namespace shatter::cli {

/// The port `view` listens on unless told otherwise.
inline constexpr std::uint16_t default_view_port = 8420;

struct ViewArgs {
  std::string input;
  /// 0: any free port (printed).
  std::uint16_t port = default_view_port;
  /// --original: the mesh file the tree was built from (empty: none).
  std::string original;
};

/// Declares the `view` subcommand on `app`.
Command add_view_command(CLI::App& app);

/// Reads the file (a .shatter mesh tree, shown with every level; or a GLB as
/// `export` or `simulate --record` writes it), listens on 127.0.0.1 at the
/// port, prints "shatter view: <file> at http://127.0.0.1:<port>/ (Ctrl-C
/// stops)" on stdout, and serves until SIGINT or SIGTERM; then prints
/// "shatter view: stopped" and returns 0. Requests (the page's API,
/// viewer/src/editor.js):
///   GET  /                   the viewer page
///   GET  /model.glb          the tree (or file) shown now
///   GET  /api/session        {file, kind ("tree" or "glb"), editable, generation, options,
///                            and original {file} with --original}
///   GET  /api/original       with --original only: the input file and its defects
///                            (original_json, view_original.hpp)
///   POST /api/fracture       {fragments, seed, strategy}: fracture the root solid again
///                            in the background (202), or 400 / 409 {error}
///   GET  /api/fracture       {state, leaves_done, fragments, generation, leaves, seconds, error}
/// Anything else is 404 with {error}. A fracture still running at the stop is
/// abandoned (nothing is written: the editor never writes files).
/// With --original, the mesh file is read and checked first (read_original_input:
/// refused with one line when unreadable, undrawable or not the tree's input).
/// Throws UsageError for a file that is neither .shatter nor .glb, --original
/// with a .glb, or a build without the viewer, CorruptFileError for a damaged file, IoError for one
/// that cannot be read or a port that cannot be listened on.
int run_view(const ViewArgs& args);

}  // namespace shatter::cli
