// Caps (triangulate/cap.hpp): the boundary of every cap over real cuts is
// exactly the border edges, and the check every cap passes before it is
// accepted refuses anything else.

#include <catch2/catch.hpp>

#include <map>
#include <string>
#include <utility>
#include <vector>

#include "shatter/slicer/slice.hpp"
#include "shatter/triangulate/cap.hpp"
#include "support/cut_cases.hpp"
#include "support/generators.hpp"

using namespace shatter;
using namespace shatter::test;

namespace {

// Empty when the triangles' boundary is exactly `border`, edge for edge and
// direction for direction, with every other edge matched by its reverse and no
// edge used twice in one direction (counted independently of cap_boundary_is_border).
std::string boundary_problem(const std::vector<Triangle>& triangles, const std::vector<Edge>& border) {
  std::map<std::pair<VertexIndex, VertexIndex>, int> edges;
  for (const Triangle& t : triangles) {
    for (int k = 0; k < 3; ++k) {
      if (t[k] == t[(k + 1) % 3]) return "a degenerate triangle";
      if (++edges[{t[k], t[(k + 1) % 3]}] > 1) return "an edge used twice in one direction";
    }
  }
  std::map<std::pair<VertexIndex, VertexIndex>, int> boundary, expected;
  for (const auto& [e, count] : edges) {
    if (!edges.count({e.second, e.first})) boundary[e] = count;
  }
  for (const Edge& e : border) ++expected[{e[0], e[1]}];
  return boundary == expected ? std::string() : "the boundary is not the border";
}

}  // namespace

TEST_CASE("each cap's boundary is exactly the border edges") {
  std::vector<NamedMesh> meshes = generated_meshes();
  for (const NamedMesh& m : corpus_meshes()) meshes.push_back(m);
  std::size_t caps_checked = 0;
  for (const NamedMesh& m : meshes) {
    for (const TestPlane& test_plane : planes_for(m.mesh, 3, 3)) {
      const Plane& plane = test_plane.plane;
      const SlicedMesh<Vec3> sliced = slice_mesh(m.mesh, plane);
      if (sliced.plane_misses()) continue;
      const Cap<Vec3> cap = triangulate_cap(sliced.positions, sliced.border_edges, plane,
                                            [&](VertexIndex v) { return exact_position(sliced, plane, v); });
      // The cap's boundary (edges without their reverse) must be the border,
      // edge for edge and direction for direction.
      INFO(m.name);
      CHECK(boundary_problem(cap.triangles, sliced.border_edges) == "");
      CHECK(cap.added_points.empty());
      ++caps_checked;
    }
  }
  CHECK(caps_checked > 30);
}

TEST_CASE("the cap check refuses caps whose boundary is not exactly the border") {
  // A square 0-1-2-3, counter-clockwise: the region lies left of every border edge.
  const std::vector<Edge> border = {{0, 1}, {1, 2}, {2, 3}, {3, 0}};
  using Triangles = std::vector<Triangle>;
  CHECK(cap_boundary_is_border(Triangles{{0, 1, 2}, {0, 2, 3}}, border));
  CHECK(cap_boundary_is_border(Triangles{{1, 2, 3}, {1, 3, 0}}, border));
  // Regression: a triangle given twice used to pass, its edges counted once.
  CHECK_FALSE(cap_boundary_is_border(Triangles{{0, 1, 2}, {0, 1, 2}, {0, 2, 3}}, border));
  CHECK_FALSE(cap_boundary_is_border(Triangles{{0, 2, 1}, {0, 3, 2}}, border));  // reversed
  CHECK_FALSE(cap_boundary_is_border(Triangles{{0, 1, 2}}, border));             // half missing
  CHECK_FALSE(cap_boundary_is_border(Triangles{{0, 1, 2}, {0, 2, 3}, {0, 0, 1}}, border));  // degenerate
  CHECK_FALSE(cap_boundary_is_border(Triangles{{0, 1, 2}, {0, 2, 3}, {3, 2, 4}}, border));  // sticks out
}
