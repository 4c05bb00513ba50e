#include "shatter/generators/solids.hpp"

#include <cmath>

namespace shatter::test {
namespace {

constexpr double pi = 3.141592653589793;

void add_quad(Mesh& m, VertexIndex a, VertexIndex b, VertexIndex c, VertexIndex d) {
  m.triangles.push_back({a, b, c});
  m.triangles.push_back({a, c, d});
}

void finish(Mesh& m) { m.surfaces.assign(m.triangles.size(), original_surface); }

}  // namespace

Mesh mesh_from(std::vector<Vec3> positions, std::vector<Triangle> triangles) {
  Mesh mesh;
  mesh.positions = std::move(positions);
  mesh.triangles = std::move(triangles);
  finish(mesh);
  return mesh;
}

Mesh prism(const std::vector<Vec2>& polygon, const std::vector<std::vector<VertexIndex>>& loops,
           const std::vector<Triangle>& triangles, double length) {
  const auto n = static_cast<VertexIndex>(polygon.size());
  std::vector<Vec3> positions;
  for (const double y : {0.0, length}) {
    for (const Vec2& p : polygon) positions.push_back({p.x, y, p.y});
  }
  std::vector<Triangle> faces;
  for (const Triangle& t : triangles) {
    faces.push_back(t);                               // y = 0 faces -y
    faces.push_back({t[0] + n, t[2] + n, t[1] + n});  // y = length faces +y
  }
  for (const auto& loop : loops) {
    for (std::size_t i = 0; i < loop.size(); ++i) {
      const VertexIndex a = loop[i], b = loop[(i + 1) % loop.size()];
      faces.push_back({a, b + n, b});
      faces.push_back({a, a + n, b + n});
    }
  }
  return mesh_from(std::move(positions), std::move(faces));
}

Mesh unit_cube() {
  return mesh_from({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}},
                   {{0, 2, 1}, {0, 3, 2},    // z = 0
                    {4, 5, 6}, {4, 6, 7},    // z = 1
                    {0, 1, 5}, {0, 5, 4},    // y = 0
                    {3, 7, 6}, {3, 6, 2},    // y = 1
                    {0, 4, 7}, {0, 7, 3},    // x = 0
                    {1, 2, 6}, {1, 6, 5}});  // x = 1
}

Mesh box(Vec3 lo, Vec3 hi) { return grid_box(lo, hi, 1); }

Mesh grid_box(Vec3 lo, Vec3 hi, int n) {
  // Vertices on the surface of an (n+1)^3 lattice, indexed through a dense map.
  Mesh m;
  const int side = n + 1;
  std::vector<VertexIndex> index(static_cast<std::size_t>(side * side * side), ~0u);
  auto vertex = [&](int i, int j, int k) {
    VertexIndex& slot = index[static_cast<std::size_t>((i * side + j) * side + k)];
    if (slot == ~0u) {
      slot = static_cast<VertexIndex>(m.positions.size());
      // Exact lattice coordinates when lo/hi and n are dyadic-friendly.
      m.positions.push_back({lo.x + (hi.x - lo.x) * i / n, lo.y + (hi.y - lo.y) * j / n,
                             lo.z + (hi.z - lo.z) * k / n});
    }
    return slot;
  };
  for (int a = 0; a < n; ++a) {
    for (int b = 0; b < n; ++b) {
      // Each face counter-clockwise seen from outside.
      add_quad(m, vertex(0, a, b), vertex(0, a, b + 1), vertex(0, a + 1, b + 1), vertex(0, a + 1, b));
      add_quad(m, vertex(n, a, b), vertex(n, a + 1, b), vertex(n, a + 1, b + 1), vertex(n, a, b + 1));
      add_quad(m, vertex(a, 0, b), vertex(a + 1, 0, b), vertex(a + 1, 0, b + 1), vertex(a, 0, b + 1));
      add_quad(m, vertex(a, n, b), vertex(a, n, b + 1), vertex(a + 1, n, b + 1), vertex(a + 1, n, b));
      add_quad(m, vertex(a, b, 0), vertex(a, b + 1, 0), vertex(a + 1, b + 1, 0), vertex(a + 1, b, 0));
      add_quad(m, vertex(a, b, n), vertex(a + 1, b, n), vertex(a + 1, b + 1, n), vertex(a, b + 1, n));
    }
  }
  finish(m);
  return m;
}

