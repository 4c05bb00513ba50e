#pragma once
// The rounding of a plane-based solid to a certified mesh (round_solid and
// triangulate_solid, shatter/triangulate/solid_mesh.hpp, which describes what
// they do and guarantee), split by responsibility across the sources beside
// this header. Private to them: never installed, and no other target includes it.
//
//   solid_mesh.cpp           faces triangulated over their own vertices; the public calls
//   rounded_mesh.cpp         steps 1 and 2: vertices rounded and merged, faces triangulated,
//                            their loops repaired first when a round asks for it
//   rounding_loops.cpp       loops over merged vertices: snap rounding's repairs of
//                            loops, faces rounded onto one plane or folded merged
//   rounding_repairs.cpp     repairs of the rounded mesh: two-sided sheets cancelled,
//                            hot pixels (vertices inserted, clusters snapped), folds found
//   rounding_separation.cpp  where a piece touches itself: its fans separated
//   rounding_volume.cpp      the volume rounding may move, and what a repair moved
//   rounding_wedges.cpp      wedges beyond rounding's reach: faces split, strips merged
//   round_solid.cpp          the rounds: round_solid's ladder of attempts and repairs
//   (rounding_exact.hpp: exact_point, for the two sources that name CGAL points)

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include <gmpxx.h>

#include "shatter/kernel/rationals.hpp"
#include "shatter/kernel/validate.hpp"
#include "shatter/triangulate/solid_mesh.hpp"

namespace shatter::rounding {

// --- Faces (solid_mesh.cpp) --------------------------------------------------------------

// A face whose boundary lost corners to merging: its loops over the merged
// vertices (each standing for the point it was placed at: the input point it
// snapped to, or its own), triangulated by the exact constrained Delaunay
// triangulation of their projection. Snapped points are off the face's plane by
// a hair, so the result is a triangulation of the projected polygon only; the
// certification that follows vouches for it in 3D. Returns false, adding
// nothing, when the placed corners bound no polygon the triangulation can cover
// without new points (a face rounded onto the edges around it, or whose loops
// now coincide).
// `also_other_axes`: when the face's own projection fails, try the others (see
// below; round_solid's repairs ask for it).
bool triangulate_merged_face(const PlaneSet& set, const SolidFace& face,
                             std::span<const std::vector<VertexIndex>> loops, std::span<const PointDef> placed,
                             Projection projection, std::vector<Triangle>& out, bool also_other_axes = false);

// --- Loops over merged vertices (rounding_loops.cpp) -------------------------------------

// Steps 1 to 3 on every face's loops (over representatives, consecutive repeats
// removed). `loops[f]`: face f's loops; `candidates`: the vertices that may lie
// inside an edge (the merged representatives, and the corners of loops that
// changed), tested against every edge with a bounding-box filter (exact: the
// positions are doubles).
// `near`: when given, a candidate within that distance of an edge's line (the
// Euclidean distance, SegmentReach) whose projection onto the line falls
// strictly between the edge's ends is inserted too: the last
// round's hot pixels in edges (snap_clusters), an edge passing within a pixel of
// a vertex routed through it.
void repair_merged_loops(std::span<const Vec3> positions, std::vector<std::vector<std::vector<VertexIndex>>>& loops,
                         std::span<const VertexIndex> candidates, const mpq_class* near = nullptr);

// Step 1 for a vertex that rounding carried across an edge of its own face:
// snap rounding routes a segment through every hot pixel it passes (Hobby 1999;
// Guibas & Marimont 1998, "Rounding arrangements dynamically"), so that no
// vertex ends up on the wrong side of a segment; here, in the plane of each face
// (its exact projection), a corner v of the face lies strictly on one side of
// the line of an edge (a, b) of the face in exact arithmetic (placed points) and
// strictly on the other on the rounded doubles, and lies between a and b along
// the edge (exactly, on the doubles): the edge is routed through v, in every
// loop that has it (the face across the edge too), and step 2 then removes the
// spike or splits the loop where it passes v twice. Positions do not change;
// certification vouches for the result. Only corners within 2^-30 of the
// coordinates' magnitude of the edge's box are tested: rounding moves a point by
// at most 2^-40 of its magnitude or 64 ulps when snapped (output_position), so
// no farther corner can have changed side. Returns whether any edge changed.
bool route_edges_through_crossed_corners(const PlaneSet& set, const Solid& solid, std::span<const PointDef> placed,
                                         std::span<const Vec3> positions,
                                         std::vector<std::vector<std::vector<VertexIndex>>>& loops);

// Step 2 for faces that rounding laid onto each other: a part thinner than the
// rounding between two faces that face opposite ways (a slab between a cap and
// an input face ulps from it) rounds onto one plane, and if the two faces' loops
// then share their vertices they overlap as a two-sided sheet, but are
// triangulated differently, so no two triangles cancel. As 2-chains on the common
// plane the faces add up to their difference, whose boundary is the sum of their
// loops as traversed, in which an edge run both ways cancels: so faces that share
// an edge run both ways, all of whose rounded corners lie exactly on one plane
// (orient3d zero) and of which two face opposite ways, are merged into one face
// over the loops left once those edges cancel (join_at_antiparallel_edge, spikes,
// splits; merge_face_group). `emit_as[f]`: the face whose description face f's
// triangles take, or no_index when f is merged into another; `home[f]`: the
// face holding f's loops (itself unless merged). Returns whether any faces
// were merged.
bool merge_coplanar_sheets(const PlaneSet& set, const Solid& solid, std::span<const Vec3> positions,
                           std::vector<std::vector<std::vector<VertexIndex>>>& loops,
                           std::vector<std::uint8_t>& changed, std::vector<std::uint32_t>& emit_as,
                           std::vector<std::uint32_t>& home);

// How far rounding moved the piece's vertices, and which corners lie within
// that reach of a plane, exactly. `rho`: the largest move of a vertex from its
// exact position to its output position, in the L1 norm (rationals). A corner
// lies within reach of plane n.x + d = 0 when its exact L1 distance to it,
// |n.x + d| / max |n_i|, is at most 2 rho: rounding the piece could have put it
// on the plane's other side. A face all of whose corners lie within reach of the
// plane of a face it shares an edge with bounds, with it, a wedge no thicker than
// that: merging the two moves at most 2 rho times its area.
struct RoundingReach {
  const PlaneSet& set;
  const Solid& solid;
  std::vector<std::optional<std::array<mpq_class, 3>>> exact;
  mpq_class rho = 0;

