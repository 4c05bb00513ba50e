#include "shatter/kernel/self_intersections.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <CGAL/box_intersection_d.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "shatter/kernel/predicates.hpp"
#include "shatter/kernel/self_intersections_detail.hpp"
#include "triangle_boxes.hpp"

namespace shatter {
namespace {

// orient2d, its floating-point filter inlined: the projection test below asks
// up to twenty orientations per pair, and on the flat faces of CAD meshes it is
// the hot path. Shewchuk's bound (3u + 16u^2 times the sum of the two products'
// magnitudes) widened to 4u, plus 2^-1000 for products that underflow (each errs
// by at most 2^-1075 then); an overflow makes the bound infinite or the
// determinant NaN, and both defer. Undecided queries go to orient2d, which is exact.
Sign orient2d_quick(const Vec2& a, const Vec2& b, const Vec2& c) {
  const double left = (a.x - c.x) * (b.y - c.y), right = (a.y - c.y) * (b.x - c.x);
  const double det = left - right;
  const double bound = 4 * 0x1p-53 * (std::fabs(left) + std::fabs(right)) + 0x1p-1000;
  if (det > bound) return Sign::positive;
  if (-det > bound) return Sign::negative;
  return orient2d(a, b, c);
}

// Whether the projections of two triangles, dropping `axis`, are both proper
// triangles and apart except at shared corners: some edge line of one has every
// corner of the other strictly outside it (corners they share excepted). Then
// each triangle meets every line along `axis` at most once, so the two can share
// no point but their shared corners, whatever their heights. Exact (orient2d on
// the doubles). Nearly coplanar neighbours, which would send orient3d to exact
// arithmetic, are settled here.
bool projections_apart(std::span<const Vec3> positions, const Triangle& a, const Triangle& b, int axis) {
  const int i = (axis + 1) % 3, j = (axis + 2) % 3;
  const auto p2 = [&](VertexIndex v) { return Vec2{positions[v][i], positions[v][j]}; };
  const Vec2 pa[3] = {p2(a[0]), p2(a[1]), p2(a[2])}, pb[3] = {p2(b[0]), p2(b[1]), p2(b[2])};
  const Sign turn_a = orient2d_quick(pa[0], pa[1], pa[2]), turn_b = orient2d_quick(pb[0], pb[1], pb[2]);
  if (turn_a == Sign::zero || turn_b == Sign::zero) return false;
  const auto separates = [&](const Vec2* p, const Triangle& t, Sign turn, const Vec2* q, const Triangle& u) {
    for (int e = 0; e < 3; ++e) {
      bool outside = true;
      for (int k = 0; k < 3 && outside; ++k) {
        if (u[k] == t[e] || u[k] == t[(e + 1) % 3]) continue;  // a shared corner
        const Sign s = orient2d_quick(p[e], p[(e + 1) % 3], q[k]);
        outside = s != Sign::zero && s != turn;
      }
      if (outside) return true;
    }
    return false;
  };
  return separates(pa, a, turn_a, pb, b) || separates(pb, b, turn_b, pa, a);
}

// Whether triangle b, but for the corners it shares with a, lies strictly on one
// side of a's plane (so it meets a at most in their shared corners), as far as
// orient3d's filter certifies: a quick rejection. Undecided queries (mostly
// exactly coplanar neighbours of one face) go on to projections_apart, which
// settles them more cheaply than orient3d's expansion stages would (asking
// orient3d here made fandisk x4 -> 256's cutting 40 % slower).
bool strictly_beside(std::span<const Vec3> positions, const Triangle& a, const Triangle& b) {
  const Vec3& p = positions[a[0]];
  const Vec3& q = positions[a[1]];
  const Vec3& r = positions[a[2]];
  Sign side = Sign::zero;
  for (const VertexIndex v : b) {
    if (v == a[0] || v == a[1] || v == a[2]) continue;
    const std::optional<Sign> s = orient3d_if_clear(p, q, r, positions[v]);
    if (!s || (side != Sign::zero && *s != side)) return false;
    side = *s;
  }
  return side != Sign::zero;
}

}  // namespace

// Whether two triangles of a mesh meet beyond the vertices and edge they share,
// exactly (the test of CGAL's self_intersections, on a triangle soup): sharing an
// edge, only when coplanar and on one side of it; sharing a vertex, when the edge
// of either opposite the vertex meets the other; otherwise, when they meet. Tried
// first, cheapest first: one triangle strictly beside the other's plane (the
// filter of the kernel's orient3d), then their projections apart along the axis of a's largest normal
// component (exact 2D orientations, which settle nearly coplanar neighbours).
bool triangles_intersect(std::span<const Vec3> positions, const Triangle& a, const Triangle& b) {
  using K = CGAL::Epick;
  if (strictly_beside(positions, a, b) || strictly_beside(positions, b, a)) return false;
  {
    const Vec3 n = cross(positions[a[1]] - positions[a[0]], positions[a[2]] - positions[a[0]]);
    const double ax = std::fabs(n.x), ay = std::fabs(n.y), az = std::fabs(n.z);
    const int axis = ax >= ay && ax >= az ? 0 : ay >= az ? 1 : 2;
    if (projections_apart(positions, a, b, axis)) return false;
  }
  const auto point = [&](VertexIndex v) {
    const Vec3& p = positions[v];
    return K::Point_3(p.x, p.y, p.z);
  };
  int shared = 0, shared_a = -1, shared_b = -1;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (a[i] != b[j]) continue;
      ++shared;
      if (shared_a < 0) shared_a = i, shared_b = j;
    }
  }
  if (shared >= 3) return true;  // the same triangle twice
  if (shared == 2) {
    // The vertex of each not on the shared edge.
    int ia = 0, ib = 0;
    for (int i = 0; i < 3; ++i) {
      if (a[i] != b[0] && a[i] != b[1] && a[i] != b[2]) ia = i;
      if (b[i] != a[0] && b[i] != a[1] && b[i] != a[2]) ib = i;
    }
    const K::Point_3 u = point(a[(ia + 1) % 3]), v = point(a[(ia + 2) % 3]), p = point(a[ia]), q = point(b[ib]);
    return CGAL::coplanar(u, v, p, q) && CGAL::coplanar_orientation(u, v, p, q) == CGAL::POSITIVE;
  }
  const K::Triangle_3 ta(point(a[0]), point(a[1]), point(a[2])), tb(point(b[0]), point(b[1]), point(b[2]));
  if (shared == 1) {
    const K::Segment_3 sa(point(a[(shared_a + 1) % 3]), point(a[(shared_a + 2) % 3]));
    const K::Segment_3 sb(point(b[(shared_b + 1) % 3]), point(b[(shared_b + 2) % 3]));
    return CGAL::do_intersect(ta, sb) || CGAL::do_intersect(tb, sa);
  }
  return CGAL::do_intersect(ta, tb);
}


