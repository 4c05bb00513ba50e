// The plane kernel's one cut call (meshtree/plane_cut.hpp) on planes through
// vertices, where a cut of a valid solid can leave a piece that touches itself
// exactly (a saddle vertex of the surface on the plane whose lobes on one side
// are one piece; a cavity's corner on the cap) or a piece thinner than the
// rounding of its coordinates. Properties over every corpus mesh and generated
// solids: no refusal; every piece either certified (the full validator agrees,
// and what is written reads back valid) or vanished (no triangles, thinner than
// its rounding); the volumes add up to the input's exactly before rounding and
// within the moved volumes after; every move within its bound.

#include <catch2/catch.hpp>

#include <gmpxx.h>

#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "shatter/kernel/error.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/mass.hpp"
#include "shatter/kernel/rationals.hpp"
#include "shatter/kernel/validate.hpp"
#include "shatter/cut/cut_solid.hpp"
#include "shatter/cut/plane_cut.hpp"
#include "shatter/cut/plane_input.hpp"
#include "shatter/generators/corpus.hpp"
#include "shatter/generators/random.hpp"
#include "shatter/generators/solids.hpp"
#include "support/checks.hpp"
#include "support/degenerate.hpp"
#include "support/sanitizers.hpp"

using namespace shatter;
using namespace shatter::test;

namespace {

struct Tally {
  std::size_t cuts = 0, pieces = 0, separated = 0, vanished = 0;
};

// Cuts `mesh` by `plane` and checks every property of the file comment.
void check_cut(const Mesh& mesh, const Plane& plane, Tally& tally) {
  const PlaneInput input = prepare_plane_input(mesh);
  const Plane cuts[] = {plane};
  const PlaneSet set = input.geometry.plane_set(cuts);
  PlaneCut cut;
  try {
    cut = cut_by_plane(input, set, input.solid, &input.mesh, PlaneRef::cut(0));
  } catch (const UnsupportedGeometryError& error) {
    FAIL_CHECK("refused: " << error.what());
    return;
  }
  ++tally.cuts;
  if (cut.plane_missed) return;
  mpq_class exact_six = 0;
  double written_volume = 0, moved = 0;
  const double scale = largest_coordinate(mesh);
  for (const CutPiece& piece : cut.pieces) {
    ++tally.pieces;
    CHECK(check_solid(set, piece.solid) == "");
    exact_six += exact_six_volume(set, piece.solid);
    if (piece.vanished) {
      ++tally.vanished;
      CHECK(piece.mesh.triangles.empty());
      CHECK(!piece.defect.empty());
      // Thinner than its rounding: its volume is below an ulp's slab over the input's area.
      CHECK(std::fabs(piece.moved_volume) <= surface_area(mesh) * std::ldexp(scale, -44));
      moved += std::fabs(piece.moved_volume);
      continue;
    }
    REQUIRE(piece.defect == "");
    const ValidationReport report = validate_mesh(piece.mesh);
    CHECK(report.summary() == "valid");
    const Mesh read = read_mesh_from_bytes(write_mesh_to_bytes(piece.mesh, MeshFormat::off), MeshFormat::off);
    CHECK(validate_mesh(read).valid());
    written_volume += signed_volume(piece.mesh);
    if (piece.separated_vertices > 0) {
      ++tally.separated;
      CHECK(piece.moved_volume <= piece.moved_volume_bound * (1 + 1e-12));
      moved += piece.moved_volume_bound;
    } else {
      CHECK(piece.moved_volume == 0);
    }
  }
  // Exactly, the pieces partition the input.
  CHECK(exact_six == exact_six_volume(set, input.solid));
  // As written, up to the rounding of coordinates (relative 1e-12 of the surface
  // over the size) and the moves.
  const double input_volume = signed_volume(mesh);
  CHECK(std::fabs(written_volume - input_volume) <= moved + 1e-12 * surface_area(mesh) * scale);
}

// Planes through vertices of `mesh`: axis-aligned, x + y = const (through the
// vertex up to rounding) and random normals with the offset rounded.
std::vector<Plane> planes_through_vertices(const Mesh& mesh, std::size_t count, std::uint64_t seed) {
  Random random(seed);
  std::vector<Plane> planes;
  for (std::size_t k = 0; k < count; ++k) {
    const Vec3 v = mesh.positions[random.index(mesh.positions.size())];
    Vec3 n;
    switch (k % 3) {
      case 0: n = {0, 1, 0}; break;
      case 1: n = {1, 1, 0}; break;
      default: n = random.direction(); break;
    }
    planes.push_back({n, -(n.x * v.x + n.y * v.y + n.z * v.z)});
  }
  return planes;
}

}  // namespace

