// The convex hulls of point sets (meshtree/hull.hpp) against their definition and
// against CGAL's convex_hull_3, over many seeds: random clouds, points on a
// sphere, lattices full of exactly coplanar and collinear points, duplicates,
// points on the hull's edges and faces, rounded points of planes through meshes
// (what the hulls of cut pieces are made of), and the non-convex nodes of trees.

#include <catch2/catch.hpp>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "shatter/generators/corpus.hpp"
#include "shatter/generators/random.hpp"
#include "shatter/generators/solids.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/predicates.hpp"
#include "shatter/kernel/union_find.hpp"
#include "shatter/kernel/validate.hpp"
#include "shatter/meshtree/build.hpp"
#include "shatter/cut/hull.hpp"

using namespace shatter;
using namespace shatter::test;

namespace {

using Key = std::tuple<double, double, double>;
Key key(const Vec3& p) { return {p.x, p.y, p.z}; }

// A convex polytope told apart from any other by what no triangulation changes:
// its vertices (boundary points on three or more facet planes) and, per facet
// (a maximal edge-connected set of exactly coplanar triangles), the vertices on
// its plane; both sorted. Precondition: `hull` is closed, outward and convex.
struct Polytope {
  std::vector<Key> vertices;
  std::vector<std::vector<Key>> facets;
  friend bool operator==(const Polytope&, const Polytope&) = default;
};

Polytope polytope_of(const Mesh& hull) {
  const std::size_t t_count = hull.triangles.size();
  std::map<std::pair<VertexIndex, VertexIndex>, std::uint32_t> triangle_of_edge;
  for (std::uint32_t t = 0; t < t_count; ++t) {
    for (int k = 0; k < 3; ++k) triangle_of_edge[{hull.triangles[t][k], hull.triangles[t][(k + 1) % 3]}] = t;
  }
  UnionFind facet_of(t_count);
  for (std::uint32_t t = 0; t < t_count; ++t) {
    const Triangle& tri = hull.triangles[t];
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t n = triangle_of_edge.at({tri[(k + 1) % 3], tri[k]});
      for (const VertexIndex v : hull.triangles[n]) {
        if (orient3d(hull.positions[tri[0]], hull.positions[tri[1]], hull.positions[tri[2]], hull.positions[v]) != Sign::zero) {
          goto not_coplanar;
        }
      }
      facet_of.unite(t, n);
    not_coplanar:;
    }
  }
  std::vector<std::uint32_t> planes;  // one triangle per facet
  for (std::uint32_t t = 0; t < t_count; ++t) {
    if (facet_of.find(t) == t) planes.push_back(t);
  }
  Polytope result;
  std::vector<std::vector<VertexIndex>> on_plane(planes.size());
  std::vector<int> planes_through(hull.positions.size(), 0);
  for (std::size_t f = 0; f < planes.size(); ++f) {
    const Triangle& tri = hull.triangles[planes[f]];
    for (VertexIndex v = 0; v < hull.positions.size(); ++v) {
      if (orient3d(hull.positions[tri[0]], hull.positions[tri[1]], hull.positions[tri[2]], hull.positions[v]) == Sign::zero) {
        on_plane[f].push_back(v);
        ++planes_through[v];
      }
    }
  }
  for (VertexIndex v = 0; v < hull.positions.size(); ++v) {
    if (planes_through[v] >= 3) result.vertices.push_back(key(hull.positions[v]));
  }
  for (const auto& facet : on_plane) {
    std::vector<Key> keys;
    for (const VertexIndex v : facet) {
      if (planes_through[v] >= 3) keys.push_back(key(hull.positions[v]));
    }
    std::sort(keys.begin(), keys.end());
    result.facets.push_back(std::move(keys));
  }
  std::sort(result.vertices.begin(), result.vertices.end());
  std::sort(result.facets.begin(), result.facets.end());
  return result;
}

// Positions equal bit for bit: Vec3's == takes -0 for +0, which the bytes of a
// file do not.
bool same_positions_bitwise(const Mesh& a, const Mesh& b) {
  return a.positions.size() == b.positions.size() &&
         std::memcmp(a.positions.data(), b.positions.data(), a.positions.size() * sizeof(Vec3)) == 0;
}

