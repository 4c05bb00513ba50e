#pragma once
// The plane kernel's solid: a closed polyhedral surface whose faces are polygons on
// planes of a fixed set and whose vertices are defined points (implicit.hpp).
//
// A face is one connected region of its supporting plane: an outer loop and any
// number of holes, each loop a cycle of corners over vertex indices, counter-
// clockwise seen from outside the solid (the face's outward side). The edge from a
// corner to the next corner of its loop lies on the face's plane and on a second,
// known line: the input segment it came from, or the face's plane met by the plane
// of the face across the edge. A new vertex where a cut crosses the edge is then
// defined from that line and the cut, never from the edge's endpoints, which is
// what keeps every predicate's degree bounded at any depth.
//
// Faces stay polygons between cuts; they are triangulated only for output
// (rounded meshes, mass properties). Topology is carried by index: every
// undirected edge is used by exactly two corners, in opposite directions.

#include <array>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "shatter/kernel/half_edges.hpp"
#include "shatter/kernel/implicit.hpp"
#include "shatter/kernel/mesh.hpp"

namespace shatter {

inline constexpr std::uint32_t no_index = std::numeric_limits<std::uint32_t>::max();

/// The line an edge lies on, besides its face's plane.
struct EdgeLine {
  /// The plane of the face across the edge; PlaneRef{no_index} when that face is
  /// coplanar with this one (then the edge is an input segment).
  PlaneRef other{no_index};
  /// The input points p < q of the input edge the edge lies on, or no_index.
  std::uint32_t p = no_index, q = no_index;

  bool is_segment() const { return p != no_index; }
  friend bool operator==(const EdgeLine&, const EdgeLine&) = default;
};

struct SolidCorner {
  VertexIndex vertex = 0;
  EdgeLine line;  ///< of the edge from this corner to the next corner of its loop
};

struct SolidLoop {
  std::uint32_t first_corner = 0, corner_count = 0;
};

struct SolidFace {
  PlaneRef plane;         ///< supporting plane
  bool reversed = false;  ///< outward normal is -n of the plane
  /// One loop, and no right turn (decided exactly): a convex polygon, possibly
  /// with collinear corners.
  bool convex = false;
  SurfaceId surface = original_surface;  ///< 0 for the input's surface, else the cap id
  /// The input triangle this face lies in (its attributes are interpolated from
  /// it), for surface 0; unused for caps.
  std::uint32_t source = 0;
  std::uint32_t first_loop = 0, loop_count = 0;
};

/// A closed plane-based solid (one outer shell and its cavities, or, before
/// separation, any closed set of faces).
struct Solid {
  std::vector<PointDef> defs;       ///< per vertex
  std::vector<ApproxPoint> approx;  ///< per vertex, approximate(defs[v])
  std::vector<SolidFace> faces;
  std::vector<SolidLoop> loops;
  std::vector<SolidCorner> corners;
  /// Decided exactly: every edge convex or flat and one shell. A cut of a convex
  /// solid gives one convex solid per side.
  bool convex = false;

  std::size_t vertex_count() const { return defs.size(); }
};

/// A directed edge between two vertices, with its line (as SolidCorner::line).
struct LoopEdge {
  VertexIndex from = 0, to = 0;
  EdgeLine line;
};

/// One edge of a face loop, as loop_edges gives it: from the vertex of corner
/// `corner` (an index into the corner array) to the next corner's vertex, on the
/// starting corner's line. The last corner's edge closes the loop.
struct CornerEdge {
  std::uint32_t corner = 0;
  VertexIndex from = 0, to = 0;
  EdgeLine line;
};

/// The edges of one loop in order, the one way every loop is walked:
/// `for (const CornerEdge& edge : loop_edges(solid.corners, loop))`. A walk may
/// start at any corner of the loop (loop_edges(corners, loop, start)); it then
/// wraps past the loop's last corner to its first and ends with the edge into
/// `start`. fan_edges walks the edges of a fan from one corner.
class LoopEdges {
 public:
  class Iterator {
   public:
    Iterator(const LoopEdges& loop, std::uint32_t corner, std::uint32_t left)
        : loop_(&loop), corner_(corner), left_(left) {}
    CornerEdge operator*() const {
      const SolidCorner& start = loop_->corners_[corner_];
      return {corner_, start.vertex, loop_->corners_[loop_->next(corner_)].vertex, start.line};
    }
    Iterator& operator++() {
      corner_ = loop_->next(corner_);
      --left_;
      return *this;
    }
    /// Iterators of one walk are equal when as many edges are left to walk.
    bool operator==(const Iterator& other) const { return left_ == other.left_; }

