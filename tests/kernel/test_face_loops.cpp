// Loops and regions on a plane (kernel/face_loops.hpp): random nests of rings
// (outer boundaries, holes, islands in holes, holes in islands) drawn on lattice
// points of planes of every projection, as cut planes and as input planes, seen
// from either side; loops touching at a vertex; shuffled edges and vertex
// numbers. group_into_regions must link exactly the drawn loops and give each
// outer loop exactly the holes drawn directly inside it; is_convex_loop and
// inside_loop must agree with convexity and ray casting done here in rationals.

#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <numbers>
#include <numeric>
#include <set>
#include <string>
#include <vector>

#include "shatter/generators/random.hpp"
#include "shatter/kernel/error.hpp"
#include "shatter/kernel/face_loops.hpp"

using namespace shatter;
using namespace shatter::test;

namespace {

using Lattice = std::array<std::int64_t, 2>;

// A plane and integer axes on it: lattice point (u, v) is origin + u e1 + v e2,
// exact in doubles for |u|, |v| < 2^22 (the axes' entries are below 8). Seen from
// the outward side, (u, v) orientation is the orientation on the face: the plane
// normal is e1 x e2, or its opposite with `reversed`.
struct Frame {
  std::string name;
  Vec3 origin, e1, e2;
  bool reversed = false;
  bool input_plane = false;  // the plane as an input plane through three points, else a cut plane
};

const std::vector<Frame>& frames() {
  static const std::vector<Frame> all = [] {
    std::vector<Frame> f{
        {"z = 0 from +z", {0, 0, 0}, {1, 0, 0}, {0, 1, 0}},
        {"z = 5 from -z", {3, -2, 5}, {0, 1, 0}, {1, 0, 0}},
        {"x = -7 from +x", {-7, 1, 2}, {0, 1, 0}, {0, 0, 1}},
        {"tilted, mostly x", {1, 2, 3}, {1, 2, 0}, {0, 1, 3}},
        {"tilted, mostly y", {-4, 0, 9}, {2, -1, 1}, {1, 1, -2}},
        {"tilted, mostly -z", {0, 6, -1}, {1, 1, 0}, {-1, 2, 1}},
    };
    const std::size_t n = f.size();
    for (std::size_t i = 0; i < n; ++i) {
      for (const int variant : {1, 2, 3}) {
        Frame other = f[i];
        other.input_plane = (variant & 1) != 0;
        other.reversed = (variant & 2) != 0;
        other.name += other.input_plane ? ", input plane" : "";
        other.name += other.reversed ? ", reversed face" : "";
        f.push_back(other);
      }
    }
    return f;
  }();
  return all;
}

// Points of one frame and the PlaneSet over them; the first three points define
// the input plane when the frame asks for one.
class FacePlane {
 public:
  explicit FacePlane(const Frame& frame) : frame_(frame) {
    // n = e1 x e2 facing outward; the plane itself faces the other way when reversed.
    const bool back = frame.reversed;
    add({0, 0});
    add(back ? Lattice{0, 1} : Lattice{1, 0});
    add(back ? Lattice{1, 0} : Lattice{0, 1});
    Vec3 normal = cross(frame.e1, frame.e2);
    if (back) normal = -normal;
    cuts_.push_back({normal, -dot(normal, frame.origin)});
    inputs_.push_back({0, 1, 2});
    input_approx_.push_back(approximate_input_plane(points_[0], points_[1], points_[2]));
  }

  VertexIndex add(Lattice p) {
    const auto [it, added] = index_of_.try_emplace(p, static_cast<VertexIndex>(points_.size()));
    if (added) {
      lattice_.push_back(p);
      points_.push_back(frame_.origin + frame_.e1 * static_cast<double>(p[0]) + frame_.e2 * static_cast<double>(p[1]));
    }
    return it->second;
  }
  // Another vertex at p's place, whether or not one is there already (as
  // copies of a vertex lie at one point where a piece meets itself along a chord).
  VertexIndex add_copy(Lattice p) {
    lattice_.push_back(p);
    points_.push_back(frame_.origin + frame_.e1 * static_cast<double>(p[0]) + frame_.e2 * static_cast<double>(p[1]));
    return static_cast<VertexIndex>(points_.size() - 1);
  }
  const Lattice& lattice(VertexIndex v) const { return lattice_[v]; }

