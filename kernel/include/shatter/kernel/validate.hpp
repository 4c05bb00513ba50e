#pragma once
// Validation of a mesh as a closed, oriented, 2-manifold solid. Every defect is
// named with its count and the first element where it occurs.

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "shatter/kernel/mesh.hpp"

namespace shatter {

// "First" means: the lowest-numbered vertex or triangle; for edges, the first edge
// met scanning triangles in order and each triangle's corners c -> c+1; for
// triangle pairs, the lexicographically smallest (i, j) with i < j. Edges are
// written "edge (i, j)" with i < j.
enum class DefectKind {
  nonfinite_coordinate,      ///< a NaN or infinite coordinate (first: vertex)
  index_out_of_range,        ///< a triangle index >= vertex count (first: triangle); such triangles are left out of every later check
  unused_vertex,             ///< a vertex no triangle uses (first: vertex)
  zero_area_triangle,        ///< a repeated index, or three collinear corners decided exactly (first: triangle);
                             ///< triangles with a repeated index are left out of the edge checks
  boundary_edge,             ///< an edge with one triangle: the mesh is open (first: edge)
  non_manifold_edge,         ///< an edge with three or more triangles (first: edge)
  non_manifold_vertex,       ///< a vertex whose triangles form several edge-connected fans, not counting
                             ///< vertices on a non-manifold edge (first: vertex)
  inconsistent_orientation,  ///< an edge whose traversals cannot be paired with opposite ones: on a
                             ///< two-triangle edge, both triangles traverse it the same way (first: edge)
  inward_orientation,        ///< negative signed volume, decided exactly: faces point inward. Checked
                             ///< only on a closed, consistently oriented mesh (count 1, first "whole mesh")
  self_intersection,         ///< pairs of triangles that intersect beyond shared elements (first: pair),
                             ///< see ValidationOptions::check_self_intersections
  misnested_shell,           ///< a shell whose orientation disagrees with its nesting: outward inside an
                             ///< outward shell, or inward inside a cavity, so part of the solid is covered
                             ///< twice (first: shell). Checked only on a closed, consistently oriented
                             ///< manifold with several shells, after the self-intersection test found none
};

/// Human-readable name of a defect, as used in messages ("boundary edges", ...).
std::string_view defect_name(DefectKind kind);

struct Defect {
  DefectKind kind;
  std::size_t count = 0;  ///< how many elements (or triangle pairs) have it
  std::string first;      ///< the first offending element, e.g. "edge (3, 7)" or "triangles 12 and 40"
};

struct ValidationOptions {
  /// Look for self-intersections (self_intersecting_pairs: a uniform grid over the
  /// triangles' boxes, then an exact test of each pair whose boxes meet, with the
  /// semantics of CGAL PMP's self_intersections; linear after bucketing on meshes
  /// of similar triangles, see self_intersections.hpp). Only
  /// run when the mesh is otherwise a closed, consistently oriented manifold with
  /// finite coordinates and no zero-area triangle. Non-manifold vertices do not
  /// prevent it: the test then sees one copy of such a vertex per fan, so the
  /// triangles of different fans meeting there count as intersecting pairs (the
  /// surface touches itself). Inward orientation and unused vertices do not matter.
  bool check_self_intersections = true;
};

struct ValidationReport {
  std::size_t vertex_count = 0;
  std::size_t triangle_count = 0;
  std::vector<Defect> defects;          ///< in DefectKind order; empty when valid
  bool self_intersections_checked = false;

