#pragma once
// The exact volume of a union of solids by CGAL's corefinement, the reference
// the arrangement's union (test_arrangement_union) and the repair of
// overlapping solids (test_arrangement_repair) are held to. Its one translation
// unit instantiates corefine_and_compute_union on exact constructions for both:
// about 50 s of compile a file in a Release build when each did.

#include <vector>

#include "shatter/kernel/exact.hpp"
#include "shatter/kernel/mesh.hpp"

namespace shatter::test {

/// Six times the volume of the union of `solids`, exactly: each solid made a
/// CGAL Surface_mesh on exact constructions (Epeck) from its doubles, and the
/// solids united in turn by PMP::corefine_and_compute_union.
/// Preconditions: at least one solid; each closed, oriented (a solid with a
/// cavity is one mesh of both shells) and free of self-intersections.
/// Throws std::runtime_error when CGAL cannot make a union.
ExactKernel::FT six_volume_of_union(const std::vector<Mesh>& solids);

}  // namespace shatter::test
