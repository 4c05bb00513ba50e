#pragma once
// Caps: the triangles that close a cut. Border edges are linked into loops by
// vertex index; the region they bound (polygons, holes, islands in holes, to any
// depth) is triangulated without ever adding a vertex on its boundary, so the cap's
// boundary is exactly the border edges and the cut is watertight by construction.
//
// Method, cheapest first, each result checked before it is accepted:
// 1. fan: one loop that is star-shaped from one of its vertices within a half-turn
//    (every fan triangle strictly counter-clockwise, tested exactly). Convex caps
//    at the leaves of a fracture take this path: no allocation beyond the output.
// 2. cdt: CGAL's constrained Delaunay triangulation of all border edges, with each
//    vertex's mesh index as info; nesting comes from the parity of constraints
//    crossed on the way from the infinite face (exact predicates throughout).
// 3. exact_cdt (rounded positions with an ExactPositionFn only): the same on the
//    exact positions the rounded crossings stand for, when rounding made loops
//    touch or cross in 2D.
// 4. steiner_fan: a last resort for inputs whose loops cross even exactly (a
//    self-intersecting mesh, allowed on request): one interior vertex per loop and a
//    fan to it. Closed and oriented, but the embedding may overlap itself.
// The checks: every border edge is used once, in its direction, and every other
// cap edge twice in opposite directions; no zero-area triangle in projection.
//
// Not installed (triangulate/internal/): caps are triangulated on CGAL Epeck points
// as well as on doubles, and their callers are the library's own sources (the
// exact triangulation of a piece's faces, solid_mesh.cpp) and the tests' oracle.

#include <functional>
#include <span>
#include <vector>

#include "shatter/kernel/exact.hpp"
#include "shatter/kernel/mesh.hpp"

namespace shatter {

enum class CapMethod { none, fan, cdt, exact_cdt, steiner_fan };

template <class Point>
struct Cap {
  /// Counter-clockwise seen from +n: the cap of the below half as given, of the
  /// above half reversed. Indices refer to the caller's positions, then to
  /// added_points (index positions.size() + i).
  std::vector<Triangle> triangles;
  /// Interior vertices added by steiner_fan; empty otherwise.
  std::vector<Point> added_points;
  std::size_t loop_count = 0;
  CapMethod method = CapMethod::none;
};

/// Gives the exact position of a vertex of the cut (the fall-back when rounding
/// made the loops touch or cross); may be empty (no fall-back).
using ExactPositionFn = std::function<ExactPoint(VertexIndex)>;

/// Triangulates the region bounded by `border` in `plane`.
/// Preconditions: border is a set of directed edges with the region on their left
/// seen from +n (SlicedMesh::border_edges), every in-degree equal to the out-degree,
/// and every vertex on the plane (exactly, or up to the rounding of its position).
/// Guarantees: the cap's boundary is exactly `border`; no vertex added on it.
/// Throws UnsupportedGeometryError only if even steiner_fan cannot close it.
/// `allow_fan` false skips method 1 (in both overloads): the constrained Delaunay
/// triangulation, whose triangles are as far from slivers as the loops allow
/// (used to retriangulate a face whose fan's slivers did not survive rounding).
Cap<Vec3> triangulate_cap(std::span<const Vec3> positions, std::span<const Edge> border,
                          const Plane& plane, const ExactPositionFn& exact_position, bool allow_fan = true);
Cap<ExactPoint> triangulate_cap(std::span<const ExactPoint> positions, std::span<const Edge> border,
                                const Plane& plane, bool allow_fan = true);

/// The check every cap passes before it is accepted: true when no edge of
/// `triangles` is degenerate or used twice in one direction, every border edge is
/// used in its own direction and not reversed, and every other edge is matched by
/// its reverse, so the triangles' boundary is exactly `border`. Linear time.
bool cap_boundary_is_border(std::span<const Triangle> triangles, std::span<const Edge> border);

/// Makes a cap triangulated over approximations of its points (a constrained
/// Delaunay triangulation of the rounded positions) one of the exact points, by
/// edge flips: each triangle that is not strictly counter-clockwise for the
/// exact points (a sliver whose middle corner rounding moved across its chord)
/// is flipped with a neighbour across one of its non-border edges, where both
/// new triangles are; each flip removes at least one such triangle and adds
/// none, so there are at most as many flips as such triangles. Then Lawson's
/// flips restore the Delaunay shape around the flipped triangles, at most eight
/// per flipped triangle, each also made only where both new triangles are.
/// `counter_clockwise(a, b, c)`: whether a, b, c (the caller's vertex indices)
/// turn strictly counter-clockwise seen from the cap's outward side, decided
/// exactly. `positions`, the rounded ones, only make choices of shape (the
/// sliver's longest edge tried first, the Delaunay test of Lawson's flips),
/// never validity. Preconditions: cap_boundary_is_border(triangles, border); a
/// position for every vertex index the triangles use.
/// Guarantees, on true: every triangle strictly counter-clockwise and
/// cap_boundary_is_border still holds, so the triangles cover the region the
/// border bounds once and meet only along edges (the argument at
/// certifies_for_exact_points, cap.cpp); true at once, unchanged, when every
/// triangle already is. On false (a sliver with no such flip) `triangles` is
/// left in an unspecified state: the caller triangulates the exact points.
bool flip_to_counter_clockwise(std::vector<Triangle>& triangles, std::span<const Edge> border,
                               std::span<const Vec3> positions,
                               const std::function<bool(VertexIndex, VertexIndex, VertexIndex)>& counter_clockwise);

/// The border edges linked into closed loops of vertex indices, in linear time.
/// Where several loops meet at a vertex, each visit takes the next unused edge.
std::vector<std::vector<VertexIndex>> link_loops(std::span<const Edge> border);

}  // namespace shatter