// CGAL's convex_hull_3 (Epick: exact predicates) as a triangle mesh.
Mesh cgal_hull(const std::vector<Vec3>& points) {
  using Point = CGAL::Epick::Point_3;
  std::vector<Point> cgal_points;
  for (const Vec3& p : points) cgal_points.emplace_back(p.x, p.y, p.z);
  CGAL::Surface_mesh<Point> hull;
  CGAL::convex_hull_3(cgal_points.begin(), cgal_points.end(), hull);
  Mesh result;
  result.positions.resize(hull.number_of_vertices());
  for (const auto v : hull.vertices()) {
    const Point& p = hull.point(v);
    result.positions[v.idx()] = {p.x(), p.y(), p.z()};
  }
  for (const auto f : hull.faces()) {
    std::vector<VertexIndex> face;
    for (const auto v : CGAL::vertices_around_face(hull.halfedge(f), hull)) face.push_back(static_cast<VertexIndex>(v.idx()));
    for (std::size_t i = 1; i + 1 < face.size(); ++i) result.triangles.push_back({face[0], face[i], face[i + 1]});
  }
  result.surfaces.assign(result.triangles.size(), original_surface);
  return result;
}

// Every property of convex_hull_of_points(points), and equality with CGAL's hull.
void require_hull(const std::vector<Vec3>& points) {
  const Mesh hull = convex_hull_of_points(points);
  // A closed, oriented, embedded solid with positive volume.
  const ValidationReport report = validate_mesh(hull);
  INFO("validate_mesh: " << report.summary());
  REQUIRE(report.valid());
  // Every hull vertex is an input point.
  std::set<Key> inputs;
  for (const Vec3& p : points) inputs.insert(key(p));
  for (const Vec3& v : hull.positions) REQUIRE(inputs.count(key(v)) == 1);
  // Convex, and holding every input point: nothing strictly beyond any triangle.
  for (const Triangle& t : hull.triangles) {
    for (const Vec3& p : hull.positions) REQUIRE(orient3d(hull.positions[t[0]], hull.positions[t[1]], hull.positions[t[2]], p) != Sign::positive);
    for (const Vec3& p : points) REQUIRE(orient3d(hull.positions[t[0]], hull.positions[t[1]], hull.positions[t[2]], p) != Sign::positive);
  }
  // Canonical: every vertex a corner (on three facet planes), so the polytope's
  // vertices are the mesh's; and the same polytope as CGAL's.
  const Polytope ours = polytope_of(hull);
  REQUIRE(ours.vertices.size() == hull.positions.size());
  REQUIRE(ours == polytope_of(cgal_hull(points)));
  // Order and repetition of the input change nothing, to the byte.
  std::vector<Vec3> shuffled = points;
  std::reverse(shuffled.begin(), shuffled.end());
  shuffled.insert(shuffled.end(), points.begin(), points.begin() + std::min<std::ptrdiff_t>(5, std::ssize(points)));
  const Mesh again = convex_hull_of_points(shuffled);
  REQUIRE(same_positions_bitwise(again, hull));
  REQUIRE(again.triangles == hull.triangles);
  // The canonical form is a fixed point: the hull, passed in as a convex mesh,
  // is its own hull. That path decides every facet's coplanarity with orient3d;
  // the point hull takes those its horizons decided, so this checks them.
  const Mesh own = convex_hull_of(hull);
  REQUIRE(same_positions_bitwise(own, hull));
  REQUIRE(own.triangles == hull.triangles);
}

// A random direction times a radius, rounded.
Vec3 random_point(Random& random, double radius) { return random.direction() * (radius * std::cbrt(random.uniform())); }

}  // namespace

TEST_CASE("convex hulls of random clouds and of points on a sphere") {
  for (std::uint64_t seed = 1; seed <= 60; ++seed) {
    Random random(seed);
    const double scale = std::pow(10.0, random.uniform(-6, 6));
    const Vec3 centre = random.direction() * (scale * random.uniform(0, 100));
    std::vector<Vec3> cloud, sphere;
    const std::size_t n = 4 + random.index(300);
    for (std::size_t i = 0; i < n; ++i) {
      cloud.push_back(centre + random_point(random, scale));
      sphere.push_back(centre + random.direction() * scale);
    }
    INFO("seed " << seed << ", " << n << " points");
    require_hull(cloud);
    require_hull(sphere);
  }
}