namespace {

using detail::box_of;
using detail::TriangleBox;

void sort_unique(std::vector<TrianglePair>& pairs) {
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
}

// A triangle's bounding box in floats, rounded outward: it contains the exact
// box, so two triangles that meet have float boxes that meet. Half the memory of
// doubles, which is what the grid's random accesses pay for; the boxes only pick
// candidates, every decision is triangles_intersect's.
struct FloatBox {
  float lo[3], hi[3];
};

float round_down(double x) {
  const float f = static_cast<float>(x);
  return static_cast<double>(f) > x ? std::nextafter(f, -std::numeric_limits<float>::infinity()) : f;
}
float round_up(double x) {
  const float f = static_cast<float>(x);
  return static_cast<double>(f) < x ? std::nextafter(f, std::numeric_limits<float>::infinity()) : f;
}

bool boxes_meet(const FloatBox& a, const FloatBox& b) {
  return a.lo[0] <= b.hi[0] && b.lo[0] <= a.hi[0] && a.lo[1] <= b.hi[1] && b.lo[1] <= a.hi[1] &&
         a.lo[2] <= b.hi[2] && b.lo[2] <= a.hi[2];
}

// The grid: cell k along an axis holds the coordinates x with
// cell_of(x) == k. cell_of is monotone in x (a rounded subtraction and
// multiplication by a positive number, a clamp and a truncation are each
// monotone), which is all the search needs: a box [lo, hi] is entered in the
// cells cell_of(lo) .. cell_of(hi), and the low corner of the overlap of two
// boxes that meet lies in a cell both were entered in. No tolerance is involved.
struct Grid {
  double origin[3] = {0, 0, 0};
  double inverse_cell = 0;
  static constexpr std::uint32_t max_cell = (1u << 21) - 1;

  std::uint32_t cell_of(float x, int axis) const {
    double t = (static_cast<double>(x) - origin[axis]) * inverse_cell;
    t = std::clamp(t, 0.0, static_cast<double>(max_cell));  // also maps -inf and +inf in range
    return static_cast<std::uint32_t>(t);
  }
  // Cells are hashed into buckets; distinct cells sharing a bucket only add
  // candidates, which the box test and the pair rule below drop.
  static std::uint64_t bucket_of(std::uint32_t x, std::uint32_t y, std::uint32_t z, std::uint64_t mask) {
    std::uint64_t h = x * 0x9E3779B97F4A7C15ull ^ y * 0xC2B2AE3D27D4EB4Full ^ z * 0x165667B19E3779F9ull;
    h ^= h >> 29;
    return h & mask;
  }
};

// A box that spans more than this many cells is searched with the box tree
// instead: a few long triangles would otherwise fill thousands of cells.
constexpr std::uint64_t max_cells_per_box = 64;

// A triangle's bounds along each axis in doubles, and its largest extent (the
// grid's cell is a multiple of the mean of these): what the serial and the
// blocked passes over the triangles both read.
struct TriangleBounds {
  double lo[3], hi[3], largest;
};

TriangleBounds triangle_bounds(std::span<const Vec3> positions, const Triangle& tri) {
  const Vec3& p = positions[tri[0]];
  const Vec3& q = positions[tri[1]];
  const Vec3& r = positions[tri[2]];
  TriangleBounds bounds{{}, {}, 0};
  for (int axis = 0; axis < 3; ++axis) {
    bounds.lo[axis] = std::min({p[axis], q[axis], r[axis]});
    bounds.hi[axis] = std::max({p[axis], q[axis], r[axis]});
    bounds.largest = std::max(bounds.largest, bounds.hi[axis] - bounds.lo[axis]);
  }
  return bounds;
}

// The float boxes of `count` triangles (triangle_at(k) is the k-th) and the grid
// both searches use, anchored at their lowest corner, with cells three times the
// mean box size: most boxes fall in one to eight cells, and a cell holds a few
// triangles. On the benchmark sphere (1.3 M triangles) 1, 1.5, 2, 3, 4 and 6 times
// took 1.50, 1.16, 0.97, 0.88, 0.87 and 0.83 us per triangle, fandisk 0.94 to
// 0.87 with 3 the best there. nullopt when no cell size is usable (coordinates at
// the extremes of double): the caller then searches with the box tree.
template <class TriangleAt>
std::optional<Grid> boxes_and_grid(std::span<const Vec3> positions, std::size_t count, TriangleAt&& triangle_at,
                                   std::vector<FloatBox>& boxes) {
  boxes.resize(count);
  double lowest[3] = {INFINITY, INFINITY, INFINITY};
  double extent_sum = 0;
  for (std::size_t k = 0; k < count; ++k) {
    const TriangleBounds bounds = triangle_bounds(positions, triangle_at(k));
    for (int axis = 0; axis < 3; ++axis) {
      boxes[k].lo[axis] = round_down(bounds.lo[axis]);
      boxes[k].hi[axis] = round_up(bounds.hi[axis]);
      lowest[axis] = std::min(lowest[axis], bounds.lo[axis]);
    }
    extent_sum += bounds.largest;
  }
  const double cell = 3 * extent_sum / static_cast<double>(count);
  if (!(cell > 0) || !std::isfinite(cell) || !(1 / cell > 0) || !std::isfinite(1 / cell)) return std::nullopt;
  Grid grid;
  grid.inverse_cell = 1 / cell;
  for (int axis = 0; axis < 3; ++axis) grid.origin[axis] = lowest[axis];
  return grid;
}

// The cells a box spans along each axis.
struct CellRange {
  std::uint32_t lo[3], hi[3];
};

// Each box's cell range, and whether it spans more than max_cells_per_box cells
// (set aside for the box tree); returns the cells of the others, counted with
// multiplicity (the grid's entries).
std::uint64_t cell_ranges(const Grid& grid, const std::vector<FloatBox>& boxes, std::vector<CellRange>& ranges,
                          std::vector<std::uint8_t>& is_large) {
  ranges.resize(boxes.size());
  is_large.assign(boxes.size(), 0);
  std::uint64_t entries = 0;
  for (std::size_t k = 0; k < boxes.size(); ++k) {
    std::uint64_t cells = 1;
    for (int axis = 0; axis < 3; ++axis) {
      ranges[k].lo[axis] = grid.cell_of(boxes[k].lo[axis], axis);
      ranges[k].hi[axis] = grid.cell_of(boxes[k].hi[axis], axis);
      cells *= ranges[k].hi[axis] - ranges[k].lo[axis] + 1;
    }
    if (cells > max_cells_per_box) {
      is_large[k] = 1;
    } else {
      entries += cells;
    }
  }
  return entries;
}

// Calls visit(bucket) for every cell of `range`.
template <class Visit>
void for_each_bucket(const CellRange& range, std::uint64_t mask, Visit&& visit) {
  for (std::uint32_t x = range.lo[0]; x <= range.hi[0]; ++x) {
    for (std::uint32_t y = range.lo[1]; y <= range.hi[1]; ++y) {
      for (std::uint32_t z = range.lo[2]; z <= range.hi[2]; ++z) visit(Grid::bucket_of(x, y, z, mask));
    }
  }
}

}  // namespace

