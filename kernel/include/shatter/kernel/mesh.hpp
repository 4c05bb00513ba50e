#pragma once
// The mesh every layer works on: welded positions, triangles over vertex indices,
// attributes per corner, and a surface id per triangle (DESIGN.md, "Data model").

#include <array>
#include <cstdint>
#include <vector>

#include "shatter/kernel/vec.hpp"

namespace shatter {

/// Index of a topological vertex (a welded position).
using VertexIndex = std::uint32_t;
/// Index of a triangle.
using TriangleIndex = std::uint32_t;
/// Three vertex indices, counter-clockwise seen from outside the solid.
using Triangle = std::array<VertexIndex, 3>;
/// A directed edge from vertex [0] to vertex [1].
using Edge = std::array<VertexIndex, 2>;

/// Which surface a triangle belongs to: the input's own surface, or the cap of
/// cut k (k >= 1). Renderers give caps an interior material; bonds find touching
/// fragments by it.
using SurfaceId = std::uint32_t;
inline constexpr SurfaceId original_surface = 0;

/// Attributes stored per corner ("wedge"), so that a UV or normal seam never opens
/// the surface. Each channel is either empty (absent) or holds 3 values per
/// triangle, corner c of triangle t at index 3*t + c.
struct CornerAttributes {
  std::vector<Vec3> normals;   ///< unit normals
  std::vector<Vec2> uvs;       ///< texture coordinates
  std::vector<Vec4> tangents;  ///< unit tangent, handedness in w

  bool has_normals() const { return !normals.empty(); }
  bool has_uvs() const { return !uvs.empty(); }
  bool has_tangents() const { return !tangents.empty(); }
};

/// A triangle mesh over points of type Point: Vec3 as stored and written, an
/// exact point where caps are triangulated exactly (the library's own kernel/internal exact.hpp). Invariants after reading and after every shatter
/// operation: `surfaces` has one entry per triangle; every present attribute
/// channel has 3 entries per triangle; every index is < positions.size().
template <class Point>
struct BasicMesh {
  std::vector<Point> positions;
  std::vector<Triangle> triangles;
  std::vector<SurfaceId> surfaces;
  CornerAttributes corners;

  std::size_t vertex_count() const { return positions.size(); }
  std::size_t triangle_count() const { return triangles.size(); }
};

/// The mesh of every node, piece and file: double coordinates.
using Mesh = BasicMesh<Vec3>;

}  // namespace shatter
