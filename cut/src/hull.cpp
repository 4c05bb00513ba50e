#include "shatter/cut/hull.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <vector>

#include "shatter/kernel/index_map.hpp"
#include "shatter/kernel/predicates.hpp"
#include "shatter/kernel/union_find.hpp"

namespace shatter {
namespace {

// A closed, connected, outward surface that is convex or flat at every edge bounds
// a convex body, so checking each edge's two triangles, and that the triangles are
// one edge-connected piece (a node can hold two separate boxes), is enough. Many
// fragments of convex inputs pass, and skip the hull computation. Orientation is
// exact (the kernel's orient3d on the stored doubles).
thread_local IndexMap edge_to_triangle;

bool convex_surface(const Mesh& mesh) {
  IndexMap& triangle_of_edge = edge_to_triangle;
  triangle_of_edge.reset(mesh.triangles.size() * 3);
  for (TriangleIndex t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& tri = mesh.triangles[t];
    for (int c = 0; c < 3; ++c) triangle_of_edge.insert(directed_edge_key(tri[c], tri[(c + 1) % 3]), t);
  }
  UnionFind piece_of(mesh.triangles.size());
  std::size_t pieces = mesh.triangles.size();
  for (TriangleIndex t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& tri = mesh.triangles[t];
    const Vec3 a = mesh.positions[tri[0]], b = mesh.positions[tri[1]], c = mesh.positions[tri[2]];
    for (int k = 0; k < 3; ++k) {
      // The neighbour across edge (u, v) traverses it as (v, u).
      const VertexIndex u = tri[k], v = tri[(k + 1) % 3];
      const std::uint32_t n = triangle_of_edge.find(directed_edge_key(v, u));
      if (n == IndexMap::absent) return false;  // not closed: let the general path decide
      VertexIndex d = mesh.triangles[n][0];
      for (const VertexIndex corner : mesh.triangles[n]) {
        if (corner != u && corner != v) d = corner;
      }
      // Positive: d lies on the side the triangle's outward normal points to.
      if (orient3d(a, b, c, mesh.positions[d]) == Sign::positive) return false;
      if (piece_of.unite(t, n)) --pieces;
    }
  }
  return pieces == 1;
}

// --- a canonical hull ---------------------------------------------------------
// The hull below is right, but the order of its output, and how it triangulates
// a face with four or more coplanar vertices, follow the order points were added
// in; a convex mesh passed in as its own hull has its own triangulation. So the
// hull is rebuilt from what is unique: its facets
// (maximal groups of exactly coplanar adjacent triangles) and their strictly
// convex corners, each facet fanned from its least vertex.


bool lexicographically_less(const Vec3& a, const Vec3& b) {
  if (a.x != b.x) return a.x < b.x;
  if (a.y != b.y) return a.y < b.y;
  return a.z < b.z;
}

// The order of the point hull's input: lexicographic by value, and among
// points equal by value (-0 and +0 in some coordinate) the one with the
// negative zero first, coordinate by coordinate. Each point is then kept once
// as the least of its equals, whatever order the points came in: by value
// alone, which of them was kept, and so the hull's bits, followed the input order.
bool less_in_value_then_bits(const Vec3& a, const Vec3& b) {
  if (lexicographically_less(a, b)) return true;
  if (lexicographically_less(b, a)) return false;
  if (std::signbit(a.x) != std::signbit(b.x)) return std::signbit(a.x);
  if (std::signbit(a.y) != std::signbit(b.y)) return std::signbit(a.y);
  return std::signbit(a.z) && !std::signbit(b.z);
}

// The strictly convex corners of a facet, counter-clockwise seen from outside
// (the side `outward`, one of its triangles, faces). The facet is projected by
// dropping a coordinate, tried in the order the rounded normal suggests; the
// first projection in which `outward` keeps positive area, decided exactly, is
// used (hulls of fragments have needle facets whose rounded normal is noise).
// Any such projection gives the same corners in the same cyclic order.
std::vector<VertexIndex> facet_polygon(const std::vector<Vec3>& positions, std::vector<VertexIndex> corners,
                                       const Triangle& outward) {
  const Vec3 a = positions[outward[0]], b = positions[outward[1]], c = positions[outward[2]];
  const Vec3 n = cross(b - a, c - a);
  std::array<int, 3> axes{0, 1, 2};
  std::sort(axes.begin(), axes.end(), [&](int p, int q) { return std::fabs(n[p]) > std::fabs(n[q]); });
  int u = 0, w = 1;
  Sign facing = Sign::zero;
  for (const int dropped : axes) {
    u = (dropped + 1) % 3;  // (u, w, dropped) is right-handed
    w = (dropped + 2) % 3;
    facing = orient2d({a[u], a[w]}, {b[u], b[w]}, {c[u], c[w]});
    if (facing != Sign::zero) break;
  }
  const auto project = [&](VertexIndex v) { return Vec2{positions[v][u], positions[v][w]}; };
  const bool counter_clockwise = facing == Sign::positive;

  std::sort(corners.begin(), corners.end(), [&](VertexIndex p, VertexIndex q) {
    const Vec2 pp = project(p), qq = project(q);
    return pp.x != qq.x ? pp.x < qq.x : pp.y < qq.y;
  });
  corners.erase(std::unique(corners.begin(), corners.end()), corners.end());
  // Andrew's monotone chain; collinear points are dropped (orientation <= 0 pops).
  std::vector<VertexIndex> hull(2 * corners.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < corners.size(); ++i) {
    while (k >= 2 && orient2d(project(hull[k - 2]), project(hull[k - 1]), project(corners[i])) != Sign::positive) --k;
    hull[k++] = corners[i];
  }
  for (std::size_t i = corners.size() - 1, lower = k + 1; i-- > 0;) {
    while (k >= lower && orient2d(project(hull[k - 2]), project(hull[k - 1]), project(corners[i])) != Sign::positive) --k;
    hull[k++] = corners[i];
  }
  hull.resize(k - 1);  // the last point repeats the first
  if (!counter_clockwise) std::reverse(hull.begin(), hull.end());
  return hull;
}

// A closed convex surface as the hull algorithms hand it over: its triangles,
// each one's neighbour across edge (v[k], v[k + 1]), and whether that neighbour
// is exactly coplanar with it where the caller already decided so (quickhull
// decides it for the edges of its horizons; `unknown` elsewhere).
constexpr std::int8_t coplanarity_unknown = -1;
struct HullSurface {
  std::vector<Triangle> triangles;
  std::vector<std::array<std::uint32_t, 3>> next;
  std::vector<std::array<std::int8_t, 3>> coplanar;  // 1, 0 or coplanarity_unknown
};

// The canonical form of a convex, closed, outward triangle surface over `positions`.
// A facet of one triangle is that triangle (its three corners are strictly convex,
// in its own outward order), so only facets of two or more triangles are
// projected and swept by facet_polygon. Scratch is per thread: hulls are built
// once per node, in parallel. `positions_sorted`: the positions are in strictly
// increasing lexicographic order already, so index order is that order.
Mesh canonical_hull(const std::vector<Vec3>& positions, const HullSurface& surface, bool positions_sorted) {
  const std::vector<Triangle>& triangles = surface.triangles;
  const std::uint32_t count = static_cast<std::uint32_t>(triangles.size());
  thread_local UnionFind facet_of;
  facet_of.reset(count);
  for (std::uint32_t t = 0; t < count; ++t) {
    const Triangle& tri = triangles[t];
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t n = surface.next[t][k];
      if (n == IndexMap::absent || n < t) continue;
      bool flat = surface.coplanar[t][k] == 1;
      if (surface.coplanar[t][k] == coplanarity_unknown) {
        VertexIndex opposite = triangles[n][0];
        for (VertexIndex v : triangles[n]) {
          if (v != tri[k] && v != tri[(k + 1) % 3]) opposite = v;
        }
        flat = orient3d(positions[tri[0]], positions[tri[1]], positions[tri[2]], positions[opposite]) == Sign::zero;
      }
      if (flat) facet_of.unite(t, n);
    }
  }
  // The triangles grouped by facet (each facet's least triangle is its
  // representative), then each facet's corners as one polygon, all in one array.
  thread_local std::vector<std::uint32_t> facet_start, facet_members;
  facet_start.assign(count + 1, 0);
  for (std::uint32_t t = 0; t < count; ++t) ++facet_start[facet_of.find(t) + 1];
  for (std::uint32_t t = 0; t < count; ++t) facet_start[t + 1] += facet_start[t];
  facet_members.resize(count);
  {
    thread_local std::vector<std::uint32_t> fill;
    fill.assign(facet_start.begin(), facet_start.end() - 1);
    for (std::uint32_t t = 0; t < count; ++t) facet_members[fill[facet_of.find(t)]++] = t;
  }
  thread_local std::vector<VertexIndex> polygon_corners;
  thread_local std::vector<std::uint32_t> polygon_start;
  polygon_corners.clear();
  polygon_start.assign(1, 0);
  std::vector<VertexIndex> corners;
  for (std::uint32_t t = 0; t < count; ++t) {
    const std::uint32_t first = facet_start[t], last = facet_start[t + 1];
    if (first == last) continue;
    if (last - first == 1) {
      polygon_corners.insert(polygon_corners.end(), triangles[t].begin(), triangles[t].end());
    } else {
      corners.clear();
      for (std::uint32_t m = first; m < last; ++m) {
        corners.insert(corners.end(), triangles[facet_members[m]].begin(), triangles[facet_members[m]].end());
      }
      const std::vector<VertexIndex> polygon = facet_polygon(positions, corners, triangles[t]);
      polygon_corners.insert(polygon_corners.end(), polygon.begin(), polygon.end());
    }
    polygon_start.push_back(static_cast<std::uint32_t>(polygon_corners.size()));
  }