TEST_CASE("convex hulls of lattices: exactly coplanar and collinear points, duplicates, points on edges") {
  for (std::uint64_t seed = 1; seed <= 80; ++seed) {
    Random random(seed);
    // A k x l x m lattice of dyadic points (exact), a random subset with repeats,
    // always with the eight corners so it spans a volume; points on the box's
    // edges and faces between them; sheared (exactly) in some cases so the
    // coplanar sets are not axis-aligned.
    const int k = 2 + int(random.index(5)), l = 2 + int(random.index(5)), m = 2 + int(random.index(5));
    const double step = std::ldexp(1.0, int(random.index(40)) - 20);
    const Vec3 origin{step * double(random.index(1000)), -step * double(random.index(1000)), step * 3};
    const bool shear = random.index(2) == 1;
    const auto at = [&](int i, int j, int h) {
      const double x = i, y = j, z = h;
      const Vec3 p = shear ? Vec3{x + y, y + 2 * z, z - x} : Vec3{x, y, z};
      return origin + p * step;  // small integers times a power of two: exact
    };
    std::vector<Vec3> points;
    for (const int i : {0, k}) {
      for (const int j : {0, l}) {
        for (const int h : {0, m}) points.push_back(at(i, j, h));
      }
    }
    const std::size_t extra = random.index(200);
    for (std::size_t e = 0; e < extra; ++e) {
      points.push_back(at(int(random.index(k + 1)), int(random.index(l + 1)), int(random.index(m + 1))));
    }
    for (int e = 0; e < 10; ++e) points.push_back(points[random.index(points.size())]);  // duplicates
    for (std::size_t e = points.size(); e > 1; --e) std::swap(points[e - 1], points[random.index(e)]);  // Fisher-Yates
    INFO("seed " << seed << ", lattice " << k << " x " << l << " x " << m << (shear ? " sheared" : ""));
    require_hull(points);
    // Only a few corners of the lattice: a thin slab (two lattice planes) with most
    // points in its two faces.
    std::vector<Vec3> slab;
    for (int i = 0; i <= k; ++i) {
      for (int j = 0; j <= l; ++j) {
        if (random.index(3) != 0) slab.push_back(at(i, j, 0));
        if (random.index(3) != 0) slab.push_back(at(i, j, 1));
      }
    }
    slab.push_back(at(0, 0, 0));
    slab.push_back(at(k, 0, 0));
    slab.push_back(at(0, l, 0));
    slab.push_back(at(0, 0, 1));
    require_hull(slab);
  }
}

TEST_CASE("convex hulls of rounded points where planes cut meshes") {
  // What the hull of a cut piece is made of: the piece's vertices on one side of
  // a plane and the plane's crossings of its edges, each rounded to doubles, so
  // nearly but rarely exactly coplanar (the case that sent CGAL's hull to GMP).
  std::vector<Mesh> meshes{torus(1.0, 0.35, 40, 20), ellipsoid({0.5, -0.25, 2}, {1, 0.5, 0.75}, 24, 12)};
  meshes.push_back(read_mesh(mesh_dir() / "fandisk.off"));
  meshes.push_back(transformed(meshes[0], 1e-5, {1e-3, 2e-3, 0}));
  for (std::size_t m = 0; m < meshes.size(); ++m) {
    const Mesh& mesh = meshes[m];
    for (std::uint64_t seed = 1; seed <= 25; ++seed) {
      Random random(seed * 100 + m);
      const Vec3 through = mesh.positions[random.index(mesh.positions.size())];
      const Vec3 normal = random.direction();
      const auto value = [&](const Vec3& p) { return dot(normal, p - through); };
      std::vector<Vec3> points;
      for (const Vec3& p : mesh.positions) {
        if (value(p) <= 0) points.push_back(p);
      }
      for (const Triangle& t : mesh.triangles) {
        for (int k = 0; k < 3; ++k) {
          const Vec3 p = mesh.positions[t[k]], q = mesh.positions[t[(k + 1) % 3]];
          const double vp = value(p), vq = value(q);
          if ((vp < 0) != (vq < 0)) points.push_back(p + (q - p) * (vp / (vp - vq)));
        }
      }
      INFO("mesh " << m << ", seed " << seed << ", " << points.size() << " points");
      // A plane grazing the mesh may leave too few points for a volume.
      if (points.size() < 4) continue;
      bool flat = true;
      for (std::size_t i = 3; i < points.size() && flat; ++i) {
        for (std::size_t j = 2; j < i && flat; ++j) {
          flat = orient3d(points[0], points[1], points[j], points[i]) == Sign::zero;
        }
      }
      if (flat) continue;
      require_hull(points);
    }
  }
}

