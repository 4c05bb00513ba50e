// Fuzz target: slice-from-bytes, the whole cut: the plane kernel's one cut call
// (meshtree/plane_cut.hpp) and the older kernels' cut_mesh (meshtree/cut.hpp).
//
// Input layout: bytes 0-31 the plane as four native doubles (normal x, y, z,
// offset; a non-finite value or a zero normal skips the input), byte 32 the mesh
// format (its value mod 4: OFF, OBJ, PLY, STL), the rest the mesh file.
// Meshes the library refuses as solids (require_valid_solid, self-intersections
// included) and meshes over max_triangles are skipped.
//
// Properties, plane kernel: every piece's exact solid is sound (check_solid) with
// a positive exact volume, the volumes summing to the input's exactly, and its
// mesh names a defect exactly when validate_mesh refuses it. Fast and exact
// kernels: every piece is a closed, consistently oriented
// 2-manifold using every vertex (fast kernel: topology is all it promises); the
// exact kernel's pieces are moreover valid solids decided on exact coordinates
// (no zero-area triangle, positive volume) whose volumes sum to the input's exactly.

#include <cmath>
#include <cstring>
#include <string>
#include <typeinfo>

#include <gmpxx.h>

#include "fuzz_support.hpp"
#include "shatter/kernel/exact.hpp"
#include "shatter/kernel/validate.hpp"
#include "shatter/meshtree/cut.hpp"
#include "shatter/meshtree/plane_cut.hpp"
#include "support/checks.hpp"

namespace {

using shatter::fuzz::fail;
using shatter::fuzz::require;

constexpr std::size_t plane_bytes = 4 * sizeof(double);

/// Cuts with one kernel, turning the documented refusal (UnsupportedGeometryError)
/// into false (counted: known_limitation_refusals) and any other exception into
/// an abort.
template <class MeshType, class Result>
bool try_cut(const MeshType& mesh, const shatter::Plane& plane, Result& result, const char* kernel) {
  try {
    result = shatter::cut_mesh(mesh, plane);
    return true;
  } catch (const shatter::UnsupportedGeometryError&) {
    ++shatter::fuzz::known_limitation_refusals;
    return false;
  } catch (const std::exception& error) {
    fail(std::string(kernel) + " cut: unexpected " + typeid(error).name() + ": " + error.what());
  }
}

/// The fast kernel's promise: every piece closed, oriented, manifold, no unused vertex.
void check_fast_cut(const shatter::Mesh& mesh, const shatter::Plane& plane) {
  shatter::CutResult<shatter::Vec3> result;
  if (!try_cut(mesh, plane, result, "fast")) return;
  require(!result.below.empty() || !result.above.empty(), "fast cut returned no piece");
  for (const auto* side : {&result.below, &result.above}) {
    for (const shatter::Mesh& piece : *side) {
      const std::string problem = shatter::test::topology_problem(piece);
      require(problem.empty(), "fast cut piece is not a closed oriented manifold: " + problem);
    }
  }
}

/// The exact kernel's promise: every piece a valid solid, volumes summing exactly.
void check_exact_cut(const shatter::Mesh& mesh, const shatter::Plane& plane) {
  const shatter::ExactMesh exact_mesh = shatter::to_exact(mesh);
  shatter::CutResult<shatter::ExactPoint> result;
  if (!try_cut(exact_mesh, plane, result, "exact")) return;
  require(!result.below.empty() || !result.above.empty(), "exact cut returned no piece");
  mpq_class six_volume = 0;
  for (const auto* side : {&result.below, &result.above}) {
    for (const shatter::ExactMesh& piece : *side) {
      const std::string problem = shatter::test::exact_solid_problem(piece);
      require(problem.empty(), "exact cut piece is not a valid solid: " + problem);
      six_volume += shatter::test::exact_six_volume(piece);
    }
  }
  require(six_volume == shatter::test::exact_six_volume(exact_mesh), "exact cut pieces' volumes do not sum to the input's");
}

/// The plane kernel's promise: sound exact pieces whose volumes add up exactly,
/// each mesh certified or its defect named (a pinch is the documented refusal).
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
    require(piece.defect.empty() == shatter::validate_mesh(piece.mesh).valid(),
            "plane cut piece: a defect named for a valid mesh, or none for an invalid one");
  }
  require(six_volume == shatter::test::exact_six_volume(mesh), "plane cut pieces' volumes do not sum to the input's");
}

}  // namespace

/// libFuzzer's entry point: one plane and one mesh, cut with every kernel.
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
  check_fast_cut(mesh, plane);
  check_exact_cut(mesh, plane);
  return 0;
}
