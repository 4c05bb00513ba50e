// Validation: every defect kind on hand-built meshes with exact counts and first
// elements, and the shared corpus (valid, bad and self-intersecting meshes).

#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <numeric>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "shatter/generators/corpus.hpp"
#include "shatter/generators/solids.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/certify.hpp"
#include "shatter/kernel/self_intersections.hpp"
#include "shatter/kernel/star_shaped.hpp"
#include "shatter/kernel/validate.hpp"
#include "support/sanitizers.hpp"

using namespace shatter;

namespace {

// The corner tetrahedron (0,0,0), (s,0,0), (0,s,0), (0,0,s), outward.
Mesh corner_tetrahedron(double s = 1) {
  return test::mesh_from({{0, 0, 0}, {s, 0, 0}, {0, s, 0}, {0, 0, s}}, {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}});
}

std::vector<DefectKind> kinds(const ValidationReport& report) {
  std::vector<DefectKind> result;
  for (const Defect& d : report.defects) result.push_back(d.kind);
  return result;
}

void reverse_all(Mesh& mesh) {
  for (Triangle& t : mesh.triangles) std::swap(t[1], t[2]);
}

}  // namespace

TEST_CASE("hand-built closed meshes validate clean", "[validate]") {
  for (const Mesh& mesh : {test::unit_cube(), corner_tetrahedron()}) {
    const ValidationReport report = validate_mesh(mesh);
    CHECK(report.valid());
    CHECK(report.defects.empty());
    CHECK(report.self_intersections_checked);
    CHECK(report.summary() == "valid");
    CHECK(report.vertex_count == mesh.vertex_count());
    CHECK(report.triangle_count == mesh.triangle_count());
  }
}

TEST_CASE("non-finite coordinates are counted and block geometric checks", "[validate]") {
  Mesh mesh = test::unit_cube();
  mesh.positions[5].x = std::numeric_limits<double>::quiet_NaN();
  mesh.positions[7].z = -std::numeric_limits<double>::infinity();
  const ValidationReport report = validate_mesh(mesh);
  REQUIRE(kinds(report) == std::vector{DefectKind::nonfinite_coordinate});
  CHECK(report.defects[0].count == 2);
  CHECK(report.defects[0].first == "vertex 5");
  CHECK_FALSE(report.self_intersections_checked);
  CHECK(report.summary().find("non-finite") != std::string::npos);
}

TEST_CASE("indices out of range are counted and never read", "[validate]") {
  Mesh mesh = test::unit_cube();
  mesh.triangles.push_back({0, 1, 42});
  mesh.triangles.push_back({42, 43, 44});
  mesh.surfaces.resize(mesh.triangles.size());
  const ValidationReport report = validate_mesh(mesh);
  REQUIRE(kinds(report) == std::vector{DefectKind::index_out_of_range});
  CHECK(report.defects[0].count == 2);
  CHECK(report.defects[0].first == "triangle 12");
  CHECK_FALSE(report.self_intersections_checked);
}

TEST_CASE("unused vertices are reported but do not block the geometric checks", "[validate]") {
  Mesh mesh = test::unit_cube();
  mesh.positions.push_back({5, 5, 5});
  mesh.positions.push_back({6, 6, 6});
  const ValidationReport report = validate_mesh(mesh);
  REQUIRE(kinds(report) == std::vector{DefectKind::unused_vertex});
  CHECK(report.defects[0].count == 2);
  CHECK(report.defects[0].first == "vertex 8");
  CHECK(report.self_intersections_checked);
}

namespace {
// A corner tetrahedron (edge 2) whose face (1,2,3) is split at the midpoint 4 of
// edge (1,2), closed by the flat triangle (1,2,4): a T-junction filled with a
// zero-area triangle, as exporters produce. Closed and consistently oriented.
Mesh tetrahedron_with_flat_triangle(Vec3 split_point) {
  return test::mesh_from({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0, 0, 2}, split_point},
                   {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 4, 3}, {4, 2, 3}, {1, 2, 4}});
}
}  // namespace

TEST_CASE("zero-area triangles are decided exactly", "[validate]") {
  SECTION("three collinear corners") {
    const ValidationReport report = validate_mesh(tetrahedron_with_flat_triangle({1, 1, 0}));
    REQUIRE(kinds(report) == std::vector{DefectKind::zero_area_triangle});
    CHECK(report.defects[0].count == 1);
    CHECK(report.defects[0].first == "triangle 5");
    CHECK_FALSE(report.self_intersections_checked);
    CHECK(report.summary().find("zero-area") != std::string::npos);
  }
  SECTION("one ulp off the line is not collinear") {
    const ValidationReport report = validate_mesh(tetrahedron_with_flat_triangle({1, std::nextafter(1.0, 2.0), 0}));
    CHECK(report.find(DefectKind::zero_area_triangle) == nullptr);
    CHECK(report.valid());
  }
  SECTION("collinear with coordinates that are not small integers") {
    // 3 * 0.1 rounds, but (0.1, 0.2, 0.3) * 2^k scalings are exact: these three
    // points are exactly collinear in doubles.
    const Vec3 a{0.1, 0.2, 0.3}, b{0.4, 0.8, 1.2}, c{0.2, 0.4, 0.6};
    Mesh mesh = test::mesh_from({a, b, c}, {{0, 1, 2}});
    const ValidationReport report = validate_mesh(mesh);
    const Defect* zero_area = report.find(DefectKind::zero_area_triangle);
    REQUIRE(zero_area != nullptr);
    CHECK(zero_area->count == 1);
    CHECK(zero_area->first == "triangle 0");
  }
  SECTION("a repeated index") {
    Mesh mesh = test::unit_cube();
    mesh.triangles.push_back({0, 0, 1});
    mesh.surfaces.resize(mesh.triangles.size());
    const ValidationReport report = validate_mesh(mesh);
    // The flat triangle is left out of the edge topology, so the cube stays closed.
    REQUIRE(kinds(report) == std::vector{DefectKind::zero_area_triangle});
    CHECK(report.defects[0].count == 1);
    CHECK(report.defects[0].first == "triangle 12");
  }
}

TEST_CASE("boundary edges of an open mesh", "[validate]") {
  Mesh mesh = test::unit_cube();
  mesh.triangles.erase(mesh.triangles.begin());  // drop (0, 2, 1)
  mesh.surfaces.pop_back();
  const ValidationReport report = validate_mesh(mesh);
  REQUIRE(kinds(report) == std::vector{DefectKind::boundary_edge});
  CHECK(report.defects[0].count == 3);
  // Edges are met in triangle order: (0, 3, 2) brings (0, 3), (2, 3), (0, 2).
  CHECK(report.defects[0].first == "edge (0, 2)");
  CHECK(report.summary() == "open mesh: 3 boundary edges, first edge (0, 2)");
  CHECK_FALSE(report.self_intersections_checked);
}

TEST_CASE("non-manifold edge: two tetrahedra sharing an edge", "[validate]") {
  // The second tetrahedron is the first turned half a turn about the x axis.
  const Mesh mesh = test::mesh_from({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, -1, 0}, {0, 0, -1}},
                              {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3},    //
                               {0, 4, 1}, {0, 1, 5}, {0, 5, 4}, {1, 4, 5}});
  const ValidationReport report = validate_mesh(mesh);
  // Two and two triangles traverse the edge each way: orientable, so only the
  // non-manifold edge is reported, not its endpoints nor the orientation.
  REQUIRE(kinds(report) == std::vector{DefectKind::non_manifold_edge});
  CHECK(report.defects[0].count == 1);
  CHECK(report.defects[0].first == "edge (0, 1)");
  CHECK_FALSE(report.self_intersections_checked);
}

