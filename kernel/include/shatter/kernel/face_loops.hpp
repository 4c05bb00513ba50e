#pragma once
// Directed edges on one plane, bounding a region on their left (seen from the
// region's outward side), linked into loops and grouped into connected regions:
// an outer loop and the holes inside it. Used for the parts of a face split by a
// cut and for caps. Every decision is an exact predicate on defined points.

#include <span>
#include <vector>

#include "shatter/kernel/solid.hpp"

namespace shatter {

/// One connected region: loops[0] its outer loop (counter-clockwise seen from the
/// outward side), then its holes (clockwise); each loop's edges chain head to tail.
struct Region {
  std::vector<std::vector<LoopEdge>> loops;
};

/// The plane the edges lie on and the points they run between.
struct FaceGeometry {
  const PlaneSet& set;
  std::span<const PointDef> defs;
  std::span<const ApproxPoint> approx;
  Projection projection;  ///< projection_of the plane
  bool reversed = false;  ///< the outward side is the plane's back (-n)

  /// Orientation of (p, q, r) seen from the outward side.
  Sign orient(VertexIndex p, VertexIndex q, VertexIndex r) const;
};

/// Whether ray v -> b comes before ray v -> c going clockwise (seen from the
/// outward side) from ray v -> a. Exact. Precondition: neither b nor c lies on
/// ray v -> a, and b and c not on one ray from v (edges at a vertex of an
/// embedded face never overlap). Where loops of a face meet at v, an incoming
/// edge a -> v is continued by the outgoing edge v -> b first clockwise from
/// v -> a: the two bound one corner of the face's region.
bool clockwise_before(const FaceGeometry& g, VertexIndex v, VertexIndex a, VertexIndex b, VertexIndex c);

/// Links `edges` into simple loops (no vertex twice) and groups them into regions.
/// Preconditions: every vertex has as many incoming as outgoing edges; the edges
/// bound a region on their left whose boundary pieces meet only at shared
/// vertices (an embedded face). Where loops touch at a vertex, an incoming edge is
/// continued by the outgoing edge first clockwise from it, so each loop traces one
/// corner of the region. Guarantees: every edge in exactly one loop; regions in
/// the order of their outer loops' first edges. `edges` is reordered.
/// Throws UnsupportedGeometryError when a hole lies in no outer loop, or a loop
/// has no vertex off the others to test it by (not made by cuts of a valid solid).
void group_into_regions(const FaceGeometry& geometry, std::vector<LoopEdge>& edges, std::vector<Region>& regions);

/// True when the loop turns left or goes straight at every corner (seen from the
/// outward side): a convex polygon. Exact.
bool is_convex_loop(const FaceGeometry& geometry, std::span<const LoopEdge> loop);

/// Where point `v` lies against the loop, by an exact ray cast in the
/// projection: positive strictly inside, negative strictly outside, zero on it
/// (on an edge, or at the place of a corner: copies of a vertex lie at one
/// point where a piece meets itself along a chord, cut_solid). Precondition: v
/// is on the plane.
Sign locate_in_loop(const FaceGeometry& geometry, VertexIndex v, std::span<const LoopEdge> loop);

/// Whether point `v` lies strictly inside the loop, by an exact ray cast in the
/// projection. Precondition: v is on the plane and not on the loop.
bool inside_loop(const FaceGeometry& geometry, VertexIndex v, std::span<const LoopEdge> loop);

}  // namespace shatter
