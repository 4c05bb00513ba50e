#include "shatter/cut/plane_cut.hpp"

#include <algorithm>

#include "shatter/cut/cut_solid.hpp"
#include "shatter/triangulate/solid_mesh.hpp"

namespace shatter {

bool PlaneCut::certified() const {
  return std::all_of(pieces.begin(), pieces.end(), [](const CutPiece& piece) { return piece.defect.empty(); });
}

bool PlaneCut::misses_as_written() const {
  const auto kept = std::count_if(pieces.begin(), pieces.end(), [](const CutPiece& piece) { return !piece.vanished; });
  return plane_missed || kept < 2;
}

PlaneCut cut_by_plane(const PlaneInput& input, const PlaneSet& set, const Solid& solid, const Mesh* solid_mesh,
                      PlaneRef cut, const PlaneCutOptions& options) {
  SolidCut exact = cut_solid(set, solid, cut, options.cap_surface, input.shells);
  PlaneCut result;
  result.plane_missed = exact.plane_missed;
  result.whole_above = exact.plane_missed && !exact.all_below;
  result.cap_faces = exact.cap_faces;
  result.cap_loops = exact.cap_loops;
  SolidMeshOptions meshing;
  meshing.attributes = &input.mesh;
  meshing.interior_uv_scale = options.interior_uv_scale;
  meshing.allow_self_intersections = options.allow_self_intersections;
  meshing.trusted = solid_mesh;
  // Against a trusted parent, the triangles to test are the new ones along the
  // cut: certification looks for what they may cross in a slab around it.
  if (solid_mesh != nullptr) meshing.cut = &set.cuts[cut.index()];
  result.pieces.reserve(exact.below.size() + exact.above.size());
  for (const bool above : {false, true}) {
    for (Solid& piece : above ? exact.above : exact.below) {
      // round_solid names validate_mesh's defects exactly when the mesh is not valid.
      RoundedSolid rounded = round_solid(set, piece, meshing);
      CutPiece& out = result.pieces.emplace_back(CutPiece{above, std::move(piece), std::move(rounded.mesh),
                                                          std::move(rounded.defect), rounded.separated_vertices,
                                                          rounded.moved_volume, rounded.moved_volume_bound});
      // A collapsed piece's moved volume is its own (round_solid measured it
      // exactly against the bound its rounding can move).
      out.vanished = rounded.collapsed;
    }
  }
  return result;
}

PlaneCut cut_mesh_by_plane(const Mesh& mesh, const Plane& plane, const PlaneCutOptions& options) {
  const PlaneInput input = prepare_plane_input(mesh);
  const Plane cuts[] = {plane};
  return cut_by_plane(input, input.geometry.plane_set(cuts), input.solid, &input.mesh, PlaneRef::cut(0), options);
}

}  // namespace shatter
