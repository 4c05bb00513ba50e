// repair_mesh: valid meshes damaged in known ways, over many seeds, must come back
// valid with every change named, and with their exact volume where the repair can
// restore it exactly; valid meshes are left alone; the corpus's bad meshes are
// repaired or refused as recorded here. `shatter ... --repair` end to end:
// tests/cli/test_repair_cli.cpp.

#include <catch2/catch.hpp>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "shatter/generators/corpus.hpp"
#include "shatter/generators/random.hpp"
#include "shatter/generators/solids.hpp"
#include "shatter/kernel/error.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/predicates.hpp"
#include "shatter/kernel/repair.hpp"
#include "shatter/kernel/validate.hpp"
#include "support/checks.hpp"
#include "shatter/generators/corpus.hpp"
#include "shatter/generators/solids.hpp"

using namespace shatter;
using namespace shatter::test;
namespace fs = std::filesystem;

namespace {

// Small and quick meshes for the many-seed loops: the generated catalogue plus
// the smaller corpus meshes.
std::vector<NamedMesh> test_meshes() {
  std::vector<NamedMesh> meshes = generated_meshes();
  for (const fs::path& path : valid_meshes()) {
    Mesh mesh = read_mesh(path);
    if (mesh.triangle_count() <= 3000) meshes.push_back({path.filename().string(), std::move(mesh)});
  }
  return meshes;
}

bool names(const RepairReport& report, RepairKind kind) { return report.find(kind) != nullptr; }
std::size_t count_of(const RepairReport& report, RepairKind kind) {
  const RepairChange* change = report.find(kind);
  return change ? change->count : 0;
}

void reverse(Triangle& t) { std::swap(t[1], t[2]); }

void reverse_corner_attributes(Mesh& mesh, std::size_t t) {
  if (mesh.corners.has_normals()) std::swap(mesh.corners.normals[3 * t + 1], mesh.corners.normals[3 * t + 2]);
  if (mesh.corners.has_uvs()) std::swap(mesh.corners.uvs[3 * t + 1], mesh.corners.uvs[3 * t + 2]);
  if (mesh.corners.has_tangents()) std::swap(mesh.corners.tangents[3 * t + 1], mesh.corners.tangents[3 * t + 2]);
}

// Per-corner UVs that name their triangle and vertex, so a test can tell whether
// each corner kept its own attribute.
void add_tracer_uvs(Mesh& mesh) {
  mesh.corners.uvs.clear();
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    for (int c = 0; c < 3; ++c) mesh.corners.uvs.push_back({double(t), double(mesh.triangles[t][c])});
  }
}

void remove_triangles(Mesh& mesh, std::vector<std::size_t> doomed) {
  std::sort(doomed.begin(), doomed.end(), std::greater<>());
  for (std::size_t t : doomed) {
    mesh.triangles.erase(mesh.triangles.begin() + static_cast<std::ptrdiff_t>(t));
    mesh.surfaces.erase(mesh.surfaces.begin() + static_cast<std::ptrdiff_t>(t));
    for (auto* channel : {&mesh.corners.uvs}) {
      if (!channel->empty()) channel->erase(channel->begin() + static_cast<std::ptrdiff_t>(3 * t),
                                            channel->begin() + static_cast<std::ptrdiff_t>(3 * t + 3));
    }
  }
}

std::string problem_after_repair(const Mesh& mesh) { return solid_problem(mesh); }

}  // namespace

TEST_CASE("repairing a valid mesh changes nothing and reports nothing", "[repair]") {
  for (NamedMesh& named : test_meshes()) {
    INFO(named.name);
    const std::string before = canonical_bytes(named.mesh);
    const RepairReport report = repair_mesh(named.mesh);
    CHECK_FALSE(report.changed());
    CHECK(report.notes.empty());
    CHECK(report.summary() == "no change");
    CHECK(canonical_bytes(named.mesh) == before);
  }
}

TEST_CASE("reversed triangles are oriented back, outward, with the exact volume", "[repair]") {
  std::size_t cases = 0;
  for (const NamedMesh& named : test_meshes()) {
    const mpq_class volume = exact_six_volume(named.mesh);
    for (std::uint64_t seed = 1; seed <= 6; ++seed) {
      INFO(named.name << " seed " << seed);
      Mesh mesh = named.mesh;
      Random random(seed * 7919 + named.mesh.triangle_count());
      add_tracer_uvs(mesh);
      const Mesh traced = mesh;
      // Seed 1 reverses every triangle (inward); the others a random subset.
      std::size_t reversed = 0;
      for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
        if (seed == 1 || random.uniform() < 0.3) {
          reverse(mesh.triangles[t]);
          reverse_corner_attributes(mesh, t);
          ++reversed;
        }
      }
      if (reversed == 0) continue;
      const RepairReport report = repair_mesh(mesh);
      CHECK(problem_after_repair(mesh).empty());
      CHECK(count_of(report, RepairKind::reversed_triangles) == reversed);
      CHECK(report.changes.size() == 1);
      CHECK(exact_six_volume(mesh) == volume);
      // Each corner keeps its own attribute, and the result is the input again.
      CHECK(canonical_bytes(mesh) == canonical_bytes(traced));
      ++cases;
    }
  }
  CHECK(cases > 50);
}

TEST_CASE("duplicate vertices and triangles are merged and removed, giving the input back", "[repair]") {
  for (const NamedMesh& named : test_meshes()) {
    for (std::uint64_t seed = 1; seed <= 4; ++seed) {
      INFO(named.name << " seed " << seed);
      Mesh mesh = named.mesh;
      Random random(seed);
      // Unweld: some corners get a fresh copy of their vertex, appended at the
      // end, so the first copy keeps its number and the input comes back exactly.
      std::size_t copies = 0;
      for (int i = 0; i < 5; ++i) {
        const std::size_t t = random.index(mesh.triangle_count());
        const int c = static_cast<int>(random.index(3));
        mesh.positions.push_back(mesh.positions[mesh.triangles[t][c]]);
        mesh.triangles[t][c] = static_cast<VertexIndex>(mesh.positions.size() - 1);
        ++copies;
      }
      // Duplicate triangles, some rotated: the same triangle all the same.
      std::size_t duplicates = 1 + random.index(3);
      for (std::size_t i = 0; i < duplicates; ++i) {
        Triangle copy = named.mesh.triangles[random.index(named.mesh.triangle_count())];
        std::rotate(copy.begin(), copy.begin() + static_cast<std::ptrdiff_t>(random.index(3)), copy.end());
        mesh.triangles.push_back(copy);
        mesh.surfaces.push_back(original_surface);
      }
      const RepairReport report = repair_mesh(mesh);
      CHECK(count_of(report, RepairKind::merged_duplicate_vertices) == copies);
      CHECK(count_of(report, RepairKind::removed_duplicate_triangles) == duplicates);
      CHECK(problem_after_repair(mesh).empty());
      CHECK(canonical_bytes(mesh) == canonical_bytes(named.mesh));
    }
  }
}

TEST_CASE("a triangle and its reverse lying back to back: the one the surface needs stays", "[repair]") {
  Mesh mesh = unit_cube();
  const Mesh cube = mesh;
  Triangle reversed = mesh.triangles[3];
  reverse(reversed);
  mesh.triangles.push_back(reversed);
  mesh.surfaces.push_back(original_surface);
  const RepairReport report = repair_mesh(mesh);
  // Removing both left a hole, which a lid of its own closed (until 2026-12-08):
  // the cube's edges say which of the two it needs.
  CHECK(count_of(report, RepairKind::removed_opposite_triangle_pairs) == 1);
  CHECK_FALSE(names(report, RepairKind::filled_holes));
  CHECK(problem_after_repair(mesh).empty());
  CHECK(canonical_bytes(mesh) == canonical_bytes(cube));
}

