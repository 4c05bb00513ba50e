#pragma once
// A plane-kernel piece as shatter writes it: rounded once (round_solid), written
// as OFF and read back. Header-only: the tests that include it link the
// triangulate layer, which the other tests need not.

#include <string>

#include "shatter/kernel/io.hpp"
#include "shatter/kernel/rationals.hpp"
#include "shatter/kernel/solid.hpp"
#include "shatter/kernel/validate.hpp"
#include "shatter/triangulate/solid_mesh.hpp"

namespace shatter::test {

/// Empty when `piece` rounds (round_solid), writes as OFF and reads back as its
/// rounded mesh, and what is read is a valid solid (self-intersections
/// included), or when it vanishes as thinner than its rounding (collapsed, its
/// exact volume within the bound reported for it); else what went wrong,
/// starting "cannot be rounded" when round_solid refuses the piece.
inline std::string written_problem(const PlaneSet& set, const Solid& piece) {
  const RoundedSolid rounded = round_solid(set, piece);
  if (rounded.collapsed) {
    if (!rounded.mesh.triangles.empty()) return "vanished with triangles left";
    const double volume = mpq_class(exact_six_volume(set, piece) / 6).get_d();
    return volume <= rounded.moved_volume_bound * (1 + 1e-12) ? std::string()
                                                              : "vanished beyond the bound of its rounding";
  }
  if (!rounded.valid) return "cannot be rounded: " + rounded.defect;
  const Mesh read = read_mesh_from_bytes(write_mesh_to_bytes(rounded.mesh, MeshFormat::off), MeshFormat::off);
  // The reader numbers vertices by first use: compare triangle by triangle.
  if (read.triangles.size() != rounded.mesh.triangles.size()) return "read back with another triangle count";
  for (std::size_t t = 0; t < read.triangles.size(); ++t) {
    for (int c = 0; c < 3; ++c) {
      if (!(read.positions[read.triangles[t][c]] == rounded.mesh.positions[rounded.mesh.triangles[t][c]])) {
        return "read back with other positions";
      }
    }
  }
  const ValidationReport report = validate_mesh(read);
  return report.valid() ? std::string() : "read back invalid: " + report.summary();
}

}  // namespace shatter::test
