// The exact arrangement of intersecting triangles (arrange_triangles), judged
// apart from the code that makes it: on the vertices' exact rational coordinates,
// the pieces of every input triangle tile it (each inside it, turning its way,
// their areas summing to its area exactly) and no two pieces cross (CGAL PMP's
// pair semantics on exact points: they meet only in what they share by index).
// Over seeded overlapping solids in general position, lattice solids whose
// contacts are exact (vertices on faces and edges, edges through edges), three
// solids whose surfaces meet at triple points, and the self-intersecting corpus.

#include <catch2/catch.hpp>

#include <CGAL/box_intersection_d.h>
#include <gmpxx.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "shatter/generators/corpus.hpp"
#include "shatter/generators/random.hpp"
#include "shatter/generators/solids.hpp"
#include "shatter/kernel/arrangement.hpp"
#include "shatter/kernel/exact.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/rationals.hpp"
#include "shatter/kernel/self_intersections.hpp"
#include "support/pair_reference.hpp"
#include "shatter/kernel/validate.hpp"
#include "support/sanitizers.hpp"
#include "support/turned.hpp"

using namespace shatter;

namespace {

using Q3 = std::array<mpq_class, 3>;
using EK = ExactKernel;

using test::turned;

// The octahedron |x - c| + |y - c| + |z - c| = r on integer points: its face
// planes are never parallel to an axis box's, so against one only exact
// contacts are degenerate, never coplanar faces.
Mesh octahedron(Vec3 c, double r) {
  std::vector<Vec3> p{{c.x + r, c.y, c.z}, {c.x - r, c.y, c.z}, {c.x, c.y + r, c.z},
                      {c.x, c.y - r, c.z}, {c.x, c.y, c.z + r}, {c.x, c.y, c.z - r}};
  return test::mesh_from(p, {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}});
}

// A soup of triangles over a pool of lattice points (drawn with repetition, so
// some positions repeat under two indices): collinear traces, several traces
// through one point, vertices on traces and edges, shared vertices and edges.
// Collinear triangles are redrawn, and unless `coplanar`, so is a triangle on
// the plane of one drawn before; with it, some triangles are drawn again as
// they are or reversed (duplicated and opposite triangles).
Mesh lattice_soup(test::Random& random, int points, int triangles, int lattice, bool coplanar = false) {
  Mesh mesh;
  const auto coordinate = [&] { return static_cast<double>(random.index(static_cast<std::size_t>(lattice) + 1)); };
  for (int i = 0; i < points; ++i) mesh.positions.push_back({coordinate(), coordinate(), coordinate()});
  // A small lattice may hold fewer triangles on distinct planes: a bounded number of draws.
  for (int draw = 0; draw < 50 * triangles && static_cast<int>(mesh.triangles.size()) < triangles; ++draw) {
    const auto pick = [&] { return static_cast<VertexIndex>(random.index(static_cast<std::size_t>(points))); };
    const Triangle t{pick(), pick(), pick()};
    const Vec3 &a = mesh.positions[t[0]], &b = mesh.positions[t[1]], &c = mesh.positions[t[2]];
    const Vec3 n = cross(b - a, c - a);  // small integers: exact
    if (n.x == 0 && n.y == 0 && n.z == 0) continue;
    bool coplanar_plane = false;
    for (const Triangle& u : mesh.triangles) {
      const Vec3& p = mesh.positions[u[0]];
      const Vec3 m = cross(mesh.positions[u[1]] - p, mesh.positions[u[2]] - p);
      coplanar_plane = coplanar_plane || (dot(m, a - p) == 0 && dot(m, b - p) == 0 && dot(m, c - p) == 0);
    }
    if (coplanar_plane && !coplanar) continue;
    mesh.triangles.push_back(t);
    if (coplanar && random.index(8) == 0) {
      mesh.triangles.push_back(random.index(2) == 0 ? t : Triangle{t[0], t[2], t[1]});
    }
  }
  mesh.surfaces.assign(mesh.triangles.size(), 0);
  return mesh;
}

