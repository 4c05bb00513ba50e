#pragma once
// The robustness cases as files other geometry code can read (issue 20 item 4):
// each drawn case's mesh as an OBJ file and its planes or fracture recipe in one
// JSON manifest, so a peer (another kernel, another fracture tool) can be fuzzed
// with exactly the cases shatter-fuzz runs, and a robustness table can be
// computed from exactly that corpus. The layout is written out for readers in
// the README.md the export puts beside the manifest.

#include <cstdint>
#include <filesystem>
#include <vector>

#include "robustness/robustness.hpp"

namespace shatter::robust {

/// What an export wrote.
struct ExportSummary {
  std::size_t cases = 0;        ///< manifest entries
  std::size_t mesh_files = 0;   ///< distinct meshes (cases that share a mesh share its file)
  std::uint64_t bytes = 0;      ///< of every file written
};

/// Writes the cases make_case(pool, seed, i) draws for each i of `indices` into
/// the new folder `dir`:
/// `manifest.json`, `README.md` and `meshes/*.obj`. Meshes are written with
/// write_mesh_to_bytes (shortest round-trip decimals: each reads back bit for
/// bit), each distinct mesh once; planes as JSON numbers (shortest round trip)
/// and as C99 hex doubles. Deterministic: the same cases give the same bytes.
/// Precondition: `dir` does not exist (it is refused, never overwritten, with
/// std::invalid_argument). Guarantees: `dir` appears whole or not at all (the
/// files are written into a sibling temporary folder renamed at the end).
/// Throws IoError when a file cannot be written (the temporary folder removed).
ExportSummary export_corpus(const MeshPool& pool, std::uint64_t seed, const std::vector<std::uint64_t>& indices,
                            const std::filesystem::path& dir);

}  // namespace shatter::robust
