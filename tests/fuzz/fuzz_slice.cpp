// Fuzz target: slice-from-bytes, the whole cut: the one cut call
// (meshtree/plane_cut.hpp), what `shatter slice` and the builder run.
//
// Input layout: bytes 0-31 the plane as four native doubles (normal x, y, z,
// offset; a non-finite value or a zero normal skips the input), byte 32 the mesh
// format (its value mod 4: OFF, OBJ, PLY, STL), the rest the mesh file.
// Meshes the library refuses as solids (require_valid_solid, self-intersections
// included) and meshes over max_triangles are skipped.
//
// Properties: every piece's exact solid is sound (check_solid) with a positive
// exact volume, the volumes summing to the input's exactly, and its mesh names a
// defect exactly when validate_mesh refuses it or rounding left no triangle.

#include <cmath>
#include <cstring>
#include <string>
#include <typeinfo>

#include <gmpxx.h>

#include "fuzz_support.hpp"
#include "shatter/kernel/validate.hpp"
#include "shatter/cut/plane_cut.hpp"
#include "support/checks.hpp"

namespace {

using shatter::fuzz::fail;
using shatter::fuzz::require;

constexpr std::size_t plane_bytes = 4 * sizeof(double);

/// The cut's promise: sound exact pieces whose volumes add up exactly,
/// each mesh certified or its defect named, a collapsed piece vanished. A
/// refusal (UnsupportedGeometryError) is counted, not failed here: the replay
/// holds the committed corpus to a ceiling of none (tests/fuzz/CMakeLists.txt).
void check_plane_cut(const shatter::Mesh& mesh, const shatter::Plane& plane) {
  const shatter::PlaneInput input = shatter::prepare_plane_input(mesh);
  const shatter::Plane cuts[] = {plane};
  const shatter::PlaneSet set = input.geometry.plane_set(cuts);
  shatter::PlaneCut cut;
  try {
    cut = shatter::cut_by_plane(input, set, input.solid, &input.mesh, shatter::PlaneRef::cut(0));
  } catch (const shatter::UnsupportedGeometryError&) {
    ++shatter::fuzz::known_limitation_refusals;
    return;
  } catch (const std::exception& error) {
    fail(std::string("plane cut: unexpected ") + typeid(error).name() + ": " + error.what());
  }
  require(cut.plane_missed == cut.pieces.empty(), "plane cut: pieces returned although the plane missed, or none");
  if (cut.plane_missed) return;
  mpq_class six_volume = 0;
  for (const shatter::CutPiece& piece : cut.pieces) {
    const std::string problem = shatter::check_solid(set, piece.solid);
    require(problem.empty(), "plane cut piece is not a sound solid: " + problem);
    const mpq_class six = shatter::test::exact_six_volume(set, piece.solid);
    require(six > 0, "plane cut piece has no positive volume");
    six_volume += six;
    // A piece that rounding collapses whole has no triangles left (which
    // validate_mesh, a check of what is there, does not call invalid); any other
    // piece names a defect exactly when validate_mesh refuses its mesh.
    // (corpus: cube-off-subnormal-plane-piece-collapses.bin, x + 2^-1029·y = 1
    // through a cube's face, leaves above it a sliver 1e-310 thick.)
    const bool collapsed = piece.mesh.triangles.empty();
    require(!collapsed || !piece.defect.empty(), "plane cut piece: no triangles, yet no defect named");
    require(collapsed == piece.vanished, "plane cut piece: vanished exactly when rounding collapsed it whole");
    require(piece.moved_volume <= piece.moved_volume_bound * (1 + 1e-12) || piece.vanished,
            "plane cut piece: a repair moved more volume than its bound");
    require(collapsed || piece.defect.empty() == shatter::validate_mesh(piece.mesh).valid(),
            "plane cut piece: a defect named for a valid mesh, or none for an invalid one");
  }
  require(six_volume == shatter::test::exact_six_volume(mesh), "plane cut pieces' volumes do not sum to the input's");
}

}  // namespace

/// libFuzzer's entry point: one plane and one mesh, cut.
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < plane_bytes + 1) return 0;
  double values[4];
  std::memcpy(values, data, plane_bytes);
  for (const double value : values) {
    if (!std::isfinite(value)) return 0;
  }
  const shatter::Plane plane{{values[0], values[1], values[2]}, values[3]};
  if (plane.normal.x == 0 && plane.normal.y == 0 && plane.normal.z == 0) return 0;

  const auto format = static_cast<shatter::MeshFormat>(data[plane_bytes] % 4);
  shatter::Mesh mesh;
  if (!shatter::fuzz::try_read(shatter::fuzz::as_bytes(data + plane_bytes + 1, size - plane_bytes - 1), format, mesh)) {
    return 0;
  }
  if (mesh.triangles.size() > shatter::fuzz::max_triangles) return 0;
  try {
    shatter::require_valid_solid(mesh, "fuzz input", /*allow_self_intersections=*/false);
  } catch (const shatter::InvalidMeshError&) {
    return 0;
  } catch (const std::exception& error) {
    fail(std::string("require_valid_solid: unexpected ") + typeid(error).name() + ": " + error.what());
  }
  check_plane_cut(mesh, plane);
  return 0;
}
