// The plane kernel's split of a solid (slicer/split.hpp), driven through the
// full cut (meshtree/cut_solid.hpp) as the builder drives it: chains of cuts in
// which every piece is exactly valid and rounds to a mesh that validates when
// read back, degenerate planes through vertices, edges and faces and a few ulps
// off them, and the bit-length bound of predicate values at depth 64, which
// holds because a split never builds a point from another constructed point.

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
#include "shatter/kernel/rationals.hpp"
#include "shatter/kernel/solid.hpp"
#include "shatter/cut/cut_solid.hpp"
#include "shatter/cut/plane_input.hpp"
#include "shatter/slicer/split.hpp"
#include "support/checks.hpp"
#include "support/sanitizers.hpp"
#include "shatter/generators/corpus.hpp"
#include "support/degenerate.hpp"
#include "shatter/generators/random.hpp"
#include "shatter/generators/solids.hpp"
#include "support/implicit_reference.hpp"
#include "support/written_back.hpp"

using namespace shatter;
using namespace shatter::test;

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

namespace {

// A double in full (17 significant digits), for messages.
std::string num(double x) {
  std::ostringstream out;
  out.precision(17);
  out << x;
  return out.str();
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
    // One side alone (CutSides) is that side of the full cut, exactly.
    for (const CutSides one_side : {CutSides::below, CutSides::above}) {
      const SolidCut alone =
          cut_solid(set, solid, cut_plane, static_cast<SurfaceId>(1 + cuts.size()), input.shells, one_side);
      const bool below = one_side == CutSides::below;
      CHECK_FALSE(alone.plane_missed);
      CHECK((below ? alone.above : alone.below).empty());
      CHECK(same_solids(below ? alone.below : alone.above, below ? cut.below : cut.above));
    }
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

// The same property at a size CI runs on every change; the 64-cut chains below are
// the [heavy] run's (tests/CMakeLists.txt).
TEST_CASE("chains of 12 cuts: every piece exactly valid, volumes exact, valid as written", "[plane][cut]") {
  for (const NamedMesh& m : generated_meshes()) check_cut_chain(m.name, m.mesh, 1, 12);
  for (const char* file : {"cube.off", "knot1.off"}) check_cut_chain(file, read_mesh(mesh_dir() / file), 3, 12);
}

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
// thinner than doubles resolve), counted against a ceiling. No cut is refused:
// two pieces meeting along a concave edge across the cap each get their cap
// face, a piece that meets itself along one gets copies of its ends (cut_solid),
// and a cavity's corner on the plane, where a piece touches itself at a point,
// is written: round_solid separates it. `stride`: every stride-th vertex and
// triangle gives planes (1: all of them). Each count has a ceiling measured for
// its stride: a change that refuses more is a regression to look at.
void check_degenerate_planes(std::size_t stride, std::size_t moved_refused_ceiling) {
  const std::vector<NamedMesh> solids = {{"staircase", staircase(4)},       {"stacked", stacked_boxes(4)},
                                         {"grid-box", grid_box({0, 0, 0}, {4, 4, 4}, 4)},
                                         {"pinch-saddle", pinch_saddle()},  {"nested-islands", nested_islands()},
                                         {"needle", needle_bridge(std::ldexp(1.0, -20))},
                                         {"flat-tet", flat_tetrahedron(std::ldexp(1.0, -30))}};
  std::size_t pieces = 0, exact_zeros = 0, moved_refused = 0, cuts_made = 0;
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
        FAIL_CHECK("refused: " << error.what());
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
                 << " pieces of moved planes refused");
  CHECK(pieces > 1000 / stride);
  CHECK(exact_zeros > 1000 / stride);
  // The refused pieces are slivers thinner than the rounding of their
  // coordinates that doubles cannot hold exactly (a moved plane 1-4 ulps from a
  // face).
  CHECK(moved_refused <= moved_refused_ceiling);
}

}  // namespace

TEST_CASE("degenerate planes: through vertices, edges and faces, exactly and a few ulps off", "[plane][cut][degenerate]") {
  // Measured 2026-12-03: no piece and no plane refused, of 1,976 cuts, once round_solid
  // repaired what rounding breaks (2026-12-02: 15 pieces of moved planes; 27 pinching
  // planes before points where a piece touches itself were separated and caps split
  // along concave edges across them).
  // Under the sanitizers every third of those vertices and faces (sanitizers.hpp).
  check_degenerate_planes(test::sized(7, 21), 0);
}

TEST_CASE("degenerate planes: every vertex, edge and face of the lattice solids", "[plane][cut][degenerate][heavy]") {
  // Measured 2026-12-03: no piece and no plane refused, of 13,701 cuts, once round_solid merged
  // opposite faces rounded onto one plane (11 pieces before, all the slab between needle-bridge's
  // face x = 1 and a plane 1-4 ulps from it: tests/regressions/unroundable-slab-rounded-onto-a-face-
  // needle-bridge-x-plane-ulps.repro; 67 before round_solid repaired what rounding breaks; 182
  // pinching planes of 13,519 cuts before points where a piece touches itself were separated and
  // caps split along concave edges across them).
  check_degenerate_planes(1, 0);
}

namespace {

bool same_border(const std::vector<LoopEdge>& a, const std::vector<LoopEdge>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].from != b[i].from || a[i].to != b[i].to || !(a[i].line == b[i].line)) return false;
  }
  return true;
}