namespace {

// Runs body(begin, end) over [0, count): on the calling thread alone when the
// enclosing arena has one thread or the range is one grain, else in blocks of at
// least `grain` on the arena's threads. Callers make their result independent of
// how the range is split.
template <class Body>
void for_blocks(std::size_t count, std::size_t grain, Body&& body) {
  if (count <= grain || tbb::this_task_arena::max_concurrency() <= 1) {
    if (count > 0) body(std::size_t{0}, count);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, grain),
                    [&](const tbb::blocked_range<std::size_t>& r) { body(r.begin(), r.end()); });
}

// Reductions whose result must not depend on the thread count (a sum of
// doubles) are made per block of this many triangles, then over the blocks in
// order.
constexpr std::size_t reduction_block = std::size_t{1} << 14;

// The low 10 bits of v spread to every third bit: one coordinate's part of a
// Morton code.
std::uint32_t spread_bits(std::uint32_t v) {
  v &= 0x3FF;
  v = (v | v << 16) & 0x030000FF;
  v = (v | v << 8) & 0x0300F00F;
  v = (v | v << 4) & 0x030C30C3;
  v = (v | v << 2) & 0x09249249;
  return v;
}

// The bits of each cell coordinate a triangle's Morton key keeps (its top ones):
// at most 2^18 keys, a counting sort's table of 1 MiB. A mesh of n triangles
// keeps about n keys (a table no larger than the mesh): the table is cleared and
// scanned on every call, and the many small meshes certification checks (a cut
// piece, a cap's neighbourhood) paid for 2^18 keys each.
constexpr int max_key_bits_per_axis = 6;

int key_bits_per_axis_for(std::size_t triangle_count) {
  return std::clamp((static_cast<int>(std::bit_width(triangle_count)) + 2) / 3, 1, max_key_bits_per_axis);
}

// A bucket's triangles, copied out for its pair search: their float boxes and
// low cells side by side (structure of arrays, so the box test of one against
// the rest vectorizes), and their triangle indices.
struct BucketScratch {
  std::vector<float> lo[3], hi[3];
  std::vector<std::uint32_t> cell[3], triangle;
  std::vector<std::uint8_t> meet;

  void resize(std::size_t size) {
    if (triangle.size() >= size) return;
    for (int axis = 0; axis < 3; ++axis) {
      lo[axis].resize(size);
      hi[axis].resize(size);
      cell[axis].resize(size);
    }
    triangle.resize(size);
    meet.resize(size);
  }
};

}  // namespace

std::vector<TrianglePair> self_intersecting_pairs(std::span<const Vec3> positions, std::span<const Triangle> triangles) {
  return detail::self_intersecting_pairs_in_blocks(positions, triangles, reduction_block);
}

