// Stage 3 of the exact self-intersection repair (issue 21, item 1): the faces
// an arrangement winds around, merged into a plane-based Solid
// (solid_from_winding_boundary), rounded and certified (round_repaired_solid),
// and the whole step as repair_mesh runs it with the hook the CLI passes. Judged
// apart from the code: the Solid is sound (check_solid) and its exact volume is
// the union's (lattice voxels, or CGAL's corefinement union on exact
// constructions, Epeck); the repaired mesh validates, reads back valid, keeps
// that volume within the bound of one rounding of its vertices, and is the same
// bytes whatever the thread count.

#include <catch2/catch.hpp>

#include <gmpxx.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "shatter/generators/corpus.hpp"
#include "shatter/generators/random.hpp"
#include "shatter/generators/solids.hpp"
#include "shatter/kernel/arrangement.hpp"
#include "shatter/kernel/exact.hpp"
#include "shatter/kernel/inside.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/mass.hpp"
#include "shatter/kernel/rationals.hpp"
#include "shatter/kernel/repair.hpp"
#include "shatter/kernel/validate.hpp"
#include "shatter/triangulate/solid_mesh.hpp"
#include "support/lattice_boxes.hpp"
#include "support/sanitizers.hpp"
#include "support/turned.hpp"
#include "support/union_volume.hpp"

using namespace shatter;

namespace {

using EK = ExactKernel;

// Six times the signed volume of a mesh, exactly, on its doubles.
mpq_class six_volume(const Mesh& mesh) {
  mpq_class sum;
  for (const Triangle& t : mesh.triangles) {
    const Vec3 &a = mesh.positions[t[0]], &b = mesh.positions[t[1]], &c = mesh.positions[t[2]];
    const mpq_class ax(a.x), ay(a.y), az(a.z), bx(b.x), by(b.y), bz(b.z), cx(c.x), cy(c.y), cz(c.z);
    sum += ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx);
  }
  return sum;
}