EK::Point_3 ek(const Q3& c) { return {EK::FT(c[0]), EK::FT(c[1]), EK::FT(c[2])}; }

// CGAL PMP's pair semantics on exact points (as tests/kernel's finder oracle).
bool pieces_intersect(const std::vector<EK::Point_3>& points, const Triangle& a, const Triangle& b) {
  return test::pmp_pair_intersects<EK>(a, b, [&](VertexIndex v) { return points[v]; });
}

// The same semantics for two pieces of one source triangle, in its projection
// dropping `axis` (one to one on its plane): exact and free of the coplanar
// degeneracy that makes the 3D test slow on neighbours in one plane.
bool pieces_intersect_in_plane(const std::vector<EK::Point_3>& points, const Triangle& a, const Triangle& b, int axis) {
  const int i = (axis + 1) % 3, j = (axis + 2) % 3;
  const auto p = [&](VertexIndex v) { return EK::Point_2(points[v][i], points[v][j]); };
  int shared = 0, shared_a = -1, shared_b = -1;
  for (int x = 0; x < 3; ++x) {
    for (int y = 0; y < 3; ++y) {
      if (a[x] != b[y]) continue;
      ++shared;
      if (shared_a < 0) shared_a = x, shared_b = y;
    }
  }
  if (shared >= 3) return true;
  if (shared == 2) {
    int ia = 0, ib = 0;
    for (int x = 0; x < 3; ++x) {
      if (a[x] != b[0] && a[x] != b[1] && a[x] != b[2]) ia = x;
      if (b[x] != a[0] && b[x] != a[1] && b[x] != a[2]) ib = x;
    }
    const EK::Point_2 u = p(a[(ia + 1) % 3]), v = p(a[(ia + 2) % 3]);
    return CGAL::orientation(u, v, p(a[ia])) != CGAL::opposite(CGAL::orientation(u, v, p(b[ib])));
  }
  const EK::Triangle_2 ta(p(a[0]), p(a[1]), p(a[2])), tb(p(b[0]), p(b[1]), p(b[2]));
  if (shared == 1) {
    const EK::Segment_2 sa(p(a[(shared_a + 1) % 3]), p(a[(shared_a + 2) % 3]));
    const EK::Segment_2 sb(p(b[(shared_b + 1) % 3]), p(b[(shared_b + 2) % 3]));
    return CGAL::do_intersect(ta, sb) || CGAL::do_intersect(tb, sa);
  }
  return CGAL::do_intersect(ta, tb);
}

struct Tally {
  std::size_t uncrossed = 0;  ///< meshes checked for crossings too
  std::size_t meshes = 0, split = 0, new_points = 0, triple_points = 0, pieces = 0, coplanar_pairs = 0;
  std::size_t coinciding = 0;  ///< pairs of pieces of two sources on the same three vertices
};

// Twice the signed area of (a, b, c) in the projection dropping `axis`.
mpq_class twice_area(const Q3& a, const Q3& b, const Q3& c, int axis) {
  const int i = (axis + 1) % 3, j = (axis + 2) % 3;
  return (b[i] - a[i]) * (c[j] - a[j]) - (b[j] - a[j]) * (c[i] - a[i]);
}

void record(Tally& tally, const Mesh& mesh, const MeshArrangement& arrangement);