TEST_CASE("zero-area triangles from an exact edge split are removed, the volume kept exactly", "[repair]") {
  using K = CGAL::Epick;
  std::size_t cases = 0;
  for (const NamedMesh& named : test_meshes()) {
    const mpq_class volume = exact_six_volume(named.mesh);
    Random random(named.mesh.triangle_count());
    for (int attempt = 0, done = 0; attempt < 40 && done < 3; ++attempt) {
      Mesh mesh = named.mesh;
      const std::size_t t = random.index(mesh.triangle_count());
      const int c = static_cast<int>(random.index(3));
      const VertexIndex a = mesh.triangles[t][c], b = mesh.triangles[t][(c + 1) % 3], x = mesh.triangles[t][(c + 2) % 3];
      const Vec3 pa = mesh.positions[a], pb = mesh.positions[b];
      const Vec3 m = (pa + pb) * 0.5;
      // Only where the rounded midpoint lies exactly inside the edge.
      const K::Point_3 ka(pa.x, pa.y, pa.z), km(m.x, m.y, m.z), kb(pb.x, pb.y, pb.z);
      if (!CGAL::collinear(ka, km, kb) || !CGAL::collinear_are_strictly_ordered_along_line(ka, km, kb)) {
        continue;
      }
      INFO(named.name << " triangle " << t);
      const VertexIndex mi = static_cast<VertexIndex>(mesh.positions.size());
      mesh.positions.push_back(m);
      // (a, b, x) becomes (a, m, x) + (m, b, x); the zero-area (a, b, m) closes the
      // edge the other triangle still traverses b -> a.
      mesh.triangles[t] = {a, mi, x};
      mesh.triangles.push_back({mi, b, x});
      mesh.triangles.push_back({a, b, mi});
      mesh.surfaces.push_back(original_surface);
      mesh.surfaces.push_back(original_surface);
      REQUIRE(validate_mesh(mesh).find(DefectKind::zero_area_triangle) != nullptr);
      const RepairReport report = repair_mesh(mesh);
      CHECK(count_of(report, RepairKind::fixed_zero_area_triangles) == 1);
      CHECK(problem_after_repair(mesh).empty());
      CHECK(exact_six_volume(mesh) == volume);
      ++done;
      ++cases;
    }
  }
  CHECK(cases > 20);
}

// The exact midpoint of a triangle's edge c -> c+1 when the rounded midpoint
// lies strictly inside the edge, else nothing.
std::optional<Vec3> midpoint_inside(const Mesh& mesh, std::size_t t, int c) {
  const Vec3 a = mesh.positions[mesh.triangles[t][c]], b = mesh.positions[mesh.triangles[t][(c + 1) % 3]];
  const Vec3 m = (a + b) * 0.5;
  if (!strictly_inside_segment(a, b, m)) return std::nullopt;
  return m;
}

// Adds up to `wanted` triangles (a, b, p), either way round, each on another
// edge (a, b) of `mesh`'s first `triangles` triangles, p = point(t, c) for the
// edge c of triangle t (none where it gives nothing). Returns how many it added.
template <class Point>
std::size_t add_triangles_on_edges(Mesh& mesh, std::size_t triangles, Random& random, std::size_t wanted,
                                   Point point) {
  std::set<std::pair<VertexIndex, VertexIndex>> used;
  std::size_t added = 0;
  for (std::size_t i = 0; i < 4 * wanted && added < wanted; ++i) {
    const std::size_t t = random.index(triangles);
    const int c = static_cast<int>(random.index(3));
    const VertexIndex a = mesh.triangles[t][c], b = mesh.triangles[t][(c + 1) % 3];
    const std::optional<Vec3> p = point(t, c);
    if (!p || !used.insert({std::min(a, b), std::max(a, b)}).second) continue;
    mesh.positions.push_back(*p);
    const auto pi = static_cast<VertexIndex>(mesh.positions.size() - 1);
    mesh.triangles.push_back(random.index(2) == 0 ? Triangle{a, b, pi} : Triangle{b, a, pi});
    mesh.surfaces.push_back(original_surface);
    ++added;
  }
  return added;
}

TEST_CASE("triangles stuck on a closed surface's edges (zero-area or fins) are removed: the surface comes back as it was",
          "[repair][chain]") {
  // Each is an edge and a point near its middle: exactly inside it (a zero-area
  // triangle of the welded chain, enclosing nothing) or off its line (a rounded
  // midpoint, or one moved a little: a fin, whose two other edges are free and
  // bound nothing). The other steps took their edges for holes: they closed
  // them with lids (a box scaled by 1e8 with 9 zero-area ones came out of
  // volume 6.67e24, not 8e24) or refused the mesh as open (a fin's only lid
  // repeats it the other way round).
  for (const bool fins : {false, true}) {
    std::size_t cases = 0;
    for (const NamedMesh& named : test_meshes()) {
      Random random(named.mesh.triangle_count() + (fins ? 41 : 17));
      for (int attempt = 0; attempt < 3; ++attempt) {
        Mesh mesh = named.mesh;
        const std::size_t added = add_triangles_on_edges(
            mesh, named.mesh.triangle_count(), random, 1 + random.index(9),
            [&](std::size_t t, int c) -> std::optional<Vec3> {
              if (!fins) return midpoint_inside(named.mesh, t, c);
              const Vec3 a = named.mesh.positions[named.mesh.triangles[t][c]];
              const Vec3 b = named.mesh.positions[named.mesh.triangles[t][(c + 1) % 3]];
              const Vec3 across = named.mesh.positions[named.mesh.triangles[t][(c + 2) % 3]] - a;
              const Vec3 m = (a + b) * 0.5 + across * std::ldexp(1.0, -static_cast<int>(10 + random.index(30)));
              if (collinear(a, b, m)) return std::nullopt;  // the move rounded away: no fin
              return m;
            });
        if (added == 0) continue;
        INFO(named.name << " attempt " << attempt << ": " << added << (fins ? " fins" : " zero-area triangles"));
        const RepairReport report = repair_mesh(mesh);
        INFO(report.summary());
        CHECK(count_of(report, fins ? RepairKind::removed_hanging_triangles : RepairKind::fixed_zero_area_triangles) ==
              added);
        CHECK(count_of(report, RepairKind::removed_unused_vertices) == added);
        CHECK_FALSE(names(report, RepairKind::filled_holes));
        CHECK(problem_after_repair(mesh).empty());
        CHECK(canonical_bytes(mesh) == canonical_bytes(named.mesh));
        ++cases;
      }
    }
    CHECK(cases > 30);
  }
}

