// Property tests of the test oracle's cut of a mesh (tests/oracle: the
// degeneracy policy of oracle/slice.hpp, observed through the full cut,
// oracle/cut.hpp) over the corpus and generated meshes, with random and
// degenerate planes, in both of its number types (rounded cut points, Epeck
// rationals): valid pieces that partition the volume, planes through vertices,
// edges and faces, determinism, the two number types' agreement, cap attributes,
// and cap corners shared bit for bit. The caps themselves: tests/triangulate;
// solid separation: tests/cut/test_separate.cpp.

#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>

#include "shatter/generators/corpus.hpp"
#include "shatter/generators/random.hpp"
#include "shatter/generators/solids.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/oracle/cut.hpp"
#include "support/checks.hpp"
#include "support/cut_cases.hpp"
#include "support/sanitizers.hpp"
#include "shatter/generators/solids.hpp"

using namespace shatter;
using namespace shatter::oracle;
using namespace shatter::test;

namespace {

template <class Point>
std::size_t piece_count(const CutResult<Point>& r) {
  return r.below.size() + r.above.size();
}

// Checks every invariant of one fast-kernel cut. Where the plane grazes a vertex
// the embedding may degenerate after rounding: topology is still required, and
// the pieces whose embedding is not valid are counted (returned), never hidden.
std::size_t check_fast_cut(const Mesh& mesh, const TestPlane& test_plane, const std::string& what) {
  const Plane& plane = test_plane.plane;
  INFO(what << " plane n=(" << plane.normal.x << ", " << plane.normal.y << ", " << plane.normal.z
            << ") d=" << plane.offset);
  const CutResult<Vec3> result = cut_mesh(mesh, plane);
  mpq_class volume = 0;
  std::size_t invalid_embeddings = 0;
  for (const auto* side : {&result.below, &result.above}) {
    for (const Mesh& piece : *side) {
      CHECK(topology_problem(piece) == "");
      if (test_plane.grazes_vertex) {
        invalid_embeddings += solid_problem(piece).empty() ? 0 : 1;
      } else {
        CHECK(solid_problem(piece) == "");
      }
      volume += exact_six_volume(piece);
    }
  }
  const double input = exact_six_volume(mesh).get_d();
  CHECK(std::fabs(volume.get_d() - input) <= 1e-9 * std::fabs(input));
  CHECK(piece_count(result) >= 1);
  return invalid_embeddings;
}

void check_exact_cut(const Mesh& mesh, const TestPlane& test_plane, const std::string& what) {
  const Plane& plane = test_plane.plane;
  INFO(what << " (exact) plane n=(" << plane.normal.x << ", " << plane.normal.y << ", " << plane.normal.z
            << ") d=" << plane.offset);
  const CutResult<ExactPoint> result = cut_mesh(to_exact(mesh), plane);
  mpq_class volume = 0;
  for (const auto* side : {&result.below, &result.above}) {
    for (const ExactMesh& piece : *side) {
      CHECK(exact_solid_problem(piece) == "");
      volume += exact_six_volume(piece);
    }
  }
  CHECK(volume == exact_six_volume(mesh));
}

}  // namespace

TEST_CASE("fast cuts of generated meshes are valid solids that partition the volume") {
  const auto meshes = generated_meshes();
  REQUIRE(meshes.size() >= 10);
  for (const NamedMesh& m : meshes) {
    REQUIRE(solid_problem(m.mesh) == "");
    for (std::uint64_t seed = 1; seed <= 6; ++seed) {
      for (const TestPlane& plane : planes_for(m.mesh, seed, 4)) check_fast_cut(m.mesh, plane, m.name);
    }
  }
}

TEST_CASE("exact cuts of generated meshes partition the volume exactly") {
  for (const NamedMesh& m : generated_meshes()) {
    for (std::uint64_t seed = 1; seed <= 2; ++seed) {
      for (const TestPlane& plane : planes_for(m.mesh, seed, 2)) check_exact_cut(m.mesh, plane, m.name);
    }
  }
}