TEST_CASE("a concave edge across the cap: each piece along it gets its own cap face", "[plane][cut]") {
  // A bar with a V groove along its top whose bottom edge lies on the plane z = 1
  // (Manifold writes the same three pieces): below, the bar under the groove;
  // above, the two ridges, which meet only along the edge.
  const Mesh groove = prism({{0, 0}, {4, 0}, {4, 2}, {3, 2}, {2, 1}, {1, 2}, {0, 2}}, {{0, 1, 2, 3, 4, 5, 6}},
                            {{0, 1, 4}, {1, 2, 3}, {1, 3, 4}, {0, 4, 5}, {0, 5, 6}}, 3);
  REQUIRE(validate_mesh(groove).summary() == "valid");
  for (const double scale : {1.0, 0.1, 3e5}) {
    INFO("scale " << scale);
    const Mesh mesh = transformed(groove, scale, {0.25, -1, 0.5});
    const Vec3 edge_point = mesh.positions[4];
    Tally tally;
    for (const Vec3 normal : {Vec3{0, 0, 1}, Vec3{0, 0, -1}}) {
      check_cut(mesh, {normal, -dot(normal, edge_point)}, tally);
    }
    CHECK(tally.pieces == 6);
    const PlaneCut cut = cut_mesh_by_plane(mesh, {{0, 0, 1}, -edge_point.z});
    CHECK(std::count_if(cut.pieces.begin(), cut.pieces.end(), [](const CutPiece& p) { return p.above; }) == 2);
    CHECK(cut.pieces.size() == 3);
  }
}

namespace {

// Checks one exact piece as a solid: sound (check_solid: every edge run once
// each way), positive volume.
void check_exact_piece(const PlaneSet& set, const Solid& solid) {
  CHECK(check_solid(set, solid) == "");
  CHECK(exact_six_volume(set, solid) > 0);
}

// The tunnel block of the test below: a block with a diamond tunnel along y
// whose lowest edge (x = 2, z = 1) lies on the plane z = 1.
Mesh tunnel_block() {
  return prism({{0, 0}, {4, 0}, {4, 4}, {0, 4}, {2, 1}, {3, 2}, {2, 3}, {1, 2}}, {{0, 1, 2, 3}, {4, 7, 6, 5}},
               {{0, 1, 4}, {1, 2, 5}, {1, 5, 4}, {2, 3, 6}, {2, 6, 5}, {3, 0, 7}, {3, 7, 6}, {0, 4, 7}}, 3);
}

}  // namespace

TEST_CASE("a concave edge across the cap with one piece on both sides: the piece is written, its sheets moved apart",
          "[plane][cut][regression]") {
  // A block with a diamond tunnel whose lowest edge lies on z = 1: above it, the
  // block around the tunnel is one piece that meets itself along the edge. It
  // was refused ("pinched along the edge"); now each sheet there has its own
  // copies of the edge's ends in the exact piece, which round_solid moves apart.
  for (const double scale : {1.0, 1e-3, 3e5}) {
    INFO("scale " << scale);
    const Mesh tunnel = transformed(tunnel_block(), scale, {0.25, -1, 0.5});
    REQUIRE(validate_mesh(tunnel).summary() == "valid");
    const double z = tunnel.positions[4].z;
    for (const Vec3 normal : {Vec3{0, 0, 1}, Vec3{0, 0, -1}}) {
      Tally tally;
      check_cut(tunnel, {normal, -dot(normal, tunnel.positions[4])}, tally);
      CHECK(tally.pieces == 2);
      CHECK(tally.separated == 1);
    }
    const PlaneCut cut = cut_mesh_by_plane(tunnel, {{0, 0, 1}, -z});
    REQUIRE(cut.pieces.size() == 2);
    // A plane a hair above the edge cuts the tunnel's walls: no pinch exactly
    // (rounding the cut points onto the edge may make one, which is separated).
    Tally tally;
    check_cut(tunnel, {{0, 0, 1}, -std::nextafter(z, 2 * z + 1)}, tally);
    CHECK(tally.pieces == 2);
  }
}