// Checks every promise of arrange_triangles on `mesh`.
void check_arrangement(const std::string& name, const Mesh& mesh, Tally& tally) {
  INFO(name);
  const MeshArrangement arrangement = arrange_triangles(mesh.positions, mesh.triangles);
  const PlaneSet set = arrangement.plane_set();
  REQUIRE(arrangement.triangles.size() == arrangement.source.size());
  REQUIRE(arrangement.defs.size() == arrangement.approx.size());
  REQUIRE(arrangement.pairs == self_intersecting_pairs(mesh.positions, mesh.triangles));
  for (VertexIndex v = 0; v < mesh.positions.size(); ++v) REQUIRE(arrangement.defs[v] == PointDef::input(v));

  // Deterministic: a second run gives the same arrangement.
  const MeshArrangement again = arrange_triangles(mesh.positions, mesh.triangles);
  CHECK(again.triangles == arrangement.triangles);
  CHECK(again.source == arrangement.source);
  CHECK(again.defs == arrangement.defs);

  std::vector<Q3> exact;
  exact.reserve(arrangement.defs.size());
  for (const PointDef& def : arrangement.defs) exact.push_back(exact_coordinates(set, def));
  // No two vertices are one point, but for input positions repeated.
  {
    std::vector<std::size_t> order(exact.size());
    for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
    const auto less = [&](std::size_t a, std::size_t b) {
      for (int k = 0; k < 3; ++k) {
        if (exact[a][k] != exact[b][k]) return exact[a][k] < exact[b][k];
      }
      return false;
    };
    std::sort(order.begin(), order.end(), less);
    for (std::size_t k = 1; k < order.size(); ++k) {
      if (!less(order[k - 1], order[k])) {
        CHECK(order[k - 1] < mesh.positions.size());
        CHECK(order[k] < mesh.positions.size());
      }
    }
  }

  // Tiling: per source, pieces inside it, turning its way, areas summing to its area.
  std::vector<mpq_class> covered(mesh.triangles.size(), 0);
  std::vector<std::size_t> piece_count(mesh.triangles.size(), 0);
  for (std::size_t k = 0; k < arrangement.triangles.size(); ++k) {
    const std::uint32_t t = arrangement.source[k];
    REQUIRE(t < mesh.triangles.size());
    const Triangle& piece = arrangement.triangles[k];
    const Triangle& tri = mesh.triangles[t];
    const int axis = projection_of(set, PlaneRef::input(t)).axis;
    const PlaneRef plane = PlaneRef::input(t);
    for (VertexIndex v : piece) {
      REQUIRE(v < arrangement.defs.size());
      CHECK(side(set, plane, arrangement.defs[v], arrangement.approx[v]) == Sign::zero);
    }
    const Q3 a{mpq_class(mesh.positions[tri[0]].x), mpq_class(mesh.positions[tri[0]].y),
               mpq_class(mesh.positions[tri[0]].z)};
    const Q3 b{mpq_class(mesh.positions[tri[1]].x), mpq_class(mesh.positions[tri[1]].y),
               mpq_class(mesh.positions[tri[1]].z)};
    const Q3 c{mpq_class(mesh.positions[tri[2]].x), mpq_class(mesh.positions[tri[2]].y),
               mpq_class(mesh.positions[tri[2]].z)};
    const mpq_class whole = twice_area(a, b, c, axis);
    const mpq_class area = twice_area(exact[piece[0]], exact[piece[1]], exact[piece[2]], axis);
    CHECK(sgn(area) == sgn(whole));  // turning the source's way, and not flat
    for (VertexIndex v : piece) {
      // Inside the closed source triangle: on no edge's outer side.
      CHECK(sgn(twice_area(a, b, exact[v], axis)) * sgn(whole) >= 0);
      CHECK(sgn(twice_area(b, c, exact[v], axis)) * sgn(whole) >= 0);
      CHECK(sgn(twice_area(c, a, exact[v], axis)) * sgn(whole) >= 0);
    }
    covered[t] += area;
    ++piece_count[t];
  }
  std::size_t split = 0;
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& tri = mesh.triangles[t];
    const int axis = projection_of(set, PlaneRef::input(t)).axis;
    Q3 p[3];
    for (int k = 0; k < 3; ++k)
      p[k] = {mpq_class(mesh.positions[tri[k]].x), mpq_class(mesh.positions[tri[k]].y),
              mpq_class(mesh.positions[tri[k]].z)};
    CHECK(covered[t] == twice_area(p[0], p[1], p[2], axis));
    CHECK(piece_count[t] >= 1);
    split += piece_count[t] > 1;
  }
  CHECK(split == arrangement.split_triangles);

  // No two pieces cross: every pair whose boxes meet, decided exactly; pieces
  // of two triangles overlapping on one plane are the same three vertices
  // where they overlap (either way round), and meet as others do elsewhere.
  std::vector<EK::Point_3> points;
  points.reserve(exact.size());
  for (const Q3& q : exact) points.push_back(ek(q));
  using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 3, std::size_t>;
  std::vector<Box> boxes;
  for (std::size_t k = 0; k < arrangement.triangles.size(); ++k) {
    const Triangle& piece = arrangement.triangles[k];
    const CGAL::Bbox_3 box = points[piece[0]].bbox() + points[piece[1]].bbox() + points[piece[2]].bbox();
    boxes.emplace_back(box, k);
  }
  std::size_t crossings = 0;
  CGAL::box_self_intersection_d(boxes.begin(), boxes.end(), [&](const Box& x, const Box& y) {
    const std::size_t i = x.info(), j = y.info();
    const std::uint32_t s = arrangement.source[i], u = arrangement.source[j];
    Triangle a = arrangement.triangles[i], b = arrangement.triangles[j];
    std::sort(a.begin(), a.end());
    std::sort(b.begin(), b.end());
    if (s != u && a == b) {
      ++tally.coinciding;
      return;
    }
    const Triangle& tu = mesh.triangles[u];
    const bool one_plane = s == u || (side(set, PlaneRef::input(s), PointDef::input(tu[0]), arrangement.approx[tu[0]]) ==
                                          Sign::zero &&
                                      side(set, PlaneRef::input(s), PointDef::input(tu[1]), arrangement.approx[tu[1]]) ==
                                          Sign::zero &&
                                      side(set, PlaneRef::input(s), PointDef::input(tu[2]), arrangement.approx[tu[2]]) ==
                                          Sign::zero);
    const bool crossing = one_plane ? pieces_intersect_in_plane(points, arrangement.triangles[i],
                                                                arrangement.triangles[j],
                                                                projection_of(set, PlaneRef::input(s)).axis)
                                    : pieces_intersect(points, arrangement.triangles[i], arrangement.triangles[j]);
    if (crossing) ++crossings;
  });
  CHECK(crossings == 0);

  ++tally.uncrossed;
  record(tally, mesh, arrangement);
}