  // Vertices in lexicographic order of their coordinates, facets fanned from their
  // least vertex, triangles sorted.
  // The vertices used, in index order: marked, then collected (each is a corner
  // of about six facets' polygons, which a sort would order first).
  thread_local std::vector<std::uint8_t> is_used;
  is_used.assign(positions.size(), 0);
  for (const VertexIndex v : polygon_corners) is_used[v] = 1;
  thread_local std::vector<VertexIndex> used;
  used.clear();
  for (VertexIndex v = 0; v < positions.size(); ++v) {
    if (is_used[v]) used.push_back(v);
  }
  if (!positions_sorted) {
    std::sort(used.begin(), used.end(), [&](VertexIndex p, VertexIndex q) {
      return lexicographically_less(positions[p], positions[q]);
    });
  }
  thread_local std::vector<VertexIndex> index_of;
  index_of.resize(positions.size());
  Mesh hull;
  hull.positions.reserve(used.size());
  for (VertexIndex v : used) {
    index_of[v] = static_cast<VertexIndex>(hull.positions.size());
    hull.positions.push_back(positions[v]);
  }
  // A fan of a polygon of k corners has k - 2 triangles: the hull is kept in the
  // tree, so its arrays are sized exactly.
  hull.triangles.reserve(polygon_corners.size() - 2 * (polygon_start.size() - 1));
  for (std::size_t f = 0; f + 1 < polygon_start.size(); ++f) {
    const auto polygon = std::span(polygon_corners).subspan(polygon_start[f], polygon_start[f + 1] - polygon_start[f]);
    for (VertexIndex& v : polygon) v = index_of[v];
    std::rotate(polygon.begin(), std::min_element(polygon.begin(), polygon.end()), polygon.end());
    for (std::size_t i = 1; i + 1 < polygon.size(); ++i) hull.triangles.push_back({polygon[0], polygon[i], polygon[i + 1]});
  }
  std::sort(hull.triangles.begin(), hull.triangles.end());
  hull.surfaces.assign(hull.triangles.size(), original_surface);
  return hull;
}

// The same for a closed convex mesh's own triangles: their neighbours found by
// their directed edges, every coplanarity decided in canonical_hull.
Mesh canonical_hull(const std::vector<Vec3>& positions, const std::vector<Triangle>& triangles) {
  HullSurface surface;
  surface.triangles = triangles;
  surface.next.resize(triangles.size());
  surface.coplanar.assign(triangles.size(), {coplanarity_unknown, coplanarity_unknown, coplanarity_unknown});
  IndexMap& triangle_of_edge = edge_to_triangle;
  triangle_of_edge.reset(3 * triangles.size());
  for (std::uint32_t t = 0; t < triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) triangle_of_edge.insert(directed_edge_key(triangles[t][k], triangles[t][(k + 1) % 3]), t);
  }
  for (std::uint32_t t = 0; t < triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      surface.next[t][k] = triangle_of_edge.find(directed_edge_key(triangles[t][(k + 1) % 3], triangles[t][k]));
    }
  }
  return canonical_hull(positions, surface, false);
}