// What rounding every vertex of `mesh` to doubles can move its volume by: each
// triangle swept by its corners' moves, at most half an ulp of the largest
// coordinate per axis (L1: 3 half-ulps), over twice its area plus the moves'
// own terms (Steiner's bound, as round_solid states it), summed.
double rounding_bound(const Mesh& mesh) {
  double largest = 0, area = 0, perimeter = 0;
  for (const Vec3& p : mesh.positions) largest = std::max({largest, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
  for (const Triangle& t : mesh.triangles) {
    const Vec3 &a = mesh.positions[t[0]], &b = mesh.positions[t[1]], &c = mesh.positions[t[2]];
    area += 0.5 * norm(cross(b - a, c - a));
    perimeter += norm(b - a) + norm(c - b) + norm(a - c);
  }
  const double d = 3 * 0.5 * std::nextafter(largest, INFINITY) - 3 * 0.5 * largest + 3 * std::ldexp(largest, -53);
  return 2 * d * area + 4 * d * d * perimeter + 5 * d * d * d * static_cast<double>(mesh.triangles.size());
}

struct Resolved {
  ArrangementSolid made;
  mpq_class exact_six_volume;  ///< of the Solid, exactly
};

// The Solid of `mesh`'s union; requires it sound when made.
Resolved resolve(const Mesh& mesh) {
  const MeshArrangement arrangement = arrange_triangles(mesh.positions, mesh.triangles);
  const WindingBoundary boundary = winding_boundary(arrangement);
  REQUIRE(boundary.status == WindingBoundary::Status::ok);
  Resolved out{solid_from_winding_boundary(arrangement, boundary, mesh.surfaces), 0};
  if (out.made.status != ArrangementSolid::Status::ok) return out;
  const PlaneSet set = arrangement.plane_set();
  INFO(check_solid(set, out.made.solid));
  REQUIRE(check_solid(set, out.made.solid).empty());
  out.exact_six_volume = exact_six_volume(set, out.made.solid);
  // Faces merged: no more faces than the boundary's triangles.
  CHECK(out.made.solid.faces.size() <= boundary.triangles.size());
  return out;
}

std::string report_text(const RepairReport& report) {
  std::string text = report.summary();
  for (const RepairNote& note : report.notes) text += "; not done: " + note.text;
  return text;
}

RepairOptions exact_options() {
  RepairOptions options;
  options.round_solid = round_repaired_solid;
  return options;
}

struct Repaired {
  Mesh mesh;
  RepairReport report;
  bool valid = false;
};

// repair_mesh with the exact step; the result validated, written as OFF, read
// back and validated again, and repaired again on one thread: the same bytes.
Repaired repair(const Mesh& damaged) {
  Repaired out{damaged, {}, false};
  out.report = repair_mesh(out.mesh, exact_options());
  out.valid = validate_mesh(out.mesh).valid();
  if (!out.valid) return out;
  const std::string bytes = write_mesh_to_bytes(out.mesh, MeshFormat::off);
  const Mesh read = read_mesh_from_bytes(bytes, MeshFormat::off);
  CHECK(validate_mesh(read).valid());
  Mesh serial = damaged;
  tbb::task_arena(1).execute([&] { repair_mesh(serial, exact_options()); });
  CHECK(write_mesh_to_bytes(serial, MeshFormat::off) == bytes);
  return out;
}

}  // namespace

TEST_CASE("unions of lattice boxes: a sound Solid of the voxels' volume, repaired into a valid mesh",
          "[arrangement][repair]") {
  // As test_arrangement_union's lattice boxes: overlapping, sharing faces,
  // inside each other, touching along an edge or at a corner.
  test::Random random(20261209);
  const std::size_t seeds = test::sized(40, 8);
  std::size_t repaired = 0, touching = 0, self_intersecting = 0;
  for (std::size_t seed = 0; seed < seeds; ++seed) {
    const int count = 2 + static_cast<int>(random.index(3));
    std::vector<Mesh> boxes;
    std::set<std::array<int, 3>> voxels;
    for (int b = 0; b < count; ++b) boxes.push_back(test::random_lattice_box(random, voxels).mesh);
    const Mesh merged = test::merge(boxes);
    INFO("lattice boxes #" << seed);
    const mpq_class expected(6 * static_cast<long>(voxels.size()));
    const Resolved resolved = resolve(merged);
    REQUIRE(resolved.made.status == ArrangementSolid::Status::ok);
    CHECK(resolved.exact_six_volume == expected);

    const Repaired result = repair(merged);
    if (!validate_mesh(merged).find(DefectKind::self_intersection)) continue;
    INFO(report_text(result.report));
    // Boxes touching along an edge: the Solid pairs its faces into wedges.
    // Until 2026-12-07 the steps before the exact one (CGAL's orientation and
    // hole filling on a soup with crowded edges) could leave such a mesh open;
    // a surface whose every edge is crossed as often each way now goes to the
    // exact step as it is (repair_mesh), and every one is repaired.
    ++(resolved.made.vertex_copies > 0 ? touching : self_intersecting);
    CHECK(result.valid);
    if (!result.valid) continue;
    ++repaired;
    // Boxes that only touch at a corner are separated by step 9 instead.
    if (const RepairChange* change = result.report.find(RepairKind::resolved_self_intersections_exactly)) {
      CHECK(change->count > 0);
    }
    // Integer corners round exactly: the volume is the voxels', but where boxes
    // touch at a corner and the copies there moved apart (within the bound the
    // report states, a hair of the edges).
    const double volume = mpq_class(six_volume(result.mesh) / 6).get_d();
    CHECK(std::abs(volume - mpq_class(expected / 6).get_d()) <= 1e-4 * mpq_class(expected / 6).get_d());
  }
  INFO("repaired " << repaired << ", of them " << self_intersecting << " without solids touching along an edge; "
                    << touching << " touching along an edge");
  CHECK(repaired == self_intersecting + touching);
  CHECK(self_intersecting > seeds / 4);
  CHECK(touching > 0);
}

namespace {

// A unit box at `corner` with its six faces split along the diagonal
// `diagonal` picks (0 or 1 per face), outward.
Mesh unit_box_at(Vec3 corner, unsigned diagonal) {
  Mesh box;
  for (int i = 0; i < 8; ++i) {
    box.positions.push_back(corner + Vec3{static_cast<double>(i & 1), static_cast<double>((i >> 1) & 1),
                                          static_cast<double>((i >> 2) & 1)});
  }
  // Each face's corners counter-clockwise seen from outside.
  const std::array<std::array<VertexIndex, 4>, 6> faces{{{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                                          {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}}};
  for (std::size_t f = 0; f < faces.size(); ++f) {
    const auto& q = faces[f];
    if ((diagonal >> f) & 1) {
      box.triangles.push_back({q[0], q[1], q[2]});
      box.triangles.push_back({q[0], q[2], q[3]});
    } else {
      box.triangles.push_back({q[1], q[2], q[3]});
      box.triangles.push_back({q[1], q[3], q[0]});
    }
  }
  box.surfaces.assign(box.triangles.size(), 0);
  return box;
}

}  // namespace

// Found by a sweep of `validate --repair` over generated dirty meshes
// (2026-12-07): unit boxes sharing whole faces whose triangles run along other
// diagonals (an L of three came out of volume 2.5, two side by side or four
// around an edge were refused as non-manifold). Every placement of 2 to 4
// boxes on a 2 x 2 x 2 lattice that shares a face, every choice of diagonals
// drawn at random: the union, of the boxes' total volume (up to the hair by
// which copies of a vertex where boxes touch only along an edge move apart),
// as a valid solid.
TEST_CASE("unit boxes sharing faces along other diagonals: their union, of their volume", "[arrangement][repair]") {
  test::Random random(20261207);
  std::size_t unions = 0;
  const std::size_t trials = test::sized(60, 12);
  for (std::size_t trial = 0; trial < trials; ++trial) {
    const int count = 2 + static_cast<int>(random.index(3));
    std::set<std::array<int, 3>> cells;
    std::vector<Mesh> boxes;
    while (static_cast<int>(boxes.size()) < count) {
      const std::array<int, 3> cell{static_cast<int>(random.index(2)), static_cast<int>(random.index(2)),
                                    static_cast<int>(random.index(2))};
      if (!cells.insert(cell).second) continue;
      boxes.push_back(unit_box_at({static_cast<double>(cell[0]), static_cast<double>(cell[1]),
                                   static_cast<double>(cell[2])},
                                  static_cast<unsigned>(random.index(64))));
    }
    const Mesh merged = test::merge(boxes);
    if (validate_mesh(merged).valid()) continue;  // no two share a face with other diagonals
    INFO("trial " << trial << ": " << count << " boxes");
    const Repaired result = repair(merged);
    INFO(report_text(result.report));
    REQUIRE(result.valid);
    // Where boxes touch only along an edge or at a corner, the copies of its
    // vertices move apart by a hair (the bound the report states).
    CHECK(std::abs(mpq_class(six_volume(result.mesh) / 6).get_d() - count) <= 1e-4 * count);
    ++unions;
  }
  CHECK(unions > trials / 2);
}

TEST_CASE("unions of solids at random angles: CGAL's exact union volume, repaired within one rounding",
          "[arrangement][repair]") {
  test::Random random(20261210);
  const std::size_t seeds = test::sized(6, 2);
  for (std::size_t seed = 0; seed < seeds; ++seed) {
    const auto angle = [&] { return random.uniform(0, 6.283185307179586); };
    const auto shift = [&](double reach) {
      return Vec3{random.uniform(-reach, reach), random.uniform(-reach, reach), random.uniform(-reach, reach)};
    };
    std::vector<Mesh> shells{
        test::turned(test::box({-1, -1, -1}, {1, 1, 1}), angle(), angle(), angle(), shift(0.8)),
        test::turned(test::ellipsoid({0, 0, 0}, {1, 1, 1}, 10, 7), angle(), angle(), angle(), shift(0.8)),
        test::turned(test::torus(1.0, 0.3, 10, 6), angle(), angle(), angle(), shift(0.5)),
    };
    if (seed % 2 == 1) {
      shells.push_back(test::turned(test::box({-0.3, -0.3, -0.3}, {0.3, 0.3, 0.3}), angle(), angle(), angle(), shift(1.2)));
    }
    const Mesh merged = test::merge(shells);
    INFO("solids at random angles #" << seed);
    const EK::FT cgal_six = test::six_volume_of_union(shells);
    const Resolved resolved = resolve(merged);
    REQUIRE(resolved.made.status == ArrangementSolid::Status::ok);
    CHECK(EK::FT(resolved.exact_six_volume) == cgal_six);

    const Repaired result = repair(merged);
    INFO(report_text(result.report));
    REQUIRE(result.valid);
    REQUIRE(result.report.find(RepairKind::resolved_self_intersections_exactly) != nullptr);
    const double exact = CGAL::to_double(cgal_six) / 6;
    const double volume = signed_volume(result.mesh);
    INFO("volume " << volume << ", union " << exact << ", bound " << rounding_bound(result.mesh));
    CHECK(std::abs(volume - exact) <= rounding_bound(result.mesh) + 1e-12 * std::abs(exact));
  }
}

TEST_CASE("a solid and a shifted copy of it, as shatter-fuzz's overlapping class makes them",
          "[arrangement][repair]") {
  for (const Mesh& solid : {test::ellipsoid({0, 0, 0}, {1, 0.7, 0.5}, 12, 8), test::torus(1.0, 0.35, 12, 8)}) {
    for (const double dx : {0.13, 0.41}) {
      const Mesh shifted = test::transformed(solid, 1.0, {dx, 0.05, -0.02});
      const Mesh merged = test::merge({solid, shifted});
      const Repaired result = repair(merged);
      INFO(report_text(result.report));
      REQUIRE(result.valid);
      // The union holds either solid and is at most both.
      const double volume = signed_volume(result.mesh), one = signed_volume(solid);
      CHECK(volume > one);
      CHECK(volume < 2 * one);
    }
  }
}

TEST_CASE("a hollow solid and its shifted copy: the cavities stay cavities", "[arrangement][repair]") {
  // shatter-fuzz's overlapping hollow-egg (seed fa6c99b8874c72dc): the copy's
  // outer shell crosses the original's cavity, and orienting the crossing
  // shells by their own volume filled both cavities (volume 7.3 for a union of
  // two 2.1 solids). They face as the input has them; the volume is CGAL's
  // union of the two hollow solids.
  const Mesh hollow = test::merge({test::ellipsoid({0, 0, 0}, {1, 0.8, 0.7}, 14, 9),
                                   test::flipped(test::ellipsoid({0, 0, 0}, {0.6, 0.5, 0.4}, 10, 7))});
  for (const double dx : {0.3, 0.55}) {
    const Mesh copy = test::transformed(hollow, 1.0, {dx, 0.07, -0.03});
    const Mesh merged = test::merge({hollow, copy});
    const double exact = CGAL::to_double(test::six_volume_of_union({hollow, copy}) / 6);
    const Repaired result = repair(merged);
    INFO("shift " << dx << ": " << report_text(result.report));
    REQUIRE(result.valid);
    REQUIRE(result.report.find(RepairKind::resolved_self_intersections_exactly) != nullptr);
    const double volume = signed_volume(result.mesh);
    INFO("volume " << volume << ", union " << exact);
    CHECK(std::abs(volume - exact) <= rounding_bound(result.mesh) + 1e-12 * std::abs(exact));
  }
}

// A prism of `height` over the convex polygon `base` (counter-clockwise seen
// from +z) from z = z0, outward.
Mesh prism_z(const std::vector<Vec2>& base, double z0, double height) {
  const auto n = static_cast<VertexIndex>(base.size());
  std::vector<Vec3> positions;
  for (const double z : {z0, z0 + height}) {
    for (const Vec2& p : base) positions.push_back({p.x, p.y, z});
  }
  std::vector<Triangle> triangles;
  for (VertexIndex k = 1; k + 1 < n; ++k) {
    triangles.push_back({0, k + 1, k});
    triangles.push_back({n, n + k, n + k + 1});
  }
  for (VertexIndex k = 0; k < n; ++k) {
    const VertexIndex next = (k + 1) % n;
    triangles.push_back({k, next, n + next});
    triangles.push_back({k, n + next, n + k});
  }
  return test::mesh_from(std::move(positions), std::move(triangles));
}

TEST_CASE("a face of the union that touches itself at a vertex: its loops split there", "[arrangement][repair]") {
  // A diamond prism standing through the top of a box, one corner of the
  // diamond on the box's top edge: the top face's triangle keeps a region
  // whose boundary passes that corner twice (the diamond's hole touches the
  // edge), in one fan of the solid. Union: 512 + 16 - 8.
  const Mesh box = test::box({0, 0, 0}, {8, 8, 8});
  const Mesh diamond = prism_z({{4, 0}, {5, 1}, {4, 2}, {3, 1}}, 4, 8);
  const Mesh merged = test::merge({box, diamond});
  const Resolved resolved = resolve(merged);
  REQUIRE(resolved.made.status == ArrangementSolid::Status::ok);
  CHECK(resolved.exact_six_volume == 6 * 520);
  CHECK(resolved.made.vertex_copies == 0);
  bool touching_loops = false;
  for (const SolidFace& face : resolved.made.solid.faces) touching_loops |= face.loop_count > 1;
  CHECK(touching_loops);

  const Repaired result = repair(merged);
  INFO(report_text(result.report));
  REQUIRE(result.valid);
  REQUIRE(result.report.find(RepairKind::resolved_self_intersections_exactly) != nullptr);
  CHECK(six_volume(result.mesh) == 6 * 520);
}

TEST_CASE("a union pinched at a vertex inside a face: one vertex copy per fan", "[arrangement][repair]") {
  // A block whose bottom is a saddle with its vertex v = (5, 2, 0) on the top
  // of a box: the saddle dips into the box over two opposite quadrants around
  // v and rises over the other two, so the top triangle keeps two wedges at v,
  // each closed by the saddle above it into a fan of its own (the outside
  // between them is pinched at v). Block: 2 x 2 x 2 less the saddle's zero
  // mean, 8; in the box, 4 x (1.5 / 6): 1. Union: 512 + 8 - 1.
  const Mesh box = test::box({0, 0, -8}, {8, 8, 0});
  const double d = 1.5, top = 2;
  const Mesh block = test::mesh_from(
      {{5, 2, 0}, {6, 3, -d}, {4, 3, d}, {4, 1, -d}, {6, 1, d}, {6, 3, top}, {4, 3, top}, {4, 1, top}, {6, 1, top}},
      {{0, 2, 1}, {0, 3, 2}, {0, 4, 3}, {0, 1, 4},                          // the saddle, facing down
       {5, 6, 7}, {5, 7, 8},                                                // top
       {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 4, 8}, {3, 8, 7},  // walls
       {4, 1, 5}, {4, 5, 8}});
  REQUIRE(validate_mesh(block).valid());
  REQUIRE(six_volume(block) == 6 * 8);
  const Mesh merged = test::merge({box, block});
  const Resolved resolved = resolve(merged);
  REQUIRE(resolved.made.status == ArrangementSolid::Status::ok);
  CHECK(resolved.exact_six_volume == 6 * 519);
  CHECK(resolved.made.vertex_copies == 1);

  const Repaired result = repair(merged);
  INFO(report_text(result.report));
  REQUIRE(result.valid);
  REQUIRE(result.report.find(RepairKind::resolved_self_intersections_exactly) != nullptr);
  // The copies moved apart, a hair of the edges at v.
  const double volume = mpq_class(six_volume(result.mesh) / 6).get_d();
  CHECK(std::abs(volume - 519) <= 1e-9 * 519);
}

TEST_CASE("a cavity whose tip touches the top of the solid from below: only the cavity's copy moves",
          "[arrangement][repair][touching]") {
  // b9_mesh.off's union, shrunk: a solid under a low roof peaked at v = origin,
  // and a narrow pyramid cavity whose apex is v. The union is pinched at v
  // between the roof's fan and the cavity's. Both fans' edges point down, so
  // moving each along its mean edge (round_solid's first separation) takes the
  // roof's copy of v down into the cavity, further than the cavity's copy (its
  // edges are longer): they cross at any scale. Keeping the roof's fan still and
  // moving the cavity's copy separates them. Volume: a box of 8 x 8 x 3 under
  // a roof of 8 x 8 x 1 / 3, less the cavity's 0.5 x 0.5 x 2 / 3.
  const double w = 4, r = 0.25;
  const Mesh solid = test::mesh_from(
      {{0, 0, 0}, {-w, -w, -1}, {w, -w, -1}, {w, w, -1}, {-w, w, -1}, {-w, -w, -4}, {w, -w, -4}, {w, w, -4}, {-w, w, -4}},
      {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}, {0, 4, 1},                          // roof
       {5, 7, 6}, {5, 8, 7},                                                // bottom
       {1, 5, 6}, {1, 6, 2}, {2, 6, 7}, {2, 7, 3}, {3, 7, 8}, {3, 8, 4},  // walls
       {4, 8, 5}, {4, 5, 1}});
  const Mesh cavity = test::mesh_from({{0, 0, 0}, {-r, -r, -2}, {r, -r, -2}, {r, r, -2}, {-r, r, -2}},
                                      {{0, 2, 1}, {0, 3, 2}, {0, 4, 3}, {0, 1, 4}, {1, 2, 3}, {1, 3, 4}});
  REQUIRE(validate_mesh(solid).valid());
  REQUIRE(six_volume(solid) == 6 * (8 * 8 * 3) + 2 * (8 * 8));
  REQUIRE(six_volume(cavity) == -2 * (0.5 * 0.5 * 2));
  const Mesh merged = test::merge({solid, cavity});
  const Resolved resolved = resolve(merged);
  REQUIRE(resolved.made.status == ArrangementSolid::Status::ok);
  CHECK(resolved.exact_six_volume == six_volume(solid) + six_volume(cavity));

  const MeshArrangement arrangement = arrange_triangles(merged.positions, merged.triangles);
  const RepairRounding rounded = round_repaired_solid(arrangement.plane_set(), resolved.made.solid, merged);
  INFO(rounded.defect);
  REQUIRE(rounded.valid);
  CHECK(validate_mesh(rounded.mesh).valid());
  CHECK(rounded.separated_vertices == 1);  // the cavity's copy only
  const double volume = mpq_class(six_volume(rounded.mesh) / 6).get_d();
  const double exact = mpq_class(resolved.exact_six_volume / 6).get_d();
  CHECK(std::abs(volume - exact) <= 1e-9 * exact);
  // The same bytes on one thread.
  RepairRounding serial;
  tbb::task_arena(1).execute([&] { serial = round_repaired_solid(arrangement.plane_set(), resolved.made.solid, merged); });
  CHECK(write_mesh_to_bytes(serial.mesh, MeshFormat::off) == write_mesh_to_bytes(rounded.mesh, MeshFormat::off));
}

TEST_CASE("a union's tetrahedron touching the rest at a vertex is kept, not cancelled as a sheet",
          "[arrangement][repair][touching]") {
  // diplodocus.off's union, shrunk: two boxes sharing an edge (their copies of
  // the edge's ends merge when rounded, so only the rounds that untangle edges
  // can write it) and a small tetrahedron touching one box at a corner. Those
  // rounds also cancel two-sided sheets over four corners, whose four triangles
  // bound a tetrahedron: they took the tetrahedron for one and lost its volume,
  // which the volume bound (nothing here moves when rounded) then refused, in
  // every round.
  const Mesh left = test::box({0, 0, 0}, {2, 2, 2});
  const Mesh right = test::box({2, 2, 0}, {4, 4, 2});
  Mesh tetrahedron = test::mesh_from({{0, 0, 0}, {-2, -1, -1}, {-1, -2, -1}, {-1, -1, -2}},
                                     {{0, 1, 2}, {0, 2, 3}, {0, 3, 1}, {1, 3, 2}});
  if (six_volume(tetrahedron) < 0) {
    for (Triangle& t : tetrahedron.triangles) std::swap(t[1], t[2]);
  }
  REQUIRE(validate_mesh(tetrahedron).valid());
  REQUIRE(six_volume(tetrahedron) == 4);
  const Mesh merged = test::merge({left, right, tetrahedron});
  const Resolved resolved = resolve(merged);
  REQUIRE(resolved.made.status == ArrangementSolid::Status::ok);
  REQUIRE(resolved.exact_six_volume == 6 * 16 + 4);

  const MeshArrangement arrangement = arrange_triangles(merged.positions, merged.triangles);
  const RepairRounding rounded = round_repaired_solid(arrangement.plane_set(), resolved.made.solid, merged);
  INFO(rounded.defect);
  REQUIRE(rounded.valid);
  CHECK(validate_mesh(rounded.mesh).valid());
  CHECK(rounded.mesh.triangles.size() == merged.triangles.size());  // the tetrahedron's four kept
  CHECK(rounded.moved_volume <= rounded.moved_volume_bound);
  const double volume = mpq_class(six_volume(rounded.mesh) / 6).get_d();
  CHECK(std::abs(volume - (16 + 4.0 / 6)) <= 1e-9 * 17);
  const Mesh read = read_mesh_from_bytes(write_mesh_to_bytes(rounded.mesh, MeshFormat::off), MeshFormat::off);
  CHECK(validate_mesh(read).valid());
}

TEST_CASE("tetrahedra around one edge (overlapping or apart): their union point by point", "[arrangement][repair]") {
  // Two to five tetrahedra on one edge, each over its own angle around it: the
  // union's wedges meet along the edge, which the rounds that untangle edges
  // separate. Those rounds also cancel two-sided sheets over four corners, and
  // a whole tetrahedron meeting the rest only along the edge looks like one:
  // removing it moved more volume than rounding can, and every round failed
  // (the sweep's three_tets_on_one_edge_overlapping.off was refused).
  test::Random random(20261208);
  const std::size_t trials = test::sized(40, 10);
  std::size_t overlapping = 0;
  for (std::size_t trial = 0; trial < trials; ++trial) {
    const int count = 2 + static_cast<int>(random.index(4));
    const bool overlap = trial % 2 == 0;
    const auto angle = [&] { return random.uniform(0, 6.283185307179586); };
    const double a = angle(), b = angle(), c = angle();
    const Vec3 shift{random.uniform(-1, 1), random.uniform(-1, 1), random.uniform(-1, 1)};
    std::vector<Mesh> tetrahedra;
    double largest = 0, sum = 0;
    for (int i = 0; i < count; ++i) {
      const double width = 6.283185307179586 / count;
      const double from = overlap ? angle() : (i + random.uniform(0.05, 0.3)) * width;
      const double to = overlap ? from + random.uniform(0.3, 1.5) : (i + 1 - random.uniform(0.05, 0.3)) * width;
      const double r0 = random.uniform(0.5, 1.5), r1 = random.uniform(0.5, 1.5);
      Mesh tetrahedron = test::mesh_from(
          {{0, 0, 0}, {0, 0, 1}, {r0 * std::cos(from), r0 * std::sin(from), random.uniform(0.2, 0.8)},
           {r1 * std::cos(to), r1 * std::sin(to), random.uniform(0.2, 0.8)}},
          {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}});
      if (six_volume(tetrahedron) < 0) {
        for (Triangle& t : tetrahedron.triangles) std::swap(t[1], t[2]);
      }
      // Turned as a whole: the edge's ends are the same doubles in each.
      tetrahedron = test::turned(tetrahedron, a, b, c, shift);
      REQUIRE(validate_mesh(tetrahedron).valid());
      const double volume = signed_volume(tetrahedron);
      largest = std::max(largest, volume);
      sum += volume;
      tetrahedra.push_back(std::move(tetrahedron));
    }
    const Mesh merged = test::merge(tetrahedra);
    INFO("trial " << trial << ": " << count << (overlap ? " overlapping" : " apart") << " tetrahedra");
    const Repaired result = repair(merged);
    INFO(report_text(result.report));
    REQUIRE(result.valid);
    const double volume = signed_volume(result.mesh);
    CHECK(volume >= largest * (1 - 1e-9));
    CHECK(volume <= sum * (1 + 1e-9));
    // Inside the result exactly where inside one of the tetrahedra (points a
    // hair from the edge, where its copies moved apart, are not drawn).
    std::vector<std::unique_ptr<PointInSolid>> parts;
    for (const Mesh& tetrahedron : tetrahedra) parts.push_back(std::make_unique<PointInSolid>(tetrahedron));
    const PointInSolid solid(result.mesh);
    Vec3 lo = merged.positions.front(), hi = lo;
    for (const Vec3& p : merged.positions) {
      lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
      hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
    }
    std::size_t disagree = 0, inside = 0;
    for (int i = 0; i < 300; ++i) {
      const Vec3 p{random.uniform(lo.x, hi.x), random.uniform(lo.y, hi.y), random.uniform(lo.z, hi.z)};
      const bool in_part = std::any_of(parts.begin(), parts.end(), [&](const auto& part) { return part->strictly_inside(p); });
      disagree += in_part != solid.strictly_inside(p);
      inside += in_part;
    }
    CHECK(disagree == 0);
    CHECK(inside > 0);
    overlapping += overlap;
  }
  CHECK(overlapping == (trials + 1) / 2);
}

