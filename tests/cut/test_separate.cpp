// Solid separation (meshtree/separate.hpp): a closed triangle set falls into
// shells, each cavity joins the innermost outward shell around it, and every
// solid comes out closed, oriented and compactly numbered. Properties over
// generated scenes of nested shells (solids with cavities holding islands with
// cavities, to depth four), several cavities side by side, shuffled triangles and
// renumbered vertices, pinched vertices, and both point types; then the cases the
// contract names: a lone inward or flat shell, a non-manifold edge, an open surface.

#include <catch2/catch.hpp>

#include <gmpxx.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "shatter/kernel/error.hpp"
#include "shatter/kernel/exact.hpp"
#include "shatter/kernel/validate.hpp"
#include "shatter/oracle/cut.hpp"
#include "shatter/cut/separate_exact.hpp"
#include "support/checks.hpp"
#include "shatter/generators/random.hpp"
#include "shatter/generators/solids.hpp"

using namespace shatter;
using namespace shatter::oracle;
using namespace shatter::test;

namespace {

// --- scenes of nested shells --------------------------------------------------------------

// One solid of a scene: its outward shell and the cavities inside it (inward
// shells), with what separation must give for it.
struct ExpectedSolid {
  std::size_t triangles = 0;
  std::size_t shells = 0;
  mpq_class six_volume = 0;
  std::size_t first_shell_triangles = 0;  // the outward shell's, which come first
};

struct Scene {
  std::vector<Mesh> shells;           // in the order they were made
  std::vector<int> solid_of_shell;    // index into solids
  std::vector<bool> outward;          // per shell: the outward shell of its solid
  std::vector<ExpectedSolid> solids;
};

// A convex or toroidal shell around `centre`, inside the ball of `radius` and
// containing the ball of inscribed(radius, kind) (for the next shell in).
enum class Shape { box, sphere, torus };
constexpr double inscribed_ratio(Shape shape) {
  // A box of half-size 0.999 r/sqrt(3) holds the ball of 0.57 r; the UV sphere of
  // 16 x 8 holds the ball of 0.85 r (cos(pi/8) cos(pi/16) = 0.906); a torus holds
  // no ball around its centre, so nothing goes inside one.
  return shape == Shape::box ? 0.57 : shape == Shape::sphere ? 0.85 : 0.0;
}
Mesh shape_mesh(Shape shape, Vec3 centre, double radius) {
  switch (shape) {
    case Shape::box: {
      const double h = radius / std::sqrt(3.0) * 0.999;
      return box(centre - Vec3{h, h, h}, centre + Vec3{h, h, h});
    }
    case Shape::sphere: return ellipsoid(centre, {radius, radius, radius}, 16, 8);
    case Shape::torus: return transformed(torus(0.7 * radius, 0.25 * radius, 12, 8), 1.0, centre);
  }
  return {};
}

// A nest of `depth` shells around `centre`: outward, inward, outward, ...
// Shell 2k and shell 2k + 1 (its cavity) form one solid; islands are solids of
// their own.
void add_nest(Scene& scene, Random& random, Vec3 centre, double radius, int depth) {
  int solid = -1;
  for (int level = 0; level < depth; ++level) {
    const bool last = level + 1 == depth;
    const Shape shape = last && random.index(3) == 0 ? Shape::torus
                                                     : random.index(2) ? Shape::box : Shape::sphere;
    Mesh mesh = shape_mesh(shape, centre, radius);
    const mpq_class six = exact_six_volume(mesh);
    const bool outward = level % 2 == 0;
    if (outward) {
      solid = static_cast<int>(scene.solids.size());
      scene.solids.push_back({mesh.triangle_count(), 1, six, mesh.triangle_count()});
    } else {
      mesh = flipped(std::move(mesh));
      ExpectedSolid& s = scene.solids[static_cast<std::size_t>(solid)];
      s.triangles += mesh.triangle_count();
      s.shells += 1;
      s.six_volume -= six;
    }
    scene.shells.push_back(std::move(mesh));
    scene.solid_of_shell.push_back(solid);
    scene.outward.push_back(outward);
    if (shape == Shape::torus) break;
    // The next shell: inside this one's inscribed ball, moved a little off centre.
    const double inner = inscribed_ratio(shape) * radius;
    const Vec3 offset = random.direction() * (0.1 * inner * random.uniform());
    centre = centre + offset;
    radius = (inner - norm(offset)) * random.uniform(0.6, 0.9);
  }
}

// An outward box holding two to four cavities side by side, each perhaps with an
// island in it.
void add_box_with_cavities(Scene& scene, Random& random, Vec3 centre) {
  const Mesh outer = box(centre - Vec3{3, 3, 3}, centre + Vec3{3, 3, 3});
  const int solid = static_cast<int>(scene.solids.size());
  scene.solids.push_back({outer.triangle_count(), 1, exact_six_volume(outer), outer.triangle_count()});
  scene.shells.push_back(outer);
  scene.solid_of_shell.push_back(solid);
  scene.outward.push_back(true);
  const Vec3 corners[] = {{-1.5, -1.5, -1.5}, {1.5, 1.5, -1.5}, {-1.5, 1.5, 1.5}, {1.5, -1.5, 1.5}};
  const std::size_t cavities = 2 + random.index(3);
  for (std::size_t k = 0; k < cavities; ++k) {
    // A cavity and its islands are a nest whose first shell is inward: start it
    // one level in, as the cavity of `solid`.
    const Vec3 c = centre + corners[k];
    const Shape shape = random.index(2) ? Shape::box : Shape::sphere;
    const Mesh cavity = flipped(shape_mesh(shape, c, 1.2));
    ExpectedSolid& s = scene.solids[static_cast<std::size_t>(solid)];
    s.triangles += cavity.triangle_count();
    s.shells += 1;
    s.six_volume += exact_six_volume(cavity);  // negative
    scene.shells.push_back(cavity);
    scene.solid_of_shell.push_back(solid);
    scene.outward.push_back(false);
    if (random.index(2)) add_nest(scene, random, c, inscribed_ratio(shape) * 1.2 * 0.8, 1 + static_cast<int>(random.index(3)));
  }
}

// Up to six nests and boxes with cavities in distinct cells of a 3 x 3 x 3 grid.
Scene random_scene(Random& random) {
  Scene scene;
  std::vector<int> cells(27);
  for (int i = 0; i < 27; ++i) cells[static_cast<std::size_t>(i)] = i;
  for (std::size_t i = cells.size(); i > 1; --i) std::swap(cells[i - 1], cells[random.index(i)]);
  const std::size_t count = 1 + random.index(6);
  for (std::size_t k = 0; k < count; ++k) {
    const int cell = cells[k];
    const Vec3 centre{8.0 * (cell % 3), 8.0 * (cell / 3 % 3), 8.0 * (cell / 9)};
    if (random.index(4) == 0) {
      add_box_with_cavities(scene, random, centre);
    } else {
      add_nest(scene, random, centre, 3.5, 1 + static_cast<int>(random.index(4)));
    }
  }
  return scene;
}

// The scene's shells as one surface: triangles shuffled, vertices renumbered at
// random. `first_triangle[s]` is where shell s's first triangle landed.
struct Surface {
  Mesh mesh;
  std::vector<std::size_t> first_triangle_of_shell;
};
Surface shuffled_surface(const Scene& scene, Random& random) {
  const Mesh joined = merge(scene.shells);
  std::vector<std::size_t> shell_of_triangle;
  for (std::size_t s = 0; s < scene.shells.size(); ++s) {
    shell_of_triangle.insert(shell_of_triangle.end(), scene.shells[s].triangle_count(), s);
  }
  std::vector<std::size_t> order(joined.triangle_count());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  for (std::size_t i = order.size(); i > 1; --i) std::swap(order[i - 1], order[random.index(i)]);
  std::vector<VertexIndex> renumber(joined.positions.size());
  for (std::size_t i = 0; i < renumber.size(); ++i) renumber[i] = static_cast<VertexIndex>(i);
  for (std::size_t i = renumber.size(); i > 1; --i) std::swap(renumber[i - 1], renumber[random.index(i)]);
  Surface out;
  out.mesh.positions.resize(joined.positions.size());
  for (std::size_t v = 0; v < renumber.size(); ++v) out.mesh.positions[renumber[v]] = joined.positions[v];
  out.first_triangle_of_shell.assign(scene.shells.size(), SIZE_MAX);
  for (std::size_t i = 0; i < order.size(); ++i) {
    const Triangle& t = joined.triangles[order[i]];
    out.mesh.triangles.push_back({renumber[t[0]], renumber[t[1]], renumber[t[2]]});
    out.mesh.surfaces.push_back(static_cast<SurfaceId>(i % 5));  // ids travel with their triangles
    std::size_t& first = out.first_triangle_of_shell[shell_of_triangle[order[i]]];
    first = std::min(first, i);
  }
  return out;
}

// --- what a separated solid must be ---------------------------------------------------------

using Corner = std::tuple<double, double, double, SurfaceId>;
// A triangle by its corners' positions (and surface id), rotated to start at the
// smallest corner: the same triangle whatever the vertex numbering.
std::array<Corner, 3> triangle_key(const Mesh& mesh, std::size_t t) {
  std::array<Corner, 3> key;
  for (int k = 0; k < 3; ++k) {
    const Vec3& p = mesh.positions[mesh.triangles[t][k]];
    key[k] = {p.x, p.y, p.z, mesh.surfaces[t]};
  }
  std::rotate(key.begin(), std::min_element(key.begin(), key.end()), key.end());
  return key;
}

// Edge-connected components of the triangles (shells), each as its triangles.
std::vector<std::vector<std::size_t>> shells_of(const Mesh& mesh) {
  std::map<std::pair<VertexIndex, VertexIndex>, std::size_t> triangle_of_edge;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    for (int k = 0; k < 3; ++k) triangle_of_edge[{mesh.triangles[t][k], mesh.triangles[t][(k + 1) % 3]}] = t;
  }
  std::vector<int> shell(mesh.triangle_count(), -1);
  std::vector<std::vector<std::size_t>> shells;
  for (std::size_t start = 0; start < mesh.triangle_count(); ++start) {
    if (shell[start] >= 0) continue;
    shells.emplace_back();
    std::vector<std::size_t> stack{start};
    shell[start] = static_cast<int>(shells.size() - 1);
    while (!stack.empty()) {
      const std::size_t t = stack.back();
      stack.pop_back();
      shells.back().push_back(t);
      for (int k = 0; k < 3; ++k) {
        const auto across = triangle_of_edge.find({mesh.triangles[t][(k + 1) % 3], mesh.triangles[t][k]});
        if (across != triangle_of_edge.end() && shell[across->second] < 0) {
          shell[across->second] = shell[start];
          stack.push_back(across->second);
        }
      }
    }
    std::sort(shells.back().begin(), shells.back().end());
  }
  return shells;
}