TEST_CASE("cuts of every corpus mesh are valid in both kernels") {
  const auto meshes = corpus_meshes();
  REQUIRE(meshes.size() >= 10);
  // Every mesh; every other one under the sanitizers (37 s there for all of
  // them, on a clean clone of fe3da8d).
  const std::size_t stride = sized(1, 2);
  for (std::size_t i = 0; i < meshes.size(); i += stride) {
    const NamedMesh& m = meshes[i];
    for (const TestPlane& plane : planes_for(m.mesh, 7, 3)) check_fast_cut(m.mesh, plane, m.name);
    for (const TestPlane& plane : planes_for(m.mesh, 11, 1)) check_exact_cut(m.mesh, plane, m.name);
  }
}

TEST_CASE("planes along grid lines hit vertices, edges and faces at once") {
  // Coordinates are multiples of 1/2 (exact), so axis and diagonal planes through
  // grid values contain many vertices, whole edges and whole faces.
  const Mesh grid = grid_box({-1, -1, -1}, {1, 1, 1}, 4);
  for (double c : {-1.0, -0.5, 0.0, 0.5, 1.0}) {
    for (int axis = 0; axis < 3; ++axis) {
      Vec3 n{};
      (axis == 0 ? n.x : axis == 1 ? n.y : n.z) = 1;
      check_fast_cut(grid, {{n, -c}}, "grid axis");
      check_exact_cut(grid, {{n, -c}}, "grid axis");
    }
    check_fast_cut(grid, {{{1, 1, 0}, -c}}, "grid diagonal");
    check_exact_cut(grid, {{{1, 1, 0}, -c}}, "grid diagonal");
    check_fast_cut(grid, {{{1, -1, 1}, -c}}, "grid body diagonal");
    check_exact_cut(grid, {{{1, -1, 1}, -c}}, "grid body diagonal");
  }
}

TEST_CASE("a plane containing a face or missing the mesh returns it whole") {
  const Mesh cube = box({0, 0, 0}, {1, 1, 1});
  for (double d : {0.0, -1.0, 5.0, -5.0}) {
    const auto result = cut_mesh(cube, {{0, 0, 1}, d});
    CHECK(result.plane_missed);
    REQUIRE(piece_count(result) == 1);
    const Mesh& piece = result.below.empty() ? result.above[0] : result.below[0];
    CHECK(piece.triangles.size() == cube.triangles.size());
    CHECK(piece.positions.size() == cube.positions.size());
    CHECK(exact_six_volume(piece) == exact_six_volume(cube));
  }
  // z = 0 holds the bottom face, which faces -z: the cube lies above.
  CHECK(cut_mesh(cube, {{0, 0, 1}, 0.0}).above.size() == 1);
  CHECK(cut_mesh(cube, {{0, 0, 1}, -1.0}).below.size() == 1);
}

TEST_CASE("the same cut twice gives identical bytes") {
  for (const NamedMesh& m : generated_meshes()) {
    for (const TestPlane& plane : planes_for(m.mesh, 5, 2)) {
      const auto first = cut_mesh(m.mesh, plane.plane);
      const auto second = cut_mesh(m.mesh, plane.plane);
      REQUIRE(first.below.size() == second.below.size());
      REQUIRE(first.above.size() == second.above.size());
      for (std::size_t i = 0; i < first.below.size(); ++i) {
        CHECK(canonical_bytes(first.below[i]) == canonical_bytes(second.below[i]));
      }
      for (std::size_t i = 0; i < first.above.size(); ++i) {
        CHECK(canonical_bytes(first.above[i]) == canonical_bytes(second.above[i]));
      }
    }
  }
}