TEST_CASE("one shell turned inside out as a whole and crossing itself is repaired as when read the right way round",
          "[arrangement][repair]") {
  // A unit box whose top is a fan around its centre, the centre pulled down
  // through the bottom: one shell crossing itself. Turned inside out, its
  // triangles all face against the input's, which the exact step follows for a
  // shell that may be a cavity; it then wound around only the spike below the
  // bottom (a spool so damaged by shatter-fuzz came out of volume 2e-5 instead
  // of 0.16). A mesh of one shell has no shell to be a cavity of.
  for (const double depth : {-0.5, -0.25, -1.5}) {
    const Mesh dented = test::mesh_from(
        {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}, {0.5, 0.5, depth}},
        {{0, 2, 1}, {0, 3, 2},                          // bottom
         {0, 1, 5}, {0, 5, 4}, {1, 2, 6}, {1, 6, 5},  // sides
         {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7},
         {4, 5, 8}, {5, 6, 8}, {6, 7, 8}, {7, 4, 8}});  // the top, fanned around its pulled centre
    Mesh inverted = dented;
    for (Triangle& t : inverted.triangles) std::swap(t[1], t[2]);
    INFO("centre pulled to z = " << depth);
    const Repaired as_read = repair(dented);
    INFO(report_text(as_read.report));
    REQUIRE(as_read.valid);
    const Repaired turned = repair(inverted);
    INFO(report_text(turned.report));
    REQUIRE(turned.valid);
    // The region wound around once: the box less the part of the cone from
    // its top to the pulled centre that lies in it (the spike below the bottom
    // is wound around -1 times). The cone's section at height z is a square of
    // side (z - depth) / (1 - depth).
    const double in_box = (std::pow(1 - depth, 3) - std::pow(-depth, 3)) / (3 * (1 - depth) * (1 - depth));
    CHECK(std::abs(signed_volume(as_read.mesh) - (1 - in_box)) <= 1e-12);
    CHECK(std::abs(signed_volume(turned.mesh) - (1 - in_box)) <= 1e-12);
  }
}

