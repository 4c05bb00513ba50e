#pragma once
// Repair's step for a closed surface that touches itself (repair.cpp, step 9):
// parts sharing a vertex or an edge taken apart and moved a hair into their own
// wedges. Private to the repair library.

#include <cstddef>
#include <string>

#include "shatter/kernel/mesh.hpp"

namespace shatter::kernel_detail {

struct TouchingSeparation {
  bool separated = false;            ///< the mesh was changed
  std::size_t edges = 0;             ///< edges with more than two triangles, their triangles paired
  std::size_t vertices = 0;          ///< vertices where several fans met (on those edges or alone)
  std::size_t copies = 0;            ///< vertex copies made (one per fan beyond the first)
  double largest_move = 0;           ///< the longest move of a copy
  double volume_change = 0;          ///< signed volume after - before, exact, rounded once
  double volume_bound = 0;           ///< sum over moves of distance x area of the moved triangles / 3
  std::string failure;               ///< when there was something to separate but it was not done: why
};

/// Splits every edge of `mesh` with more than two triangles into pairs
/// (pair_around_non_manifold_edges: exact angular order, each pair bounding one
/// wedge) and every vertex where several fans meet into one vertex per fan
/// (split_vertex_fans). Copies at one position still touch (validate_mesh counts
/// the triangles meeting there as intersecting pairs), so each fan but the
/// vertex's first moves its copy into its own wedge: along the mean of the unit
/// vectors to its neighbours (or, where that makes triangles cross, against the
/// fan's area-weighted normal) by `scale` times the distance to its nearest
/// neighbour. The result is kept only when no moved triangle has collinear corners
/// or meets another triangle beyond shared indices (self_intersecting_pairs,
/// exact), and the surface is then a manifold by index; otherwise `mesh` is left
/// as it was and `failure` says why.
/// Preconditions: closed and consistently oriented (every edge used as often
/// each way), finite coordinates, no triangle with collinear corners; 0 < scale < 1.
/// Returns with separated == false and an empty failure when nothing touches.
TouchingSeparation separate_touching_parts(Mesh& mesh, double scale);

}  // namespace shatter::kernel_detail