   private:
    const LoopEdges* loop_;
    std::uint32_t corner_;
    std::uint32_t left_;  ///< edges not yet walked, this one included
  };

  /// `edges` edges of `loop` from corner `start`. Preconditions: as the functions below.
  LoopEdges(std::span<const SolidCorner> corners, const SolidLoop& loop, std::uint32_t start, std::uint32_t edges)
      : corners_(corners), first_(loop.first_corner), end_(loop.first_corner + loop.corner_count), start_(start),
        edges_(edges) {}
  Iterator begin() const { return {*this, start_, edges_}; }
  Iterator end() const { return {*this, start_, 0}; }
  /// The corner after `corner` in the loop (the first after the last).
  std::uint32_t next(std::uint32_t corner) const { return corner + 1 == end_ ? first_ : corner + 1; }

 private:
  std::span<const SolidCorner> corners_;
  std::uint32_t first_, end_, start_, edges_;
};

/// The edges of `loop`, whose corners are corners[loop.first_corner] onwards,
/// from the loop's first corner.
/// Precondition: loop.first_corner + loop.corner_count <= corners.size()
/// (check_solid checks it; code reading unchecked loops checks it first).
/// Never throws; O(1), the walk O(corners of the loop).
inline LoopEdges loop_edges(std::span<const SolidCorner> corners, const SolidLoop& loop) {
  return {corners, loop, loop.first_corner, loop.corner_count};
}

/// The edges of `loop` from corner `start` (an index into `corners`, as
/// CornerEdge::corner): start's edge first, the edge into start last, each edge
/// once. For a walk whose output must begin at a chosen corner (a face part that
/// starts on one side of a cut).
/// Preconditions: as loop_edges(corners, loop), and loop.first_corner <= start <
/// loop.first_corner + loop.corner_count. Never throws; O(1), the walk
/// O(corners of the loop).
inline LoopEdges loop_edges(std::span<const SolidCorner> corners, const SolidLoop& loop, std::uint32_t start) {
  return {corners, loop, start, loop.corner_count};
}

/// The edges of `loop` that do not touch corner `apex`, in order from the corner
/// after it: the fan from apex is the triangles (apex's vertex, edge.from,
/// edge.to), loop.corner_count - 2 of them (none for a loop of fewer than 3
/// corners). A triangulation of the loop when it is convex and no triangle is
/// flat.
/// Preconditions: as loop_edges(corners, loop, apex). Never throws; O(1), the
/// walk O(corners of the loop).
inline LoopEdges fan_edges(std::span<const SolidCorner> corners, const SolidLoop& loop, std::uint32_t apex) {
  const LoopEdges whole = loop_edges(corners, loop, apex);
  return {corners, loop, whole.next(apex), loop.corner_count < 2 ? 0 : loop.corner_count - 2};
}

/// Faces over a vertex numbering kept elsewhere (a side of a split, a cap).
struct FaceSet {
  std::vector<SolidFace> faces;  ///< their loops index `loops`
  std::vector<SolidLoop> loops;  ///< their corners index `corners`
  std::vector<SolidCorner> corners;

  void clear() {
    faces.clear();
    loops.clear();
    corners.clear();
  }
};

/// The input planes and input points a build's solids are defined over: one plane
/// per input face (a maximal edge-connected set of coplanar input triangles when
/// merged, else one triangle), held as three of its points.
struct InputGeometry {
  std::vector<Vec3> points;
  std::vector<std::array<VertexIndex, 3>> planes;
  std::vector<ApproxPlane> plane_approx;