std::vector<TrianglePair> detail::self_intersecting_pairs_in_blocks(std::span<const Vec3> positions,
                                                                    std::span<const Triangle> triangles,
                                                                    std::size_t block) {
  std::vector<TrianglePair> pairs;
  const std::size_t count = triangles.size();
  block = std::max<std::size_t>(block, 1);
  if (count < 2) return pairs;
  if (count > std::numeric_limits<std::uint32_t>::max()) return self_intersecting_pairs_by_box_tree(positions, triangles);
  const auto box_of_triangle = [&](std::size_t t) {
    const Triangle& tri = triangles[t];
    const Vec3& p = positions[tri[0]];
    const Vec3& q = positions[tri[1]];
    const Vec3& r = positions[tri[2]];
    FloatBox box;
    for (int axis = 0; axis < 3; ++axis) {
      box.lo[axis] = round_down(std::min({p[axis], q[axis], r[axis]}));
      box.hi[axis] = round_up(std::max({p[axis], q[axis], r[axis]}));
    }
    return box;
  };

  // The grid: anchored at the lowest corner, cells three times the mean largest
  // extent of a triangle's box. The extents are summed per fixed block, then the
  // blocks in order, so the cell size does not depend on the thread count (nor
  // would the pairs: any cell size finds the same ones).
  const std::size_t blocks = (count + block - 1) / block;
  struct Extent {
    double lowest[3], highest[3], sum;
  };
  std::vector<Extent> extents(blocks);
  for_blocks(blocks, 1, [&](std::size_t first, std::size_t last) {
    for (std::size_t k = first; k < last; ++k) {
      Extent part{{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}, 0};
      for (std::size_t t = k * block; t < std::min(count, (k + 1) * block); ++t) {
        const TriangleBounds bounds = triangle_bounds(positions, triangles[t]);
        for (int axis = 0; axis < 3; ++axis) {
          part.lowest[axis] = std::min(part.lowest[axis], bounds.lo[axis]);
          part.highest[axis] = std::max(part.highest[axis], bounds.hi[axis]);
        }
        part.sum += bounds.largest;
      }
      extents[k] = part;
    }
  });
  Extent all{{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}, 0};
  for (const Extent& part : extents) {
    for (int axis = 0; axis < 3; ++axis) {
      all.lowest[axis] = std::min(all.lowest[axis], part.lowest[axis]);
      all.highest[axis] = std::max(all.highest[axis], part.highest[axis]);
    }
    all.sum += part.sum;
  }
  const double cell = 3 * all.sum / static_cast<double>(count);
  if (!(cell > 0) || !std::isfinite(cell) || !(1 / cell > 0) || !std::isfinite(1 / cell)) {
    return self_intersecting_pairs_by_box_tree(positions, triangles);
  }
  Grid grid;
  grid.inverse_cell = 1 / cell;
  for (int axis = 0; axis < 3; ++axis) grid.origin[axis] = all.lowest[axis];
  const auto range_of = [&](const FloatBox& box) {
    CellRange range;
    for (int axis = 0; axis < 3; ++axis) {
      range.lo[axis] = grid.cell_of(box.lo[axis], axis);
      range.hi[axis] = grid.cell_of(box.hi[axis], axis);
    }
    return range;
  };

  // The triangles ranked along a Morton curve through the cells of their boxes'
  // low corners (the cell coordinates cut to their top key_bits_per_axis bits; a
  // stable counting sort): triangles near each other in space come near each
  // other in the arrays below, and the buckets are searched in that order.
  // Only the speed depends on the order: pairs are reported by triangle index.
  const int key_bits_per_axis = key_bits_per_axis_for(count);
  int shift = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const std::uint32_t top = grid.cell_of(round_up(all.highest[axis]), axis);
    shift = std::max(shift, static_cast<int>(std::bit_width(top)) - key_bits_per_axis);
  }
  std::vector<std::uint32_t> keys(count);
  for_blocks(count, block, [&](std::size_t first, std::size_t last) {
    for (std::size_t t = first; t < last; ++t) {
      const CellRange range = range_of(box_of_triangle(t));
      keys[t] = spread_bits(range.lo[0] >> shift) | spread_bits(range.lo[1] >> shift) << 1 |
                spread_bits(range.lo[2] >> shift) << 2;
    }
  });
  std::vector<std::uint32_t> triangle_of(count);
  {
    std::vector<std::uint32_t> next(std::size_t{1} << 3 * key_bits_per_axis, 0);
    for (const std::uint32_t key : keys) ++next[key];
    std::uint32_t running = 0;
    for (std::uint32_t& n : next) running += std::exchange(n, running);
    for (std::size_t t = 0; t < count; ++t) triangle_of[next[keys[t]]++] = static_cast<std::uint32_t>(t);
  }
  std::vector<std::uint32_t>().swap(keys);

  // By rank: the box, and whether it spans more than max_cells_per_box cells (set
  // aside for the box tree); the entries (cells of the others) counted per block.
  std::vector<FloatBox> boxes(count);
  std::vector<std::uint8_t> is_large(count);
  std::vector<std::uint64_t> block_entries(blocks);
  for_blocks(blocks, 1, [&](std::size_t first, std::size_t last) {
    for (std::size_t k = first; k < last; ++k) {
      std::uint64_t entries = 0;
      for (std::size_t r = k * block; r < std::min(count, (k + 1) * block); ++r) {
        boxes[r] = box_of_triangle(triangle_of[r]);
        const CellRange range = range_of(boxes[r]);
        std::uint64_t cells = 1;
        for (int axis = 0; axis < 3; ++axis) cells *= range.hi[axis] - range.lo[axis] + 1;
        is_large[r] = cells > max_cells_per_box;
        if (!is_large[r]) entries += cells;
      }
      block_entries[k] = entries;
    }
  });
  std::uint64_t entries = 0;
  for (const std::uint64_t e : block_entries) entries += e;
  if (entries > std::numeric_limits<std::uint32_t>::max()) return self_intersecting_pairs_by_box_tree(positions, triangles);

  // Bucket the (cell, rank) entries by a counting sort, each bucket's ranks in
  // increasing order: its first is its least, and a triangle entered twice in
  // one bucket (two of its cells hash there) appears twice in a row. Bucket b is
  // members[start[b] .. start[b + 1]).
  const std::uint64_t bucket_count = std::bit_ceil(std::max<std::uint64_t>(16, entries / 2));
  const std::uint64_t mask = bucket_count - 1;
  std::vector<std::uint32_t> start(bucket_count + 1, 0);
  std::vector<std::uint32_t> members(entries);
  const bool parallel = tbb::this_task_arena::max_concurrency() > 1 && count > block;
  if (!parallel) {
    for (std::size_t r = 0; r < count; ++r) {
      if (!is_large[r]) for_each_bucket(range_of(boxes[r]), mask, [&](std::uint64_t b) { ++start[b]; });
    }
    for (std::uint64_t b = 1; b < bucket_count; ++b) start[b] += start[b - 1];
    // From the highest rank down, each bucket filled from its end: increasing.
    for (std::size_t r = count; r-- > 0;) {
      if (!is_large[r]) {
        for_each_bucket(range_of(boxes[r]), mask, [&](std::uint64_t b) { members[--start[b]] = static_cast<std::uint32_t>(r); });
      }
    }
  } else {
    for_blocks(count, block, [&](std::size_t first, std::size_t last) {
      for (std::size_t r = first; r < last; ++r) {
        if (is_large[r]) continue;
        for_each_bucket(range_of(boxes[r]), mask, [&](std::uint64_t b) {
          std::atomic_ref<std::uint32_t>(start[b]).fetch_add(1, std::memory_order_relaxed);
        });
      }
    });
    for (std::uint64_t b = 1; b < bucket_count; ++b) start[b] += start[b - 1];
    for_blocks(count, block, [&](std::size_t first, std::size_t last) {
      for (std::size_t r = first; r < last; ++r) {
        if (is_large[r]) continue;
        for_each_bucket(range_of(boxes[r]), mask, [&](std::uint64_t b) {
          members[std::atomic_ref<std::uint32_t>(start[b]).fetch_sub(1, std::memory_order_relaxed) - 1] =
              static_cast<std::uint32_t>(r);
        });
      }
    });
    // The threads filled each bucket in no particular order: sorted, it is what
    // the one-thread fill gives.
    for_blocks(bucket_count, block, [&](std::size_t first, std::size_t last) {
      for (std::size_t b = first; b < last; ++b) {
        const std::uint32_t end = b + 1 < bucket_count ? start[b + 1] : static_cast<std::uint32_t>(entries);
        if (end - start[b] > 1) std::sort(members.begin() + start[b], members.begin() + end);
      }
    });
  }
  start[bucket_count] = static_cast<std::uint32_t>(entries);

  // Each bucket is searched once, by its least rank, when the ranks come to it.
  // A pair of distinct triangles in it whose boxes meet is tested there if it is
  // the bucket of the cell holding the low corner of their boxes' overlap: one
  // cell, entered by both, so exactly one bucket tests the pair. That cell is,
  // axis by axis, the larger of the two boxes' low cells (cell_of is monotone).
  const auto search_bucket = [&](std::uint64_t b, BucketScratch& local, std::vector<TrianglePair>& found) {
    const std::uint32_t begin = start[b], end = start[b + 1];
    local.resize(end - begin);
    std::size_t size = 0;
    for (std::uint32_t i = begin; i < end; ++i) {
      const std::uint32_t r = members[i];
      if (i > begin && members[i - 1] == r) continue;  // entered twice
      const FloatBox& box = boxes[r];
      for (int axis = 0; axis < 3; ++axis) {
        local.lo[axis][size] = box.lo[axis];
        local.hi[axis][size] = box.hi[axis];
        local.cell[axis][size] = grid.cell_of(box.lo[axis], axis);
      }
      local.triangle[size++] = triangle_of[r];
    }
    const float* lo[3] = {local.lo[0].data(), local.lo[1].data(), local.lo[2].data()};
    const float* hi[3] = {local.hi[0].data(), local.hi[1].data(), local.hi[2].data()};
    std::uint8_t* meet = local.meet.data();
    for (std::size_t i = 0; i + 1 < size; ++i) {
      const float lo_x = lo[0][i], lo_y = lo[1][i], lo_z = lo[2][i], hi_x = hi[0][i], hi_y = hi[1][i], hi_z = hi[2][i];
      for (std::size_t j = i + 1; j < size; ++j) {
        meet[j] = (lo_x <= hi[0][j]) & (lo[0][j] <= hi_x) & (lo_y <= hi[1][j]) & (lo[1][j] <= hi_y) &
                  (lo_z <= hi[2][j]) & (lo[2][j] <= hi_z);
      }
      for (std::size_t j = i + 1; j < size; ++j) {
        if (!meet[j]) continue;
        const std::uint32_t x = std::max(local.cell[0][i], local.cell[0][j]);
        const std::uint32_t y = std::max(local.cell[1][i], local.cell[1][j]);
        const std::uint32_t z = std::max(local.cell[2][i], local.cell[2][j]);
        if (Grid::bucket_of(x, y, z, mask) != b) continue;
        const std::uint32_t s = local.triangle[i], t = local.triangle[j];
        if (triangles_intersect(positions, triangles[s], triangles[t])) found.emplace_back(std::min(s, t), std::max(s, t));
      }
    }
  };
  const auto search_ranks = [&](std::size_t first, std::size_t last, std::vector<TrianglePair>& found) {
    BucketScratch local;
    std::uint64_t searched[max_cells_per_box];
    for (std::size_t r = first; r < last; ++r) {
      if (is_large[r]) continue;
      std::size_t done = 0;
      for_each_bucket(range_of(boxes[r]), mask, [&](std::uint64_t b) {
        if (members[start[b]] != r || std::find(searched, searched + done, b) != searched + done) return;
        searched[done++] = b;
        search_bucket(b, local, found);
      });
    }
  };
  if (!parallel) {
    search_ranks(0, count, pairs);
  } else {
    tbb::enumerable_thread_specific<std::vector<TrianglePair>> found;
    for_blocks(count, std::min<std::size_t>(block, 1024),
               [&](std::size_t first, std::size_t last) { search_ranks(first, last, found.local()); });
    for (const std::vector<TrianglePair>& some : found) pairs.insert(pairs.end(), some.begin(), some.end());
  }

  // The long triangles against every triangle, with the box tree: each pair of
  // a long and a gridded triangle once, each pair of long ones twice (once per
  // order), kept once.
  std::vector<std::size_t> large;
  for (std::size_t r = 0; r < count; ++r) {
    if (is_large[r]) large.push_back(triangle_of[r]);
  }
  if (!large.empty()) {
    std::vector<std::uint8_t> long_triangle(count, 0);
    for (const std::size_t t : large) long_triangle[t] = 1;
    std::vector<TriangleBox> long_boxes, all_boxes;
    long_boxes.reserve(large.size());
    for (const std::size_t t : large) long_boxes.push_back(box_of(positions, triangles[t], t));
    all_boxes.reserve(count);
    for (std::size_t t = 0; t < count; ++t) all_boxes.push_back(box_of(positions, triangles[t], t));
    CGAL::box_intersection_d(
        long_boxes.begin(), long_boxes.end(), all_boxes.begin(), all_boxes.end(),
        [&](const TriangleBox& a, const TriangleBox& c) {
          const std::size_t i = a.handle(), j = c.handle();
          if (i == j || (long_triangle[j] && j < i)) return;
          if (triangles_intersect(positions, triangles[i], triangles[j])) pairs.emplace_back(std::min(i, j), std::max(i, j));
        },
        std::ptrdiff_t{10}, CGAL::Box_intersection_d::CLOSED);
  }
  sort_unique(pairs);
  return pairs;
}

