#pragma once
// Exact predicates on double coordinates.
//
// Every function here returns the sign of a polynomial in its double inputs as if
// it were evaluated in real arithmetic. Each first evaluates in floating point and
// compares the result against a proven error bound; only when the bound cannot
// certify the sign does it recompute exactly (orient3d on double expansions, the
// others with GMP rationals). Zero is a real answer.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "shatter/kernel/vec.hpp"

namespace shatter {

/// Which side of `plane` the point p lies on: sign(n·p + d), exactly.
/// Preconditions: all inputs finite. Guarantees: the exact sign of the real value.
Sign side_of_plane(const Plane& plane, Vec3 p);

/// Sign of the 2D orientation determinant of (a, b, c): positive when the
/// triangle turns counter-clockwise. Preconditions: finite inputs. Exact.
Sign orient2d(Vec2 a, Vec2 b, Vec2 c);

/// Sign of the orientation of the tetrahedron (a, b, c, d): positive when d lies
/// on the side of the plane through a, b, c that (b - a) x (c - a) points to, zero
/// when the four points are coplanar (CGAL's orientation(a, b, c, d); the opposite
/// of the sign Shewchuk's orient3d returns).
/// Preconditions: finite inputs.
/// Guarantees: the exact sign of det[b - a, c - a, d - a] over the reals, for every
/// finite input. A floating-point filter decides most queries; where it cannot
/// (nearly or exactly coplanar points), the determinant is evaluated exactly in
/// double-expansion arithmetic, with no allocation. Only inputs outside the range
/// where that arithmetic is exact (some coordinate of magnitude 2^300 or more, or
/// nonzero and below 2^-300) go to GMP rationals; the counters below say how often.
/// Failure: none (NaN or infinite input is outside the precondition).
Sign orient3d(Vec3 a, Vec3 b, Vec3 c, Vec3 d);

/// orient3d's floating-point filter alone: its sign when the filter certifies it,
/// nullopt when it cannot (nearly or exactly coplanar points, or coordinates of
/// magnitude 2^300 or more). For a quick rejection that has a cheaper exact test
/// behind it than orient3d's expansion stages (exactly coplanar neighbours in a
/// self-intersection test). Preconditions: finite inputs. Failure: none.
std::optional<Sign> orient3d_if_clear(Vec3 a, Vec3 b, Vec3 c, Vec3 d);

/// For four coplanar points with p, q, r not collinear: positive when r and s lie
/// on the same side of the line pq in their plane, negative when on opposite
/// sides, zero when s lies on the line (CGAL's coplanar_orientation(p, q, r, s)).
/// Decided by orient2d in a coordinate projection where (p, q, r) does not
/// degenerate: such a projection maps the plane one to one and keeps or reverses
/// every orientation alike, so the product of the two signs is the answer.
/// Preconditions: finite inputs, the four points coplanar (orient3d zero), p, q, r
/// not collinear. Guarantees: exact. Failure: none (zero for collinear p, q, r,
/// which is outside the precondition).
Sign coplanar_orientation(Vec3 p, Vec3 q, Vec3 r, Vec3 s);

/// Whether a, b and c lie on one line (two or three of them may coincide):
/// every coordinate projection of them is collinear, decided by orient2d.
/// Preconditions: finite inputs. Guarantees: exact. Failure: none.
bool collinear(Vec3 a, Vec3 b, Vec3 c);

/// Whether p lies on the segment from a to b and is neither of its ends: collinear
/// with them, and strictly between them along the first coordinate where a and b
/// differ (on a line through two distinct points every such coordinate orders
/// the points alike; comparing doubles is exact). False when a == b.
/// Preconditions: finite inputs. Guarantees: exact. Failure: none.
bool strictly_inside_segment(Vec3 a, Vec3 b, Vec3 p);

/// Whether p lies strictly inside the triangle (a, b, c), whichever way the
/// triangle turns: orient2d of p against its three edges has one non-zero sign.
/// False for p on an edge or a corner, and for a flat triangle.
/// Preconditions: finite inputs. Guarantees: exact. Failure: none.
bool strictly_inside_triangle(Vec2 a, Vec2 b, Vec2 c, Vec2 p);

/// The points `around` ordered by their angle about the oriented line from a to
/// b, counter-clockwise seen from b looking at a (the right-hand turn about b - a),
/// starting with around[0]: indices into `around`. Every comparison is an exact
/// orientation (orient3d, and coplanar_orientation for points in one plane with
/// the line), as CGAL's sorted_around_edge orders the faces around an edge in
/// its corefinement. Returns nullopt when two points lie in one half-plane bounded
/// by the line (equal angles: no strict order) or one lies on the line.
/// Preconditions: finite inputs, a != b. Cost: O(k log k) orientations for k
/// points. Failure: none.
std::optional<std::vector<std::size_t>> order_around_line(Vec3 a, Vec3 b, std::span<const Vec3> around);

/// Counters of how often the floating-point filters had to fall back to exact
/// arithmetic; per thread, so readers need no locking. Used by the predicate
/// audit and the benchmarks.
struct PredicateCounters {
  std::uint64_t side_of_plane_calls = 0;
  std::uint64_t side_of_plane_exact = 0;
  std::uint64_t orient3d_calls = 0;
  std::uint64_t orient3d_expansion = 0;  ///< the filter deferred to exact arithmetic (integers or expansions)
  std::uint64_t orient3d_integer = 0;    ///< of those, decided on integers (coordinates of one scale)
  std::uint64_t orient3d_full = 0;       ///< of the rest, the adaptive stages did not decide either
  std::uint64_t orient3d_gmp = 0;        ///< outside the expansions' exact range: GMP
};
PredicateCounters& predicate_counters();

}  // namespace shatter
