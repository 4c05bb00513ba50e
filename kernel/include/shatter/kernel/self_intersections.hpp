#pragma once
// Self-intersections of a triangle mesh: which pairs of its triangles meet beyond
// the vertices and edge they share, decided exactly.
//
// Two finders give the same pairs. self_intersecting_pairs is the fast one, a
// uniform grid over the triangles' bounding boxes; the box-tree finder (CGAL's
// box_self_intersection_d) is kept as the reference the tests compare it with.
// Both decide every candidate pair with triangles_intersect, so they differ only
// in how they find the candidates, and both find every pair whose closed boxes
// meet: a pair that intersects is never missed by either.

#include <cstddef>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "shatter/kernel/mesh.hpp"

namespace shatter {

/// Two triangle indices, the smaller first.
using TrianglePair = std::pair<std::size_t, std::size_t>;

/// Whether triangles a and b of a mesh meet beyond the vertices and the edge they
/// share (by index), exactly: the semantics of CGAL PMP's self_intersections on a
/// triangle soup. Sharing an edge, they intersect only when coplanar and on one
/// side of it; sharing a vertex, when the edge of either opposite the vertex meets
/// the other; sharing nothing, when they meet at all; sharing three indices, always.
/// Preconditions: indices in range, finite coordinates, neither triangle has
/// collinear corners (CGAL would call a degenerate triangle intersecting itself).
/// Cost: usually one or two floating-point filters (one triangle strictly beside
/// the other's plane, or their projections apart); exact arithmetic only for
/// nearly coplanar neighbours. Failure: none.
bool triangles_intersect(std::span<const Vec3> positions, const Triangle& a, const Triangle& b);

/// Every pair of triangles that intersect (triangles_intersect), sorted: the
/// smaller index first in each pair, pairs in lexicographic order.
/// Candidates come from a hashed uniform grid over the triangles' bounding boxes
/// (in floats rounded outward; cells three times the mean box size; a pair is
/// tested in the one cell holding the low corner of the overlap of their boxes,
/// so once): for a mesh of triangles of similar size, linear time. Triangles whose boxes span
/// many cells are tested against the others with CGAL's box intersection instead,
/// so a few long triangles cost O(T log T), not a crowded grid.
/// The triangles are ranked along a Morton curve of their boxes' low cells and
/// each bucket is searched once, by its least-ranked triangle, so that a search
/// finds the boxes it compares in cache. Threads: a mesh of more than 16,384
/// triangles is searched on the threads of the enclosing tbb::task_arena (the
/// default one outside any), one thread when it has one.
/// Preconditions: as triangles_intersect, for every triangle.
/// Guarantees: the same pairs as self_intersecting_pairs_by_box_tree, whatever
/// the thread count; deterministic. Failure: none (std::bad_alloc aside).
std::vector<TrianglePair> self_intersecting_pairs(std::span<const Vec3> positions, std::span<const Triangle> triangles);

/// The reference finder: CGAL's box_self_intersection_d over closed bounding boxes,
/// each pair whose boxes meet decided by triangles_intersect. Same preconditions,
/// guarantees and result as self_intersecting_pairs; O(T log T) with a larger
/// constant. For tests and benchmarks.
std::vector<TrianglePair> self_intersecting_pairs_by_box_tree(std::span<const Vec3> positions,
                                                              std::span<const Triangle> triangles);

/// The pairs of triangles among `members` (indices into `triangles`, each once)
/// that intersect (triangles_intersect) and of which at least one is tested
/// (`tested[t] != 0`; one flag per triangle of `triangles`), sorted as
/// self_intersecting_pairs sorts them: the search of a mesh most of whose
/// triangles are known not to meet each other (validate_mesh_against tests only
/// the triangles a cut made). Candidates come from the same hashed uniform grid
/// (cells three times the members' mean box size, a pair tested once, in the cell
/// holding the low corner of the overlap of their float boxes rounded outward); a
/// triangle that is not tested is entered only in the buckets a tested one
/// occupies, and pairs of two untested triangles are never looked at. Members whose
/// boxes span more than 64 cells are compared with every member's box (when that
/// is at most 2^20 box tests), or else go to CGAL's box intersection, as there. A
/// candidate whose box lies beyond the tested triangle's plane (in doubles, past a
/// bound on their rounding) is dropped before the exact test: it cannot meet it.
/// Preconditions: as triangles_intersect, for every member.
/// Guarantees: the same pairs as intersecting_pairs_with_by_box_tree;
/// deterministic. Failure: none (std::bad_alloc aside).
/// `embedded`: empty, or one entry per triangle of `triangles`: pairs of two
/// triangles with the same entry other than no_embedded_group are skipped (the
/// caller certified each such group with triangles_embed_in_projection).
std::vector<TrianglePair> intersecting_pairs_with(std::span<const Vec3> positions, std::span<const Triangle> triangles,
                                                  std::span<const std::uint32_t> members,
                                                  std::span<const std::uint8_t> tested,
                                                  std::span<const std::uint32_t> embedded = {});

/// The reference for intersecting_pairs_with: CGAL's box_intersection_d of the
/// tested members' closed boxes against all members' (what validate_mesh_against
/// ran before the grid). Same preconditions and result; for tests and benchmarks.
std::vector<TrianglePair> intersecting_pairs_with_by_box_tree(std::span<const Vec3> positions,
                                                              std::span<const Triangle> triangles,
                                                              std::span<const std::uint32_t> members,
                                                              std::span<const std::uint8_t> tested,
                                                              std::span<const std::uint32_t> embedded = {});

/// The entry of intersecting_pairs_with's `embedded` that names no group.
inline constexpr std::uint32_t no_embedded_group = 0xFFFFFFFFu;

/// Whether the triangles `group` (indices into `triangles`) are certified to meet
/// each other only in the vertices and edges they share by index (no pair of them
/// intersects in triangles_intersect's sense), by their projection dropping
/// coordinate `axis` (0, 1 or 2). Checked exactly (orient2d on the doubles): every
/// triangle's projection turns the same way, strictly; the edges of the group not
/// matched by a reverse within it (its boundary) leave every vertex at most once,
/// their projections meet only where consecutive ones share their vertex; and of the
/// closed polygons they form, exactly one turns the triangles' way. Why that
/// suffices: the number of triangles covering a point of the plane off their
/// edges is the winding number of the boundary around it (the triangles' boundaries
/// sum to it, each triangle counting 1 inside itself); disjoint simple polygons of
/// which one turns that way wind at most once, so the projections have disjoint
/// interiors, and, the boundary being simple, touch only in shared vertices and
/// edges; each triangle meets each vertical line once, so two meet in 3D only
/// above where their projections meet: in what they share. Nothing is assumed of
/// the group (not planarity, not one face): false proves nothing, and then its
/// pairs are tested as usual. Preconditions: indices in range, finite coordinates.
/// Cost: O(k log k) for k triangles, plus the pairs of boundary edges whose boxes meet.
bool triangles_embed_in_projection(std::span<const Vec3> positions, std::span<const Triangle> triangles,
                                   std::span<const std::uint32_t> group, int axis);

}  // namespace shatter