  /// A PlaneSet over these inputs and the given cut planes.
  PlaneSet plane_set(std::span<const Plane> cuts) const { return {points, planes, plane_approx, cuts}; }
};

/// Converts a closed, oriented, 2-manifold triangle mesh with positive volume
/// (validate_mesh) into a plane-based solid over `geometry`, whose points must be
/// `mesh.positions` (the caller sets them; input planes are appended).
/// With `merge_coplanar`, edge-connected input triangles on one plane (decided
/// exactly) and of one surface id become one polygon face, with the vertices inside such a face dropped;
/// without it (a mesh with attributes, which are interpolated per input
/// triangle), every triangle is its own face. A face's `source` is one of its
/// triangles, its surface id theirs. Decides convexity exactly. Throws InvalidMeshError if the mesh is
/// not closed and oriented.
/// `twins`: the mesh's half-edge twins (half_edge_twins) when the caller has them
/// already; computed here otherwise. The result does not depend on which.
Solid solid_from_mesh(const Mesh& mesh, bool merge_coplanar, InputGeometry& geometry,
                      const HalfEdgeTwins* twins = nullptr);

/// Whether the solid is convex, decided exactly: its faces form one edge-connected
/// shell and at every edge some vertex of the face across lies strictly inside the
/// face's plane, or all of them on it (a flat edge). Precondition: closed (every
/// directed edge matched by its reverse). O(sum over edges of the face sizes).
bool solid_is_convex(const PlaneSet& set, const Solid& solid);

/// The point where `plane` meets the line of an edge of `face` (`line`, the
/// edge's EdgeLine): the meet of the input segment and the plane when the edge
/// lies on one, else of the face's plane, the plane across the edge and `plane`,
/// the first two ordered by their bits so that the one edge, seen from either of
/// its faces, gets one definition (and one set of predicate results). Defined
/// from the edge's line, never its endpoints, which keeps every predicate's degree
/// bounded however deep the cuts go. How a cut (split_solid) and a refinement
/// (round_solid's wedge split) make each crossing vertex.
/// Precondition: the edge crosses `plane` (its endpoints strictly on either
/// side), so the point is defined. Never throws; O(1), constructs nothing exact.
PointDef edge_crossing_def(const SolidFace& face, const EdgeLine& line, PlaneRef plane);

/// The outward side of a face's plane at a point: side() of the plane, negated when
/// the face is reversed, so negative means inside the face's half-space.
Sign outward_side(const PlaneSet& set, const SolidFace& face, const PointDef& point, const ApproxPoint& approx);

/// Whether two faces' outward normals point the same way: the exact sign of
/// their dot product (compare_normals of their planes, negated when exactly one
/// face is reversed). Positive: they face one way; negative: opposite ways, as
/// the two faces of a wedge of the solid do; zero: perpendicular.
/// Preconditions: both planes in `set`. Guarantees: exact. Failure: none.
Sign compare_outward_normals(const PlaneSet& set, const SolidFace& a, const SolidFace& b);

/// The outward side of `face`'s plane at the first vertex of `across` off it,
/// its loops and corners walked in order (`loops` and `corners` are the ones
/// `across` indexes; `defs` and `approx` its vertices'): zero when every vertex
/// of `across` lies on the plane. At an edge the two faces share, positive means
/// the edge is reflex, which is how convexity is decided (solid_is_convex, and
/// the cut's pieces as it finds them). Preconditions: indices in range. Never
/// throws; O(corners of `across`), exact.
Sign outward_side_of_face(const PlaneSet& set, const SolidFace& face, const SolidFace& across,
                          std::span<const SolidLoop> loops, std::span<const SolidCorner> corners,
                          std::span<const PointDef> defs, std::span<const ApproxPoint> approx);

/// Checks a solid's structure: every corner's vertex in range, every loop of at
/// least 3 corners, every undirected edge used by exactly two corners in opposite
/// directions, every vertex used, and every corner's vertex lying on its face's
/// plane and on its edge's line (exact predicates). Returns an empty string when
/// sound, else the first defect in words. For tests and debug checks; O(corners).
std::string check_solid(const PlaneSet& set, const Solid& solid);

}  // namespace shatter
