// The solid an arrangement winds around (winding_boundary), judged apart from
// the code that makes it: the selected faces are closed and oriented (every
// edge passed as often each way), each face once, and the volume they bound,
// summed exactly on the vertices' rational coordinates, is the union's: for
// lattice boxes the count of unit voxels any box covers, for solids at random
// angles CGAL's corefinement union on exact constructions (Epeck) of the
// separate shells. Where the result is also 2-manifold (no solids touching
// along an edge or at a point), validate_mesh on its coordinates, exact for
// lattice boxes, accepts it.

#include <catch2/catch.hpp>

#include <gmpxx.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "shatter/generators/corpus.hpp"
#include "shatter/generators/random.hpp"
#include "shatter/generators/solids.hpp"
#include "shatter/kernel/arrangement.hpp"
#include "shatter/kernel/exact.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/rationals.hpp"
#include "shatter/kernel/validate.hpp"
#include "support/lattice_boxes.hpp"
#include "support/sanitizers.hpp"
#include "support/turned.hpp"
#include "support/union_volume.hpp"

using namespace shatter;

namespace {

using Q3 = std::array<mpq_class, 3>;
using EK = ExactKernel;

using test::turned;

struct Checked {
  WindingBoundary boundary;
  mpq_class six_volume;
  bool manifold = false;  ///< no edge with more than two triangles, no pinched vertex
  bool valid = false;     ///< validate_mesh accepted it (asked only when manifold and exact in doubles)
};

// Arranges `mesh`, selects the boundary, and checks what holds for any input of
// closed shells: status ok, each face once, closed and oriented.
Checked check_union(const std::string& name, const Mesh& mesh) {
  INFO(name);
  const MeshArrangement arrangement = arrange_triangles(mesh.positions, mesh.triangles);
  Checked checked;
  checked.boundary = winding_boundary(arrangement);
  const WindingBoundary& boundary = checked.boundary;
  REQUIRE(boundary.status == WindingBoundary::Status::ok);
  REQUIRE(boundary.triangles.size() == boundary.source.size());
  CHECK(winding_boundary(arrangement).triangles == boundary.triangles);  // deterministic
  const PlaneSet set = arrangement.plane_set();
  std::map<VertexIndex, Q3> exact;
  for (const Triangle& t : boundary.triangles) {
    for (VertexIndex v : t) {
      if (!exact.count(v)) exact.emplace(v, exact_coordinates(set, arrangement.defs[v]));
    }
  }
  std::set<Triangle> seen;
  std::map<std::pair<VertexIndex, VertexIndex>, long> passes;  // (u, v): u -> v minus v -> u
  std::map<std::pair<VertexIndex, VertexIndex>, int> uses;
  for (std::size_t k = 0; k < boundary.triangles.size(); ++k) {
    Triangle t = boundary.triangles[k];
    // Each face once, and in its source triangle's plane.
    for (VertexIndex v : t) {
      CHECK(side(set, PlaneRef::input(boundary.source[k]), arrangement.defs[v], arrangement.approx[v]) == Sign::zero);
    }
    Triangle key = t;
    std::sort(key.begin(), key.end());
    CHECK(seen.insert(key).second);
    for (int e = 0; e < 3; ++e) {
      const VertexIndex u = t[e], v = t[(e + 1) % 3];
      passes[{std::min(u, v), std::max(u, v)}] += u < v ? 1 : -1;
      ++uses[{std::min(u, v), std::max(u, v)}];
    }
    const Q3 &a = exact.at(t[0]), &b = exact.at(t[1]), &c = exact.at(t[2]);
    checked.six_volume += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                          a[2] * (b[0] * c[1] - b[1] * c[0]);
  }
  std::size_t unbalanced = 0, crowded = 0;
  for (const auto& [edge, net] : passes) unbalanced += net != 0;
  for (const auto& [edge, count] : uses) crowded += count > 2;
  CHECK(unbalanced == 0);
  // A compact mesh of the result, where its coordinates are exact in doubles.
  bool exact_in_doubles = true;
  Mesh out;
  std::map<VertexIndex, VertexIndex> index;
  for (const auto& [v, q] : exact) {
    index[v] = static_cast<VertexIndex>(out.positions.size());
    out.positions.push_back({q[0].get_d(), q[1].get_d(), q[2].get_d()});
    exact_in_doubles = exact_in_doubles && mpq_class(q[0].get_d()) == q[0] && mpq_class(q[1].get_d()) == q[1] &&
                       mpq_class(q[2].get_d()) == q[2];
  }
  for (const Triangle& t : boundary.triangles) out.triangles.push_back({index[t[0]], index[t[1]], index[t[2]]});
  out.surfaces.assign(out.triangles.size(), 0);
  if (exact_in_doubles && crowded == 0) {
    const ValidationReport report = validate_mesh(out);
    checked.manifold = true;
    for (const Defect& defect : report.defects) {
      // A vertex where solids touch at a point is pinched, and its fans meet there.
      if (defect.kind == DefectKind::non_manifold_vertex) checked.manifold = false;
    }
    if (checked.manifold) {
      INFO((report.defects.empty() ? std::string() : report.defects.front().first));
      CHECK(report.valid());
    }
    checked.valid = report.valid();
  }
  return checked;
}

}  // namespace

