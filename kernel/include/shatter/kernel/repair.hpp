#pragma once
// Opt-in repair of a mesh that is not a valid solid (`--repair` on the CLI).
// Nothing else in shatter ever changes a mesh silently: readers weld and keep
// everything as written, validation only names defects. Repair is the one place
// that edits an input, and it reports every change it makes.
//
// Exactness as everywhere: "duplicate" means exactly equal positions (-0.0 and
// +0.0 are equal, as the readers weld them), "zero-area" means exactly collinear,
// orientation and self-intersection are decided by exact predicates (CGAL Epick's
// filtered predicates on the double coordinates). No tolerance decides anything.

#include <array>
#include <cstddef>
#include <functional>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "shatter/kernel/implicit.hpp"
#include "shatter/kernel/mesh.hpp"
#include "shatter/kernel/solid.hpp"

namespace shatter {

/// What one repair step changed. In the order the steps run.
enum class RepairKind {
  merged_duplicate_vertices,     ///< vertices at exactly the same position joined into one
  removed_repeated_index_triangles,  ///< triangles using one vertex twice (after merging): no area, no edges
  removed_duplicate_triangles,   ///< extra copies of a triangle over the same three vertices, same orientation
  removed_opposite_triangle_pairs,   ///< a triangle and its reverse over the same vertices: they enclose nothing
  reversed_triangles,            ///< triangles reversed: consistently oriented (orient_polygon_soup), then every
                                 ///< shell bounding its volume, the outer ones outward (orient_to_bound_a_volume);
                                 ///< counted once, against the input's orientation
  stitched_border_edges,         ///< pairs of boundary edges with exactly equal endpoints joined (stitch_borders)
  fixed_zero_area_triangles,     ///< exactly collinear triangles removed by edge flips/collapses (remove_degenerate_faces),
                                 ///< or outright where the welded surface closes without them (their edges split)
  filled_holes,                  ///< boundary cycles closed by new triangles over their own vertices (triangulate_hole)
  resolved_self_intersections,   ///< retired, made by no repair now: CGAL 5.5's experimental autorefinement
                                 ///< (an opt-in step 8 until 2026-12-05, replaced by the exact step 11); kept so
                                 ///< a file naming it still reads and the kinds after it keep their numbers
  removed_unused_vertices,       ///< vertices no triangle uses any more
  separated_touching_parts,      ///< parts of a closed surface touching at a vertex or along an edge (non-manifold
                                 ///< vertices and edges) split apart and moved a hair into their own wedges; runs
                                 ///< before removed_unused_vertices (appended here: the position is the file's number)
  resolved_self_intersections_exactly,  ///< intersecting triangles split along their intersections exactly (mesh
                                        ///< arrangement), the faces bounding winding number >= 1 kept, rounded and
                                        ///< certified once (RepairOptions::round_solid); runs last
  removed_flat_pieces,  ///< connected pieces (through shared vertices) whose corners all lie in one plane, exactly: however
                        ///< they are closed they enclose no volume; runs after step 2 (appended: see above)
  split_edges_at_vertices,  ///< edges split at the vertices lying exactly inside them (T-junctions), closing a
                            ///< surface whose welded triangles cross every segment as often each way (appended)
  removed_hanging_triangles,  ///< fins: triangles on an edge three or more triangles use, their other edges used by
                              ///< no other triangle, removed where the surface closes without them (appended)
};

/// Every RepairKind (in step order, but for the last two); a kind's position is the number the
/// .shatter file stores for it (formats/file.hpp, section `rpar`), so new kinds
/// are appended, never inserted.
inline constexpr std::array<RepairKind, 15> all_repair_kinds = {
    RepairKind::merged_duplicate_vertices,       RepairKind::removed_repeated_index_triangles,
    RepairKind::removed_duplicate_triangles,     RepairKind::removed_opposite_triangle_pairs,
    RepairKind::reversed_triangles,              RepairKind::stitched_border_edges,
    RepairKind::fixed_zero_area_triangles,       RepairKind::filled_holes,
    RepairKind::resolved_self_intersections,     RepairKind::removed_unused_vertices,
    RepairKind::separated_touching_parts,        RepairKind::resolved_self_intersections_exactly,
    RepairKind::removed_flat_pieces,             RepairKind::split_edges_at_vertices,
    RepairKind::removed_hanging_triangles};

/// The kind's name as the CLI's JSON prints it, e.g. "filled_holes".
std::string_view repair_kind_name(RepairKind kind);

struct RepairChange {
  RepairKind kind;
  std::size_t count = 0;  ///< the main count of the step (vertices, triangles, edges or holes)
  std::string text;       ///< one line, e.g. "filled 1 hole (4 border edges) with 2 triangles"
};

/// A step that could not be done, e.g. a hole larger than the limit. The mesh is
/// still changed by the other steps; validation afterwards names what is left.
struct RepairNote {
  std::string text;
};

/// A plane-based solid rounded to doubles and certified, as every output is
/// (round_solid in the triangulate layer, which the kernel does not depend on:
/// see RepairOptions::round_solid).
struct RepairRounding {
  Mesh mesh;
  bool valid = false;  ///< the mesh passed validate_mesh (self-intersections included)
  std::string defect;  ///< when not valid: what the rounding left
  double moved_volume = 0, moved_volume_bound = 0;  ///< |volume change| rounding's repairs made, and its bound
  std::size_t separated_vertices = 0;  ///< vertex copies moved apart where the exact solid touches itself
};

/// Rounds `solid` (over `set`) to a certified mesh, interpolating per-corner
/// attributes from `attributes`, whose triangles the faces' sources name.
using RepairRoundingHook = std::function<RepairRounding(const PlaneSet& set, const Solid& solid, const Mesh& attributes)>;

struct RepairOptions {
  /// Fill a boundary cycle (hole) only when it has at most this many edges;
  /// larger ones are left and noted. By default every hole is filled, whatever
  /// its size: a fracture needs a closed solid, and an opening that is really
  /// meant to be open cannot be cut into solids anyway. A filled hole's lid is an
  /// invented surface over the hole's own vertices; the report says how many
  /// holes and triangles it took.
  std::size_t max_hole_edges = std::numeric_limits<std::size_t>::max();
  /// How far step 9 moves each copy of a vertex where parts of a closed surface
  /// touch (a non-manifold vertex, or the ends of an edge with more than two
  /// triangles), as a share of the distance to the copy's nearest neighbour. The
  /// copies cannot stay at one position: validate_mesh counts triangles of
  /// different fans meeting at one point as intersecting (the surface touches
  /// itself), so a split alone is still refused. 2^-20 keeps the change far below
  /// any feature of the mesh and still about 2^32 units in the last place of a
  /// coordinate near the copy's edges, so every later exact decision and rounding
  /// sees the parts apart. 0 < value < 1.
  double touching_separation = 0x1p-20;
  /// Exact resolution of self-intersections (step 11): when set and the mesh is
  /// still self-intersecting after the other steps, its mesh arrangement is
  /// computed on plane-based points (arrange_triangles), the faces between
  /// winding number >= 1 and <= 0 kept (winding_boundary), merged per source
  /// triangle into a plane-based Solid (solid_from_winding_boundary) and rounded
  /// and certified by this hook. The kernel cannot round a Solid itself (that is
  /// the triangulate layer's round_solid), so a caller above it passes it:
  /// the CLI passes round_repaired_solid (triangulate/solid_mesh.hpp). Empty by
  /// default: self-intersections are then named by validation, not resolved.
  RepairRoundingHook round_solid = nullptr;
};

struct RepairReport {
  std::vector<RepairChange> changes;  ///< in step order; empty when nothing was changed
  std::vector<RepairNote> notes;      ///< what was attempted but not done
  std::size_t vertices_before = 0, triangles_before = 0;
  std::size_t vertices_after = 0, triangles_after = 0;
  /// Empty, or why the surface encloses no volume (a flat or back-to-back surface),
  /// so that no repair can make a solid of it, in one phrase: "every piece of it is
  /// flat (all its corners in one plane)" when step 2 removed every triangle as flat
  /// (the mesh is left empty), or "every cell of its exact arrangement has winding
  /// number <= 0" when step 11 found no cell of winding number >= 1. A caller
  /// refusing the mesh names this, not the self-intersections left. Not stored in
  /// .shatter files (the note says it too).
  std::string no_volume_reason;

