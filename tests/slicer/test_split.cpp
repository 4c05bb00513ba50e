// Properties of the plane kernel (kernel/implicit.hpp, kernel/solid.hpp,
// slicer/split.hpp, triangulate/cap_faces.hpp and solid_mesh.hpp,
// meshtree/cut_solid.hpp): its predicates against an independent exact
// evaluation, the bit-length bound of their values at depth, the conversion of
// meshes, chains of cuts in which every piece is exactly valid and rounds to a
// mesh that validates when read back, degenerate planes, and the reproducers of
// the issue that introduced the kernel.

#include <catch2/catch.hpp>

#include <gmpxx.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "shatter/kernel/error.hpp"
#include "shatter/kernel/implicit.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/solid.hpp"
#include "shatter/kernel/validate.hpp"
#include "shatter/meshtree/cut_solid.hpp"
#include "shatter/meshtree/plane_input.hpp"
#include "shatter/triangulate/solid_mesh.hpp"
#include "support/checks.hpp"
#include "support/corpus.hpp"
#include "support/degenerate.hpp"
#include "support/generators.hpp"

using namespace shatter;
using namespace shatter::test;

namespace {

// --- an independent exact evaluation ------------------------------------------------
// Written apart from kernel/src/implicit.cpp (which evaluates over CGAL::Mpzf): GMP
// rationals, straight from the definitions in implicit.hpp.

struct Q3 {
  mpq_class x, y, z;
};
struct Q4 {
  mpq_class a, b, c, d;
};

Q3 q3(const Vec3& p) { return {mpq_class(p.x), mpq_class(p.y), mpq_class(p.z)}; }
Q3 sub(const Q3& a, const Q3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Q3 crossq(const Q3& a, const Q3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
mpq_class dotq(const Q3& a, const Q3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

Q4 reference_plane(const PlaneSet& set, PlaneRef plane) {
  if (plane.is_cut()) {
    const Plane& p = set.cuts[plane.index()];
    return {mpq_class(p.normal.x), mpq_class(p.normal.y), mpq_class(p.normal.z), mpq_class(p.offset)};
  }
  const auto& idx = set.inputs[plane.index()];
  const Q3 p0 = q3(set.points[idx[0]]), p1 = q3(set.points[idx[1]]), p2 = q3(set.points[idx[2]]);
  const Q3 n = crossq(sub(p1, p0), sub(p2, p0));
  return {n.x, n.y, n.z, -dotq(n, p0)};
}

// The point's rational coordinates.
Q3 reference_point(const PlaneSet& set, const PointDef& def) {
  if (def.kind == PointKind::input) return q3(set.points[def.a]);
  if (def.kind == PointKind::segment_plane) {
    const Q3 p = q3(set.points[def.a]), q = q3(set.points[def.b]);
    const Q4 h = reference_plane(set, def.planes[0]);
    const Q3 n{h.a, h.b, h.c};
    const mpq_class at_p = dotq(n, p) + h.d, at_q = dotq(n, q) + h.d;
    const mpq_class t = at_p / (at_p - at_q);  // p + t (q - p)
    return {p.x + t * (q.x - p.x), p.y + t * (q.y - p.y), p.z + t * (q.z - p.z)};
  }
  // Three planes: Cramer's rule.
  Q4 h[3];
  for (int k = 0; k < 3; ++k) h[k] = reference_plane(set, def.planes[k]);
  auto det3 = [](const mpq_class m[3][3]) -> mpq_class {
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  };
  mpq_class a[3][3] = {{h[0].a, h[0].b, h[0].c}, {h[1].a, h[1].b, h[1].c}, {h[2].a, h[2].b, h[2].c}};
  const mpq_class rhs[3] = {-h[0].d, -h[1].d, -h[2].d};
  const mpq_class det = det3(a);
  REQUIRE(det != 0);
  Q3 x;
  mpq_class* out[3] = {&x.x, &x.y, &x.z};
  for (int col = 0; col < 3; ++col) {
    mpq_class m[3][3];
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) m[r][c] = c == col ? rhs[r] : a[r][c];
    }
    *out[col] = det3(m) / det;
  }
  return x;
}

Sign sign_of(const mpq_class& v) { return sgn(v) < 0 ? Sign::negative : sgn(v) > 0 ? Sign::positive : Sign::zero; }

Sign reference_side(const PlaneSet& set, PlaneRef plane, const PointDef& def) {
  const Q4 h = reference_plane(set, plane);
  const Q3 p = reference_point(set, def);
  return sign_of(h.a * p.x + h.b * p.y + h.c * p.z + h.d);
}

// --- a random plane set ----------------------------------------------------------------

// Input points, input planes through triples of them, and cut planes: some
// random, some through chosen input points (exactly, on small lattices) so that
// zero answers and near-zero ones are common.
struct RandomGeometry {
  InputGeometry input;
  std::vector<Plane> cuts;
  PlaneSet set() const { return input.plane_set(cuts); }
};

RandomGeometry random_geometry(Random& random, bool lattice) {
  RandomGeometry g;
  const double scale = lattice ? 1.0 : std::ldexp(1.0, static_cast<int>(random.index(41)) - 20);
  for (int i = 0; i < 12; ++i) {
    Vec3 p;
    if (lattice) {
      p = {static_cast<double>(random.index(9)) - 4, static_cast<double>(random.index(9)) - 4,
           static_cast<double>(random.index(9)) - 4};
    } else {
      p = Vec3{random.uniform(-1, 1), random.uniform(-1, 1), random.uniform(-1, 1)} * scale;
    }
    g.input.points.push_back(p);
  }
  for (int i = 0; i < 6; ++i) {
    std::array<VertexIndex, 3> idx{static_cast<VertexIndex>(random.index(12)), static_cast<VertexIndex>(random.index(12)),
                                   static_cast<VertexIndex>(random.index(12))};
    const Vec3 n = cross(g.input.points[idx[1]] - g.input.points[idx[0]], g.input.points[idx[2]] - g.input.points[idx[0]]);
    if (n.x == 0 && n.y == 0 && n.z == 0) {
      --i;
      continue;
    }
    g.input.planes.push_back(idx);
    g.input.plane_approx.push_back(
        approximate_input_plane(g.input.points[idx[0]], g.input.points[idx[1]], g.input.points[idx[2]]));
  }
  for (int i = 0; i < 6; ++i) {
    Plane p;
    if (lattice) {
      p.normal = {static_cast<double>(random.index(5)) - 2, static_cast<double>(random.index(5)) - 2,
                  static_cast<double>(random.index(5)) - 2};
      if (p.normal.x == 0 && p.normal.y == 0 && p.normal.z == 0) p.normal = {1, 0, 0};
      // Through an input point exactly.
      p.offset = -dot(p.normal, g.input.points[random.index(12)]);
    } else {
      p.normal = random.direction();
      p.offset = -dot(p.normal, g.input.points[random.index(12)]) + (random.index(2) ? 0.0 : random.uniform(-0.1, 0.1) * scale);
    }
    g.cuts.push_back(p);
  }
  return g;
}

// A random point definition over g whose construction is sound (w != 0), or none.
std::optional<PointDef> random_point(const RandomGeometry& g, Random& random) {
  const PlaneSet set = g.set();
  auto plane = [&]() {
    return random.index(2) ? PlaneRef::input(static_cast<std::uint32_t>(random.index(g.input.planes.size())))
                           : PlaneRef::cut(static_cast<std::uint32_t>(random.index(g.cuts.size())));
  };
  PointDef def;
  switch (random.index(3)) {
    case 0: def = PointDef::input(static_cast<std::uint32_t>(random.index(12))); break;
    case 1: {
      const auto p = static_cast<std::uint32_t>(random.index(12)), q = static_cast<std::uint32_t>(random.index(12));
      if (p == q) return std::nullopt;
      def = PointDef::segment_plane(p, q, plane());
      const Q4 h = reference_plane(set, def.planes[0]);
      const Q3 a = q3(set.points[p]), b = q3(set.points[q]);
      if (h.a * (b.x - a.x) + h.b * (b.y - a.y) + h.c * (b.z - a.z) == 0) return std::nullopt;
      break;
    }
    default: {
      def = PointDef::three_planes(plane(), plane(), plane());
      Q4 h[3];
      for (int k = 0; k < 3; ++k) h[k] = reference_plane(set, def.planes[k]);
      const Q3 n0{h[0].a, h[0].b, h[0].c}, n1{h[1].a, h[1].b, h[1].c}, n2{h[2].a, h[2].b, h[2].c};
      if (dotq(n0, crossq(n1, n2)) == 0) return std::nullopt;
    }
  }
  return def;
}

}  // namespace

TEST_CASE("plane kernel predicates agree with an independent exact evaluation", "[plane][predicates]") {
  std::size_t zeros = 0, queries = 0;
  for (std::uint64_t seed = 1; seed <= 60; ++seed) {
    Random random(seed);
    const bool lattice = seed % 2 == 0;
    const RandomGeometry g = random_geometry(random, lattice);
    const PlaneSet set = g.set();
    std::vector<PointDef> defs;
    while (defs.size() < 24) {
      if (auto def = random_point(g, random)) defs.push_back(*def);
    }
    std::vector<ApproxPoint> approx;
    for (const PointDef& def : defs) approx.push_back(approximate(set, def));
    for (std::size_t i = 0; i < defs.size(); ++i) {
      // Sides against every plane of the set.
      for (std::uint32_t k = 0; k < g.input.planes.size() + g.cuts.size(); ++k) {
        const PlaneRef plane = k < g.input.planes.size() ? PlaneRef::input(k)
                                                         : PlaneRef::cut(k - static_cast<std::uint32_t>(g.input.planes.size()));
        const Sign expected = reference_side(set, plane, defs[i]);
        INFO("seed " << seed << " point " << i << " plane " << k);
        CHECK(side(set, plane, defs[i], approx[i]) == expected);
        zeros += expected == Sign::zero ? 1 : 0;
        ++queries;
      }
      // Coordinates: exact, and the rounded position is within the promised
      // bound of them (correctly rounded when the filter cannot bound it).
      const Q3 exact = reference_point(set, defs[i]);
      const std::array<mpq_class, 3> kernel = exact_coordinates(set, defs[i]);
      CHECK(kernel[0] == exact.x);
      CHECK(kernel[1] == exact.y);
      CHECK(kernel[2] == exact.z);
      const Vec3 rounded = rounded_position(set, defs[i], approx[i]);
      for (const auto& [r, e] : {std::pair{rounded.x, exact.x}, std::pair{rounded.y, exact.y}, std::pair{rounded.z, exact.z}}) {
        const mpq_class error = abs(mpq_class(r) - e);
        CHECK(error <= abs(e) * mpq_class(std::ldexp(1.0, -40)) + mpq_class(std::ldexp(1.0, -1074)));
      }
    }
    // Coordinate order and order along lines, on the same points.
    for (std::size_t i = 0; i + 1 < defs.size(); ++i) {
      const Q3 p = reference_point(set, defs[i]), q = reference_point(set, defs[i + 1]);
      for (int axis = 0; axis < 3; ++axis) {
        const mpq_class& pa = axis == 0 ? p.x : axis == 1 ? p.y : p.z;
        const mpq_class& qa = axis == 0 ? q.x : axis == 1 ? q.y : q.z;
        CHECK(compare_coordinate(set, axis, defs[i], approx[i], defs[i + 1], approx[i + 1]) == sign_of(qa - pa));
      }
      const PlaneRef a = PlaneRef::cut(0), b = PlaneRef::cut(1);
      const Q4 ha = reference_plane(set, a), hb = reference_plane(set, b);
      const Q3 direction = crossq({ha.a, ha.b, ha.c}, {hb.a, hb.b, hb.c});
      CHECK(compare_along(set, a, b, defs[i], approx[i], defs[i + 1], approx[i + 1]) ==
            sign_of(dotq(direction, sub(q, p))));
    }
  }
  INFO(zeros << " of " << queries << " sides were exactly zero");
  CHECK(zeros > queries / 50);  // the lattice cases exercise the exact path
}

TEST_CASE("orientation in a plane agrees with an independent exact evaluation", "[plane][predicates]") {
  // Points defined on one cut plane: the meets of that plane with segments and
  // with pairs of other planes, as caps have them.
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    Random random(seed * 7919);
    const RandomGeometry g = random_geometry(random, seed % 2 == 0);
    const PlaneSet set = g.set();
    const PlaneRef on = PlaneRef::cut(0);
    std::vector<PointDef> defs;
    for (int tries = 0; tries < 400 && defs.size() < 10; ++tries) {
      PointDef def;
      if (random.index(2)) {
        const auto p = static_cast<std::uint32_t>(random.index(12)), q = static_cast<std::uint32_t>(random.index(12));
        if (p == q) continue;
        def = PointDef::segment_plane(p, q, on);
      } else {
        const auto pick = [&] {
          return random.index(2) ? PlaneRef::input(static_cast<std::uint32_t>(random.index(g.input.planes.size())))
                                 : PlaneRef::cut(1 + static_cast<std::uint32_t>(random.index(g.cuts.size() - 1)));
        };
        def = PointDef::three_planes(on, pick(), pick());
      }
      try {
        (void)approximate(set, def);
        (void)reference_point(set, def);
      } catch (...) {
        continue;
      }
      if (std::find(defs.begin(), defs.end(), def) == defs.end()) defs.push_back(def);
    }
    std::vector<ApproxPoint> approx;
    std::vector<Q3> exact;
    for (const PointDef& def : defs) {
      approx.push_back(approximate(set, def));
      exact.push_back(reference_point(set, def));
    }
    const Projection projection = projection_of(set, on);
    const Q4 h = reference_plane(set, on);
    const Q3 normal{h.a, h.b, h.c};
    for (std::size_t i = 0; i < defs.size(); ++i) {
      for (std::size_t j = 0; j < defs.size(); ++j) {
        for (std::size_t k = 0; k < defs.size(); ++k) {
          if (i == j || j == k || k == i) continue;
          // Seen from +n: the sign of n · ((q - p) x (r - p)).
          const Sign expected = sign_of(dotq(normal, crossq(sub(exact[j], exact[i]), sub(exact[k], exact[i]))));
          INFO("seed " << seed << " points " << i << " " << j << " " << k);
          CHECK(orient_in_plane(set, projection, defs[i], approx[i], defs[j], approx[j], defs[k], approx[k]) ==
                expected);
        }
      }
    }
  }
}