void record(Tally& tally, const Mesh& mesh, const MeshArrangement& arrangement) {
  ++tally.meshes;
  tally.split += arrangement.split_triangles;
  tally.new_points += arrangement.defs.size() - mesh.positions.size();
  for (const PointDef& def : arrangement.defs) tally.triple_points += def.kind == PointKind::three_planes;
  tally.pieces += arrangement.triangles.size();
  tally.coplanar_pairs += arrangement.coplanar_pairs.size();
}

}  // namespace

TEST_CASE("a mesh whose triangles do not intersect is its own arrangement", "[arrangement]") {
  for (const test::NamedMesh& named : test::generated_meshes()) {
    INFO(named.name);
    const MeshArrangement arrangement = arrange_triangles(named.mesh.positions, named.mesh.triangles);
    CHECK(arrangement.pairs.empty());
    CHECK(arrangement.triangles == named.mesh.triangles);
    CHECK(arrangement.defs.size() == named.mesh.positions.size());
    CHECK(arrangement.split_triangles == 0);
    for (std::uint32_t t = 0; t < arrangement.source.size(); ++t) CHECK(arrangement.source[t] == t);
  }
}

// Two boxes, two spheres, and a sphere, a torus and a box at random angles, for
// each of `seeds` seeds; the exact crossing checks of neighbouring pieces make
// this the suite's costliest arrangement case (about 2.8 s a seed, Release).
void check_general_position(int seeds) {
  test::Random random(20261204);
  Tally tally;
  for (int seed = 0; seed < seeds; ++seed) {
    const std::string tag = " #" + std::to_string(seed);
    const auto angle = [&] { return random.uniform(0, 6.283185307179586); };
    const auto shift = [&](double reach) {
      return Vec3{random.uniform(-reach, reach), random.uniform(-reach, reach), random.uniform(-reach, reach)};
    };
    // Two boxes overlapping at a random angle.
    const Mesh box = test::box({-1, -1, -1}, {1, 1, 1});
    check_arrangement("two boxes" + tag, test::merge({box, turned(box, angle(), angle(), angle(), shift(1.5))}), tally);
    // Two spheres, and a third solid through both: triple points.
    const Mesh sphere = test::ellipsoid({0, 0, 0}, {1, 1, 1}, 10 + seed % 4, 7 + seed % 3);
    check_arrangement("two spheres" + tag,
                      test::merge({turned(sphere, angle(), angle(), angle(), shift(0.2)),
                                   turned(sphere, angle(), angle(), angle(), shift(1.2))}),
                      tally);
    const Mesh small = test::ellipsoid({0, 0, 0}, {1, 1, 1}, 8, 6);
    check_arrangement("sphere, torus and box" + tag,
                      test::merge({turned(small, angle(), angle(), angle(), shift(0.3)),
                                   turned(test::torus(0.9, 0.3, 8, 5), angle(), angle(), angle(), shift(0.3)),
                                   turned(box, angle(), angle(), angle(), shift(0.8))}),
                      tally);
  }
  INFO("split " << tally.split << ", triple points " << tally.triple_points);
  CHECK(tally.meshes == 3 * static_cast<std::size_t>(seeds));
  CHECK(tally.uncrossed == tally.meshes);
  // The properties were checked on real intersections.
  CHECK(tally.split > 100 * static_cast<std::size_t>(seeds));
  CHECK(tally.triple_points > 2 * static_cast<std::size_t>(seeds));
}

