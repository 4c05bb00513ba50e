#pragma once
// projection.hpp's projection for CGAL's exact points (Epeck): the same axes
// kept, the same orientation convention. Not installed (kernel/internal/).

#include "shatter/kernel/exact.hpp"
#include "shatter/kernel/projection.hpp"

namespace shatter {

/// `p` projected to the plane's two kept axes, exactly (dropping a coordinate).
inline ExactKernel::Point_2 project(const PlaneProjection& proj, const ExactPoint& p) {
  return {p.cartesian(proj.u_axis), p.cartesian(proj.v_axis)};
}

/// Orientation of triangle (a, b, c) seen from the +n side of the projection's
/// plane: positive when counter-clockwise. Exact.
inline Sign orientation_in_projection(const PlaneProjection& proj, const ExactPoint& a, const ExactPoint& b,
                                      const ExactPoint& c) {
  const CGAL::Orientation o = CGAL::orientation(project(proj, a), project(proj, b), project(proj, c));
  return o == CGAL::LEFT_TURN ? Sign::positive : o == CGAL::RIGHT_TURN ? Sign::negative : Sign::zero;
}

}  // namespace shatter