  RoundingReach(const PlaneSet& s, const Solid& piece, std::span<const Vec3> positions)
      : set(s), solid(piece), exact(piece.defs.size()) {
    for (VertexIndex v = 0; v < piece.defs.size(); ++v) {
      const auto& x = point(v);
      mpq_class moved = 0;
      for (int k = 0; k < 3; ++k) moved += abs(mpq_class(positions[v][k]) - x[k]);
      if (moved > rho) rho = moved;
    }
  }
  const std::array<mpq_class, 3>& point(VertexIndex v) {
    if (!exact[v]) exact[v] = exact_coordinates(set, solid.defs[v]);
    return *exact[v];
  }
  // The points within reach of `plane` (PlaneReach, exact).
  PlaneReach near(PlaneRef plane) const { return PlaneReach(set, plane, 2 * rho); }
  // A rounded position within reach of `plane`.
  bool within(const Vec3& p, PlaneRef plane) const { return near(plane).locate(p).within; }
  // Every corner of `loops` within reach of `plane`.
  bool within(const std::vector<std::vector<VertexIndex>>& loops, PlaneRef plane) {
    const PlaneReach reach = near(plane);
    for (const auto& loop : loops) {
      for (const VertexIndex v : loop) {
        if (!reach.locate(point(v)).within) return false;
      }
    }
    return true;
  }
  // Every corner of the solid's face `f` within reach of `plane`.
  bool within(std::uint32_t f, PlaneRef plane) {
    const SolidFace& face = solid.faces[f];
    std::vector<std::vector<VertexIndex>> loops;
    for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
      std::vector<VertexIndex>& loop = loops.emplace_back();
      for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[l])) loop.push_back(edge.from);
    }
    return within(loops, plane);
  }
};