TEST_CASE("a triangle split at a point inside an edge its neighbour does not split (a T-junction): the neighbour is "
          "split there and the volume kept exactly",
          "[repair][chain]") {
  std::size_t cases = 0;
  for (const NamedMesh& named : test_meshes()) {
    const mpq_class volume = exact_six_volume(named.mesh);
    Random random(named.mesh.triangle_count() + 29);
    for (int attempt = 0, done = 0; attempt < 40 && done < 3; ++attempt) {
      Mesh mesh = named.mesh;
      // One or two triangles split at the midpoints of their edges; a triangle
      // split twice has a T-junction on two of its neighbours' edges.
      const std::size_t t = random.index(mesh.triangle_count());
      std::vector<int> edges;
      for (int c = 0; c < 3; ++c) {
        if (midpoint_inside(named.mesh, t, c) && (edges.empty() || random.index(2) == 0)) edges.push_back(c);
      }
      if (edges.empty()) continue;
      const Triangle original = mesh.triangles[t];
      const int c = edges.front();
      const VertexIndex a = original[c], b = original[(c + 1) % 3], x = original[(c + 2) % 3];
      mesh.positions.push_back(*midpoint_inside(named.mesh, t, c));
      const auto m = static_cast<VertexIndex>(mesh.positions.size() - 1);
      mesh.triangles[t] = {a, m, x};
      mesh.triangles.push_back({m, b, x});
      mesh.surfaces.push_back(original_surface);
      std::size_t junctions = 1;
      if (edges.size() > 1) {
        // The second edge of the original triangle now lies in (m, b, x) or (a, m, x).
        const int d = edges[1];
        const VertexIndex u = original[d], v = original[(d + 1) % 3];
        mesh.positions.push_back(*midpoint_inside(named.mesh, t, d));
        const auto n = static_cast<VertexIndex>(mesh.positions.size() - 1);
        for (std::size_t s : {t, mesh.triangles.size() - 1}) {
          for (int e = 0; e < 3; ++e) {
            if (mesh.triangles[s][e] == u && mesh.triangles[s][(e + 1) % 3] == v) {
              const VertexIndex w = mesh.triangles[s][(e + 2) % 3];
              mesh.triangles[s] = {u, n, w};
              mesh.triangles.push_back({n, v, w});
              mesh.surfaces.push_back(original_surface);
              ++junctions;
              break;
            }
          }
        }
      }
      INFO(named.name << " triangle " << t << ", " << junctions << " T-junctions");
      REQUIRE_FALSE(validate_mesh(mesh).valid());
      const RepairReport report = repair_mesh(mesh);
      INFO(report.summary());
      CHECK(count_of(report, RepairKind::split_edges_at_vertices) == junctions);
      CHECK_FALSE(names(report, RepairKind::filled_holes));
      CHECK(problem_after_repair(mesh).empty());
      CHECK(exact_six_volume(mesh) == volume);
      CHECK(mesh.triangle_count() == named.mesh.triangle_count() + 2 * junctions);
      ++done;
      ++cases;
    }
  }
  CHECK(cases > 30);
}

TEST_CASE("reversed and repeated copies of a closed surface's triangles: the copies its edges need stay and the "
          "surface comes back as it was",
          "[repair][chain]") {
  // A triangle and its reverse enclose nothing, but a reversed copy added to a
  // closed surface is no pair of the surface's own: the other steps removed
  // both and closed the hole with a lid of their own (a torus of quads lost 3 %
  // of its volume). What the triangle's neighbours cross its edges with says
  // which copy the surface needs, also where copied triangles are neighbours.
  for (const NamedMesh& named : test_meshes()) {
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
      Mesh mesh = named.mesh;
      Random random(seed * 7919 + named.mesh.triangle_count());
      const std::size_t count = named.mesh.triangle_count();
      // A run of neighbours (by index, often adjacent) and some anywhere.
      const std::size_t first = random.index(count);
      std::vector<std::size_t> copied;
      for (std::size_t i = 0; i < std::min<std::size_t>(count, 4); ++i) copied.push_back((first + i) % count);
      for (int i = 0; i < 6; ++i) copied.push_back(random.index(count));
      std::size_t reversed_copies = 0;
      for (const std::size_t t : copied) {
        Triangle copy = named.mesh.triangles[t];
        std::rotate(copy.begin(), copy.begin() + static_cast<std::ptrdiff_t>(random.index(3)), copy.end());
        const int kind = static_cast<int>(random.index(3));  // reversed, repeated, or both
        if (kind != 1) {
          Triangle turned = copy;
          reverse(turned);
          mesh.triangles.push_back(turned);
          mesh.surfaces.push_back(original_surface);
          ++reversed_copies;
        }
        if (kind != 0) {
          mesh.triangles.push_back(copy);
          mesh.surfaces.push_back(original_surface);
        }
      }
      INFO(named.name << " seed " << seed << ": " << reversed_copies << " reversed copies");
      const RepairReport report = repair_mesh(mesh);
      INFO(report.summary());
      CHECK(names(report, RepairKind::removed_opposite_triangle_pairs));
      CHECK_FALSE(names(report, RepairKind::filled_holes));
      CHECK(problem_after_repair(mesh).empty());
      CHECK(canonical_bytes(mesh) == canonical_bytes(named.mesh));
    }
  }
}

TEST_CASE("small holes are filled: one to three adjacent triangles deleted", "[repair]") {
  std::size_t cases = 0, single = 0;
  for (const NamedMesh& named : test_meshes()) {
    const mpq_class volume = exact_six_volume(named.mesh);
    for (std::uint64_t seed = 1; seed <= 4; ++seed) {
      Mesh mesh = named.mesh;
      add_tracer_uvs(mesh);
      Random random(seed * 31 + named.mesh.triangle_count());
      const std::size_t holes = 1 + seed % 3;  // triangles deleted
      std::vector<std::size_t> doomed{random.index(mesh.triangle_count())};
      // Grow by triangles sharing an edge with the first one.
      for (std::size_t t = 0; t < mesh.triangle_count() && doomed.size() < holes; ++t) {
        const Triangle& a = mesh.triangles[doomed[0]];
        const Triangle& b = mesh.triangles[t];
        int shared = 0;
        for (VertexIndex v : a) shared += std::count(b.begin(), b.end(), v) ? 1 : 0;
        if (shared == 2) doomed.push_back(t);
      }
      // Skip damage that would orphan a vertex: that is not a hole any more.
      std::map<VertexIndex, int> uses;
      for (const Triangle& t : mesh.triangles) for (VertexIndex v : t) ++uses[v];
      for (std::size_t t : doomed) for (VertexIndex v : mesh.triangles[t]) --uses[v];
      if (std::any_of(uses.begin(), uses.end(), [](const auto& u) { return u.second == 0; })) continue;
      INFO(named.name << " seed " << seed << " deleted " << doomed.size());
      remove_triangles(mesh, doomed);
      const RepairReport report = repair_mesh(mesh);
      CHECK(count_of(report, RepairKind::filled_holes) == 1);
      CHECK(problem_after_repair(mesh).empty());
      CHECK(mesh.corners.uvs.size() == 3 * mesh.triangle_count());
      // New corners borrow an existing corner's value at the same vertex.
      for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
        for (int c = 0; c < 3; ++c) CHECK(mesh.corners.uvs[3 * t + c].y == double(mesh.triangles[t][c]));
      }
      if (doomed.size() == 1) {
        // A 3-edge hole has one lid: the deleted triangle itself.
        CHECK(exact_six_volume(mesh) == volume);
        ++single;
      }
      ++cases;
    }
  }
  CHECK(cases > 30);
  CHECK(single > 10);
}

TEST_CASE("several kinds of damage at once are each named", "[repair]") {
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    INFO("seed " << seed);
    const Mesh original = grid_box({0, 0, 0}, {1, 2, 3}, 3);
    Mesh mesh = original;
    Random random(seed);
    for (Triangle& t : mesh.triangles) {
      if (random.uniform() < 0.2) reverse(t);
    }
    mesh.positions.push_back(mesh.positions[mesh.triangles[5][0]]);
    mesh.triangles[5][0] = static_cast<VertexIndex>(mesh.positions.size() - 1);
    mesh.triangles.push_back(mesh.triangles[9]);
    mesh.surfaces.push_back(original_surface);
    const RepairReport report = repair_mesh(mesh);
    CHECK(names(report, RepairKind::merged_duplicate_vertices));
    CHECK(names(report, RepairKind::removed_duplicate_triangles));
    CHECK(problem_after_repair(mesh).empty());
    CHECK(exact_six_volume(mesh) == exact_six_volume(original));
    // Repairing again finds nothing left to do.
    const std::string once = canonical_bytes(mesh);
    CHECK_FALSE(repair_mesh(mesh).changed());
    CHECK(canonical_bytes(mesh) == once);
  }
}

