#include "shatter/kernel/deepest_point.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

namespace shatter::kernel_detail {

namespace {

// Seidel's recursion: the optimum of the first i constraints is kept; when
// constraint i cuts it off, the new optimum lies on its hyperplane (the segment
// from the old optimum to any new one crosses it, at a point as good as the new
// one), so it is the optimum of a problem one dimension lower: constraint i's
// largest coefficient's variable eliminated from the objective, from the
// constraints before it and from that variable's own box.
// The lower problems' constraints, one array per dimension below the top
// (solve(d) fills lower[d - 2], which solve(d - 1) reads while it fills
// lower[d - 3]), kept between calls so no problem allocates.
thread_local std::array<std::vector<HalfSpace>, 3> lower_constraints;

bool solve(int d, std::span<const HalfSpace> constraints, const std::array<double, 4>& c, double box, double slack,
           std::array<double, 4>& x) {
  if (d == 1) {
    double lo = -box, hi = box;
    for (const HalfSpace& h : constraints) {
      const double a = h.a[0], b = h.b + slack;
      if (a > 0) {
        hi = std::min(hi, b / a);
      } else if (a < 0) {
        lo = std::max(lo, b / a);
      } else if (b < 0) {
        return false;
      }
    }
    if (!(lo <= hi)) return false;
    x[0] = c[0] > 0 ? hi : c[0] < 0 ? lo : 0.5 * (lo + hi);
    return true;
  }
  // The box's corner best for c (any point of the box where c's coefficient is 0).
  for (int j = 0; j < d; ++j) x[j] = c[j] > 0 ? box : c[j] < 0 ? -box : 0;
  std::vector<HalfSpace>& lower = lower_constraints[d - 2];
  for (std::size_t i = 0; i < constraints.size(); ++i) {
    const HalfSpace& h = constraints[i];
    double value = 0;
    for (int j = 0; j < d; ++j) value += h.a[j] * x[j];
    if (value <= h.b + slack) continue;
    int k = 0;
    for (int j = 1; j < d; ++j) {
      if (std::fabs(h.a[j]) > std::fabs(h.a[k])) k = j;
    }
    const double ak = h.a[k];
    if (!(std::fabs(ak) > 0)) return false;  // 0 <= b, cut off: b < -slack
    // x_k = (b - sum over j != k of a_j x_j) / a_k, substituted into g: h's
    // coefficients but k's, over a_k, then g's less g_k times those.
    const double inverse = 1 / ak;
    std::array<double, 4> ratio{};
    for (int j = 0, m = 0; j < d; ++j) {
      if (j != k) ratio[m++] = h.a[j] * inverse;
    }
    const double ratio_b = h.b * inverse;
    const auto eliminate = [&](const HalfSpace& g, HalfSpace& p) {
      const double f = g.a[k];
      for (int j = 0, m = 0; j < d; ++j) {
        if (j != k) {
          p.a[m] = g.a[j] - f * ratio[m];
          ++m;
        }
      }
      p.b = g.b - f * ratio_b;
    };
    HalfSpace up, down;  // x_k's box
    up.a[k] = 1;
    up.b = box;
    down.a[k] = -1;
    down.b = box;
    lower.resize(i + 2);
    eliminate(up, lower[0]);
    eliminate(down, lower[1]);
    for (std::size_t g = 0; g < i; ++g) eliminate(constraints[g], lower[g + 2]);
    std::array<double, 4> lower_c{};
    for (int j = 0, m = 0; j < d; ++j) {
      if (j != k) {
        lower_c[m] = c[j] - c[k] * ratio[m];
        ++m;
      }
    }
    std::array<double, 4> y{};
    if (!solve(d - 1, lower, lower_c, box, slack, y)) return false;
    double rest = h.b;
    for (int j = 0, m = 0; j < d; ++j) {
      if (j == k) continue;
      x[j] = y[m++];
      rest -= h.a[j] * x[j];
    }
    x[k] = rest / ak;
  }
  return true;
}

}  // namespace

std::optional<std::array<double, 4>> maximize_in_box(int d, std::span<const HalfSpace> constraints,
                                                    const std::array<double, 4>& c, double box, double slack) {
  if (d < 1 || d > 4 || !(box > 0) || !(slack >= 0)) return std::nullopt;
  std::array<double, 4> x{};
  if (!solve(d, constraints, c, box, slack, x)) return std::nullopt;
  return x;
}

std::optional<Vec3> deepest_inner_point(const Mesh& mesh) {
  const std::size_t n = mesh.positions.size();
  if (mesh.triangles.empty() || n == 0) return std::nullopt;
  Vec3 lo = mesh.positions.front(), hi = lo;
  for (const Vec3& p : mesh.positions) {
    if (!is_finite(p)) return std::nullopt;
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  // In the box's own frame, [-1, 1] on its longest side: the program's slack and
  // margin are then relative to the piece's size.
  const Vec3 centre = (lo + hi) * 0.5;
  const double scale = 0.5 * std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
  if (!(scale > 0) || !std::isfinite(scale) || !(1 / scale > 0)) return std::nullopt;
  const auto local = [&](VertexIndex v) { return (mesh.positions[v] - centre) * (1 / scale); };
  std::vector<HalfSpace> constraints;
  constraints.reserve(mesh.triangles.size());
  for (const Triangle& t : mesh.triangles) {
    if (t[0] >= n || t[1] >= n || t[2] >= n) return std::nullopt;
    const Vec3 a = local(t[0]);
    const Vec3 normal = cross(local(t[1]) - a, local(t[2]) - a);
    const double length = norm(normal);
    if (!(length > 0)) return std::nullopt;
    const Vec3 unit = normal * (1 / length);
    // unit·p + margin <= unit·a: p at least `margin` behind the triangle's plane.
    constraints.push_back({{unit.x, unit.y, unit.z, 1}, dot(unit, a)});
  }
  // Seidel's expected bound holds for a random order; a fixed seed keeps the
  // same mesh's point the same (xorshift64*, Vigna 2016).
  std::uint64_t state = 0x9E3779B97F4A7C15ull ^ constraints.size();
  const auto next = [&state] {
    state ^= state >> 12;
    state ^= state << 25;
    state ^= state >> 27;
    return state * 0x2545F4914F6CDD1Dull;
  };
  for (std::size_t i = constraints.size(); i > 1; --i) std::swap(constraints[i - 1], constraints[next() % i]);
  // Points within twice the unit box, margins up to as much: the deepest point
  // of the kernel lies in the piece's box, its margin at most the box's half side.
  constexpr double box = 2, slack = 0x1p-40;
  // A margin too thin to tell from the program's rounding makes no candidate.
  constexpr double thinnest = 0x1p-30;
  const std::array<double, 4> objective{0, 0, 0, 1};
  // Few constraints decide the optimum (four, in general position), so it is
  // found on a random sample, grown by every constraint its optimum cuts off
  // until none does (Clarkson's iterative sampling, J. ACM 42, 1995): a pass
  // over all of them is four products each, where Seidel's recursion copies
  // the constraints before every one it meets cut off. The same optimum value;
  // after a few rounds without convergence, Seidel's alone on all of them.
  constexpr std::size_t sample = 96, rounds = 8;
  std::optional<std::array<double, 4>> best;
  if (constraints.size() > 2 * sample) {
    std::vector<HalfSpace> working(constraints.begin(), constraints.begin() + sample);
    for (std::size_t round = 0; round < rounds; ++round) {
      best = maximize_in_box(4, working, objective, box, slack);
      // Fewer constraints allow at least as deep a point: too thin a margin
      // here is too thin for all of them.
      if (!best || !((*best)[3] > thinnest)) return std::nullopt;
      const std::size_t before = working.size();
      for (const HalfSpace& h : constraints) {
        const double value = h.a[0] * (*best)[0] + h.a[1] * (*best)[1] + h.a[2] * (*best)[2] + h.a[3] * (*best)[3];
        if (value > h.b + slack) working.push_back(h);
      }
      if (working.size() == before) break;
      best.reset();
      if (working.size() > constraints.size() / 2) break;
    }
  }
  if (!best) best = maximize_in_box(4, constraints, objective, box, slack);
  if (!best || !((*best)[3] > thinnest)) return std::nullopt;
  const Vec3 point = centre + Vec3{(*best)[0], (*best)[1], (*best)[2]} * scale;
  if (!is_finite(point)) return std::nullopt;
  return point;
}

}  // namespace shatter::kernel_detail