// --- quickhull ---------------------------------------------------------------
// Barber, Dobkin & Huhdanpaa, "The Quickhull Algorithm for Convex Hulls", ACM
// TOMS 22 (1996), on triangles, with every geometric decision an exact orient3d:
// a point is outside a triangle only when strictly beyond its plane. So a point
// on the hull (on a facet, an edge, or a duplicate of a vertex) is never added,
// no triangle is ever degenerate (its apex was strictly beyond a plane holding
// its base), and coplanar triangles are left for canonical_hull to merge. Which
// outside point is taken next (the furthest, in floating point) only steers the
// speed: any order gives the same hull, and canonical_hull the same mesh.
class Quickhull {
 public:
  // Precondition: points distinct, spanning a volume (checked: std::invalid_argument).
  explicit Quickhull(std::span<const Vec3> points) : points_(points), horizon_from_(points.size(), none) {
    // The floating-point choices (which point is furthest) are made on a copy
    // scaled by a power of two to magnitudes at most 1, so they cannot overflow,
    // whatever the input's magnitude (the tests trap overflow).
    double largest = 0;
    for (const Vec3& p : points) {
      largest = std::fmax(largest, std::fmax(std::fabs(p.x), std::fmax(std::fabs(p.y), std::fabs(p.z))));
    }
    int exponent = 0;
    std::frexp(largest, &exponent);
    scaled_.reserve(points.size());
    for (const Vec3& p : points) {
      scaled_.push_back({std::ldexp(p.x, -exponent), std::ldexp(p.y, -exponent), std::ldexp(p.z, -exponent)});
    }
    start();
    while (!pending_.empty()) {
      const std::uint32_t f = pending_.back();
      pending_.pop_back();
      if (faces_[f].alive && !faces_[f].outside.empty()) add_furthest_point_of(f);
    }
  }

