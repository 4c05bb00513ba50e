#pragma once
// Typed errors. Each carries a one-line message that names the defect and, where
// there is one, the first element at fault; the CLI maps the type to its exit code.

#include <stdexcept>
#include <string>

namespace shatter {

/// The input mesh is malformed or violates a precondition (CLI exit code 3).
struct InvalidMeshError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// A file could not be opened, read or written (CLI exit code 4).
struct IoError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// A file is damaged, truncated or not of the expected format, e.g. a .shatter
/// file that fails its checksums or structure checks (CLI exit code 3).
struct CorruptFileError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// A configuration shatter decides exactly but cannot yet process; refused
/// rather than approximated (CLI exit code 3, as the input is the cause).
struct UnsupportedGeometryError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace shatter
