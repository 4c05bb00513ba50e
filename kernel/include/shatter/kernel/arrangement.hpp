#pragma once
// The exact arrangement of a triangle mesh whose triangles may intersect: every
// triangle that meets another one split along their intersection, so that the
// pieces tile the input triangles exactly and no two pieces cross. The first
// stage of resolving self-intersections as mesh arrangements do (Zhou,
// Grinspun, Zorin & Jacobson 2016, "Mesh arrangements for solid geometry":
// intersect, subdivide each triangle by a constrained triangulation in its own
// plane, later label cells by winding number; Cherchi, Livesu, Scateni & Attene
// 2020, "Fast and robust mesh arrangements using floating-point arithmetic":
// the new points kept implicit, as meets of the input planes, and every decision
// an exact predicate on them). Winding numbers and the solid they select are not
// here yet (README, "Repair").
//
// Every vertex is a plane-based point (implicit.hpp) over the input points and
// one input plane per triangle (input plane t is triangle t's plane): an input
// vertex; an edge of one triangle met by another's plane (segment_plane); or the
// meet of three triangles' planes, where two intersection segments cross inside
// a third triangle (three_planes). Where two triangles overlap on one plane and
// their edges cross, the crossing is an edge met by a plane across theirs
// through the other edge (an input plane past the triangles' own, through the
// edge's ends and a point added off the plane). No coordinate is constructed to decide
// anything: where two segments meet and how each triangle's pieces are laid out
// are decided by exact orientation and order predicates on these points; the
// triangulation of a split triangle is a constrained Delaunay triangulation of
// its points' exact rational coordinates in its projection.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "shatter/kernel/implicit.hpp"
#include "shatter/kernel/mesh.hpp"
#include "shatter/kernel/self_intersections.hpp"
#include "shatter/kernel/solid.hpp"

namespace shatter {

/// The arrangement of a triangle soup: triangles over plane-based vertices.
struct MeshArrangement {
  /// points: the input positions, then the points off the plane that carry
  /// edge planes; input plane t < triangles.size(): the plane of input triangle
  /// t through its corners (so its front is the side the triangle faces), then
  /// the edge planes (see the file comment), none unless coplanar edges cross.
  InputGeometry geometry;
  /// Per vertex. Vertex v < positions.size() is input vertex v
  /// (PointDef::input(v)); new points follow, each once (no two vertices are
  /// the same point, exactly, but for input positions the caller repeated).
  std::vector<PointDef> defs;
  std::vector<ApproxPoint> approx;  ///< per vertex, approximate(defs[v])
  /// The pieces, over vertex indices, each in its source triangle's plane and
  /// turning as that triangle does. Grouped by source in input order: a triangle
  /// that meets no other (or only on its own plane) is copied as it is.
  std::vector<Triangle> triangles;
  std::vector<std::uint32_t> source;  ///< per piece: the input triangle it lies in
  /// The intersecting pairs (self_intersecting_pairs), and of those the pairs on
  /// one plane (resolved as the others are: see arrange_triangles).
  std::vector<TrianglePair> pairs, coplanar_pairs;
  std::size_t split_triangles = 0;  ///< input triangles split into more than one piece

