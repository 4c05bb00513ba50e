#include "seed_modeller.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <unordered_map>

#include "pslg_triangulator.hpp"

namespace seed_peer {

const char* failure_name(FailureKind kind) {
  switch (kind) {
    case FailureKind::none: return "none";
    case FailureKind::edge_linking_failed: return "edge_linking_failed";
    case FailureKind::loop_not_closed: return "loop_not_closed";
    case FailureKind::triangulation_failed: return "triangulation_failed";
    case FailureKind::invalid_piece: return "invalid_piece";
    case FailureKind::timeout: return "timeout";
  }
  return "?";
}

namespace {

// A uniform float in [0, 1): the top 24 bits of one draw, so every value is a float.
float uniform01(std::mt19937& rng) { return static_cast<float>(rng() >> 8) * (1.0f / 16777216.0f); }

bool same(Vec3f a, Vec3f b, Compare compare) {
  return compare == Compare::unity ? unity_equal(a, b) : exactly_equal(a, b);
}

struct Find {
  std::vector<std::uint32_t> parent;
  explicit Find(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  std::uint32_t root(std::uint32_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  }
  void join(std::uint32_t a, std::uint32_t b) {
    a = root(a);
    b = root(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);  // the lower index leads its group
  }
};

// A border edge B0-B1 (4.2), oriented so that A is where the triangle's boundary,
// walked in its own order, passes from the positive to the negative side: then the
// B of one edge is the A of the edge of the neighbouring triangle, which is what
// Listing 4.4 links.
struct BorderEdge {
  Vec3f a, b;
};

// One vertex loop of Listing 4.4.
using Loop = std::vector<Vec3f>;

// Listing 4.4, ExtractVertexLoop: the first edge's A is the end point, its B starts
// the loop; the list is scanned from its start for an edge whose A matches the
// loop's last vertex; that edge's B is appended and the edge removed; the loop is
// returned when that B matches the end point, else the scan starts over. The
// listing loops forever when nothing matches; here that is the failure it is.
bool extract_loop(std::vector<BorderEdge>& edges, Compare compare, Linker linker, Loop& loop, Failure& failure) {
  const Vec3f end_point = edges.front().a;
  loop.push_back(edges.front().b);
  edges.erase(edges.begin());
  if (linker == Linker::check_first && same(loop.back(), end_point, compare)) return true;
  for (;;) {
    bool found = false;
    for (std::size_t i = 0; i < edges.size(); ++i) {
      if (!same(loop.back(), edges[i].a, compare)) continue;
      const Vec3f b = edges[i].b;
      loop.push_back(b);
      edges.erase(edges.begin() + static_cast<std::ptrdiff_t>(i));
      if (same(b, end_point, compare)) return true;
      found = true;
      break;
    }
    if (found) continue;
    if (edges.empty()) {
      failure.kind = FailureKind::loop_not_closed;
      failure.detail = "all border edges used, loop of " + std::to_string(loop.size()) +
                       " vertices never returned to its start";
    } else {
      // The nearest edge start says which way the comparison failed: just past 1e-5,
      // two copies of one cut point rounded apart; far, the edge belongs elsewhere.
      double nearest = INFINITY;
      for (const auto& e : edges) {
        const double dx = double(e.a.x) - loop.back().x, dy = double(e.a.y) - loop.back().y,
                     dz = double(e.a.z) - loop.back().z;
        nearest = std::min(nearest, std::sqrt(dx * dx + dy * dy + dz * dz));
      }
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.3g", nearest);
      failure.kind = FailureKind::edge_linking_failed;
      failure.detail = std::to_string(edges.size()) + " border edges left, none starts at the open loop's end (" +
                       std::to_string(loop.size()) + " vertices linked; the nearest edge start is " + buf + " away)";
    }
    return false;
  }
}

// Eq. 4.1: for every edge of the loop (the closing edge included), the triangle of
// that edge and the origin; its area |Vi x Vi+1| / 2 is added when it turns
// counter-clockwise around the plane normal and subtracted otherwise. With the
// mesh's origin off the plane these triangles stand out of it, their areas are
// not the loop's, and the sum can take the wrong sign for a loop small against
// its distance (README.md, "Eq. 4.1 taken literally").
float loop_area(const Loop& loop, Vec3f normal, Vec3f origin) {
  float ccw = 0, cw = 0;
  for (std::size_t i = 0; i < loop.size(); ++i) {
    const Vec3f c = cross(loop[i] - origin, loop[(i + 1) % loop.size()] - origin);
    const float half = magnitude(c) / 2;
    if (dot(c, normal) > 0) ccw += half;
    else cw += half;
  }
  return ccw - cw;
}

// Crossing-number point-in-polygon test in floats (the text says only that a point
// "is within the hole").
bool inside(const std::vector<std::array<float, 2>>& poly, float x, float y) {
  bool in = false;
  for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const float xi = poly[i][0], yi = poly[i][1], xj = poly[j][0], yj = poly[j][1];
    if ((yi > y) != (yj > y) && x < (xj - xi) * (y - yi) / (yj - yi) + xi) in = !in;
  }
  return in;
}

}  // namespace

std::vector<std::uint32_t> group_positions(const std::vector<Vec3f>& positions, Compare compare) {
  const std::size_t n = positions.size();
  Find find(n);
  // Bitwise-equal positions first (most corners are copies of one position).
  struct Hash {
    std::size_t operator()(const std::array<float, 3>& p) const {
      std::size_t h = 0;
      for (float f : p) h = h * 1000003u ^ std::hash<float>{}(f);
      return h;
    }
  };
  std::unordered_map<std::array<float, 3>, std::uint32_t, Hash> first;
  std::vector<std::uint32_t> distinct;
  for (std::uint32_t i = 0; i < n; ++i) {
    const auto [it, added] = first.emplace(std::array<float, 3>{positions[i].x, positions[i].y, positions[i].z}, i);
    if (added) distinct.push_back(i);
    else find.join(it->second, i);
  }
  if (compare == Compare::unity) {
    // Unity's == holds only below a distance of 1e-5: sorted by x, each position is
    // compared with those whose x is within 2e-5 (a margin over the float test).
    std::sort(distinct.begin(), distinct.end(),
              [&](std::uint32_t a, std::uint32_t b) { return positions[a].x < positions[b].x; });
    for (std::size_t i = 0; i < distinct.size(); ++i) {
      const Vec3f p = positions[distinct[i]];
      for (std::size_t j = i + 1; j < distinct.size(); ++j) {
        const Vec3f q = positions[distinct[j]];
        if (static_cast<double>(q.x) - p.x > 2e-5) break;
        if (unity_equal(p, q)) find.join(distinct[i], distinct[j]);
      }
    }
  }
  std::vector<std::uint32_t> out(n);
  for (std::uint32_t i = 0; i < n; ++i) out[i] = find.root(i);
  return out;
}

namespace {

// Listing 4.6: hulls grow by adding every triangle with a vertex in common with the
// hull until none is added. The result is the connected components of "shares a
// vertex position", which this computes directly (union-find) instead of by the
// listing's quadratic rescans; the components are the same.
std::vector<Piece> separate_hulls(Piece side, Compare compare) {
  std::vector<Vec3f> corners;
  corners.reserve(side.triangles.size() * 3);
  for (const auto& t : side.triangles)
    for (const auto& p : t) corners.push_back(p);
  const auto group = group_positions(corners, compare);
  Find find(corners.size());
  for (std::uint32_t i = 0; i < corners.size(); ++i) {
    find.join(i, group[i]);
    if (i % 3) find.join(i, i - i % 3);
  }
  std::unordered_map<std::uint32_t, std::size_t> hull_of;
  std::vector<Piece> hulls;
  for (std::size_t t = 0; t < side.triangles.size(); ++t) {
    const auto r = find.root(static_cast<std::uint32_t>(3 * t));
    const auto [it, added] = hull_of.emplace(r, hulls.size());
    if (added) hulls.emplace_back();
    hulls[it->second].triangles.push_back(side.triangles[t]);
  }
  return hulls;
}

}  // namespace

SliceOutcome slice_piece(const Piece& piece, const PlaneF& plane, const SliceOptions& options,
                         std::mt19937& hole_rng) {
  const Compare compare = options.compare;
  SliceOutcome out;
  Piece pos, neg;
  std::vector<BorderEdge> edges;

  // 4.2: sort whole triangles by side, split the straddling ones.
  for (const auto& t : piece.triangles) {
    const bool side[3] = {plane.get_side(t[0]), plane.get_side(t[1]), plane.get_side(t[2])};
    if (side[0] == side[1] && side[1] == side[2]) {
      (side[0] ? pos : neg).triangles.push_back(t);
      continue;
    }
    // The lonely vertex S and the pair P0, P1 that follow it in the triangle's own
    // order, so the new triangles keep the source's orientation.
    const int s = side[0] != side[1] && side[0] != side[2] ? 0 : (side[1] != side[0] && side[1] != side[2] ? 1 : 2);
    const Vec3f S = t[s], P0 = t[(s + 1) % 3], P1 = t[(s + 2) % 3];
    const Vec3f B0 = plane.raycast_point(S, P0);  // the raytrace from S to P0
    const Vec3f B1 = plane.raycast_point(S, P1);  // and from S to P1
    Piece& lonely = side[s] ? pos : neg;
    Piece& pair = side[s] ? neg : pos;
    lonely.triangles.push_back({S, B0, B1});
    pair.triangles.push_back({B0, P0, P1});
    pair.triangles.push_back({B0, P1, B1});
    // Walking S -> P0 -> P1 -> S, the boundary leaves S's side at B0 and comes back
    // at B1: when S is positive, B0 is the positive-to-negative crossing.
    edges.push_back(side[s] ? BorderEdge{B0, B1} : BorderEdge{B1, B0});
  }
  out.stats.border_edges = edges.size();
  for (const auto& e : edges) out.stats.tiny_border_edges += same(e.a, e.b, compare) ? 1 : 0;
  // 4.3.1: link the border edges into loops.
  std::vector<Loop> loops;
  while (!edges.empty()) {
    Loop loop;
    if (!extract_loop(edges, compare, options.linker, loop, out.failure)) return out;
    if (options.linker == Linker::check_first && loop.size() < 3) {
      ++out.stats.dropped_loops;
      continue;
    }
    loops.push_back(std::move(loop));
  }
  out.stats.loops = loops.size();
  // No loop (the plane misses the piece, or check_first dropped every loop): no cap.
  if (!loops.empty()) {

    // 4.3.2: polygon outlines turn counter-clockwise around the normal with these
    // edge directions (Eq. 4.1 positive), holes the other way.
    const Vec3f origin = options.area_origin == AreaOrigin::mesh ? Vec3f{} : plane.normal * -plane.distance;
    std::vector<char> is_hole(loops.size());
    for (std::size_t i = 0; i < loops.size(); ++i) {
      is_hole[i] = !(loop_area(loops[i], plane.normal, origin) > 0);
      // For the report only: the loop's own signed area around the normal, in doubles.
      double twice = 0;
      for (std::size_t k = 0; k < loops[i].size(); ++k) {
        const Vec3f p = loops[i][k], q = loops[i][(k + 1) % loops[i].size()];
        twice += (static_cast<double>(p.y) * q.z - static_cast<double>(p.z) * q.y) * plane.normal.x +
                 (static_cast<double>(p.z) * q.x - static_cast<double>(p.x) * q.z) * plane.normal.y +
                 (static_cast<double>(p.x) * q.y - static_cast<double>(p.y) * q.x) * plane.normal.z;
      }
      if ((twice > 0) == static_cast<bool>(is_hole[i])) ++out.stats.misclassified_loops;
    }
    // The PSLG in the plane's own 2D frame (u, v, normal right-handed), in floats.
    const Vec3f n = plane.normal;
    const float ax = std::fabs(n.x), ay = std::fabs(n.y), az = std::fabs(n.z);
    const Vec3f axis = ax <= ay && ax <= az ? Vec3f{1, 0, 0} : (ay <= az ? Vec3f{0, 1, 0} : Vec3f{0, 0, 1});
    const Vec3f u = normalized(cross(n, axis));
    const Vec3f v = cross(n, u);
    Pslg pslg;
    std::vector<Vec3f> points3;
    std::vector<std::vector<std::array<float, 2>>> flat(loops.size());
    for (std::size_t i = 0; i < loops.size(); ++i) {
      const int first = static_cast<int>(points3.size());
      const int count = static_cast<int>(loops[i].size());
      for (int k = 0; k < count; ++k) {
        const Vec3f p = loops[i][static_cast<std::size_t>(k)];
        const float x = dot(p, u), y = dot(p, v);
        flat[i].push_back({x, y});
        pslg.points.push_back({x, y});
        points3.push_back(p);
        pslg.segments.push_back({first + k, first + (k + 1) % count});
      }
    }
    // 4.3.3: a random point within the hole's bounds, kept when it is inside the
    // hole and inside none of the polygons within the hole. The seed retries for
    // ever; after 1,000 tries this reports the failure.
    for (std::size_t h = 0; h < loops.size(); ++h) {
      if (!is_hole[h]) continue;
      float lo_x = flat[h][0][0], hi_x = lo_x, lo_y = flat[h][0][1], hi_y = lo_y;
      for (const auto& p : flat[h]) {
        lo_x = std::min(lo_x, p[0]);
        hi_x = std::max(hi_x, p[0]);
        lo_y = std::min(lo_y, p[1]);
        hi_y = std::max(hi_y, p[1]);
      }
      bool placed = false;
      for (int attempt = 0; attempt < 1000 && !placed; ++attempt) {
        const float x = lo_x + (hi_x - lo_x) * uniform01(hole_rng);
        const float y = lo_y + (hi_y - lo_y) * uniform01(hole_rng);
        if (!inside(flat[h], x, y)) continue;
        bool in_polygon = false;
        for (std::size_t p = 0; p < loops.size() && !in_polygon; ++p)
          if (!is_hole[p] && inside(flat[h], flat[p][0][0], flat[p][0][1]) && inside(flat[p], x, y))
            in_polygon = true;
        if (in_polygon) continue;
        pslg.holes.push_back({x, y});
        placed = true;
      }
      if (!placed) {
        out.failure.kind = FailureKind::triangulation_failed;
        out.failure.detail = "no point inside hole loop " + std::to_string(h) + " (" +
                             std::to_string(loops[h].size()) + " vertices) in 1000 random tries";
        return out;
      }
    }
    const PslgTriangulation cap = triangulate_pslg(pslg);
    if (!cap.ok) {
      out.failure.kind = FailureKind::triangulation_failed;
      out.failure.detail = cap.error + " (" + std::to_string(loops.size()) + " loops, " +
                           std::to_string(pslg.points.size()) + " points)";
      return out;
    }
    // Counter-clockwise in (u, v) faces +normal: outward for the negative side; the
    // positive side gets the triangles reversed. The cap's corners are the loop
    // vertices themselves, found by the triangulator's point numbers.
    for (const auto& t : cap.triangles) {
      const Vec3f a = points3[static_cast<std::size_t>(t[0])], b = points3[static_cast<std::size_t>(t[1])],
                  c = points3[static_cast<std::size_t>(t[2])];
      neg.triangles.push_back({a, b, c});
      pos.triangles.push_back({a, c, b});
    }
  }

  // 4.4: each side into its hulls.
  for (Piece* side : {&pos, &neg}) {
    if (side->triangles.empty()) continue;
    for (auto& hull : separate_hulls(std::move(*side), compare)) {
      out.pieces.push_back(std::move(hull));
      out.above.push_back(side == &pos);
    }
  }
  return out;
}

Vec3f centre_of_mass(const Piece& piece, float& volume6) {
  Vec3f weighted{};
  volume6 = 0;
  for (const auto& t : piece.triangles) {
    const float w = dot(t[0], cross(t[1], t[2]));
    volume6 += w;
    weighted = weighted + (t[0] + t[1] + t[2]) * w;
  }
  return weighted / (4.0f * volume6);
}

Vec3f random_direction(std::mt19937& rng) {
  for (;;) {
    const Vec3f p{2 * uniform01(rng) - 1, 2 * uniform01(rng) - 1, 2 * uniform01(rng) - 1};
    const float m2 = dot(p, p);
    if (m2 > 1e-6f && m2 <= 1.0f) return normalized(p);
  }
}

BuildResult build_fragments(const Piece& source, const BuildOptions& options,
                            std::chrono::steady_clock::time_point start) {
  BuildResult result;
  std::mt19937 plane_rng(options.seed);
  std::mt19937 hole_rng(options.seed ^ 0x9e3779b9u);
  const auto build_start = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  std::vector<Piece> leaves{source};
  int idle_levels = 0;
  while (static_cast<int>(leaves.size()) < options.fragments) {
    ++result.levels;
    const std::size_t before = leaves.size();
    std::vector<Piece> next;
    std::size_t count = leaves.size();
    for (std::size_t i = 0; i < leaves.size(); ++i) {
      if (static_cast<int>(count) >= options.fragments) {
        next.push_back(std::move(leaves[i]));
        continue;
      }
      if (elapsed() > options.time_cap) {
        result.failure = {FailureKind::timeout, result.levels, static_cast<int>(i),
                          "passed the " + std::to_string(options.time_cap) + " s cap"};
        break;
      }
      float volume6 = 0;
      const Vec3f centre = centre_of_mass(leaves[i], volume6);
      if (!(volume6 > 0) || !std::isfinite(centre.x) || !std::isfinite(centre.y) || !std::isfinite(centre.z)) {
        result.failure = {FailureKind::invalid_piece, result.levels, static_cast<int>(i),
                          "the piece to split has float volume " + std::to_string(volume6 / 6) + " <= 0: not a closed solid"};
        break;
      }
      const PlaneF plane = PlaneF::through(random_direction(plane_rng), centre);
      SliceOutcome slice = slice_piece(leaves[i], plane, options.slice, hole_rng);
      result.stats.add(slice.stats);
      if (slice.failure.kind != FailureKind::none) {
        result.failure = slice.failure;
        result.failure.level = result.levels;
        result.failure.piece = static_cast<int>(i);
        break;
      }
      count += slice.pieces.size() - 1;
      for (auto& p : slice.pieces) next.push_back(std::move(p));
    }
    if (result.failure.kind != FailureKind::none) {
      // The leaves when it stopped: this level's results so far, then the pieces not
      // yet split (the one that failed among them).
      const auto failed_at = static_cast<std::size_t>(result.failure.piece);
      for (std::size_t i = failed_at; i < leaves.size(); ++i) next.push_back(std::move(leaves[i]));
      leaves = std::move(next);
      break;
    }
    leaves = std::move(next);
    // A plane through the centre of mass always cuts a solid; a level that made no
    // new piece three times running means the pieces are not solids any more.
    idle_levels = leaves.size() == before ? idle_levels + 1 : 0;
    if (idle_levels == 3) {
      result.failure = {FailureKind::invalid_piece, result.levels, -1,
                        "three levels of planes through the centres of mass cut no piece"};
      break;
    }
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - build_start).count();
  result.leaves = std::move(leaves);
  return result;
}

}  // namespace seed_peer