  // The FaceGeometry over every point added so far (valid until the next add).
  FaceGeometry geometry() {
    set_ = PlaneSet{points_, inputs_, input_approx_, cuts_};
    defs_.clear();
    approx_.clear();
    for (std::uint32_t i = 0; i < points_.size(); ++i) {
      defs_.push_back(PointDef::input(i));
      approx_.push_back(approximate(set_, defs_.back()));
    }
    const PlaneRef plane = frame_.input_plane ? PlaneRef::input(0) : PlaneRef::cut(0);
    return FaceGeometry{set_, defs_, approx_, projection_of(set_, plane), frame_.reversed};
  }

 private:
  Frame frame_;
  std::map<Lattice, VertexIndex> index_of_;
  std::vector<Lattice> lattice_;
  std::vector<Vec3> points_;
  std::vector<std::array<VertexIndex, 3>> inputs_;
  std::vector<ApproxPlane> input_approx_;
  std::vector<Plane> cuts_;
  PlaneSet set_;
  std::vector<PointDef> defs_;
  std::vector<ApproxPoint> approx_;
};

// Exact on the lattice: coordinates stay below 2^23, products below 2^48.
int orient2(const Lattice& a, const Lattice& b, const Lattice& c) {
  const std::int64_t d = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
  return (d > 0) - (d < 0);
}

std::int64_t twice_area(const std::vector<Lattice>& loop) {
  std::int64_t sum = 0;
  for (std::size_t i = 0; i < loop.size(); ++i) {
    const Lattice& a = loop[i];
    const Lattice& b = loop[(i + 1) % loop.size()];
    sum += a[0] * b[1] - a[1] * b[0];
  }
  return sum;
}

// A drawn loop: its corners in order (counter-clockwise for an outer loop or an
// island, clockwise for a hole) and the outer loop a hole belongs to.
struct DrawnLoop {
  std::vector<Lattice> corners;
  bool outer = true;
  int owner = -1;  // for a hole: the index of its outer loop
};

// A polygon around `centre` with corners at increasing angles, every gap below
// a half-turn (so it is simple), at radii in [0.30, 0.45] x size: it lies in the
// disc of radius 0.45 size. One that will hold children has 8 to 14 corners with
// gaps of at most 1.5 / 8 of a turn, so it also holds the disc of radius
// 0.30 cos(67.5 / 2 degrees) size = 0.249 size.
std::vector<Lattice> star(Random& random, double cx, double cy, double size, bool clockwise, bool holds_children) {
  const int m = holds_children ? 8 + static_cast<int>(random.index(7)) : 3 + static_cast<int>(random.index(8));
  const double jitter = holds_children ? 0.5 : m == 3 ? 0.4 : 0.8;
  const bool round = random.index(3) == 0;  // equal radii: convex up to rounding
  std::vector<Lattice> corners;
  for (int k = 0; k < m; ++k) {
    const double angle = 2 * std::numbers::pi * (k + jitter * random.uniform()) / m;
    const double r = size * (round ? 0.42 : random.uniform(0.30, 0.45));
    corners.push_back({std::llround(cx + r * std::cos(angle)), std::llround(cy + r * std::sin(angle))});
  }
  if (clockwise) std::reverse(corners.begin(), corners.end());
  return corners;
}

// Rings nested `depth` deep below a ring of the given size: inside each ring up to
// four children in a 2 x 2 grid of cells of 0.18 size around its centre (each
// child within 0.09 sqrt 2 + 0.45 x 0.18 = 0.208 size of it, inside the disc the
// ring holds), alternating outer loops and holes by level.
void draw_rings(Random& random, double cx, double cy, double size, int level, int depth, int owner,
                std::vector<DrawnLoop>& loops) {
  const bool outer = level % 2 == 0;
  const double cell = 0.18 * size;
  std::vector<int> children;
  for (int i = 0; i < 4 && level < depth; ++i) {
    if (random.index(3) != 0 || (i == 0 && level == 0)) children.push_back(i);  // the outermost loop always gets a hole
  }
  const int index = static_cast<int>(loops.size());
  loops.push_back({star(random, cx, cy, size, !outer, !children.empty()), outer, outer ? -1 : owner});
  for (const int i : children) {
    const double x = cx + (i % 2 == 0 ? -0.5 : 0.5) * cell, y = cy + (i / 2 == 0 ? -0.5 : 0.5) * cell;
    draw_rings(random, x, y, cell, level + 1, depth, outer ? index : -1, loops);
  }
}

// Closed segments ab and cd share a point.
bool segments_meet(const Lattice& a, const Lattice& b, const Lattice& c, const Lattice& d) {
  const int o1 = orient2(a, b, c), o2 = orient2(a, b, d), o3 = orient2(c, d, a), o4 = orient2(c, d, b);
  if (o1 * o2 < 0 && o3 * o4 < 0) return true;
  const auto on = [](const Lattice& p, const Lattice& q, const Lattice& r) {
    return std::min(p[0], q[0]) <= r[0] && r[0] <= std::max(p[0], q[0]) && std::min(p[1], q[1]) <= r[1] &&
           r[1] <= std::max(p[1], q[1]);
  };
  return (o1 == 0 && on(a, b, c)) || (o2 == 0 && on(a, b, d)) || (o3 == 0 && on(c, d, a)) || (o4 == 0 && on(c, d, b));
}

// The drawing is what group_into_regions requires (an embedded face): edges
// meet only at the corners they share.
bool embedded(const std::vector<DrawnLoop>& drawn) {
  struct Segment {
    Lattice a, b;
  };
  std::vector<Segment> segments;
  for (const DrawnLoop& d : drawn) {
    for (std::size_t i = 0; i < d.corners.size(); ++i) segments.push_back({d.corners[i], d.corners[(i + 1) % d.corners.size()]});
  }
  for (std::size_t i = 0; i < segments.size(); ++i) {
    for (std::size_t j = i + 1; j < segments.size(); ++j) {
      const Segment &s = segments[i], &t = segments[j];
      const bool shared = s.a == t.a || s.a == t.b || s.b == t.a || s.b == t.b;
      if (!shared && segments_meet(s.a, s.b, t.a, t.b)) return false;
      // Sharing a corner: they must not overlap beyond it.
      if (shared) {
        const Lattice& corner = s.a == t.a || s.a == t.b ? s.a : s.b;
        const Lattice& s_far = s.a == corner ? s.b : s.a;
        const Lattice& t_far = t.a == corner ? t.b : t.a;
        if (orient2(corner, s_far, t_far) == 0 &&
            (s_far[0] - corner[0]) * (t_far[0] - corner[0]) + (s_far[1] - corner[1]) * (t_far[1] - corner[1]) > 0) {
          return false;
        }
      }
    }
  }
  return true;
}

using EdgeKey = std::pair<VertexIndex, VertexIndex>;

struct Tally {
  std::size_t regions = 0, holes = 0, convex_loops = 0, concave_loops = 0, inside = 0, outside = 0,
              on_vertex_rows = 0, on_boundary = 0;
};

// Groups the drawn loops' edges and checks the regions against the drawing.
void check_grouping(FacePlane& plane, const std::vector<DrawnLoop>& drawn, Random& random, Tally& tally) {
  REQUIRE(embedded(drawn));
  // Vertex numbers by first appearance in a random order, so regions and loops
  // do not come out in drawing order by accident.
  std::vector<std::size_t> order(drawn.size());
  std::iota(order.begin(), order.end(), 0u);
  for (std::size_t i = order.size(); i > 1; --i) std::swap(order[i - 1], order[random.index(i)]);
  std::vector<std::vector<VertexIndex>> vertices(drawn.size());
  for (const std::size_t d : order) {
    for (const Lattice& p : drawn[d].corners) vertices[d].push_back(plane.add(p));
  }
  std::vector<LoopEdge> edges;
  std::map<std::set<EdgeKey>, std::size_t> drawn_of_edges;
  for (std::size_t d = 0; d < drawn.size(); ++d) {
    std::set<EdgeKey> keys;
    for (std::size_t i = 0; i < vertices[d].size(); ++i) {
      const VertexIndex a = vertices[d][i], b = vertices[d][(i + 1) % vertices[d].size()];
      edges.push_back({a, b, {}});
      keys.insert({a, b});
    }
    drawn_of_edges[keys] = d;
  }
  for (std::size_t i = edges.size(); i > 1; --i) std::swap(edges[i - 1], edges[random.index(i)]);
  std::multiset<EdgeKey> given;
  for (const LoopEdge& e : edges) given.insert({e.from, e.to});

  const FaceGeometry geometry = plane.geometry();
  std::vector<Region> regions;
  group_into_regions(geometry, edges, regions);

  std::size_t expected_regions = 0;
  for (const DrawnLoop& d : drawn) expected_regions += d.outer;
  REQUIRE(regions.size() == expected_regions);
  std::multiset<EdgeKey> linked;
  std::vector<int> found(drawn.size(), 0);
  for (const Region& region : regions) {
    REQUIRE_FALSE(region.loops.empty());
    std::vector<std::size_t> ids;
    std::int64_t region_area = 0;
    for (const auto& loop : region.loops) {
      std::set<VertexIndex> seen;
      std::set<EdgeKey> keys;
      std::vector<Lattice> corners;
      for (std::size_t i = 0; i < loop.size(); ++i) {
        CHECK(loop[i].to == loop[(i + 1) % loop.size()].from);  // chained head to tail, closed
        CHECK(seen.insert(loop[i].from).second);                // simple
        keys.insert({loop[i].from, loop[i].to});
        linked.insert({loop[i].from, loop[i].to});
        corners.push_back(plane.lattice(loop[i].from));
      }
      const auto match = drawn_of_edges.find(keys);
      REQUIRE(match != drawn_of_edges.end());  // exactly a drawn loop
      ids.push_back(match->second);
      ++found[match->second];
      region_area += twice_area(corners);
      // Convex: no right turn, decided here on the lattice.
      bool convex = true;
      for (std::size_t i = 0; i < corners.size(); ++i) {
        convex = convex && orient2(corners[i], corners[(i + 1) % corners.size()], corners[(i + 2) % corners.size()]) >= 0;
      }
      CHECK(is_convex_loop(geometry, loop) == convex);
      ++(convex ? tally.convex_loops : tally.concave_loops);
    }
    // The outer loop first, then exactly the holes drawn directly inside it.
    const std::size_t outer = ids.front();
    CHECK(drawn[outer].outer);
    std::set<std::size_t> holes(ids.begin() + 1, ids.end()), expected_holes;
    for (std::size_t d = 0; d < drawn.size(); ++d) {
      if (!drawn[d].outer && drawn[d].owner == static_cast<int>(outer)) expected_holes.insert(d);
    }
    CHECK(holes == expected_holes);
    CHECK(region_area > 0);
    ++tally.regions;
    tally.holes += holes.size();
  }
  CHECK(linked == given);  // every edge in exactly one loop
  CHECK(std::all_of(found.begin(), found.end(), [](int n) { return n == 1; }));
}

// inside_loop against a ray cast on the lattice (half-open rule, exact), for
// points anywhere, many of them level with a vertex (the ray through a corner).
void check_inside(FacePlane& plane, const std::vector<DrawnLoop>& drawn, Random& random, Tally& tally) {
  std::vector<Lattice> queries;
  Lattice lo{INT64_MAX, INT64_MAX}, hi{INT64_MIN, INT64_MIN};
  for (const DrawnLoop& d : drawn) {
    for (const Lattice& p : d.corners) {
      for (int a = 0; a < 2; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
    }
  }
  for (int k = 0; k < 40; ++k) {
    Lattice p{lo[0] + static_cast<std::int64_t>(random.index(static_cast<std::size_t>(hi[0] - lo[0] + 1))),
              lo[1] + static_cast<std::int64_t>(random.index(static_cast<std::size_t>(hi[1] - lo[1] + 1)))};
    if (k % 2 == 1) {
      // Level with a corner, seen along any of the frame's projections: the
      // point differs from a corner in one lattice coordinate only.
      const DrawnLoop& d = drawn[random.index(drawn.size())];
      const Lattice& corner = d.corners[random.index(d.corners.size())];
      p[random.index(2)] = corner[random.index(2)];
    }
    queries.push_back(p);
  }
  // At the place of a corner, as another vertex (copies of a vertex lie at one
  // point where a piece meets itself along a chord): on the loop for
  // locate_in_loop.
  const std::size_t drawn_queries = queries.size();
  for (const DrawnLoop& d : drawn) queries.push_back(d.corners.front());
  std::vector<VertexIndex> query_vertices;
  for (std::size_t q = 0; q < queries.size(); ++q) {
    query_vertices.push_back(q < drawn_queries ? plane.add(queries[q]) : plane.add_copy(queries[q]));
  }
  const FaceGeometry geometry = plane.geometry();
  for (std::size_t q = 0; q < queries.size(); ++q) {
    const Lattice& p = queries[q];
    for (const DrawnLoop& d : drawn) {
      const auto& c = d.corners;
      bool on_boundary = false, inside = false;
      for (std::size_t i = 0; i < c.size(); ++i) {
        const Lattice& a = c[i];
        const Lattice& b = c[(i + 1) % c.size()];
        if (orient2(a, b, p) == 0 && std::min(a[0], b[0]) <= p[0] && p[0] <= std::max(a[0], b[0]) &&
            std::min(a[1], b[1]) <= p[1] && p[1] <= std::max(a[1], b[1])) {
          on_boundary = true;
        }
        if ((a[1] <= p[1]) != (b[1] <= p[1])) {
          // The edge crosses the row of p; it crosses to p's right when p is on
          // the left of the upward-directed edge.
          const bool upward = b[1] > a[1];
          if ((orient2(a, b, p) > 0) == upward) inside = !inside;
        }
      }
      std::vector<LoopEdge> loop;
      for (std::size_t i = 0; i < c.size(); ++i) loop.push_back({plane.add(c[i]), plane.add(c[(i + 1) % c.size()]), {}});
      INFO("point (" << p[0] << ", " << p[1] << ")");
      const Sign located = locate_in_loop(geometry, query_vertices[q], loop);
      CHECK(located == (on_boundary ? Sign::zero : inside ? Sign::positive : Sign::negative));
      tally.on_boundary += on_boundary;
      if (on_boundary) continue;  // inside_loop's precondition
      CHECK(inside_loop(geometry, query_vertices[q], loop) == inside);
      ++(inside ? tally.inside : tally.outside);
      for (const Lattice& corner : c) tally.on_vertex_rows += corner[1] == p[1] || corner[0] == p[0];
    }
  }
}

}  // namespace

TEST_CASE("group_into_regions: random nests of rings on every kind of plane (seeds 1 to 16)",
          "[plane][face-loops][property]") {
  Tally tally;
  std::size_t cases = 0;
  for (const Frame& frame : frames()) {
    for (std::uint64_t seed = 1; seed <= 16; ++seed) {
      INFO(frame.name << ", seed " << seed);
      Random random(seed * 7919 + frame.name.size());
      FacePlane plane(frame);
      std::vector<DrawnLoop> drawn;
      // One to three nests side by side, each up to four levels deep.
      const int nests = 1 + static_cast<int>(random.index(3));
      const double size = 0x1p20;
      for (int n = 0; n < nests; ++n) {
        draw_rings(random, n * size * 1.1, 0, size, 0, static_cast<int>(random.index(4)), -1, drawn);
      }
      check_grouping(plane, drawn, random, tally);
      check_inside(plane, drawn, random, tally);
      ++cases;
    }
  }
  INFO(tally.regions << " regions, " << tally.holes << " holes, " << tally.convex_loops << " convex and "
                     << tally.concave_loops << " other loops; inside_loop: " << tally.inside << " in, "
                     << tally.outside << " out");
  CHECK(cases == frames().size() * 16);
  CHECK(tally.regions >= 500);
  CHECK(tally.holes >= 300);
  CHECK(tally.convex_loops >= 100);
  CHECK(tally.concave_loops >= 300);
  CHECK(tally.inside >= 300);
  CHECK(tally.outside >= 1000);
  CHECK(tally.on_vertex_rows >= 200);
  // Points on a loop, as locate_in_loop finds them: on its edges, at its
  // corners, and copies of its corners (another vertex at the place).
  CHECK(tally.on_boundary >= 100);
}

TEST_CASE("group_into_regions: loops touching at a vertex stay simple and keep their roles", "[plane][face-loops]") {
  // Each figure is drawn on the lattice, placed by a random shift and scale on
  // every frame; touching corners are one vertex.
  struct Figure {
    std::string name;
    std::vector<DrawnLoop> loops;
  };
  const auto square = [](std::int64_t x0, std::int64_t y0, std::int64_t x1, std::int64_t y1, bool clockwise) {
    std::vector<Lattice> c{{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
    if (clockwise) std::reverse(c.begin(), c.end());
    return c;
  };
  const std::vector<Figure> figures{
      {"two squares sharing a corner (a bow tie)", {{square(0, 0, 2, 2, false), true}, {square(2, 2, 4, 4, false), true}}},
      {"a hole touching its outer loop", {{square(0, 0, 4, 4, false), true}, {{{4, 4}, {3, 1}, {1, 3}}, false, 0}}},
      {"two holes touching each other",
       {{square(0, 0, 6, 6, false), true}, {square(1, 1, 3, 3, true), false, 0}, {square(3, 3, 5, 5, true), false, 0}}},
      {"an island touching its hole",
       {{square(0, 0, 8, 8, false), true}, {square(1, 1, 7, 7, true), false, 0}, {{{7, 7}, {3, 5}, {5, 3}}, true}}},
      // Two regions: the hole is placed by a corner of its own, not the shared one.
      {"a hole touching its outer loop, beside a second region",
       {{square(0, 0, 4, 4, false), true}, {{{4, 4}, {3, 1}, {1, 3}}, false, 0}, {square(10, 0, 12, 2, false), true}}},
  };
  std::size_t checked = 0;
  Tally tally;
  for (const Frame& frame : frames()) {
    for (const Figure& figure : figures) {
      for (std::uint64_t seed = 1; seed <= 3; ++seed) {
        INFO(frame.name << ": " << figure.name << ", seed " << seed);
        Random random(seed);
        const std::int64_t scale = 1 + static_cast<std::int64_t>(random.index(1000));
        const std::int64_t dx = static_cast<std::int64_t>(random.index(20000)) - 10000;
        const std::int64_t dy = static_cast<std::int64_t>(random.index(20000)) - 10000;
        std::vector<DrawnLoop> drawn = figure.loops;
        for (DrawnLoop& d : drawn) {
          for (Lattice& p : d.corners) p = {p[0] * scale + dx, p[1] * scale + dy};
        }
        FacePlane plane(frame);
        check_grouping(plane, drawn, random, tally);
        ++checked;
      }
    }
  }
  CHECK(checked == frames().size() * figures.size() * 3);
  CHECK(tally.holes == frames().size() * 3 * 5);
}

TEST_CASE("group_into_regions: a face pinched at its hole's corners falls into the spikes around it",
          "[plane][face-loops]") {
  // A three-pointed star whose core triangle is a hole touching the star at all
  // three of its corners: what remains is three triangular spikes meeting only
  // at vertices, three regions with no hole. Every loop still comes out simple,
  // counter-clockwise, and the spikes' areas add up to the star's minus the core.
  const Lattice tips[] = {{0, 100}, {-87, -50}, {87, -50}};
  const Lattice notches[] = {{26, 15}, {-26, 15}, {0, -30}};
  std::size_t checked = 0;
  for (const Frame& frame : frames()) {
    FacePlane plane(frame);
    std::vector<VertexIndex> star, core;
    const Lattice outline[] = {tips[0], notches[1], tips[1], notches[2], tips[2], notches[0]};
    for (const Lattice& p : outline) star.push_back(plane.add(p));
    for (const Lattice& p : {notches[0], notches[2], notches[1]}) core.push_back(plane.add(p));  // clockwise
    std::vector<LoopEdge> edges;
    for (const auto* loop : {&star, &core}) {
      for (std::size_t i = 0; i < loop->size(); ++i) edges.push_back({(*loop)[i], (*loop)[(i + 1) % loop->size()], {}});
    }
    std::vector<Region> regions;
    group_into_regions(plane.geometry(), edges, regions);
    INFO(frame.name);
    REQUIRE(regions.size() == 3);
    std::vector<Lattice> outline_points(std::begin(outline), std::end(outline));
    std::vector<Lattice> core_points{notches[0], notches[2], notches[1]};
    std::int64_t total = 0;
    for (const Region& region : regions) {
      REQUIRE(region.loops.size() == 1);
      REQUIRE(region.loops.front().size() == 3);
      std::vector<Lattice> corners;
      for (const LoopEdge& e : region.loops.front()) corners.push_back(plane.lattice(e.from));
      CHECK(twice_area(corners) > 0);
      total += twice_area(corners);
    }
    CHECK(total == twice_area(outline_points) + twice_area(core_points));
    ++checked;
  }
  CHECK(checked == frames().size());
}

TEST_CASE("group_into_regions refuses loops that bound no region", "[plane][face-loops][errors]") {
  std::size_t refused = 0;
  for (const Frame& frame : frames()) {
    INFO(frame.name);
    {
      // Only clockwise loops: holes with nothing around them.
      FacePlane plane(frame);
      std::vector<LoopEdge> edges;
      const Lattice square[] = {{0, 0}, {0, 5}, {5, 5}, {5, 0}};
      for (int i = 0; i < 4; ++i) edges.push_back({plane.add(square[i]), plane.add(square[(i + 1) % 4]), {}});
      std::vector<Region> regions;
      CHECK_THROWS_AS(group_into_regions(plane.geometry(), edges, regions), UnsupportedGeometryError);
      ++refused;
    }
    {
      // Two outer loops and a hole inside neither.
      FacePlane plane(frame);
      std::vector<LoopEdge> edges;
      const auto add_square = [&](std::int64_t x, bool clockwise) {
        std::vector<Lattice> c{{x, 0}, {x + 4, 0}, {x + 4, 4}, {x, 4}};
        if (clockwise) std::reverse(c.begin(), c.end());
        for (std::size_t i = 0; i < 4; ++i) edges.push_back({plane.add(c[i]), plane.add(c[(i + 1) % 4]), {}});
      };
      add_square(0, false);
      add_square(10, false);
      add_square(20, true);
      std::vector<Region> regions;
      CHECK_THROWS_AS(group_into_regions(plane.geometry(), edges, regions), UnsupportedGeometryError);
      ++refused;
    }
    {
      // No edges: no regions.
      FacePlane plane(frame);
      std::vector<LoopEdge> edges;
      std::vector<Region> regions(2);
      group_into_regions(plane.geometry(), edges, regions);
      CHECK(regions.empty());
    }
  }
  CHECK(refused == 2 * frames().size());
}