TEST_CASE("meshes repair cannot give a meaning to are left unchanged with a note", "[repair]") {
  Mesh mesh = unit_cube();
  mesh.positions[2].y = std::numeric_limits<double>::infinity();
  std::reverse(mesh.triangles[0].begin(), mesh.triangles[0].end());
  const std::string before = canonical_bytes(mesh);
  const RepairReport report = repair_mesh(mesh);
  CHECK_FALSE(report.changed());
  REQUIRE(report.notes.size() == 1);
  CHECK(report.notes[0].text.find("non-finite") != std::string::npos);
  CHECK(canonical_bytes(mesh) == before);

  Mesh empty;
  CHECK_FALSE(repair_mesh(empty).changed());
}

// The triangles of `mesh` that have vertex `v`.
std::vector<std::size_t> triangles_at(const Mesh& mesh, VertexIndex v) {
  std::vector<std::size_t> at;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    if (std::find(mesh.triangles[t].begin(), mesh.triangles[t].end(), v) != mesh.triangles[t].end()) at.push_back(t);
  }
  return at;
}

TEST_CASE("holes touching at vertices are all filled: a convex solid with holes punched comes back valid",
          "[repair]") {
  // An ellipsoid of three different radii (no four of its vertices on one plane,
  // so a lid over a hole's own vertices lies inside and meets the surface only
  // along the hole), with holes punched by removing random triangles and the
  // whole fan of random vertices: fans next to each other leave holes that touch
  // at a vertex or pass through one twice, whose lids CGAL draws over copies of
  // that vertex and would repeat an edge (the repair then closes them over the
  // welded vertices). Every case must come back a valid solid, every hole filled.
  // Each case also reversed whole, and with a box inside facing outward too:
  // the welded lids close the surface only when it is written, after CGAL's
  // orientation step saw it open, so the written shells must still be turned
  // the way their nesting asks (found by shatter-fuzz --repair-cases: such
  // meshes came back closed but inward-facing, or misnested).
  std::size_t welded = 0, cases = 0;
  for (std::uint64_t draw = 1; draw <= 180; ++draw) {
    const std::uint64_t seed = (draw + 2) / 3;
    const int variant = int(draw % 3);  // 1: as punched, 2: reversed, 0: with a misnested box inside
    INFO("seed " << seed << " variant " << variant);
    Mesh mesh = ellipsoid({0, 0, 0}, {1.0, 1.3, 0.8}, 20, 14);
    Random random(seed);
    std::set<std::size_t> doomed;
    const std::size_t fans = 1 + random.index(6), singles = random.index(8);
    for (std::size_t k = 0; k < fans; ++k) {
      for (const std::size_t t : triangles_at(mesh, static_cast<VertexIndex>(random.index(mesh.vertex_count())))) {
        doomed.insert(t);
      }
    }
    for (std::size_t k = 0; k < singles; ++k) doomed.insert(random.index(mesh.triangle_count()));
    // Keep most of the solid: a lid over half of it is another test.
    if (doomed.size() > mesh.triangle_count() / 4) continue;
    ++cases;
    remove_triangles(mesh, {doomed.begin(), doomed.end()});
    if (variant == 2) mesh = flipped(mesh);
    if (variant == 0) mesh = merge({mesh, box({-0.25, -0.25, -0.25}, {0.25, 0.25, 0.25})});
    REQUIRE(validate_mesh(mesh).find(DefectKind::boundary_edge) != nullptr);
    const RepairReport report = repair_mesh(mesh);
    CHECK(names(report, RepairKind::filled_holes));
    INFO(report.summary());
    CHECK(problem_after_repair(mesh) == "");
    CHECK(report.notes.empty());
    const RepairChange* filled = report.find(RepairKind::filled_holes);
    if (filled && filled->text.find("over the welded vertices") != std::string::npos) ++welded;
  }
  CHECK(cases >= 120);
  // The case this closes: without the welded lids these stayed open.
  CHECK(welded >= 15);
}

// The triangles of `mesh` whose three corners have z = 0 exactly (a face of a box).
std::vector<std::size_t> triangles_on_plane_z0(const Mesh& mesh) {
  std::vector<std::size_t> on;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const Triangle& tri = mesh.triangles[t];
    if (mesh.positions[tri[0]].z == 0 && mesh.positions[tri[1]].z == 0 && mesh.positions[tri[2]].z == 0) on.push_back(t);
  }
  return on;
}

TEST_CASE("a hole of any size is filled by default", "[repair]") {
  // Regression: holes of more than 64 edges were left open by default, so a mesh
  // with one large opening could not be fractured even with --repair.
  Mesh mesh = grid_box({0, 0, 0}, {1, 1, 1}, 40);
  const std::vector<std::size_t> bottom = triangles_on_plane_z0(mesh);
  REQUIRE(bottom.size() == 2 * 40 * 40);
  remove_triangles(mesh, bottom);
  const RepairReport report = repair_mesh(mesh);
  CHECK(count_of(report, RepairKind::filled_holes) == 1);
  CHECK(report.find(RepairKind::filled_holes)->text.find("160 border edges") != std::string::npos);
  CHECK(problem_after_repair(mesh).empty());
  CHECK(exact_six_volume(mesh) == 6);
}

// An open fan: an apex and a rim of `rim` points at random heights, the rim
// going once around it, so the hole is a saddle whenever the heights alternate.
Mesh saddle_fan(std::uint64_t seed) {
  Random random(seed);
  const std::size_t rim = 5 + random.index(5);
  Mesh mesh;
  mesh.positions.push_back({0, 0, random.uniform(-0.3, 0.3)});
  for (std::size_t k = 0; k < rim; ++k) {
    const double angle = 2 * M_PI * static_cast<double>(k) / static_cast<double>(rim) + random.uniform(-0.2, 0.2);
    const double radius = random.uniform(0.6, 1.4);
    mesh.positions.push_back({radius * std::cos(angle), radius * std::sin(angle), random.uniform(-0.8, 0.8)});
  }
  for (std::size_t k = 0; k < rim; ++k) {
    mesh.triangles.push_back({0, static_cast<VertexIndex>(1 + k), static_cast<VertexIndex>(1 + (k + 1) % rim)});
    mesh.surfaces.push_back(0);
  }
  return mesh;
}

TEST_CASE("a hole's lid that would cross the surface gives way to one that does not", "[repair]") {
  // Regression: the search over every triangulation of a hole (taken for its
  // determinism) found lids through the surface where CGAL's Delaunay-restricted
  // search had none: 5 of CGAL's 143 demo meshes (negative.off, fold.off,
  // blobby_3cc.off, mech-holes-shark.off, mesh_with_border.off) went from
  // repaired to refused, and of 300 seeded saddle fans like these 19 were left
  // self-intersecting. A crossing lid is now replaced by the Delaunay search's
  // when that one does not cross. What stays refused is a fan under which
  // both searches' lids cross: 2 of the 300 (seeds 83 and 206).
  std::size_t valid = 0;
  std::vector<std::uint64_t> refused;
  for (std::uint64_t seed = 0; seed < 300; ++seed) {
    Mesh mesh = saddle_fan(seed);
    const RepairReport report = repair_mesh(mesh);
    CHECK(count_of(report, RepairKind::filled_holes) == 1);
    if (problem_after_repair(mesh).empty()) {
      ++valid;
      CHECK(exact_six_volume(mesh) > 0);
    } else {
      refused.push_back(seed);
    }
  }
  std::ostringstream seeds;
  for (std::uint64_t seed : refused) seeds << ' ' << seed;
  INFO("refused seeds:" << seeds.str());
  CHECK(valid >= 298);
}