std::vector<TrianglePair> self_intersecting_pairs_by_box_tree(std::span<const Vec3> positions,
                                                              std::span<const Triangle> triangles) {
  std::vector<TriangleBox> boxes;
  boxes.reserve(triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) boxes.push_back(box_of(positions, triangles[t], t));
  std::vector<TrianglePair> pairs;
  CGAL::box_self_intersection_d(
      boxes.begin(), boxes.end(),
      [&](const TriangleBox& a, const TriangleBox& b) {
        const std::size_t i = a.handle(), j = b.handle();
        if (triangles_intersect(positions, triangles[i], triangles[j])) pairs.emplace_back(std::min(i, j), std::max(i, j));
      },
      std::ptrdiff_t{10}, CGAL::Box_intersection_d::CLOSED);
  sort_unique(pairs);
  return pairs;
}

std::vector<TrianglePair> intersecting_pairs_with(std::span<const Vec3> positions, std::span<const Triangle> triangles,
                                                  std::span<const std::uint32_t> members,
                                                  std::span<const std::uint8_t> tested,
                                                  std::span<const std::uint32_t> embedded) {
  std::vector<TrianglePair> pairs;
  const std::size_t count = members.size();
  const auto is_tested = [&](std::size_t t) { return tested[t] != 0; };
  if (count < 2 || std::none_of(members.begin(), members.end(), is_tested)) return pairs;
  // Per member (by its position k in `members`): its float box and cell range.
  std::vector<FloatBox> boxes;
  const std::optional<Grid> made =
      boxes_and_grid(positions, count, [&](std::size_t k) -> const Triangle& { return triangles[members[k]]; }, boxes);
  if (!made) return intersecting_pairs_with_by_box_tree(positions, triangles, members, tested, embedded);
  const Grid& grid = *made;

  std::vector<CellRange> ranges;
  std::vector<std::uint8_t> is_large;
  const std::uint64_t entries = cell_ranges(grid, boxes, ranges, is_large);
  const bool any_large = std::find(is_large.begin(), is_large.end(), 1) != is_large.end();
  if (entries > std::numeric_limits<std::uint32_t>::max()) {
    return intersecting_pairs_with_by_box_tree(positions, triangles, members, tested, embedded);
  }
  const std::uint64_t bucket_count = std::bit_ceil(std::max<std::uint64_t>(16, entries));
  const std::uint64_t mask = bucket_count - 1;
  const auto for_each_cell = [&](std::size_t k, auto&& visit) { for_each_bucket(ranges[k], mask, visit); };
  // The buckets the tested members occupy: an untested member is entered only
  // there. A pair with a tested member is tested in the bucket of the low corner
  // of the boxes' overlap, a cell inside both boxes, which the tested one marked.
  std::vector<std::uint8_t> occupied(bucket_count, 0);
  for (std::size_t k = 0; k < count; ++k) {
    if (!is_large[k] && is_tested(members[k])) for_each_cell(k, [&](std::uint64_t b) { occupied[b] = 1; });
  }
  // A counting sort of the entries by bucket, each member's entries together,
  // so a member entered twice in one bucket appears twice in a row.
  std::vector<std::uint32_t> start(bucket_count + 1, 0);
  const auto entered = [&](std::size_t k, std::uint64_t b) { return is_tested(members[k]) || occupied[b]; };
  for (std::size_t k = 0; k < count; ++k) {
    if (!is_large[k]) {
      for_each_cell(k, [&](std::uint64_t b) {
        if (entered(k, b)) ++start[b + 1];
      });
    }
  }
  for (std::uint64_t b = 0; b < bucket_count; ++b) start[b + 1] += start[b];
  std::vector<std::uint32_t> slots(start[bucket_count]);
  {
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (std::size_t k = 0; k < count; ++k) {
      if (!is_large[k]) {
        for_each_cell(k, [&](std::uint64_t b) {
          if (entered(k, b)) slots[fill[b]++] = static_cast<std::uint32_t>(k);
        });
      }
    }
  }
  // Each tested member's plane, as a separating direction: n (the cross product
  // of two edges, in doubles; any direction would be sound) and the range of
  // n·x over its corners, widened by a bound on the rounding of every n·x taken
  // here. With |x_i| <= bound[i] for every corner and box corner (each lies in a
  // member's float box), a dot product of three terms errs by at most
  // 3.001u·sum |n_i| bound[i]; the range and a box's extreme each err by that, so
  // 8u·sum |n_i| bound[i] (plus 2^-1000 for products that underflow) covers both
  // and the rounding of the widening itself. A box whose extremes along n lie
  // past the widened range on one side holds no point of the plane's triangle:
  // its triangle cannot meet the tested one (not even at a shared vertex, which
  // would lie in both ranges), so triangles_intersect is not asked. Overflow
  // gives an infinite or NaN bound, and a comparison with it never separates.
  double bound[3] = {0, 0, 0};
  for (std::size_t k = 0; k < count; ++k) {
    for (int axis = 0; axis < 3; ++axis) {
      bound[axis] = std::max({bound[axis], std::fabs(static_cast<double>(boxes[k].lo[axis])),
                              std::fabs(static_cast<double>(boxes[k].hi[axis]))});
    }
  }
  struct Separator {
    double n[3], lo, hi;
  };
  std::vector<Separator> separators(count);
  for (std::size_t k = 0; k < count; ++k) {
    if (!is_tested(members[k])) continue;
    const Triangle& tri = triangles[members[k]];
    const Vec3 n = cross(positions[tri[1]] - positions[tri[0]], positions[tri[2]] - positions[tri[0]]);
    const double slack =
        8 * 0x1p-53 * (std::fabs(n.x) * bound[0] + std::fabs(n.y) * bound[1] + std::fabs(n.z) * bound[2]) + 0x1p-1000;
    double lo = INFINITY, hi = -INFINITY;
    for (const VertexIndex v : tri) {
      const double value = n.x * positions[v].x + n.y * positions[v].y + n.z * positions[v].z;
      lo = std::min(lo, value);
      hi = std::max(hi, value);
    }
    separators[k] = {{n.x, n.y, n.z}, lo - slack, hi + slack};
  }
  // Whether member k's box lies strictly beyond tested member s's plane range.
  const auto separated = [&](std::size_t s, std::size_t k) {
    const Separator& sep = separators[s];
    const FloatBox& box = boxes[k];
    double least = 0, most = 0;
    for (int axis = 0; axis < 3; ++axis) {
      const double lo = sep.n[axis] * box.lo[axis], hi = sep.n[axis] * box.hi[axis];
      least += std::min(lo, hi);
      most += std::max(lo, hi);
    }
    return least > sep.hi || most < sep.lo;
  };
  const auto report = [&](std::size_t i, std::size_t j) {
    const std::size_t s = members[i], t = members[j];
    if (!embedded.empty() && embedded[s] == embedded[t] && embedded[s] != no_embedded_group) return;
    if (is_tested(s) ? separated(i, j) : separated(j, i)) return;
    if (triangles_intersect(positions, triangles[s], triangles[t])) pairs.emplace_back(std::min(s, t), std::max(s, t));
  };
  // Each tested member s walks its own cells; a member t in the cell's bucket
  // whose box meets s's is tested when that cell holds the low corner of the
  // boxes' overlap (one cell, which both boxes cover: the pair is found there
  // and nowhere else), and, t tested as well, when s comes first.
  // Per member, in the order the inner loop reads them: tested, and its group.
  std::vector<std::uint8_t> member_tested(count);
  std::vector<std::uint32_t> member_group(count, no_embedded_group);
  for (std::size_t k = 0; k < count; ++k) {
    member_tested[k] = is_tested(members[k]);
    if (!embedded.empty()) member_group[k] = embedded[members[k]];
  }
  for (std::size_t s = 0; s < count; ++s) {
    if (is_large[s] || !member_tested[s]) continue;
    const std::uint32_t group_s = member_group[s];
    const FloatBox& box_s = boxes[s];
    const CellRange& range = ranges[s];
    for (std::uint32_t x = range.lo[0]; x <= range.hi[0]; ++x) {
      for (std::uint32_t y = range.lo[1]; y <= range.hi[1]; ++y) {
        for (std::uint32_t z = range.lo[2]; z <= range.hi[2]; ++z) {
          const std::uint64_t b = Grid::bucket_of(x, y, z, mask);
          const std::uint32_t begin = start[b], end = start[b + 1];
          for (std::uint32_t j = begin; j < end; ++j) {
            const std::uint32_t t = slots[j];
            if (t == s || (j > begin && slots[j - 1] == t)) continue;  // s itself, or t entered twice
            if (t < s && member_tested[t]) continue;                    // that pair is s's turn at t
            if (group_s != no_embedded_group && member_group[t] == group_s) continue;  // certified apart
            const FloatBox& box_t = boxes[t];
            if (!boxes_meet(box_s, box_t)) continue;
            if (grid.cell_of(std::max(box_s.lo[0], box_t.lo[0]), 0) != x ||
                grid.cell_of(std::max(box_s.lo[1], box_t.lo[1]), 1) != y ||
                grid.cell_of(std::max(box_s.lo[2], box_t.lo[2]), 2) != z) {
              continue;
            }
            report(s, t);
          }
        }
      }
    }
  }
  // The long members: a tested long one against every member (two tested long
  // ones once), an untested long one against the tested members in the grid
  // (the tested long ones found it already). A few long ones (a cut's pieces
  // have few) are compared with every member's float box directly; more go to
  // the box tree, whose set-up costs every member's box. Either way every pair
  // whose boxes meet is offered to `report`.
  std::vector<std::uint32_t> long_members;
  if (any_large) {
    for (std::size_t k = 0; k < count; ++k) {
      if (is_large[k]) long_members.push_back(static_cast<std::uint32_t>(k));
    }
  }
  constexpr std::size_t most_box_tests_by_scan = std::size_t{1} << 20;
  const bool scan = long_members.size() * count <= most_box_tests_by_scan;
  if (any_large && scan) {
    for (const std::uint32_t s : long_members) {
      const FloatBox& box_s = boxes[s];
      for (std::size_t t = 0; t < count; ++t) {
        const bool offered = member_tested[s] ? t != s && !(is_large[t] && member_tested[t] && t < s)
                                              : !is_large[t] && member_tested[t];
        if (offered && boxes_meet(box_s, boxes[t])) report(s, t);
      }
    }
  } else if (any_large) {
    std::vector<TriangleBox> long_tested, long_untested, every, gridded_tested;
    for (std::size_t k = 0; k < count; ++k) {
      const TriangleBox box = box_of(positions, triangles[members[k]], k);
      every.push_back(box);
      if (is_large[k]) (is_tested(members[k]) ? long_tested : long_untested).push_back(box);
      else if (is_tested(members[k])) gridded_tested.push_back(box);
    }
    if (!long_tested.empty()) {
      CGAL::box_intersection_d(
          long_tested.begin(), long_tested.end(), every.begin(), every.end(),
          [&](const TriangleBox& a, const TriangleBox& c) {
            const std::size_t i = a.handle(), j = c.handle();
            if (i == j || (is_large[j] && is_tested(members[j]) && j < i)) return;
            report(i, j);
          },
          std::ptrdiff_t{10}, CGAL::Box_intersection_d::CLOSED);
    }
    if (!long_untested.empty() && !gridded_tested.empty()) {
      CGAL::box_intersection_d(
          long_untested.begin(), long_untested.end(), gridded_tested.begin(), gridded_tested.end(),
          [&](const TriangleBox& a, const TriangleBox& c) { report(a.handle(), c.handle()); }, std::ptrdiff_t{10},
          CGAL::Box_intersection_d::CLOSED);
    }
  }
  sort_unique(pairs);
  return pairs;
}

