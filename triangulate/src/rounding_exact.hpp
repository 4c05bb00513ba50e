#pragma once
// The one part of the rounding (rounding.hpp) that names CGAL's exact points,
// apart so that the other sources do not parse CGAL's Epeck headers (some 5 s
// of compile a source, in each of CI's three builds).

#include "shatter/kernel/exact.hpp"
#include "shatter/kernel/implicit.hpp"

namespace shatter::rounding {

// The exact position a defined point stands for, as CGAL's exact point.
ExactPoint exact_point(const PlaneSet& set, const PointDef& def);

}  // namespace shatter::rounding