  // The hull's triangles, outward, over the input's indices, with their
  // neighbours and the coplanarities the horizons decided.
  HullSurface surface() const {
    HullSurface result;
    std::vector<std::uint32_t> number(faces_.size(), IndexMap::absent);
    for (std::uint32_t f = 0; f < faces_.size(); ++f) {
      if (faces_[f].alive) number[f] = static_cast<std::uint32_t>(result.triangles.size()), result.triangles.push_back(faces_[f].v);
    }
    result.next.reserve(result.triangles.size());
    result.coplanar.reserve(result.triangles.size());
    for (const Face& face : faces_) {
      if (!face.alive) continue;
      result.next.push_back({number[face.next[0]], number[face.next[1]], number[face.next[2]]});
      result.coplanar.push_back(face.coplanar);
    }
    return result;
  }

 private:
  static constexpr std::uint32_t none = 0xffffffffu;

  struct Face {
    Triangle v{};                      // counter-clockwise seen from outside
    std::array<std::uint32_t, 3> next{};  // the face across edge (v[i], v[i + 1])
    Vec3 normal;                       // rounded, of the scaled points: only to pick the furthest point
    std::vector<std::uint32_t> outside;  // points strictly beyond this face, each in one face only
    // Per edge: whether the face across is exactly coplanar (1, 0, or
    // coplanarity_unknown), recorded where a horizon's test decided it.
    std::array<std::int8_t, 3> coplanar{};
    Sign eye_side = Sign::zero;  // of the current eye, for the faces tested in add_furthest_point_of
    std::uint32_t visible_mark = 0, tested_mark = 0;
    bool alive = false;
  };