std::vector<TrianglePair> intersecting_pairs_with_by_box_tree(std::span<const Vec3> positions,
                                                              std::span<const Triangle> triangles,
                                                              std::span<const std::uint32_t> members,
                                                              std::span<const std::uint8_t> tested,
                                                              std::span<const std::uint32_t> embedded) {
  std::vector<TriangleBox> tested_boxes, member_boxes;
  member_boxes.reserve(members.size());
  for (const std::uint32_t t : members) {
    const TriangleBox box = box_of(positions, triangles[t], t);
    member_boxes.push_back(box);
    if (tested[t]) tested_boxes.push_back(box);
  }
  std::vector<TrianglePair> pairs;
  if (tested_boxes.empty()) return pairs;
  CGAL::box_intersection_d(
      tested_boxes.begin(), tested_boxes.end(), member_boxes.begin(), member_boxes.end(),
      [&](const TriangleBox& a, const TriangleBox& b) {
        const std::size_t i = a.handle(), j = b.handle();
        if (i == j || (tested[j] && j < i)) return;  // each pair of tested triangles once
        if (!embedded.empty() && embedded[i] == embedded[j] && embedded[i] != no_embedded_group) return;
        if (triangles_intersect(positions, triangles[i], triangles[j])) pairs.emplace_back(std::min(i, j), std::max(i, j));
      },
      std::ptrdiff_t{10}, CGAL::Box_intersection_d::CLOSED);
  sort_unique(pairs);
  return pairs;
}

