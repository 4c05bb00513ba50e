// Where a rounded piece touches itself (a vertex or an edge shared by parts
// meeting there): its fans taken apart. See rounding.hpp.
#include "rounding.hpp"

#include <algorithm>
#include <cmath>

#include "shatter/kernel/face_loops.hpp"
#include "shatter/kernel/non_manifold.hpp"

namespace shatter {

// --- Where a piece touches itself -----------------------------------------------
// A cut can leave a piece that touches itself at a point, exactly: the plane
// passes through a saddle vertex of the surface whose two lobes on one side are
// one piece (several fans of faces meet at the vertex), or through the corner of
// a cavity or a dent that reaches the plane inside the cap (the corner touches
// the cap). No mesh of such a piece is valid, however it is rounded. The part
// thinner than the rounding, a point, gives way instead: each fan gets its own
// copy of the vertex, and every copy, and every corner touching a cap, moves a
// hair into its own fan's cone (along the mean direction to its neighbours).
// Certification then vouches for the result, as for any other rounding.

namespace rounding {

std::vector<VertexIndex> corners_touching_caps(const PlaneSet& set, const Solid& solid) {
  std::vector<VertexIndex> touching;
  std::vector<PlaneRef> planes;
  for (const SolidFace& face : solid.faces) {
    if (face.plane.is_cut() && std::find(planes.begin(), planes.end(), face.plane) == planes.end()) {
      planes.push_back(face.plane);
    }
  }
  std::vector<std::uint8_t> corner_of_plane;
  std::vector<LoopEdge> loop;
  for (const PlaneRef plane : planes) {
    corner_of_plane.assign(solid.defs.size(), 0);
    for (const SolidFace& face : solid.faces) {
      if (face.plane != plane) continue;
      for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
        for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[l])) corner_of_plane[edge.from] = 1;
      }
    }
    const FaceGeometry geometry{set, solid.defs, solid.approx, projection_of(set, plane), false};
    for (VertexIndex v = 0; v < solid.defs.size(); ++v) {
      if (corner_of_plane[v] || side(set, plane, solid.defs[v], solid.approx[v]) != Sign::zero) continue;
      for (const SolidFace& face : solid.faces) {
        if (face.plane != plane) continue;
        // On a loop (at the place of a corner: a copy of a vertex of a piece
        // that meets itself along a chord) touches the cap as well.
        bool inside = false, on = false;
        for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count && !on; ++l) {
          loop.clear();
          for (const CornerEdge& edge : loop_edges(solid.corners, solid.loops[l])) loop.push_back({edge.from, edge.to, {}});
          const Sign where = locate_in_loop(geometry, v, loop);
          on = where == Sign::zero;
          if (where == Sign::positive) inside = !inside;
        }
        if (inside || on) {
          touching.push_back(v);
          break;
        }
      }
    }
  }
  return touching;
}

// --- Edges that rounding made non-manifold ---------------------------------------
// A part of a piece thinner than the rounding can round onto an edge without
// flattening into a sheet: a neck squeezed to a segment, or two walls of a
// thin slot rounded onto one edge. The edge then has 2k triangles, k running it
// each way. As where a piece touches itself at a point, the part thinner than
// the rounding gives way: the triangles around the edge are paired in exact
// angular order, each pair bounding one wedge of the solid, and each pair gets
// its own copies of the edge's vertices (separate_touching), which then move a
// hair into their own wedges. This is how exact boolean operations on
// non-manifold input untangle an edge (CGAL's corefinement orders the faces
// around an edge with sorted_around_edge and pairs each face with the next one
// across the volume: Loriot, Tournois & Jamin, "Polygon Mesh Processing", CGAL
// 5.5 manual, section "Corefinement and Boolean Operations"; Granados et al.
// 2003, "Boolean operations on 3D selective Nef complexes", for the general
// radial order).

// pair_around_non_manifold_edges (shatter/kernel/non_manifold.hpp) pairs them.