  Sign side(const Face& face, std::uint32_t p) const {
    return orient3d(points_[face.v[0]], points_[face.v[1]], points_[face.v[2]], points_[p]);
  }

  std::uint32_t new_face(VertexIndex a, VertexIndex b, VertexIndex c) {
    std::uint32_t f;
    if (!free_.empty()) {
      f = free_.back();
      free_.pop_back();
    } else {
      f = static_cast<std::uint32_t>(faces_.size());
      faces_.emplace_back();
    }
    Face& face = faces_[f];
    face.v = {a, b, c};
    face.normal = cross(scaled_[b] - scaled_[a], scaled_[c] - scaled_[a]);
    face.outside.clear();
    face.coplanar = {coplanarity_unknown, coplanarity_unknown, coplanarity_unknown};
    face.alive = true;
    return f;
  }

  // Puts p in the outside set of a face of `candidates` it is strictly beyond:
  // the one it lies highest above in floating point if it is beyond that one,
  // else the first it is beyond; a point beyond none is inside the hull or on
  // it and is dropped. Trying the highest first (any face p is beyond would
  // do: the hull is the same) spares the exact tests of the faces before it,
  // nearly coplanar ones among them: a fifth of the hulls' orient3d calls on
  // fractured curved meshes, and 4-9 % of their time.
  void assign(std::uint32_t p, std::span<const std::uint32_t> candidates) {
    if (candidates.empty()) return;
    std::size_t highest = 0;
    double highest_height = -INFINITY;
    for (std::size_t i = 0; i < candidates.size(); ++i) {
      const Face& face = faces_[candidates[i]];
      const double height = dot(face.normal, scaled_[p] - scaled_[face.v[0]]);
      if (height > highest_height) highest_height = height, highest = i;
    }
    if (side(faces_[candidates[highest]], p) == Sign::positive) {
      faces_[candidates[highest]].outside.push_back(p);
      return;
    }
    for (std::size_t i = 0; i < candidates.size(); ++i) {
      if (i == highest) continue;
      if (side(faces_[candidates[i]], p) == Sign::positive) {
        faces_[candidates[i]].outside.push_back(p);
        return;
      }
    }
  }

  // A first tetrahedron, from points far apart (found in floating point, checked
  // exactly), its faces turned outward.
  void start() {
    const std::size_t n = points_.size();
    if (n < 4) throw std::invalid_argument("convex hull: fewer than four distinct points span no volume");
    // The lexicographically least and greatest points: distinct, as the points are.
    std::uint32_t a = 0, b = 0;
    for (std::uint32_t i = 1; i < n; ++i) {
      if (lexicographically_less(points_[i], points_[a])) a = i;
      if (lexicographically_less(points_[b], points_[i])) b = i;
    }
    const Vec3 ab = scaled_[b] - scaled_[a];
    const auto by_area = [&](std::uint32_t i) { const Vec3 w = cross(ab, scaled_[i] - scaled_[a]); return dot(w, w); };
    std::uint32_t c = a;
    for (std::uint32_t i = 0; i < n; ++i) {
      if (by_area(i) > by_area(c)) c = i;
    }
    if (collinear(a, b, c)) {
      c = none;
      for (std::uint32_t i = 0; i < n && c == none; ++i) {
        if (!collinear(a, b, i)) c = i;
      }
      if (c == none) throw std::invalid_argument("convex hull: the points are collinear");
    }
    const Vec3 normal = cross(scaled_[b] - scaled_[a], scaled_[c] - scaled_[a]);
    const auto by_height = [&](std::uint32_t i) { return std::fabs(dot(normal, scaled_[i] - scaled_[a])); };
    std::uint32_t d = a;
    for (std::uint32_t i = 0; i < n; ++i) {
      if (by_height(i) > by_height(d)) d = i;
    }
    if (orient3d(points_[a], points_[b], points_[c], points_[d]) == Sign::zero) {
      d = none;
      for (std::uint32_t i = 0; i < n && d == none; ++i) {
        if (orient3d(points_[a], points_[b], points_[c], points_[i]) != Sign::zero) d = i;
      }
      if (d == none) throw std::invalid_argument("convex hull: the points are coplanar");
    }
    // With d below the plane of (a, b, c), these four faces face outward.
    if (orient3d(points_[a], points_[b], points_[c], points_[d]) == Sign::positive) std::swap(b, c);
    const std::array<std::uint32_t, 4> first{new_face(a, b, c), new_face(a, d, b), new_face(b, d, c), new_face(c, d, a)};
    for (const std::uint32_t f : first) {
      for (int i = 0; i < 3; ++i) {
        const VertexIndex u = faces_[f].v[i], w = faces_[f].v[(i + 1) % 3];
        for (const std::uint32_t g : first) {
          for (int j = 0; j < 3; ++j) {
            if (faces_[g].v[j] == w && faces_[g].v[(j + 1) % 3] == u) faces_[f].next[i] = g;
          }
        }
      }
    }
    for (std::uint32_t p = 0; p < n; ++p) {
      if (p != a && p != b && p != c && p != d) assign(p, first);
    }
    for (const std::uint32_t f : first) {
      if (!faces_[f].outside.empty()) pending_.push_back(f);
    }
  }