TEST_CASE("holes larger than the limit are left, and noted", "[repair]") {
  Mesh mesh = grid_box({0, 0, 0}, {1, 1, 1}, 4);
  // Delete the whole z = 0 face: a 16-edge hole.
  const std::vector<std::size_t> bottom = triangles_on_plane_z0(mesh);
  REQUIRE(bottom.size() == 32);
  remove_triangles(mesh, bottom);
  RepairOptions small;
  small.max_hole_edges = 15;
  Mesh refused = mesh;
  const RepairReport report = repair_mesh(refused, small);
  CHECK_FALSE(names(report, RepairKind::filled_holes));
  REQUIRE(report.notes.size() == 1);
  CHECK(report.notes[0].text.find("16 edges") != std::string::npos);
  CHECK(validate_mesh(refused).find(DefectKind::boundary_edge) != nullptr);
  // The interior grid vertices of the face are gone with it.
  CHECK(names(report, RepairKind::removed_unused_vertices));

  RepairOptions enough;
  enough.max_hole_edges = 16;
  const RepairReport filled = repair_mesh(mesh, enough);
  CHECK(count_of(filled, RepairKind::filled_holes) == 1);
  CHECK(problem_after_repair(mesh).empty());
  CHECK(exact_six_volume(mesh) == 6);
}

// What repair does with each mesh in the corpus's bad/ folder, recorded.
// The oriented triangles of `mesh` as position triples, each rotated to start at
// its least position and the list sorted: equal for the same oriented surface
// whatever its vertex and triangle numbering.
std::vector<std::array<double, 9>> oriented_triangles(const Mesh& mesh) {
  std::vector<std::array<double, 9>> all;
  for (const Triangle& t : mesh.triangles) {
    std::array<std::array<double, 3>, 3> corners;
    for (int c = 0; c < 3; ++c) {
      const Vec3& p = mesh.positions[t[c]];
      corners[c] = {p.x, p.y, p.z};
    }
    const int first = int(std::min_element(corners.begin(), corners.end()) - corners.begin());
    std::array<double, 9> key;
    for (int c = 0; c < 3; ++c) std::copy(corners[(first + c) % 3].begin(), corners[(first + c) % 3].end(), key.begin() + 3 * c);
    all.push_back(key);
  }
  std::sort(all.begin(), all.end());
  return all;
}

TEST_CASE("a patch cut off all round by holes touching its corners is joined back, not closed on its own",
          "[repair][touching]") {
  // Regression (shatter-fuzz --repair-cases 800 --seed 2, case 7fdb8afdd0fc228b):
  // two triangles of a torus whose four neighbours across their outer edges are
  // removed hang on by their four corners alone. CGAL's orientation split those
  // corners, the pair became a piece of its own, and its own border was lidded:
  // closed into a tetrahedron beside the torus, then separated from it (step 9)
  // and, where it bounded its volume inside out, turned over: input triangles
  // came back reversed. Each removed triangle is the gap between the two fans at
  // each of its corners, a hole of three edges whose one lid is the triangle
  // itself: every case must give the torus back exactly, every triangle as read.
  // Over every pair of triangles sharing an edge, on a torus and on the fuzz's
  // scaled copy of it.
  std::size_t cases = 0;
  for (const Mesh& whole : {torus(1.0, 0.35, 12, 10), transformed(torus(1.0, 0.35, 12, 10), 1e6, {0, 0, 0})}) {
    const std::vector<std::array<double, 9>> expected = oriented_triangles(whole);
    std::map<std::pair<VertexIndex, VertexIndex>, std::size_t> triangle_of_edge;  // directed edge -> triangle
    for (std::size_t t = 0; t < whole.triangle_count(); ++t) {
      for (int c = 0; c < 3; ++c) triangle_of_edge[{whole.triangles[t][c], whole.triangles[t][(c + 1) % 3]}] = t;
    }
    const auto across = [&](std::size_t t, int c) {
      return triangle_of_edge.at({whole.triangles[t][(c + 1) % 3], whole.triangles[t][c]});
    };
    for (std::size_t t = 0; t < whole.triangle_count(); ++t) {
      for (int c = 0; c < 3; ++c) {
        const std::size_t u = across(t, c);
        if (u < t) continue;  // each pair once
        std::set<std::size_t> doomed;
        for (int k = 1; k < 3; ++k) doomed.insert(across(t, (c + k) % 3));
        for (int k = 0; k < 3; ++k) {
          const std::size_t w = across(u, k);
          if (w != t) doomed.insert(w);
        }
        if (doomed.size() != 4 || doomed.count(t) || doomed.count(u)) continue;
        Mesh mesh = whole;
        remove_triangles(mesh, {doomed.begin(), doomed.end()});
        INFO("triangles " << t << " and " << u << " of " << whole.triangle_count());
        const RepairReport report = repair_mesh(mesh);
        INFO(report.summary());
        CHECK(problem_after_repair(mesh) == "");
        CHECK(oriented_triangles(mesh) == expected);
        CHECK_FALSE(names(report, RepairKind::reversed_triangles));
        ++cases;
      }
    }
  }
  CHECK(cases == 2 * 360);
}

TEST_CASE("repairing one mesh again and again gives the same bytes (hole lids do not depend on the heap)",
          "[repair]") {
  // Regression (shatter-fuzz --repair-cases 800 --seed 2, case c3e86611603229a3,
  // "two repairs of the same mesh differ"): CGAL's triangulate_hole searched a 3D
  // Delaunay triangulation of a hole's vertices by default, whose edge iterator
  // starts each edge at its incident cell of least address; between lids of
  // exactly equal weight (the symmetric holes of a torus) the one it met first
  // won, so the lid followed where malloc had put the cells. The case itself
  // (four triangles at one vertex of the fuzz's scaled torus), then the whole fan
  // of vertices around the torus, each repaired several times with the heap
  // stirred in between, must give one mesh, byte for byte.
  const Mesh whole = transformed(torus(1.0, 0.35, 12, 10), 1e6, {0, 0, 0});
  std::vector<std::vector<std::size_t>> damages{{190, 191, 192, 213}};
  for (VertexIndex v = 3; v < whole.vertex_count(); v += 11) damages.push_back(triangles_at(whole, v));
  for (const std::vector<std::size_t>& doomed : damages) {
    Mesh damaged = whole;
    remove_triangles(damaged, doomed);
    INFO("removed " << doomed.size() << " triangles, the first " << doomed.front());
    std::string first;
    for (int repeat = 0; repeat < 6; ++repeat) {
      // Blocks of several sizes, half of them freed again: the next repair's
      // allocations land elsewhere.
      std::vector<std::vector<char>> stir;
      for (int k = 0; k < 7 * repeat + 3; ++k) stir.emplace_back(std::size_t(24 + 40 * (k % 7) + 200 * repeat));
      for (std::size_t k = 0; k < stir.size(); k += 2) stir[k] = {};
      Mesh mesh = damaged;
      repair_mesh(mesh);
      REQUIRE(problem_after_repair(mesh) == "");
      const std::string bytes = canonical_bytes(mesh);
      if (repeat == 0) first = bytes;
      CHECK(bytes == first);
    }
  }
}

