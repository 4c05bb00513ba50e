#pragma once
// Output of the plane kernel: a plane-based solid triangulated and rounded to
// doubles once, then certified, so that what shatter writes is a valid mesh.
//
// 1. Round: every vertex to doubles, by rounded_position (a function of its
//    definition alone: pieces that share a vertex share its position bit for bit).
// 2. Triangulate each face polygon over its own vertices, decided on the exact
//    points: a convex face by a fan from a corner that sees every other edge at a
//    non-zero angle; any other face by a constrained Delaunay triangulation of its
//    rounded projection, kept only if every triangle is counter-clockwise in exact
//    arithmetic (then it triangulates the exact polygon: the boundary winds once
//    around every inner point and no triangle is negative), else of its exact
//    points. A face with k corners gets k - 2 triangles plus 2 per hole.
// 3. Certify the rounded mesh exactly (validate_mesh, self-intersections
//    included) and repair what rounding broke, as iterated snap rounding does
//    (Hobby 1999; Halperin & Packer 2002; in 3D, Lazard & Valque 2025, behind
//    CGAL 6's autorefine_triangle_soup): vertices that rounded onto one point are
//    merged and the triangles they flatten removed; on a retry, the faces' loops
//    over merged vertices are repaired as snap rounding repairs segments (a vertex
//    lying exactly inside an edge is inserted into it, spikes removed, loops that
//    run one edge both ways joined across it, a loop through one point twice
//    split there; on the last round, an edge of a face routed through a corner of
//    the face that rounding carried across it, and faces facing opposite ways
//    that rounding laid onto one plane over shared corners merged into the one
//    face their sum leaves) and a fold is retried with another triangulation of
//    the faces involved; triangles that rounding laid over each other once each
//    way (a part thinner than the rounding, flattened into a two-sided sheet)
//    vanish, and on the last round so do four triangles that cover four corners
//    both ways with different diagonals (while the volume moved stays within
//    its bound);
//    an edge that a part thinner than the rounding was squeezed onto (2k
//    triangles around it) is untangled: its triangles paired in exact angular
//    order, one copy of the edge per pair, moved apart as a pinched vertex is;
//    the result is checked again. Last, faces that rounding folded against each
//    other (their triangles cross, or crowd an edge, and their loops share an
//    edge: the wedge between them is thinner than the rounding and rounding
//    turned it inside out) are merged into the face their sum leaves, as faces
//    rounded onto one plane are, and retried with the pairs each retry still
//    finds folded; then a rounded vertex that crossed a face within rounding's
//    reach of its plane is inserted into the triangle it crossed, as 3D snap
//    rounding inserts a hot pixel (while the volume moved stays within its
//    bound); last, a face folded against a cap it shares no edge with, all
//    within rounding's reach of the cap's plane (a cavity's face ulps from it),
//    becomes a hole of the cap. A piece that still fails and whose volume is
//    within what rounding its vertices can move vanishes whole. What cannot be
//    repaired is reported, never written as valid.

#include <cstdint>
#include <span>
#include <string>

#include "shatter/kernel/mass.hpp"
#include "shatter/kernel/mesh.hpp"
#include "shatter/kernel/repair.hpp"
#include "shatter/kernel/solid.hpp"
#include "shatter/kernel/validate.hpp"