  bool collinear(std::uint32_t a, std::uint32_t b, std::uint32_t c) const {
    // Three points are collinear exactly when all three axis projections are.
    const Vec3 p = points_[a], q = points_[b], r = points_[c];
    return orient2d({p.x, p.y}, {q.x, q.y}, {r.x, r.y}) == Sign::zero &&
           orient2d({p.y, p.z}, {q.y, q.z}, {r.y, r.z}) == Sign::zero &&
           orient2d({p.z, p.x}, {q.z, q.x}, {r.z, r.x}) == Sign::zero;
  }

  void add_furthest_point_of(std::uint32_t f) {
    // The eye: the outside point furthest from the face in floating point. It is
    // strictly beyond f (decided exactly when it was assigned), which is all the
    // steps below rely on.
    std::vector<std::uint32_t>& candidates = faces_[f].outside;
    const Vec3 origin = scaled_[faces_[f].v[0]], normal = faces_[f].normal;
    std::size_t best = 0;
    double best_height = -1;
    for (std::size_t i = 0; i < candidates.size(); ++i) {
      const double height = dot(normal, scaled_[candidates[i]] - origin);
      if (height > best_height) best_height = height, best = i;
    }
    const std::uint32_t eye = candidates[best];
    candidates[best] = candidates.back();
    candidates.pop_back();

    // The faces the eye is strictly beyond: a connected patch, as the hull is
    // convex, found from f across edges.
    ++mark_;
    visible_.clear();
    visible_.push_back(f);
    faces_[f].visible_mark = faces_[f].tested_mark = mark_;
    for (std::size_t k = 0; k < visible_.size(); ++k) {
      const Face& face = faces_[visible_[k]];
      for (const std::uint32_t g : face.next) {
        if (faces_[g].tested_mark == mark_) continue;
        faces_[g].tested_mark = mark_;
        faces_[g].eye_side = side(faces_[g], eye);
        if (faces_[g].eye_side == Sign::positive) {
          faces_[g].visible_mark = mark_;
          visible_.push_back(g);
        }
      }
    }

    // The horizon: the patch's boundary edges, oriented as in their visible
    // face. The patch is a disk, so they form one simple cycle, which each of
    // its vertices starts exactly one edge of.
    horizon_.clear();
    for (const std::uint32_t v : visible_) {
      const Face& face = faces_[v];
      for (int i = 0; i < 3; ++i) {
        const std::uint32_t g = face.next[i];
        if (faces_[g].visible_mark == mark_) continue;
        horizon_from_[face.v[i]] = static_cast<std::uint32_t>(horizon_.size());
        horizon_.push_back({face.v[i], face.v[(i + 1) % 3], g});
      }
    }

    // A cone of new faces from the horizon to the eye, in cycle order.
    cone_.clear();
    std::uint32_t e = 0;
    for (std::size_t k = 0; k < horizon_.size(); ++k) {
      const HorizonEdge& edge = horizon_[e];
      const std::uint32_t g = new_face(edge.from, edge.to, eye);
      cone_.push_back(g);
      faces_[g].next[0] = edge.beyond;
      Face& outer = faces_[edge.beyond];
      // The face across the horizon was tested against the eye above (it
      // borders a visible face): zero there is exact coplanarity of the two.
      const std::int8_t coplanar = outer.eye_side == Sign::zero ? 1 : 0;
      faces_[g].coplanar[0] = coplanar;
      for (int i = 0; i < 3; ++i) {
        if (outer.v[i] == edge.to && outer.v[(i + 1) % 3] == edge.from) outer.next[i] = g, outer.coplanar[i] = coplanar;
      }
      e = horizon_from_[edge.to];
    }
    if (e != 0) throw std::logic_error("convex hull: the horizon is not one cycle");
    for (std::size_t k = 0; k < cone_.size(); ++k) {
      faces_[cone_[k]].next[1] = cone_[(k + 1) % cone_.size()];                 // edge (to, eye)
      faces_[cone_[k]].next[2] = cone_[(k + cone_.size() - 1) % cone_.size()];  // edge (eye, from)
    }
    for (const HorizonEdge& edge : horizon_) horizon_from_[edge.from] = none;

    // The visible faces go; their outside points move to the cone (every point
    // still outside the hull is beyond some face of the cone: Barber et al.).
    for (const std::uint32_t v : visible_) {
      faces_[v].alive = false;
      for (const std::uint32_t p : faces_[v].outside) assign(p, cone_);
      faces_[v].outside.clear();
      free_.push_back(v);
    }
    for (const std::uint32_t g : cone_) {
      if (!faces_[g].outside.empty()) pending_.push_back(g);
    }
  }