TEST_CASE("predicate values stay within their bit-length bound at depth 64", "[plane][predicates][bounds]") {
  // Integer inputs of at most b bits: a box with integer corners cut 64 times by
  // planes with integer coefficients; every vertex of every piece, against every
  // plane of the set, has an exact value n·x̃ + d·w (an integer here) of at most
  // side_bound(...).bits(b) bits, whatever the depth that made the point.
  constexpr int b = 20;
  const double big = std::ldexp(1.0, b - 1);
  Mesh mesh = box({-big, -big, -big}, {big, big, big});
  PlaneInput input = prepare_plane_input(mesh);
  std::vector<Plane> cuts;
  Random random(2026);
  std::vector<Solid> pieces{input.solid};
  std::size_t checked = 0;
  int worst_margin = 1 << 20;
  for (int depth = 0; depth < 64; ++depth) {
    // Cut the piece with the most vertices by a plane with integer coefficients
    // through (near) its vertex average.
    std::size_t largest = 0;
    for (std::size_t i = 1; i < pieces.size(); ++i) {
      if (pieces[i].vertex_count() > pieces[largest].vertex_count()) largest = i;
    }
    const Solid solid = pieces[largest];
    Vec3 centre;
    for (const ApproxPoint& a : solid.approx) centre = centre + Vec3{a.x.value / a.w.value, a.y.value / a.w.value, a.z.value / a.w.value};
    centre = centre * (1.0 / static_cast<double>(solid.approx.size()));
    Plane plane;
    plane.normal = {std::round(random.uniform(-big, big)), std::round(random.uniform(-big, big)),
                    std::round(random.uniform(-big, big))};
    // d = -n·c rounded to an integer (|d| < 2^(2b)): the plane's coefficients are
    // then integers of at most 2b bits; the bound below counts d as two inputs.
    plane.offset = -std::round(dot(plane.normal, Vec3{std::round(centre.x), std::round(centre.y), std::round(centre.z)}));
    cuts.push_back(plane);
    const PlaneSet set = input.geometry.plane_set(cuts);
    const SolidCut cut = cut_solid(set, solid, PlaneRef::cut(static_cast<std::uint32_t>(cuts.size() - 1)), 1, input.shells);
    if (cut.plane_missed) continue;
    pieces.erase(pieces.begin() + static_cast<std::ptrdiff_t>(largest));
    for (const auto* side_solids : {&cut.below, &cut.above}) {
      for (const Solid& piece : *side_solids) {
        pieces.push_back(piece);
        for (std::size_t v = 0; v < piece.defs.size(); ++v) {
          const std::array<mpq_class, 4> h = exact_homogeneous(set, piece.defs[v]);
          for (std::uint32_t k = 0; k < cuts.size() + input.geometry.planes.size(); ++k) {
            const PlaneRef ref = k < cuts.size() ? PlaneRef::cut(k) : PlaneRef::input(static_cast<std::uint32_t>(k - cuts.size()));
            const Q4 p = reference_plane(set, ref);
            const mpq_class value = p.a * h[0] + p.b * h[1] + p.c * h[2] + p.d * h[3];
            REQUIRE(value.get_den() == 1);  // integers in, integers out
            const int bits = value == 0 ? 0 : static_cast<int>(mpz_sizeinbase(value.get_num_mpz_t(), 2));
            // Cut offsets carry up to 2b bits: count the inputs at 2b bits each.
            const int bound = side_bound(set, ref, piece.defs[v]).bits(2 * b);
            INFO("depth " << depth << " vertex kind " << int(piece.defs[v].kind) << " bits " << bits << " bound " << bound);
            CHECK(bits <= bound);
            worst_margin = std::min(worst_margin, bound - bits);
            ++checked;
          }
        }
      }
    }
  }
  INFO(checked << " values checked; smallest margin " << worst_margin << " bits");
  CHECK(checked > 50000);
  // The table of implicit.hpp, from the code that evaluates the predicates.
  const PlaneSet set = input.geometry.plane_set(cuts);
  const PlaneRef cut = PlaneRef::cut(1), plane = PlaneRef::input(2);
  const PointDef kinds[] = {PointDef::input(0), PointDef::segment_plane(0, 6, PlaneRef::cut(0)),
                            PointDef::three_planes(PlaneRef::cut(0), PlaneRef::cut(2), PlaneRef::cut(3)),
                            PointDef::three_planes(PlaneRef::input(0), PlaneRef::cut(2), PlaneRef::cut(3))};
  const int against_cut[] = {2, 4, 4, 6}, against_input[] = {4, 5, 6, 7};
  for (int k = 0; k < 4; ++k) {
    INFO("point kind " << k);
    CHECK(side_bound(set, cut, kinds[k]).degree == against_cut[k]);
    CHECK(side_bound(set, plane, kinds[k]).degree == against_input[k]);
    CHECK(side_bound(set, plane, kinds[k]).bits(53) <= 7 * 53 + 12);
  }
  CHECK(orient_bound(set, Projection{2, false}, kinds[3], kinds[3], kinds[3]).degree == 14);
}