TEST_CASE("non-manifold edge: three triangles on one edge", "[validate]") {
  SECTION("two one way, one the other: paired as far as possible") {
    const Mesh mesh = test::mesh_from({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, -1, 0}},
                                {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}});
    const ValidationReport report = validate_mesh(mesh);
    // The odd third triangle is the non-manifold defect, not an orientation one.
    REQUIRE(kinds(report) == std::vector{DefectKind::boundary_edge, DefectKind::non_manifold_edge});
    CHECK(report.find(DefectKind::boundary_edge)->count == 6);
    CHECK(report.find(DefectKind::boundary_edge)->first == "edge (1, 2)");
    CHECK(report.find(DefectKind::non_manifold_edge)->count == 1);
    CHECK(report.find(DefectKind::non_manifold_edge)->first == "edge (0, 1)");
  }
  SECTION("all three the same way: also inconsistently oriented") {
    const Mesh mesh = test::mesh_from({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, -1, 0}},
                                {{0, 1, 2}, {0, 1, 3}, {0, 1, 4}});
    const ValidationReport report = validate_mesh(mesh);
    REQUIRE(kinds(report) == std::vector{DefectKind::boundary_edge, DefectKind::non_manifold_edge,
                                         DefectKind::inconsistent_orientation});
    CHECK(report.find(DefectKind::inconsistent_orientation)->count == 1);
    CHECK(report.find(DefectKind::inconsistent_orientation)->first == "edge (0, 1)");
  }
}

TEST_CASE("non-manifold vertex: two tetrahedra touching at a vertex", "[validate]") {
  // The second tetrahedron is the first reflected through the origin, with its
  // triangles reversed to stay outward.
  const Mesh mesh = test::mesh_from({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {-1, 0, 0}, {0, -1, 0}, {0, 0, -1}},
                              {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3},    //
                               {0, 4, 5}, {0, 6, 4}, {0, 5, 6}, {4, 6, 5}});
  const ValidationReport report = validate_mesh(mesh);
  REQUIRE(kinds(report) == std::vector{DefectKind::non_manifold_vertex, DefectKind::self_intersection});
  CHECK(report.defects[0].count == 1);
  CHECK(report.defects[0].first == "vertex 0");
  CHECK(report.summary().find("non-manifold") != std::string::npos);
  // The crossing test runs with one copy of vertex 0 per fan: each of the three
  // triangles of one solid at the pinch touches each of the three of the other.
  CHECK(report.self_intersections_checked);
  CHECK(report.defects[1].count == 9);
  CHECK(report.defects[1].first == "triangles 0 and 4");
}

TEST_CASE("inconsistent orientation: one face of a tetrahedron flipped", "[validate]") {
  Mesh mesh = corner_tetrahedron();
  mesh.triangles[1] = {0, 3, 1};
  const ValidationReport report = validate_mesh(mesh);
  REQUIRE(kinds(report) == std::vector{DefectKind::inconsistent_orientation});
  CHECK(report.defects[0].count == 3);
  // Edge order: (0,2), (1,2), (0,1) from triangle 0; (0,1) is the first bad one.
  CHECK(report.defects[0].first == "edge (0, 1)");
  CHECK_FALSE(report.self_intersections_checked);
  CHECK(report.summary().find("inconsistent orientation") != std::string::npos);
}

TEST_CASE("inward orientation: every face reversed", "[validate]") {
  for (Mesh mesh : {test::unit_cube(), corner_tetrahedron()}) {
    reverse_all(mesh);
    const ValidationReport report = validate_mesh(mesh);
    REQUIRE(kinds(report) == std::vector{DefectKind::inward_orientation});
    CHECK(report.summary() == "inward-facing: negative volume (faces point inward)");
    // A reversed mesh is still a closed 2-manifold, so it was checked for crossings.
    CHECK(report.self_intersections_checked);
  }
}

namespace {
// A big tetrahedron pierced through its slanted face (triangle 3) by the apex of a
// small one (triangles 4-7, apex faces 5, 6, 7): exactly three crossing pairs.
Mesh pierced_tetrahedron() {
  return test::mesh_from({{0, 0, 0}, {10, 0, 0}, {0, 10, 0}, {0, 0, 10}, {2, 2, 2}, {4, 2, 2}, {2, 4, 2}, {3, 3, 5}},
                   {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3},    //
                    {4, 6, 5}, {4, 5, 7}, {5, 6, 7}, {6, 4, 7}});
}
}  // namespace

TEST_CASE("self-intersections: count and first pair", "[validate]") {
  const ValidationReport report = validate_mesh(pierced_tetrahedron());
  CHECK(report.self_intersections_checked);
  REQUIRE(kinds(report) == std::vector{DefectKind::self_intersection});
  CHECK(report.defects[0].count == 3);
  CHECK(report.defects[0].first == "triangles 3 and 5");
  CHECK(report.summary() == "self-intersecting: 3 pairs of intersecting triangles, first triangles 3 and 5");

  ValidationOptions skip;
  skip.check_self_intersections = false;
  const ValidationReport unchecked = validate_mesh(pierced_tetrahedron(), skip);
  CHECK(unchecked.valid());
  CHECK_FALSE(unchecked.self_intersections_checked);
}

TEST_CASE("defects are listed in enum order and the summary names the first", "[validate]") {
  Mesh mesh = test::unit_cube();
  mesh.triangles.erase(mesh.triangles.begin());
  mesh.surfaces.pop_back();
  mesh.positions.push_back({9, 9, 9});
  const ValidationReport report = validate_mesh(mesh);
  REQUIRE(kinds(report) == std::vector{DefectKind::unused_vertex, DefectKind::boundary_edge});
  CHECK(report.summary() == "unused vertices: 1 vertex no triangle uses, first vertex 8; also boundary edges (3)");
}

TEST_CASE("the empty mesh has no defect", "[validate]") {
  const ValidationReport report = validate_mesh(Mesh{});
  CHECK(report.valid());
}

TEST_CASE("defect names are distinct and non-empty", "[validate]") {
  std::vector<std::string> names;
  for (int k = 0; k <= static_cast<int>(DefectKind::misnested_shell); ++k) {
    names.emplace_back(defect_name(static_cast<DefectKind>(k)));
    CHECK_FALSE(names.back().empty());
  }
  std::sort(names.begin(), names.end());
  CHECK(std::unique(names.begin(), names.end()) == names.end());
  // Messages about crossings always carry the word "self-intersecting".
  CHECK(defect_name(DefectKind::self_intersection).find("self-intersecting") != std::string_view::npos);
}

// --- Nesting ------------------------------------------------------------------
// Shells must alternate going inward: outward, cavity, island, cavity... Every
// orientation of up to four nested lattice boxes (and a fifth beside them) is
// tried; the mesh is valid exactly when each box faces outward at even depth
// and inward at odd depth. (Found by shatter-fuzz --repair-cases: two nested
// outward boxes passed validation, and fracture wrote leaves covering the inner
// box twice.)
TEST_CASE("shells nested with the wrong orientation are misnested, every combination", "[validate]") {
  using test::box;
  using test::flipped;
  using test::merge;
  for (int depth = 2; depth <= 4; ++depth) {
    for (bool with_neighbour : {false, true}) {
      for (unsigned orientation = 0; orientation < (1u << depth); ++orientation) {
        std::vector<Mesh> shells;
        bool expect_valid = true;
        for (int level = 0; level < depth; ++level) {
          const double inset = 2.0 * level;  // exact lattice boxes, one inside the other
          Mesh shell = box({inset, inset, inset}, {20 - inset, 20 - inset, 20 - inset});
          const bool outward = (orientation >> level & 1u) == 0;
          if (!outward) shell = flipped(shell);
          expect_valid = expect_valid && (outward == (level % 2 == 0));
          shells.push_back(shell);
        }
        // A box beside the outermost one, facing out: depth 0, never misnested.
        if (with_neighbour) shells.push_back(box({30, 0, 0}, {31, 1, 1}));
        const ValidationReport report = validate_mesh(merge(shells));
        INFO("depth " << depth << " orientation " << orientation << " neighbour " << with_neighbour << ": "
                      << report.summary());
        CHECK(report.valid() == expect_valid);
        if (!expect_valid) {
          // Everything reversed reads as inward-facing; anything else as misnested.
          CHECK((report.find(DefectKind::misnested_shell) != nullptr ||
                 report.find(DefectKind::inward_orientation) != nullptr));
        }
      }
    }
  }
}