// Vertices are numbered 0, 1, 2, ... in order of first use by the triangles.
bool numbered_by_first_use(const Mesh& mesh) {
  VertexIndex next = 0;
  for (const Triangle& t : mesh.triangles) {
    for (const VertexIndex v : t) {
      if (v > next) return false;
      if (v == next) ++next;
    }
  }
  return next == mesh.positions.size();
}

void check_scene(const Scene& scene, const Surface& surface) {
  const std::vector<Mesh> solids = separate_solids(surface.mesh);
  REQUIRE(solids.size() == scene.solids.size());
  // Expected solids in the order of their outward shell's first triangle.
  std::vector<std::pair<std::size_t, std::size_t>> order;  // (first triangle, solid)
  for (std::size_t s = 0; s < scene.shells.size(); ++s) {
    if (scene.outward[s]) order.push_back({surface.first_triangle_of_shell[s], std::size_t(scene.solid_of_shell[s])});
  }
  std::sort(order.begin(), order.end());
  std::multiset<std::array<Corner, 3>> input_triangles, output_triangles;
  for (std::size_t t = 0; t < surface.mesh.triangle_count(); ++t) input_triangles.insert(triangle_key(surface.mesh, t));
  mpq_class total = 0;
  for (std::size_t i = 0; i < solids.size(); ++i) {
    const Mesh& solid = solids[i];
    const ExpectedSolid& expected = scene.solids[order[i].second];
    INFO("solid " << i << " of " << solids.size());
    CHECK(solid_problem(solid) == "");
    CHECK(numbered_by_first_use(solid));
    CHECK(solid.triangle_count() == expected.triangles);
    const mpq_class six = exact_six_volume(solid);
    CHECK(six == expected.six_volume);
    total += six;
    const auto shells = shells_of(solid);
    CHECK(shells.size() == expected.shells);
    // The outward shell first: the shell of triangle 0 is the first triangles.
    std::vector<std::size_t> leading(expected.first_shell_triangles);
    for (std::size_t t = 0; t < leading.size(); ++t) leading[t] = t;
    CHECK(shells.front() == leading);
    for (std::size_t t = 0; t < solid.triangle_count(); ++t) output_triangles.insert(triangle_key(solid, t));
  }
  CHECK(total == exact_six_volume(surface.mesh));
  CHECK(output_triangles == input_triangles);  // every triangle once, with its surface id

  // The exact point type decides the same way: the same solids, bit for bit.
  const std::vector<ExactMesh> exact = separate_solids(to_exact(surface.mesh));
  REQUIRE(exact.size() == solids.size());
  for (std::size_t i = 0; i < exact.size(); ++i) CHECK(canonical_bytes(to_fast(exact[i])) == canonical_bytes(solids[i]));
}