TEST_CASE("meshes become sound plane-based solids, coplanar faces merged without attributes", "[plane][solid]") {
  std::vector<NamedMesh> meshes = generated_meshes();
  for (const auto& path : valid_meshes()) meshes.push_back({path.filename().string(), read_mesh(path)});
  REQUIRE(meshes.size() > 20);
  for (const NamedMesh& m : meshes) {
    INFO(m.name);
    const PlaneInput input = prepare_plane_input(m.mesh);
    CHECK(check_solid(input.geometry.plane_set({}), input.solid) == "");
    CHECK(input.solid.faces.size() <= m.mesh.triangle_count());
    CHECK(input.shells.shell_of_triangle.size() == m.mesh.triangle_count());
    // The solid has the mesh's volume exactly.
    CHECK(exact_six_volume(input.geometry.plane_set({}), input.solid) == exact_six_volume(m.mesh));
  }
  const PlaneInput cube = prepare_plane_input(unit_cube());
  CHECK(cube.solid.faces.size() == 6);
  CHECK(cube.solid.convex);
  const PlaneInput seams = prepare_plane_input(with_seams(unit_cube()));
  CHECK(seams.solid.faces.size() == 12);  // attributes: every triangle its own face
  CHECK(seams.solid.convex);
  CHECK_FALSE(prepare_plane_input(torus(3, 1, 16, 8)).solid.convex);
}

