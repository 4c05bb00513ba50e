#pragma once
// The orientation predicate's references for the tests and the fuzz target:
// the determinant in GMP rationals (exact for any finite double), and the
// spread of a coordinate column as orient3d's integer stage defines it
// (kernel/internal/shatter/kernel/integer_orient.hpp), measured another way.

#include <gmpxx.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "shatter/kernel/predicates.hpp"
#include "shatter/kernel/vec.hpp"

namespace shatter::test {

/// det[b - a, c - a, d - a] in rationals: orient3d's sign, exact for any finite double.
inline Sign reference_orient3d(Vec3 a, Vec3 b, Vec3 c, Vec3 d) {
  const mpq_class m[3][3] = {{mpq_class(b.x) - a.x, mpq_class(b.y) - a.y, mpq_class(b.z) - a.z},
                             {mpq_class(c.x) - a.x, mpq_class(c.y) - a.y, mpq_class(c.z) - a.z},
                             {mpq_class(d.x) - a.x, mpq_class(d.y) - a.y, mpq_class(d.z) - a.z}};
  const mpq_class det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                        m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                        m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  return sgn(det) < 0 ? Sign::negative : sgn(det) > 0 ? Sign::positive : Sign::zero;
}

/// An orient3d sign in Shewchuk's convention (+1 where orient3d says negative),
/// as orient3d_by_integers answers.
inline int shewchuk_sign(Sign s) { return s == Sign::positive ? -1 : s == Sign::negative ? 1 : 0; }

/// The spread of a column of finite coordinates: from the least significant set
/// bit of any of them (frexp, then the fraction's trailing zeros) to the top of
/// the largest magnitude (ilogb + 1); 0 for a column of zeros.
inline int column_spread(const std::array<double, 4>& column) {
  int least = 0, top = 0;
  bool any = false;
  for (const double v : column) {
    if (v == 0) continue;
    int exponent = 0;
    double fraction = std::fabs(std::frexp(v, &exponent));  // v = fraction * 2^exponent
    int low = exponent;
    while (fraction != std::floor(fraction)) fraction *= 2, --low;  // fraction * 2^k is an integer from here
    least = any ? std::min(least, low) : low;
    top = any ? std::max(top, std::ilogb(v) + 1) : std::ilogb(v) + 1;
    any = true;
  }
  return any ? top - least : 0;
}

}  // namespace shatter::test