namespace shatter {

struct SolidMeshOptions {
  /// The input mesh whose triangles the faces' `source` indices name, to
  /// interpolate per-corner attributes from; nullptr for none. Caps get the cut's
  /// normal, planar UVs times interior_uv_scale and the plane's tangent for the
  /// channels this mesh has.
  const Mesh* attributes = nullptr;
  double interior_uv_scale = 1.0;
  /// A valid mesh this one shares most triangles with (the mesh of the solid this
  /// one was cut from), or nullptr: certification then tests only the pairs of
  /// triangles not both found in it (validate_mesh_against).
  const Mesh* trusted = nullptr;
  /// `trusted`'s triangles, indexed at the first certification that needs them
  /// and kept (TrustedTrianglesOnce of that same mesh), or nullptr to index them
  /// at each certification: a caller rounding several pieces of one mesh (a
  /// cut's pieces, a Voronoi input's fragments) indexes it at most once. Used
  /// only with `trusted`.
  const TrustedTrianglesOnce* trusted_triangles = nullptr;
  /// The cut plane that made this solid from `trusted` (its new triangles lie
  /// along it), or nullptr: narrows the intersection tests to a slab around it.
  const Plane* cut = nullptr;
  /// The valid meshes of the parts this solid is the union of (a union glued
  /// along the parts' shared faces, which are gone from it), or empty. When not
  /// empty, certification tests for self-intersections only the pairs of
  /// triangles not both found in one part (validate_mesh_of_parts; `trusted`
  /// and `cut` are then not used): each part was certified already, and a
  /// triangle the union writes differently (a vertex rounded elsewhere, a face
  /// triangulated or repaired otherwise) is found in no part and tested against
  /// every triangle. The mesh written is the same as without it (the checks
  /// accept the same meshes); only the time differs.
  std::span<const Mesh* const> parts;
  /// With `parts`: where the parts' triangles lie (PartRegions), or nullptr.
  /// Certification then tests pairs across parts region pair by region pair,
  /// leaving out those the regions' planes keep apart; the same meshes pass.
  const PartRegions* part_regions = nullptr;
  /// Per face of the solid, the attempt of triangulate_face its face takes on
  /// round_solid's first attempt, or empty for attempt 0 everywhere. A union of
  /// parts passes the attempt that certified each face's part
  /// (RoundedSolid::attempt), so that it writes those faces as its parts wrote
  /// them (and certification, knowing the parts, skips them) instead of failing
  /// where a part's first attempt failed. Later attempts take one attempt for
  /// every face, as without it. Throws std::invalid_argument (round_solid) when
  /// not empty and not one per face.
  std::span<const std::uint8_t> face_attempts;
  /// Per face of the solid, triangles to write it with on round_solid's first
  /// attempt instead of triangulating it: face f's are
  /// face_triangles[face_triangles_first[f] .. face_triangles_first[f + 1]),
  /// over the solid's vertex indices; an empty range triangulates the face as
  /// usual, and so do later attempts. Precondition (not checked: certification
  /// takes the topology of a first attempt as sound): a face's triangles are a
  /// triangulation of its exact polygon over its own corners, as
  /// triangulate_face writes one: a union passes the triangles its part wrote
  /// the same face with (the same loops over the same points), so that it
  /// writes them again without triangulating. Both empty for none; throws
  /// std::invalid_argument (round_solid) when face_triangles_first is neither
  /// empty nor one more than the faces, or a range runs past face_triangles.
  std::span<const Triangle> face_triangles;
  std::span<const std::uint32_t> face_triangles_first;
  /// Per triangle of face_triangles (or empty), where it was taken from: the
  /// part's index in `parts` << 32 | that part mesh's triangle
  /// (validate_mesh_of_parts' `origins`), or ~0 for none. Certification checks each against the part's
  /// triangle and, when every triangle written holds, matches none by position.
  /// Throws std::invalid_argument (round_solid) when neither empty nor one per
  /// face triangle.
  std::span<const std::uint64_t> face_triangle_origins;
  /// Keep RoundedSolid::mesh_vertex_of for a plain triangulation.
  bool keep_vertex_map = false;
  /// Certify without the self-intersection check, and accept vertices where the
  /// surface touches itself (a self-intersecting input was accepted on request:
  /// only the topology can be promised).
  bool allow_self_intersections = false;
};

/// The solid's faces triangulated over its rounded vertices (steps 1 and 2), with
/// surface ids and attributes; not yet certified. Vertices are the solid's, in its
/// order. A face whose corners merged (rounded onto one position) and that cannot
/// be triangulated over the merged corners is left out (it vanished, or the mesh
/// is open and certification will say so). Throws UnsupportedGeometryError if a
/// face cannot be triangulated over its own vertices (only a non-embedded solid
/// gets there).
Mesh triangulate_solid(const PlaneSet& set, const Solid& solid, const SolidMeshOptions& options = {});

/// Appends the triangles of face `face` of `solid` (over the solid's vertex
/// indices, counter-clockwise seen from outside) to `out`: a fan from a corner
/// that makes no flat triangle when the face is convex, else a constrained
/// triangulation checked in exact arithmetic (see the file comment).
/// `positions`: the vertices' rounded or approximate positions, which only guide
/// the first attempt. `attempt` 0 is the cheapest; later attempts (round_solid's
/// repairs) take the fan whose thinnest triangle is roundest, then the next
/// corners, and the exact constrained Delaunay triangulation for other faces.
/// Throws UnsupportedGeometryError as triangulate_solid.
void triangulate_face(const PlaneSet& set, const Solid& solid, std::uint32_t face, std::span<const Vec3> positions,
                      std::vector<Triangle>& out, std::size_t attempt = 0);

/// The result of round_solid.
struct RoundedSolid {
  Mesh mesh;
  bool valid = false;       ///< the mesh passes validate_mesh with self-intersections
  /// Rounding collapsed the whole piece onto a few points (it is thinner than the
  /// rounding of its coordinates): no triangles, and `defect` says so.
  bool collapsed = false;
  std::size_t merged_vertices = 0;  ///< vertices merged because they rounded onto one point
  std::size_t retriangulated_faces = 0;  ///< faces whose triangulation was changed to undo a fold
  /// Vertex copies moved where the exact piece touches itself (see round_solid);
  /// a vertex pinched between k fans counts k times (k - 1 when its first fan
  /// had to stay still: the last resort round_solid takes).
  std::size_t separated_vertices = 0;
  /// Triangles removed because rounding laid them over each other, once each way
  /// (a part thinner than the rounding, flattened into a two-sided sheet).
  std::size_t vanished_triangles = 0;
  /// Faces merged into each other because rounding folded them against each other
  /// (a wedge thinner than the rounding turned inside out, or a slab between a
  /// cap and a face ulps from its plane; see round_solid).
  std::size_t folded_faces = 0;
  /// Rounded vertices inserted into a triangle of a face they crossed within
  /// rounding's reach of its plane (3D snap rounding's hot pixels; see round_solid).
  std::size_t inserted_vertices = 0;
  /// Vertices the last round placed at another vertex's rounded position, within
  /// a pixel of it, and edges routed through a vertex within a pixel of them
  /// (snap rounding's hot pixels at a coarser pixel; see round_solid): the count
  /// of vertices so moved.
  std::size_t snapped_vertices = 0;
  /// Faces split where they leave rounding's reach of a cap they folded
  /// against, so that the thin part of the wedge between them could vanish (the
  /// last repair; see round_solid): the count of faces added by the splits.
  std::size_t wedge_faces_split = 0;
  /// |volume change| the repairs made: the separation's moves, the written mesh
  /// against the exact piece when parts of it vanished as sheets, the whole
  /// exact volume when the piece collapsed (exact values rounded toward zero to
  /// doubles, so moved_volume <= moved_volume_bound holds as it does exactly;
  /// infinite where the exact value exceeds the double range).
  double moved_volume = 0;
  /// A bound on moved_volume, which a repaired mesh is held to: the separation's
  /// (sum of distance moved x twice the area of the moved copies' triangles, in
  /// the L1 norm), plus, when
  /// parts vanished or faces were merged or snapped, the most that rounding the
  /// piece's vertices can move whatever the triangulation over them (Steiner's
  /// bound over each face's fan triangles with the face's furthest move, its
  /// area term doubled for a triangulation other than the fan; see round_solid);
  /// for a collapsed piece, that bound with each fan triangle's own furthest move.
  double moved_volume_bound = 0;
  std::string defect;       ///< when not valid: validate_mesh's summary of what is left
  /// When valid and the mesh is the plain triangulation of the rounded vertices
  /// (nothing merged, repaired, separated, snapped or vanished): the attempt every
  /// face took in triangulate_face (0 to 3; 0 with SolidMeshOptions::face_attempts
  /// given means each face took its own); -1 otherwise. A union with other solids
  /// passes it on (face_attempts) to write this one's faces alike.
  int attempt = -1;
  /// With SolidMeshOptions::keep_vertex_map and a plain triangulation (attempt
  /// >= 0): per vertex of the solid, its vertex in `mesh`; else empty.
  std::vector<VertexIndex> mesh_vertex_of;
};

/// Steps 1 to 3, and the separation of a piece that touches itself. A cut can
/// leave a piece touching itself at a point, exactly: where the plane passes
/// through a saddle vertex whose two lobes on one side are one piece (several fans
/// meet there), or through the corner of a cavity or a dent that reaches the plane
/// inside the cap (the corner touches the cap). No mesh of such a piece is valid.
/// When certification finds only pinched vertices and intersections, each fan of a
/// pinched vertex gets its own copy, and every copy and every corner touching a
/// cap moves toward its own neighbours by 2^-40 of the distance to the nearest
/// (then 2^-30, 2^-20) until certification passes: the point where the piece
/// touched itself gives way, moving `moved_volume` (at most `moved_volume_bound`).
/// Where rounding squeezed a part thinner than the rounding onto an edge (2k
/// triangles around it, k each way) and nothing else repairs the piece, the
/// triangles around the edge are paired in exact angular order (each pair bounds
/// one wedge of the solid; order_around_line) and each pair gets its own copies
/// of the edge's vertices, separated as above; an edge whose triangles tie in
/// angle or do not alternate in direction around it (a fold) is left as it is.
/// When all of that fails, faces that rounding folded against each other vanish
/// into each other: every pair of faces with triangles that certification finds
/// crossing, or sharing an edge with more than two triangles or run one way by
/// both, that face opposite ways (the solid between them) and whose loops share
/// an edge run both ways, is merged into the one face their loops' sum leaves
/// (edges run both ways cancel; the wedge between the two faces, thinner than
/// the rounding, is dropped), triangulated over the placed corners in
/// projection (`folded_faces`); the pairs each retry still finds are added,
/// until a retry finds none new (a fixed number of times at most). First only
/// pairs whose wedge is thin by its corners (those of one face all within twice
/// the largest rounding move of the other's exact plane, in the L1 norm), then
/// every pair; then the thin pairs again with 3D snap rounding's hot pixels: a
/// rounded vertex inside a triangle it crosses (in that face's projection) and
/// within that reach of the face's exact plane is inserted into the triangle
/// (`inserted_vertices`), after which the piece touches itself there and is
/// separated as above, or the triangles made cancel as sheets. A mesh so
/// repaired is taken only when certified and when the volume it moved, measured
/// exactly against the exact piece (`moved_volume`), is within what rounding the
/// piece's vertices can move (the sweep below, plus a separation's own bound:
/// `moved_volume_bound`).
/// The last round, tried only when every other has failed, is 3D snap rounding
/// at a coarser pixel (Halperin & Packer 2002's iterated snap rounding; CGAL 6's
/// autorefine_triangle_soup snaps the same way): with pixels of 2^1, 2^3, 2^6,
/// 2^10, 2^16 and 2^24 times the largest rounding move, vertices whose rounded positions lie within
/// a pixel of each other (L-infinity, exactly) are placed at one of them (an
/// input point when the cluster has one), and an edge that passes within a
/// pixel of a vertex, between its ends, is routed through it; the loops are then
/// repaired as above (spikes, splits, sheets, separation, folds merged, retried
/// with the pairs each failure finds). The tip of a wedge between near-parallel
/// planes, thinner than the rounding near the shared edge, so vanishes into the
/// edge (`snapped_vertices`); the mesh is taken only when certified and when the
/// volume moved, measured exactly against the exact piece (the signed volume
/// difference), is within what rounding the piece's vertices can move (the sweep
/// below), as for folds merged.
/// After it, the thin pairs of folded faces are merged once more with pairs
/// whose loops share no edge among them, when one face's corners all lie within
/// the reach above of the other's plane: a slab thinner than the rounding
/// between a cap and a face it passes ulps from (a cavity's face in a plane that
/// holds it up to rounding) folds where no edge of the cap is near; the face's
/// loops, run the other way, become a hole of the cap, the slab vanishes and the
/// cavity opens through it (`folded_faces`; held to the same certificate and
/// volume bound).
/// Last, only for a piece that would otherwise be refused (neither certified nor
/// collapsed) and is no union of parts: the faces the rounds found folded against
/// a cap (a face on a cut plane) that are convex and leave rounding's reach of it
/// (a near-parallel chain's earlier cap, clipped) are split along a plane
/// parallel to the cap's, offset into the piece by 2, 1 or 4 times the largest
/// rounding move (an exact plane: the cap's doubles with another offset), the
/// crossing points inserted into the edges of the faces across; every round above
/// then runs once on the refined solid (the same point set), whose strips by the
/// cap are thin by their corners and merge into it (`wedge_faces_split`); held to
/// the certificate and to the original piece's volume bound, measured exactly.
/// When no double offset lies within that reach (ulp of the cap's offset larger
/// than it), the cap's plane scaled by 9/8 to 15/8 and rounded, its offset
/// stepped by ulps (a plane tilted by the rounding), is used instead, the first
/// whose crossing points all lie strictly inside the piece and within reach of
/// the cap's plane, decided exactly.
/// When those fail too, the same planes split every convex face with a corner
/// strictly inside the piece within rounding's reach of the cap's plane (the
/// tip of a wedge between earlier caps a fraction of the rounding under the
/// cap, a fan of an earlier cap whose corners lie ulps from it), and the
/// refined solid's folds are merged by groups (a pair joins when any face of
/// one side's group may merge with any of the other's, until none joins; the
/// merged face on the cap's plane when the cap sees it counter-clockwise), then
/// by groups with faces facing one way merged too when one's corners all lie
/// within reach of the other's plane (the sliver of space the merge fills is
/// thinner than the rounding); held to the same certificate and volume bound.
/// When every plane has failed, the strips thin by their corners: for each cap,
/// the faces reached from it across shared edges whose corners all lie within
/// that reach of its plane (decided exactly), found from the exact solid
/// rather than from what certification names (a corner a fraction of an ulp
/// inside the piece takes the position of its own crossings with the cap, and
/// the faces between it and the cap lie on the cap over its own triangles,
/// cancelled as sheets or crossing them where thicker folds cross too), are
/// merged into the cap as thin folds (by pairs, then by groups), with no
/// snapping and then with each pixel of the snapping round, attempts 1 to 3:
/// first on the piece itself, then on each refined solid of the wedge split
/// (its planes over the faces found folded, then widened) instead of the rounds
/// above (`folded_faces`, `wedge_faces_split`); held to the same certificate
/// and to the original piece's volume bound, measured exactly.
/// When those fail as well, the split takes every convex face with a corner on
/// the cap's plane too (the tip of a wedge between the cap and an earlier cap
/// nearly parallel to it crosses the piece: every face crossing the cap is thin
/// near its crossing line, though none has a corner strictly inside within
/// reach), and the refined solid is rounded by the rounds above with its folds
/// merged by groups, then by groups with faces facing one way too; held to the
/// same certificate and bound.
/// A part thinner than the rounding that rounds flat (its triangles laid over each
/// other once each way) vanishes into its neighbour (`vanished_triangles`); a piece
/// that rounds flat whole, or that cannot be certified while its exact volume is
/// at most what moving its vertices to their rounded positions can sweep
/// (2 d A + 4 d^2 P + 5 d^3 over its faces' fan triangles, d the furthest corner's
/// move, A and P the area and perimeter, all exact upper bounds in the L1 norm:
/// Steiner's formula for the region within d of a triangle), is thinner than the
/// rounding of its coordinates: it is `collapsed`, with no triangles, its exact
/// volume as `moved_volume` and that sweep as `moved_volume_bound`.
/// Preconditions: `solid` sound (check_solid), over `set`; embedded but for such
/// touching points.
/// Guarantees: `valid` is true exactly when `mesh` passes validate_mesh (closed,
/// oriented, 2-manifold, positive volume, no zero-area triangle, no unused vertex,
/// no self-intersection); a piece whose first rounding certifies is written as
/// before any repair existed; every repair is a finite pass (merges and removals
/// only shrink the mesh, insertions put a vertex into an edge that passes exactly
/// through it, merges of folded faces only remove loops, a hot pixel splits a
/// triangle once per step, over a fixed set of four attempts, each tried again
/// untangling edges, and three of them at most six times in each of three
/// phases of folds, of six pixel sizes and of the pairs apart, and at most nine
/// refined solids per cap plane (three planes, each with the faces found folded,
/// then widened, merged two ways), each rounded by that ladder without refining
/// again; then the strips' pass, seven pixels by two ways of merging by three
/// attempts, on the piece and on the refined solids of the first two face sets
/// again (at most six per cap plane, and a tilted plane per reach and set);
/// then the split to the cap, two ways of merging by three offsets (and a
/// tilted plane per reach), each rounded by the ladder without refining again;
/// merging by groups passes over a fixed list of pairs again only after a union,
/// and there are fewer unions than faces: a finite ladder of steps, each a
/// finite pass); deterministic. Failure: neither
/// valid nor collapsed, `defect` names what the first rounding broke.
RoundedSolid round_solid(const PlaneSet& set, const Solid& solid, const SolidMeshOptions& options = {});

/// The solid's mass properties (unit density), integrated over its faces' fans on
/// the vertices' floating-point approximations, each within a few ulps of the exact
/// vertex: volume, centroid and inertia carry a relative error of order 1e-15 times
/// (surface area x size / volume), the conditioning of the divergence theorem.
MassProperties solid_mass_properties(const Solid& solid);

/// The rounding of a solid that repair made (RepairOptions::round_solid, which
/// the CLI sets to this): round_solid with `attributes` as the mesh whose
/// triangles the faces' sources name, its result as the kernel's repair takes it.
/// A collapsed solid (thinner than its rounding) is not valid. Failure: as
/// round_solid's (not valid, with its defect); std::bad_alloc.
RepairRounding round_repaired_solid(const PlaneSet& set, const Solid& solid, const Mesh& attributes);

}  // namespace shatter
