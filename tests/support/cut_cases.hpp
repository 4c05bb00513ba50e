#pragma once
// What the one-cut tests sweep: the corpus's valid meshes, and planes of every
// kind for one mesh (tests/slicer, tests/triangulate). Header-only, like the
// tests that use it.

#include <cstdint>
#include <vector>

#include "shatter/kernel/io.hpp"
#include "support/checks.hpp"
#include "shatter/generators/corpus.hpp"
#include "support/degenerate.hpp"
#include "shatter/generators/random.hpp"
#include "shatter/generators/solids.hpp"

namespace shatter::test {

/// Every valid corpus mesh, read, with its file name; never empty.
inline std::vector<NamedMesh> corpus_meshes() {
  std::vector<NamedMesh> meshes;
  for (const auto& path : valid_meshes()) meshes.push_back({path.filename().string(), read_mesh(path)});
  return meshes;
}

// A plane, and whether it may pass within rounding distance of a vertex without
// containing it exactly: there the fast kernel's rounded crossings may collapse
// onto the vertex, so only its topology is guaranteed.
struct TestPlane {
  Plane plane;
  bool grazes_vertex = false;
};

// Planes of every kind for one mesh: random ones through the bounding box, axis
// planes exactly through a vertex (often along edges and faces too), and one
// through a vertex with a random normal (rounded, so it grazes the vertex).
inline std::vector<TestPlane> planes_for(const Mesh& mesh, std::uint64_t seed, int random_count) {
  Random random(seed);
  const Box3 b = bounds(mesh);
  std::vector<TestPlane> planes;
  for (int i = 0; i < random_count; ++i) {
    const Vec3 p{random.uniform(b.lo.x, b.hi.x), random.uniform(b.lo.y, b.hi.y), random.uniform(b.lo.z, b.hi.z)};
    planes.push_back({plane_through(p, random.direction())});
  }
  for (int axis = 0; axis < 3; ++axis) {
    const Vec3 v = mesh.positions[random.index(mesh.positions.size())];
    Vec3 normal{};
    (axis == 0 ? normal.x : axis == 1 ? normal.y : normal.z) = axis == 1 ? -1.0 : 1.0;
    // Exactly through v; other vertices may lie within an ulp of it (coordinates
    // computed by sin and cos), so it may graze them.
    planes.push_back({{normal, -(v[axis] * (axis == 1 ? -1.0 : 1.0))}, true});
  }
  planes.push_back({plane_through(mesh.positions[random.index(mesh.positions.size())], random.direction()), true});
  return planes;
}

}  // namespace shatter::test
