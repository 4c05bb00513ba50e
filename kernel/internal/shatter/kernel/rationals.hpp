#pragma once
// The plane kernel's exact values as GMP rationals: the coordinates of a defined
// point (implicit.hpp) and the volume of a solid (solid.hpp). Not installed (the
// library's internal headers, kernel/internal/, are on the include path of the
// build and its tests only): the library's own sources use these where a decision
// needs the exact value itself rather than a sign (the exact triangulation of a
// piece's faces, the volume of a piece too thin for doubles), and the tests and
// audits compare against them. Installed headers name no GMP type.

#include <array>

#include <gmpxx.h>

#include "shatter/kernel/implicit.hpp"
#include "shatter/kernel/solid.hpp"

namespace shatter {

/// The point's exact coordinates (x/w, y/w, z/w) as GMP rationals (tests, audits,
/// and exact triangulations of a piece's faces).
/// Preconditions: as approximate(): the definition is sound.
/// Throws std::domain_error when the definition is degenerate (w = 0 exactly).
/// Cost: multi-precision, one evaluation of the homogeneous polynomials.
std::array<mpq_class, 3> exact_coordinates(const PlaneSet& set, const PointDef& point);

/// The exact homogeneous coordinates (x̃, ỹ, z̃, w) of the definition, as the
/// polynomials of implicit.hpp's file comment (w not normalised: its sign is the
/// polynomial's). For audits that check the bit-length bounds. Never divides, so
/// a degenerate definition gives w = 0 instead of throwing.
std::array<mpq_class, 4> exact_homogeneous(const PlaneSet& set, const PointDef& point);

/// Six times the solid's volume, exactly: the divergence theorem over fans of its
/// faces, on the vertices' exact rational coordinates. Precondition: closed
/// (check_solid). For tests and audits, and for pieces too thin for doubles,
/// whose vertex approximations may coincide. Cost: multi-precision, O(corners).
mpq_class exact_six_volume(const PlaneSet& set, const Solid& solid);

}  // namespace shatter
