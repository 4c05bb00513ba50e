#pragma once
// The two halves of certify_star_shaped (validate.hpp), for certify_piece
// (certify.cpp), which tests the facing first, before any topology, then the
// covering once the topology is known sound, so neither is computed twice.
// Not installed (kernel/internal/); the tests compare the two covering tests.

#include <optional>

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

/// Whether the ray from `centre` through the centroid of one of the first few
/// triangles meets exactly one triangle's cone (true) or more (false): by the
/// covering argument in validate.cpp, true exactly when winds_once_around
/// holds and the surface is connected. std::nullopt when no such ray is found
/// inside a triangle's cone, or the ray runs along an edge's or a vertex's
/// image (the count would not be the covering's degree). Preconditions: as
/// winds_once_around's, every vertex used. O(T), exact orientations.
std::optional<bool> covered_once_along_a_ray(const Mesh& mesh, const Vec3& centre);

/// Whether the surface covers the sphere around `centre` once: every vertex
/// used, then covered_once_along_a_ray, or winds_once_around where the ray
/// decides nothing. Equivalent to winds_once_around. Preconditions: as
/// winds_once_around's, and the surface connected (two shells around the
/// centre wind once each; the ray says no, the walk yes).
bool covers_once(const Mesh& mesh, const Vec3& centre);

}  // namespace shatter::kernel_detail