TEST_CASE("unions of lattice boxes: closed, oriented, the voxels' volume", "[arrangement][union]") {
  // Two to five boxes on integer corners in [0, 4]^3, some tessellated finer
  // (half-integer vertices), some repeated: faces shared, overlapping on one
  // plane either way round, edges along edges, boxes inside boxes, boxes
  // touching along an edge or at a corner.
  test::Random random(20261207);
  const std::size_t seeds = test::sized(60, 12);
  std::size_t valid = 0, touching = 0, cancelled = 0;
  for (std::size_t seed = 0; seed < seeds; ++seed) {
    const int count = 2 + static_cast<int>(random.index(4));
    std::vector<Mesh> boxes;
    std::set<std::array<int, 3>> voxels;
    for (int b = 0; b < count; ++b) {
      test::LatticeBox drawn = test::random_lattice_box(random, voxels);
      boxes.push_back(std::move(drawn.mesh));
      if (random.index(6) == 0) boxes.push_back(test::box(drawn.lo, drawn.hi));  // the same box again
    }
    const Checked checked = check_union("lattice boxes #" + std::to_string(seed), test::merge(boxes));
    INFO("lattice boxes #" << seed);
    CHECK(checked.six_volume == mpq_class(6 * static_cast<long>(voxels.size())));
    valid += checked.valid;
    touching += !checked.manifold;
    cancelled += checked.boundary.cancelled;
  }
  INFO("valid " << valid << ", touching " << touching);
  CHECK(valid + touching == seeds);  // every result validates unless solids touch
  CHECK(valid > seeds / 8);
  CHECK(touching > 0);
  CHECK(cancelled > 0);  // faces shared by two boxes, one each way
}

TEST_CASE("unions of solids at random angles: closed, oriented, CGAL's exact union volume", "[arrangement][union]") {
  // A box, a sphere and a torus (and a second box) turned and shifted at
  // random so that they overlap, and a solid inside another one.
  test::Random random(20261208);
  const std::size_t seeds = test::sized(6, 2);
  for (std::size_t seed = 0; seed < seeds; ++seed) {
    const auto angle = [&] { return random.uniform(0, 6.283185307179586); };
    const auto shift = [&](double reach) {
      return Vec3{random.uniform(-reach, reach), random.uniform(-reach, reach), random.uniform(-reach, reach)};
    };
    std::vector<Mesh> shells{
        turned(test::box({-1, -1, -1}, {1, 1, 1}), angle(), angle(), angle(), shift(0.8)),
        turned(test::ellipsoid({0, 0, 0}, {1, 1, 1}, 10, 7), angle(), angle(), angle(), shift(0.8)),
        turned(test::torus(1.0, 0.3, 10, 6), angle(), angle(), angle(), shift(0.5)),
    };
    if (seed % 2 == 1) shells.push_back(turned(test::box({-0.2, -0.2, -0.2}, {0.2, 0.2, 0.2}), angle(), angle(), angle(), {0, 0, 0}));
    const std::string name = "solids at random angles #" + std::to_string(seed);
    const Checked checked = check_union(name, test::merge(shells));
    INFO(name);
    CHECK(EK::FT(checked.six_volume) == test::six_volume_of_union(shells));
    CHECK(checked.boundary.triangles.size() > 100);
  }
}

TEST_CASE("a solid and its copy, and a solid and itself inside out", "[arrangement][union]") {
  const Mesh sphere = test::ellipsoid({0, 0, 0}, {1, 1, 1}, 8, 6);
  const Checked twice = check_union("a sphere twice", test::merge({sphere, sphere}));
  CHECK(twice.boundary.triangles.size() == sphere.triangles.size());
  CHECK(twice.boundary.max_winding == 2);
  CHECK(twice.valid);
  const Checked gone = check_union("a sphere and its inverse", test::merge({sphere, test::flipped(sphere)}));
  CHECK(gone.boundary.triangles.empty());
  CHECK(gone.boundary.cancelled == sphere.triangles.size());
  // Nested: the inner sphere adds nothing; a cavity (inverted inner sphere) is
  // kept.
  const Mesh inner = test::ellipsoid({0, 0, 0}, {0.5, 0.5, 0.5}, 8, 6);
  const Checked nested = check_union("nested spheres", test::merge({sphere, inner}));
  CHECK(nested.boundary.triangles.size() == sphere.triangles.size());
  const Checked hollow = check_union("a sphere with a cavity", test::merge({sphere, test::flipped(inner)}));
  CHECK(hollow.boundary.triangles.size() == sphere.triangles.size() + inner.triangles.size());
}

TEST_CASE("the self-intersecting corpus: the union is closed and oriented", "[arrangement][union][corpus]") {
  std::size_t meshes = 0;
  for (const auto& path : test::self_intersecting_meshes()) {
    const Mesh mesh = read_mesh(path);
    const Checked checked = check_union(path.filename().string(), mesh);
    CHECK(checked.six_volume > 0);
    ++meshes;
  }
  CHECK(meshes >= 3);
}