// How merge_folded_faces joins the pairs of folded faces it is given: `pairs`,
// each pair on its own merits (every round of round_solid); `groups`, a pair
// joins when any face of one side's group so far may merge with any face of the
// other's, repeated until no pair joins, so that what a fold merges does not
// depend on the order the pairs come in, and the merged face is written on a
// cap's plane when a cap of the group sees its loops counter-clockwise (a
// refined wedge's strips, merged into the cap through a sliver that reaches the
// cap first, stay on the cap's plane instead of taking the sliver's);
// `groups_one_way`, the same, and two faces facing one way merge as well when
// one's corners all lie within rounding's reach of the other's plane (the
// sliver of space between them that the merge fills is thinner than the
// rounding, as a wedge that vanishes is). Only the last repair's refined solids
// take the latter two (see round_solid_rounds).
enum class FoldMerge { pairs, groups, groups_one_way };

// Faces that rounding folded against each other (see round_solid): a pair of
// faces whose rounded triangles certification found crossing, or sharing an
// edge with other triangles (a fold: the wedge between them is thinner than
// the rounding, and rounding turned it inside out), and whose loops share an
// edge run both ways. The wedge between such faces is a part thinner than the
// rounding, as a two-sided sheet is, though its faces do not lie on one plane;
// it vanishes the same way: the faces are merged into the face their sum leaves
// (merge_face_group), triangulated on the placed corners in projection, and
// certification and the volume the merge moved (held to what rounding can
// move) vouch for the result. `folds`: pairs of faces (indices of the loops
// before any merge, mapped through `home`). Decided by index; changes no
// position. `thin_only`: merge only pairs whose wedge is thin by its corners
// (within_rounding_reach), so that no fold that needs a wider merge drags a
// thick wedge along. `apart_too` (with `thin_only`): pairs whose loops share no
// edge are merged as well when thin: a slab thinner than the rounding between a
// cap and a face inside it (a cavity's face ulps from the cap's plane) rounds
// into a fold that touches no edge of the cap; as 2-chains on the cap's plane
// the face's loops, run the other way, add a hole to the cap, through which the
// cavity opens (the slab vanishes). `mode`: see FoldMerge. Returns how many
// faces were merged (each group counts its members).
std::size_t merge_folded_faces(const PlaneSet& set, const Solid& solid, std::span<const Vec3> positions,
                        std::vector<std::vector<std::vector<VertexIndex>>>& loops, std::vector<std::uint8_t>& changed,
                        std::vector<std::uint32_t>& emit_as, std::vector<std::uint32_t>& home,
                        std::span<const std::pair<std::uint32_t, std::uint32_t>> folds, bool thin_only,
                        bool apart_too = false, FoldMerge mode = FoldMerge::pairs);

// --- The rounded mesh (rounded_mesh.cpp) -------------------------------------------------

// Steps 1 and 2 (see solid_mesh.hpp): positions, vertices merged where they
// rounded onto one point, faces triangulated.
// `repair_loops`: repair the loops of faces over merged vertices
// (repair_merged_loops) before triangulating them; round_solid asks for it once
// the plain merge has failed certification, so that a piece valid without it is
// written as before. `route_crossed`: the last round's repairs as well (edges
// routed through crossed corners, faces rounded onto one plane merged).
// `folds`: pairs of faces rounding folded against each other, merged
// (merge_folded_faces, only with `route_crossed`; `thin_folds_only` as there);
// `folded` receives how many faces that merged; `folds_apart_too`: as
// merge_folded_faces' `apart_too`. `face_of_triangle`: when given,
// the face (loop index) each triangle of `mesh` came from, in order.
// `triangle_origins`: when given, per triangle of `mesh`, its
// SolidMeshOptions::face_triangle_origins entry when it is one of the given
// face triangles written, else ~0.
void triangulate(const PlaneSet& set, const Solid& solid, const SolidMeshOptions& options, std::size_t attempt,
                 Mesh& mesh, std::size_t& merged, std::vector<VertexIndex>* mesh_vertex_of = nullptr,
                 bool repair_loops = false, bool route_crossed = false,
                 std::span<const std::pair<std::uint32_t, std::uint32_t>> folds = {},
                 std::vector<std::uint32_t>* face_of_triangle = nullptr, std::size_t* folded = nullptr,
                 bool thin_folds_only = false, std::span<const VertexIndex> snapped_to = {},
                 const mpq_class* snap_within = nullptr, bool folds_apart_too = false,
                 FoldMerge fold_merge = FoldMerge::pairs, std::vector<std::uint64_t>* triangle_origins = nullptr);

