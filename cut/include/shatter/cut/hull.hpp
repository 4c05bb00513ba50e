#pragma once
// Convex hulls of node meshes, the colliders the runtime builds its compound
// shapes from (DESIGN.md, "Bonds and the runtime"). Hulls are returned in one
// canonical form, so a tree's bytes never depend on the order the hull
// algorithm happens to emit facets in.

#include <span>

#include "shatter/kernel/mesh.hpp"
#include "shatter/kernel/vec.hpp"

namespace shatter {

/// The convex hull of a closed mesh's vertices as an outward triangle mesh (surface
/// ids 0, no attributes), computed by convex_hull_of_points (exact predicates). A
/// mesh that is convex already (every edge convex or flat, decided exactly) is its
/// own hull, without a hull computation, when it is one edge-connected piece.
/// Precondition: the mesh is closed and oriented with positive volume.
/// Guarantees: the canonical form: vertices in lexicographic order of their
/// coordinates, each facet (maximal set of exactly coplanar triangles) fanned
/// from its least vertex over its strictly convex corners, triangles sorted; so
/// equal inputs give equal hulls on any thread and machine.
Mesh convex_hull_of(const Mesh& mesh);

/// The convex hull of a point set, in the same canonical form: quickhull (Barber,
/// Dobkin & Huhdanpaa 1996) deciding every step with the exact orient3d of
/// kernel/predicates.hpp, so exactly coplanar or collinear points, points on the
/// hull's edges and faces, and duplicates need no special care and cost no
/// multi-precision arithmetic. Every hull vertex is an input point.
/// Preconditions: finite points that span a volume (four of them not coplanar).
/// Guarantees: every input point lies inside the hull or on it, exactly; the hull
/// is closed, convex and outward; equal point sets (in any order, with any
/// repetitions) give equal meshes, to the bit (of points equal in value but for
/// the sign of a zero, the one with negative zeros first is kept).
/// Failure: std::invalid_argument when the points are all coplanar (or fewer
/// than four distinct).
Mesh convex_hull_of_points(std::span<const Vec3> points);

}  // namespace shatter
