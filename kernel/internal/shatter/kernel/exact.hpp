#pragma once
// CGAL's Epeck points (lazily evaluated exact rationals with interval filters)
// and their conversions to and from doubles. The library triangulates faces and
// caps on them where rounded positions would not do (triangulate/cap.hpp), and
// separates shells with their exact volumes; the tests' oracle (tests/oracle)
// cuts whole meshes with them. Caps and solid separation are written once over
// Vec3 and ExactPoint, using the overloads below. The kernel's own vertices are
// plane-based definitions (implicit.hpp), not these.
//
// Not installed (kernel/internal/ is on the include path of the build and its
// tests only): no installed header names a CGAL type, so a program using the
// library compiles without CGAL, Boost or GMP.

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>

#include "shatter/kernel/mesh.hpp"
#include "shatter/kernel/predicates.hpp"

namespace shatter {

using ExactKernel = CGAL::Epeck;
using ExactPoint = ExactKernel::Point_3;
using ExactMesh = BasicMesh<ExactPoint>;

/// The same mesh with exact coordinates (every double is a rational exactly).
ExactMesh to_exact(const Mesh& mesh);

/// The mesh with every coordinate rounded to the nearest double. Deterministic:
/// equal exact coordinates round to equal doubles, so pieces that share a vertex
/// fit together bit for bit.
Mesh to_fast(const ExactMesh& mesh);

/// A coordinate's nearest double (round-to-nearest, ties to even).
double round_to_double(const ExactKernel::FT& value);
Vec3 to_vec3(const ExactPoint& p);
inline Vec3 to_vec3(const Vec3& p) { return p; }

/// sign(n·p + d) for an exact point, exactly.
Sign side_of_plane(const Plane& plane, const ExactPoint& p);

/// The point where segment (a, b) meets the plane, and its parameter t along a->b
/// as a double (for interpolating attributes).
/// Preconditions: side_of_plane(a) and side_of_plane(b) are opposite and non-zero.
/// Fast kernel: rounded; symmetric in (a, b) up to the parameter (callers pass the
/// endpoints in a fixed order so both triangles of an edge get the same point).
/// Exact kernel: the exact intersection point.
struct CrossingVec3 {
  Vec3 point;
  double t;
};
struct CrossingExact {
  ExactPoint point;
  double t;
};
CrossingVec3 crossing_point(const Plane& plane, const Vec3& a, const Vec3& b);
CrossingExact crossing_point(const Plane& plane, const ExactPoint& a, const ExactPoint& b);

/// The exact rational position a rounded crossing stands for; a cap on rounded
/// crossings (the oracle's rounded cut) is rebuilt on these when rounding made it
/// invalid.
ExactPoint exact_crossing_point(const Plane& plane, const Vec3& a, const Vec3& b);

}  // namespace shatter
