// pair_around_non_manifold_edges and split_vertex_fans (non_manifold.hpp): parts
// of a closed surface that touch at a vertex or along an edge, taken apart by
// index, over random placements. Moving the copies apart is repair's
// (test_repair.cpp, "touching parts").

#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <vector>

#include "shatter/generators/random.hpp"
#include "shatter/generators/solids.hpp"
#include "shatter/kernel/non_manifold.hpp"
#include "shatter/kernel/solid.hpp"
#include "shatter/kernel/validate.hpp"

using namespace shatter;
using namespace shatter::test;

namespace {

// Vertices at exactly equal positions joined (what the readers do), the first
// of each position kept.
Mesh welded(Mesh mesh) {
  std::map<std::array<double, 3>, VertexIndex> first;
  std::vector<VertexIndex> number(mesh.positions.size());
  std::vector<Vec3> positions;
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    const Vec3 p = mesh.positions[v];
    const auto [it, fresh] = first.try_emplace({p.x, p.y, p.z}, static_cast<VertexIndex>(positions.size()));
    if (fresh) positions.push_back(p);
    number[v] = it->second;
  }
  for (Triangle& t : mesh.triangles) {
    for (VertexIndex& v : t) v = number[v];
  }
  mesh.positions = std::move(positions);
  return mesh;
}

Vec3 highest_corner(const Mesh& mesh) {
  Vec3 hi = mesh.positions[0];
  for (const Vec3& p : mesh.positions) hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  return hi;
}

// A rotation about a random axis (Rodrigues), applied to every position alike, so
// positions equal before stay equal after.
Mesh rotated(Mesh mesh, Random& random) {
  const Vec3 k = random.direction();
  const double angle = random.uniform(0, 6.283185307179586);
  const double c = std::cos(angle), s = std::sin(angle);
  for (Vec3& p : mesh.positions) p = p * c + cross(k, p) * s + k * (dot(k, p) * (1 - c));
  return mesh;
}

// The triangle's part: triangles [0, split) come from the first mesh merged.
int part_of(std::uint32_t triangle, std::size_t split) { return triangle < split ? 0 : 1; }

}  // namespace

TEST_CASE("two boxes sharing an edge: each triangle on the edge is paired within its own box", "[non_manifold]") {
  for (std::uint64_t seed = 0; seed < 100; ++seed) {
    INFO("seed " << seed);
    Random random(seed);
    const Mesh a = box({0, 0, 0}, {1 + random.uniform(), 1 + random.uniform(), 2});
    const Vec3 hi = highest_corner(a);
    const Mesh b = box({hi.x, hi.y, 0}, {hi.x + 1 + random.uniform(), hi.y + 1 + random.uniform(), 2});
    Mesh mesh = welded(rotated(merge({a, b}), random));
    REQUIRE(mesh.positions.size() == 14);
    const ValidationReport before = validate_mesh(mesh);
    REQUIRE(before.find(DefectKind::non_manifold_edge) != nullptr);

    const auto partner = pair_around_non_manifold_edges(mesh);
    REQUIRE(partner.has_value());
    std::size_t paired = 0;
    for (std::uint32_t slot = 0; slot < partner->size(); ++slot) {
      if ((*partner)[slot] == no_index) continue;
      ++paired;
      CHECK(part_of(slot / 3, a.triangles.size()) == part_of((*partner)[slot], a.triangles.size()));
    }
    CHECK(paired == 4);  // the shared edge's four triangles

    // Without the pairing the two boxes stay joined at the edge's ends; with it,
    // each end gets one vertex per box and the surface is a manifold.
    Mesh unpaired = mesh;
    CHECK(split_vertex_fans(unpaired).empty());
    const std::vector<VertexFan> fans = split_vertex_fans(mesh, *partner);
    REQUIRE(fans.size() == 4);
    CHECK(mesh.positions.size() == 16);
    CHECK(is_closed_oriented_manifold(mesh));
    for (const VertexFan& fan : fans) {
      CHECK(mesh.positions[fan.vertex] == mesh.positions[fan.split_from]);
      for (const std::uint32_t corner : fan.corners) CHECK(mesh.triangles[corner / 3][corner % 3] == fan.vertex);
    }
  }
}