TEST_CASE("convex hulls of the non-convex nodes of trees, and of convex meshes") {
  std::size_t checked = 0;
  for (const char* name : {"fandisk.off", "knot1.off"}) {
    TreeRecipe recipe;
    recipe.fragments = 24;
    recipe.seed = 7;
    const MeshTree tree = build_mesh_tree(read_mesh(mesh_dir() / name), recipe, {.threads = 2});
    for (const MeshTreeNode& node : tree.nodes) {
      INFO(name << ", a node of " << node.mesh->positions.size() << " vertices");
      if (node.convex) {
        // A convex node's mesh is its own hull; the point hull finds the same one.
        const Mesh own = convex_hull_of(node.mesh);
        const Mesh of_points = convex_hull_of_points(node.mesh->positions);
        REQUIRE(own.positions == of_points.positions);
        REQUIRE(own.triangles == of_points.triangles);
        continue;
      }
      require_hull(node.mesh->positions);
      ++checked;
    }
  }
  CHECK(checked > 10);
}

TEST_CASE("convex hulls of points given with -0 and +0 are the same bits in any order") {
  // A zero coordinate written both ways is one point twice; which of the two the
  // hull keeps must not follow the input order (it did: the first in order won).
  Random random(7);
  for (int draw = 0; draw < 200; ++draw) {
    std::vector<Vec3> points;
    const std::size_t count = 4 + random.index(30);
    for (std::size_t i = 0; i < count; ++i) {
      // Coordinates from {-1, 0, 1, 2}, a zero drawn as -0 half the time, so
      // many points come in both signs of zero, on the hull and inside it.
      Vec3 p;
      for (int axis = 0; axis < 3; ++axis) {
        double c = double(random.index(4)) - 1;
        if (c == 0 && random.index(2) == 1) c = -0.0;
        (axis == 0 ? p.x : axis == 1 ? p.y : p.z) = c;
      }
      points.push_back(p);
    }
    for (const Vec3 corner : {Vec3{-1, -1, -1}, Vec3{2, -1, -1}, Vec3{-1, 2, -1}, Vec3{-1, -1, 2}}) points.push_back(corner);
    INFO("draw " << draw);
    const Mesh hull = convex_hull_of_points(points);
    for (int shuffle = 0; shuffle < 4; ++shuffle) {
      std::vector<Vec3> order = points;
      for (std::size_t e = order.size(); e > 1; --e) std::swap(order[e - 1], order[random.index(e)]);
      const Mesh again = convex_hull_of_points(order);
      REQUIRE(same_positions_bitwise(again, hull));
      REQUIRE(again.triangles == hull.triangles);
    }
  }
}

TEST_CASE("convex_hull_of_points refuses points that span no volume") {
  CHECK_THROWS_AS(convex_hull_of_points(std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}), std::invalid_argument);
  CHECK_THROWS_AS(convex_hull_of_points(std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}, {1, 0, 0}}),
                  std::invalid_argument);
  CHECK_THROWS_AS(convex_hull_of_points(std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0.5, 0.25, 0}}),
                  std::invalid_argument);
  CHECK_THROWS_AS(convex_hull_of_points(std::vector<Vec3>{{1, 2, 3}, {1, 2, 3}, {1, 2, 3}, {1, 2, 3}}), std::invalid_argument);
  // Four points, the least number that spans a volume.
  const Mesh tetrahedron = convex_hull_of_points(std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}});
  CHECK(tetrahedron.positions.size() == 4);
  CHECK(tetrahedron.triangles.size() == 4);
}