// The one-sided cut (CutSides below or above, which leaves out the faces lying
// whole on the other side when no vertex is on the plane: split_solid's
// SplitSides) against the full cut, on one piece and one plane: the split's kept
// side, border, new vertices and sides, and the cut's pieces, field by field.
// Returns whether the split left the other side's whole faces out.
bool check_one_side(const PlaneSet& set, const Solid& solid, PlaneRef plane, const InputShells& shells) {
  SplitSolid full, alone;
  split_solid(set, solid, plane, full);
  CHECK_FALSE(full.other_side_partial);
  const SolidCut both = cut_solid(set, solid, plane, 7, shells);
  bool partial = false;
  for (const bool below : {true, false}) {
    split_solid(set, solid, plane, alone, below ? SplitSides::below : SplitSides::above);
    CHECK(alone.plane_misses == full.plane_misses);
    CHECK(alone.all_below == full.all_below);
    const bool any_on = std::find(full.sides.begin(), full.sides.begin() + static_cast<std::ptrdiff_t>(solid.vertex_count()),
                                  Sign::zero) != full.sides.begin() + static_cast<std::ptrdiff_t>(solid.vertex_count());
    CHECK(alone.other_side_partial == !any_on);
    partial = partial || (alone.other_side_partial && !alone.plane_misses);
    if (!full.plane_misses) {
      CHECK(alone.defs == full.defs);
      CHECK(alone.sides == full.sides);
      CHECK(same_border(alone.border, full.border));
      CHECK(same_faces(below ? alone.below : alone.above, below ? full.below : full.above));
      if (!alone.other_side_partial) CHECK(same_faces(below ? alone.above : alone.below, below ? full.above : full.below));
    }
    const SolidCut one = cut_solid(set, solid, plane, 7, shells, below ? CutSides::below : CutSides::above);
    CHECK(one.plane_missed == both.plane_missed);
    CHECK(one.all_below == both.all_below);
    CHECK(one.cap_faces == both.cap_faces);
    CHECK(one.cap_loops == both.cap_loops);
    CHECK((below ? one.above : one.below).empty());
    CHECK(same_solids(below ? one.below : one.above, below ? both.below : both.above));
  }
  // The pieces' convexity, decided while separating them, is solid_is_convex's.
  for (const auto* side_solids : {&both.below, &both.above}) {
    for (const Solid& piece : *side_solids) CHECK(piece.convex == solid_is_convex(set, piece));
  }
  return partial;
}

}  // namespace

// What a Voronoi cell's cuts do (meshtree/voronoi.cpp): chains of one-sided cuts,
// each keeping one side, from the whole solid down to small convex pieces, by
// random planes near the piece's vertex average and, every third cut, by an axis
// plane through one of its input vertices (vertices on the plane: the full
// split). Each cut is the full cut's side exactly.
TEST_CASE("one side alone is that side of the full cut exactly, the other side's whole faces left out",
          "[plane][cut]") {
  std::vector<NamedMesh> meshes = generated_meshes();
  for (const char* file : {"cube.off", "knot1.off", "fandisk.off", "elephant.off"}) {
    meshes.push_back({file, read_mesh(mesh_dir() / file)});
  }
  meshes.push_back({"staircase", staircase(4)});
  meshes.push_back({"grid-box", grid_box({0, 0, 0}, {4, 4, 4}, 4)});
  std::size_t partial = 0, full = 0, convex_pieces = 0;
  for (const NamedMesh& m : meshes) {
    const PlaneInput input = prepare_plane_input(m.mesh);
    for (const std::uint64_t seed : {1u, 2u, 3u}) {
      INFO(m.name << " seed " << seed);
      Random random(seed);
      std::vector<Plane> cuts;
      Solid piece = input.solid;
      for (int k = 0; k < 24; ++k) {
        Vec3 centre;
        for (const ApproxPoint& a : piece.approx) {
          centre = centre + Vec3{a.x.value / a.w.value, a.y.value / a.w.value, a.z.value / a.w.value};
        }
        centre = centre * (1.0 / static_cast<double>(piece.approx.size()));
        std::uint32_t input_vertex = no_index;
        for (std::size_t v = 0; v < piece.vertex_count() && input_vertex == no_index; ++v) {
          const std::size_t at = (v + static_cast<std::size_t>(random.index(piece.vertex_count()))) % piece.vertex_count();
          if (piece.defs[at].kind == PointKind::input) input_vertex = piece.defs[at].a;
        }
        if (k % 3 == 2 && input_vertex != no_index) {
          cuts.push_back(axis_plane_through(m.mesh.positions[input_vertex], k % 3));
        } else {
          const Vec3 normal = random.direction();
          cuts.push_back({normal, -dot(normal, centre + random.direction() * 1e-3)});
        }
        const PlaneSet set = input.geometry.plane_set(cuts);
        const PlaneRef plane = PlaneRef::cut(static_cast<std::uint32_t>(cuts.size() - 1));
        (check_one_side(set, piece, plane, input.shells) ? partial : full) += 1;
        const bool below = random.index(2) == 0;
        SolidCut cut = cut_solid(set, piece, plane, 7, input.shells, below ? CutSides::below : CutSides::above);
        std::vector<Solid>& kept = below ? cut.below : cut.above;
        if (cut.plane_missed || kept.empty()) continue;
        piece = std::move(kept.front());
        REQUIRE(check_solid(set, piece) == "");
        convex_pieces += piece.convex;
      }
    }
  }
  INFO(partial << " cuts left the other side's faces out, " << full << " made both sides, " << convex_pieces
               << " convex pieces kept");
  CHECK(partial > 200);
  CHECK(full > 50);
  CHECK(convex_pieces > 50);
}