namespace {

using SegmentBox = CGAL::Box_intersection_d::Box_with_handle_d<double, 2, std::size_t, CGAL::Box_intersection_d::ID_EXPLICIT>;

// Whether q lies on the closed segment ab, given that a, b, q are collinear:
// exact coordinate comparisons.
bool on_collinear_segment(const Vec2& a, const Vec2& b, const Vec2& q) {
  return std::min(a.x, b.x) <= q.x && q.x <= std::max(a.x, b.x) && std::min(a.y, b.y) <= q.y && q.y <= std::max(a.y, b.y);
}

// Whether the closed segments ab and cd share a point, exactly.
bool segments_meet(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  const Sign o1 = orient2d(a, b, c), o2 = orient2d(a, b, d), o3 = orient2d(c, d, a), o4 = orient2d(c, d, b);
  if (o1 != Sign::zero && o2 != Sign::zero && o1 != o2 && o3 != Sign::zero && o4 != Sign::zero && o3 != o4) return true;
  return (o1 == Sign::zero && on_collinear_segment(a, b, c)) || (o2 == Sign::zero && on_collinear_segment(a, b, d)) ||
         (o3 == Sign::zero && on_collinear_segment(c, d, a)) || (o4 == Sign::zero && on_collinear_segment(c, d, b));
}

}  // namespace

