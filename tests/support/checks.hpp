#pragma once
// Invariant checks shared by the property tests (DESIGN.md, "Invariants").

#include <gmpxx.h>

#include <string>
#include <vector>

#include "shatter/kernel/exact.hpp"
#include "shatter/kernel/mesh.hpp"
#include "shatter/kernel/rationals.hpp"
#include "shatter/kernel/solid.hpp"
#include "shatter/meshtree/tree.hpp"

namespace shatter::test {

/// Empty when `mesh` is a closed, oriented 2-manifold with positive volume, no
/// zero-area triangle and no unused vertex, and its attribute channels have 3
/// entries per triangle; otherwise the validator's one-line summary.
std::string solid_problem(const Mesh& mesh);

/// Empty when `mesh` is closed, consistently oriented and 2-manifold with every
/// vertex used: the fast kernel's guarantee whatever rounding did to the
/// embedding. Otherwise the first such defect.
std::string topology_problem(const Mesh& mesh);

/// Empty when validate_tree finds nothing wrong with `tree`: its structure and
/// caches, and with `geometry` every node's plane, mass, mesh and hull too
/// (TreeValidationOptions::geometry, the costly part). Otherwise the report's
/// summary, naming the part and index at fault. The check every test makes after
/// a build.
std::string tree_problem(const MeshTree& tree, bool geometry = false);

/// solid_problem for an exact mesh, decided on the exact coordinates: topology as
/// topology_problem, then no exactly collinear triangle, then positive volume.
std::string exact_solid_problem(const ExactMesh& mesh);

/// Empty when the closed triangle mesh `hull` is convex at every edge: the far
/// corner of the triangle across each edge is not above the triangle's plane
/// (CGAL's exact orientation); else the first triangle where it is open or not
/// convex.
std::string convexity_problem(const Mesh& hull);

/// Empty when `hull` holds `mesh` as a node's hull must: a valid solid with
/// surface ids 0, convex at every edge, and every vertex of `mesh` on or behind
/// every hull triangle (exact orientation). It may exceed the hull of the
/// mesh's own vertices (an internal node's hull is built from its children's).
/// Else the first problem found, naming the vertex or triangle.
std::string containing_hull_problem(const Mesh& mesh, const Mesh& hull);

/// Six times the volume, exactly, as a rational.
mpq_class exact_six_volume(const ExactMesh& mesh);
mpq_class exact_six_volume(const Mesh& mesh);

/// Six times the volume of a plane-based solid, exactly (the kernel's).
using shatter::exact_six_volume;

/// Whether two sets of faces with their loops and corners (a Solid's, or a
/// split's FaceSet) are the same, field by field.
template <class Faces>
bool same_faces(const Faces& a, const Faces& b) {
  if (a.faces.size() != b.faces.size() || a.loops.size() != b.loops.size() || a.corners.size() != b.corners.size()) {
    return false;
  }
  for (std::size_t f = 0; f < a.faces.size(); ++f) {
    const SolidFace &p = a.faces[f], &q = b.faces[f];
    if (p.plane != q.plane || p.reversed != q.reversed || p.convex != q.convex || p.surface != q.surface ||
        p.source != q.source || p.first_loop != q.first_loop || p.loop_count != q.loop_count) {
      return false;
    }
  }
  for (std::size_t l = 0; l < a.loops.size(); ++l) {
    if (a.loops[l].first_corner != b.loops[l].first_corner || a.loops[l].corner_count != b.loops[l].corner_count) return false;
  }
  for (std::size_t c = 0; c < a.corners.size(); ++c) {
    if (a.corners[c].vertex != b.corners[c].vertex || !(a.corners[c].line == b.corners[c].line)) return false;
  }
  return true;
}

/// Whether two plane-based solids are the same, field by field: definitions,
/// faces, loops, corners and convexity (the approximations are functions of
/// the definitions, so they are not compared).
bool same_solid(const Solid& a, const Solid& b);
/// The same for two lists of solids, in order.
bool same_solids(const std::vector<Solid>& a, const std::vector<Solid>& b);

/// The mesh's bytes in a canonical binary form, to compare outputs for identity.
std::string canonical_bytes(const Mesh& mesh);

/// Total area of the triangles, in doubles: for tolerances, never for decisions.
double surface_area(const Mesh& mesh);
/// The largest absolute coordinate: what one ulp of rounding is relative to.
double largest_coordinate(const Mesh& mesh);

/// An axis-aligned box.
struct Box3 {
  Vec3 lo, hi;
};
/// The bounding box of a mesh's positions. Precondition: at least one position.
Box3 bounds(const Mesh& mesh);

}  // namespace shatter::test