Separation separate_touching(Mesh& mesh, std::span<const VertexIndex> touching, double scale,
                             std::span<const std::uint32_t> partner, std::span<const std::uint8_t> held) {
  const std::size_t n = mesh.positions.size();
  const auto vertex_of = [&](std::uint32_t corner, std::uint32_t step) {
    return mesh.triangles[corner / 3][(corner % 3 + step) % 3];
  };
  // The fans of every vertex where several meet, each vertex's first keeping it
  // (split_vertex_fans), and every vertex of `touching` that has one fan: all
  // move, in vertex order, each vertex's fans in the order of their first corner.
  std::vector<VertexFan> split = split_vertex_fans(mesh, partner);
  std::vector<std::uint8_t> wanted(n, 0);
  for (const VertexIndex v : touching) wanted[v] = 1;
  for (const VertexFan& fan : split) wanted[fan.split_from] = 0;
  std::vector<std::vector<std::uint32_t>> lone_corners(n);  // of the wanted vertices left whole, in triangle order
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    for (std::uint32_t c = 0; c < 3; ++c) {
      const VertexIndex v = mesh.triangles[t][c];
      if (v < n && wanted[v]) lone_corners[v].push_back(3 * t + c);
    }
  }
  std::vector<VertexFan> to_move;
  to_move.reserve(split.size() + touching.size());
  std::size_t next_split = 0;
  for (VertexIndex v = 0; v < n; ++v) {
    if (!lone_corners[v].empty()) to_move.push_back({v, v, std::move(lone_corners[v])});
    while (next_split < split.size() && split[next_split].split_from == v) to_move.push_back(std::move(split[next_split++]));
  }
  // Moving p to p' changes the volume by dot(p' - p, sum of (b - p) x (c - p))/6
  // over its fan's triangles (p, b, c): each fan is a closed ring, so this equals
  // the change of the divergence sum, and it is computed on differences near p,
  // not on coordinates near the origin. Each triangle's part is a tetrahedron no
  // thicker than the move over the triangle: at most distance x area / 3.
  // In doubles first, as the moves are made; where coordinates near the top of
  // the double range overflow the products (fuzz_slice regressions:
  // cube-ply-huge-coordinates-pinch.bin gave NaN for both), again exactly, on
  // rationals over the moved doubles, the bound in the L1 norm (an upper bound
  // of the Euclidean one): twice the area x the distance, a third of which
  // bounds the change.
  Separation result;
  double volume_change = 0, volume_bound = 0;
  struct Move {
    VertexIndex vertex;
    const std::vector<std::uint32_t>* corners;
    Vec3 from, to;
  };
  std::vector<Move> moves;
  for (const VertexFan& fan : to_move) {
    if (fan.vertex == fan.split_from && fan.vertex < held.size() && held[fan.vertex]) continue;
    const Vec3 p = mesh.positions[fan.vertex];
    Vec3 direction, normal_sum;
    double nearest = INFINITY, area = 0;
    for (const std::uint32_t corner : fan.corners) {
      const Vec3 b = mesh.positions[vertex_of(corner, 1)] - p, c = mesh.positions[vertex_of(corner, 2)] - p;
      for (const Vec3& d : {b, c}) {
        const double length = norm(d);
        if (length > 0) direction = direction + d * (1 / length), nearest = std::min(nearest, length);
      }
      normal_sum = normal_sum + cross(b, c);
      area += 0.5 * norm(cross(b, c));
    }
    const double length = norm(direction);
    if (!(length > 0) || !std::isfinite(nearest)) continue;
    const double distance = scale * nearest;
    const Vec3 move = direction * (distance / length);
    mesh.positions[fan.vertex] = p + move;
    volume_change += dot(move, normal_sum) / 6;
    volume_bound += distance * area;
    moves.push_back({fan.vertex, &fan.corners, p, mesh.positions[fan.vertex]});
    ++result.moved;
  }
  if (std::isfinite(volume_change) && std::isfinite(volume_bound)) {
    result.volume_change = std::fabs(volume_change);
    result.volume_bound = volume_bound;
    return result;
  }
  // Exactly: the moves replayed in order, each against the positions its
  // neighbours had when it was made, so that the changes add up to the whole.
  for (auto m = moves.rbegin(); m != moves.rend(); ++m) mesh.positions[m->vertex] = m->from;
  mpq_class volume_change6 = 0, bound = 0;
  for (const Move& m : moves) {
    const std::array<mpq_class, 3> from{mpq_class(m.from.x), mpq_class(m.from.y), mpq_class(m.from.z)};
    const std::array<mpq_class, 3> step{mpq_class(m.to.x) - from[0], mpq_class(m.to.y) - from[1], mpq_class(m.to.z) - from[2]};
    mpq_class twice_area1 = 0;
    for (const std::uint32_t corner : *m.corners) {
      const Vec3 &bp = mesh.positions[vertex_of(corner, 1)], &cp = mesh.positions[vertex_of(corner, 2)];
      const std::array<mpq_class, 3> b{mpq_class(bp.x) - from[0], mpq_class(bp.y) - from[1], mpq_class(bp.z) - from[2]};
      const std::array<mpq_class, 3> c{mpq_class(cp.x) - from[0], mpq_class(cp.y) - from[1], mpq_class(cp.z) - from[2]};
      const std::array<mpq_class, 3> normal{b[1] * c[2] - b[2] * c[1], b[2] * c[0] - b[0] * c[2], b[0] * c[1] - b[1] * c[0]};
      volume_change6 += step[0] * normal[0] + step[1] * normal[1] + step[2] * normal[2];
      twice_area1 += abs(normal[0]) + abs(normal[1]) + abs(normal[2]);
    }
    bound += (abs(step[0]) + abs(step[1]) + abs(step[2])) * twice_area1;
    mesh.positions[m.vertex] = m.to;
  }
  result.volume_change = abs(volume_change6) / 6;
  result.volume_bound = bound;
  return result;
}

}  // namespace rounding

}  // namespace shatter