// Welds vertices at identical positions (the scenes below share corners).
Mesh welded(const Mesh& mesh) {
  std::map<std::tuple<double, double, double>, VertexIndex> index_of;
  std::vector<VertexIndex> remap(mesh.positions.size());
  Mesh out;
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    const Vec3& p = mesh.positions[v];
    const auto [it, inserted] = index_of.insert({{p.x, p.y, p.z}, static_cast<VertexIndex>(out.positions.size())});
    if (inserted) out.positions.push_back(p);
    remap[v] = it->second;
  }
  out.triangles = mesh.triangles;
  for (Triangle& t : out.triangles) {
    for (VertexIndex& v : t) v = remap[v];
  }
  out.surfaces = mesh.surfaces;
  return out;
}

}  // namespace

TEST_CASE("separation of generated scenes: nested shells, cavities side by side, shuffled", "[separate][property]") {
  std::size_t solids = 0, cavities = 0;
  for (std::uint64_t seed = 1; seed <= 60; ++seed) {
    Random random(seed);
    const Scene scene = random_scene(random);
    const Surface surface = shuffled_surface(scene, random);
    INFO("seed " << seed << ": " << scene.shells.size() << " shells, " << scene.solids.size() << " solids, "
                 << surface.mesh.triangle_count() << " triangles");
    check_scene(scene, surface);
    solids += scene.solids.size();
    for (const ExpectedSolid& s : scene.solids) cavities += s.shells - 1;
  }
  // The scenes do reach what they are for: many solids, many cavities.
  CHECK(solids > 150);
  CHECK(cavities > 60);
}

