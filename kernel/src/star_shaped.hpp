#pragma once
// The two halves of certify_star_shaped (validate.hpp), for certify_piece
// (certify.cpp), which tests the facing first, before any topology, then the
// winding once the topology is known sound, so neither is computed twice.

#include "shatter/kernel/mesh.hpp"

namespace shatter::kernel_detail {

/// Whether every triangle has `centre` strictly behind it (exact orient3d on the
/// doubles), stopping at the first that does not. Preconditions: indices in range.
bool faces_away_from(const Mesh& mesh, const Vec3& centre);

/// Whether the triangles around every vertex wind exactly once around the ray from
/// `centre` through it (exact orientations), every vertex used. Preconditions: the
/// mesh is closed, consistently oriented and 2-manifold, and faces_away_from(mesh,
/// centre) holds. O(T).
bool winds_once_around(const Mesh& mesh, const Vec3& centre);

}  // namespace shatter::kernel_detail
