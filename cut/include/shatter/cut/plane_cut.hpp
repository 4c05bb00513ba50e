#pragma once
// The plane kernel's one cut call: a solid cut by a plane, both sides closed and
// separated into solids (cut_solid), then every piece rounded to doubles and
// certified (round_solid). `shatter slice`, the tree builder, the benchmarks and
// the robustness runner all cut through it; none of them decides a side itself.

#include <string>
#include <vector>

#include "shatter/kernel/mesh.hpp"
#include "shatter/kernel/solid.hpp"
#include "shatter/cut/plane_input.hpp"

namespace shatter {

struct PlaneCutOptions {
  /// Surface id of the cap triangles; the input's own ids are kept.
  SurfaceId cap_surface = 1;
  /// Cap UVs are the cap's plane coordinates times this (when the input has UVs).
  double interior_uv_scale = 1.0;
  /// The input was accepted although it intersects itself: certify the pieces'
  /// topology only (SolidMeshOptions::allow_self_intersections).
  bool allow_self_intersections = false;
};

/// One solid of one side of a cut.
struct CutPiece {
  bool above = false;  ///< on the n·x + d > 0 side
  /// The exact piece, over the cut's plane set: what a further cut starts from.
  Solid solid;
  /// The piece rounded to doubles: a valid closed solid as written exactly when
  /// `defect` is empty; no triangles at all when rounding collapses the whole
  /// piece (a sliver thinner than the rounding of its coordinates). Surface ids are the input's, and the cap's on the cap;
  /// per-corner attributes are interpolated from the input triangle each face
  /// came from (the faces' `source`), which is the piece's provenance.
  Mesh mesh;
  /// Why `mesh` is not valid as written (rounding to doubles broke it), or empty.
  std::string defect;
  /// Where the exact piece touches itself at a point (round_solid), the vertex
  /// copies moved apart; and the volume that rounding's repairs moved (the
  /// separation, parts flattened into sheets that vanished, or the whole of a
  /// vanished piece), at most moved_volume_bound.
  std::size_t separated_vertices = 0;
  double moved_volume = 0;
  double moved_volume_bound = 0;
  /// Rounding collapsed the whole piece: it is thinner than the rounding of its
  /// coordinates, so as written it vanishes into its neighbours across the cut
  /// (whose rounded caps close over it). `mesh` has no triangles, `defect` names
  /// the collapse, and `moved_volume` is the piece's exact volume (as a double),
  /// which moves to them; it is at most `moved_volume_bound`, the volume rounding
  /// the piece's vertices can move (see round_solid).
  bool vanished = false;
};

struct PlaneCut {
  /// The pieces below, then above; each side's in the order of their first face.
  std::vector<CutPiece> pieces;
  /// True when the plane misses or only touches the solid: nothing is cut, there
  /// are no pieces, and `whole_above` tells the side the solid lies on.
  bool plane_missed = false;
  bool whole_above = false;
  std::size_t cap_faces = 0;  ///< connected regions of the cap (each an outer loop and its holes)
  std::size_t cap_loops = 0;  ///< loops of the cap, holes included

  /// True when every piece is valid as written (no piece has a defect).
  bool certified() const;
  /// True when, as written, the plane does not cut the solid: it misses it
  /// (plane_missed), or every piece but at most one vanishes (thinner than the
  /// rounding of its coordinates). The mesh tree builder redraws such a plane,
  /// and only such a plane. Never throws.
  bool misses_as_written() const;
};

/// Cuts `solid` by the cut plane `cut` of `set` and rounds every piece.
/// Preconditions: `solid` is `input.solid` or a piece cut from it, sound and
/// embedded over `set` (every solid made from a valid mesh by cuts is), and `set`
/// is `input.geometry`'s plane set with `cut` among its cut planes.
/// `solid_mesh`: the certified mesh of `solid` (the input mesh for the input's
/// solid), or nullptr; certification then tests only the triangles the cut made
/// or moved against it (validate_mesh_against) instead of every pair.
/// Guarantees: as cut_solid for the solids (closed, exact, meeting only on the
/// cut, volumes adding up exactly), as round_solid for the meshes (a mesh with
/// no defect passes validate_mesh; a piece that touches itself at a point, or
/// meets itself along a concave edge of the surface on the plane, is separated
/// there, see cut_solid and round_solid; a piece thinner than its rounding
/// vanishes, see CutPiece::vanished); deterministic. Throws
/// UnsupportedGeometryError only as cut_solid does.
PlaneCut cut_by_plane(const PlaneInput& input, const PlaneSet& set, const Solid& solid, const Mesh* solid_mesh,
                      PlaneRef cut, const PlaneCutOptions& options = {});

/// Cuts a whole mesh by one plane: prepare_plane_input, then cut_by_plane with
/// the mesh as the trusted parent. For one cut: the pieces' solids refer to the
/// prepared input, which is not returned; to cut on, call both yourself.
/// Preconditions: as prepare_plane_input (a valid closed solid, or several; not
/// self-intersecting unless options.allow_self_intersections); `plane` finite
/// with a non-zero normal. Guarantees and failures: as cut_by_plane, and
/// prepare_plane_input's InvalidMeshError for an open or inconsistently oriented mesh.
PlaneCut cut_mesh_by_plane(const Mesh& mesh, const Plane& plane, const PlaneCutOptions& options = {});

/// cut_mesh_by_plane of a mesh already prepared: `input` is prepare_plane_input's
/// result (or prepare_plane_input_beside's, made beside a check of the mesh, as
/// `shatter slice` does). The pieces' solids refer to `input`.
/// Preconditions, guarantees and failures: cut_mesh_by_plane's.
PlaneCut cut_mesh_by_plane(const PlaneInput& input, const Plane& plane, const PlaneCutOptions& options = {});

}  // namespace shatter