// --- Repairs of the rounded mesh (rounding_repairs.cpp) ----------------------------------

// Removes every pair of triangles over the same three vertices turning opposite
// ways (matched by index; the first unmatched one in mesh order pairs with the
// first of its reverse), with their surfaces and corner attributes, then the
// vertices no triangle uses any more. Returns how many triangles went.
// `renumbered`: each old vertex's new index (no_index when it went).
// `quads`: also remove two-sided sheets over four corners triangulated with the
// two different diagonals, (a, b, c) + (a, c, d) one way and (a, d, b) + (b, d,
// c) the other (a cap whose corners snapped onto those of two input triangles,
// triangulated across the other diagonal): the four bound only the thin
// tetrahedron between the two triangulations, and removing them keeps every
// directed edge matched (their boundaries are a -> b -> c -> d and its reverse).
// Four such triangles always bound a tetrahedron: one that no other triangle
// meets along an edge, its corners off one plane (exact), is a part of its own
// (a union's tiny part touching the rest at a vertex), not a sheet, and stays.
// `kept`: when given, the old index of each triangle left, in order.
// `quad_triangles`: when given, how many of those removed were such quads' (a
// multiple of four).
std::size_t cancel_two_sided_sheets(Mesh& mesh, std::vector<VertexIndex>& renumbered, bool quads = false,
                                    std::vector<std::uint32_t>* kept_triangles = nullptr,
                                    std::size_t* quad_triangles = nullptr);

// The triangles of `mesh` with a shape (self_intersecting_pairs' precondition):
// three distinct corners not on one line (collinear, exact on the doubles).
// `index[i]` is shaped[i]'s place in mesh.triangles.
void shaped_triangles(const Mesh& mesh, std::vector<Triangle>& shaped, std::vector<std::uint32_t>& index);

// The hot pixels of 3D snap rounding (Hobby 1999's hot pixels; in 3D, as CGAL
// 6's autorefine_triangle_soup snaps): a rounded vertex v that landed within
// rounding's reach of the plane of a face it does not belong to, and inside one
// of that face's triangles that crosses a triangle at v, is inserted into it: the
// triangle (a, b, c) becomes (a, b, v), (b, c, v), (c, a, v). The face then
// passes through v, as its exact surface passes within reach of it, and the
// piece touches itself at v (two fans), which separate_touching then takes
// apart. Decided exactly: the crossing pairs by self_intersecting_pairs, reach
// by RoundingReach on the face's exact plane, "inside" by exact orientations of
// the doubles in the face's projection (strictly inside, so no triangle made is
// flat in projection). Each triangle takes one vertex per pass; the new corner's
// attributes are the mean of the triangle's. `face_of[t]`: triangle t's face,
// extended for the triangles made. Returns how many vertices were inserted.
std::size_t insert_vertices_into_crossed_triangles(const PlaneSet& set, const Solid& solid, RoundingReach& reach,
                                                   Mesh& mesh, std::vector<std::uint32_t>& face_of);

// The last round's hot pixels (3D snap rounding, Halperin & Packer 2002's
// iterated form, Lazard & Valque 2025 behind CGAL 6's autorefine_triangle_soup:
// features closer than the rounding unit are snapped together). Rounding each
// vertex on its own to doubles can scramble vertices that lie closer together
// than the rounding moves them: the tip of a wedge between near-parallel planes
// holds corners of both of its faces ulps apart, and a face a few ulps off
// another holds its corners that close to the other's; rounded separately they
// change order and the faces fold. Vertices whose output positions lie within
// `within` of each other (the L-infinity norm, decided exactly on the doubles)
// are put into one cluster, transitively, and each vertex of a cluster is
// placed at its representative's output position: an input point of the
// cluster when it has one (doubles hold it exactly), else its smallest index.
// The part between the vertices of a cluster, thinner than the pixel, then
// vanishes, as parts that rounded onto one point do. `snapped_to[v]`: v's
// representative (v itself when alone). Returns whether any cluster has two
// vertices.
bool snap_clusters(const Solid& solid, std::span<const Vec3> positions, const mpq_class& within,
                   std::vector<VertexIndex>& snapped_to);