TEST_CASE("an outward shell inside an outward shell is named as misnested", "[validate]") {
  const Mesh two_outward = test::merge({test::box({0, 0, 0}, {8, 8, 8}), test::box({2, 2, 2}, {4, 4, 4})});
  const ValidationReport report = validate_mesh(two_outward);
  REQUIRE(report.find(DefectKind::misnested_shell) != nullptr);
  CHECK(report.find(DefectKind::misnested_shell)->count == 1);
  CHECK(report.summary().find("misnested shells: 1 shell faces the same way") == 0);
  // Only the self-intersection-checked validation can tell.
  CHECK(validate_mesh(two_outward, {.check_self_intersections = false}).valid());
}

// --- The shared corpus -------------------------------------------------------

TEST_CASE("every valid corpus mesh validates clean", "[validate][corpus]") {
  for (const auto& path : shatter::test::valid_meshes()) {
    INFO(path.filename().string());
    const Mesh mesh = read_mesh(path);
    const ValidationReport report = validate_mesh(mesh);
    CHECK(report.summary() == "valid");
    CHECK(report.valid());
    CHECK(report.self_intersections_checked);
  }
}

TEST_CASE("every bad corpus mesh reports the defect its name implies", "[validate][corpus]") {
  // Each file's complete list of defects, with the count and first element of the
  // defect that names it.
  struct Expected {
    std::vector<DefectKind> kinds;
    DefectKind main;
    std::size_t count;
    std::string first;
  };
  // First elements name indices of the mesh as read (the reader renumbers vertices
  // in order of first use), so corpus checks pin counts and kinds of element only.
  const std::map<std::string, Expected> expected = {
      // One square face (two triangles) missing: its four edges are open.
      {"cube-ouvert.off", {{DefectKind::boundary_edge}, DefectKind::boundary_edge, 4, "edge ("}},
      // Of its six edges, (0,1), (1,2), (0,3) and (2,3) are traversed the same way twice.
      {"tet-shuffled.off",
       {{DefectKind::inconsistent_orientation}, DefectKind::inconsistent_orientation, 4, "edge ("}},
      {"tetrahedron.off", {{DefectKind::inward_orientation}, DefectKind::inward_orientation, 1, "whole mesh"}},
      // A flat (z = 0) open fan in which four triangles have collinear corners; the
      // first, triangle 2, is (2,0), (4,0), (1,0).
      {"degtri_sliding.off",
       {{DefectKind::zero_area_triangle, DefectKind::boundary_edge}, DefectKind::zero_area_triangle, 4,
        "triangle 2"}},
      // Holes, and 65 positions written twice in the file: welded, some of them
      // pinch the surface into non-manifold vertices.
      {"elephant-with-holes.off",
       {{DefectKind::boundary_edge, DefectKind::non_manifold_vertex}, DefectKind::boundary_edge, 1353, "edge ("}},
      // A closed tetrahedron plus a stray triangle: the stray triangle's three edges
      // are open, so the mesh is refused as open before any crossing is looked for.
      {"tetra_intersected_by_triangle.off",
       {{DefectKind::boundary_edge}, DefectKind::boundary_edge, 3, "edge ("}},
      // A box of side 8 holding one of side 2, both facing out: the inner is misnested.
      {"box-in-box-both-outward.off",
       {{DefectKind::misnested_shell}, DefectKind::misnested_shell, 1, "shell of triangle 12"}},
  };
  const auto paths = shatter::test::bad_meshes();
  CHECK(paths.size() == expected.size());
  for (const auto& path : paths) {
    const std::string name = path.filename().string();
    INFO(name);
    const auto it = expected.find(name);
    REQUIRE(it != expected.end());
    const ValidationReport report = validate_mesh(read_mesh(path));
    INFO(report.summary());
    CHECK_FALSE(report.valid());
    CHECK(kinds(report) == it->second.kinds);
    const Defect* main = report.find(it->second.main);
    REQUIRE(main != nullptr);
    CHECK(main->count == it->second.count);
    CHECK(main->first.rfind(it->second.first, 0) == 0);
  }
}

TEST_CASE("self-intersecting corpus meshes report the known pair counts", "[validate][corpus]") {
  const std::map<std::string, std::size_t> expected_pairs = {{"cow.off", 101}, {"camel.off", 20}, {"elk.off", 7}};
  const auto paths = shatter::test::self_intersecting_meshes();
  CHECK(paths.size() == expected_pairs.size());
  for (const auto& path : paths) {
    const std::string name = path.filename().string();
    INFO(name);
    REQUIRE(expected_pairs.count(name) == 1);
    const ValidationReport report = validate_mesh(read_mesh(path));
    INFO(report.summary());
    CHECK(report.self_intersections_checked);
    // cow.off writes one position twice (vertices 44 and 2903); welded, the surface
    // pinches there. CGAL's 101 pairs count the unwelded file, in which the two
    // fans merely touch: the fan-split test reproduces exactly that.
    const std::vector<DefectKind> expected_kinds =
        name == "cow.off" ? std::vector{DefectKind::non_manifold_vertex, DefectKind::self_intersection}
                          : std::vector{DefectKind::self_intersection};
    REQUIRE(kinds(report) == expected_kinds);
    const Defect* crossings = report.find(DefectKind::self_intersection);
    REQUIRE(crossings != nullptr);
    CHECK(crossings->count == expected_pairs.at(name));
    CHECK(crossings->first.rfind("triangles ", 0) == 0);
    CHECK(report.summary().find("self-intersecting") != std::string::npos);
    // Deterministic: the same mesh gives the same first pair.
    CHECK(validate_mesh(read_mesh(path)).find(DefectKind::self_intersection)->first == crossings->first);
  }
}

// --- the plane kernel's certificates -------------------------------------------------

namespace {
bool same_defects(const ValidationReport& a, const ValidationReport& b);
}  // namespace

TEST_CASE("validate_mesh_against finds what validate_mesh finds, on its own and against a trusted mesh",
          "[validate][certify]") {
  std::vector<std::pair<std::string, Mesh>> meshes;
  for (auto& named : test::generated_meshes()) meshes.emplace_back(named.name, std::move(named.mesh));
  for (const auto& path : test::valid_meshes()) meshes.emplace_back(path.filename().string(), read_mesh(path));
  for (const auto& path : test::self_intersecting_meshes()) {
    if (path.filename() != "cow.off") meshes.emplace_back(path.filename().string(), read_mesh(path));
  }
  meshes.emplace_back("pierced tetrahedron", pierced_tetrahedron());
  for (const auto& [name, mesh] : meshes) {
    INFO(name);
    const ValidationReport reference = validate_mesh(mesh);
    const ValidationReport alone = validate_mesh_against(mesh, nullptr);
    CHECK(kinds(alone) == kinds(reference));
    if (const Defect* d = reference.find(DefectKind::self_intersection)) {
      REQUIRE(alone.find(DefectKind::self_intersection) != nullptr);
      CHECK(alone.find(DefectKind::self_intersection)->count == d->count);
    }
    // Against itself only when valid: every pair is then trusted.
    if (reference.valid()) CHECK(validate_mesh_against(mesh, &mesh).valid());
  }
  // Trust never hides a new crossing: the pierced tetrahedron against its own
  // tetrahedron (the piercing triangles are new).
  const Mesh pierced = pierced_tetrahedron();
  Mesh tetrahedron_only = pierced;
  tetrahedron_only.triangles.resize(4);
  tetrahedron_only.surfaces.resize(4);
  const ValidationReport against = validate_mesh_against(pierced, &tetrahedron_only);
  REQUIRE(against.find(DefectKind::self_intersection) != nullptr);
  CHECK(against.find(DefectKind::self_intersection)->count == 3);
  const ValidationReport indexed = validate_mesh_against(pierced, TrustedTriangles(tetrahedron_only));
  REQUIRE(indexed.find(DefectKind::self_intersection) != nullptr);
  CHECK(indexed.find(DefectKind::self_intersection)->count == 3);
}

