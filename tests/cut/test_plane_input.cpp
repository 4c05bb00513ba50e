// An input mesh made ready for the plane kernel (meshtree/plane_input.hpp): every
// generated and corpus mesh becomes a sound plane-based solid with the mesh's exact
// volume, coplanar triangles merged into one face when the mesh has no attributes.
// Then the kernel's one cut call on it (meshtree/plane_cut.hpp).

#include <catch2/catch.hpp>

#include <gmpxx.h>

#include <tbb/task_arena.h>

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "shatter/kernel/error.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/mass.hpp"
#include "shatter/kernel/rationals.hpp"
#include "shatter/kernel/validate.hpp"
#include "shatter/kernel/solid.hpp"
#include "shatter/cut/plane_cut.hpp"
#include "shatter/cut/plane_input.hpp"
#include "support/checks.hpp"
#include "shatter/generators/corpus.hpp"
#include "support/degenerate.hpp"
#include "shatter/generators/random.hpp"
#include "shatter/generators/solids.hpp"

using namespace shatter;
using namespace shatter::test;

TEST_CASE("meshes become sound plane-based solids, coplanar faces merged without attributes", "[plane][solid]") {
  std::vector<NamedMesh> meshes = generated_meshes();
  for (const auto& path : valid_meshes()) meshes.push_back({path.filename().string(), read_mesh(path)});
  REQUIRE(meshes.size() > 20);
  for (const NamedMesh& m : meshes) {
    INFO(m.name);
    const PlaneInput input = prepare_plane_input(m.mesh);
    CHECK(check_solid(input.geometry.plane_set({}), input.solid) == "");
    CHECK(input.solid.faces.size() <= m.mesh.triangle_count());
    CHECK(input.shells.shell_of_triangle.size() == m.mesh.triangle_count());
    // The solid has the mesh's volume exactly.
    CHECK(exact_six_volume(input.geometry.plane_set({}), input.solid) == exact_six_volume(m.mesh));
  }
  const PlaneInput cube = prepare_plane_input(unit_cube());
  CHECK(cube.solid.faces.size() == 6);
  CHECK(cube.solid.convex);
  const PlaneInput seams = prepare_plane_input(with_seams(unit_cube()));
  CHECK(seams.solid.faces.size() == 12);  // attributes: every triangle its own face
  CHECK(seams.solid.convex);
  CHECK_FALSE(prepare_plane_input(torus(3, 1, 16, 8)).solid.convex);
}