// Adds to `pairs` (kept sorted and unique, the smaller face first) the pairs
// of faces whose triangles in `mesh` fold against each other: triangles of
// different faces around an edge that more than two triangles share, or run one
// way by both, and pairs of triangles of different faces that intersect
// (self_intersecting_pairs, exact, over the triangles with three distinct
// non-collinear corners). `face_of[t]`: the face (loop index) triangle t came from.
void add_folded_face_pairs(const Mesh& mesh, std::span<const std::uint32_t> face_of,
                           std::vector<std::pair<std::uint32_t, std::uint32_t>>& pairs);

// --- Where a piece touches itself (rounding_separation.cpp) ------------------------------

// The solid's vertices that lie on the plane of one of its cut faces (a cap)
// inside that face or on its boundary without being a corner of it. Exact.
std::vector<VertexIndex> corners_touching_caps(const PlaneSet& set, const Solid& solid);

// What separate_touching did.
struct Separation {
  std::size_t moved = 0;        ///< vertex copies moved (a pinched vertex counts once per fan)
  mpq_class volume_change = 0;  ///< |signed volume after - before|, exactly
  /// Sum over moved copies of the distance moved x twice the area of their
  /// triangles, both in the L1 norm (upper bounds of the Euclidean), exactly.
  mpq_class volume_bound = 0;
};

// Splits every vertex of `mesh` where several edge-connected fans of triangles
// meet into one vertex per fan, then moves each copy, and each vertex of
// `touching` (one fan, touching a cap), toward its fan's neighbours by `scale`
// times its nearest neighbour's distance. Returns nothing moved when there is
// nothing to separate. `partner`: empty, or for each directed edge slot on a
// non-manifold edge the triangle it is paired with (pair_around_non_manifold_edges):
// triangles meet across such an edge only in their pairs, so the edge's
// vertices fall into one fan per pair where nothing else joins them.
// `held`: empty, or per vertex of the split mesh (split_vertex_fans numbers
// the copies the same way for the same mesh) whether the fan that keeps that
// vertex stays where it is, only the other fans' copies moving (see
// round_solid_rounds: a nearly flat fan's mean edge can point into another
// fan's wedge).
// Preconditions: closed and consistently oriented (each edge run as often each
// way), and every non-manifold edge paired in `partner`.
Separation separate_touching(Mesh& mesh, std::span<const VertexIndex> touching, double scale,
                             std::span<const std::uint32_t> partner = {}, std::span<const std::uint8_t> held = {});

// --- Volume moved (rounding_volume.cpp) --------------------------------------------------

// How much volume rounding the solid's vertices to their output positions can
// move, exactly (rationals), as a bound: every point of a fan triangle of a face
// moves no further than the furthest of its corners, delta, so the region swept
// between the exact triangle and its rounded image lies within delta of the
// exact triangle, whose volume is at most 2 delta A + pi delta^2 P + 4/3 pi
// delta^3 (Steiner's formula for a convex plane set: area A, perimeter P). Here
// A, P and delta are taken in the L1 norm (upper bounds of the Euclidean
// ones), pi as 4 and 4/3 pi as 5. The written volume of the piece then differs
// from the exact one by at most the sum over the fan triangles; a piece whose
// rounding leaves no volume at all (it collapsed onto sheets or points) has
// its whole volume within it.
// That holds for the fan around `centre` only. With `any_triangulation`, delta
// is the furthest move over the whole face and the area term is doubled, which
// also covers a face triangulated otherwise over its rounded corners (the repairs'
// roundest fans, Delaunay, loops routed through a vertex on their edges): all
// such corners lie within delta of the exact plane, so two surfaces over the
// same loops, each covering the face once in projection, enclose at most 2 delta
// times its area between them. (fuzz_slice corpus: cube-off-cap-routed-through-
// vertex.bin, a cap fan whose wide triangle has exact corners while the
// retriangulated cap moved 0.33 eps x its area.)
mpq_class rounding_sweep_bound(const PlaneSet& set, const Solid& solid, bool any_triangulation = false);

// The volume a repair moved: the written mesh's volume against the exact piece's
// (both sides exact: the mesh's doubles and the solid's rationals), and what
// rounding the piece's vertices can move, whatever the triangulation over them
// (rounding_sweep_bound with any_triangulation), which the repaired mesh is held
// to: its triangles are the exact piece's, moved by the rounding and triangulated
// again, less sheets of no volume.
struct MovedVolume {
  mpq_class change = 0, bound = 0;
};

