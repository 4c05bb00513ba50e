// The readers' triangulation of a polygon face (io_internal.hpp): the fan where
// it is sound, ear clipping with exact orient2d where the fan folds.
#include <array>
#include <cmath>
#include <cstddef>
#include <vector>

#include "io_internal.hpp"
#include "shatter/kernel/predicates.hpp"

namespace shatter::io_detail {

std::vector<std::array<std::size_t, 3>> polygon_triangles(const std::vector<Vec3>& corners) {
  const std::size_t n = corners.size();
  std::vector<std::array<std::size_t, 3>> fan;
  for (std::size_t k = 1; k + 1 < n; ++k) fan.push_back({0, k, k + 1});
  if (n <= 3 || n > kMaxClippedCorners) return fan;

  // Newell's normal; its largest component names the axis projected away.
  double nx = 0, ny = 0, nz = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 a = corners[i], b = corners[(i + 1) % n];
    nx += (a.y - b.y) * (a.z + b.z);
    ny += (a.z - b.z) * (a.x + b.x);
    nz += (a.x - b.x) * (a.y + b.y);
  }
  if (!std::isfinite(nx) || !std::isfinite(ny) || !std::isfinite(nz)) return fan;
  const double ax = std::abs(nx), ay = std::abs(ny), az = std::abs(nz);
  std::vector<Vec2> p(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 c = corners[i];
    p[i] = az >= ax && az >= ay ? Vec2{c.x, c.y} : ax >= ay ? Vec2{c.y, c.z} : Vec2{c.z, c.x};
  }
  // The polygon's turn in the projection: that of its lowest-leftmost corner,
  // exactly (a corner of the hull; zero where the polygon is degenerate there).
  std::size_t low = 0;
  for (std::size_t i = 1; i < n; ++i) {
    if (p[i].y < p[low].y || (p[i].y == p[low].y && p[i].x < p[low].x)) low = i;
  }
  const Sign turn = orient2d(p[(low + n - 1) % n], p[low], p[(low + 1) % n]);
  if (turn == Sign::zero) return fan;
  bool fan_sound = true;
  for (const auto& [a, b, c] : fan) fan_sound = fan_sound && orient2d(p[a], p[b], p[c]) == turn;
  if (fan_sound) return fan;

  std::vector<std::size_t> left(n);
  for (std::size_t i = 0; i < n; ++i) left[i] = i;
  std::vector<std::array<std::size_t, 3>> triangles;
  const auto inside_or_on = [&](std::size_t a, std::size_t b, std::size_t c, std::size_t q) {
    return orient2d(p[a], p[b], p[q]) != flip(turn) && orient2d(p[b], p[c], p[q]) != flip(turn) &&
           orient2d(p[c], p[a], p[q]) != flip(turn);
  };
  while (left.size() > 3) {
    const std::size_t m = left.size();
    bool clipped = false;
    for (std::size_t i = 0; i < m && !clipped; ++i) {
      const std::size_t a = left[(i + m - 1) % m], b = left[i], c = left[(i + 1) % m];
      if (orient2d(p[a], p[b], p[c]) != turn) continue;
      bool ear = true;
      for (std::size_t j = 0; j < m && ear; ++j) {
        const std::size_t q = left[j];
        if (q != a && q != b && q != c) ear = !inside_or_on(a, b, c, q);
      }
      if (!ear) continue;
      triangles.push_back({a, b, c});
      left.erase(left.begin() + static_cast<std::ptrdiff_t>(i));
      clipped = true;
    }
    if (!clipped) {
      // Not simple in projection: the rest as a fan, as before.
      for (std::size_t k = 1; k + 1 < left.size(); ++k) triangles.push_back({left[0], left[k], left[k + 1]});
      return triangles;
    }
  }
  triangles.push_back({left[0], left[1], left[2]});
  return triangles;
}

}  // namespace shatter::io_detail