bool triangles_embed_in_projection(std::span<const Vec3> positions, std::span<const Triangle> triangles,
                                   std::span<const std::uint32_t> group, int axis) {
  if (group.empty()) return false;
  const int i = (axis + 1) % 3, j = (axis + 2) % 3;
  const auto project = [&](VertexIndex v) { return Vec2{positions[v][i], positions[v][j]}; };
  // Every triangle strictly turning one way.
  Sign turn = Sign::zero;
  for (const std::uint32_t t : group) {
    const Triangle& tri = triangles[t];
    const Sign s = orient2d(project(tri[0]), project(tri[1]), project(tri[2]));
    if (s == Sign::zero || (turn != Sign::zero && s != turn)) return false;
    turn = s;
  }
  // The boundary: directed edges not matched by their reverse within the group.
  struct HalfEdge {
    VertexIndex low, high;
    bool forward;  // low -> high
  };
  std::vector<HalfEdge> edges;
  edges.reserve(3 * group.size());
  for (const std::uint32_t t : group) {
    const Triangle& tri = triangles[t];
    for (int c = 0; c < 3; ++c) {
      const VertexIndex u = tri[c], v = tri[(c + 1) % 3];
      edges.push_back({std::min(u, v), std::max(u, v), u < v});
    }
  }
  std::sort(edges.begin(), edges.end(), [](const HalfEdge& a, const HalfEdge& b) {
    return std::tie(a.low, a.high, a.forward) < std::tie(b.low, b.high, b.forward);
  });
  std::vector<std::pair<VertexIndex, VertexIndex>> boundary;  // from, to
  for (std::size_t k = 0; k < edges.size();) {
    std::size_t end = k + 1;
    while (end < edges.size() && edges[end].low == edges[k].low && edges[end].high == edges[k].high) ++end;
    if (end - k == 1) {
      const HalfEdge& e = edges[k];
      boundary.emplace_back(e.forward ? e.low : e.high, e.forward ? e.high : e.low);
    } else if (end - k != 2 || edges[k].forward == edges[k + 1].forward) {
      return false;  // an edge used twice one way, or by three triangles: not a surface
    }
    k = end;
  }
  if (boundary.empty()) return false;
  // Each vertex left at most once: the boundary is vertex-disjoint cycles.
  std::sort(boundary.begin(), boundary.end());
  for (std::size_t k = 1; k < boundary.size(); ++k) {
    if (boundary[k].first == boundary[k - 1].first) return false;
  }
  const auto next_of = [&](VertexIndex from) {
    const auto it = std::lower_bound(boundary.begin(), boundary.end(), std::pair<VertexIndex, VertexIndex>{from, 0});
    return it != boundary.end() && it->first == from ? std::optional<std::size_t>(it - boundary.begin()) : std::nullopt;
  };
  // The boundary's projections meet only where consecutive edges share their vertex.
  std::vector<SegmentBox> boxes;
  boxes.reserve(boundary.size());
  for (std::size_t k = 0; k < boundary.size(); ++k) {
    const Vec2 a = project(boundary[k].first), b = project(boundary[k].second);
    double lo[2] = {std::min(a.x, b.x), std::min(a.y, b.y)}, hi[2] = {std::max(a.x, b.x), std::max(a.y, b.y)};
    boxes.emplace_back(SegmentBox(lo, hi, k));
  }
  bool simple = true;
  CGAL::box_self_intersection_d(
      boxes.begin(), boxes.end(),
      [&](const SegmentBox& x, const SegmentBox& y) {
        if (!simple) return;
        auto [p, q] = boundary[x.handle()];
        auto [r, s] = boundary[y.handle()];
        if (q == r || s == p) {
          // Consecutive (p -> q -> s, or r -> s -> q): they meet only at the shared
          // vertex unless the far ends lie along one ray from it.
          if (s == p) std::swap(p, r), std::swap(q, s);  // now p -> q, q -> s
          if (q != r || p == s) {
            simple = false;  // a cycle of two edges, or not consecutive after all
            return;
          }
          const Vec2 a = project(p), b = project(q), c = project(s);
          if (orient2d(a, b, c) != Sign::zero) return;
          // Collinear: apart only when a and c lie on opposite sides of b.
          const bool a_low = a.x < b.x || (a.x == b.x && a.y < b.y), c_low = c.x < b.x || (c.x == b.x && c.y < b.y);
          if (a_low == c_low) simple = false;
          return;
        }
        if (p == r || q == s) {
          simple = false;  // not vertex-disjoint cycles (excluded above; kept for safety)
          return;
        }
        if (segments_meet(project(p), project(q), project(r), project(s))) simple = false;
      },
      std::ptrdiff_t{10}, CGAL::Box_intersection_d::CLOSED);
  if (!simple) return false;
  // The cycles: exactly one turns the triangles' way, decided at its
  // lexicographically least vertex (a strictly convex corner of a simple polygon).
  std::vector<std::uint8_t> seen(boundary.size(), 0);
  std::vector<std::size_t> cycle;
  std::size_t turning = 0;
  for (std::size_t start = 0; start < boundary.size(); ++start) {
    if (seen[start]) continue;
    cycle.clear();
    std::size_t least = 0;  // position in `cycle` of the edge leaving the least vertex
    std::size_t k = start;
    while (!seen[k]) {
      seen[k] = 1;
      const Vec2 here = project(boundary[k].first), best = project(boundary[cycle.empty() ? k : cycle[least]].first);
      if (here.x < best.x || (here.x == best.x && here.y < best.y)) least = cycle.size();
      cycle.push_back(k);
      const std::optional<std::size_t> next = next_of(boundary[k].second);
      if (!next) return false;  // not closed (cannot happen for a chain's boundary)
      k = *next;
    }
    if (k != start) return false;  // ran into another cycle (cannot happen: each vertex is entered once)
    const std::size_t into = cycle[(least + cycle.size() - 1) % cycle.size()], out = cycle[least];
    const Sign s = orient2d(project(boundary[into].first), project(boundary[out].first), project(boundary[out].second));
    if (s == Sign::zero) return false;
    if (s == turn) ++turning;
  }
  return turning == 1;
}

}  // namespace shatter