namespace {

// Rounds a piece, writes it as OFF and reads it back: empty when what is read is
// the piece's rounded mesh and a valid solid (self-intersections included).
std::string num(double x) {
  std::ostringstream out;
  out.precision(17);
  out << x;
  return out.str();
}

std::string written_problem(const PlaneSet& set, const Solid& piece) {
  const RoundedSolid rounded = round_solid(set, piece);
  if (!rounded.valid) return "cannot be rounded: " + rounded.defect;
  const Mesh read = read_mesh_from_bytes(write_mesh_to_bytes(rounded.mesh, MeshFormat::off), MeshFormat::off);
  // The reader numbers vertices by first use: compare triangle by triangle.
  if (read.triangles.size() != rounded.mesh.triangles.size()) return "read back with another triangle count";
  for (std::size_t t = 0; t < read.triangles.size(); ++t) {
    for (int c = 0; c < 3; ++c) {
      if (!(read.positions[read.triangles[t][c]] == rounded.mesh.positions[rounded.mesh.triangles[t][c]])) {
        return "read back with other positions";
      }
    }
  }
  const ValidationReport report = validate_mesh(read);
  return report.valid() ? std::string() : "read back invalid: " + report.summary();
}

// 64 successive cuts of one solid: each time the largest piece (by approximate
// volume) is cut by a random plane through its vertex average. Every piece made
// is checked: sound (check_solid), exact volumes of the two sides summing to the
// cut piece's exactly, and written as a mesh that validates read back.
void check_cut_chain(const std::string& name, const Mesh& mesh, std::uint64_t seed, int cuts_wanted) {
  INFO(name << " seed " << seed);
  PlaneInput input = prepare_plane_input(mesh);
  std::vector<Plane> cuts;
  cuts.reserve(static_cast<std::size_t>(cuts_wanted));
  Random random(seed);
  struct Piece {
    Solid solid;
    mpq_class six;
    double volume;
  };
  std::vector<Piece> pieces;
  {
    const PlaneSet set = input.geometry.plane_set(cuts);
    const mpq_class six = exact_six_volume(set, input.solid);
    pieces.push_back({input.solid, six, six.get_d()});
  }
  int made = 0;
  for (int attempt = 0; made < cuts_wanted && attempt < 4 * cuts_wanted; ++attempt) {
    std::size_t largest = 0;
    for (std::size_t i = 1; i < pieces.size(); ++i) {
      if (pieces[i].volume > pieces[largest].volume) largest = i;
    }
    const Solid& solid = pieces[largest].solid;
    Vec3 centre;
    for (const ApproxPoint& a : solid.approx) centre = centre + Vec3{a.x.value / a.w.value, a.y.value / a.w.value, a.z.value / a.w.value};
    centre = centre * (1.0 / static_cast<double>(solid.approx.size()));
    const Vec3 normal = random.direction();
    cuts.push_back({normal, -dot(normal, centre)});
    const PlaneSet set = input.geometry.plane_set(cuts);
    const PlaneRef cut_plane = PlaneRef::cut(static_cast<std::uint32_t>(cuts.size() - 1));
    const SolidCut cut = cut_solid(set, solid, cut_plane, static_cast<SurfaceId>(1 + cuts.size()), input.shells);
    if (cut.plane_missed) continue;
    ++made;
    mpq_class sum = 0;
    std::vector<Piece> made_pieces;
    // The two sides meet along the cap: the vertices on the cut plane must be
    // the same exact points on both sides, and must round to the same doubles,
    // or neighbouring fragments would not share their cap corners as written.
    std::array<std::vector<std::array<mpq_class, 3>>, 2> on_cap_exact;
    std::array<std::vector<Vec3>, 2> on_cap_written;
    for (int side = 0; side < 2; ++side) {
      for (const Solid& piece : side == 0 ? cut.below : cut.above) {
        for (std::size_t v = 0; v < piece.vertex_count(); ++v) {
          if (reference_side(set, cut_plane, piece.defs[v]) != Sign::zero) continue;
          const Q3 q = reference_point(set, piece.defs[v]);
          on_cap_exact[side].push_back({q.x, q.y, q.z});
          on_cap_written[side].push_back(output_position(set, piece.defs[v], piece.approx[v]));
        }
      }
      std::sort(on_cap_exact[side].begin(), on_cap_exact[side].end());
      on_cap_exact[side].erase(std::unique(on_cap_exact[side].begin(), on_cap_exact[side].end()), on_cap_exact[side].end());
      std::sort(on_cap_written[side].begin(), on_cap_written[side].end(), [](const Vec3& a, const Vec3& b) {
        return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
      });
      on_cap_written[side].erase(std::unique(on_cap_written[side].begin(), on_cap_written[side].end(),
                                             [](const Vec3& a, const Vec3& b) { return a == b; }),
                                 on_cap_written[side].end());
    }
    CHECK(on_cap_exact[0].size() >= 3);
    CHECK(on_cap_exact[0] == on_cap_exact[1]);
    CHECK(on_cap_written[0] == on_cap_written[1]);
    for (const auto* side_solids : {&cut.below, &cut.above}) {
      for (const Solid& piece : *side_solids) {
        INFO("cut " << made << " piece of " << piece.faces.size() << " faces");
        REQUIRE(check_solid(set, piece) == "");
        const mpq_class six = exact_six_volume(set, piece);
        CHECK(six > 0);
        sum += six;
        CHECK(written_problem(set, piece) == "");
        made_pieces.push_back({piece, six, six.get_d()});
      }
    }
    CHECK(sum == pieces[largest].six);
    pieces.erase(pieces.begin() + static_cast<std::ptrdiff_t>(largest));
    for (Piece& p : made_pieces) pieces.push_back(std::move(p));
  }
  CHECK(made == cuts_wanted);
}

}  // namespace