TEST_CASE("a piece that meets itself along an edge cuts again: through the edge, along it, through its ends",
          "[plane][cut]") {
  // The exact piece above the tunnel's pinch, cut by a second plane: across the
  // pinched segment (its two sheets' edges cut at one point), holding it, through
  // one of its ends, and random planes through those. Every piece is sound
  // exactly and written valid, and the volumes add up exactly.
  const Mesh tunnel = tunnel_block();
  const PlaneInput input = prepare_plane_input(tunnel);
  std::vector<Plane> second{{{0, 1, 0}, -1.5}, {{1, 0, 0}, -2}, {{0, 1, 0}, 0}, {{1, 1, 0}, -2},
                            {{1, -1, 0}, -2}, {{0, 1, 1}, -2.5}, {{1, 0, 1}, -3}, {{-1, 0, 1}, 1}};
  Random random(29);
  for (int k = 0; k < 12; ++k) {
    const Vec3 n = random.direction();
    const Vec3 through = k % 2 == 0 ? Vec3{2, 0, 1} : Vec3{2, 1.25, 1};
    second.push_back({n, -dot(n, through)});
  }
  std::size_t written = 0, separated = 0;
  for (const Plane& plane : second) {
    INFO("second plane " << plane.normal.x << " " << plane.normal.y << " " << plane.normal.z << " " << plane.offset);
    const Plane cuts[] = {{{0, 0, 1}, -1}, plane};
    const PlaneSet set = input.geometry.plane_set(cuts);
    const PlaneCut first = cut_by_plane(input, set, input.solid, &input.mesh, PlaneRef::cut(0));
    for (const CutPiece& piece : first.pieces) {
      check_exact_piece(set, piece.solid);
      REQUIRE(piece.defect == "");
      if (!piece.above) continue;
      const PlaneCut again = cut_by_plane(input, set, piece.solid, nullptr, PlaneRef::cut(1));
      if (again.plane_missed) continue;
      mpq_class six = 0;
      for (const CutPiece& part : again.pieces) {
        check_exact_piece(set, part.solid);
        six += exact_six_volume(set, part.solid);
        if (part.vanished) continue;
        CHECK(part.defect == "");
        CHECK(validate_mesh(part.mesh).summary() == "valid");
        ++written;
        separated += part.separated_vertices > 0;
      }
      CHECK(six == exact_six_volume(set, piece.solid));
    }
  }
  CHECK(written >= second.size());
  CHECK(separated >= 1);
}

TEST_CASE("tunnels of random shapes cut along their lowest edge: every piece sound, written valid, cut again",
          "[plane][cut][property]") {
  // The tunnel block with its four-sided tunnel drawn at random (its lowest
  // edge kept on z = 1), its length, scale and place drawn too: the plane
  // z = 1 leaves the block above meeting itself along the edge. Every piece is
  // sound exactly and written valid (check_cut), and the piece above cut again
  // by a random plane through an end of the edge is too.
  Random random(41);
  std::size_t tunnels = 0, separated = 0, again = 0;
  for (int seed = 0; seed < 24; ++seed) {
    const double right_x = 2 + random.uniform(0.3, 1.5), right_z = 1 + random.uniform(0.2, 1.5);
    const double left_x = 2 - random.uniform(0.3, 1.5), left_z = 1 + random.uniform(0.2, 1.5);
    const double top_x = 2 + random.uniform(-0.4, 0.4), top_z = std::max(right_z, left_z) + random.uniform(0.2, 0.8);
    const double length = random.uniform(1, 5), scale = std::pow(10.0, random.uniform(-3, 3));
    const Vec3 shift{random.uniform(-1, 1), random.uniform(-1, 1), random.uniform(-1, 1)};
    const Mesh block = prism({{0, 0}, {4, 0}, {4, 4}, {0, 4}, {2, 1}, {right_x, right_z}, {top_x, top_z}, {left_x, left_z}},
                             {{0, 1, 2, 3}, {4, 7, 6, 5}},
                             {{0, 1, 4}, {1, 2, 5}, {1, 5, 4}, {2, 3, 6}, {2, 6, 5}, {3, 0, 7}, {3, 7, 6}, {0, 4, 7}},
                             length);
    const Mesh tunnel = transformed(block, scale, shift);
    if (validate_mesh(tunnel).summary() != "valid") continue;
    ++tunnels;
    INFO("seed " << seed);
    const Vec3 end = tunnel.positions[4];
    Tally tally;
    check_cut(tunnel, {{0, 0, 1}, -end.z}, tally);
    CHECK(tally.pieces == 2);
    separated += tally.separated;
    const Vec3 n = random.direction();
    const Plane cuts[] = {{{0, 0, 1}, -end.z}, {n, -dot(n, end)}};
    const PlaneInput input = prepare_plane_input(tunnel);
    const PlaneSet set = input.geometry.plane_set(cuts);
    const PlaneCut first = cut_by_plane(input, set, input.solid, &input.mesh, PlaneRef::cut(0));
    for (const CutPiece& piece : first.pieces) {
      if (!piece.above) continue;
      const PlaneCut second = cut_by_plane(input, set, piece.solid, nullptr, PlaneRef::cut(1));
      mpq_class six = 0;
      for (const CutPiece& part : second.pieces) {
        check_exact_piece(set, part.solid);
        six += exact_six_volume(set, part.solid);
        if (part.vanished) continue;
        CHECK(part.defect == "");
        CHECK(validate_mesh(part.mesh).valid());
        ++again;
      }
      if (!second.plane_missed) CHECK(six == exact_six_volume(set, piece.solid));
    }
  }
  CHECK(tunnels >= 16);
  CHECK(separated == tunnels);
  CHECK(again >= tunnels);
}