TEST_CASE("every bad corpus mesh is repaired or refused as recorded", "[repair][corpus]") {
  struct Expected {
    bool valid;
    std::vector<RepairKind> changes;    // named in the report
    DefectKind remaining{};             // when refused: the first defect left
    mpq_class six_volume = 0;           // when repaired: exactly, unless
    double near_volume = 0;             // ... this is set: within 0.1 % of it
    bool emptied = false;               // repair removed every triangle: it encloses no volume
  };
  const std::map<std::string, Expected> expected{
      {"cube-ouvert.off", {true, {RepairKind::filled_holes}, {}, 48}},
      {"tet-shuffled.off", {true, {RepairKind::reversed_triangles}, {}, 1}},
      {"tetrahedron.off", {true, {RepairKind::reversed_triangles}, {}, 1}},
      // The inner box reversed into a cavity: six times (512 - 8).
      {"box-in-box-both-outward.off", {true, {RepairKind::reversed_triangles}, {}, 3024}},
      // Flat: every triangle lies in z = 0; no solid to recover. One flat piece,
      // removed whole: the refusal says the input encloses no volume (before:
      // its 4 zero-area triangles, which no flip removes, were named).
      {"degtri_sliding.off", {false, {RepairKind::removed_flat_pieces}, {}, 0, 0, true}},
      // 106 holes, touching at 65 pinched vertices, one of 78 edges: all filled
      // (38 of them, touching others, over the welded vertices), a valid solid
      // whose volume is within 0.1 % of the corpus elephant's, which the holes
      // were cut from (0.0461837 against 0.0462012 measured).
      {"elephant-with-holes.off", {true, {RepairKind::filled_holes}, {}, 0, 0.0462012}},
      // The stray triangle is a flat piece crossing the tetrahedron: it encloses
      // nothing, is removed, and the tetrahedron is turned outward (before: its
      // lid, its own reverse, was refused and the mesh stayed open).
      {"tetra_intersected_by_triangle.off",
       {true, {RepairKind::removed_flat_pieces, RepairKind::reversed_triangles}, {}, mpq_class("6369053643422139/4503599627370496")}},
  };
  std::size_t seen = 0;
  for (const fs::path& path : bad_meshes()) {
    const std::string name = path.filename().string();
    INFO(name);
    const auto it = expected.find(name);
    REQUIRE(it != expected.end());  // a new bad mesh needs its outcome recorded here
    ++seen;
    Mesh mesh = read_mesh(path);
    const RepairReport report = repair_mesh(mesh);
    CHECK((report.changed() || !report.notes.empty()));
    for (RepairKind kind : it->second.changes) CHECK(names(report, kind));
    if (it->second.emptied) {
      CHECK(mesh.triangles.empty());
      continue;
    }
    const ValidationReport after = validate_mesh(mesh);
    CHECK(after.valid() == it->second.valid);
    // A repair that ends valid has nothing to say it did not do (regression: the
    // elephant's pinched vertices were noted as a failure, then joined by its lids).
    if (it->second.valid) CHECK(report.notes.empty());
    if (it->second.valid && it->second.near_volume > 0) {
      CHECK(std::abs(signed_volume(mesh) / it->second.near_volume - 1) < 1e-3);
    } else if (it->second.valid) {
      CHECK(exact_six_volume(mesh) == it->second.six_volume);
    } else {
      CHECK_FALSE(names(report, RepairKind::separated_touching_parts));
      REQUIRE_FALSE(after.defects.empty());
      CHECK(after.defects.front().kind == it->second.remaining);
      CHECK_THROWS_AS(require_valid_solid(mesh, name, false), InvalidMeshError);
    }
  }
  CHECK(seen == expected.size());
}

TEST_CASE("self-intersections: left and named when no exact rounding is passed", "[repair][corpus]") {
  // The kernel cannot round a Solid (step 11 needs RepairOptions::round_solid,
  // which the triangulate layer gives); without it self-intersections are named.
  for (const fs::path& path : self_intersecting_meshes()) {
    INFO(path.filename().string());
    Mesh mesh = read_mesh(path);
    const RepairReport report = repair_mesh(mesh);
    CHECK_FALSE(names(report, RepairKind::resolved_self_intersections_exactly));
    CHECK(validate_mesh(mesh).find(DefectKind::self_intersection) != nullptr);
  }
}

// --- touching parts (step 9) ---------------------------------------------------------

namespace {

// An oriented triangle as its three positions, starting at the smallest.
std::array<Vec3, 3> position_triple(const Mesh& mesh, const Triangle& t) {
  std::array<Vec3, 3> corners{mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]]};
  const auto less = [](const Vec3& a, const Vec3& b) {
    return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
  };
  const int first = int(std::min_element(corners.begin(), corners.end(), less) - corners.begin());
  return {corners[first], corners[(first + 1) % 3], corners[(first + 2) % 3]};
}

bool has_triangle(const Mesh& mesh, const std::array<Vec3, 3>& triple) {
  for (const Triangle& t : mesh.triangles) {
    if (position_triple(mesh, t) == triple) return true;
  }
  return false;
}

Mesh outward(Mesh mesh) { return validate_mesh(mesh).find(DefectKind::inward_orientation) ? flipped(mesh) : mesh; }

Mesh tetrahedron(Vec3 a, Vec3 b, Vec3 c, Vec3 d) {
  return outward(mesh_from({a, b, c, d}, {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}));
}

double longest_edge(const Mesh& mesh) {
  double longest = 0;
  for (const Triangle& t : mesh.triangles) {
    for (int c = 0; c < 3; ++c) longest = std::max(longest, norm(mesh.positions[t[(c + 1) % 3]] - mesh.positions[t[c]]));
  }
  return longest;
}

// Positions that occur in more than one of `parts`: where they touch.
std::set<std::array<double, 3>> shared_positions(const std::vector<Mesh>& parts) {
  std::map<std::array<double, 3>, std::set<std::size_t>> owners;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    for (const Vec3& p : parts[i].positions) owners[{p.x, p.y, p.z}].insert(i);
  }
  std::set<std::array<double, 3>> shared;
  for (const auto& [p, who] : owners) {
    if (who.size() > 1) shared.insert(p);
  }
  return shared;
}

}  // namespace

TEST_CASE("a bowtie: two tetrahedra sharing a vertex are separated into a valid solid", "[repair][touching]") {
  const Mesh below = tetrahedron({0, 0, 0}, {-1, 0, 0}, {0, -1, 0}, {0, 0, -1});
  const Mesh above = tetrahedron({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1});
  Mesh mesh = merge({below, above});
  add_tracer_uvs(mesh);
  const Mesh input = mesh;
  REQUIRE(validate_mesh(mesh).find(DefectKind::self_intersection) != nullptr);  // touching at the apex

  const RepairReport report = repair_mesh(mesh);
  INFO(report.summary());
  CHECK(problem_after_repair(mesh).empty());
  CHECK(count_of(report, RepairKind::merged_duplicate_vertices) == 1);
  CHECK(count_of(report, RepairKind::separated_touching_parts) == 1);
  CHECK(report.notes.empty());
  CHECK(report.find(RepairKind::separated_touching_parts)->text.rfind("separated parts touching at 1 vertex: 1 vertex copy", 0) == 0);
  // The merged apex split again: 7 positions read, 8 vertices written.
  CHECK(mesh.vertex_count() == 8);
  REQUIRE(mesh.triangle_count() == 8);
  // Triangles and their corners' attributes keep their places; the lower
  // tetrahedron (the apex's first fan) is untouched.
  CHECK(mesh.corners.uvs == input.corners.uvs);
  for (std::size_t t = 0; t < 4; ++t) CHECK(position_triple(mesh, mesh.triangles[t]) == position_triple(input, input.triangles[t]));
  // The upper one's apex moved into it, by 2^-20 of its shortest edge (1).
  const Vec3 apex = mesh.positions[mesh.triangles[4][0]];
  CHECK(apex.x > 0);
  CHECK(apex.y > 0);
  CHECK(apex.z > 0);
  CHECK(norm(apex) <= 0x1p-20 * (1 + 1e-12));
  // The volume lost is the sliver swept by the apex's three faces: at most the
  // move times their area (3/2) over 3.
  const mpq_class six = exact_six_volume(mesh);
  CHECK(six < 2);
  CHECK(six.get_d() >= 2 - 6 * 0x1p-20 * 1.5 / 3);
}

