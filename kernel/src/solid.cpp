#include "shatter/kernel/solid.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <numeric>
#include <string>
#include <utility>

#include "shatter/kernel/error.hpp"
#include "shatter/kernel/index_map.hpp"
#include "shatter/kernel/predicates.hpp"
#include "shatter/kernel/rationals.hpp"
#include "shatter/kernel/union_find.hpp"

namespace shatter {
namespace {

using EpickPoint = CGAL::Epick::Point_3;
EpickPoint epick(const Vec3& p) { return {p.x, p.y, p.z}; }

}  // namespace

Solid solid_from_mesh(const Mesh& mesh, bool merge_coplanar, InputGeometry& geometry, const HalfEdgeTwins* twins) {
  const std::size_t triangle_count = mesh.triangles.size();
  // Half-edge 3t + c runs from corner c of triangle t to corner c + 1. Each one's
  // twin (the same edge the other way) and the triangle that holds it.
  HalfEdgeTwins computed;
  if (twins == nullptr) {
    computed = half_edge_twins(mesh.triangles, mesh.positions.size());
    twins = &computed;
  }
  if (twins->repeated) {
    throw InvalidMeshError("solid_from_mesh: directed edge used twice (not a consistently oriented manifold)");
  }
  if (twins->first_unmatched != HalfEdgeTwins::none) {
    throw InvalidMeshError("solid_from_mesh: open mesh (an edge has one triangle)");
  }
  const std::vector<std::uint32_t>& twin = twins->twin;

  // Each edge once: are its two triangles on one plane (exact), and is it convex?
  // The same orientation decides all three: merging, which edges need a second
  // plane, and whether the solid is convex (every edge convex or flat, one shell).
  std::vector<std::uint8_t> coplanar_at(3 * triangle_count, 0);  // per half-edge
  UnionFind groups(triangle_count), shells(triangle_count);
  std::size_t shell_count = triangle_count;
  bool reflex_edge = false;
  for (TriangleIndex t = 0; t < triangle_count; ++t) {
    const Triangle& tri = mesh.triangles[t];
    for (std::uint32_t c = 0; c < 3; ++c) {
      const std::uint32_t h = 3 * t + c, opposite = twin[h];
      const TriangleIndex other = opposite / 3;
      if (other < t || (other == t && opposite < h)) continue;
      const VertexIndex u = tri[c], v = tri[(c + 1) % 3], a = tri[(c + 2) % 3];
      const VertexIndex b = mesh.triangles[other][(opposite % 3 + 2) % 3];
      const Sign turn = orient3d(mesh.positions[u], mesh.positions[v], mesh.positions[a], mesh.positions[b]);
      // Positive: b is on the side triangle (u, v, a) faces, outward.
      reflex_edge = reflex_edge || turn == Sign::positive;
      if (shells.unite(t, other)) --shell_count;
      if (turn != Sign::zero) continue;
      coplanar_at[h] = coplanar_at[opposite] = 1;
      // Coplanar and continuing each other (a and b on opposite sides of the edge).
      if (merge_coplanar && mesh.surfaces[t] == mesh.surfaces[other] &&
          CGAL::coplanar_orientation(epick(mesh.positions[u]), epick(mesh.positions[v]), epick(mesh.positions[a]),
                                     epick(mesh.positions[b])) == CGAL::NEGATIVE) {
        groups.unite(t, other);
      }
    }
  }

  // Groups numbered in the order of their first triangle.
  std::vector<std::uint32_t> group_of(triangle_count);
  std::vector<TriangleIndex> front;  // per group: its first triangle (source and plane)
  std::vector<std::uint32_t> member_start;
  {
    std::vector<std::uint32_t> index_of_root(triangle_count, no_index);
    for (TriangleIndex t = 0; t < triangle_count; ++t) {
      const std::uint32_t root = groups.find(t);
      if (index_of_root[root] == no_index) {
        index_of_root[root] = static_cast<std::uint32_t>(front.size());
        front.push_back(t);
      }
      group_of[t] = index_of_root[root];
    }
  }
  // Members of each group in triangle order (a counting sort).
  std::vector<TriangleIndex> members(triangle_count);
  {
    member_start.assign(front.size() + 1, 0);
    for (TriangleIndex t = 0; t < triangle_count; ++t) ++member_start[group_of[t] + 1];
    for (std::size_t g = 0; g < front.size(); ++g) member_start[g + 1] += member_start[g];
    std::vector<std::uint32_t> fill(member_start.begin(), member_start.end() - 1);
    for (TriangleIndex t = 0; t < triangle_count; ++t) members[fill[group_of[t]]++] = t;
  }

  // Each group's boundary loops, as half-edges (flat: loop l is
  // loop_half_edges[loop_start[l] .. loop_start[l + 1])), linked by vertex index.
  // A group whose boundary passes a vertex twice (coplanar triangles touching at
  // a point) is split back into its triangles: a face is a region with simple loops.
  std::vector<std::uint32_t> loop_half_edges, loop_start{0};
  std::vector<std::uint32_t> group_first_loop(front.size()), group_loop_count(front.size());
  const auto add_triangle_loop = [&](TriangleIndex t) {
    for (std::uint32_t c = 0; c < 3; ++c) loop_half_edges.push_back(3 * t + c);
    loop_start.push_back(static_cast<std::uint32_t>(loop_half_edges.size()));
  };
  loop_half_edges.reserve(3 * triangle_count);
  std::vector<std::uint32_t> boundary;  // half-edges
  std::vector<std::uint8_t> used;
  IndexMap next_of;  // start vertex -> boundary edge
  const std::size_t original_groups = front.size();
  for (std::uint32_t g = 0; g < original_groups; ++g) {
    group_first_loop[g] = static_cast<std::uint32_t>(loop_start.size() - 1);
    const std::uint32_t size = member_start[g + 1] - member_start[g];
    if (size == 1) {
      add_triangle_loop(front[g]);
      group_loop_count[g] = 1;
      continue;
    }
    boundary.clear();
    for (std::uint32_t m = member_start[g]; m < member_start[g + 1]; ++m) {
      for (std::uint32_t c = 0; c < 3; ++c) {
        const std::uint32_t h = 3 * members[m] + c;
        if (group_of[twin[h] / 3] != g) boundary.push_back(h);
      }
    }
    const auto start_of = [&](std::uint32_t h) { return mesh.triangles[h / 3][h % 3]; };
    const auto end_of = [&](std::uint32_t h) { return mesh.triangles[h / 3][(h % 3 + 1) % 3]; };
    next_of.reset(boundary.size());
    bool pinched = false;
    for (std::uint32_t e = 0; e < boundary.size() && !pinched; ++e) pinched = next_of.insert(start_of(boundary[e]), e) != e;
    if (!pinched) {
      used.assign(boundary.size(), 0);
      std::uint32_t loops = 0;
      for (std::uint32_t e = 0; e < boundary.size(); ++e) {
        if (used[e]) continue;
        for (std::uint32_t f = e; !used[f]; f = next_of.find(end_of(boundary[f]))) {
          used[f] = 1;
          loop_half_edges.push_back(boundary[f]);
        }
        loop_start.push_back(static_cast<std::uint32_t>(loop_half_edges.size()));
        ++loops;
      }
      group_loop_count[g] = loops;
    } else {
      // Split the group back into single triangles, appended as new groups.
      add_triangle_loop(front[g]);
      group_loop_count[g] = 1;
      for (std::uint32_t m = member_start[g] + 1; m < member_start[g + 1]; ++m) {
        const TriangleIndex t = members[m];
        group_of[t] = static_cast<std::uint32_t>(front.size());
        front.push_back(t);
        group_first_loop.push_back(static_cast<std::uint32_t>(loop_start.size() - 1));
        group_loop_count.push_back(1);
        add_triangle_loop(t);
      }
    }
  }

  // Planes: one input plane per group, through the points of its first triangle.
  const auto plane_base = static_cast<std::uint32_t>(geometry.planes.size());
  // Reserved: growing these (64-byte elements, one per face) by doubling copied
  // more than was written on a large mesh.
  geometry.planes.reserve(plane_base + front.size());
  geometry.plane_approx.reserve(plane_base + front.size());
  for (const TriangleIndex t : front) {
    const Triangle& tri = mesh.triangles[t];
    geometry.planes.push_back({tri[0], tri[1], tri[2]});
    geometry.plane_approx.push_back(approximate_input_plane(mesh.positions[tri[0]], mesh.positions[tri[1]],
                                                            mesh.positions[tri[2]]));
  }
  auto plane_of_group = [&](std::uint32_t g) { return PlaneRef::input(plane_base + g); };

  Solid solid;
  solid.faces.reserve(front.size());
  solid.loops.reserve(loop_start.size() - 1);
  solid.corners.reserve(loop_half_edges.size());
  solid.defs.reserve(mesh.positions.size());
  std::vector<VertexIndex> local(mesh.positions.size(), no_index);
  for (std::uint32_t g = 0; g < front.size(); ++g) {
    SolidFace face;
    face.plane = plane_of_group(g);
    face.source = front[g];
    face.surface = mesh.surfaces[face.source];
    face.first_loop = static_cast<std::uint32_t>(solid.loops.size());
    face.loop_count = group_loop_count[g];
    for (std::uint32_t l = group_first_loop[g]; l < group_first_loop[g] + group_loop_count[g]; ++l) {
      solid.loops.push_back({static_cast<std::uint32_t>(solid.corners.size()), loop_start[l + 1] - loop_start[l]});
      for (std::uint32_t k = loop_start[l]; k < loop_start[l + 1]; ++k) {
        const std::uint32_t h = loop_half_edges[k];
        const Triangle& tri = mesh.triangles[h / 3];
        const VertexIndex u = tri[h % 3], v = tri[(h % 3 + 1) % 3];
        if (local[u] == no_index) {
          local[u] = static_cast<VertexIndex>(solid.defs.size());
          solid.defs.push_back(PointDef::input(u));
        }
        EdgeLine line;
        line.p = std::min(u, v);
        line.q = std::max(u, v);
        // The groups on the two sides share a plane exactly when the two triangles
        // at this edge do (every group lies in one plane): then the edge has no
        // second plane, only its input segment.
        if (!coplanar_at[h]) line.other = plane_of_group(group_of[twin[h] / 3]);
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
  solid.convex = !reflex_edge && shell_count == 1;
  return solid;
}

PointDef edge_crossing_def(const SolidFace& face, const EdgeLine& line, PlaneRef plane) {
  if (line.is_segment()) return PointDef::segment_plane(line.p, line.q, plane);
  PlaneRef a = face.plane, b = line.other;
  if (b.bits < a.bits) std::swap(a, b);
  return PointDef::three_planes(a, b, plane);
}

Sign outward_side(const PlaneSet& set, const SolidFace& face, const PointDef& point, const ApproxPoint& approx) {
  const Sign s = side(set, face.plane, point, approx);
  return face.reversed ? flip(s) : s;
}

Sign compare_outward_normals(const PlaneSet& set, const SolidFace& a, const SolidFace& b) {
  const Sign s = compare_normals(set, a.plane, b.plane);
  return a.reversed != b.reversed ? flip(s) : s;
}

Sign outward_side_of_face(const PlaneSet& set, const SolidFace& face, const SolidFace& across,
                          std::span<const SolidLoop> loops, std::span<const SolidCorner> corners,
                          std::span<const PointDef> defs, std::span<const ApproxPoint> approx) {
  for (std::uint32_t m = across.first_loop; m < across.first_loop + across.loop_count; ++m) {
    const SolidLoop& loop = loops[m];
    for (std::uint32_t k = 0; k < loop.corner_count; ++k) {
      const VertexIndex x = corners[loop.first_corner + k].vertex;
      const Sign s = outward_side(set, face, defs[x], approx[x]);
      if (s != Sign::zero) return s;
    }
  }
  return Sign::zero;
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
  // Called once per non-convex parent's piece: the scratch is kept per thread
  // so that deciding a small piece allocates nothing.
  thread_local IndexMap face_of_edge;
  thread_local UnionFind shells;
  map_edges_to_faces(solid, face_of_edge);
  shells.reset(solid.faces.size());
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
        if (outward_side_of_face(set, face, solid.faces[g], solid.loops, solid.corners, solid.defs, solid.approx) ==
            Sign::positive) {
          return false;
        }
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