  bool changed() const { return !changes.empty(); }
  /// The surface encloses no volume: no_volume_reason says why.
  bool encloses_no_volume() const { return !no_volume_reason.empty(); }
  /// Nothing changed and nothing noted: the report of a mesh used as read.
  bool empty() const { return changes.empty() && notes.empty(); }
  /// The change of this kind, or nullptr.
  const RepairChange* find(RepairKind kind) const;
  /// One line: "no change" or the changes' texts joined with "; ".
  std::string summary() const;
};

/// Repairs `mesh` in place, step by step, each step doing something only when its
/// defect is present. First, a surface that welded by position crosses every
/// edge as often one way as the other (closed as winding numbers need it, as
/// overlapping or face-sharing closed shells are) but is not valid goes to step
/// 11 as it is (after merging equal positions, reported as step 1), and when
/// that certifies a valid mesh, that is the repair: the steps below would take
/// such a surface apart at its crowded edges and close the borders so made with
/// lids of no shell. Otherwise:
///  1. merge vertices at exactly equal positions (a caller may pass an unwelded mesh);
///  2. remove triangles that use one vertex twice, extra copies of a triangle, and
///     pairs of a triangle with its reverse; then every piece (triangles connected
///     through shared vertices) whose corners all lie in one plane (exact tests):
///     a flat sheet, e.g. a stray triangle crossing a solid, encloses no volume
///     whatever lid closes it, so it cannot add to the solid, and its lid would
///     only lie on it (the item 6: such input encloses nothing). When
///     that leaves no triangle, the mesh is left with none (callers refuse it);
///  3. orient each connected piece consistently (CGAL orient_polygon_soup; a vertex
///     or edge that cannot be made manifold is split for CGAL only and joined again
///     on output, since shatter's meshes are welded by position);
///  4. stitch boundary edges whose endpoints are exactly equal (stitch_borders);
///  5. remove exactly collinear triangles by flipping or collapsing edges
///     (remove_degenerate_faces; no point is moved or created);
///  6. fill each hole of at most `max_hole_edges` edges (by default all) with
///     triangles over its own vertices (triangulate_hole; no new vertex: up to 200
///     edges over every triangulation of them, cubic in the hole's edges, since its
///     Delaunay-restricted search breaks exact ties by memory address; a larger
///     hole keeps that search, deterministic unless two lids weigh the same); a hole
///     whose border passes through one vertex twice or meets exactly one other
///     hole's border at a vertex (holes touching there), or whose CGAL lid would
///     repeat an edge once vertex copies are joined, is closed over the welded
///     vertices instead: where two borders pass a vertex, each gap between its
///     two fans becomes one hole (from one fan's border to the other's), split
///     where a hole still passes a vertex twice, each part by its least-area
///     triangulation that adds no edge or triangle the mesh has; when every
///     triangulation does (a flat border with collinear corners along its
///     sides whose corners are ears of the surface: CGAL's patch-23.off), by a
///     fan from one new vertex at the mean of the part's corners, which adds
///     only new edges, taken when no fan triangle is exactly collinear and the
///     mean is no vertex's position (else noted, the hole left);
///  7. when the mesh is closed, orient every shell to bound a volume, the outermost
///     outward (orient_to_bound_a_volume);
///  8. (none: CGAL's experimental autorefinement was here, an opt-in whose outcome
///     depended on the build; step 11 resolves self-intersections exactly);
///  9. when the surface is closed and consistently oriented but touches itself
///     (parts sharing a vertex or an edge: non-manifold vertices and edges), split
///     every edge with more than two triangles into pairs, each bounding one wedge
///     of the solid (exact angular order around the edge:
///     pair_around_non_manifold_edges, non_manifold.hpp), and every vertex where
///     several fans meet into one vertex per fan; then move each copy but the
///     first into its own part, `touching_separation` times its nearest
///     neighbour's distance, along the mean of its edges (against its fan's
///     normal where that makes triangles cross). Kept only if no moved triangle
///     then meets another one or loses its shape (exact); otherwise undone and
///     noted. The report gives the largest move and the exact volume change
///     with a bound (distance x area / 3 summed over the moves); then each
///     shell is oriented by its nesting, as after welded lids;
///  10. drop vertices no triangle uses;
///  11. when `round_solid` is set and the result is still self-intersecting
///     (but has no zero-area triangle): resolve the intersections exactly, as
///     mesh arrangements do (Zhou, Grinspun, Zorin & Jacobson 2016; Cherchi et
///     al. 2020): arrange_triangles splits every triangle along its
///     intersections on plane-based points, winding_boundary keeps the faces
///     between winding number >= 1 and <= 0 (for overlapping closed shells,
///     their union; for a cavity, what it carves), solid_from_winding_boundary
///     merges them into polygon faces of a plane-based Solid, and the hook rounds
///     it once and certifies it as every cut piece is. Taken only when the hook
///     returns a valid mesh (which replaces the whole mesh: vertices renumbered,
///     attributes interpolated from each face's source triangle); else the mesh
///     stays as steps 1-10 left it and a note says why (an open surface, faces
///     around an edge that cannot be paired into wedges, a rounding that
///     failed). Before it, every
///     shell that crosses another faces as the input held it where the input
///     held all its triangles one way round, else out of its own volume (steps
///     3 and 7 orient by nesting, which crossing shells do not have). The change
///     names the pairs resolved, the pieces, the faces kept and the volume change.
///
/// Attributes: a surviving triangle keeps its corners' attributes (they follow the
/// vertex when it is reversed or rotated; normals are not negated on reversal, as
/// the winding, not the normal, is taken to be the mistake). A triangle made by a
/// flip or by hole filling takes, at each corner, the attribute of an existing
/// corner at the same vertex (the first one, in triangle order, of the same
/// surface where there is one); its surface id is that of an adjacent triangle.
/// A triangle cut by autorefinement gets its attributes interpolated from the
/// triangle it came from. Unchanged triangles keep their order and corner order,
/// and unchanged vertices their relative order; new ones (step 9's copies among
/// them) come after. A triangle at a copy step 9 moved keeps its corners'
/// attributes: the move is a hair, far below what a normal or UV would show.
///
/// Preconditions: none; any mesh may be passed. A mesh with a non-finite
/// coordinate or an index out of range is left unchanged with a note (there is no
/// exact meaning to repair it by). A mesh with no triangle is left unchanged.
/// Guarantees: every change is in the report; a mesh that validate_mesh finds
/// valid (with self-intersections checked) is left bit-for-bit unchanged with an
/// empty report; the BasicMesh invariants hold on return. The result is not
/// promised to be valid: run validate_mesh on it (the CLI does) to learn what is
/// left. The work is done on a copy and moved into `mesh` at the end, so on an
/// exception (std::bad_alloc) `mesh` is unchanged; a CGAL failure inside the
/// self-intersection step is caught, that step undone and noted.
RepairReport repair_mesh(Mesh& mesh, const RepairOptions& options = {});

}  // namespace shatter