TEST_CASE("two cubes sharing an edge are separated into a valid solid", "[repair][touching]") {
  const Mesh a = box({0, 0, 0}, {1, 1, 1}), b = box({1, 1, 0}, {2, 2, 1});
  Mesh mesh = merge({a, b});
  REQUIRE(validate_mesh(mesh).valid() == false);
  const RepairReport report = repair_mesh(mesh);
  INFO(report.summary());
  CHECK(problem_after_repair(mesh).empty());
  CHECK(count_of(report, RepairKind::merged_duplicate_vertices) == 2);
  CHECK(count_of(report, RepairKind::separated_touching_parts) == 2);
  CHECK(report.find(RepairKind::separated_touching_parts)->text.find("on 1 edge with more than two triangles") != std::string::npos);
  CHECK(mesh.vertex_count() == 16);
  CHECK(mesh.triangle_count() == 24);
  for (const Triangle& t : a.triangles) CHECK(has_triangle(mesh, position_triple(a, t)));
  // Each cube's own triangles away from the edge are kept too.
  std::size_t kept = 0;
  for (const Triangle& t : b.triangles) kept += has_triangle(mesh, position_triple(b, t)) ? 1 : 0;
  CHECK(kept >= 4);  // the faces x = 2, y = 2 (and whatever triangles of the others miss the edge)
  const mpq_class six = exact_six_volume(mesh);
  CHECK(six < 12);
  CHECK(six.get_d() > 12 - 6 * 0x1p-20 * 6);
}

TEST_CASE("parts touching at vertices and edges are separated over seeds: valid, deterministic, the rest kept",
          "[repair][touching]") {
  for (std::uint64_t seed = 0; seed < 60; ++seed) {
    INFO("seed " << seed);
    Random random(seed);
    const auto integer = [&](int lo, int hi) { return double(lo + int(random.index(std::size_t(hi - lo + 1)))); };
    // A box, and two more: one sharing a corner or an edge with it, and one
    // sharing a corner or an edge with the second (a chain of touching parts).
    std::vector<Mesh> parts{box({0, 0, 0}, {integer(1, 3), integer(1, 3), integer(1, 3)})};
    for (int k = 0; k < 2; ++k) {
      Vec3 hi = parts.back().positions[0];
      for (const Vec3& p : parts.back().positions) hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
      Vec3 lo = parts.back().positions[0];
      for (const Vec3& p : parts.back().positions) lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
      if (random.index(2) == 0) {
        parts.push_back(box(hi, {hi.x + integer(1, 3), hi.y + integer(1, 3), hi.z + integer(1, 3)}));
      } else {
        parts.push_back(box({hi.x, hi.y, lo.z}, {hi.x + integer(1, 3), hi.y + integer(1, 3), hi.z}));
      }
    }
    const bool rotate = random.index(2) == 0;
    const Vec3 axis = random.direction();
    const double angle = random.uniform(0, 6.283185307179586), c = std::cos(angle), s = std::sin(angle);
    for (Mesh& part : parts) {
      if (!rotate) continue;
      // The same rotation of the same doubles: shared positions stay shared.
      for (Vec3& p : part.positions) p = p * c + cross(axis, p) * s + axis * (dot(axis, p) * (1 - c));
    }
    Mesh original = merge(parts);
    const std::set<std::array<double, 3>> shared = shared_positions(parts);
    REQUIRE(shared.size() >= 2);
    // The damage: one part reversed sometimes, triangles shuffled, corners rotated.
    Mesh damaged = original;
    if (random.index(3) == 0) {
      const std::size_t part = random.index(parts.size());
      for (std::size_t t = 12 * part; t < 12 * part + 12; ++t) reverse(damaged.triangles[t]);
    }
    for (std::size_t i = damaged.triangles.size(); i > 1; --i) std::swap(damaged.triangles[i - 1], damaged.triangles[random.index(i)]);
    for (Triangle& t : damaged.triangles) std::rotate(t.begin(), t.begin() + random.index(3), t.end());

    Mesh repaired = damaged, again = damaged;
    const RepairReport report = repair_mesh(repaired);
    repair_mesh(again);
    INFO(report.summary());
    CHECK(canonical_bytes(repaired) == canonical_bytes(again));
    REQUIRE(problem_after_repair(repaired).empty());
    CHECK(names(report, RepairKind::separated_touching_parts));
    CHECK(report.notes.empty());
    CHECK(repaired.triangle_count() == original.triangle_count());
    // Every triangle away from where the parts touch is kept, as oriented in the
    // original; the others moved by at most 2^-20 of the longest edge.
    const auto at_touching = [&](const Mesh& mesh, const Triangle& t) {
      for (const VertexIndex v : t) {
        const Vec3 p = mesh.positions[v];
        if (shared.count({p.x, p.y, p.z})) return true;
      }
      return false;
    };
    for (const Triangle& t : original.triangles) {
      if (!at_touching(original, t)) CHECK(has_triangle(repaired, position_triple(original, t)));
    }
    const double reach = 0x1p-20 * longest_edge(original);
    for (const Vec3& p : repaired.positions) {
      if (shared.count({p.x, p.y, p.z})) continue;
      bool from_input = false;
      for (const Vec3& q : original.positions) from_input = from_input || q == p;
      if (from_input) continue;
      double nearest = INFINITY;
      for (const auto& q : shared) nearest = std::min(nearest, norm(p - Vec3{q[0], q[1], q[2]}));
      CHECK(nearest <= reach);
    }
    // The volume lost: at most the moves times the area they sweep.
    const double before = signed_volume(original), after = signed_volume(repaired);
    CHECK(after < before);
    CHECK(before - after <= reach * surface_area(original));
  }
}

TEST_CASE("a surface touching itself that is still open is not separated, and the note says why", "[repair][touching]") {
  Mesh a = box({0, 0, 0}, {1, 1, 1}), b = box({1, 1, 0}, {2, 2, 1});
  // Open the second cube's top (z = 1) face, away from the shared edge's sides.
  std::vector<std::size_t> top;
  for (std::size_t t = 0; t < b.triangles.size(); ++t) {
    bool all_top = true;
    for (const VertexIndex v : b.triangles[t]) all_top = all_top && b.positions[v].z == 1;
    if (all_top) top.push_back(t);
  }
  REQUIRE(top.size() == 2);
  remove_triangles(b, top);
  Mesh mesh = merge({a, b});
  RepairOptions no_fill;
  no_fill.max_hole_edges = 0;
  const RepairReport report = repair_mesh(mesh, no_fill);
  INFO(report.summary());
  CHECK_FALSE(names(report, RepairKind::separated_touching_parts));
  bool noted = false;
  for (const RepairNote& note : report.notes) noted = noted || note.text.find("did not separate") != std::string::npos;
  CHECK(noted);
  const ValidationReport after = validate_mesh(mesh);
  CHECK(after.find(DefectKind::boundary_edge) != nullptr);
  CHECK(after.find(DefectKind::non_manifold_edge) != nullptr);
  // Filled, the same mesh is separated.
  Mesh filled = merge({a, b});
  const RepairReport full = repair_mesh(filled);
  INFO(full.summary());
  CHECK(names(full, RepairKind::filled_holes));
  CHECK(names(full, RepairKind::separated_touching_parts));
  CHECK(problem_after_repair(filled).empty());
}

TEST_CASE("an edge whose triangles cannot be paired into wedges is left, noted and refused", "[repair][touching]") {
  // Two tetrahedra on one edge with a face each in the half-plane y = 0, x > 0:
  // those faces overlap, and their third corners share an angle about the edge.
  const Mesh a = tetrahedron({0, 0, 0}, {0, 0, 1}, {1, 0, 0.5}, {0, 1, 0.5});
  const Mesh b = tetrahedron({0, 0, 0}, {0, 0, 1}, {2, 0, 0.5}, {0, -1, 0.5});
  Mesh mesh = merge({a, b});
  const RepairReport report = repair_mesh(mesh);
  INFO(report.summary());
  CHECK_FALSE(names(report, RepairKind::separated_touching_parts));
  bool noted = false;
  for (const RepairNote& note : report.notes) noted = noted || note.text.find("cannot be paired") != std::string::npos;
  CHECK(noted);
  CHECK_FALSE(validate_mesh(mesh).valid());
  CHECK_THROWS_AS(require_valid_solid(mesh, "two tetrahedra", false), InvalidMeshError);
}