TEST_CASE("chains of 64 cuts: every piece exactly valid, volumes exact, valid as written", "[plane][cut][heavy]") {
  for (const NamedMesh& m : generated_meshes()) {
    for (const std::uint64_t seed : {1u, 2u}) check_cut_chain(m.name, m.mesh, seed, 64);
  }
  for (const char* file : {"cube.off", "knot1.off", "fandisk.off", "elephant.off"}) {
    check_cut_chain(file, read_mesh(mesh_dir() / file), 3, 64);
  }
}

namespace {

// Lattice solids and planes: exactly through vertices, along edges, holding
// faces; then the same planes moved 1 to 4 ulps, which leaves slivers as thin as
// the rounding of their coordinates (at x = 0 an ulp is 4.9e-324). Every cut is
// exact. Written pieces must validate when read back; the only allowed failure is
// a clean refusal to round a piece, and only for the moved planes (a sliver
// thinner than doubles resolve), counted against a ceiling. A plane that touches
// the surface inside the solid (a cavity's corner on it) pinches a piece:
// cut_solid refuses that, counted too. `stride`: every stride-th vertex and
// triangle gives planes (1: all of them).
void check_degenerate_planes(std::size_t stride) {
  const std::vector<NamedMesh> solids = {{"staircase", staircase(4)},       {"stacked", stacked_boxes(4)},
                                         {"grid-box", grid_box({0, 0, 0}, {4, 4, 4}, 4)},
                                         {"pinch-saddle", pinch_saddle()},  {"nested-islands", nested_islands()},
                                         {"needle", needle_bridge(std::ldexp(1.0, -20))},
                                         {"flat-tet", flat_tetrahedron(std::ldexp(1.0, -30))}};
  std::size_t pieces = 0, exact_zeros = 0, moved_refused = 0, pinched = 0, cuts_made = 0;
  for (const NamedMesh& m : solids) {
    const PlaneInput input = prepare_plane_input(m.mesh);
    std::vector<Plane> planes;
    for (std::size_t v = 0; v < m.mesh.positions.size(); v += stride) {
      for (int axis = 0; axis < 3; ++axis) planes.push_back(axis_plane_through(m.mesh.positions[v], axis));
    }
    for (std::size_t t = 0; t < m.mesh.triangles.size(); t += 3 * stride) {
      const Triangle& tri = m.mesh.triangles[t];
      planes.push_back(plane_through_points(m.mesh.positions[tri[0]], m.mesh.positions[tri[1]], m.mesh.positions[tri[2]]));
      planes.push_back(plane_through(m.mesh.positions[tri[0]], Vec3{1, 1, 0}));  // x + y = const: a vertex, up to rounding
    }
    const std::size_t exact_count = planes.size();
    for (std::size_t i = 0; i < exact_count; ++i) {
      planes.push_back(offset_by_ulps(planes[i], 1 + static_cast<int>(i % 4)));
      planes.push_back(offset_by_ulps(planes[i], -1 - static_cast<int>(i % 3)));
    }
    for (std::size_t i = 0; i < planes.size(); ++i) {
      const Plane& plane = planes[i];
      if (plane.normal.x == 0 && plane.normal.y == 0 && plane.normal.z == 0) continue;
      const bool moved = i >= exact_count;
      INFO(m.name << " plane " << i << (moved ? " (moved)" : "") << ": " << num(plane.normal.x) << " " << num(plane.normal.y)
                  << " " << num(plane.normal.z) << " " << num(plane.offset));
      exact_zeros += plane_contact(m.mesh, plane).on;
      const std::vector<Plane> cuts{plane};
      const PlaneSet set = input.geometry.plane_set(cuts);
      SolidCut cut;
      try {
        cut = cut_solid(set, input.solid, PlaneRef::cut(0), 1, input.shells);
      } catch (const UnsupportedGeometryError& error) {
        CHECK(std::string(error.what()).find("pinched") != std::string::npos);
        ++pinched;
        continue;
      }
      if (cut.plane_missed) continue;
      ++cuts_made;
      mpq_class sum = 0;
      for (const auto* side_solids : {&cut.below, &cut.above}) {
        for (const Solid& piece : *side_solids) {
          REQUIRE(check_solid(set, piece) == "");
          sum += exact_six_volume(set, piece);
          const std::string problem = written_problem(set, piece);
          if (moved && problem.rfind("cannot be rounded", 0) == 0) {
            ++moved_refused;
          } else {
            CHECK(problem == "");
          }
          ++pieces;
        }
      }
      CHECK(sum == exact_six_volume(m.mesh));
    }
  }
  INFO(cuts_made << " cuts, " << pieces << " pieces, " << exact_zeros << " vertex contacts, " << moved_refused
                 << " pieces of moved planes refused, " << pinched << " pinching planes refused");
  CHECK(pieces > 1000 / stride);
  CHECK(exact_zeros > 1000 / stride);
  // Ceilings measured when written (2026-12-01: 67 and 182 of 13,519 cuts): a
  // change that refuses more is a regression to look at. The refused pieces are
  // slivers thinner than the rounding of their coordinates that doubles cannot
  // hold exactly (a moved plane 1-4 ulps from a face); the pinching planes hold a
  // concave edge or a cavity's corner of a lattice solid.
  CHECK(moved_refused <= 67);
  CHECK(pinched <= 182);
}

}  // namespace