  bool valid() const { return defects.empty(); }
  /// The defect of this kind, or nullptr.
  const Defect* find(DefectKind kind) const;
  /// One line naming the first defect with its count and first element, e.g.
  /// "open mesh: 4 boundary edges, first edge (0, 3)", followed by the names and
  /// counts of any other defects ("; also self-intersecting triangle pairs (101)");
  /// "valid" when there is none. Self-intersections always read "self-intersecting".
  std::string summary() const;
};

/// Checks every defect in DefectKind order. Never throws on a malformed mesh:
/// finding what is wrong is its job. Guarantees: the counts are exact. Cost:
/// linear for the topology of a sound mesh (a counting sort of its half-edges;
/// the defect-naming checks run only when that finds something), about linear
/// for the self-intersection test (self_intersecting_pairs).
ValidationReport validate_mesh(const Mesh& mesh, const ValidationOptions& options = {});

/// validate_mesh, faster on the meshes shatter writes, and faster still for a mesh
/// that shares most of its triangles with `trusted` (nullptr: none), a mesh that
/// passed validate_mesh with the self-intersection test (a cut piece and the solid
/// it was cut from). Every check is made in full except the self-intersection
/// test, which skips pairs of triangles that both appear in `trusted` (the same
/// three corner positions, turning the same way): two such triangles do not
/// intersect there, so they do not here. Nor are pairs within a group of new
/// triangles (edge-connected, normals nearly parallel: a face triangulated anew, a
/// cap) that triangles_embed_in_projection certifies exactly: none of them meet
/// beyond what they share. Every other pair whose boxes meet (found on a hashed
/// grid, intersecting_pairs_with) is tested exactly, unless its box lies beyond
/// the new triangle's plane by more than a bound on the rounding: first whether
/// their projections along the largest normal component of one are apart (exact 2D
/// orientations, which settle the nearly coplanar triangles of a flat face without
/// exact arithmetic), then as CGAL's self_intersections tests them. The same
/// validity as validate_mesh, and its report when the only defects are crossings
/// (the self-intersection count counts only the pairs tested, and a skipped pair
/// never intersects); any other defect is reported without the search.
/// `near`: a plane the triangles not in `trusted` are known to lie along (a cut);
/// only triangles within the slab of n·x + d values those span are then tested
/// against them (a prefilter in doubles, widened by a bound on its rounding). The
/// new triangles flat along it (the cap: every corner's value within 2^-36 of the
/// largest |n_x x| + |n_y y| + |n_z z| + |d|) span a slab a few ulps thick, and
/// are tested only against the triangles reaching that slab; the other new ones
/// against their own slab.
/// `exact_vertices`: empty, or one flag per vertex. The triangles whose three
/// corners are flagged (and whose positions no other vertex shares) are known
/// not to meet each other beyond what they share by index, and their pairs are
/// not tested either. A caller flags the vertices written at their exact
/// positions where the mesh triangulates faces of an exact solid that meet only
/// in what they share (round_solid's first rounding: the input vertices on no
/// cap), so such a pair is two triangles of that surface. A pair is then tested
/// when one of its triangles is new and one has an unflagged corner: the new
/// triangles with an unflagged corner against all the others (as above), and
/// the new ones all flagged only against the trusted ones with an unflagged
/// corner. Throws std::invalid_argument when `exact_vertices` is neither empty
/// nor one flag per vertex (checked before anything else).
/// Cost: O(T log T) plus the pairs of boxes that meet a tested triangle's box
/// (about linear on the grid for triangles of similar size).
ValidationReport validate_mesh_against(const Mesh& mesh, const Mesh* trusted, const Plane* near = nullptr,
                                       std::span<const std::uint8_t> exact_vertices = {});

/// The triangles of a mesh by their three corner positions, turning the same
/// way (any rotation), in a hash table for lookup in O(1) expected: what
/// validate_mesh_against finds its trusted triangles by. Built once (O(T)
/// expected), it serves every mesh checked against one trusted mesh (the pieces
/// of one cut, the fragments of one input), where building it per check would
/// cost the whole trusted mesh each time. Coordinates compare as doubles (-0
/// equals 0); the mesh must have finite coordinates.
class TrustedTriangles {
 public:
  TrustedTriangles() = default;
  explicit TrustedTriangles(const Mesh& mesh);
  /// Whether triangle `t` of `mesh` (indices in range) is one of them.
  bool contains(const Mesh& mesh, const Triangle& t) const;
  bool empty() const { return keys_.empty(); }

