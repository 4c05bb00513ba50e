// An input mesh made ready for the plane kernel (meshtree/plane_input.hpp): every
// generated and corpus mesh becomes a sound plane-based solid with the mesh's exact
// volume, coplanar triangles merged into one face when the mesh has no attributes.

#include <catch2/catch.hpp>

#include <gmpxx.h>

#include <vector>

#include "shatter/kernel/io.hpp"
#include "shatter/kernel/solid.hpp"
#include "shatter/meshtree/plane_input.hpp"
#include "support/checks.hpp"
#include "shatter/generators/corpus.hpp"
#include "support/degenerate.hpp"
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
