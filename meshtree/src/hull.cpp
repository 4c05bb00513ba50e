#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>

#include <vector>

#include "shatter/kernel/index_map.hpp"
#include "shatter/meshtree/build.hpp"

namespace shatter {
namespace {

using Epick = CGAL::Epick;
using EpickPoint = Epick::Point_3;

EpickPoint to_epick(const Vec3& p) { return {p.x, p.y, p.z}; }

// A closed, connected, outward surface that is convex or flat at every edge bounds
// a convex body, so checking each edge's two triangles is enough. Deep in a
// fracture almost every fragment is convex and this saves the hull computation.
// Orientation is exact (Epick's filtered predicate on the stored doubles).
thread_local IndexMap edge_to_triangle;

bool every_edge_convex(const Mesh& mesh) {
  IndexMap& opposite_of_edge = edge_to_triangle;
  opposite_of_edge.reset(mesh.triangles.size() * 3);
  for (TriangleIndex t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& tri = mesh.triangles[t];
    for (int c = 0; c < 3; ++c) {
      opposite_of_edge.insert(directed_edge_key(tri[c], tri[(c + 1) % 3]), tri[(c + 2) % 3]);
    }
  }
  for (const Triangle& tri : mesh.triangles) {
    const EpickPoint a = to_epick(mesh.positions[tri[0]]), b = to_epick(mesh.positions[tri[1]]),
                     c = to_epick(mesh.positions[tri[2]]);
    for (int k = 0; k < 3; ++k) {
      // The neighbour across edge (u, v) traverses it as (v, u).
      const std::uint32_t d = opposite_of_edge.find(directed_edge_key(tri[(k + 1) % 3], tri[k]));
      if (d == IndexMap::absent) return false;  // not closed: let the general path decide
      // Positive: d lies on the side the triangle's outward normal points to.
      if (CGAL::orientation(a, b, c, to_epick(mesh.positions[d])) == CGAL::NEGATIVE) return false;
    }
  }
  return true;
}

// Vertices whose triangles are used, renumbered in order of first use.
Mesh compact(const std::vector<Vec3>& positions, const std::vector<Triangle>& triangles) {
  Mesh hull;
  std::vector<VertexIndex> index_of(positions.size(), IndexMap::absent);
  hull.triangles.reserve(triangles.size());
  for (Triangle t : triangles) {
    for (VertexIndex& v : t) {
      if (index_of[v] == IndexMap::absent) {
        index_of[v] = static_cast<VertexIndex>(hull.positions.size());
        hull.positions.push_back(positions[v]);
      }
      v = index_of[v];
    }
    hull.triangles.push_back(t);
  }
  hull.surfaces.assign(hull.triangles.size(), original_surface);
  return hull;
}

}  // namespace

Mesh convex_hull_of(const Mesh& mesh) {
  if (every_edge_convex(mesh)) return compact(mesh.positions, mesh.triangles);

  std::vector<EpickPoint> points;
  points.reserve(mesh.positions.size());
  for (const Vec3& p : mesh.positions) points.push_back(to_epick(p));
  CGAL::Surface_mesh<EpickPoint> hull_mesh;
  CGAL::convex_hull_3(points.begin(), points.end(), hull_mesh);

  // convex_hull_3 gives triangles; a polygon face, should one come, is fanned
  // (hull faces are convex).
  Mesh hull;
  std::vector<VertexIndex> index_of(hull_mesh.number_of_vertices(), IndexMap::absent);
  for (auto v : hull_mesh.vertices()) {
    const EpickPoint& p = hull_mesh.point(v);
    index_of[v.idx()] = static_cast<VertexIndex>(hull.positions.size());
    hull.positions.push_back({p.x(), p.y(), p.z()});
  }
  std::vector<VertexIndex> face;
  for (auto f : hull_mesh.faces()) {
    face.clear();
    for (auto v : CGAL::vertices_around_face(hull_mesh.halfedge(f), hull_mesh)) face.push_back(index_of[v.idx()]);
    for (std::size_t i = 1; i + 1 < face.size(); ++i) hull.triangles.push_back({face[0], face[i], face[i + 1]});
  }
  hull.surfaces.assign(hull.triangles.size(), original_surface);
  return hull;
}

}  // namespace shatter