Mesh torus(double major_radius, double minor_radius, int segments, int rings) {
  Mesh m;
  for (int i = 0; i < segments; ++i) {
    const double u = 2 * pi * i / segments;
    for (int j = 0; j < rings; ++j) {
      const double v = 2 * pi * j / rings;
      const double r = major_radius + minor_radius * std::cos(v);
      m.positions.push_back({r * std::cos(u), r * std::sin(u), minor_radius * std::sin(v)});
    }
  }
  auto at = [&](int i, int j) { return static_cast<VertexIndex>((i % segments) * rings + (j % rings)); };
  for (int i = 0; i < segments; ++i) {
    for (int j = 0; j < rings; ++j) add_quad(m, at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
  }
  finish(m);
  return m;
}

Mesh ellipsoid(Vec3 centre, Vec3 radii, int slices, int stacks) {
  Mesh m;
  m.positions.push_back({centre.x, centre.y, centre.z + radii.z});  // north pole
  for (int k = 1; k < stacks; ++k) {
    const double theta = pi * k / stacks;
    for (int s = 0; s < slices; ++s) {
      const double phi = 2 * pi * s / slices;
      m.positions.push_back({centre.x + radii.x * std::sin(theta) * std::cos(phi),
                             centre.y + radii.y * std::sin(theta) * std::sin(phi),
                             centre.z + radii.z * std::cos(theta)});
    }
  }
  m.positions.push_back({centre.x, centre.y, centre.z - radii.z});  // south pole
  const auto south = static_cast<VertexIndex>(m.positions.size() - 1);
  auto ring = [&](int k, int s) { return static_cast<VertexIndex>(1 + (k - 1) * slices + (s % slices)); };
  for (int s = 0; s < slices; ++s) {
    m.triangles.push_back({0, ring(1, s), ring(1, s + 1)});
    m.triangles.push_back({south, ring(stacks - 1, s + 1), ring(stacks - 1, s)});
  }
  for (int k = 1; k + 1 < stacks; ++k) {
    for (int s = 0; s < slices; ++s) add_quad(m, ring(k, s), ring(k + 1, s), ring(k + 1, s + 1), ring(k, s + 1));
  }
  finish(m);
  return m;
}

Mesh merge(const std::vector<Mesh>& parts) {
  Mesh m;
  for (const Mesh& part : parts) {
    const auto offset = static_cast<VertexIndex>(m.positions.size());
    m.positions.insert(m.positions.end(), part.positions.begin(), part.positions.end());
    for (Triangle t : part.triangles) m.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  }
  finish(m);
  return m;
}

Mesh flipped(Mesh mesh) {
  for (Triangle& t : mesh.triangles) std::swap(t[1], t[2]);
  return mesh;
}

Mesh hollow_egg() {
  // 2 * 20 * 19 = 760 triangles a shell; the egg is taller than wide and its
  // cavity is off-centre, as a real shell would be.
  return merge({ellipsoid({0, 0, 0}, {1.0, 1.0, 1.35}, 20, 20),
                flipped(ellipsoid({0, 0, -0.05}, {0.85, 0.85, 1.15}, 20, 20))});
}

Mesh nested_shells_with_island() {
  return merge({grid_box({0, 0, 0}, {4, 4, 4}, 2), flipped(box({1, 1, 1}, {3, 3, 3})),
                box({1.5, 1.5, 1.5}, {2.5, 2.5, 2.5})});
}

Mesh two_boxes() { return merge({box({0, 0, 0}, {1, 1, 1}), box({2, 0.25, 0}, {3, 1.25, 1})}); }

Mesh sliver() {
  Mesh m;
  // A tetrahedron 1e-4 thick and 1 long, and a 1e-3 x 1e-3 x 10 needle beside it.
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0.5, 1e-4, 0}, {0.5, 0.3, 1e-4}};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  finish(m);
  return merge({m, box({2, 0, 0}, {2.001, 0.001, 10})});
}

Mesh transformed(Mesh mesh, double scale, Vec3 shift) {
  for (Vec3& p : mesh.positions) p = p * scale + shift;
  return mesh;
}

std::vector<NamedMesh> generated_meshes() {
  std::vector<NamedMesh> meshes;
  meshes.push_back({"box", box({0, 0, 0}, {1, 1, 1})});
  meshes.push_back({"grid-box-4", grid_box({-1, -1, -1}, {1, 1, 1}, 4)});
  meshes.push_back({"torus-800", torus(1.0, 0.35, 20, 20)});
  meshes.push_back({"hollow-egg", hollow_egg()});
  meshes.push_back({"nested-shells-island", nested_shells_with_island()});
  meshes.push_back({"two-boxes", two_boxes()});
  meshes.push_back({"sliver", sliver()});
  meshes.push_back({"torus-tiny-1e-6", transformed(torus(1.0, 0.35, 12, 10), 1e-6, {0, 0, 0})});
  meshes.push_back({"torus-huge-1e6", transformed(torus(1.0, 0.35, 12, 10), 1e6, {0, 0, 0})});
  meshes.push_back({"egg-far-from-origin", transformed(hollow_egg(), 1.0, {1e6, -2e6, 3e5})});
  return meshes;
}

}  // namespace shatter::test
