#include "shatter/meshtree/hull.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "shatter/kernel/index_map.hpp"
#include "shatter/kernel/predicates.hpp"
#include "shatter/kernel/union_find.hpp"

namespace shatter {
namespace {

using Epick = CGAL::Epick;
using EpickPoint = Epick::Point_3;

EpickPoint to_epick(const Vec3& p) { return {p.x, p.y, p.z}; }

// A closed, connected, outward surface that is convex or flat at every edge bounds
// a convex body, so checking each edge's two triangles, and that the triangles are
// one edge-connected piece (a node can hold two separate boxes), is enough. Many
// fragments of convex inputs pass, and skip the hull computation. Orientation is
// exact (Epick's filtered predicate on the stored doubles).
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
    const EpickPoint a = to_epick(mesh.positions[tri[0]]), b = to_epick(mesh.positions[tri[1]]),
                     c = to_epick(mesh.positions[tri[2]]);
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
      if (CGAL::orientation(a, b, c, to_epick(mesh.positions[d])) == CGAL::POSITIVE) return false;
      if (piece_of.unite(t, n)) --pieces;
    }
  }
  return pieces == 1;
}

// --- a canonical hull ---------------------------------------------------------
// CGAL's hull is right, but the order of its output, and how it triangulates a
// face with four or more coplanar vertices, follow memory addresses, which differ
// between runs and threads. So the hull is rebuilt from what is unique: its facets
// (maximal groups of exactly coplanar adjacent triangles) and their strictly
// convex corners, each facet fanned from its least vertex.


bool lexicographically_less(const Vec3& a, const Vec3& b) {
  if (a.x != b.x) return a.x < b.x;
  if (a.y != b.y) return a.y < b.y;
  return a.z < b.z;
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

// The canonical form of a convex, closed, outward triangle surface over `positions`.
Mesh canonical_hull(const std::vector<Vec3>& positions, const std::vector<Triangle>& triangles) {
  IndexMap triangle_of_edge(3 * triangles.size());
  for (std::uint32_t t = 0; t < triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) triangle_of_edge.insert(directed_edge_key(triangles[t][k], triangles[t][(k + 1) % 3]), t);
  }
  UnionFind facet_of(triangles.size());
  for (std::uint32_t t = 0; t < triangles.size(); ++t) {
    const Triangle& tri = triangles[t];
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t n = triangle_of_edge.find(directed_edge_key(tri[(k + 1) % 3], tri[k]));
      if (n == IndexMap::absent || n < t) continue;
      VertexIndex opposite = triangles[n][0];
      for (VertexIndex v : triangles[n]) {
        if (v != tri[k] && v != tri[(k + 1) % 3]) opposite = v;
      }
      if (CGAL::orientation(to_epick(positions[tri[0]]), to_epick(positions[tri[1]]), to_epick(positions[tri[2]]),
                            to_epick(positions[opposite])) == CGAL::COPLANAR) {
        facet_of.unite(t, n);
      }
    }
  }
  std::vector<std::vector<VertexIndex>> corners_of(triangles.size());
  for (std::uint32_t t = 0; t < triangles.size(); ++t) {
    auto& corners = corners_of[facet_of.find(t)];
    corners.insert(corners.end(), triangles[t].begin(), triangles[t].end());
  }
  std::vector<std::vector<VertexIndex>> polygons;
  for (std::uint32_t t = 0; t < triangles.size(); ++t) {
    if (!corners_of[t].empty()) polygons.push_back(facet_polygon(positions, std::move(corners_of[t]), triangles[t]));
  }

  // Vertices in lexicographic order of their coordinates, facets fanned from their
  // least vertex, triangles sorted.
  std::vector<VertexIndex> used;
  for (const auto& polygon : polygons) used.insert(used.end(), polygon.begin(), polygon.end());
  std::sort(used.begin(), used.end());
  used.erase(std::unique(used.begin(), used.end()), used.end());
  std::sort(used.begin(), used.end(), [&](VertexIndex p, VertexIndex q) {
    return lexicographically_less(positions[p], positions[q]);
  });
  std::vector<VertexIndex> index_of(positions.size(), IndexMap::absent);
  Mesh hull;
  for (VertexIndex v : used) {
    index_of[v] = static_cast<VertexIndex>(hull.positions.size());
    hull.positions.push_back(positions[v]);
  }
  for (auto& polygon : polygons) {
    for (VertexIndex& v : polygon) v = index_of[v];
    std::rotate(polygon.begin(), std::min_element(polygon.begin(), polygon.end()), polygon.end());
    for (std::size_t i = 1; i + 1 < polygon.size(); ++i) hull.triangles.push_back({polygon[0], polygon[i], polygon[i + 1]});
  }
  std::sort(hull.triangles.begin(), hull.triangles.end());
  hull.surfaces.assign(hull.triangles.size(), original_surface);
  return hull;
}

}  // namespace

Mesh convex_hull_of(const Mesh& mesh) {
  if (convex_surface(mesh)) return canonical_hull(mesh.positions, mesh.triangles);
  return convex_hull_of_points(mesh.positions);
}

Mesh convex_hull_of_points(std::span<const Vec3> input) {
  std::vector<EpickPoint> points;
  points.reserve(input.size());
  for (const Vec3& p : input) points.push_back(to_epick(p));
  CGAL::Surface_mesh<EpickPoint> hull_mesh;
  CGAL::convex_hull_3(points.begin(), points.end(), hull_mesh);

  // convex_hull_3 gives triangles; a polygon face, should one come, is fanned
  // (hull faces are convex).
  std::vector<Vec3> positions(hull_mesh.num_vertices());  // indexed by Surface_mesh vertex index
  for (auto v : hull_mesh.vertices()) {
    const EpickPoint& p = hull_mesh.point(v);
    positions[v.idx()] = {p.x(), p.y(), p.z()};
  }
  std::vector<Triangle> triangles;
  std::vector<VertexIndex> face;
  for (auto f : hull_mesh.faces()) {
    face.clear();
    for (auto v : CGAL::vertices_around_face(hull_mesh.halfedge(f), hull_mesh)) face.push_back(static_cast<VertexIndex>(v.idx()));
    for (std::size_t i = 1; i + 1 < face.size(); ++i) triangles.push_back({face[0], face[i], face[i + 1]});
  }
  return canonical_hull(positions, triangles);
}

}  // namespace shatter