 private:
  std::vector<std::array<Vec3, 3>> keys_;  // each rotated to start at its least corner, one per distinct triangle
  std::vector<std::uint32_t> slots_;       // open addressing (linear probing) into keys_; empty_slot where none
  static constexpr std::uint32_t empty_slot = ~std::uint32_t{0};
};

/// A mesh's TrustedTriangles, made at the first get() and then kept: the
/// pieces of one cut share their parent's, and a cut whose pieces are all
/// certified without it (convex, star-shaped) never pays for it.
/// Precondition: `mesh` outlives this object, unchanged, with finite
/// coordinates. Thread-safe: concurrent get() calls make it once and all see it.
class TrustedTrianglesOnce {
 public:
  explicit TrustedTrianglesOnce(const Mesh& mesh) : mesh_(&mesh) {}
  TrustedTrianglesOnce(const TrustedTrianglesOnce&) = delete;
  TrustedTrianglesOnce& operator=(const TrustedTrianglesOnce&) = delete;
  /// The mesh whose triangles these are.
  const Mesh& mesh() const { return *mesh_; }
  /// The index, made on the first call. Throws what building it throws (memory).
  const TrustedTriangles& get() const;

 private:
  const Mesh* mesh_;
  mutable std::once_flag made_;
  mutable TrustedTriangles index_;
};

/// validate_mesh_against with the trusted mesh's triangles indexed already; the
/// same report.
ValidationReport validate_mesh_against(const Mesh& mesh, const TrustedTriangles& trusted, const Plane* near = nullptr,
                                       std::span<const std::uint8_t> exact_vertices = {});

/// What a caller knows of where the triangles of validate_mesh_of_parts' parts
/// lie: each part's triangles grouped into regions, and for two regions of
/// different parts a plane between them (one region's triangles on one side, the
/// other's on the other, but for what rounding moved). Nothing of it is trusted:
/// it decides only which pairs across parts go untested, and a pair goes
/// untested only when the plane's values at its two triangles' corners span
/// disjoint intervals (exactly, by a floating-point evaluation with its error
/// bound), which no two triangles that meet can do, whatever the plane. So a
/// wrong region or a plane that separates nothing leaves more pairs to test,
/// never a pair that meets untested, and the report is the same. Why it pays:
/// the Voronoi hierarchy's parts are fragments of cells, and the bisector of two
/// cells leaves only the triangles at their shared face within rounding's reach
/// of it; the pairs across parts are then those few, found region pair by
/// region pair, instead of every pair of triangles whose boxes meet.
struct PartRegions {
  /// Per part (as `parts`), the region of each triangle of its mesh; a part
  /// given no regions (an empty span, or one of another size) is one region
  /// of its own, without planes.
  std::span<const std::span<const std::uint32_t>> region_of;
  /// A plane between regions a and b (each a region_of value of a different
  /// part), or none: their triangles are then tested wherever their boxes meet.
  /// Called at most once per pair of regions whose triangles' bounding boxes
  /// meet, on the thread that called validate_mesh_of_parts, while that
  /// thread's buffers are in use: it must not wait on parallel work.
  std::function<std::optional<Plane>(std::uint32_t a, std::uint32_t b)> plane_between;
};

/// validate_mesh for a mesh made of the triangles of several valid meshes
/// (`parts`, each of which passed validate_mesh with the self-intersection
/// test; nullptr entries are skipped), plus any new ones: the union of solids
/// glued along shared faces (meshtree's Voronoi hierarchy). Every check is made
/// in full except the self-intersection test, which skips the pairs of
/// triangles that both appear in one part (the same three corner positions,
/// turning the same way; a triangle found in several parts counts as the first
/// one's). Every other pair whose boxes meet is tested exactly (triangles_intersect):
/// pairs from different parts, and every pair with a triangle found in no part.
/// Why that is sound: the skipped pair's two triangles are two different
/// triangles of one valid mesh, so they do not intersect there; the test is a
/// function of the six corner positions and of which corners are one vertex,
/// and that is the same in both meshes once no two vertices share a position.
/// A valid mesh has no two vertices at one position; in `mesh`, the triangles
/// with a corner at a position another vertex shares are tested as new ones
/// (so two coincident copies of a part are found). Two triangles over the same
/// vertices turning the same way fail the topology check first.
/// Same report as validate_mesh when valid; when not, the same defects but a
/// self-intersection count of the pairs tested.
/// With `regions` (PartRegions), pairs across parts are enumerated region pair
/// by region pair, and a pair whose triangles the pair's plane provably keeps
/// apart is not tested: the same pairs are found meeting, so the same report.
/// Cost: O(T log T) plus the pairs of boxes that meet across parts or with a
/// new triangle (with regions: the pairs of regions whose boxes meet, each
/// O(its triangles) plus the pairs near its plane); the pairs within one part
/// (most pairs of nearby triangles) are never enumerated.
/// `topology_sound`: the caller knows the mesh a closed, consistently oriented
/// 2-manifold by index with every vertex used (as certify_piece's
/// topology_sound: a union's faces triangulated over their own corners, none
/// merged, glued edge for edge); the topology checks are then skipped, and the
/// report is the one they would have let through.
/// `origins`: per triangle of `mesh` (or empty), where the caller took it from,
/// part << 32 | that part's triangle, or ~0 for none. Nothing of it is trusted:
/// a triangle is that part's only if the part's triangle has the same corner
/// positions turning the same way; every other triangle is looked for in all
/// parts as above. When every triangle's origin holds, no table of the parts'
/// triangles is made (the Voronoi hierarchy writes each union face with its
/// part's triangles and knows them). A triangle found in several parts then
/// counts as the one its origin names, a witness as good as the first: the
/// skipped pairs are still pairs of triangles of one valid mesh.
ValidationReport validate_mesh_of_parts(const Mesh& mesh, std::span<const Mesh* const> parts,
                                        const PartRegions* regions = nullptr, bool topology_sound = false,
                                        std::span<const std::uint64_t> origins = {});

/// Whether the mesh is a closed, consistently oriented 2-manifold by index: every
/// index in range, every vertex used, no triangle repeating an index, every
/// directed edge used once and its reverse once, and the triangles around each
/// vertex one fan. Coordinates are not looked at. The linear fast path of
/// validate_mesh's topology checks (a mesh that passes has none of the topological
/// defects). O(T) after sorting each vertex's out-edges. Never throws.
bool is_closed_oriented_manifold(const Mesh& mesh);

/// A fast exact certificate that a closed, consistently oriented, 2-manifold,
/// connected triangle mesh is a valid solid star-shaped around `centre`: every
/// triangle strictly faces away from the centre, and the ring of triangles around
/// every vertex winds exactly once around the ray from the centre through it. The
/// radial projection from the centre is then a covering of the sphere with one
/// sheet, so the surface is embedded (no self-intersection, no two vertices at one
/// point, no zero-area triangle) and bounds a positive volume. Every test is an
/// exact orientation on the doubles (CGAL's filtered orient3d).
/// Preconditions: the mesh's topology is as stated (not checked: it holds by
/// construction for meshes made from plane-based solids). Returns false when the
/// certificate does not apply (which proves nothing: validate_mesh decides then).
/// O(T) after an O(T) pass to order each vertex's triangles.
bool certify_star_shaped(const Mesh& mesh, const Vec3& centre);

/// Refuses a mesh that is not a valid solid, with InvalidMeshError "invalid mesh
/// <name>: <summary>" (an empty mesh: "invalid mesh <name>: empty (no triangles)"). Self-intersections, and the pinched vertices where a surface
/// touches itself, pass when `allow_self_intersections`: a cut then still gives
/// closed, oriented pieces, but their embedding may overlap. Never returns on a
/// mesh the slicer's preconditions exclude. A mesh certify_piece certifies
/// (certify.hpp) passes without the self-intersection search; any other is
/// checked in full, so what passes and what is refused, and the message, are
/// validate_mesh's either way.
void require_valid_solid(const Mesh& mesh, std::string_view name, bool allow_self_intersections);

}  // namespace shatter
