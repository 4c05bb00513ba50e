#include "support/degenerate.hpp"

#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <stdexcept>
#include <tuple>

#include "shatter/generators/solids.hpp"
#include "shatter/kernel/predicates.hpp"

namespace shatter::test {
namespace {

// A solid made of grid cells: cell (i, j, k) spans [xs[i], xs[i+1]] x [ys[j],
// ys[j+1]] x [zs[k], zs[k+1]]. Every face between a filled and an empty cell
// becomes two triangles facing the empty one, over vertices welded by grid
// index, so the surface is closed and outward by construction. The caller
// keeps cells from touching along an edge or a corner only (which would be a
// non-manifold edge or vertex). Uneven grids give needles and slivers with
// exactly the coordinates given.
using CellFilled = std::function<bool(int i, int j, int k)>;

Mesh grid_cell_solid(const std::vector<double>& xs, const std::vector<double>& ys, const std::vector<double>& zs,
                     const CellFilled& filled) {
  const std::array<int, 3> cells{int(xs.size()) - 1, int(ys.size()) - 1, int(zs.size()) - 1};
  auto inside = [&](std::array<int, 3> c) {
    for (int a = 0; a < 3; ++a) {
      if (c[a] < 0 || c[a] >= cells[a]) return false;
    }
    return filled(c[0], c[1], c[2]);
  };
  std::map<std::array<int, 3>, VertexIndex> vertex_of;
  std::vector<Vec3> positions;
  auto vertex = [&](std::array<int, 3> g) {
    auto [it, inserted] = vertex_of.try_emplace(g, VertexIndex(positions.size()));
    if (inserted) positions.push_back({xs[g[0]], ys[g[1]], zs[g[2]]});
    return it->second;
  };
  std::vector<Triangle> triangles;
  for (int i = 0; i < cells[0]; ++i) {
    for (int j = 0; j < cells[1]; ++j) {
      for (int k = 0; k < cells[2]; ++k) {
        if (!filled(i, j, k)) continue;
        for (int axis = 0; axis < 3; ++axis) {
          for (int step : {-1, 1}) {
            std::array<int, 3> neighbour{i, j, k};
            neighbour[axis] += step;
            if (inside(neighbour)) continue;
            // The face's corners counter-clockwise in (u, v) = (axis+1, axis+2):
            // e_u x e_v = e_axis, so this order faces +axis; reversed for -axis.
            const int u = (axis + 1) % 3, v = (axis + 2) % 3;
            std::array<VertexIndex, 4> corner{};
            const std::array<std::array<int, 2>, 4> uv{{{0, 0}, {1, 0}, {1, 1}, {0, 1}}};
            for (int c = 0; c < 4; ++c) {
              std::array<int, 3> g{i, j, k};
              if (step > 0) g[axis] += 1;
              g[u] += uv[c][0];
              g[v] += uv[c][1];
              corner[c] = vertex(g);
            }
            if (step < 0) std::swap(corner[1], corner[3]);
            // Alternate the diagonal so planes meet both kinds.
            if ((i + j + k) % 2 == 0) {
              triangles.push_back({corner[0], corner[1], corner[2]});
              triangles.push_back({corner[0], corner[2], corner[3]});
            } else {
              triangles.push_back({corner[1], corner[2], corner[3]});
              triangles.push_back({corner[1], corner[3], corner[0]});
            }
          }
        }
      }
    }
  }
  return mesh_from(std::move(positions), std::move(triangles));
}

std::vector<double> integers(int n) {
  std::vector<double> values;
  for (int i = 0; i <= n; ++i) values.push_back(i);
  return values;
}

// Adds a convex-from-its-first-vertex polygon (corners counter-clockwise seen
// from outside) as a fan from that vertex.
void add_fan(std::vector<Triangle>& triangles, const std::vector<VertexIndex>& polygon) {
  for (std::size_t i = 1; i + 1 < polygon.size(); ++i) triangles.push_back({polygon[0], polygon[i], polygon[i + 1]});
}

}  // namespace

Mesh staircase(int steps) {
  if (steps < 1) throw std::invalid_argument("staircase: steps >= 1");
  // Column x holds x + 1 cells: treads at z = x + 1, risers at x = k.
  return grid_cell_solid(integers(steps), integers(2), integers(steps), [](int i, int, int k) { return k <= i; });
}

Mesh stacked_boxes(int count) {
  if (count < 1) throw std::invalid_argument("stacked_boxes: count >= 1");
  // Floor k covers x cells k .. k+2: consecutive floors share two cells' worth of
  // face, and floor k's top is coplanar with floor k+1's bottom beyond the overlap.
  return grid_cell_solid(integers(count + 3), integers(2), integers(count),
                         [](int i, int, int k) { return i >= k && i < k + 3; });
}

Mesh pinch_saddle() {
  std::vector<Vec3> p = {
      {1, 1, 0},                                                        // 0: the saddle vertex
      {0, 0, 0},  {1, 0, -1}, {2, 0, 0},  {2, 1, 1},                    // 1-4: rim
      {2, 2, 0},  {1, 2, -1}, {0, 2, 0},  {0, 1, 1},                    // 5-8: rim
      {0, 0, -2}, {2, 0, -2}, {2, 2, -2}, {0, 2, -2},                   // 9-12: bottom
  };
  std::vector<Triangle> t;
  for (VertexIndex i = 1; i <= 8; ++i) t.push_back({0, i, i == 8 ? 1u : i + 1});  // top: a fan round the saddle
  add_fan(t, {2, 1, 9, 10, 3});    // y = 0 wall, fanned from its notch (1, 0, -1)
  add_fan(t, {6, 5, 11, 12, 7});   // y = 2 wall, fanned from its notch (1, 2, -1)
  add_fan(t, {10, 11, 5, 4, 3});   // x = 2 wall (convex)
  add_fan(t, {9, 1, 8, 7, 12});    // x = 0 wall (convex)
  add_fan(t, {9, 12, 11, 10});     // bottom
  return mesh_from(std::move(p), std::move(t));
}

Mesh needle_bridge(double neck) {
  if (!(neck > 0 && neck < 1)) throw std::invalid_argument("needle_bridge: 0 < neck < 1");
  const std::vector<double> across{0, 0.5 - neck / 2, 0.5 + neck / 2, 1};
  return grid_cell_solid({0, 1, 2, 3}, across, across,
                         [](int i, int j, int k) { return i != 1 || (j == 1 && k == 1); });
}

Mesh flat_tetrahedron(double height) {
  return mesh_from({{0, 0, 0}, {1, 0, 0}, {0.5, 0.875, 0}, {0.5, 0.25, height}},
                   {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {2, 0, 3}});
}

Mesh nested_islands() {
  // Shell A: cells 0..8 minus 1..7; island B: 2..6 minus 3..5; island C: cell 4.
  return grid_cell_solid(integers(9), integers(9), integers(9), [](int i, int j, int k) {
    const int ring = std::min({i, j, k, 8 - i, 8 - j, 8 - k});  // 0 on the outer layer
    return ring == 0 || ring == 2 || ring == 4;
  });
}

Mesh box_with_through_hole() {
  return grid_cell_solid(integers(3), integers(3), integers(1), [](int i, int j, int) { return i != 1 || j != 1; });
}

Mesh pit_and_bump() {
  // The pit (2, 2, 1) and the bump (1, 1, 2) share only the vertex (2, 2, 2);
  // around it both the filled and the empty cells are face-connected, so the
  // surface stays a 2-manifold there.
  return grid_cell_solid(integers(4), integers(4), integers(3), [](int i, int j, int k) {
    if (k < 2) return !(i == 2 && j == 2 && k == 1);
    return i == 1 && j == 1 && k == 2;
  });
}

Mesh with_seams(Mesh mesh) {
  const std::size_t corners = 3 * mesh.triangles.size();
  mesh.corners.normals.resize(corners);
  mesh.corners.uvs.resize(corners);
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& tri = mesh.triangles[t];
    const Vec3 a = mesh.positions[tri[0]], b = mesh.positions[tri[1]], c = mesh.positions[tri[2]];
    const Vec3 normal = normalized(cross(b - a, c - a));
    for (int k = 0; k < 3; ++k) {
      const Vec3 p = mesh.positions[tri[k]];
      mesh.corners.normals[3 * t + k] = normal;
      // A chart per triangle: corners at one position get different UVs.
      mesh.corners.uvs[3 * t + k] = {p.x + p.z + double(t % 7), p.y - p.z + double(t % 5)};
    }
  }
  return mesh;
}

