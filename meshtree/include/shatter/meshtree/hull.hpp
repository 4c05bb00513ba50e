#pragma once
// Convex hulls of node meshes, the colliders the runtime builds its compound
// shapes from (DESIGN.md, "Bonds and the runtime"). Hulls are returned in one
// canonical form, so a tree's bytes never depend on the order CGAL happens to
// emit facets in.

#include <span>

#include "shatter/kernel/mesh.hpp"
#include "shatter/kernel/vec.hpp"

namespace shatter {

/// The convex hull of a closed mesh's vertices as an outward triangle mesh (surface
/// ids 0, no attributes), computed with CGAL convex_hull_3 (exact predicates). A
/// mesh that is convex already (every edge convex or flat, decided exactly) is its
/// own hull, without a hull computation, when it is one edge-connected piece.
/// Precondition: the mesh is closed and oriented with positive volume.
/// Guarantees: the canonical form: vertices in lexicographic order of their
/// coordinates, each facet (maximal set of exactly coplanar triangles) fanned
/// from its least vertex over its strictly convex corners, triangles sorted; so
/// equal inputs give equal hulls on any thread and machine.
Mesh convex_hull_of(const Mesh& mesh);

/// The convex hull of a point set, in the same canonical form (CGAL
/// convex_hull_3, exact predicates). Precondition: the points span a volume.
Mesh convex_hull_of_points(std::span<const Vec3> points);

}  // namespace shatter
