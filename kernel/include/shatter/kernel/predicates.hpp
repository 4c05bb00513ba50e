#pragma once
// Exact predicates on double coordinates.
//
// Every function here returns the sign of a polynomial in its double inputs as if
// it were evaluated in real arithmetic. Each first evaluates in floating point and
// compares the result against a proven error bound; only when the bound cannot
// certify the sign does it recompute with GMP rationals. Zero is a real answer.

#include <cstdint>

#include "shatter/kernel/vec.hpp"

namespace shatter {

/// Which side of `plane` the point p lies on: sign(n·p + d), exactly.
/// Preconditions: all inputs finite. Guarantees: the exact sign of the real value.
Sign side_of_plane(const Plane& plane, Vec3 p);

/// Sign of the 2D orientation determinant of (a, b, c): positive when the
/// triangle turns counter-clockwise. Preconditions: finite inputs. Exact.
Sign orient2d(Vec2 a, Vec2 b, Vec2 c);

/// Counters of how often the floating-point filters had to fall back to exact
/// arithmetic; per thread, so readers need no locking. Used by the predicate
/// audit and the benchmarks.
struct PredicateCounters {
  std::uint64_t side_of_plane_calls = 0;
  std::uint64_t side_of_plane_exact = 0;
};
PredicateCounters& predicate_counters();

}  // namespace shatter