TEST_CASE("regression: the saddle planes of issue 17 write valid pieces, separated where they touched", "[plane][cut][regression]") {
  // `shatter slice helmet.off --plane 0,1,0,-0.014781300000000001` and
  // `shatter slice torus_quad.off --plane 1,1,0,-0.25782700000000003` exited 3:
  // each plane holds a saddle vertex whose two lobes below are one piece, which
  // touches itself there (a cap face whose hole touches its outer loop at the
  // vertex; two cap faces meeting at it), so no mesh of it is valid.
  for (const auto& [file, plane] : {std::pair{"helmet.off", Plane{{0, 1, 0}, -0.014781300000000001}},
                                    std::pair{"torus_quad.off", Plane{{1, 1, 0}, -0.25782700000000003}}}) {
    INFO(file);
    Tally tally;
    check_cut(read_mesh(mesh_dir() / file), plane, tally);
    CHECK(tally.pieces == 2);
    CHECK(tally.separated == 1);
  }
}

namespace {

// `count` planes through vertices of each corpus mesh (planes_through_vertices).
Tally check_corpus_vertex_planes(std::size_t count) {
  Tally tally;
  for (const auto& path : valid_meshes()) {
    const Mesh mesh = read_mesh(path);
    for (const Plane& plane : planes_through_vertices(mesh, count, 17)) {
      INFO(path.filename().string() << " plane " << plane.normal.x << " " << plane.normal.y << " " << plane.normal.z
                                    << " " << plane.offset);
      check_cut(mesh, plane, tally);
    }
  }
  return tally;
}

}  // namespace

// The same property at a size CI runs on every change (under the sanitizers, 2
// planes a mesh); the 30 planes a mesh below are the [heavy] run's.
TEST_CASE("planes through vertices of every corpus mesh: no refusal, every piece valid or vanished", "[plane][cut]") {
  const std::size_t count = sized(6, 2);
  const Tally tally = check_corpus_vertex_planes(count);
  CHECK(tally.cuts == count * valid_meshes().size());
}

TEST_CASE("30 planes through vertices of every corpus mesh: none refused, both repairs exercised",
          "[plane][cut][heavy]") {
  // Measured 2026-12-02: before points where a piece touches itself were
  // separated, `shatter slice` exited 3 on 7 of these 390 planes (5 saddle
  // vertices, 2 pieces thinner than their rounding); now on none.
  const Tally tally = check_corpus_vertex_planes(30);
  INFO(tally.cuts << " cuts, " << tally.pieces << " pieces, " << tally.separated << " separated, " << tally.vanished
                  << " vanished");
  CHECK(tally.cuts == 30 * valid_meshes().size());
  CHECK(tally.separated >= 1);
  CHECK(tally.vanished >= 1);
}

namespace {

// cut_solid's result in an arena of `threads` threads, or its refusal's line.
struct CutOrRefusal {
  SolidCut cut;
  std::string refusal;
};
CutOrRefusal cut_on(int threads, const PlaneInput& input, const PlaneSet& set) {
  tbb::task_arena arena(threads);
  return arena.execute([&] {
    CutOrRefusal result;
    try {
      result.cut = cut_solid(set, input.solid, PlaneRef::cut(0), 1, input.shells);
    } catch (const UnsupportedGeometryError& e) {
      result.refusal = e.what();
    }
    return result;
  });
}

}  // namespace