TEST_CASE("degenerate planes: through vertices, edges and faces, exactly and a few ulps off", "[plane][cut][degenerate]") {
  check_degenerate_planes(7);
}

TEST_CASE("degenerate planes: every vertex, edge and face of the lattice solids", "[plane][cut][degenerate][heavy]") {
  check_degenerate_planes(1);
}

TEST_CASE("regression: a plane through a vertex up to rounding no longer writes an invalid piece", "[plane][regression]") {
  // The reproducer: `shatter slice elephant.off --plane 1,1,0,-0.062960299999999997`
  // (x + y + d = 0 through a vertex, d the rounded -(x + y)) wrote pieces that
  // `shatter validate` refused. Here: that plane and the same construction
  // through 48 vertices of the elephant and of a generated ellipsoid.
  const Mesh elephant = read_mesh(mesh_dir() / "elephant.off");
  const Mesh ellipsoid_mesh = ellipsoid({0.1, 0.2, 0.3}, {1.3, 0.7, 0.9}, 24, 16);
  for (const Mesh* mesh : {&elephant, &ellipsoid_mesh}) {
    const PlaneInput input = prepare_plane_input(*mesh);
    std::vector<Plane> planes;
    if (mesh == &elephant) planes.push_back({{1, 1, 0}, -0.062960299999999997});
    Random random(12);
    for (int k = 0; k < 48; ++k) {
      const Vec3 p = mesh->positions[random.index(mesh->positions.size())];
      planes.push_back({{1, 1, 0}, -(p.x + p.y)});
    }
    std::size_t written = 0;
    for (const Plane& plane : planes) {
      const std::vector<Plane> cuts{plane};
      const PlaneSet set = input.geometry.plane_set(cuts);
      const SolidCut cut = cut_solid(set, input.solid, PlaneRef::cut(0), 1, input.shells);
      for (const auto* side_solids : {&cut.below, &cut.above}) {
        for (const Solid& piece : *side_solids) {
          INFO("plane x + y + " << plane.offset);
          CHECK(written_problem(set, piece) == "");
          ++written;
        }
      }
    }
    CHECK(written > 2 * planes.size() - 10);
  }
}
