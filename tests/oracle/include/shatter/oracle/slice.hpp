#pragma once
// One plane cut of one closed mesh into two open halves that share their new
// vertices, plus the border edges the caps must close. Part of the test oracle
// (oracle/cut.hpp says why it is there).
//
// Degeneracy policy (every case decided by the exact sign of n·p + d):
// - A vertex on the plane is reused by both halves, never duplicated or moved.
// - A triangle with vertices strictly on both sides is split; each crossing edge
//   gets exactly one new vertex, keyed by its two vertex indices, which both
//   triangles of the edge and both halves use.
// - A triangle not split goes to the side of its off-plane vertices; vertices on
//   the plane do not vote.
// - A triangle lying in the plane goes below when it faces +n (counter-clockwise
//   seen from +n), above otherwise: it is the lid of the solid on that side. This
//   is the one rule for faces in the plane, and edges along the plane follow from
//   it: such an edge is a border edge exactly when its two triangles went to
//   different sides.
// No new triangle has zero area when constructions are exact: a split triangle's
// pieces each have a vertex strictly off the plane and two on distinct points.

#include <array>
#include <vector>

#include "shatter/kernel/exact.hpp"
#include "shatter/kernel/mesh.hpp"

namespace shatter::oracle {

/// The triangles of one side, over the shared vertex array of a SlicedMesh.
struct OpenHalf {
  std::vector<Triangle> triangles;
  std::vector<SurfaceId> surfaces;
  CornerAttributes corners;  ///< same channels as the input
};

template <class Point>
struct SlicedMesh {
  /// The input's vertices, then one new vertex per crossing edge.
  std::vector<Point> positions;
  /// The input edge each new vertex lies on (as sorted vertex indices): new vertex
  /// input_vertex_count + i lies on crossing_edges[i]. Lets the fast kernel
  /// rebuild any new vertex's exact position.
  std::vector<Edge> crossing_edges;
  std::size_t input_vertex_count = 0;
  OpenHalf below;  ///< n·p + d < 0 side
  OpenHalf above;  ///< n·p + d > 0 side
  /// The boundary of the above half, each edge directed as an above triangle
  /// traverses it. Seen from +n the cut region lies to the left of every edge, so a
  /// cap whose triangles run counter-clockwise seen from +n has exactly these edges
  /// as its boundary; the below half's boundary is the same edges reversed.
  std::vector<Edge> border_edges;

  /// True when the plane leaves one side empty (it misses or only touches).
  bool plane_misses() const { return below.triangles.empty() || above.triangles.empty(); }
};

/// The exact position vertex v of a fast-kernel slice stands for: an input vertex
/// as it is, a new vertex as the exact crossing of its input edge (which the
/// rounded position only approximates). Precondition: v < sliced.positions.size().
ExactPoint exact_position(const SlicedMesh<Vec3>& sliced, const Plane& plane, VertexIndex v);

/// Splits a closed mesh by `plane` (n·x + d = 0).
/// Preconditions: mesh is closed, 2-manifold and consistently oriented (as
/// validate_mesh checks), plane.normal is not zero, every coordinate finite.
/// Guarantees: the degeneracy policy above; below ∪ above uses every input
/// triangle exactly once (split or whole); border_edges is the exact boundary of
/// the above half. Deterministic: the same input gives the same output.
/// Complexity: O(V + T), one hash probe per crossing edge per triangle.
SlicedMesh<Vec3> slice_mesh(const Mesh& mesh, const Plane& plane);
SlicedMesh<ExactPoint> slice_mesh(const ExactMesh& mesh, const Plane& plane);

}  // namespace shatter::oracle