TEST_CASE("a large solid's two sides are separated in parallel: the same solids on 1 and 2 threads", "[plane][cut]") {
  // cut_solid separates the sides of a solid of 1,024 faces or more on two
  // threads; the pieces, and a refusal's line, must not depend on it.
  std::vector<NamedMesh> meshes;
  for (const auto& path : valid_meshes()) meshes.push_back({path.filename().string(), read_mesh(path)});
  meshes.push_back({"torus 64 x 32", torus(3, 1, 64, 32)});
  meshes.push_back({"ellipsoid 48 x 24", ellipsoid({0.1, 0.2, 0.3}, {1, 2, 3}, 48, 24)});
  std::size_t large = 0, cuts = 0;
  for (const NamedMesh& m : meshes) {
    const PlaneInput input = prepare_plane_input(m.mesh);
    if (input.solid.faces.size() < 1024) continue;
    ++large;
    for (const Plane& plane : planes_through_vertices(m.mesh, sized(4, 2), 29)) {
      INFO(m.name << " plane " << plane.normal.x << " " << plane.normal.y << " " << plane.normal.z << " " << plane.offset);
      const Plane planes[] = {plane};
      const PlaneSet set = input.geometry.plane_set(planes);
      const CutOrRefusal one = cut_on(1, input, set), two = cut_on(2, input, set);
      REQUIRE(one.refusal == two.refusal);
      REQUIRE(one.cut.plane_missed == two.cut.plane_missed);
      REQUIRE(same_solids(one.cut.below, two.cut.below));
      REQUIRE(same_solids(one.cut.above, two.cut.above));
      if (!one.cut.below.empty() && !one.cut.above.empty()) ++cuts;
    }
  }
  CHECK(large >= 3);
  CHECK(cuts >= 2 * large);
}

TEST_CASE("a cavity's corner on the cut: the piece around it is written, the corner moved off the cap", "[plane][cut]") {
  // A box with a cavity shaped as an octahedron whose lowest corner lies on the
  // plane z = 0 inside the box: the piece above touches the cap at that corner.
  for (const double size : {1.0, 1e-3, 1e6}) {
    INFO("size " << size);
    const double s = size;
    const Mesh octahedron = mesh_from({{0, 0, 0}, {s, 0, s}, {0, s, s}, {-s, 0, s}, {0, -s, s}, {0, 0, 2 * s}},
                                      {{0, 2, 1}, {0, 3, 2}, {0, 4, 3}, {0, 1, 4}, {5, 1, 2}, {5, 2, 3}, {5, 3, 4}, {5, 4, 1}});
    REQUIRE(signed_volume(octahedron) > 0);
    const Mesh mesh = merge({box({-2 * s, -2 * s, -2 * s}, {2 * s, 2 * s, 3 * s}), flipped(octahedron)});
    REQUIRE(validate_mesh(mesh).summary() == "valid");
    Tally tally;
    check_cut(mesh, Plane{{0, 0, 1}, 0}, tally);
    check_cut(mesh, Plane{{0, 0, -1}, 0}, tally);
    CHECK(tally.pieces == 4);
    CHECK(tally.separated == 2);
  }
}

TEST_CASE("a plane misses as written when every piece but one vanishes", "[plane][cut]") {
  // A plane through the corner (1, -1, 1) of the cube up to rounding cuts off a
  // tetrahedron far thinner than an ulp: it vanishes, and as written the plane
  // does not cut the cube (the mesh tree builder redraws such a plane, and no
  // other). With a second box on the tetrahedron's side, the same plane parts two
  // solids that do not vanish: it cuts, and the tetrahedron is simply no piece of
  // what is written.
  const Plane plane{{-0.51784138889905429, 0.87762787624213567, -0.40292203608095672}, 1.7983913012221466};
  const Mesh cube = read_mesh(mesh_dir() / "cube.off");
  const PlaneCut alone = cut_mesh_by_plane(cube, plane);
  REQUIRE_FALSE(alone.plane_missed);
  REQUIRE(alone.pieces.size() == 2);
  CHECK(std::count_if(alone.pieces.begin(), alone.pieces.end(), [](const CutPiece& p) { return p.vanished; }) == 1);
  CHECK(alone.misses_as_written());
  Tally tally;
  check_cut(cube, plane, tally);
  CHECK(tally.vanished == 1);

  const Mesh two = merge({cube, box({9, -11, 9}, {11, -9, 11})});
  const PlaneCut parted = cut_mesh_by_plane(two, plane);
  REQUIRE(parted.pieces.size() == 3);
  CHECK(std::count_if(parted.pieces.begin(), parted.pieces.end(), [](const CutPiece& p) { return p.vanished; }) == 1);
  CHECK_FALSE(parted.misses_as_written());
  check_cut(two, plane, tally);
  CHECK(tally.vanished == 2);
  // A plane that misses exactly misses as written too.
  const PlaneCut away = cut_mesh_by_plane(cube, {{1, 0, 0}, 5});
  CHECK(away.plane_missed);
  CHECK(away.misses_as_written());
}
