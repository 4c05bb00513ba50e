#pragma once
// Solid separation on CGAL Epeck points, for the tests' oracle (tests/oracle),
// which cuts whole meshes exactly. Not installed (cut/internal/ is on the include
// path of the build and its tests only), so no installed header names a CGAL type;
// the overload on doubles is in separate.hpp.

#include <vector>

#include "shatter/cut/separate.hpp"
#include "shatter/kernel/exact.hpp"

namespace shatter {

/// separate_solids (separate.hpp) on exact points: the same preconditions,
/// guarantees and exceptions, every decision exact as there.
std::vector<ExactMesh> separate_solids(const ExactMesh& surface);

}  // namespace shatter
