#pragma once
// orient3d's integer stage (predicates.cpp): the sign of the orientation
// determinant computed exactly in 64-, 128- and 192-bit integers, for the
// points of one scale that nearly all the filter's undecided queries are (the
// hull points of a fragment, a cap's corners rounded from one plane).
//
// Why it is exact: scaling a column of a determinant by a positive number
// scales the determinant by it, so the sign is kept when each column (x, y, z)
// of the four points is divided by a power of two. Each coordinate is an odd
// integer times a power of two; dividing a column by its least such power
// leaves integers, and when every one of them is below 2^61 in magnitude the
// differences are below 2^62, each 2x2 minor below 2^125 (a signed 128-bit
// integer), each term of the expansion along z below 2^187 and their sum below
// 2^189 (a signed 192-bit integer): no step rounds or overflows.
//
// Not installed (kernel/internal/): a stage of orient3d, separate so that its
// tests can reach it directly, not through the filter.

#include <optional>

#include "shatter/kernel/vec.hpp"

namespace shatter {

/// Whether the compiler has the 128-bit integers the stage needs (GCC and
/// Clang do); without them orient3d_by_integers never answers and orient3d
/// goes to its expansions as before.
#if defined(__SIZEOF_INT128__)
inline constexpr bool integer_orient_available = true;
#else
inline constexpr bool integer_orient_available = false;
#endif

/// The sign of det[a - d, b - d, c - d] (Shewchuk's convention: +1, 0 or -1,
/// the opposite of orient3d's Sign) when every column of the four points, x, y
/// and z apart, is integers below 2^61 times one power of two (the spread of
/// each column, from its least significant set bit to its largest magnitude,
/// at most 61 bits) and integer_orient_available; nothing otherwise.
/// Preconditions: finite coordinates, each zero or normal (no subnormal).
/// Guarantees: exact. Failure: none (nothing outside its range).
std::optional<int> orient3d_by_integers(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

}  // namespace shatter