TEST_CASE("TrustedTriangles finds a mesh's triangles in any rotation, not reversed, and serves validate_mesh_against alike",
          "[validate][certify]") {
  std::vector<std::pair<std::string, Mesh>> meshes;
  for (auto& named : test::generated_meshes()) meshes.emplace_back(named.name, std::move(named.mesh));
  for (const auto& path : test::valid_meshes()) {
    Mesh mesh = read_mesh(path);
    if (mesh.triangles.size() <= 20000) meshes.emplace_back(path.filename().string(), std::move(mesh));
  }
  std::mt19937_64 random(11);
  for (const auto& [name, mesh] : meshes) {
    INFO(name);
    const TrustedTriangles index(mesh);
    // Each triangle, rotated, is found; reversed, it is not (a valid mesh has no
    // triangle over the same corners turning the other way).
    std::size_t missing = 0, reversed_found = 0;
    for (Triangle t : mesh.triangles) {
      std::rotate(t.begin(), t.begin() + static_cast<std::ptrdiff_t>(random() % 3), t.end());
      missing += !index.contains(mesh, t);
      std::swap(t[1], t[2]);
      reversed_found += index.contains(mesh, t);
    }
    CHECK(missing == 0);
    if (validate_mesh(mesh).valid()) CHECK(reversed_found == 0);
    // Against a part of itself, and with a vertex moved (its triangles are new):
    // the same report as from the trusted mesh.
    Mesh half = mesh;
    half.triangles.resize(mesh.triangles.size() / 2);
    half.surfaces.resize(half.triangles.size());
    Mesh moved = mesh;
    const std::size_t v = random() % moved.positions.size();
    moved.positions[v] = moved.positions[v] * 0.5;
    for (const Mesh* checked : std::array<const Mesh*, 2>{&mesh, &moved}) {
      CHECK(same_defects(validate_mesh_against(*checked, TrustedTriangles(half)), validate_mesh_against(*checked, &half)));
      CHECK(same_defects(validate_mesh_against(*checked, TrustedTriangles(half)), validate_mesh(*checked)));
    }
  }
}

TEST_CASE("validate_mesh_against with exact vertices finds what validate_mesh finds whenever the all-exact triangles meet only as they share",
          "[validate][certify]") {
  // The flags' promise (validate.hpp): triangles with three flagged corners meet
  // only in what they share. Each draw moves one vertex of a valid mesh, often
  // through the surface, flags a random share of the vertices (the moved one or
  // not), and checks the promise by brute force on the all-flagged triangles
  // alone; where it holds, the report must be validate_mesh's, against the
  // original as the trusted mesh and against none. Every pair class the search
  // splits is counted where it intersects, so each path is shown to find some.
  std::vector<std::pair<std::string, Mesh>> meshes;
  for (auto& named : test::generated_meshes()) meshes.emplace_back(named.name, std::move(named.mesh));
  // Smaller under the sanitizers (the library's checks run about 12 times slower).
  const std::size_t largest = test::sized(6000, 2500);
  const int draws = static_cast<int>(test::sized(24, 8));
  for (const auto& path : test::valid_meshes()) {
    Mesh mesh = read_mesh(path);
    if (mesh.triangles.size() <= largest) meshes.emplace_back(path.filename().string(), std::move(mesh));
  }
  std::mt19937_64 random(23);
  std::size_t checked = 0, promise_broken = 0, intersecting = 0;
  std::size_t new_moved_pairs = 0, new_exact_against_trusted_moved = 0;
  for (const auto& [name, mesh] : meshes) {
    INFO(name);
    REQUIRE(validate_mesh(mesh).valid());
    Vec3 low = mesh.positions[0], high = mesh.positions[0];
    for (const Vec3& p : mesh.positions) {
      low = {std::min(low.x, p.x), std::min(low.y, p.y), std::min(low.z, p.z)};
      high = {std::max(high.x, p.x), std::max(high.y, p.y), std::max(high.z, p.z)};
    }
    const double size = std::sqrt(dot(high - low, high - low));
    const TrustedTriangles original(mesh);
    for (int draw = 0; draw < draws; ++draw) {
      INFO("draw " << draw);
      Mesh edited = mesh;
      const std::size_t v = random() % edited.positions.size();
      std::normal_distribution<double> normal;
      const Vec3 direction = normalized(Vec3{normal(random), normal(random), normal(random)});
      const double reach = size * std::ldexp(1.0, -static_cast<int>(random() % 8));  // size to size/128
      edited.positions[v] = edited.positions[v] + direction * reach;
      const double share = static_cast<double>(1 + random() % 9) / 10.0;  // of the other vertices flagged
      std::vector<std::uint8_t> exact(edited.positions.size(), 0);
      for (std::size_t w = 0; w < exact.size(); ++w) {
        exact[w] = std::uniform_real_distribution<double>(0, 1)(random) < share;
      }
      exact[v] = random() % 2;
      // The promise, by brute force: the all-flagged triangles among themselves.
      const auto all_flagged = [&](const Triangle& t) { return exact[t[0]] && exact[t[1]] && exact[t[2]]; };
      std::vector<Triangle> flagged;
      for (const Triangle& t : edited.triangles) {
        if (all_flagged(t)) flagged.push_back(t);
      }
      if (!self_intersecting_pairs(edited.positions, flagged).empty()) {
        ++promise_broken;
        continue;
      }
      ++checked;
      // The flags change no report: the same as without them, and validate_mesh's
      // validity (its very report when the only defects are crossings; another
      // defect ends validate_mesh_against before its search, flags or not).
      const ValidationReport reference = validate_mesh(edited);
      const ValidationReport unflagged = validate_mesh_against(edited, &mesh);
      const bool crossings_only = std::all_of(reference.defects.begin(), reference.defects.end(),
                                              [](const Defect& d) { return d.kind == DefectKind::self_intersection; });
      for (const ValidationReport& report :
           {validate_mesh_against(edited, &mesh, nullptr, exact), validate_mesh_against(edited, original, nullptr, exact),
            validate_mesh_against(edited, nullptr, nullptr, exact)}) {
        CHECK(same_defects(report, unflagged));
        CHECK(report.valid() == reference.valid());
        if (crossings_only) CHECK(same_defects(report, reference));
      }
      const std::vector<TrianglePair> pairs = self_intersecting_pairs(edited.positions, edited.triangles);
      if (pairs.empty()) continue;
      ++intersecting;
      for (const auto& [a, b] : pairs) {
        const Triangle &s = edited.triangles[a], &t = edited.triangles[b];
        const bool new_s = !original.contains(edited, s), new_t = !original.contains(edited, t);
        const bool moved_s = !all_flagged(s), moved_t = !all_flagged(t);
        if ((new_s && moved_s) || (new_t && moved_t)) {
          ++new_moved_pairs;
        } else if ((new_s && !moved_s && !new_t && moved_t) || (new_t && !moved_t && !new_s && moved_s)) {
          ++new_exact_against_trusted_moved;
        }
      }
    }
  }
  INFO("checked " << checked << ", promise broken " << promise_broken << ", intersecting " << intersecting);
  CHECK(checked >= 3 * promise_broken);
  CHECK(intersecting >= checked / 10);
  CHECK(new_moved_pairs >= test::sized(100, 30));
  CHECK(new_exact_against_trusted_moved >= test::sized(20, 5));
  // One flag per vertex, or none.
  const Mesh tetrahedron = corner_tetrahedron();
  const std::vector<std::uint8_t> short_flags(3, 1);
  CHECK_THROWS_AS(validate_mesh_against(tetrahedron, &tetrahedron, nullptr, short_flags), std::invalid_argument);
}