TEST_CASE("overlapping solids in general position: pieces tile their triangles and never cross", "[arrangement]") {
  check_general_position(static_cast<int>(test::sized(3, 1)));
}

TEST_CASE("overlapping solids in general position, eight seeds", "[arrangement][heavy]") {
  check_general_position(8);
}

TEST_CASE("exact contacts on a lattice: vertices on faces and edges, edges through edges", "[arrangement]") {
  test::Random random(7);
  Tally tally;
  for (int seed = 0; seed < 200; ++seed) {
    // An axis box and an octahedron on integer points: the octahedron's corners
    // land on the box's faces, edges and corners, its edges cross the box's
    // edges and pass through its corners, and no two faces are coplanar.
    const auto lattice = [&](int lo, int hi) {
      return static_cast<double>(lo + static_cast<int>(random.index(hi - lo + 1)));
    };
    const Mesh box = test::grid_box({0, 0, 0}, {2, 2, 2}, 1 + seed % 2);
    const Mesh octa = octahedron({lattice(-1, 3), lattice(-1, 3), lattice(-1, 3)}, lattice(1, 3));
    check_arrangement("box and octahedron #" + std::to_string(seed), test::merge({box, octa}), tally);
  }
  CHECK(tally.meshes == 200);
  CHECK(tally.uncrossed == 200);
  CHECK(tally.split > 500);
}

TEST_CASE("the self-intersecting corpus: pieces tile their triangles and never cross", "[arrangement][corpus]") {
  Tally tally;
  for (const auto& path : test::self_intersecting_meshes()) {
    const Mesh mesh = read_mesh(path);
    check_arrangement(path.filename().string(), mesh, tally);
  }
  CHECK(tally.meshes >= 3);
  CHECK(tally.uncrossed == tally.meshes);
  CHECK(tally.split > 100);
}

TEST_CASE("lattice soups: every degenerate contact but coplanar ones, pieces tile and never cross", "[arrangement]") {
  test::Random random(20261205);
  Tally tally;
  const std::size_t soups = test::sized(20, 5);
  for (std::size_t seed = 0; seed < soups; ++seed) {
    check_arrangement("lattice soup #" + std::to_string(seed),
                      lattice_soup(random, static_cast<int>(10 + seed % 20), static_cast<int>(12 + seed % 25),
                                   static_cast<int>(3 + seed % 4)),
                      tally);
  }
  INFO("split " << tally.split << ", triple points " << tally.triple_points);
  CHECK(tally.meshes == soups);
  CHECK(tally.uncrossed == soups);
  CHECK(tally.split > 10 * soups);
  CHECK(tally.triple_points > soups / 2);
}

