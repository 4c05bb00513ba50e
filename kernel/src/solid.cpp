#include "shatter/kernel/solid.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <numeric>
#include <string>

#include "shatter/kernel/error.hpp"
#include "shatter/kernel/index_map.hpp"
#include "shatter/kernel/predicates.hpp"
#include "shatter/kernel/union_find.hpp"

namespace shatter {
namespace {

using EpickPoint = CGAL::Epick::Point_3;
EpickPoint epick(const Vec3& p) { return {p.x, p.y, p.z}; }

// Exact: do the triangles (u, v, a) and (v, u, b), sharing edge u-v, lie on one
// plane and continue each other (a and b on opposite sides of the edge)?
bool flat_continuation(const Vec3& u, const Vec3& v, const Vec3& a, const Vec3& b) {
  if (CGAL::orientation(epick(u), epick(v), epick(a), epick(b)) != CGAL::COPLANAR) return false;
  // Coplanar: opposite sides of the line u-v within the plane.
  return CGAL::coplanar_orientation(epick(u), epick(v), epick(a), epick(b)) == CGAL::NEGATIVE;
}

VertexIndex third_vertex(const Triangle& t, VertexIndex u, VertexIndex v) {
  for (VertexIndex w : t) {
    if (w != u && w != v) return w;
  }
  return t[0];
}

}  // namespace

Solid solid_from_mesh(const Mesh& mesh, bool merge_coplanar, InputGeometry& geometry) {
  const std::size_t triangle_count = mesh.triangles.size();
  IndexMap triangle_of_edge(triangle_count * 3);
  for (TriangleIndex t = 0; t < triangle_count; ++t) {
    const Triangle& tri = mesh.triangles[t];
    for (int c = 0; c < 3; ++c) {
      const std::uint64_t key = directed_edge_key(tri[c], tri[(c + 1) % 3]);
      if (triangle_of_edge.insert(key, t) != t) {
        throw InvalidMeshError("solid_from_mesh: directed edge used twice (not a consistently oriented manifold)");
      }
    }
  }
  auto twin_of = [&](VertexIndex u, VertexIndex v) {
    const std::uint32_t t = triangle_of_edge.find(directed_edge_key(v, u));
    if (t == IndexMap::absent) throw InvalidMeshError("solid_from_mesh: open mesh (an edge has one triangle)");
    return t;
  };

  // Groups of coplanar triangles.
  UnionFind groups(triangle_count);
  if (merge_coplanar) {
    for (TriangleIndex t = 0; t < triangle_count; ++t) {
      const Triangle& tri = mesh.triangles[t];
      for (int c = 0; c < 3; ++c) {
        const VertexIndex u = tri[c], v = tri[(c + 1) % 3];
        const TriangleIndex other = twin_of(u, v);
        if (other < t) continue;
        const VertexIndex a = tri[(c + 2) % 3], b = third_vertex(mesh.triangles[other], u, v);
        if (mesh.surfaces[t] == mesh.surfaces[other] &&
            flat_continuation(mesh.positions[u], mesh.positions[v], mesh.positions[a], mesh.positions[b])) {
          groups.unite(t, other);
        }
      }
    }
  }

  // Each group's boundary edges, linked into loops by vertex index. A group whose
  // boundary passes a vertex twice (coplanar triangles touching at a point) is
  // split back into its triangles: a face is a region with simple loops.
  std::vector<std::uint32_t> group_of(triangle_count);
  std::vector<std::vector<TriangleIndex>> members;
  {
    std::vector<std::uint32_t> index_of_root(triangle_count, no_index);
    for (TriangleIndex t = 0; t < triangle_count; ++t) {
      const std::uint32_t root = groups.find(t);
      if (index_of_root[root] == no_index) {
        index_of_root[root] = static_cast<std::uint32_t>(members.size());
        members.emplace_back();
      }
      group_of[t] = index_of_root[root];
      members[group_of[t]].push_back(t);
    }
  }

  struct BoundaryEdge {
    VertexIndex u, v;
  };
  std::vector<std::vector<std::vector<VertexIndex>>> group_loops(members.size());
  std::vector<BoundaryEdge> boundary;
  IndexMap next_of;  // start vertex -> boundary edge
  for (std::size_t g = 0; g < members.size(); ++g) {
    if (members[g].size() == 1) {
      const Triangle& tri = mesh.triangles[members[g][0]];
      group_loops[g] = {{tri[0], tri[1], tri[2]}};
      continue;
    }
    boundary.clear();
    for (TriangleIndex t : members[g]) {
      const Triangle& tri = mesh.triangles[t];
      for (int c = 0; c < 3; ++c) {
        const VertexIndex u = tri[c], v = tri[(c + 1) % 3];
        if (group_of[twin_of(u, v)] != g) boundary.push_back({u, v});
      }
    }
    next_of.reset(boundary.size());
    bool pinched = false;
    for (std::uint32_t e = 0; e < boundary.size() && !pinched; ++e) {
      pinched = next_of.insert(boundary[e].u, e) != e;
    }
    if (!pinched) {
      std::vector<bool> used(boundary.size(), false);
      for (std::uint32_t e = 0; e < boundary.size(); ++e) {
        if (used[e]) continue;
        std::vector<VertexIndex> loop;
        for (std::uint32_t f = e; !used[f]; f = next_of.find(boundary[f].v)) {
          used[f] = true;
          loop.push_back(boundary[f].u);
        }
        group_loops[g].push_back(std::move(loop));
      }
    }
    if (pinched) {
      // Split the group back into single triangles, appended as new groups.
      for (std::size_t k = 1; k < members[g].size(); ++k) {
        const TriangleIndex t = members[g][k];
        group_of[t] = static_cast<std::uint32_t>(members.size());
        members.push_back({t});
        const Triangle& tri = mesh.triangles[t];
        group_loops.push_back({{tri[0], tri[1], tri[2]}});
      }
      members[g].resize(1);
      const Triangle& tri = mesh.triangles[members[g][0]];
      group_loops[g] = {{tri[0], tri[1], tri[2]}};
    }
  }

  // Planes: one input plane per group, through the points of its first triangle.
  const auto plane_base = static_cast<std::uint32_t>(geometry.planes.size());
  for (const auto& group : members) {
    const Triangle& tri = mesh.triangles[group.front()];
    geometry.planes.push_back({tri[0], tri[1], tri[2]});
    geometry.plane_approx.push_back(approximate_input_plane(mesh.positions[tri[0]], mesh.positions[tri[1]],
                                                            mesh.positions[tri[2]]));
  }
  auto plane_of_group = [&](std::uint32_t g) { return PlaneRef::input(plane_base + g); };
  // Two groups are coplanar only when merging was off (or undone at a pinch):
  // then the edge between them has no second plane, only its input segment.
  auto groups_coplanar = [&](std::uint32_t g, std::uint32_t h) {
    const Triangle& a = mesh.triangles[members[g].front()];
    const Triangle& b = mesh.triangles[members[h].front()];
    for (VertexIndex w : b) {
      if (CGAL::orientation(epick(mesh.positions[a[0]]), epick(mesh.positions[a[1]]), epick(mesh.positions[a[2]]),
                            epick(mesh.positions[w])) != CGAL::COPLANAR) {
        return false;
      }
    }
    return true;
  };

  Solid solid;
  std::vector<VertexIndex> local(mesh.positions.size(), no_index);
  for (std::uint32_t g = 0; g < members.size(); ++g) {
    SolidFace face;
    face.plane = plane_of_group(g);
    face.source = members[g].front();
    face.surface = mesh.surfaces[face.source];
    face.first_loop = static_cast<std::uint32_t>(solid.loops.size());
    face.loop_count = static_cast<std::uint32_t>(group_loops[g].size());
    for (const auto& loop : group_loops[g]) {
      solid.loops.push_back({static_cast<std::uint32_t>(solid.corners.size()), static_cast<std::uint32_t>(loop.size())});
      for (std::size_t i = 0; i < loop.size(); ++i) {
        const VertexIndex u = loop[i], v = loop[(i + 1) % loop.size()];
        if (local[u] == no_index) {
          local[u] = static_cast<VertexIndex>(solid.defs.size());
          solid.defs.push_back(PointDef::input(u));
        }
        const std::uint32_t across = group_of[twin_of(u, v)];
        EdgeLine line;
        line.p = std::min(u, v);
        line.q = std::max(u, v);
        if (!groups_coplanar(g, across)) line.other = plane_of_group(across);
        solid.corners.push_back({local[u], line});
      }
    }
    solid.faces.push_back(face);
  }

  const PlaneSet set = geometry.plane_set({});
  solid.approx.reserve(solid.defs.size());
  for (const PointDef& def : solid.defs) solid.approx.push_back(approximate(set, def));

  // Convexity of each face (one loop, no right turn) and of the solid.
  for (SolidFace& face : solid.faces) {
    if (face.loop_count != 1) continue;
    const SolidLoop& loop = solid.loops[face.first_loop];
    if (loop.corner_count == 3) {
      face.convex = true;
      continue;
    }
    const Projection projection = projection_of(set, face.plane);
    // No right turn at any corner: each edge against the one before it, the
    // first against the last.
    const auto left_or_straight = [&](VertexIndex a, VertexIndex b, VertexIndex c) {
      return orient_in_plane(set, projection, solid.defs[a], solid.approx[a], solid.defs[b], solid.approx[b],
                             solid.defs[c], solid.approx[c]) != Sign::negative;
    };
    VertexIndex before = solid.corners[loop.first_corner + loop.corner_count - 1].vertex;
    bool convex = true;
    for (const CornerEdge& edge : loop_edges(solid.corners, loop)) {
      convex = left_or_straight(before, edge.from, edge.to);
      if (!convex) break;
      before = edge.from;
    }
    face.convex = convex;
  }
  solid.convex = solid_is_convex(set, solid);
  return solid;
}

Sign outward_side(const PlaneSet& set, const SolidFace& face, const PointDef& point, const ApproxPoint& approx) {
  const Sign s = side(set, face.plane, point, approx);
  return face.reversed ? flip(s) : s;
}

namespace {

// Directed edge (u -> v) -> the face whose loop runs it.
void map_edges_to_faces(const Solid& solid, IndexMap& face_of_edge) {
  face_of_edge.reset(solid.corners.size());
  for (std::uint32_t f = 0; f < solid.faces.size(); ++f) {
    const SolidFace& face = solid.faces[f];
    for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
      for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[l])) {
        face_of_edge.insert(directed_edge_key(edge.from, edge.to), f);
      }
    }
  }
}

}  // namespace

