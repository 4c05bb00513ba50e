#pragma once
// The angular sort about an oriented line, written once for every point type
// that can answer its two exact questions: order_around_line (predicates.cpp,
// on doubles) and order_around_exact (on exact rationals: order_around_edge's
// plane-based points, and the faces around an arrangement's edges when its
// cells' winding numbers are propagated).

#include <gmpxx.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <optional>
#include <span>
#include <vector>

#include "shatter/kernel/vec.hpp"

namespace shatter::kernel_detail {

/// The k points ordered by their angle about an oriented line, counter-clockwise
/// seen from its head (the right-hand turn), starting with point 0. `turn(i, j)`:
/// the exact sign of orient3d(a, b, p_i, p_j) for the line a -> b (positive when
/// the right-hand turn from p_i reaches p_j in less than a half turn). `ray(i)`,
/// asked only for a point on the plane through the line and p_0: positive when it
/// lies on p_0's side of the line, negative on the other, zero on the line.
/// Returns nullopt when two points share a half-plane bounded by the line (no
/// strict order) or one lies on the line. O(k log k) calls.
template <class Turn, class Ray>
std::optional<std::vector<std::size_t>> order_by_half_turns(std::size_t k, const Turn& turn, const Ray& ray) {
  std::vector<std::size_t> order(k);
  for (std::size_t i = 0; i < k; ++i) order[i] = i;
  if (k == 0) return order;
  // Half-turns from point 0: 0 on its own ray, 1 in the open half-space ahead
  // (turn(0, i) > 0), 2 on the opposite ray, 3 behind. A point on the line has
  // no angle.
  std::vector<int> half(k);
  for (std::size_t i = 0; i < k; ++i) {
    const Sign o = i == 0 ? Sign::zero : turn(0, i);
    if (o == Sign::positive) {
      half[i] = 1;
    } else if (o == Sign::negative) {
      half[i] = 3;
    } else {
      const Sign same = ray(i);
      if (same == Sign::zero) return std::nullopt;
      half[i] = same == Sign::positive ? 0 : 2;
    }
  }
  // Within one open half-space every two angles differ by less than a half turn,
  // so the orientation of the pair orders them; on a ray, all share one angle.
  bool tie = false;
  std::sort(order.begin(), order.end(), [&](std::size_t i, std::size_t j) {
    if (half[i] != half[j]) return half[i] < half[j];
    if (i == j) return false;
    if (half[i] == 0 || half[i] == 2) {
      tie = true;
      return i < j;
    }
    const Sign o = turn(i, j);
    if (o == Sign::zero) {
      tie = true;
      return i < j;
    }
    return o == Sign::positive;
  });
  if (tie) return std::nullopt;
  return order;
}

/// order_by_half_turns about the line from a to b for points given by their
/// exact rational coordinates (an arrangement's plane-based points). Exact:
/// rational determinants. Precondition: a != b.
inline std::optional<std::vector<std::size_t>> order_around_exact(const std::array<mpq_class, 3>& a,
                                                                  const std::array<mpq_class, 3>& b,
                                                                  std::span<const std::array<mpq_class, 3>> around) {
  using Q3 = std::array<mpq_class, 3>;
  const std::size_t k = around.size();
  if (k == 0) return std::vector<std::size_t>{};
  const auto minus = [](const Q3& x, const Q3& y) { return Q3{x[0] - y[0], x[1] - y[1], x[2] - y[2]}; };
  const auto dot = [](const Q3& x, const Q3& y) { return mpq_class(x[0] * y[0] + x[1] * y[1] + x[2] * y[2]); };
  const Q3 d = minus(b, a);
  const mpq_class dd = dot(d, d);
  std::vector<Q3> from(k);
  for (std::size_t i = 0; i < k; ++i) from[i] = minus(around[i], a);
  // det[d, u, v]: orient3d(a, b, a + u, a + v)'s value.
  const auto turn = [&](std::size_t i, std::size_t j) {
    const Q3 &u = from[i], &v = from[j];
    const mpq_class det =
        d[0] * (u[1] * v[2] - u[2] * v[1]) - d[1] * (u[0] * v[2] - u[2] * v[0]) + d[2] * (u[0] * v[1] - u[1] * v[0]);
    return static_cast<Sign>(sgn(det));
  };
  // The component of u across the line, times d·d (a positive factor).
  const auto across = [&](const Q3& u) {
    const mpq_class along = dot(u, d);
    return Q3{u[0] * dd - d[0] * along, u[1] * dd - d[1] * along, u[2] * dd - d[2] * along};
  };
  const Q3 first = across(from[0]);
  return order_by_half_turns(k, turn, [&](std::size_t i) { return static_cast<Sign>(sgn(dot(first, across(from[i])))); });
}

}  // namespace shatter::kernel_detail