TEST_CASE("overlaps on one plane: pieces tile, coincide where triangles overlap, and never cross", "[arrangement]") {
  // Axis boxes sharing face planes (faces overlapping on one plane, facing
  // the same way or opposite ways, beside faces that cross), a box and its
  // copy, and a box against a copy of itself turned inside out.
  Tally tally;
  for (int seed = 0; seed < 8; ++seed) {
    const double s = 0.25 * (1 + seed % 4);
    check_arrangement(
        "boxes on shared planes #" + std::to_string(seed),
        test::merge({test::grid_box({0, 0, 0}, {1, 1, 1}, 1 + seed % 2), test::box({s, s, 0}, {s + 1, s + 1, 1}),
                     octahedron({0.5, 0.5, 0.5 + 0.25 * (seed % 3)}, 0.75)}),
        tally);
    check_arrangement("boxes sharing a face #" + std::to_string(seed),
                      test::merge({test::grid_box({0, 0, 0}, {1, 1, 1}, 1 + seed % 2),
                                   test::grid_box({s - 0.5, s - 0.5, 1}, {s + 0.5, s + 0.5, 2}, 1 + seed / 4)}),
                      tally);
  }
  // Lattice boxes, tessellated one way or another: faces on shared planes whose
  // edges cross, and edges shared by two planes (an edge plane made for one
  // face's plane once served the other's, where it could lie in that plane).
  test::Random random(99);
  // (20 of them; 5 under the sanitizers, where the 20 took 11 s.)
  const int lattice_seeds = static_cast<int>(test::sized(20, 5));
  for (int seed = 0; seed < lattice_seeds; ++seed) {
    std::vector<Mesh> boxes;
    for (int b = 0; b < 4; ++b) {
      std::array<double, 3> lo{}, hi{};
      for (int c = 0; c < 3; ++c) {
        lo[c] = static_cast<double>(random.index(4));
        hi[c] = lo[c] + 1 + static_cast<double>(random.index(static_cast<std::size_t>(4 - lo[c])));
      }
      boxes.push_back(test::grid_box({lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}, 1 + static_cast<int>(random.index(2))));
    }
    check_arrangement("lattice boxes #" + std::to_string(seed), test::merge(boxes), tally);
  }
  Mesh inverted = test::box({0, 0, 0}, {1, 1, 1});
  for (Triangle& t : inverted.triangles) std::swap(t[1], t[2]);
  check_arrangement("a box and its copy",
                    test::merge({test::grid_box({0, 0, 0}, {1, 1, 1}, 2), test::box({0, 0, 0}, {1, 1, 1})}), tally);
  check_arrangement("a box and itself inside out", test::merge({test::box({0, 0, 0}, {1, 1, 1}), inverted}), tally);
  CHECK(tally.meshes == 18 + static_cast<std::size_t>(lattice_seeds));
  CHECK(tally.uncrossed == tally.meshes);
  CHECK(tally.coplanar_pairs > 100);
  CHECK(tally.coinciding > 20);
  CHECK(tally.split > 50);
}

TEST_CASE("lattice soups with coplanar overlaps and repeated triangles: pieces tile and never cross",
          "[arrangement]") {
  test::Random random(20261206);
  Tally tally;
  const std::size_t soups = test::sized(20, 5);
  for (std::size_t seed = 0; seed < soups; ++seed) {
    check_arrangement("coplanar lattice soup #" + std::to_string(seed),
                      lattice_soup(random, static_cast<int>(8 + seed % 12), static_cast<int>(10 + seed % 20),
                                   static_cast<int>(2 + seed % 3), true),
                      tally);
  }
  INFO("split " << tally.split << ", coplanar pairs " << tally.coplanar_pairs);
  CHECK(tally.meshes == soups);
  CHECK(tally.uncrossed == soups);
  CHECK(tally.coplanar_pairs > 2 * soups);
  CHECK(tally.coinciding > soups / 4);
}