// The piece's exact six-fold volume and its rounding bounds (rounding_sweep_bound,
// per fan and for any triangulation), each computed at its first need and kept:
// they depend on the piece alone, while the rounds measure mesh after mesh
// against them (diplodocus.off's repair: the whole piece's exact volume, again
// at every attempt, was an eighth of its time). `set` and `solid` must outlive it.
class PieceVolumes {
 public:
  PieceVolumes(const PlaneSet& set, const Solid& solid) : set_(set), solid_(solid) {}
  const mpq_class& six() {
    if (!six_) six_ = exact_six_volume(set_, solid_);
    return *six_;
  }
  const mpq_class& sweep(bool any_triangulation) {
    std::optional<mpq_class>& kept = any_triangulation ? sweep_any_ : sweep_fan_;
    if (!kept) kept = rounding_sweep_bound(set_, solid_, any_triangulation);
    return *kept;
  }

 private:
  const PlaneSet& set_;
  const Solid& solid_;
  std::optional<mpq_class> six_, sweep_fan_, sweep_any_;
};

MovedVolume measured_moved_volume(PieceVolumes& piece, const Mesh& mesh);

// Reports `moved` in `result` (as doubles, each rounded toward zero, so the
// order the exact values have is kept) and says whether it is within its bound.
bool report_moved_volume(const MovedVolume& moved, RoundedSolid& result);

// --- Wedges beyond rounding's reach (rounding_wedges.cpp) --------------------------------

// The solid with each face of `split` (convex, one loop, with corners strictly on
// both sides of `plane`) split along its line with `plane`, the crossing vertices
// inserted into the edges of the faces across. `set` must hold `plane`. Returns
// false, leaving `out` undefined, when no face was split.
bool split_faces_along(const PlaneSet& set, const Solid& solid, PlaneRef plane, std::span<const std::uint32_t> split,
                       Solid& out);

// Every cap's strips thin by their corners (strips_thin_by_corners) merged into
// it as folds (merge_folded_faces, thin pairs: each face's group joins the cap's
// only through faces within reach), with no snapping, then with snap rounding's
// pixels (snap_levels, as the snapping round: a fold of the thicker faces along
// an edge shorter than the rounding vanishes into a vertex), each by pairs, then
// by groups (FoldMerge), over attempts 1 to 3, sheets cancelled; the first mesh
// certified whose exact volume moved is within the piece's rounding bound
// (measured_moved_volume). A finite pass: a fixed list of pairs, seven pixels,
// two modes, three attempts, each one triangulation and certification.
// `positions`: the output positions of the solid's vertices; `reach` over them;
// `piece` the solid's volumes.
std::optional<RoundedSolid> round_merging_thin_strips(const PlaneSet& set, const Solid& solid,
                                                      const SolidMeshOptions& options,
                                                      std::span<const Vec3> positions, RoundingReach& reach,
                                                      std::span<const int> snap_levels, PieceVolumes& piece);

// --- Certification (round_solid.cpp) -----------------------------------------------------

// A mesh triangulating `solid`'s faces over their own vertices, none merged
// (round_solid's first rounding), with each solid vertex's mesh vertex (or
// no_index): what certify_rounded flags validate_mesh_against's exact vertices
// from (exact_input_vertices in round_solid.cpp says which and why).
struct ExactVertexSource {
  const Solid& solid;
  std::span<const VertexIndex> mesh_vertex_of;
};

// Certifies a rounded mesh as round_solid promises: the linear certificate of
// certify_piece when it applies (it accepts only valid meshes, and the full check
// accepts every valid one, so the mesh written is the same either way), else
// validate_knowing; or the topology alone (with vertices where the surface
// touches itself allowed) for a solid accepted with self-intersections.
// `exact`: nullptr, or where the mesh came from; its flags are made only when
// the full check runs (certify_piece certifies most pieces without them).
// `triangle_origins`: for a union of parts, triangulate's (checked, not
// trusted: validate_mesh_of_parts' `origins`).
ValidationReport certify_rounded(const Mesh& mesh, const SolidMeshOptions& options,
                                 const ExactVertexSource* exact = nullptr,
                                 std::span<const std::uint64_t> triangle_origins = {});

}  // namespace shatter::rounding
