#pragma once
// How the shatter command fails: one usage-error type, one table of exit codes,
// and one mapping from any exception to its exit code and its `error:` line.
// The libraries' typed errors (kernel/error.hpp) say what went wrong; this file
// alone decides what the command does about it.

#include <exception>
#include <stdexcept>
#include <string>

namespace shatter::cli {

/// The exit codes of `shatter` (the README lists them too).
enum class ExitCode : int {
  ok = 0,
  internal_error = 1,  ///< a bug, or a failure no input explains (std::bad_alloc, ...)
  usage_error = 2,     ///< flags CLI11 refuses, or that a command finds inconsistent
  invalid_input = 3,   ///< a mesh that is not a valid solid, geometry a cut refuses, a damaged .shatter file
  io_error = 4,        ///< a file that cannot be read or written
};

/// "Exit codes: 0 ok, 1 internal error, 2 usage error, 3 invalid input (mesh,
/// geometry or .shatter file), 4 I/O error.", made from the same table that
/// failure_of applies, for --help.
std::string exit_codes_help();

/// A usage problem a command finds after CLI11 has parsed its flags: a value
/// CLI11 cannot check, or flags that contradict each other. Exit code 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// What a failed run reports: its exit code and the message of its one
/// `error:` line.
struct Failure {
  ExitCode code = ExitCode::internal_error;
  std::string message;
};

/// The failure an exception stands for: UsageError, and CLI::ParseError (its
/// message followed by " (see --help)"), exit 2; InvalidMeshError,
/// UnsupportedGeometryError and CorruptFileError, exit 3; IoError, exit 4; any
/// other exception, exit 1 with its message after "internal error: ".
/// Precondition: `error` is not null. Never throws but std::bad_alloc.
Failure failure_of(const std::exception_ptr& error);

/// Prints `failure` as exactly one line, "error: <message>", on stderr (a
/// message spanning lines, as CLI11's and some libraries' do, is joined with
/// "; ", so scripts can rely on one line), and returns its exit code for main.
int report_failure(const Failure& failure);

}  // namespace shatter::cli