TEST_CASE("order_around_edge orders input points as order_around_line does", "[arrangement][order]") {
  test::Random random(42);
  for (int round = 0; round < 300; ++round) {
    // Lattice points: ties (two points on one ray) and points on the line;
    // every third round doubles in general position.
    std::vector<Vec3> points;
    const bool lattice = round % 3 != 0;
    for (int i = 0; i < 8; ++i) {
      points.push_back(lattice ? Vec3{static_cast<double>(random.index(3)), static_cast<double>(random.index(3)),
                                      static_cast<double>(random.index(3))}
                               : Vec3{random.uniform(-1, 1), random.uniform(-1, 1), random.uniform(-1, 1)});
    }
    if (points[0].x == points[1].x && points[0].y == points[1].y && points[0].z == points[1].z) continue;
    const std::vector<std::array<VertexIndex, 3>> no_planes;
    const std::vector<ApproxPlane> no_approx;
    const PlaneSet set{points, no_planes, no_approx, {}};
    std::vector<PointDef> around;
    for (VertexIndex i = 2; i < points.size(); ++i) around.push_back(PointDef::input(i));
    INFO("round " << round);
    CHECK(order_around_edge(set, PointDef::input(0), PointDef::input(1), around) ==
          order_around_line(points[0], points[1], std::span<const Vec3>(points).subspan(2)));
  }
}

TEST_CASE("around an edge where two surfaces cross, their pieces alternate", "[arrangement][order]") {
  // Two spheres in general position: every edge of the pieces is shared by two
  // pieces, or by four along an intersection, two of each surface, and a surface
  // that crosses the other there alternates with it around the edge.
  test::Random random(11);
  std::size_t crossing_edges = 0;
  for (int seed = 0; seed < 6; ++seed) {
    const auto angle = [&] { return random.uniform(0, 6.283185307179586); };
    const Mesh sphere = test::ellipsoid({0, 0, 0}, {1, 1, 1}, 10, 7);
    const Mesh first = turned(sphere, angle(), angle(), angle(), {0, 0, 0});
    const Mesh mesh = test::merge({first, turned(sphere, angle(), angle(), angle(), {0.5, 0.3, 0.2})});
    const MeshArrangement arrangement = arrange_triangles(mesh.positions, mesh.triangles);
    REQUIRE(arrangement.coplanar_pairs.empty());
    const PlaneSet set = arrangement.plane_set();
    std::map<std::pair<VertexIndex, VertexIndex>, std::vector<std::size_t>> pieces_at;  // by (from, to) of the lesser way
    for (std::size_t k = 0; k < arrangement.triangles.size(); ++k) {
      const Triangle& piece = arrangement.triangles[k];
      for (int c = 0; c < 3; ++c) {
        const VertexIndex u = piece[c], v = piece[(c + 1) % 3];
        pieces_at[{std::min(u, v), std::max(u, v)}].push_back(k);
      }
    }
    const auto surface = [&](std::size_t piece) { return arrangement.source[piece] < first.triangles.size(); };
    for (const auto& [edge, pieces] : pieces_at) {
      INFO("seed " << seed << ", edge " << edge.first << "-" << edge.second);
      REQUIRE((pieces.size() == 2 || pieces.size() == 4));
      if (pieces.size() != 4) continue;
      std::vector<PointDef> opposite;
      for (std::size_t piece : pieces) {
        for (VertexIndex w : arrangement.triangles[piece]) {
          if (w != edge.first && w != edge.second) opposite.push_back(arrangement.defs[w]);
        }
      }
      const auto order = order_around_edge(set, arrangement.defs[edge.first], arrangement.defs[edge.second], opposite);
      REQUIRE(order.has_value());
      for (std::size_t i = 0; i < 4; ++i) {
        CHECK(surface(pieces[(*order)[i]]) != surface(pieces[(*order)[(i + 1) % 4]]));
      }
      ++crossing_edges;
    }
  }
  CHECK(crossing_edges > 100);
}
