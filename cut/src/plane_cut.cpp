#include "shatter/cut/plane_cut.hpp"

#include <algorithm>
#include <optional>

#include <tbb/parallel_for.h>

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
  // cut: certification looks for what they may cross in a slab around it. The
  // parent's triangles are indexed once for all the pieces, and only if one
  // needs them (a piece certified convex or star-shaped does not).
  std::optional<TrustedTrianglesOnce> parent_triangles;
  if (solid_mesh != nullptr) {
    meshing.cut = &set.cuts[cut.index()];
    meshing.trusted_triangles = &parent_triangles.emplace(*solid_mesh);
  }
  std::vector<Solid*> exact_pieces;
  exact_pieces.reserve(exact.below.size() + exact.above.size());
  std::size_t faces = 0;
  for (std::vector<Solid>* side : {&exact.below, &exact.above}) {
    for (Solid& piece : *side) {
      exact_pieces.push_back(&piece);
      faces += piece.faces.size();
    }
  }
  result.pieces.resize(exact_pieces.size());
  const auto round_piece = [&](std::size_t i) {
    Solid& piece = *exact_pieces[i];
    // round_solid names validate_mesh's defects exactly when the mesh is not valid.
    RoundedSolid rounded = round_solid(set, piece, meshing);
    CutPiece& out = result.pieces[i];
    out.above = i >= exact.below.size();
    out.solid = std::move(piece);
    out.mesh = std::move(rounded.mesh);
    out.defect = std::move(rounded.defect);
    out.separated_vertices = rounded.separated_vertices;
    out.moved_volume = rounded.moved_volume;
    out.moved_volume_bound = rounded.moved_volume_bound;
    // A collapsed piece's moved volume is its own (round_solid measured it
    // exactly against the bound its rounding can move).
    out.vanished = rounded.collapsed;
  };
  // Each piece is rounded and certified on its own (round_solid is a pure
  // function of it), so the pieces of a big cut go to idle threads: the first
  // cuts of a build are its serial part (one node, then two). Small pieces are
  // rounded in turn, where a task would cost more than it saves; either way the
  // pieces are the same.
  constexpr std::size_t parallel_faces = 1024;
  if (exact_pieces.size() > 1 && faces >= parallel_faces) {
    tbb::parallel_for(std::size_t{0}, exact_pieces.size(), round_piece, tbb::simple_partitioner());
  } else {
    for (std::size_t i = 0; i < exact_pieces.size(); ++i) round_piece(i);
  }
  return result;
}

PlaneCut cut_mesh_by_plane(const Mesh& mesh, const Plane& plane, const PlaneCutOptions& options) {
  return cut_mesh_by_plane(prepare_plane_input(mesh), plane, options);
}

PlaneCut cut_mesh_by_plane(const PlaneInput& input, const Plane& plane, const PlaneCutOptions& options) {
  const Plane cuts[] = {plane};
  return cut_by_plane(input, input.geometry.plane_set(cuts), input.solid, &input.mesh, PlaneRef::cut(0), options);
}

}  // namespace shatter