  /// The plane set the vertices are defined over (a view of `geometry`).
  PlaneSet plane_set() const { return geometry.plane_set({}); }
};

/// The exact arrangement of `triangles` (see the file comment). For every pair
/// the exact grid finder reports (self_intersecting_pairs) whose triangles are
/// not on one plane, their intersection, a segment or a point on the line where
/// their planes meet, is computed as plane-based points (ordered along that line
/// exactly); in each triangle, the segments of its pairs are cut where they cross
/// one another (three_planes points) and wherever a vertex lies on them, and the
/// triangle is triangulated with those pieces as constraints. Triangles that
/// overlap on one plane (and those overlapping them, transitively) are
/// triangulated together, each with the others' edges and traces as
/// constraints too, and each keeps the faces inside it.
/// Guarantees: the pieces of each input triangle tile it exactly (their union
/// is the triangle, their interiors are disjoint, none is flat); any two pieces
/// meet, if at all, in a vertex or an edge they share by index (no crossing, no
/// vertex inside another piece's edge), or, for pieces of two triangles that
/// overlap on one plane, are the same three vertices (either way round: a
/// face of the arrangement that several input triangles cover); so the pieces
/// are a triangle soup over the same surface that intersects itself only in
/// such repeated faces.
/// A mesh whose triangles do not intersect comes back as it is: the same
/// triangles, no new vertex. Deterministic: a function of the input alone.
/// Preconditions: indices in range, finite coordinates, no triangle with
/// collinear corners (as self_intersecting_pairs). Failure: none beyond
/// std::bad_alloc. Cost: the pair search, plus per split triangle (or group of
/// triangles on one plane) with k segments O(k^2) exact predicates to find
/// crossings, O(k * vertices) to cut the segments, a rational constrained
/// triangulation of its vertices, and for a group of m triangles O(m *
/// vertices) exact orientations to give each its faces.
MeshArrangement arrange_triangles(std::span<const Vec3> positions, std::span<const Triangle> triangles);

/// The points `around` ordered by their angle about the oriented line from p to
/// q, counter-clockwise seen from q looking at p (the right-hand turn about
/// q - p), starting with around[0]: indices into `around`. order_around_line for
/// plane-based points, decided on their exact rational coordinates, as the order
/// of an arrangement's pieces around an edge they share is (the cells between
/// consecutive pieces are where winding numbers propagate; Zhou et al. 2016,
/// section 4). Returns nullopt when two points lie in one half-plane bounded by
/// the line (equal angles: no strict order) or one lies on the line.
/// Preconditions: sound definitions over `set`, p and q different points.
/// Cost: the exact coordinates of the k + 2 points, then O(k log k) rational
/// determinants. Failure: none beyond std::bad_alloc.
std::optional<std::vector<std::size_t>> order_around_edge(const PlaneSet& set, const PointDef& p, const PointDef& q,
                                                          std::span<const PointDef> around);

/// The boundary of the solid an arrangement's surface winds around at least
/// once: the faces with winding number >= 1 on one side and <= 0 on the other,
/// turned so that they face the side <= 0 (the union of the input's solids,
/// for an input of closed shells; Zhou, Grinspun, Zorin & Jacobson 2016,
/// section 3.2, "winding number labeling").
struct WindingBoundary {
  enum class Status : std::uint8_t {
    ok,
    /// The pieces do not close up: some edge is passed more times one way
    /// than the other (counting each face as often as pieces cover it, with
    /// their turns). Nothing is selected.
    open,
    /// No seed ray clear of every edge and vertex was found for some part
    /// (64 fixed directions tried), or two faces around an edge could not be
    /// ordered (not expected of an arrangement): nothing is selected.
    undecided,
  };
  Status status = Status::ok;
  /// Over the arrangement's vertices, each face once; closed and oriented (every
  /// edge passed as often each way) when status is ok.
  std::vector<Triangle> triangles;
  std::vector<std::uint32_t> source;  ///< per triangle: an input triangle it lies in
  std::size_t faces = 0;      ///< faces of the arrangement (pieces on the same three vertices counted once)
  std::size_t cancelled = 0;  ///< of those, faces whose pieces cancel (as often one way round as the other)
  std::size_t cells = 0;      ///< the face sides joined into cells around edges (a cell may count twice)
  std::size_t seeds = 0;      ///< rays cast to fix a part's winding numbers
  int max_winding = 0;        ///< the largest winding number of a cell next to a face
};

/// The faces of `arrangement` between winding number >= 1 and <= 0 (see
/// WindingBoundary), decided exactly on its vertices' rational coordinates.
/// Faces are the pieces' vertex triples; a face covered by several pieces
/// counts each with its turn (a duplicated triangle twice, a triangle and its
/// reverse not at all), and the winding number drops by that count crossing it
/// to its front. Around every edge the faces are ordered exactly
/// (order_around_edge's order), and the two face sides bounding each wedge
/// between neighbours are one cell; each part of the surface (faces joined by
/// edges and cells) has its winding numbers fixed by one ray from a face's
/// centroid, counting the faces it crosses with their turns, in the first of a
/// fixed list of directions that passes no edge or vertex.
/// Guarantees when status is ok: the triangles are a subset of the faces, each
/// once, turned to face out of the solid; every edge is passed as often one way
/// as the other (closed and oriented, but not necessarily 2-manifold: solids
/// touching along an edge give it four triangles), and two triangles meet only
/// as the arrangement's pieces do. Deterministic.
/// Preconditions: `arrangement` is arrange_triangles' result (pieces that meet
/// only in shared vertices and edges or coincide). Failure: status (nothing
/// selected), std::bad_alloc. Cost: the exact coordinates of the vertices; per
/// edge with k > 2 faces O(k log k) rational determinants; per part one ray
/// tested against every face (rational arithmetic).
WindingBoundary winding_boundary(const MeshArrangement& arrangement);

/// The plane-based solid a winding boundary bounds (solid_from_winding_boundary).
struct ArrangementSolid {
  enum class Status : std::uint8_t {
    ok,
    /// The boundary's status is not ok, or it selected no face (nothing encloses
    /// a volume): no solid.
    not_selected,
    /// An edge of the boundary has more than two triangles (solids touching along
    /// it) that cannot be paired into wedges: two tie in angle around it, or they
    /// do not alternate in direction. No solid.
    crowded_edge,
    /// A face's boundary, turned about its vertices through its own triangles,
    /// does not close into loops of at least 3 corners each (not expected of
    /// an arrangement: a boundary passing a vertex twice is split into simple
    /// loops there). No solid.
    pinched_face,
    /// An edge lies on no input segment and on no plane but its faces' own (not
    /// expected of an arrangement). No solid.
    no_edge_line,
  };
  Status status = Status::ok;
  /// Over arrangement.plane_set(): vertices the boundary uses (and copies of those
  /// on edges where solids touch and where the solid is pinched at a vertex a
  /// face passes twice), in first use;
  /// faces in the order of their first triangle in the boundary.
  Solid solid;
  std::size_t merged_triangles = 0;  ///< boundary triangles merged into faces of more than one triangle
  std::size_t vertex_copies = 0;     ///< copies made where solids touch (edge ends, pinched vertices)
};

/// The boundary's triangles as the kernel's Solid, stage 3 of resolving
/// self-intersections: the triangles of one source triangle that face one way
/// and are joined by edges become one polygon face on that triangle's input
/// plane (reversed where they face its back), the edges between them and the
/// vertices inside dropped, so that no face edge is a diagonal of a piece's
/// triangulation. Each remaining edge gets its known line (EdgeLine): the input
/// segment of a triangle holding the edge whose line it lies on (decided exactly,
/// among the triangles of the arrangement's pieces on the edge, the lowest first),
/// and the plane of the face across when that plane is another; else, where the
/// face across lies on the same plane, the plane of the lowest such triangle that
/// lies on another. A face's source is its source triangle, its surface id
/// `surfaces[source]`; convexity per face decided exactly, the solid not claimed
/// convex. Where solids touch along an edge (2k triangles on it), the triangles
/// are paired in exact angular order into the k wedges of the solid and each end
/// of the edge gets one vertex per fan of triangles around it: copies of one
/// point, apart by index (round_solid moves them apart when it writes the solid,
/// as at a pinch). A face whose boundary passes a vertex twice is kept: where
/// the solid is pinched there (its triangles around the vertex form several
/// fans, e.g. a saddle of one part dipping into another's face), each fan gets
/// its own copy of the vertex, as at an edge where solids touch; where the
/// passes lie in one fan (a hole of the face touching its outer loop or another
/// hole), the boundary is cut there into loops that each pass it once. A face's
/// loops follow its triangles around each vertex (by index), so they are simple
/// and may touch one another only at a vertex.
/// Guarantees when status is ok: check_solid(arrangement.plane_set(), solid) is
/// empty, and the solid bounds what the boundary's triangles bound (the same
/// region; its exact volume is theirs). Deterministic.
/// Preconditions: `boundary` is winding_boundary(arrangement); `surfaces` has one
/// entry per input triangle. Failure: status (empty solid), std::bad_alloc.
/// Cost: O(T log T) over the boundary's T triangles, plus one exact orientation
/// per triangle and per boundary edge and input edge tried.
ArrangementSolid solid_from_winding_boundary(const MeshArrangement& arrangement, const WindingBoundary& boundary,
                                             std::span<const SurfaceId> surfaces);

}  // namespace shatter
