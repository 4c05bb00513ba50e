#pragma once
// The benchmarks' command lines are CLI11 apps; this is how each one runs the parse,
// so --help and usage errors end every benchmark the same way.

#include <CLI/CLI.hpp>

#include <optional>

namespace shatter::bench {

/// Parses `argv` into the options of `app`. Returns nothing when the benchmark
/// should run; otherwise the exit status to end with: 0 after --help (the help
/// printed on stdout), `usage_error` after a bad option or value (CLI11's message,
/// naming the option, on stderr). Never throws a CLI11 error.
inline std::optional<int> parse_command_line(CLI::App& app, int argc, char** argv, int usage_error) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : usage_error;
  }
  return std::nullopt;
}

}  // namespace shatter::bench