namespace {

// The parts of two plane inputs that the builder reads, compared field by field.
void require_same_input(const PlaneInput& a, const PlaneInput& b) {
  REQUIRE(a.mesh.triangles == b.mesh.triangles);
  REQUIRE(a.mesh.positions == b.mesh.positions);
  REQUIRE(a.geometry.planes.size() == b.geometry.planes.size());
  REQUIRE(a.shells.shell_of_triangle == b.shells.shell_of_triangle);
  REQUIRE(same_solid(a.solid, b.solid));
}

// require_valid_solid's refusal of `mesh`, or "" when it passes.
std::string refusal_of(const Mesh& mesh) {
  try {
    require_valid_solid(mesh, "m", false);
  } catch (const InvalidMeshError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("prepare_plane_input_beside prepares as prepare_plane_input or throws the check's refusal", "[plane][solid]") {
  // On one thread the check runs first; on two, beside the preparation once a
  // linear pass has ruled out every defect but self-intersections. Either way
  // the input is prepare_plane_input's, and a refused mesh throws the check's
  // own line, never what the preparation met (this main traps floating-point
  // exceptions: a preparation run on a NaN coordinate stopped the test).
  std::vector<NamedMesh> meshes = generated_meshes();
  for (const auto& path : valid_meshes()) meshes.push_back({path.filename().string(), read_mesh(path)});
  for (const auto& path : bad_meshes()) {
    try {
      meshes.push_back({path.filename().string(), read_mesh(path)});
    } catch (const std::exception&) {
      // refused by the reader: nothing to prepare
    }
  }
  Mesh not_finite = unit_cube();
  not_finite.positions[3].y = std::numeric_limits<double>::quiet_NaN();
  meshes.push_back({"NaN coordinate", not_finite});
  Mesh degenerate = unit_cube();
  degenerate.positions.push_back({0.5, 0, 0});
  degenerate.triangles.push_back({0, 1, static_cast<VertexIndex>(degenerate.positions.size() - 1)});
  degenerate.surfaces.push_back(original_surface);
  meshes.push_back({"zero-area triangle", degenerate});
  Mesh open = box({0, 0, 0}, {1, 1, 1});
  open.triangles.pop_back();
  open.surfaces.pop_back();
  meshes.push_back({"open box", open});
  meshes.push_back({"flipped box", flipped(box({0, 0, 0}, {1, 1, 1}))});
  meshes.push_back({"two overlapping boxes", merge({box({0, 0, 0}, {2, 2, 2}), box({1, 1, 1}, {3, 3, 3})})});
  std::size_t refused = 0, prepared = 0;
  for (const NamedMesh& m : meshes) {
    INFO(m.name);
    const std::string refusal = refusal_of(m.mesh);
    for (const int threads : {1, 2}) {
      INFO(threads << " threads");
      tbb::task_arena arena(threads);
      const auto beside = [&] {
        return arena.execute([&] {
          return prepare_plane_input_beside(m.mesh, [&] { require_valid_solid(m.mesh, "m", false); });
        });
      };
      if (!refusal.empty()) {
        ++refused;
        try {
          beside();
          FAIL("no refusal");
        } catch (const InvalidMeshError& e) {
          REQUIRE(std::string(e.what()) == refusal);
        }
        continue;
      }
      ++prepared;
      require_same_input(beside(), prepare_plane_input(m.mesh));
      // The check's exception wins on a mesh the preparation handles well.
      REQUIRE_THROWS_WITH(arena.execute([&] {
                            return prepare_plane_input_beside(m.mesh, [] { throw std::runtime_error("checked"); });
                          }),
                          "checked");
    }
  }
  CHECK(refused >= 2 * 8);
  CHECK(prepared >= 2 * 20);
}

// The one cut call (plane_cut.hpp) over generated solids and the corpus: a plane
// through the volume centroid cuts (the centroid lies inside the convex hull, so
// vertices lie strictly on both sides; its rounding, a few ulps, does not take it
// out of any of these solids); the pieces are sound, on the
// side they name, with exact volumes adding up to the input's; a piece's mesh
// names a defect exactly when validate_mesh refuses it; each side has cap
// triangles, with the asked surface id, exactly when the cut has a cap. A plane
// beyond the bounding box misses and names the side.
TEST_CASE("cut_by_plane: pieces sound on their side, exact volumes add up, meshes certified", "[plane][cut]") {
  std::vector<NamedMesh> meshes = generated_meshes();
  for (const auto& path : valid_meshes()) meshes.push_back({path.filename().string(), read_mesh(path)});
  REQUIRE(meshes.size() > 20);
  Random random(20261202);
  for (const NamedMesh& m : meshes) {
    INFO(m.name);
    const PlaneInput input = prepare_plane_input(m.mesh);
    const mpq_class six = exact_six_volume(m.mesh);
    const Vec3 centroid = mass_properties(m.mesh).centroid;
    for (int k = 0; k < 3; ++k) {
      const Vec3 n = random.direction();
      const Plane planes[] = {{n, -dot(n, centroid)}};
      INFO("plane " << n.x << ' ' << n.y << ' ' << n.z << ' ' << planes[0].offset);
      const PlaneSet set = input.geometry.plane_set(planes);
      PlaneCutOptions options;
      options.cap_surface = 7;
      PlaneCut cut;
      try {
        cut = cut_by_plane(input, set, input.solid, &input.mesh, PlaneRef::cut(0), options);
      } catch (const UnsupportedGeometryError& error) {
        FAIL_CHECK("refused: " << error.what());  // a pinch: not met by a random plane through the centroid
        continue;
      }
      CHECK_FALSE(cut.plane_missed);
      CHECK(cut.cap_loops >= cut.cap_faces);
      mpq_class sum = 0;
      std::size_t certified = 0, cap_triangles[2] = {0, 0};
      bool seen_above = false, seen_below = false;
      for (const CutPiece& piece : cut.pieces) {
        REQUIRE(check_solid(set, piece.solid) == "");
        sum += exact_six_volume(set, piece.solid);
        (piece.above ? seen_above : seen_below) = true;
        for (std::size_t v = 0; v < piece.solid.defs.size(); ++v) {
          const Sign s = side(set, PlaneRef::cut(0), piece.solid.defs[v], piece.solid.approx[v]);
          CHECK(s != (piece.above ? Sign::negative : Sign::positive));
        }
        CHECK(piece.defect.empty() == validate_mesh(piece.mesh).valid());
        if (!piece.defect.empty()) continue;
        ++certified;
        cap_triangles[piece.above] +=
            std::size_t(std::count(piece.mesh.surfaces.begin(), piece.mesh.surfaces.end(), options.cap_surface));
      }
      CHECK((seen_above && seen_below));
      CHECK(sum == six);
      CHECK(cut.certified() == (certified == cut.pieces.size()));
      // A cap on each side exactly when the plane crosses the inside (two solids
      // side by side may have the plane pass between them).
      if (cut.certified()) {
        CHECK((cap_triangles[0] > 0) == (cut.cap_faces > 0));
        CHECK((cap_triangles[1] > 0) == (cut.cap_faces > 0));
      }
    }
    // Planes beyond the bounding box, on either side: missed, the whole named.
    double lo = m.mesh.positions[0].x, hi = lo;
    for (const Vec3& p : m.mesh.positions) lo = std::min(lo, p.x), hi = std::max(hi, p.x);
    const Vec3 x{1, 0, 0};
    for (const auto& [plane, above] : {std::pair{Plane{x, -(hi + 1)}, false}, std::pair{Plane{x, -(lo - 1)}, true}}) {
      const PlaneCut missed = cut_mesh_by_plane(m.mesh, plane);
      CHECK(missed.plane_missed);
      CHECK(missed.pieces.empty());
      CHECK(missed.whole_above == above);
    }
  }
}
