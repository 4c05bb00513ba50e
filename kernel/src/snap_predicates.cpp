#include "shatter/kernel/snap_predicates.hpp"

#include <cmath>

namespace shatter {
namespace {

Sign sign_of(const mpq_class& value) {
  const int s = sgn(value);
  return s < 0 ? Sign::negative : s > 0 ? Sign::positive : Sign::zero;
}

}  // namespace

CoordinateReach::CoordinateReach(const mpq_class& reach) : reach_(reach), approximate_reach_(reach.get_d()) {}

bool CoordinateReach::within(double a, double b) const {
  const double difference = std::fabs(a - b);
  // The filters hold while the reach is a normal double (get_d truncates a
  // smaller one to a few bits, or to zero).
  if (approximate_reach_ < 0x1p-1000) return abs(mpq_class(a) - b) <= reach_;
  if (difference > approximate_reach_ * (1 + 0x1p-40)) return false;
  if (difference < approximate_reach_ * (1 - 0x1p-40)) return true;
  return abs(mpq_class(a) - b) <= reach_;
}

SegmentReach::SegmentReach(const mpq_class& reach)
    : reach_(reach), approximate_reach_(reach.get_d()), reach_is_zero_(sgn(reach) == 0) {}

bool SegmentReach::within(const Vec3& a, const Vec3& b, const Vec3& p) const {
  // Rejection in doubles, with an error bound: each component of the cross
  // product of the rounded differences is off the exact one by at most
  // (1 + u)^4 - 1 < 4.01 u times the sum of its two products' magnitudes (two
  // rounded differences, a product, a subtraction), plus what underflow loses;
  // the norm and the right side round by a few u more, which the factor 1.5
  // (against at most 1 + 10 u) covers. Overflow gives inf - inf = NaN, which
  // rejects nothing.
  const Vec3 dab = b - a, dap = p - a;
  const Vec3 c = cross(dab, dap);
  constexpr double u = 0x1p-53;
  const double rounding = 4.01 * u *
                              (std::fabs(dab.y * dap.z) + std::fabs(dab.z * dap.y) + std::fabs(dab.z * dap.x) +
                               std::fabs(dab.x * dap.z) + std::fabs(dab.x * dap.y) + std::fabs(dab.y * dap.x)) +
                          0x1p-1000;
  const double cross_lower = std::sqrt(dot(c, c)) * (1 - 8 * u) - rounding;
  const double length2 = dot(dab, dab), allowed = 1.5 * approximate_reach_ * std::sqrt(length2);
  // Where the right side lost bits to underflow it bounds nothing: decide exactly.
  const bool right_side_sound = reach_is_zero_ || (length2 >= 0x1p-1000 && allowed >= 0x1p-900);
  if (right_side_sound && cross_lower > allowed) return false;
  mpq_class ab[3], ap[3];
  for (int k = 0; k < 3; ++k) ab[k] = mpq_class(b[k]) - a[k], ap[k] = mpq_class(p[k]) - a[k];
  const mpq_class along = ab[0] * ap[0] + ab[1] * ap[1] + ab[2] * ap[2];
  const mpq_class exact_length2 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
  if (sgn(along) <= 0 || along >= exact_length2) return false;
  const mpq_class c0 = ab[1] * ap[2] - ab[2] * ap[1], c1 = ab[2] * ap[0] - ab[0] * ap[2],
                  c2 = ab[0] * ap[1] - ab[1] * ap[0];
  return c0 * c0 + c1 * c1 + c2 * c2 <= reach_ * reach_ * exact_length2;
}

bool projects_strictly_inside_segment(const Vec3& a, const Vec3& b, const Vec3& p) {
  mpq_class along_a = 0, along_b = 0;
  for (int k = 0; k < 3; ++k) {
    along_a += (mpq_class(p[k]) - a[k]) * (mpq_class(b[k]) - a[k]);
    along_b += (mpq_class(p[k]) - b[k]) * (mpq_class(a[k]) - b[k]);
  }
  return sgn(along_a) > 0 && sgn(along_b) > 0;
}

Sign compare_along_direction(const Vec3& from, const Vec3& to, const Vec3& p, const Vec3& q) {
  mpq_class t = 0;
  for (int k = 0; k < 3; ++k) t += (mpq_class(p[k]) - q[k]) * (mpq_class(to[k]) - from[k]);
  return sign_of(t);
}

Sign compare_distance_to(const Vec3& origin, const Vec3& p, const Vec3& q) {
  mpq_class dp = 0, dq = 0;
  for (int k = 0; k < 3; ++k) {
    const mpq_class u = mpq_class(p[k]) - origin[k], w = mpq_class(q[k]) - origin[k];
    dp += u * u;
    dq += w * w;
  }
  return sign_of(dp - dq);
}

Sign loops_orientation(std::span<const Vec3> positions, std::span<const std::vector<VertexIndex>> loops,
                       Projection projection) {
  const int u = (projection.axis + 1) % 3, w = (projection.axis + 2) % 3;
  mpq_class twice = 0;
  for (const auto& loop : loops) {
    for (std::size_t i = 0; i < loop.size(); ++i) {
      const Vec3 &p = positions[loop[i]], &q = positions[loop[(i + 1) % loop.size()]];
      twice += mpq_class(p[u]) * q[w] - mpq_class(q[u]) * p[w];
    }
  }
  const Sign s = sign_of(twice);
  return projection.flipped ? flip(s) : s;
}

}  // namespace shatter