TEST_CASE("TrustedTriangles on grid coordinates finds exactly the triangles a sorted set of keys holds",
          "[validate][certify]") {
  // Coordinates on a coarse grid (small integers and halves, +0 and -0) share
  // their low bits, where a hash table takes its slots: every lookup must still
  // answer as a brute-force set of the rotated corner triples does.
  std::mt19937_64 random(20261206);
  for (int round = 0; round < 6; ++round) {
    INFO("round " << round);
    const int side = 8 + round * 6;
    Mesh grid;
    const auto coordinate = [&](int i) { return i == 0 && round % 2 == 1 ? -0.0 : 0.5 * i; };
    for (int i = 0; i <= side; ++i) {
      for (int j = 0; j <= side; ++j) grid.positions.push_back({coordinate(i), coordinate(j), double((i * j) % 3)});
    }
    const auto at = [&](int i, int j) { return static_cast<VertexIndex>(i * (side + 1) + j); };
    for (int i = 0; i < side; ++i) {
      for (int j = 0; j < side; ++j) {
        grid.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
        grid.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
      }
    }
    // Every other triangle trusted; the same triangle twice is held once.
    Mesh trusted = grid;
    trusted.triangles.clear();
    for (std::size_t t = 0; t < grid.triangles.size(); t += 2) trusted.triangles.push_back(grid.triangles[t]);
    trusted.triangles.push_back(trusted.triangles.front());
    const auto key = [](const Mesh& mesh, Triangle t) {
      std::array<std::array<double, 3>, 3> corners;
      for (int c = 0; c < 3; ++c) {
        const Vec3 p = mesh.positions[t[c]];
        corners[c] = {p.x + 0.0, p.y + 0.0, p.z + 0.0};  // -0 + 0 is +0: the index's equality
      }
      std::rotate(corners.begin(), std::min_element(corners.begin(), corners.end()), corners.end());
      return corners;
    };
    std::set<std::array<std::array<double, 3>, 3>> reference;
    for (const Triangle& t : trusted.triangles) reference.insert(key(trusted, t));
    const TrustedTrianglesOnce once(trusted);
    // Asked from several threads at once, the index is made once and answers alike.
    std::vector<std::size_t> mismatches(4, 0);
    std::vector<std::thread> askers;
    for (std::size_t a = 0; a < mismatches.size(); ++a) {
      askers.emplace_back([&, a] {
        std::mt19937_64 mine(a);
        for (int k = 0; k < 2000; ++k) {
          Triangle t{static_cast<VertexIndex>(mine() % grid.positions.size()),
                     static_cast<VertexIndex>(mine() % grid.positions.size()),
                     static_cast<VertexIndex>(mine() % grid.positions.size())};
          if (k % 2 == 0) t = grid.triangles[mine() % grid.triangles.size()];
          std::rotate(t.begin(), t.begin() + static_cast<std::ptrdiff_t>(mine() % 3), t.end());
          mismatches[a] += once.get().contains(grid, t) != reference.contains(key(grid, t));
        }
      });
    }
    for (std::thread& asker : askers) asker.join();
    for (const std::size_t m : mismatches) CHECK(m == 0);
    std::size_t found = 0;
    for (const Triangle& t : grid.triangles) found += once.get().contains(grid, t);
    CHECK(found == grid.triangles.size() / 2);
    CHECK(&once.get() == &once.get());
    CHECK(&once.mesh() == &trusted);
  }
  CHECK_FALSE(TrustedTriangles().contains(Mesh{}, Triangle{0, 0, 0}));
}

namespace {

// The two reports name the same defects with the same counts and first elements.
bool same_defects(const ValidationReport& a, const ValidationReport& b) {
  if (a.defects.size() != b.defects.size()) return false;
  for (std::size_t k = 0; k < a.defects.size(); ++k) {
    const Defect& x = a.defects[k];
    const Defect& y = b.defects[k];
    if (x.kind != y.kind || x.count != y.count || x.first != y.first) return false;
  }
  return true;
}

}  // namespace

TEST_CASE("validate_mesh_of_parts reports what validate_mesh reports on meshes joined from valid parts",
          "[validate][certify]") {
  // Parts placed anywhere (apart, touching, overlapping, nested, coincident),
  // joined as they are (merge) and given as the parts: the pairs within a part
  // are skipped, and the report must still be validate_mesh's, counts and first
  // pairs included.
  const std::vector<Mesh> shapes{test::grid_box({0, 0, 0}, {1, 1, 1}, 3), test::ellipsoid({0.5, 0.5, 0.5}, {0.6, 0.4, 0.5}, 12, 7),
                                 test::torus(0.6, 0.2, 12, 8), test::box({0, 0, 0}, {1, 0.5, 0.25})};
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> offset(-1.2, 1.2);
  std::size_t refused = 0, accepted = 0;
  for (int trial = 0; trial < 120; ++trial) {
    const Mesh& first = shapes[trial % shapes.size()];
    const Mesh& second = shapes[(trial / shapes.size()) % shapes.size()];
    Vec3 shift{offset(random), offset(random), offset(random)};
    if (trial % 10 == 0) shift = {0, 0, 0};        // coincident (or nested) copies
    if (trial % 10 == 1) shift = {1, 0, 0};        // touching along a face or less
    if (trial % 10 == 2) shift = {10, 0, 0};       // apart
    const double scale = trial % 10 == 3 ? 0.25 : 1.0;  // often nested
    const Mesh moved = test::transformed(second, scale, shift);
    const Mesh joined = test::merge({first, moved});
    const std::array<const Mesh*, 2> parts{&first, &moved};
    INFO("trial " << trial);
    const ValidationReport full = validate_mesh(joined);
    const ValidationReport fast = validate_mesh_of_parts(joined, parts);
    CHECK(same_defects(fast, full));
    CHECK(fast.valid() == full.valid());
    (full.valid() ? accepted : refused) += 1;
  }
  // Both outcomes occur, so the comparison can fail either way.
  CHECK(accepted > 10);
  CHECK(refused > 10);
}

TEST_CASE("validate_mesh_of_parts refuses parts that cross, touch or repeat each other", "[validate][certify]") {
  const Mesh cube = test::grid_box({0, 0, 0}, {1, 1, 1}, 2);
  // Crossing: every triangle of the mesh is one of a part's, so only the pairs
  // across the parts are tested, and they intersect.
  const Mesh crossing = test::transformed(cube, 1, {0.5, 0.25, 0.125});
  const std::array<const Mesh*, 2> crossing_parts{&cube, &crossing};
  const ValidationReport crossed = validate_mesh_of_parts(test::merge({cube, crossing}), crossing_parts);
  REQUIRE(crossed.find(DefectKind::self_intersection) != nullptr);
  CHECK(crossed.find(DefectKind::self_intersection)->count ==
        validate_mesh(test::merge({cube, crossing})).find(DefectKind::self_intersection)->count);
  // A coincident copy over other vertices: each triangle is one of the first
  // part's (the same corner positions), yet the copies meet everywhere. Only
  // the shared positions show it: their triangles are tested as new.
  const std::array<const Mesh*, 1> one_part{&cube};
  const ValidationReport doubled = validate_mesh_of_parts(test::merge({cube, cube}), one_part);
  REQUIRE(doubled.find(DefectKind::self_intersection) != nullptr);
  CHECK(same_defects(doubled, validate_mesh(test::merge({cube, cube}))));
  // Touching along a face, vertices at one position but not one vertex.
  const Mesh beside = test::transformed(cube, 1, {1, 0, 0});
  const std::array<const Mesh*, 2> touching_parts{&cube, &beside};
  CHECK_FALSE(validate_mesh_of_parts(test::merge({cube, beside}), touching_parts).valid());
  // New triangles are tested against everything: the pierced tetrahedron given
  // only its tetrahedron as a part.
  const Mesh pierced = pierced_tetrahedron();
  Mesh tetrahedron_only = pierced;
  tetrahedron_only.triangles.resize(4);
  tetrahedron_only.surfaces.resize(4);
  const std::array<const Mesh*, 2> with_null{nullptr, &tetrahedron_only};
  CHECK(same_defects(validate_mesh_of_parts(pierced, with_null), validate_mesh(pierced)));
  // Parts that are valid and apart: accepted, as validate_mesh accepts them.
  const Mesh far = test::transformed(cube, 1, {3, 0, 0});
  const std::array<const Mesh*, 2> apart{&cube, &far};
  CHECK(validate_mesh_of_parts(test::merge({cube, far}), apart).valid());
}