bool solid_is_convex(const PlaneSet& set, const Solid& solid) {
  IndexMap face_of_edge;
  map_edges_to_faces(solid, face_of_edge);
  UnionFind shells(solid.faces.size());
  for (std::uint32_t f = 0; f < solid.faces.size(); ++f) {
    const SolidFace& face = solid.faces[f];
    for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
      for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[l])) {
        const VertexIndex u = edge.from, v = edge.to;
        const std::uint32_t g = face_of_edge.find(directed_edge_key(v, u));
        if (g == IndexMap::absent) return false;  // not closed: no claim
        shells.unite(f, g);
        if (g < f) continue;  // each edge once
        // A vertex of the face across, off this face's plane, decides the edge.
        const SolidFace& across = solid.faces[g];
        Sign s = Sign::zero;
        for (std::uint32_t m = across.first_loop; m < across.first_loop + across.loop_count && s == Sign::zero; ++m) {
          const SolidLoop& other = solid.loops[m];
          for (std::uint32_t k = 0; k < other.corner_count && s == Sign::zero; ++k) {
            const VertexIndex x = solid.corners[other.first_corner + k].vertex;
            s = outward_side(set, face, solid.defs[x], solid.approx[x]);
          }
        }
        if (s == Sign::positive) return false;
      }
    }
  }
  for (std::uint32_t f = 1; f < solid.faces.size(); ++f) {
    if (shells.find(f) != shells.find(0)) return false;
  }
  return true;
}