TEST_CASE("separation at pinched vertices: one solid per fan, the vertex duplicated", "[separate][property]") {
  // Boxes along a diagonal, each touching the next at one corner: welded, that
  // corner is one vertex shared by two solids.
  for (std::size_t count = 2; count <= 6; ++count) {
    std::vector<Mesh> boxes;
    for (std::size_t i = 0; i < count; ++i) {
      const double lo = static_cast<double>(i);
      boxes.push_back(box({lo, lo, lo}, {lo + 1, lo + 1, lo + 1}));
    }
    const Mesh chain = welded(merge(boxes));
    REQUIRE(chain.positions.size() == 8 * count - (count - 1));
    INFO(count << " boxes");
    const std::vector<Mesh> solids = separate_solids(chain);
    REQUIRE(solids.size() == count);
    for (std::size_t i = 0; i < count; ++i) {
      CHECK(solid_problem(solids[i]) == "");
      CHECK(solids[i].positions.size() == 8);
      CHECK(exact_six_volume(solids[i]) == 6);
      CHECK(canonical_bytes(solids[i]) == canonical_bytes(separate_solids(boxes[i]).front()));
    }
    const std::vector<ExactMesh> exact = separate_solids(to_exact(chain));
    REQUIRE(exact.size() == count);
    for (std::size_t i = 0; i < count; ++i) CHECK(canonical_bytes(to_fast(exact[i])) == canonical_bytes(solids[i]));
  }
}