Plane axis_plane_through(Vec3 point, int axis) {
  Vec3 normal{};
  (axis == 0 ? normal.x : axis == 1 ? normal.y : normal.z) = 1;
  return {normal, -point[axis]};
}

Plane plane_through(Vec3 point, Vec3 normal) { return {normal, -dot(normal, point)}; }

Plane plane_through_points(Vec3 a, Vec3 b, Vec3 c) { return plane_through(a, cross(b - a, c - a)); }

Plane offset_by_ulps(Plane plane, int ulps) {
  for (int i = 0; i < std::abs(ulps); ++i) {
    plane.offset = std::nextafter(plane.offset, ulps > 0 ? INFINITY : -INFINITY);
  }
  return plane;
}

std::vector<Plane> near_parallel_fan(Vec3 a, Vec3 b, Vec3 side, int count, double start, double ratio) {
  const Vec3 axis = normalized(b - a);
  const Vec3 in_plane = normalized(side - axis * dot(axis, side));
  const Vec3 base_normal = cross(axis, in_plane);
  std::vector<Plane> planes;
  double angle = start;
  for (int i = 0; i < count; ++i, angle *= ratio) {
    planes.push_back(plane_through(a, base_normal * std::cos(angle) + in_plane * std::sin(angle)));
  }
  return planes;
}

PlaneContact plane_contact(const Mesh& mesh, const Plane& plane) {
  PlaneContact contact;
  for (const Vec3& p : mesh.positions) {
    switch (side_of_plane(plane, p)) {
      case Sign::negative: ++contact.below; break;
      case Sign::zero: ++contact.on; break;
      case Sign::positive: ++contact.above; break;
    }
  }
  return contact;
}

}  // namespace shatter::test