TEST_CASE("tetrahedra sharing a vertex are split into one vertex per tetrahedron", "[non_manifold]") {
  for (std::uint64_t seed = 0; seed < 100; ++seed) {
    INFO("seed " << seed);
    Random random(seed);
    // k tetrahedra around a shared apex, each on its own side of a plane through
    // it, so they meet only there.
    const Vec3 apex{random.uniform(-1, 1), random.uniform(-1, 1), random.uniform(-1, 1)};
    const std::size_t k = 2 + random.index(3);
    std::vector<Mesh> parts;
    for (std::size_t i = 0; i < k; ++i) {
      const double angle = 6.283185307179586 * double(i) / double(k);
      const Vec3 out{std::cos(angle), std::sin(angle), 0};
      const Vec3 side{-std::sin(angle), std::cos(angle), 0};
      const double spread = 0.4 * std::sin(3.141592653589793 / double(k));
      Vec3 p = apex + out + side * spread, q = apex + out - side * spread, r = apex + out + Vec3{0, 0, 0.5};
      Mesh tet = mesh_from({apex, p, q, r}, {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}});
      if (validate_mesh(tet).find(DefectKind::inward_orientation)) tet = flipped(tet);
      REQUIRE(validate_mesh(tet).valid());
      parts.push_back(tet);
    }
    Mesh mesh = welded(merge(parts));
    REQUIRE(mesh.positions.size() == 3 * k + 1);
    REQUIRE(validate_mesh(mesh).find(DefectKind::non_manifold_vertex) != nullptr);
    const auto partner = pair_around_non_manifold_edges(mesh);
    REQUIRE(partner.has_value());
    CHECK(std::all_of(partner->begin(), partner->end(), [](std::uint32_t p) { return p == no_index; }));
    const std::vector<VertexFan> fans = split_vertex_fans(mesh, *partner);
    REQUIRE(fans.size() == k);
    CHECK(fans[0].vertex == fans[0].split_from);
    std::set<VertexIndex> copies;
    for (const VertexFan& fan : fans) {
      CHECK(fan.corners.size() == 3);
      copies.insert(fan.vertex);
    }
    CHECK(copies.size() == k);
    CHECK(is_closed_oriented_manifold(mesh));
  }
}

TEST_CASE("an edge whose triangles share an angle around it cannot be paired", "[non_manifold]") {
  // Two tetrahedra on the edge (0,0,0)-(0,0,1), each with a face in the half-plane
  // y = 0, x > 0: their third corners there have one angle about the edge.
  const Mesh a = mesh_from({{0, 0, 0}, {0, 0, 1}, {1, 0, 0.5}, {0, 1, 0.5}}, {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}});
  const Mesh b = mesh_from({{0, 0, 0}, {0, 0, 1}, {2, 0, 0.5}, {0, -1, 0.5}}, {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}});
  const Mesh mesh = welded(merge({validate_mesh(a).valid() ? a : flipped(a), validate_mesh(b).valid() ? b : flipped(b)}));
  REQUIRE(validate_mesh(mesh).find(DefectKind::non_manifold_edge) != nullptr);
  CHECK_FALSE(pair_around_non_manifold_edges(mesh).has_value());
}

TEST_CASE("a manifold surface has nothing to pair or split", "[non_manifold]") {
  for (NamedMesh& named : generated_meshes()) {
    INFO(named.name);
    Mesh mesh = named.mesh;
    const auto partner = pair_around_non_manifold_edges(mesh);
    REQUIRE(partner.has_value());
    CHECK(std::all_of(partner->begin(), partner->end(), [](std::uint32_t p) { return p == no_index; }));
    CHECK(split_vertex_fans(mesh, *partner).empty());
    CHECK(mesh.positions.size() == named.mesh.positions.size());
  }
}