TEST_CASE("separation keeps a shell no outward shell contains as a solid of its own", "[separate]") {
  // Only a self-intersecting input or a rounded embedding makes one; the output
  // stays closed and oriented, and validation then names the defect.
  const Mesh outside = box({0, 0, 0}, {1, 1, 1});
  const Mesh inward = flipped(box({3, 0, 0}, {4, 1, 1}));  // beside it, not inside
  const Mesh flat = mesh_from({{0, 0, 5}, {1, 0, 5}, {0, 1, 5}}, {{0, 1, 2}, {0, 2, 1}});
  for (const Mesh& lone : {inward, flat}) {
    const std::vector<Mesh> alone = separate_solids(lone);
    REQUIRE(alone.size() == 1);
    CHECK(alone[0].triangle_count() == lone.triangle_count());
    const std::vector<Mesh> solids = separate_solids(merge({lone, outside}));
    REQUIRE(solids.size() == 2);
    CHECK(solid_problem(solids[0]) == "");  // the outward shell first
    CHECK(canonical_bytes(solids[0]) == canonical_bytes(separate_solids(outside).front()));
    CHECK(solids[1].triangle_count() == lone.triangle_count());
    CHECK(exact_six_volume(solids[1]) <= 0);
    CHECK_FALSE(validate_mesh(solids[1]).valid());  // inward, or flat: its two faces meet
  }
}

TEST_CASE("separation refuses a non-manifold edge and reports an open surface", "[separate][errors]") {
  // Two boxes sharing an edge: each of its two directed edges is used twice.
  const Mesh shared_edge = welded(merge({box({0, 0, 0}, {1, 1, 1}), box({1, 1, 0}, {2, 2, 1})}));
  CHECK_THROWS_AS(separate_solids(shared_edge), UnsupportedGeometryError);
  CHECK_THROWS_AS(separate_solids(to_exact(shared_edge)), UnsupportedGeometryError);
  for (std::uint64_t seed = 1; seed <= 12; ++seed) {
    Random random(seed);
    Mesh open = merge({box({0, 0, 0}, {1, 1, 1}), flipped(box({0.25, 0.25, 0.25}, {0.75, 0.75, 0.75}))});
    const std::size_t doomed = random.index(open.triangle_count());
    open.triangles.erase(open.triangles.begin() + static_cast<std::ptrdiff_t>(doomed));
    open.surfaces.erase(open.surfaces.begin() + static_cast<std::ptrdiff_t>(doomed));
    INFO("triangle " << doomed << " removed");
    CHECK_THROWS_AS(separate_solids(open), std::logic_error);
    CHECK_THROWS_AS(separate_solids(to_exact(open)), std::logic_error);
  }
}

TEST_CASE("a hollow egg cut above its cavity keeps the cavity with the outer shell") {
  const Mesh egg = hollow_egg();
  // The cavity reaches z = 1.1; the outer shell z = 1.35.
  const auto top_off = cut_mesh(egg, {{0, 0, 1}, -1.2});
  REQUIRE(top_off.above.size() == 1);
  REQUIRE(top_off.below.size() == 1);
  CHECK(top_off.below[0].triangles.size() > top_off.above[0].triangles.size());
  CHECK(solid_problem(top_off.below[0]) == "");
  // Through the middle: two bowls, each capped by an annulus (two loops).
  const auto halves = cut_mesh(egg, {{0, 0, 1}, 0.013});
  CHECK(halves.below.size() == 1);
  CHECK(halves.above.size() == 1);
  CHECK(halves.cap_loops == 2);
  CHECK(halves.cap_method == CapMethod::cdt);
}

TEST_CASE("nested shells: the island separates from the shell around its cavity") {
  const Mesh nested = nested_shells_with_island();
  const auto result = cut_mesh(nested, {{1, 0.01, 0.02}, -2.0});
  // Each side: the outer shell's half (open cavity now part of its surface) and
  // the island's half.
  CHECK(result.below.size() == 2);
  CHECK(result.above.size() == 2);
  CHECK(result.cap_loops == 3);  // outer boundary, cavity hole, island
  // A cut that misses the cavity: the whole inner structure stays in one solid
  // on one side, with the island as a separate solid inside the cavity.
  const auto side = cut_mesh(nested, {{1, 0, 0}, -0.5});
  CHECK(side.below.size() == 1);
  CHECK(side.above.size() == 2);
}