TEST_CASE("both kernels agree on topology when no vertex lies on the plane") {
  std::size_t compared = 0;
  for (const NamedMesh& m : generated_meshes()) {
    Random random(99);
    const Box3 b = bounds(m.mesh);
    for (int i = 0; i < 4; ++i) {
      const Vec3 p{random.uniform(b.lo.x, b.hi.x), random.uniform(b.lo.y, b.hi.y), random.uniform(b.lo.z, b.hi.z)};
      const Plane plane = plane_through(p, random.direction());
      bool touches_vertex = false;
      for (const Vec3& v : m.mesh.positions) touches_vertex |= side_of_plane(plane, v) == Sign::zero;
      if (touches_vertex) continue;
      const auto fast = cut_mesh(m.mesh, plane);
      const auto exact = cut_mesh(to_exact(m.mesh), plane);
      INFO(m.name);
      REQUIRE(fast.below.size() == exact.below.size());
      REQUIRE(fast.above.size() == exact.above.size());
      auto same = [](const Mesh& fast_piece, const ExactMesh& exact_piece) {
        return fast_piece.positions.size() == exact_piece.positions.size() &&
               fast_piece.triangles.size() == exact_piece.triangles.size();
      };
      for (std::size_t k = 0; k < fast.below.size(); ++k) CHECK(same(fast.below[k], exact.below[k]));
      for (std::size_t k = 0; k < fast.above.size(); ++k) CHECK(same(fast.above[k], exact.above[k]));
      ++compared;
    }
  }
  CHECK(compared > 20);
}

TEST_CASE("cap corners carry the plane normal, UVs and tangents") {
  Mesh cube = box({0, 0, 0}, {1, 1, 1});
  const std::size_t corners = 3 * cube.triangles.size();
  cube.corners.normals.assign(corners, {0, 0, 1});
  cube.corners.uvs.assign(corners, {0.5, 0.5});
  cube.corners.tangents.assign(corners, {1, 0, 0, 1});
  CutOptions options;
  options.cap_surface = 7;
  options.interior_uv_scale = 2.0;
  const Plane plane{{0, 0, 2}, -1};  // z = 0.5, normal not unit length
  const auto result = cut_mesh(cube, plane, options);
  REQUIRE(result.below.size() == 1);
  REQUIRE(result.above.size() == 1);
  for (const auto* side : {&result.below, &result.above}) {
    const Mesh& piece = side->front();
    CHECK(solid_problem(piece) == "");
    const double expected_z = side == &result.below ? 1.0 : -1.0;
    std::size_t cap_corners = 0;
    for (std::size_t t = 0; t < piece.triangles.size(); ++t) {
      if (piece.surfaces[t] != 7) continue;
      for (int k = 0; k < 3; ++k) {
        const Vec3 n = piece.corners.normals[3 * t + k];
        CHECK(n.z == expected_z);
        const Vec3 p = piece.positions[piece.triangles[t][k]];
        const Vec2 uv = piece.corners.uvs[3 * t + k];
        CHECK(std::fabs(uv.x * uv.x + uv.y * uv.y - 4 * (p.x * p.x + p.y * p.y)) < 1e-12);
        ++cap_corners;
      }
    }
    CHECK(cap_corners >= 6);
  }
}

TEST_CASE("exact pieces on both sides of a cut round their shared cap vertices to identical doubles") {
  std::size_t shared_checked = 0;
  for (const NamedMesh& m : generated_meshes()) {
    for (const TestPlane& plane : planes_for(m.mesh, 13, 2)) {
      const auto result = cut_mesh(to_exact(m.mesh), plane.plane);
      if (result.plane_missed) continue;
      // The rounded positions of every cap vertex, per side: each side's cap is
      // the same vertices, so the two sets must agree bit for bit.
      auto cap_vertices = [](const std::vector<ExactMesh>& side) {
        std::vector<std::array<double, 3>> points;
        for (const ExactMesh& piece : side) {
          const Mesh rounded = to_fast(piece);
          for (std::size_t t = 0; t < rounded.triangles.size(); ++t) {
            if (rounded.surfaces[t] == original_surface) continue;
            for (VertexIndex v : rounded.triangles[t]) {
              const Vec3 p = rounded.positions[v];
              points.push_back({p.x, p.y, p.z});
            }
          }
        }
        std::sort(points.begin(), points.end());
        points.erase(std::unique(points.begin(), points.end()), points.end());
        return points;
      };
      const auto below = cap_vertices(result.below);
      INFO(m.name);
      CHECK(below == cap_vertices(result.above));
      shared_checked += below.size();
    }
  }
  CHECK(shared_checked > 100);
}
