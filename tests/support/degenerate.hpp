#pragma once
// Degenerate-case generators: the solids and planes that break other slicers.
//
// Meshes here are valid solids (closed, outward, 2-manifold, no self-intersection)
// whose coordinates are chosen so that the degeneracy is exact, not approximate:
// lattice coordinates (small integers times powers of two) make "this plane holds
// that face" true in real arithmetic, which is what the exact predicates then see.
// Planes come in two kinds: exact ones (every coefficient and product exactly
// representable, so the named vertices lie exactly on them) and the same planes
// moved by a few ulps, which leave those vertices a hair off the plane, the case
// rounding-based tools get wrong.

#include <cstdint>
#include <vector>

#include "shatter/kernel/mesh.hpp"

namespace shatter::test {

// --- meshes -------------------------------------------------------------------

/// A staircase of `steps` unit-high steps, each one unit deep, all in one piece:
/// every tread lies in a plane z = k shared with no other face, and every riser
/// face's plane x = k also holds the edge of the next tread, so planes through
/// a tread or riser contain whole faces and many edges. Integer coordinates.
Mesh staircase(int steps);

/// `count` boxes stacked into one tower of staggered floors glued into a single
/// solid: floor k is [k/2, k/2+2] x [0,2] x [k, k+1], so each floor's top and the
/// next floor's bottom are coplanar and overlap partly. Integer/half coordinates.
Mesh stacked_boxes(int count);

/// A box [0,2]^2 x [-2,0] whose top is a saddle around the vertex (1,1,0): the
/// rim rises to z = +1 at the middles of the x sides and falls to z = -1 at the
/// middles of the y sides. The plane z = 0 meets the solid in two triangles that
/// touch only at the saddle vertex: a pinched cap with a vertex shared by two loops.
Mesh pinch_saddle();

/// Two boxes joined by a square bridge whose cross-section shrinks to
/// `neck` x `neck`: planes across the neck leave caps that are tiny beside the
/// solid's size. neck > 0 (e.g. 2^-20 for a needle neck).
Mesh needle_bridge(double neck);

/// A regular tetrahedron flattened to height `height` (a sliver): 4 vertices.
Mesh flat_tetrahedron(double height);

/// A hollow box (a cavity) with a box island floating in it and a second island
/// inside a cavity of the first: five nested shells, lattice coordinates.
Mesh nested_islands();

/// A 3 x 3 x 1 block of unit cells without its middle cell: a box with a square
/// through-hole (genus 1). A plane across the hole leaves an annulus cap (one
/// face, an outer loop and a hole); its top and bottom faces are annuli too.
/// Integer coordinates.
Mesh box_with_through_hole();

/// A 4 x 4 x 2 slab with a one-cell pit in its top and a one-cell bump on it,
/// pit and bump meeting at one vertex of the top plane z = 2: the coplanar top
/// triangles form one edge-connected region whose boundary passes that vertex
/// twice (a pinched region, which a polygon face with simple loops cannot hold).
/// Integer coordinates.
Mesh pit_and_bump();

/// `mesh` with per-corner normals and UVs that differ between corners at one
/// position (face normals; UVs from a per-triangle chart), so every vertex is a
/// seam of several corners.
Mesh with_seams(Mesh mesh);

// --- planes -------------------------------------------------------------------

/// The plane with normal +-e_axis through `point`: exactly through it and through
/// every vertex sharing that coordinate (often whole faces on CAD meshes).
Plane axis_plane_through(Vec3 point, int axis);

/// A plane through `point` with normal `normal`, d rounded to the nearest double:
/// the point lies on it only up to that rounding (it grazes the point).
Plane plane_through(Vec3 point, Vec3 normal);

/// The plane through a, b and c, computed in doubles. Exact (all three lie on it)
/// when the inputs are small lattice points (integers or halves below 2^10).
Plane plane_through_points(Vec3 a, Vec3 b, Vec3 c);

/// The same plane with its offset moved by `ulps` units in the last place
/// (negative: down). The normal is untouched, so the plane is parallel to the first.
Plane offset_by_ulps(Plane plane, int ulps);

/// Planes that all hold (up to rounding) the segment a-b and turn about it by
/// angles start, start * ratio, start * ratio^2, ... (count planes): a chain of
/// near-parallel cuts through one edge. `side` is any direction not along a-b.
std::vector<Plane> near_parallel_fan(Vec3 a, Vec3 b, Vec3 side, int count, double start, double ratio);

/// Which side of the plane each vertex lies on, counted: how degenerate a plane is
/// for a mesh (vertices exactly on it).
struct PlaneContact {
  std::size_t below = 0, on = 0, above = 0;
};
PlaneContact plane_contact(const Mesh& mesh, const Plane& plane);

}  // namespace shatter::test
