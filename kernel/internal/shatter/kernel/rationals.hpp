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

/// The plane's exact coefficients (n_x, n_y, n_z, d): a cut's four doubles, or
/// the input plane through its three points, n = (p1 - p0) × (p2 - p0),
/// d = -n·p0 (implicit.hpp's file comment: the polynomials side() evaluates).
/// Cost: multi-precision, a few products.
std::array<mpq_class, 4> exact_plane_coefficients(const PlaneSet& set, PlaneRef plane);

/// The points within L1 distance `reach` of a plane n·x + d = 0, decided exactly.
/// A point's L1 distance to the plane is |n·x + d| / max |n_i| (the L1 norm's
/// dual is the largest |n_i|: the plane's nearest point lies along that axis),
/// so x lies within reach when |n·x + d| <= reach · max |n_i|. Rounding that
/// moves every vertex by at most rho (L1) can put a point within 2 rho of a
/// plane on its other side, and a face whose corners all lie within that reach
/// of a neighbour's plane bounds with it a wedge no thicker than the reach
/// (round_solid's thin folds, wedge split and strips ask this).
class PlaneReach {
 public:
  /// Preconditions: the normal (n_x, n_y, n_z) is not zero; reach >= 0.
  PlaneReach(const std::array<mpq_class, 4>& plane, const mpq_class& reach);
  /// The plane of the set (exact_plane_coefficients).
  PlaneReach(const PlaneSet& set, PlaneRef plane, const mpq_class& reach);
  /// An explicit plane of doubles, taken exactly.
  PlaneReach(const Plane& plane, const mpq_class& reach);

  struct Where {
    Sign side = Sign::zero;  ///< the exact sign of n·x + d
    bool within = false;     ///< |n·x + d| <= reach · max |n_i|
  };
  /// Where the point lies against the plane and its reach. Exact.
  Where locate(const std::array<mpq_class, 3>& x) const;
  /// The same for a point of doubles, on the doubles' exact values.
  Where locate(const Vec3& p) const;

 private:
  std::array<mpq_class, 4> plane_;
  mpq_class limit_;  // reach · max |n_i|
};

/// Six times the solid's volume, exactly: the divergence theorem over fans of its
/// faces, on the vertices' exact rational coordinates. Precondition: closed
/// (check_solid). For tests and audits, and for pieces too thin for doubles,
/// whose vertex approximations may coincide. Cost: multi-precision, O(corners).
mpq_class exact_six_volume(const PlaneSet& set, const Solid& solid);

}  // namespace shatter
