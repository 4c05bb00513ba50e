#pragma once
// Where a closed surface touches itself: an edge with more than two triangles
// (two parts meeting along it) and a vertex where several edge-connected fans of
// triangles meet (parts meeting at a point). Both are taken apart by index here,
// the edge's triangles paired by the exact angular order around it; moving the
// copies apart is the caller's (repair: repair.hpp; a rounded piece that touches
// itself: triangulate/src/rounding_separation.cpp).

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "shatter/kernel/mesh.hpp"

namespace shatter {

/// For every directed edge slot of a triangle on an edge with more than two
/// triangles (slot c of triangle t runs from corner c to corner c + 1; index
/// 3 t + c), the triangle it is paired with across the edge; no_index
/// (shatter/kernel/solid.hpp) on every other slot. Around the edge u -> v, a
/// triangle running it v -> u has the solid ahead of it in the right-hand turn
/// about v - u and one running it u -> v has the solid behind it, so each v -> u
/// triangle is paired with the next triangle in that turn, which must run u -> v:
/// each pair bounds one wedge of the solid. This is how exact boolean operations
/// on non-manifold input untangle an edge (CGAL's corefinement orders the faces
/// around an edge with sorted_around_edge and pairs each face with the next one
/// across the volume: Loriot, Tournois & Jamin, "Polygon Mesh Processing", CGAL
/// 5.5 manual, "Corefinement and Boolean Operations"; Granados et al. 2003,
/// "Boolean operations on 3D selective Nef complexes", for the radial order).
/// Exact: order_around_line (predicates.hpp) on the positions.
/// Preconditions: indices in range, finite coordinates, no triangle repeating an
/// index. Returns nullopt when an edge has an odd count of triangles, two third
/// corners share an angle about the edge (or one lies on its line), or the
/// directions do not alternate around it: then the edge cannot be untangled by
/// pairing. Every slot no_index when no edge has more than two triangles.
/// Cost: O(T log T). Failure: none.
std::optional<std::vector<std::uint32_t>> pair_around_non_manifold_edges(const Mesh& mesh);

/// The triangle corners (3 t + c) at one vertex that form one edge-connected fan.
struct VertexFan {
  VertexIndex vertex;                  ///< the vertex the fan's corners now use
  VertexIndex split_from;              ///< the vertex it was split from (== vertex for the first fan)
  std::vector<std::uint32_t> corners;  ///< in triangle order
};

/// Splits every vertex where several edge-connected fans of triangles meet into
/// one vertex per fan: the fan holding the vertex's first corner (in triangle
/// order) keeps it, each other fan gets a new vertex at the same position,
/// appended to `mesh.positions` in vertex order. Around a vertex v, the corner
/// leaving v along v -> w and the corner entering v along w -> v are neighbours
/// in a fan, except across an edge paired in `partner`
/// (pair_around_non_manifold_edges), where a corner's neighbour is its paired
/// triangle's only: the edge's vertices then fall into one fan per pair where
/// nothing else joins them. Returns the fans of every vertex split, grouped by
/// vertex in vertex order, its first fan first; empty when no vertex has two fans.
/// Triangles, surfaces and corner attributes keep their order; only vertex
/// indices of the moved corners change, so the copies are touching (at one
/// position): a caller that wants an embedded surface moves them apart.
/// Preconditions: indices in range; every edge used as often each way (a closed,
/// consistently oriented surface; elsewhere a fan ends at a border and corners
/// are joined only where an edge enters and leaves); `partner` empty or as
/// pair_around_non_manifold_edges returns it for this mesh.
/// Cost: O(sum over vertices of the square of their corner count). Failure: none.
std::vector<VertexFan> split_vertex_fans(Mesh& mesh, std::span<const std::uint32_t> partner = {});

}  // namespace shatter