TEST_CASE("the exact step changes nothing where nothing self-intersects", "[arrangement][repair]") {
  // A valid mesh, and one the earlier steps repair (unwelded, a triangle
  // reversed): the same bytes with the hook as without.
  const Mesh sphere = test::ellipsoid({0, 0, 0}, {1, 1, 1}, 10, 7);
  Mesh flipped = sphere;
  std::swap(flipped.triangles[3][1], flipped.triangles[3][2]);
  for (const Mesh& input : {sphere, flipped}) {
    Mesh with = input, without = input;
    const RepairReport a = repair_mesh(with, exact_options());
    const RepairReport b = repair_mesh(without);
    CHECK(a.summary() == b.summary());
    CHECK(write_mesh_to_bytes(with, MeshFormat::off) == write_mesh_to_bytes(without, MeshFormat::off));
    CHECK_FALSE(a.find(RepairKind::resolved_self_intersections_exactly));
  }
}

TEST_CASE("the self-intersecting corpus: resolved into valid solids", "[arrangement][repair][corpus]") {
  std::size_t meshes = 0, valid = 0;
  for (const auto& path : test::self_intersecting_meshes()) {
    const Mesh mesh = read_mesh(path);
    const Repaired result = repair(mesh);
    INFO(path.filename().string() << ": " << report_text(result.report));
    CHECK(result.valid);
    valid += result.valid;
    ++meshes;
  }
  CHECK(meshes >= 3);
  CHECK(valid == meshes);
}