TEST_CASE("validate_mesh_of_parts given regions and planes, or a sound topology, reports what it reports without them",
          "[validate][certify]") {
  // The planes only decide which pairs go untested, and only pairs no two
  // triangles that meet can be: so whatever the regions and planes (separating,
  // through the contact, through the crossing, random, missing), the report is
  // the one without them, which is validate_mesh's. The shapes touch and cross
  // each other often, so a filter that dropped a meeting pair would show.
  const std::vector<Mesh> shapes{test::grid_box({0, 0, 0}, {1, 1, 1}, 3), test::ellipsoid({0.5, 0.5, 0.5}, {0.6, 0.4, 0.5}, 12, 7),
                                 test::torus(0.6, 0.2, 12, 8), test::box({0, 0, 0}, {1, 0.5, 0.25})};
  std::mt19937_64 random(11);
  std::uniform_real_distribution<double> offset(-1.2, 1.2), unit(-1, 1);
  std::size_t refused = 0, accepted = 0;
  for (int trial = 0; trial < 160; ++trial) {
    const Mesh& first = shapes[trial % shapes.size()];
    const Mesh& second = shapes[(trial / shapes.size()) % shapes.size()];
    Vec3 shift{offset(random), offset(random), offset(random)};
    if (trial % 8 == 0) shift = {0, 0, 0};   // coincident or nested
    if (trial % 8 == 1) shift = {1, 0, 0};   // touching at x = 1 (boxes) or crossing
    if (trial % 8 == 2) shift = {1.25, 0, 0};
    const Mesh moved = test::transformed(second, 1.0, shift);
    const Mesh joined = test::merge({first, moved});
    const std::array<const Mesh*, 2> parts{&first, &moved};
    // Regions: each part's triangles by the octant of their first corner
    // around the part's own centre (so a part has up to 8 regions), numbered
    // apart per part; some trials leave the second part without regions.
    const auto octants = [](const Mesh& mesh, std::uint32_t base) {
      Vec3 centre;
      for (const Vec3& p : mesh.positions) centre = centre + p;
      centre = centre * (1.0 / static_cast<double>(mesh.positions.size()));
      std::vector<std::uint32_t> region;
      for (const Triangle& t : mesh.triangles) {
        const Vec3 p = mesh.positions[t[0]];
        region.push_back(base + (p.x > centre.x ? 1u : 0u) + (p.y > centre.y ? 2u : 0u) + (p.z > centre.z ? 4u : 0u));
      }
      return region;
    };
    const std::vector<std::uint32_t> first_regions = octants(first, 0), second_regions = octants(moved, 8);
    std::vector<std::span<const std::uint32_t>> region_of{first_regions, second_regions};
    if (trial % 5 == 4) region_of[1] = {};
    // Planes: the one between the parts' centres when they are apart (x = 1 for
    // the touching boxes), through the contact or the crossing otherwise, a
    // random one, or none, by trial and region pair.
    const int kind = trial % 4;
    const Plane random_plane{{unit(random), unit(random), unit(random)}, unit(random)};
    PartRegions regions{region_of, [&](std::uint32_t a, std::uint32_t b) -> std::optional<Plane> {
                          CHECK((a < 8) != (b < 8));  // asked only across parts
                          if (kind == 3 && (a + b) % 3 == 0) return std::nullopt;
                          if (kind == 2) return random_plane;
                          const double at = kind == 1 ? 1.0 : 0.5 * (1.0 + shift.x);
                          return Plane{{a < 8 ? 1.0 : -1.0, 0, 0}, a < 8 ? -at : at};
                        }};
    INFO("trial " << trial);
    const ValidationReport full = validate_mesh(joined);
    const ValidationReport without = validate_mesh_of_parts(joined, parts);
    const ValidationReport with = validate_mesh_of_parts(joined, parts, &regions);
    CHECK(same_defects(with, without));
    CHECK(same_defects(with, full));
    // Two closed manifolds over separate vertices are one by index: the topology
    // given as sound changes nothing.
    CHECK(same_defects(validate_mesh_of_parts(joined, parts, &regions, true), full));
    // Where each triangle came from: right, crossed over between the parts, or
    // wild (none, or any part and index, in range or not). Checked against the
    // named part's triangle, never trusted: the same report.
    std::vector<std::uint64_t> right, crossed, wild;
    for (std::size_t t = 0; t < joined.triangles.size(); ++t) {
      const bool in_first = t < first.triangles.size();
      const std::uint64_t index = in_first ? t : t - first.triangles.size();
      right.push_back((in_first ? 0 : std::uint64_t{1} << 32) | index);
      crossed.push_back((in_first ? std::uint64_t{1} << 32 : 0) | index);
      wild.push_back(t % 3 == 0 ? ~std::uint64_t{0} : std::uint64_t{t % 5} << 32 | (t * 7919 % (joined.triangles.size() + 3)));
    }
    for (const std::vector<std::uint64_t>* origins : {&right, &crossed, &wild}) {
      CHECK(same_defects(validate_mesh_of_parts(joined, parts, &regions, false, *origins), full));
      CHECK(same_defects(validate_mesh_of_parts(joined, parts, nullptr, true, *origins), full));
    }
    CHECK(with.valid() == full.valid());
    (full.valid() ? accepted : refused) += 1;
  }
  CHECK(accepted > 10);
  CHECK(refused > 10);
  // The cases above by name: crossing cubes split by a plane through the
  // crossing, cubes touching along x = 1 with the plane there, and coincident
  // copies (their shared positions make their triangles new) all refused.
  const Mesh cube = test::grid_box({0, 0, 0}, {1, 1, 1}, 2);
  for (const Vec3& shift : {Vec3{0.5, 0.25, 0.125}, Vec3{1, 0, 0}, Vec3{0, 0, 0}}) {
    const Mesh other = test::transformed(cube, 1, shift);
    const std::vector<std::uint32_t> zeros(cube.triangles.size(), 0), ones(other.triangles.size(), 1);
    const std::array<std::span<const std::uint32_t>, 2> region_of{zeros, ones};
    const PartRegions split{region_of, [&](std::uint32_t, std::uint32_t) -> std::optional<Plane> {
                              return Plane{{1, 0, 0}, -(0.5 + 0.5 * shift.x)};
                            }};
    const std::array<const Mesh*, 2> parts{&cube, &other};
    const Mesh joined = test::merge({cube, other});
    INFO("shift " << shift.x);
    const ValidationReport with = validate_mesh_of_parts(joined, parts, &split);
    CHECK_FALSE(with.valid());
    CHECK(same_defects(with, validate_mesh(joined)));
  }
}

