// The plane kernel's rounding and certification of a solid
// (triangulate/solid_mesh.hpp): pieces of cuts through a vertex up to rounding,
// the issue that introduced the kernel, are rounded once and written as meshes
// that validate when read back. (Every written piece of every other plane-kernel
// test is checked the same way: support/written_back.hpp.)

#include <catch2/catch.hpp>

#include <cstdint>
#include <vector>

#include "shatter/kernel/io.hpp"
#include "shatter/kernel/solid.hpp"
#include "shatter/meshtree/cut_solid.hpp"
#include "shatter/meshtree/plane_input.hpp"
#include "shatter/generators/corpus.hpp"
#include "shatter/generators/random.hpp"
#include "shatter/generators/solids.hpp"
#include "support/written_back.hpp"

using namespace shatter;
using namespace shatter::test;

TEST_CASE("regression: a plane through a vertex up to rounding no longer writes an invalid piece", "[plane][regression]") {
  // The reproducer: `shatter slice elephant.off --plane 1,1,0,-0.062960299999999997`
  // (x + y + d = 0 through a vertex, d the rounded -(x + y)) wrote pieces that
  // `shatter validate` refused. Here: that plane and the same construction
  // through 48 vertices of the elephant and of a generated ellipsoid.
  const Mesh elephant = read_mesh(mesh_dir() / "elephant.off");
  const Mesh ellipsoid_mesh = ellipsoid({0.1, 0.2, 0.3}, {1.3, 0.7, 0.9}, 24, 16);
  for (const Mesh* mesh : {&elephant, &ellipsoid_mesh}) {
    const PlaneInput input = prepare_plane_input(*mesh);
    std::vector<Plane> planes;
    if (mesh == &elephant) planes.push_back({{1, 1, 0}, -0.062960299999999997});
    Random random(12);
    for (int k = 0; k < 48; ++k) {
      const Vec3 p = mesh->positions[random.index(mesh->positions.size())];
      planes.push_back({{1, 1, 0}, -(p.x + p.y)});
    }
    std::size_t written = 0;
    for (const Plane& plane : planes) {
      const std::vector<Plane> cuts{plane};
      const PlaneSet set = input.geometry.plane_set(cuts);
      const SolidCut cut = cut_solid(set, input.solid, PlaneRef::cut(0), 1, input.shells);
      for (const auto* side_solids : {&cut.below, &cut.above}) {
        for (const Solid& piece : *side_solids) {
          INFO("plane x + y + " << plane.offset);
          CHECK(written_problem(set, piece) == "");
          ++written;
        }
      }
    }
    CHECK(written > 2 * planes.size() - 10);
  }
}