std::string check_solid(const PlaneSet& set, const Solid& solid) {
  const std::size_t n = solid.defs.size();
  if (solid.approx.size() != n) return "approx and defs differ in size";
  std::vector<bool> used(n, false);
  IndexMap count_of_edge(solid.corners.size());
  std::vector<std::uint32_t> counts;
  for (std::uint32_t f = 0; f < solid.faces.size(); ++f) {
    const SolidFace& face = solid.faces[f];
    if (face.loop_count == 0) return "face " + std::to_string(f) + " has no loop";
    if (face.first_loop + face.loop_count > solid.loops.size()) return "face " + std::to_string(f) + ": loops out of range";
    for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
      const SolidLoop& loop = solid.loops[l];
      if (loop.corner_count < 3) return "loop " + std::to_string(l) + " has fewer than 3 corners";
      if (loop.first_corner + loop.corner_count > solid.corners.size()) return "loop " + std::to_string(l) + ": corners out of range";
      for (const CornerEdge& edge : loop_edges(solid.corners, loop)) {
        const VertexIndex u = edge.from, v = edge.to;
        if (u >= n) return "corner vertex out of range in face " + std::to_string(f);
        used[u] = true;
        if (u == v) return "repeated vertex " + std::to_string(u) + " in face " + std::to_string(f);
        const std::uint32_t slot = count_of_edge.insert(directed_edge_key(u, v), static_cast<std::uint32_t>(counts.size()));
        if (slot == counts.size()) counts.push_back(0);
        if (++counts[slot] > 1) return "directed edge (" + std::to_string(u) + ", " + std::to_string(v) + ") used twice";
        if (side(set, face.plane, solid.defs[u], solid.approx[u]) != Sign::zero) {
          return "vertex " + std::to_string(u) + " is not on the plane of face " + std::to_string(f);
        }
        const EdgeLine& line = edge.line;
        for (VertexIndex w : {u, v}) {
          if (line.other.bits != no_index && side(set, line.other, solid.defs[w], solid.approx[w]) != Sign::zero) {
            return "vertex " + std::to_string(w) + " of face " + std::to_string(f) + " is not on its edge's plane";
          }
          if (line.is_segment()) {
            const Projection projection = projection_of(set, face.plane);
            const PointDef p = PointDef::input(line.p), q = PointDef::input(line.q);
            if (orient_in_plane(set, projection, p, approximate(set, p), q, approximate(set, q), solid.defs[w],
                                solid.approx[w]) != Sign::zero) {
              return "vertex " + std::to_string(w) + " of face " + std::to_string(f) + " is off its edge's segment line";
            }
          }
        }
      }
    }
  }
  for (std::uint32_t f = 0; f < solid.faces.size(); ++f) {
    const SolidFace& face = solid.faces[f];
    for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
      for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[l])) {
        if (count_of_edge.find(directed_edge_key(edge.to, edge.from)) == IndexMap::absent) {
          return "edge (" + std::to_string(edge.from) + ", " + std::to_string(edge.to) +
                 ") has no reverse: the solid is open";
        }
      }
    }
  }
  for (VertexIndex v = 0; v < n; ++v) {
    if (!used[v]) return "vertex " + std::to_string(v) + " is unused";
  }
  return {};
}

mpq_class exact_six_volume(const PlaneSet& set, const Solid& solid) {
  std::vector<std::array<mpq_class, 3>> points;
  points.reserve(solid.defs.size());
  for (const PointDef& def : solid.defs) points.push_back(exact_coordinates(set, def));
  mpq_class six = 0;
  for (const SolidFace& face : solid.faces) {
    const auto& c = points[solid.corners[solid.loops[face.first_loop].first_corner].vertex];
    for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
      for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[l])) {
        const auto& a = points[edge.from];
        const auto& b = points[edge.to];
        six += c[0] * (a[1] * b[2] - a[2] * b[1]) - c[1] * (a[0] * b[2] - a[2] * b[0]) +
               c[2] * (a[0] * b[1] - a[1] * b[0]);
      }
    }
  }
  return six;
}

}  // namespace shatter