TEST_CASE("the star-shaped certificate accepts convex solids around an inner point and nothing invalid",
          "[validate][certify]") {
  const Mesh box = test::box({0, 0, 0}, {2, 3, 4});
  CHECK(certify_star_shaped(box, {1, 1.5, 2}));
  CHECK_FALSE(certify_star_shaped(box, {5, 1.5, 2}));     // outside: triangles face it
  CHECK_FALSE(certify_star_shaped(box, {0, 1.5, 2}));     // on a face: orientation zero
  const Mesh sphere = test::ellipsoid({0, 0, 0}, {1, 2, 3}, 16, 12);
  CHECK(certify_star_shaped(sphere, {0.1, -0.2, 0.3}));
  const Mesh torus = test::torus(3, 1, 16, 8);
  CHECK_FALSE(certify_star_shaped(torus, {0, 0, 0}));
  CHECK_FALSE(certify_star_shaped(torus, {3, 0, 0}));
  // A surface wrapping its centre twice: a bipyramid whose equator goes around
  // twice (radius 1, then 1.5), so every triangle faces away from the centre but
  // the rings around the poles wind twice. It intersects itself; the facing test
  // alone would pass it, the winding test must not.
  {
    const int m = 7;
    std::vector<Vec3> positions{{0, 0, 1}, {0, 0, -1}};
    std::vector<Triangle> triangles;
    for (int k = 0; k < 2 * m; ++k) {
      const double angle = 4 * M_PI * k / (2 * m), radius = k < m ? 1.0 : 1.5;
      positions.push_back({radius * std::cos(angle), radius * std::sin(angle), 0});
    }
    for (int k = 0; k < 2 * m; ++k) {
      const auto a = static_cast<VertexIndex>(2 + k), b = static_cast<VertexIndex>(2 + (k + 1) % (2 * m));
      triangles.push_back({0, a, b});
      triangles.push_back({1, b, a});
    }
    const Mesh double_cover = test::mesh_from(positions, triangles);
    // Every triangle faces away from the centre (so only the winding test can
    // reject it): the centre lies behind each, exactly.
    for (const Triangle& t : double_cover.triangles) {
      const Vec3 a = positions[t[0]], b = positions[t[1]], c = positions[t[2]];
      CHECK(dot(cross(b - a, c - a), Vec3{} - a) < 0);
    }
    CHECK_FALSE(validate_mesh(double_cover).valid());
    CHECK_FALSE(certify_star_shaped(double_cover, {0, 0, 0}));
  }
  Mesh inward = corner_tetrahedron();
  reverse_all(inward);
  CHECK_FALSE(certify_star_shaped(inward, {0.1, 0.1, 0.1}));
  // Anything the certificate accepts, validate_mesh accepts: every generated
  // convex mesh around its vertex average.
  for (const auto& named : test::generated_meshes()) {
    Vec3 centre;
    for (const Vec3& p : named.mesh.positions) centre = centre + p;
    centre = centre * (1.0 / static_cast<double>(named.mesh.positions.size()));
    INFO(named.name);
    if (certify_star_shaped(named.mesh, centre)) CHECK(validate_mesh(named.mesh).valid());
  }
}

namespace {

// An octahedron with vertices at +-1 on the axes, its first triangle (e_x, e_y,
// e_z), faces outward.
Mesh octahedron() {
  const std::vector<Vec3> positions{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {-1, 0, 0}, {0, -1, 0}, {0, 0, -1}};
  std::vector<Triangle> triangles;
  for (const VertexIndex x : {0u, 3u}) {
    for (const VertexIndex y : {1u, 4u}) {
      for (const VertexIndex z : {2u, 5u}) {
        // Outward when the signs of the three axes are even (counted by the negatives).
        const int negatives = (x == 3) + (y == 4) + (z == 5);
        triangles.push_back(negatives % 2 == 0 ? Triangle{x, y, z} : Triangle{x, z, y});
      }
    }
  }
  return test::mesh_from(positions, triangles);
}

// The bipyramid whose equator goes around `turns` times (m vertices a turn,
// radius growing from 1 by `step` a vertex): every triangle faces away from
// the origin, and the rings around the poles wind `turns` times.
Mesh wrapped_bipyramid(int m, int turns, double step) {
  std::vector<Vec3> positions{{0, 0, 1}, {0, 0, -1}};
  std::vector<Triangle> triangles;
  const int n = m * turns;
  for (int k = 0; k < n; ++k) {
    const double angle = 2 * M_PI * turns * k / n, radius = 1 + step * k;
    positions.push_back({radius * std::cos(angle), radius * std::sin(angle), 0});
  }
  for (int k = 0; k < n; ++k) {
    const auto a = static_cast<VertexIndex>(2 + k), b = static_cast<VertexIndex>(2 + (k + 1) % n);
    triangles.push_back({0, a, b});
    triangles.push_back({1, b, a});
  }
  return test::mesh_from(positions, triangles);
}

}  // namespace

TEST_CASE("one ray's count decides the covering as the walk around every vertex does", "[validate][certify][property]") {
  // covered_once_along_a_ray against winds_once_around with connectivity, on
  // every surface both apply to (sound topology, every triangle facing away):
  // convex and star-shaped solids around many centres, surfaces wrapping their
  // centre two or three times, two shells around one centre. Where the ray
  // decides, it must agree; where it does not, covers_once falls back to the walk.
  std::vector<std::pair<std::string, Mesh>> surfaces;
  for (const auto& named : test::generated_meshes()) surfaces.emplace_back(named.name, named.mesh);
  surfaces.emplace_back("ellipsoid", test::ellipsoid({0.2, -0.1, 0.3}, {1, 2, 3}, 16, 12));
  surfaces.emplace_back("octahedron", octahedron());
  for (const int turns : {1, 2, 3}) {
    for (const int m : {3, 5, 8}) {
      surfaces.emplace_back("bipyramid " + std::to_string(turns) + "x" + std::to_string(m),
                            wrapped_bipyramid(m, turns, turns == 1 ? 0.0 : 0.5 / m));
    }
  }
  surfaces.emplace_back("two shells", test::merge({test::ellipsoid({0, 0, 0}, {1, 1, 1}, 10, 8),
                                                   test::ellipsoid({0, 0, 0}, {3, 2.5, 2}, 12, 9)}));
  // Star-shaped but far from convex: an ellipsoid's vertices moved along their rays.
  std::mt19937_64 random(71);
  std::uniform_real_distribution<double> unit(0, 1);
  for (int draw = 0; draw < 40; ++draw) {
    Mesh bumpy = test::ellipsoid({0, 0, 0}, {1, 1.5, 2}, 6 + draw % 10, 5 + draw % 7);
    for (Vec3& p : bumpy.positions) p = p * (0.6 + 0.8 * unit(random));
    surfaces.emplace_back("bumpy " + std::to_string(draw), bumpy);
  }
  std::size_t decided = 0, undecided = 0, accepted = 0, refused = 0;
  for (const auto& [name, mesh] : surfaces) {
    INFO(name);
    if (!is_closed_oriented_manifold(mesh)) continue;
    Vec3 average;
    for (const Vec3& p : mesh.positions) average = average + p;
    average = average * (1.0 / static_cast<double>(mesh.positions.size()));
    std::vector<Vec3> centres{average, {0, 0, 0}};
    for (int k = 0; k < 20; ++k) centres.push_back(average + Vec3{unit(random) - 0.5, unit(random) - 0.5, unit(random) - 0.5});
    for (const Vec3& centre : centres) {
      INFO("centre " << centre.x << " " << centre.y << " " << centre.z);
      if (!kernel_detail::faces_away_from(mesh, centre)) continue;
      const bool walked = kernel_detail::winds_once_around(mesh, centre) && connected_surface(mesh);
      const std::optional<bool> counted = kernel_detail::covered_once_along_a_ray(mesh, centre);
      if (counted) {
        ++decided;
        CHECK(*counted == walked);
        (*counted ? accepted : refused) += 1;
      } else {
        ++undecided;
      }
      if (connected_surface(mesh)) CHECK(kernel_detail::covers_once(mesh, centre) == walked);
      if (walked) CHECK(validate_mesh(mesh).valid());
    }
  }
  // Both answers are met many times; a ray along an edge's image is rare.
  CHECK(accepted > 100);
  CHECK(refused >= 10);
  CHECK(undecided * 20 < decided);

  // A ray along a vertex's image decides nothing: the octahedron's first
  // triangle's centroid, (1/3, 1/3, 1/3) in doubles, points from the origin at
  // the corner (2, 2, 2) of a box around it. The walk then decides: it winds
  // once around every vertex of both shells (the connectivity test, which the
  // certificates run first, is what refuses two shells).
  const Mesh nested = test::merge({octahedron(), test::box({-2, -2, -2}, {2, 2, 2})});
  REQUIRE(is_closed_oriented_manifold(nested));
  REQUIRE(kernel_detail::faces_away_from(nested, {0, 0, 0}));
  CHECK_FALSE(kernel_detail::covered_once_along_a_ray(nested, {0, 0, 0}).has_value());
  CHECK(kernel_detail::covers_once(nested, {0, 0, 0}) == kernel_detail::winds_once_around(nested, {0, 0, 0}));
  CHECK_FALSE(connected_surface(nested));
  // Moved off that corner, the same shells are counted twice.
  const Mesh shifted = test::merge({octahedron(), test::box({-2, -2.5, -2}, {2.5, 2.25, 3})});
  REQUIRE(kernel_detail::faces_away_from(shifted, {0, 0, 0}));
  CHECK(kernel_detail::covered_once_along_a_ray(shifted, {0, 0, 0}) == std::optional<bool>(false));
}