namespace {

// Appends a flat sheet to `mesh`: a fan over a pentagon p + a u + b v with small
// integer a, b and dyadic p, u, v, so every corner lies exactly on one plane.
// Sized like the mesh's box and placed in it, so the sheet mostly crosses the
// solid (as the stray triangle of CGAL's tetra_intersected_by_triangle.off does).
// Returns the number of triangles added.
std::size_t add_flat_sheet(Mesh& mesh, Random& random) {
  Vec3 lo = mesh.positions.front(), hi = lo;
  for (const Vec3& p : mesh.positions) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  const double size = std::exp2(std::floor(std::log2(std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z})))) / 4;
  const auto dyadic = [&](double from, double to) { return std::floor(random.uniform(from, to) * 64 / size) * size / 64; };
  const Vec3 p{dyadic(lo.x, hi.x), dyadic(lo.y, hi.y), dyadic(lo.z, hi.z)};
  Vec3 u, v, n;
  do {
    u = {dyadic(-size, size), dyadic(-size, size), dyadic(-size, size)};
    v = {dyadic(-size, size), dyadic(-size, size), dyadic(-size, size)};
    n = {u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x};
  } while (n.x == 0 && n.y == 0 && n.z == 0);
  const int pentagon[5][2] = {{-2, -1}, {2, -2}, {3, 1}, {0, 3}, {-2, 2}};
  const VertexIndex first = static_cast<VertexIndex>(mesh.positions.size());
  for (const auto& [a, b] : pentagon) mesh.positions.push_back(p + u * double(a) + v * double(b));
  for (VertexIndex k = 1; k + 1 < 5; ++k) {
    mesh.triangles.push_back({first, first + k, first + k + 1});
    mesh.surfaces.push_back(original_surface);
    for (int c = 0; c < 3; ++c) {
      if (mesh.corners.has_normals()) mesh.corners.normals.push_back(n);
      if (mesh.corners.has_uvs()) mesh.corners.uvs.push_back({0, 0});
      if (mesh.corners.has_tangents()) mesh.corners.tangents.push_back(mesh.corners.tangents.front());
    }
  }
  return 3;
}

}  // namespace

TEST_CASE("a flat sheet through a solid is removed, giving the solid back (tetra_intersected_by_triangle)",
          "[repair][flat]") {
  std::size_t meshes = 0;
  for (const NamedMesh& named : test_meshes()) {
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
      INFO(named.name << " seed " << seed);
      Random random(seed);
      Mesh mesh = named.mesh;
      const std::size_t added = add_flat_sheet(mesh, random);
      const RepairReport report = repair_mesh(mesh);
      CHECK(count_of(report, RepairKind::removed_flat_pieces) == added);
      CHECK(report.notes.empty());
      CHECK(problem_after_repair(mesh).empty());
      // The solid itself is untouched: the sheet's vertices came last and go unused.
      CHECK(canonical_bytes(mesh) == canonical_bytes(named.mesh));
      ++meshes;
    }
  }
  REQUIRE(meshes > 10);
}

TEST_CASE("a mesh that is all flat is emptied: it encloses no volume (mesh_with_colors, degtri_sliding)",
          "[repair][flat]") {
  // CGAL's degtri_sliding.off in miniature: a flat strip with zero-area triangles
  // sliding along one line, which no flip or collapse removes; and a flat open sheet.
  Mesh sliding;
  sliding.positions = {{4, -2, 0}, {6, 0, 0}, {4, 0, 0}, {2, 0, 0}, {1, 0, 0}, {3, 0, 0}, {5, 0, 0}, {3, 2, 0}};
  sliding.triangles = {{0, 1, 2}, {0, 2, 3}, {3, 2, 4}, {2, 1, 6}, {2, 6, 4}, {4, 6, 5}, {5, 6, 7}, {4, 5, 7}};
  sliding.surfaces.assign(sliding.triangles.size(), original_surface);
  Random random(7);
  Mesh sheet;
  sheet.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 1}};
  add_flat_sheet(sheet, random);
  sheet.positions.erase(sheet.positions.begin(), sheet.positions.begin() + 4);
  for (Triangle& t : sheet.triangles) {
    for (VertexIndex& v : t) v -= 4;
  }
  for (Mesh* mesh : {&sliding, &sheet}) {
    const std::size_t triangles = mesh->triangle_count();
    const RepairReport report = repair_mesh(*mesh);
    CHECK(count_of(report, RepairKind::removed_flat_pieces) == triangles);
    CHECK(mesh->triangles.empty());
    CHECK(mesh->positions.empty());
    REQUIRE(report.notes.size() == 1);
    CHECK(report.notes[0].text.find("no triangle left") != std::string::npos);
  }
}

TEST_CASE("a flat fin joined to a solid by an edge is not a piece of its own and is kept", "[repair][flat]") {
  Mesh mesh = unit_cube();
  // A triangle over an edge of the cube, sticking out in the plane of one face.
  const Triangle& t = mesh.triangles[0];
  const Vec3 a = mesh.positions[t[0]], b = mesh.positions[t[1]];
  mesh.positions.push_back(a + (a - mesh.positions[t[2]]) + (b - a) * 0.5);
  mesh.triangles.push_back({t[1], t[0], static_cast<VertexIndex>(mesh.positions.size() - 1)});
  mesh.surfaces.push_back(original_surface);
  const RepairReport report = repair_mesh(mesh);
  CHECK_FALSE(names(report, RepairKind::removed_flat_pieces));
}

TEST_CASE("a hole no lid over its own corners closes gets a fan from a new vertex (patch-23)", "[repair][holes]") {
  // CGAL's patch-23.off in miniature: a tent over a flat rectangular border whose
  // sides hold collinear corners, and three of whose four corners are ears of
  // the tent (the ear's diagonal is a mesh edge). Every triangulation over the
  // border's own corners then draws a taken diagonal or a triangle over one side's
  // collinear corners: the least-area lid finds none. The fan from the corners'
  // mean, (2, 1, 0), lies in the border's plane: the tent's volume, exactly.
  const std::vector<Vec3> points = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}, {4, 0, 0}, {4, 1, 0},
                                    {4, 2, 0}, {3, 2, 0}, {2, 2, 0}, {1, 2, 0}, {0, 2, 0}, {0, 1, 0},
                                    {1, 1, 1}, {2, 1, 1}, {3, 1, 1}};
  const std::vector<Triangle> triangles = {{0, 1, 12},  {0, 12, 11}, {1, 2, 13},  {1, 13, 12}, {2, 3, 14},  {2, 14, 13},
                                           {3, 5, 14},  {11, 12, 9}, {12, 13, 8}, {12, 8, 9},  {13, 14, 7}, {13, 7, 8},
                                           {14, 5, 7},  {3, 4, 5},   {5, 6, 7},   {9, 10, 11}};
  Mesh mesh = mesh_from(points, triangles);
  const RepairReport report = repair_mesh(mesh);
  INFO(report.summary());
  REQUIRE(names(report, RepairKind::filled_holes));
  CHECK(report.find(RepairKind::filled_holes)->text.find("by a fan from a new vertex") != std::string::npos);
  CHECK(report.notes.empty());
  CHECK(problem_after_repair(mesh).empty());
  CHECK(mesh.vertex_count() == 16);
  CHECK(mesh.positions.back() == Vec3{2, 1, 0});
  CHECK(exact_six_volume(mesh) == 17);
  // Deterministic: the same bytes again.
  Mesh again = mesh_from(points, triangles);
  repair_mesh(again);
  CHECK(canonical_bytes(again) == canonical_bytes(mesh));
}

// --- the command ------------------------------------------------------------------
