#pragma once
// Synthetic solids for the tests and the benchmarks: closed, outward-oriented
// meshes with known volumes, the seed thesis's shapes (the torus, the hollow egg
// shell), and transforms that stress the arithmetic (tiny, huge, far from the
// origin). Everything here is deterministic: the same call gives the same doubles
// on every machine, so a test or a benchmark row built on it is reproducible.
//
// The namespace is shatter::test: these are fixtures, shared by the test suite and
// the benchmarks, not part of the installed library (see generators/CMakeLists.txt).

#include <string>
#include <vector>

#include "shatter/kernel/mesh.hpp"
#include "shatter/kernel/vec.hpp"

namespace shatter::test {

/// Makes a mesh of `triangles` (#T by 3 indices into `positions`), every triangle
/// on the original surface. Nothing is checked or welded: a bad index or an open
/// surface is the caller's to build on purpose (the validator tests do).
Mesh mesh_from(std::vector<Vec3> positions, std::vector<Triangle> triangles);

/// Makes a prism along y from 0 to `length` over a polygon in the (x, z) plane:
/// `loops` index `polygon` (the outer loop counter-clockwise in (x, z), holes
/// clockwise) and `triangles` triangulate it counter-clockwise. Closed and outward
/// when they are; nothing is checked. (The cut tests' grooves and tunnels.)
Mesh prism(const std::vector<Vec2>& polygon, const std::vector<std::vector<VertexIndex>>& loops,
           const std::vector<Triangle>& triangles, double length);

/// Makes the unit cube [0,1]^3, 12 triangles, outward, with the fixed numbering the
/// validator tests refer to: vertices 0-3 are the z = 0 square counter-clockwise
/// from the origin, 4-7 the same corners at z = 1.
Mesh unit_cube();

/// Makes the axis-aligned box [lo, hi], 12 triangles, outward. Precondition:
/// lo < hi in every coordinate. Volume (hi-lo).x * (hi-lo).y * (hi-lo).z.
Mesh box(Vec3 lo, Vec3 hi);

/// Makes the box [lo, hi] with each face split into n x n squares (2 n^2 triangles
/// a face, 12 n^2 in all), so axis planes through grid lines hit many vertices,
/// edges and faces at once. Precondition: n >= 1 and lo < hi in every coordinate.
/// Lattice coordinates are exact when lo, hi and n are dyadic-friendly.
Mesh grid_box(Vec3 lo, Vec3 hi, int n);

/// Makes a torus around the z axis: `segments` x `rings` quads, 2 triangles each,
/// outward. Precondition: 0 < minor_radius < major_radius, segments >= 3, rings >= 3.
Mesh torus(double major_radius, double minor_radius, int segments, int rings);

/// Makes a UV sphere stretched to the ellipsoid with semi-axes `radii` around
/// `centre`: 2 * slices * (stacks - 1) triangles, outward, with a vertex at each
/// pole. Precondition: every radius > 0, slices >= 3, stacks >= 2.
Mesh ellipsoid(Vec3 centre, Vec3 radii, int slices, int stacks);

/// Makes the seed thesis's hollow egg: an outer egg and an inward-facing inner one
/// (a cavity, off-centre), 1,520 triangles, one solid with two shells.
Mesh hollow_egg();

/// Makes a box with a box-shaped cavity that holds a box island: three nested
/// shells, the outer one a grid box (2 x 2 squares a face).
Mesh nested_shells_with_island();

/// Makes two disjoint unit boxes in one mesh: one mesh, two solids.
Mesh two_boxes();

/// Makes slivers: a tetrahedron 1e-4 thick and 1 long, and beside it a
/// 1e-3 x 1e-3 x 10 needle, in one mesh.
Mesh sliver();

/// Concatenates `parts`: vertex indices offset, nothing welded, every triangle on
/// the original surface.
Mesh merge(const std::vector<Mesh>& parts);

/// Returns `mesh` with every position p replaced by p * scale + shift (rounded as
/// doubles round; topology unchanged).
Mesh transformed(Mesh mesh, double scale, Vec3 shift);

/// Returns `mesh` with every triangle reversed (outward becomes inward).
Mesh flipped(Mesh mesh);

/// A generated mesh and the name a test reports it by.
struct NamedMesh {
  std::string name;
  Mesh mesh;
};

/// Returns the generated catalogue the property tests run over: the solids above
/// plus tiny (1e-6), huge (1e6) and far-from-the-origin variants. Never empty;
/// every mesh is a valid solid.
std::vector<NamedMesh> generated_meshes();

}  // namespace shatter::test