  struct HorizonEdge {
    VertexIndex from, to;
    std::uint32_t beyond;  // the face across, not visible
  };

  std::span<const Vec3> points_;
  std::vector<Vec3> scaled_;  // points_ times a power of two, for the floating-point choices only
  std::vector<Face> faces_;
  std::vector<std::uint32_t> free_, pending_, visible_, cone_;
  std::vector<HorizonEdge> horizon_;
  std::vector<std::uint32_t> horizon_from_;  // per point: its horizon edge, or none
  std::uint32_t mark_ = 0;
};

}  // namespace

Mesh convex_hull_of(const Mesh& mesh) {
  if (convex_surface(mesh)) return canonical_hull(mesh.positions, mesh.triangles);
  return convex_hull_of_points(mesh.positions);
}

Mesh convex_hull_of_points(std::span<const Vec3> input) {
  // Duplicates removed first (a node's points repeat the vertices its children
  // share); the sort also makes the hull's work independent of the input order.
  std::vector<Vec3> points(input.begin(), input.end());
  // An internal node's points are its children's hull vertices, each hull's in
  // lexicographic order already: a few ascending runs, merged rather than sorted.
  constexpr std::size_t most_runs_merged = 8;
  std::vector<std::size_t> run_ends;
  for (std::size_t i = 1; i < points.size() && run_ends.size() < most_runs_merged; ++i) {
    if (less_in_value_then_bits(points[i], points[i - 1])) run_ends.push_back(i);
  }
  if (run_ends.size() < most_runs_merged) {
    run_ends.push_back(points.size());
    for (std::size_t k = 1; k < run_ends.size(); ++k) {
      std::inplace_merge(points.begin(), points.begin() + static_cast<std::ptrdiff_t>(run_ends[k - 1]),
                         points.begin() + static_cast<std::ptrdiff_t>(run_ends[k]), less_in_value_then_bits);
    }
  } else {
    std::sort(points.begin(), points.end(), less_in_value_then_bits);
  }
  points.erase(std::unique(points.begin(), points.end()), points.end());  // equal by value: the first kept
  const Quickhull hull(points);
  return canonical_hull(points, hull.surface(), true);
}

}  // namespace shatter