// --- the fast topology path against an independent count ------------------------
// validate_mesh first checks topology on flat arrays and runs the detailed,
// defect-naming checks only when that fails. So a bug in the fast path would pass
// a broken mesh silently. Random edits of closed meshes, each judged by a plain
// count written here (a map of directed edges, the fans at each vertex), must be
// reported defective exactly when the count says so.

namespace {

// Topologically sound by a plain count: indices in range and distinct per
// triangle, every vertex used, every directed edge once with its reverse once,
// and each vertex's triangles one edge-connected fan.
bool sound_by_count(const Mesh& mesh) {
  const std::size_t n = mesh.positions.size();
  std::map<std::pair<VertexIndex, VertexIndex>, int> directed;
  std::vector<std::vector<std::size_t>> triangles_at(n);
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& tri = mesh.triangles[t];
    for (const VertexIndex v : tri) {
      if (v >= n) return false;
    }
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) return false;
    for (int c = 0; c < 3; ++c) {
      ++directed[{tri[c], tri[(c + 1) % 3]}];
      triangles_at[tri[c]].push_back(t);
    }
  }
  for (const auto& [edge, count] : directed) {
    const auto reverse = directed.find({edge.second, edge.first});
    if (count != 1 || reverse == directed.end() || reverse->second != 1) return false;
  }
  for (VertexIndex v = 0; v < n; ++v) {
    const std::vector<std::size_t>& around = triangles_at[v];
    if (around.empty()) return false;
    // Flood the fan from the first triangle across edges (v, w).
    std::vector<bool> reached(around.size(), false);
    std::vector<std::size_t> stack{0};
    reached[0] = true;
    while (!stack.empty()) {
      const Triangle& tri = mesh.triangles[around[stack.back()]];
      stack.pop_back();
      for (std::size_t k = 0; k < around.size(); ++k) {
        if (reached[k]) continue;
        const Triangle& other = mesh.triangles[around[k]];
        std::ptrdiff_t shared = 0;
        for (const VertexIndex a : tri) shared += std::count(other.begin(), other.end(), a);
        if (shared >= 2) reached[k] = true, stack.push_back(k);
      }
    }
    if (std::count(reached.begin(), reached.end(), false) > 0) return false;
  }
  return true;
}

bool reports_topology_defect(const ValidationReport& report) {
  return std::any_of(report.defects.begin(), report.defects.end(), [](const Defect& d) {
    return d.kind != DefectKind::inward_orientation && d.kind != DefectKind::self_intersection &&
           d.kind != DefectKind::nonfinite_coordinate;
  });
}

}  // namespace

TEST_CASE("validate_mesh finds every topological edit an independent count finds, and no other", "[validate]") {
  // Corners in general position (no three collinear), so a zero-area report can
  // only come from a repeated index.
  const std::vector<Mesh> bases = {
      test::ellipsoid({0.1, 0.2, 0.3}, {1.0, 0.8, 0.6}, 9, 7), test::torus(1.0, 0.35, 10, 7),
      test::merge({test::ellipsoid({0, 0, 0}, {1, 1, 1}, 6, 5), test::ellipsoid({3, 0.1, 0.2}, {0.7, 1, 0.9}, 5, 4)})};
  std::mt19937_64 random(20261203);
  std::size_t sound = 0, broken = 0;
  for (const Mesh& base : bases) {
    REQUIRE(validate_mesh(base).valid());
    for (int trial = 0; trial < 400; ++trial) {
      Mesh mesh = base;
      const auto pick = [&](std::size_t n) { return std::uniform_int_distribution<std::size_t>(0, n - 1)(random); };
      const int edits = 1 + static_cast<int>(pick(2));
      std::string what;
      for (int e = 0; e < edits; ++e) {
        const std::size_t t = pick(mesh.triangles.size());
        switch (pick(9)) {
          case 0: std::swap(mesh.triangles[t][1], mesh.triangles[t][2]), what += " flip"; break;
          case 1: mesh.triangles.erase(mesh.triangles.begin() + static_cast<std::ptrdiff_t>(t)), what += " delete"; break;
          case 2: mesh.triangles.push_back(mesh.triangles[t]), what += " duplicate"; break;
          case 3: mesh.triangles[t][pick(3)] = static_cast<VertexIndex>(pick(mesh.positions.size())), what += " redirect"; break;
          case 4: {  // weld vertex w into v, then fill w's slot with the last vertex
            const auto v = static_cast<VertexIndex>(pick(mesh.positions.size()));
            const auto w = static_cast<VertexIndex>(pick(mesh.positions.size()));
            if (v == w) break;
            const auto last = static_cast<VertexIndex>(mesh.positions.size() - 1);
            for (Triangle& tri : mesh.triangles) {
              for (VertexIndex& x : tri) x = x == w ? v : x;
            }
            mesh.positions[w] = mesh.positions[last];
            for (Triangle& tri : mesh.triangles) {
              for (VertexIndex& x : tri) x = x == last ? w : x;
            }
            mesh.positions.pop_back();
            what += " weld";
            break;
          }
          case 5: mesh.positions.push_back({9, 9, 9}), what += " unused"; break;
          case 6: {  // a second copy of the whole mesh touching it at one vertex
            const Mesh copy = test::transformed(base, 1.0, {5, 0, 0});
            const auto offset = static_cast<VertexIndex>(mesh.positions.size());
            const auto shared = static_cast<VertexIndex>(pick(base.positions.size()));
            mesh.positions.insert(mesh.positions.end(), copy.positions.begin(), copy.positions.end());
            for (Triangle tri : copy.triangles) {
              for (VertexIndex& x : tri) x = x == shared ? shared : x + offset;
              mesh.triangles.push_back(tri);
            }
            mesh.surfaces.resize(mesh.triangles.size(), 0);
            what += " pinch";
            break;
          }
          case 7: {  // renumber vertices, rotate corners, reorder triangles: still sound
            std::vector<VertexIndex> order(mesh.positions.size());
            std::iota(order.begin(), order.end(), VertexIndex{0});
            std::shuffle(order.begin(), order.end(), random);
            std::vector<Vec3> positions(mesh.positions.size());
            for (std::size_t v = 0; v < order.size(); ++v) positions[order[v]] = mesh.positions[v];
            mesh.positions = positions;
            for (Triangle& tri : mesh.triangles) {
              for (VertexIndex& x : tri) x = x < order.size() ? order[x] : x;
              std::rotate(tri.begin(), tri.begin() + static_cast<std::ptrdiff_t>(pick(3)), tri.end());
            }
            std::shuffle(mesh.triangles.begin(), mesh.triangles.end(), random);
            what += " renumber";
            break;
          }
          default: {  // an index past the end
            mesh.triangles[t][pick(3)] = static_cast<VertexIndex>(mesh.positions.size() + pick(3));
            what += " out-of-range";
            break;
          }
        }
      }
      mesh.surfaces.resize(mesh.triangles.size(), 0);
      const bool expected_sound = sound_by_count(mesh);
      const ValidationReport report = validate_mesh(mesh, {.check_self_intersections = false});
      INFO("edits:" << what << "; report: " << report.summary());
      CHECK(reports_topology_defect(report) == !expected_sound);
      (expected_sound ? sound : broken) += 1;
    }
  }
  // Both verdicts occur, so neither direction goes untested.
  CHECK(sound > 50);
  CHECK(broken > 1000);
}
