// The plane kernel's rounding and certification of a solid
// (triangulate/solid_mesh.hpp): pieces of cuts through a vertex up to rounding,
// the issue that introduced the kernel, are rounded once and written as meshes
// that validate when read back. (Every written piece of every other plane-kernel
// test is checked the same way: support/written_back.hpp.) Every face of input
// solids and cut pieces, convex or not, with holes or not, is triangulated by
// triangulate_face, at every attempt, into triangles judged in rationals: each
// counter-clockwise seen from outside (none flat), their areas summing to the
// face's, their edges the face's boundary once and inner edges in both
// directions, k - 2 + 2 h of them; and the faces' fans give the solid's volume.
// Pieces rounding breaks (slivers between near-parallel cuts, planes ulps off a
// face, a pinched saddle) are repaired or vanish whole, each within the volume
// bound round_solid reports, over 96 seeds.

#include <catch2/catch.hpp>

#include <gmpxx.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>
#include <vector>

#include "shatter/kernel/io.hpp"
#include "shatter/kernel/rationals.hpp"
#include "shatter/kernel/solid.hpp"
#include "shatter/kernel/validate.hpp"
#include "shatter/cut/cut_solid.hpp"
#include "shatter/cut/plane_input.hpp"
#include "shatter/triangulate/solid_mesh.hpp"
#include "shatter/generators/corpus.hpp"
#include "shatter/generators/random.hpp"
#include "shatter/generators/solids.hpp"
#include "support/checks.hpp"
#include "support/exact_faces.hpp"
#include "support/plane_pieces.hpp"
#include "support/sanitizers.hpp"
#include "support/written_back.hpp"

using namespace shatter;
using namespace shatter::test;

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

namespace {

struct TriangulationTally {
  std::size_t faces = 0, triangle_faces = 0, convex_faces = 0, other_faces = 0, faces_with_holes = 0, triangles = 0,
              attempts = 0, convex_without_fan = 0;
};

// Every property of triangulate_face on one face at one attempt. `h`, `p`: the
// solid's vertices exactly (support/exact_faces.hpp).
void check_face_triangulation(const PlaneSet& set, const Solid& solid, std::uint32_t f, const std::vector<H4>& h,
                              const std::vector<Q3>& p, std::span<const Vec3> positions, std::size_t attempt,
                              TriangulationTally& tally) {
  const SolidFace& face = solid.faces[f];
  INFO("face " << f << " (" << face.loop_count << " loops, " << (face.convex ? "convex" : "not convex")
                << "), attempt " << attempt);
  // Appends: what is already there stays.
  std::vector<Triangle> out{{7, 7, 7}};
  triangulate_face(set, solid, f, positions, out, attempt);
  REQUIRE_FALSE(out.empty());
  CHECK(out.front() == Triangle{7, 7, 7});
  const std::span<const Triangle> triangles(out.data() + 1, out.size() - 1);

  std::vector<std::vector<VertexIndex>> loops;
  std::size_t corners = 0;
  for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) {
    loops.push_back(loop_vertices(solid.loops, solid.corners, l));
    corners += loops.back().size();
  }
  CHECK(triangles.size() == corners - 2 + 2 * (face.loop_count - 1));
  ++tally.attempts;
  if (attempt == 0) {
    ++tally.faces;
    tally.triangle_faces += corners == 3;
    ++(face.convex ? tally.convex_faces : tally.other_faces);
    tally.faces_with_holes += face.loop_count > 1;
    tally.triangles += triangles.size();
  }
  if (corners == 3) {
    // A triangle is its own triangulation (no arithmetic: the face is the solid's).
    REQUIRE(triangles.size() == 1);
    Triangle t = triangles.front();
    const auto at = std::find(t.begin(), t.end(), loops[0][0]);
    REQUIRE(at != t.end());
    std::rotate(t.begin(), at, t.end());
    CHECK((t == Triangle{loops[0][0], loops[0][1], loops[0][2]}));
    return;
  }
  const Z4 plane = plane_z(set, face.plane);
  const int axis = dominant_axis(plane);
  std::set<VertexIndex> own;
  std::multiset<std::pair<VertexIndex, VertexIndex>> boundary;
  mpq_class face_area = 0;
  for (const auto& loop : loops) {
    face_area += twice_area_along(p, loop, axis);
    for (std::size_t i = 0; i < loop.size(); ++i) {
      own.insert(loop[i]);
      boundary.insert({loop[i], loop[(i + 1) % loop.size()]});
    }
  }
  mpq_class area = 0;
  std::size_t flat = 0, foreign = 0;
  std::map<std::pair<VertexIndex, VertexIndex>, int> edges;
  for (const Triangle& t : triangles) {
    for (const VertexIndex v : t) foreign += own.count(v) == 0;  // only the face's own vertices
    // Counter-clockwise seen from outside: never flat.
    flat += turn(plane, face.reversed, h[t[0]], h[t[1]], h[t[2]]) <= 0;
    const std::array<VertexIndex, 3> loop{t[0], t[1], t[2]};
    area += twice_area_along(p, loop, axis);
    for (int c = 0; c < 3; ++c) ++edges[{t[c], t[(c + 1) % 3]}];
  }
  REQUIRE(foreign == 0);
  CHECK(flat == 0);
  // All on the face's plane, so one component of the vector areas decides.
  CHECK(area == face_area);
  // A triangulation of the face: its boundary edges once each, as the face runs
  // them, and every other edge once in each direction.
  std::size_t boundary_found = 0, repeated = 0, unpaired = 0;
  for (const auto& [edge, count] : edges) {
    repeated += count != 1;
    if (boundary.count(edge) != 0) {
      ++boundary_found;
    } else {
      unpaired += edges.count({edge.second, edge.first}) != 1;
    }
  }
  CHECK(repeated == 0);
  CHECK(unpaired == 0);
  CHECK(boundary_found == boundary.size());
  if (face.convex && face.loop_count == 1) {
    // A convex face is a fan whenever some corner's fan has no flat triangle
    // (with collinear corners, none may).
    const std::vector<VertexIndex>& loop = loops[0];
    bool fan_exists = false;
    for (std::size_t apex = 0; apex < loop.size() && !fan_exists; ++apex) {
      bool valid = true;
      for (std::size_t i = 1; i + 1 < loop.size() && valid; ++i) {
        valid = turn(plane, face.reversed, h[loop[apex]], h[loop[(apex + i) % loop.size()]],
                     h[loop[(apex + i + 1) % loop.size()]]) > 0;
      }
      fan_exists = valid;
    }
    std::map<VertexIndex, std::size_t> uses;
    for (const Triangle& t : triangles) {
      for (const VertexIndex v : t) ++uses[v];
    }
    const bool is_fan = std::any_of(uses.begin(), uses.end(), [&](const auto& u) { return u.second == triangles.size(); });
    if (fan_exists) CHECK(is_fan);
    tally.convex_without_fan += !fan_exists && attempt == 0;
  }
}

void run_triangulation_matrix(std::size_t corpus_limit, std::initializer_list<std::uint64_t> seeds, int cuts,
                              std::size_t max_pieces) {
  TriangulationTally tally;
  std::size_t solids = 0;
  for (const NamedMesh& mesh : part_test_meshes(corpus_limit)) {
    for (const std::uint64_t seed : seeds) {
      for (const PlanePiece& piece : plane_pieces(mesh, seed, cuts, max_pieces)) {
        INFO(piece.name << " seed " << seed);
        const PlaneSet set = piece.set();
        const Solid& solid = piece.solid;
        const std::vector<H4> h = homogeneous_points(set, solid.defs);
        std::vector<Q3> p;
        for (const H4& point : h) p.push_back(rational(point));
        std::vector<Vec3> rounded, approximate_positions;
        for (std::size_t v = 0; v < solid.defs.size(); ++v) {
          rounded.push_back(output_position(set, solid.defs[v], solid.approx[v]));
          const ApproxPoint& a = solid.approx[v];
          approximate_positions.push_back({a.x.value / a.w.value, a.y.value / a.w.value, a.z.value / a.w.value});
        }
        // Attempts 0 and 2 guided by the rounded positions, 1 and 3 by the
        // approximations: the guide may differ, the result must not be wrong.
        for (std::uint32_t f = 0; f < solid.faces.size(); ++f) {
          for (std::size_t attempt = 0; attempt < 4; ++attempt) {
            check_face_triangulation(set, solid, f, h, p, attempt % 2 == 0 ? rounded : approximate_positions, attempt,
                                     tally);
          }
        }
        // The faces' fans give the volume within the rounding of the vertices
        // (mass.hpp: relative error of order 1e-15 times area x size / volume;
        // 64 ulps of the largest coordinate times the area allows that).
        const double exact = exact_six_volume(set, solid).get_d() / 6;
        const MassProperties mass = solid_mass_properties(solid);
        Mesh approximate_mesh;
        approximate_mesh.positions = approximate_positions;
        double area = 0;
        for (const SolidFace& face : solid.faces) {
          const Q3 twice = twice_face_area(p, solid.loops, solid.corners, face);
          area += std::sqrt(dotq(twice, twice).get_d()) / 2;
        }
        const Box3 box = bounds(approximate_mesh);
        const double size = std::max(norm(box.hi - box.lo), largest_coordinate(approximate_mesh));
        CHECK(std::fabs(mass.volume - exact) <= 64 * std::numeric_limits<double>::epsilon() * area * size);
        ++solids;
      }
    }
  }
  INFO(solids << " solids, " << tally.faces << " faces (" << tally.triangle_faces << " triangles, "
              << tally.convex_faces << " convex, " << tally.convex_without_fan << " of them with no valid fan, "
              << tally.other_faces << " not convex, " << tally.faces_with_holes << " with holes), " << tally.triangles
              << " triangles");
  // Floors at about two thirds of what the smaller matrix measured (2026-12-02).
  CHECK(solids >= 160);
  CHECK(tally.attempts == 4 * tally.faces);
  CHECK(tally.other_faces >= 180);
  CHECK(tally.faces_with_holes >= 25);
  CHECK(tally.convex_faces - tally.triangle_faces >= 3000);
  CHECK(tally.convex_without_fan >= 100);
}

}  // namespace

TEST_CASE("triangulate_face: every face of input solids and cut pieces, every attempt, exact triangles",
          "[plane][triangulate][property]") {
  run_triangulation_matrix(500, {5, 6}, 4, 6);
}

TEST_CASE("triangulate_face, the larger matrix: corpus meshes to 2,000 triangles, deeper pieces, seeds 5 to 8",
          "[plane][triangulate][property][heavy]") {
  run_triangulation_matrix(2000, {5, 6, 7, 8}, 6, 10);
}

namespace {

// What round_solid did to the pieces of a family of cuts, counted by outcome.
struct RoundingTally {
  std::size_t pieces = 0, plain = 0, collapsed = 0, flattened_parts = 0, separated = 0, folded = 0, inserted = 0, refused = 0;
  std::size_t wedges = 0;  ///< written after faces were split where they leave rounding's reach of a cap
  std::size_t later_attempt = 0;  ///< certified as a plain triangulation at attempt 1 to 3
};

// RoundedSolid::attempt and SolidMeshOptions::face_attempts: a mesh certified
// as a plain triangulation at some attempt is written again, bit for bit, at
// the first attempt when every face is given that attempt (what a union of
// pieces asks for its faces); faces given attempt 0 change nothing; a list of
// the wrong length is refused.
void check_face_attempts(const PlaneSet& set, const Solid& piece, const RoundedSolid& rounded, RoundingTally& tally) {
  SolidMeshOptions zero;
  const std::vector<std::uint8_t> zeros(piece.faces.size(), 0);
  zero.face_attempts = zeros;
  const RoundedSolid again = round_solid(set, piece, zero);
  CHECK(again.valid == rounded.valid);
  CHECK(again.attempt == rounded.attempt);
  CHECK(again.mesh.positions == rounded.mesh.positions);
  CHECK(again.mesh.triangles == rounded.mesh.triangles);
  SolidMeshOptions short_list;
  const std::vector<std::uint8_t> too_few(piece.faces.size() - 1, 0);
  short_list.face_attempts = too_few;
  CHECK_THROWS_AS(round_solid(set, piece, short_list), std::invalid_argument);
  if (!rounded.valid || rounded.attempt <= 0) return;
  ++tally.later_attempt;
  SolidMeshOptions same;
  const std::vector<std::uint8_t> attempts(piece.faces.size(), static_cast<std::uint8_t>(rounded.attempt));
  same.face_attempts = attempts;
  const RoundedSolid first = round_solid(set, piece, same);
  CHECK(first.valid);
  CHECK(first.attempt == 0);
  CHECK(first.mesh.positions == rounded.mesh.positions);
  CHECK(first.mesh.triangles == rounded.mesh.triangles);
}

// RoundedSolid::mesh_vertex_of and SolidMeshOptions::face_triangles: a plain
// triangulation read back over the solid's vertices, face by face (each face's
// k - 2 + 2h triangles together, in face order), and given as every face's
// triangles, or every other face's, is written again bit for bit at the first
// attempt (what a Voronoi union asks with its parts' triangles); offsets of the
// wrong length, descending or past the triangles are refused.
// `rounded` is round_solid's with keep_vertex_map.
void check_face_triangles(const PlaneSet& set, const Solid& piece, const RoundedSolid& rounded) {
  if (!rounded.valid || rounded.attempt < 0) {
    CHECK(rounded.mesh_vertex_of.empty());
    return;
  }
  REQUIRE(rounded.mesh_vertex_of.size() == piece.defs.size());
  std::vector<VertexIndex> solid_vertex_of(rounded.mesh.positions.size(), no_index);
  for (VertexIndex v = 0; v < piece.defs.size(); ++v) {
    REQUIRE(rounded.mesh_vertex_of[v] < solid_vertex_of.size());
    CHECK(solid_vertex_of[rounded.mesh_vertex_of[v]] == no_index);  // one solid vertex each
    solid_vertex_of[rounded.mesh_vertex_of[v]] = v;
  }
  std::vector<Triangle> over_solid;
  for (const Triangle& t : rounded.mesh.triangles) {
    over_solid.push_back({solid_vertex_of[t[0]], solid_vertex_of[t[1]], solid_vertex_of[t[2]]});
  }
  std::vector<std::uint32_t> first{0}, every_other{0};
  std::vector<Triangle> some;
  for (std::uint32_t f = 0; f < piece.faces.size(); ++f) {
    std::size_t corners = 0;
    for (std::uint32_t l = piece.faces[f].first_loop; l < piece.faces[f].first_loop + piece.faces[f].loop_count; ++l) {
      corners += piece.loops[l].corner_count;
    }
    const auto count = static_cast<std::uint32_t>(corners + 2 * piece.faces[f].loop_count - 4);
    first.push_back(first.back() + count);
    if (f % 2 == 0) some.insert(some.end(), over_solid.begin() + first[f], over_solid.begin() + first[f + 1]);
    every_other.push_back(static_cast<std::uint32_t>(some.size()));
  }
  REQUIRE(first.back() == over_solid.size());
  const std::vector<std::uint8_t> attempts(piece.faces.size(), static_cast<std::uint8_t>(rounded.attempt));
  // Rounded with `given`, the piece's first attempt writes the same mesh again.
  const auto writes_it_again = [&](const SolidMeshOptions& given) {
    const RoundedSolid again = round_solid(set, piece, given);
    CHECK(again.valid);
    CHECK(again.attempt == 0);
    CHECK(again.mesh.positions == rounded.mesh.positions);
    CHECK(again.mesh.triangles == rounded.mesh.triangles);
  };
  for (const auto& [triangles, offsets] : {std::pair{&over_solid, &first}, std::pair{&some, &every_other}}) {
    SolidMeshOptions given;
    given.face_attempts = attempts;
    given.face_triangles = *triangles;
    given.face_triangles_first = *offsets;
    writes_it_again(given);
  }
  // Certified as a union of one part, its own first rounding, told where each
  // triangle came from (rightly, or each from the next triangle): the same mesh.
  std::vector<std::uint64_t> right_origins, shifted_origins;
  for (std::uint64_t t = 0; t < over_solid.size(); ++t) {
    right_origins.push_back(t);
    shifted_origins.push_back((t + 1) % over_solid.size());
  }
  const std::array<const Mesh*, 1> own{&rounded.mesh};
  for (const std::vector<std::uint64_t>* origins : {&right_origins, &shifted_origins}) {
    SolidMeshOptions given;
    given.face_attempts = attempts;
    given.face_triangles = over_solid;
    given.face_triangles_first = first;
    given.face_triangle_origins = *origins;
    given.parts = own;
    writes_it_again(given);
  }
  SolidMeshOptions wrong;
  wrong.face_triangles = over_solid;
  wrong.face_triangles_first = first;
  const std::vector<std::uint64_t> short_origins(right_origins.begin(), right_origins.end() - 1);
  wrong.face_triangle_origins = short_origins;
  CHECK_THROWS_AS(round_solid(set, piece, wrong), std::invalid_argument);
  wrong.face_triangle_origins = {};
  const std::vector<std::uint32_t> short_offsets(first.begin(), first.end() - 1);
  wrong.face_triangles_first = short_offsets;
  CHECK_THROWS_AS(round_solid(set, piece, wrong), std::invalid_argument);
  std::vector<std::uint32_t> past = first;
  past.back() += 1;
  wrong.face_triangles_first = past;
  CHECK_THROWS_AS(round_solid(set, piece, wrong), std::invalid_argument);
  if (first.size() > 2) {
    std::vector<std::uint32_t> descending = first;
    std::swap(descending[1], descending[2]);
    if (descending[1] != descending[2]) {
      wrong.face_triangles_first = descending;
      CHECK_THROWS_AS(round_solid(set, piece, wrong), std::invalid_argument);
    }
  }
}

// Six times the volume of a mesh of doubles, exactly.
mpq_class six_volume_of(const Mesh& mesh) {
  mpq_class six = 0;
  for (const Triangle& t : mesh.triangles) {
    const Vec3 &a = mesh.positions[t[0]], &b = mesh.positions[t[1]], &c = mesh.positions[t[2]];
    const mpq_class ax(a.x), ay(a.y), az(a.z), bx(b.x), by(b.y), bz(b.z), cx(c.x), cy(c.y), cz(c.z);
    six += ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx);
  }
  return six;
}

// Every promise of round_solid on one piece: valid exactly when the mesh passes
// validate_mesh; a collapsed piece has no triangles and reports its own exact
// volume as moved, within the bound of what its rounding can move; a piece
// written after parts of it rounded flat (or after separation) moved what its
// mesh and the exact piece disagree on, within the bound.
void check_rounding(const PlaneSet& set, const Solid& piece, RoundingTally& tally) {
  // Keeping the vertex map changes nothing else (check_face_attempts compares
  // the mesh with one rounded without it).
  SolidMeshOptions keep;
  keep.keep_vertex_map = true;
  const RoundedSolid rounded = round_solid(set, piece, keep);
  ++tally.pieces;
  check_face_attempts(set, piece, rounded, tally);
  check_face_triangles(set, piece, rounded);
  const mpq_class six = exact_six_volume(set, piece);
  REQUIRE(six > 0);
  const double volume = mpq_class(six / 6).get_d();
  if (rounded.collapsed) {
    ++tally.collapsed;
    CHECK_FALSE(rounded.valid);
    CHECK(rounded.mesh.triangles.empty());
    CHECK_FALSE(rounded.defect.empty());
    CHECK(std::fabs(rounded.moved_volume - volume) <= 1e-12 * volume);
    CHECK(volume <= rounded.moved_volume_bound * (1 + 1e-12));
    return;
  }
  if (!rounded.valid) {
    ++tally.refused;
    CHECK_FALSE(rounded.defect.empty());
    CHECK((rounded.mesh.triangles.empty() || !validate_mesh(rounded.mesh).valid()));
    return;
  }
  INFO("defect " << rounded.defect);
  CHECK(rounded.defect.empty());
  CHECK(validate_mesh(rounded.mesh).valid());
  if (rounded.vanished_triangles > 0) {
    ++tally.flattened_parts;
    CHECK(rounded.vanished_triangles % 2 == 0);
  }
  if (rounded.separated_vertices > 0) ++tally.separated;
  // Faces folded against each other merged: the volume moved is the written
  // mesh's against the exact piece (plus a separation's, when there was one),
  // and within the bound.
  if (rounded.folded_faces > 0) {
    ++tally.folded;
    CHECK(rounded.folded_faces >= 2);
  }
  // Rounded vertices inserted into faces they crossed (the piece then touches
  // itself there and is separated, or the triangles made cancel as sheets):
  // held to the same bound.
  if (rounded.inserted_vertices > 0) ++tally.inserted;
  // Faces split where they leave rounding's reach of a cap (the last repair): the
  // volume moved is the written mesh's against the exact piece, held to the
  // piece's own bound.
  if (rounded.wedge_faces_split > 0) {
    ++tally.wedges;
    const double moved = mpq_class(abs(six_volume_of(rounded.mesh) - six) / 6).get_d();
    CHECK(std::fabs(rounded.moved_volume - moved) <= 1e-12 * moved + 1e-300);
  }
  if (rounded.vanished_triangles > 0 || rounded.separated_vertices > 0 || rounded.folded_faces > 0 ||
      rounded.inserted_vertices > 0 || rounded.wedge_faces_split > 0) {
    const double moved = mpq_class(abs(six_volume_of(rounded.mesh) - six) / 6).get_d();
    if ((rounded.vanished_triangles > 0 || rounded.folded_faces > 0 || rounded.inserted_vertices > 0) &&
        rounded.separated_vertices == 0) {
      CHECK(std::fabs(rounded.moved_volume - moved) <= 1e-12 * moved + 1e-300);
    }
    CHECK(rounded.moved_volume <= rounded.moved_volume_bound * (1 + 1e-12));
    CHECK(rounded.attempt == -1);  // repaired: no plain triangulation
  } else {
    ++tally.plain;
  }
}

// Cuts the prepared input by one plane and checks every piece's rounding.
void check_cut_rounding(const PlaneInput& input, const Plane& plane, RoundingTally& tally) {
  const std::vector<Plane> cuts{plane};
  const PlaneSet set = input.geometry.plane_set(cuts);
  const SolidCut cut = cut_solid(set, input.solid, PlaneRef::cut(0), 1, input.shells);
  for (const auto* side : {&cut.below, &cut.above}) {
    for (const Solid& piece : *side) check_rounding(set, piece, tally);
  }
}

}  // namespace

TEST_CASE("round_solid: parts rounding breaks are repaired, or the piece vanishes within its bound, over 96 seeds",
          "[plane][round]") {
  // Chains of near-parallel planes through a mesh edge (the slivers between them
  // are thinner than their rounding near the edge), planes a few ulps off faces
  // and through the saddle of a pinched solid: the cuts whose pieces rounding
  // flattens, folds or pinches. Every piece is checked (check_rounding), and
  // every way of writing a broken piece has to be met.
  std::vector<NamedMesh> meshes;
  for (NamedMesh& m : part_test_meshes(0)) {
    if (m.mesh.triangles.size() <= 1000) meshes.push_back(std::move(m));
  }
  REQUIRE(meshes.size() >= 8);
  // By family: near-parallel chains, planes ulps off a face, the pinched saddle.
  RoundingTally families[3];
  // Under the sanitizers every other block of three seeds (one per family, the
  // meshes still all met): about half the cost, every repair still reached.
  const std::uint64_t block_stride = test::sized(1, 2);
  for (std::uint64_t seed = 0; seed < 96; ++seed) {
    if ((seed / 3) % block_stride != 0) continue;
    RoundingTally& tally = families[seed % 3];
    Random random(seed * 7919 + 17);
    const NamedMesh& m = meshes[seed % meshes.size()];
    std::vector<Plane> planes;
    const Triangle& t = m.mesh.triangles[random.index(m.mesh.triangles.size())];
    switch (seed % 3) {
      case 0: {
        const double start = std::pow(10.0, -random.uniform(1, 8));
        const double ratio = std::pow(10.0, -random.uniform(0.5, 3));
        // Drawn one statement each: the order a call evaluates its arguments in is
        // unspecified (GCC and Clang differ), and the sanitized build must test the
        // same cases as the Release one.
        const Vec3 tilt = random.direction();
        const int count = 2 + int(random.index(2));
        planes = near_parallel_fan(m.mesh.positions[t[0]], m.mesh.positions[t[1]], tilt, count, start, ratio);
        break;
      }
      case 1: {
        const Plane face = plane_through_points(m.mesh.positions[t[0]], m.mesh.positions[t[1]], m.mesh.positions[t[2]]);
        planes.push_back(offset_by_ulps(face, int(random.index(9)) - 4));
        break;
      }
      default: {
        // Through the saddle of pinch_saddle, tilted, a few ulps off.
        const Mesh saddle = pinch_saddle();
        Plane plane = plane_through({1, 1, 0}, {double(random.index(3)) - 1, double(random.index(3)) - 1, 4});
        plane = offset_by_ulps(plane, int(random.index(9)) - 4);
        const PlaneInput input = prepare_plane_input(saddle);
        const std::vector<Plane> cuts{plane};
        const PlaneSet set = input.geometry.plane_set(cuts);
        const SolidCut cut = cut_solid(set, input.solid, PlaneRef::cut(0), 1, input.shells);
        for (const auto* side : {&cut.below, &cut.above}) {
          for (const Solid& piece : *side) check_rounding(set, piece, tally);
        }
        continue;
      }
    }
    INFO(m.name << ", seed " << seed);
    const PlaneInput input = prepare_plane_input(m.mesh);
    const PlaneSet set = input.geometry.plane_set(planes);
    std::vector<Solid> pieces{input.solid};
    for (std::size_t i = 0; i < planes.size(); ++i) {
      std::vector<Solid> next;
      for (const Solid& solid : pieces) {
        const SolidCut cut = cut_solid(set, solid, PlaneRef::cut(static_cast<std::uint32_t>(i)), SurfaceId(i + 1),
                                       input.shells);
        if (cut.plane_missed) {
          next.push_back(solid);
          continue;
        }
        for (const auto* side : {&cut.below, &cut.above}) {
          for (const Solid& piece : *side) {
            check_rounding(set, piece, tally);
            next.push_back(piece);
          }
        }
      }
      pieces = std::move(next);
    }
  }
  RoundingTally tally;
  for (const RoundingTally& f : families) {
    INFO("family: pieces " << f.pieces << ", written as rounded " << f.plain << ", vanished " << f.collapsed
                           << ", written after parts rounded flat " << f.flattened_parts << ", separated "
                           << f.separated << ", refused " << f.refused);
    CHECK(f.pieces > 0);
    tally.pieces += f.pieces, tally.plain += f.plain, tally.collapsed += f.collapsed;
    tally.flattened_parts += f.flattened_parts, tally.separated += f.separated, tally.refused += f.refused;
    tally.folded += f.folded, tally.inserted += f.inserted, tally.later_attempt += f.later_attempt;
  }
  INFO("pieces " << tally.pieces << ", written as rounded " << tally.plain << ", vanished " << tally.collapsed
                 << ", written after parts rounded flat " << tally.flattened_parts << ", separated "
                 << tally.separated << ", folds merged " << tally.folded << ", vertices inserted " << tally.inserted << ", refused " << tally.refused);
  CHECK(tally.pieces > test::sized(300, 150));
  // The repairs this family meets, each at least once, so the test cannot pass
  // by testing nothing (parts rounded flat inside a written piece are met by the
  // regression reproducers of tests/regressions, not here).
  CHECK(tally.collapsed > 0);
  CHECK(tally.separated > 0);
  CHECK(tally.folded > 0);
  CHECK(tally.inserted > 0);
  CHECK(tally.later_attempt > 0);  // face_attempts is met on pieces that need it
  // What is left unrepaired: folds of thick pieces against a nearly coplanar
  // face, a ceiling measured 2026-12-03, the same in the Release (GCC) and the
  // sanitized (Clang) builds since the near-parallel fans draw their random
  // numbers in a fixed order: 2 since round_solid's last round snaps vertices
  // closer than a pixel together (the ceiling was 8 before). On the cases GCC's
  // argument order drew before: 7;
  // 9 before round_solid inserted rounded vertices into faces they crossed, 14
  // before it merged faces rounding folded against each other, 20 before it
  // untangled non-manifold edges and routed edges through corners carried across
  // them.
  CHECK(tally.refused <= 2);
}

namespace {

// The piece and plane of a reproducer of tests/regressions (a slice of a mesh
// given inline, `mesh-obj N` followed by N bytes of OBJ).
struct SliceCase {
  Mesh mesh;
  Plane plane;
};

SliceCase read_slice_reproducer(const std::string& name) {
  const std::filesystem::path path = test::mesh_dir().parent_path().parent_path() / "regressions" / name;
  std::ifstream in(path, std::ios::binary);
  REQUIRE(in);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  SliceCase c;
  const std::size_t plane = text.find("\nplane ");
  REQUIRE(plane != std::string::npos);
  // Hexadecimal doubles without the 0x (as the reproducers write them).
  std::istringstream line(text.substr(plane + 7, text.find('\n', plane + 1) - plane - 7));
  double v[4];
  for (double& x : v) {
    std::string token;
    REQUIRE(line >> token);
    const bool negative = token[0] == '-';
    const std::string hex = "0x" + token.substr(negative ? 1 : 0);
    char* end = nullptr;
    x = std::strtod(hex.c_str(), &end);
    REQUIRE(end == hex.c_str() + hex.size());
    if (negative) x = -x;
  }
  c.plane = Plane{{v[0], v[1], v[2]}, v[3]};
  const std::size_t obj = text.find("\nmesh-obj ");
  REQUIRE(obj != std::string::npos);
  const std::size_t size_end = text.find('\n', obj + 1);
  const std::size_t size = std::stoul(text.substr(obj + 10, size_end - obj - 10));
  REQUIRE(size_end + 1 + size <= text.size());
  c.mesh = read_mesh_from_bytes(std::string_view(text).substr(size_end + 1, size), MeshFormat::obj);
  return c;
}

}  // namespace

TEST_CASE("round_solid: wedges beyond rounding's reach of a cap are split and collapse, over 24 seeds",
          "[plane][round]") {
  // Pieces of near-parallel chains as written in doubles (an egg far from the
  // origin, a huge torus, a sphere: the fuzz's corpus cases 700, 1372 and 1084),
  // cut by the chain's next plane moved by -4 to 3 ulps of its offset: the cap
  // folds against clipped faces of the earlier cap that lie nearly in its plane
  // and leave rounding's reach, which no round but the last repairs. Every piece
  // is checked (check_rounding: valid as written, or vanished within its bound;
  // the volume the split and merge moved measured exactly and within the bound).
  const char* const files[] = {
      "unroundable-wedge-beyond-reach-split-near-parallel-chain-corpus-700.repro",
      "unroundable-wedge-beyond-reach-split-near-parallel-chain-corpus-1372.repro",
      "unroundable-wedge-beyond-reach-split-near-parallel-chain-corpus-1084.repro",
  };
  std::vector<SliceCase> cases;
  for (const char* file : files) cases.push_back(read_slice_reproducer(file));
  RoundingTally tally;
  // Under the sanitizers every other offset (-4, -2, 0, 2 ulps) of each piece.
  const std::uint64_t offset_stride = test::sized(1, 2);
  for (std::uint64_t seed = 0; seed < 24; ++seed) {
    if ((seed / 3) % offset_stride != 0) continue;
    const SliceCase& c = cases[seed % 3];
    const int ulps = static_cast<int>(seed / 3) - 4;
    INFO(files[seed % 3] << ", plane offset by " << ulps << " ulps");
    check_cut_rounding(prepare_plane_input(c.mesh), offset_by_ulps(c.plane, ulps), tally);
  }
  INFO("pieces " << tally.pieces << ", written as rounded " << tally.plain << ", vanished " << tally.collapsed
                 << ", folds merged " << tally.folded << ", wedges split " << tally.wedges << ", refused "
                 << tally.refused);
  CHECK(tally.pieces >= test::sized(40, 20));
  CHECK(tally.wedges > 0);  // the repair is met, so the test cannot pass by testing nothing
  CHECK(tally.refused == 0);
}

TEST_CASE("regression: a wedge split where no parallel plane of doubles lies within rounding's reach (corpus 908)",
          "[plane][round][regression]") {
  // A piece of a near-parallel chain on torus-800 as written (two earlier caps
  // 3.7e-7 rad apart meeting at a tip edge), cut by the chain's next plane half an
  // ulp over the tip: the cap folds against the clipped faces of the lower cap,
  // which leave rounding's reach, but the cap's offset 1.15 has ulps of 2.2e-16,
  // more than twice the rounding move, so no plane parallel to the cap in doubles
  // lies within reach and the piece was refused. The cap's plane scaled and
  // rounded (tilted by the rounding) splits them within reach, decided exactly.
  const SliceCase c = read_slice_reproducer("unroundable-wedge-split-plane-tilted-near-parallel-chain-corpus-908.repro");
  RoundingTally tally;
  check_cut_rounding(prepare_plane_input(c.mesh), c.plane, tally);
  CHECK(tally.pieces == 2);
  CHECK(tally.wedges == 1);
  CHECK(tally.refused == 0);
  CHECK(tally.collapsed == 0);
}

namespace {

// The slice of a reproducer's piece by its plane, every piece rounded.
RoundingTally round_reproducer_pieces(const std::string& name) {
  const SliceCase c = read_slice_reproducer(name);
  RoundingTally tally;
  check_cut_rounding(prepare_plane_input(c.mesh), c.plane, tally);
  return tally;
}

}  // namespace

TEST_CASE("regression: a wedge split widened to every face by the cap, folds merged by groups (corpus 364, 988)",
          "[plane][round][regression][not-sanitized]") {
  // [not-sanitized]: 12 s of CPU in Release, 50 under the sanitizers, nearly all
  // of it in the rational arithmetic of rounds that fail before the one that
  // certifies. The widened split (split_faces_along) and the merge by groups
  // (merge_folded_faces) run under the sanitizers in the 24-seed wedge property
  // and the corpus 908 and 4060 cases (counted with gdb, 2026-12-05).
  // Pieces of near-parallel chains as written, cut by the chain's next plane. On
  // torus-huge-1e6 (364) the cap passes 0.16 of the rounding move over the tip
  // where the two earlier caps meet, nearly parallel to both: splitting only the
  // faces found folded left the tip's faces of the upper cap (facing the cap's
  // way) crossing it. On torus-800 (988) a fan of the earlier cap runs 0.01 to
  // 0.07 of the rounding move from the cap, apart from it, and the fan's
  // triangles that certification reached only once the first ones merged were
  // never split, while a sliver merged first took the cap onto its own plane.
  // Both were refused by every plane of the wedge split; splitting every face
  // with a corner within reach, and merging folds by groups (faces facing one
  // way too, when thin by their corners), certifies them.
  const RoundingTally tip =
      round_reproducer_pieces("unroundable-wedge-tip-under-the-cap-widened-split-near-parallel-chain-corpus-364.repro");
  CHECK(tip.pieces == 5);
  // Since 2026-12-07 a cut point whose homogeneous approximation is coarse next
  // to it (a torus at 1e6) is approximated in cartesian form and rounds to its
  // floating-point coordinates where they are within 2^-40: the tip's piece then
  // certifies without the wedge split, which the fan below and the wedge
  // property still take.
  CHECK(tip.wedges <= 1);
  CHECK(tip.collapsed == 1);  // a sliver above the cap, thinner than its rounding
  CHECK(tip.refused == 0);
  const RoundingTally fan =
      round_reproducer_pieces("unroundable-fan-ulps-over-the-cap-widened-split-near-parallel-chain-corpus-988.repro");
  CHECK(fan.pieces == 2);
  CHECK(fan.wedges == 1);
  CHECK(fan.collapsed == 0);
  CHECK(fan.refused == 0);
}

TEST_CASE("regression: corners rounded onto their own crossings with the cap, thin strips merged (smoke 7 case 28)",
          "[plane][round][regression][not-sanitized]") {
  // [not-sanitized]: 19 s of CPU in Release, 77 under the sanitizers (rational
  // arithmetic of the failing rounds before the strips). The strips' merge runs
  // under the sanitizers in the corpus 4060 case (ten merges).
  // A piece of a near-parallel chain on the hollow egg as written (about 2^-32
  // of its size thick), cut by the chain's next plane. Two earlier-cap vertices
  // lie 3e-17 and 5e-17 inside the piece from the new plane: their steep
  // edges' crossings snap onto them (output_point), so each vertex lands on the
  // cap's loop and the faces between it and the cap, thin by their corners, lie
  // on the cap over its own triangles; certification never names them (their
  // triangles cancel as sheets or overlap where thicker folds also cross), and
  // the wedge split's widest merge certified only by moving 8.5e-11 against a
  // bound of 3.6e-14. The strips found from the exact solid (every face reached
  // from the cap whose corners all lie within rounding's reach of its plane),
  // merged into the cap on the refined solid with crossings 2e-16 apart snapped
  // together, certify within the bound.
  const RoundingTally tally = round_reproducer_pieces(
      "unroundable-corner-on-its-own-crossings-thin-strips-near-parallel-chain-smoke7-28.repro");
  CHECK(tally.pieces == 2);
  CHECK(tally.wedges == 1);
  CHECK(tally.folded >= 1);
  CHECK(tally.collapsed == 0);
  CHECK(tally.refused == 0);
}

TEST_CASE("regression: a wedge tip across the earlier cap, split at every face meeting the cap (smoke 7 case 28, piece 0)",
          "[plane][round][regression][heavy]") {
  // [heavy]: about 11 s of CPU (the piece reaches this repair only after every
  // other round has failed, and check_rounding rounds it twice); the Release
  // suite replays the reproducer (valid as written) in about 5.
  // The same chain's other piece at that level (the hollow egg's, as written),
  // cut by the same plane: below it lies a wedge 1e-9 rad thin between the cap
  // and the earlier cap, whose tip line crosses the piece (four earlier-cap
  // corners 0.05 to 0.08 rounding moves inside the piece, the far ones 1e5 to 5e5
  // moves off). Every earlier-cap face crossing the cap is thin near its
  // crossing line; splitting only the faces found folded, or those with a corner
  // strictly inside within reach, left the others to fold once the first
  // merged, and only pixels that moved 2e-11 (bound 7e-15) certified. Split at
  // every face meeting the cap's plane as well, the band by the cap merges into
  // it: certified, 1.6e-16 moved.
  const RoundingTally tally = round_reproducer_pieces(
      "unroundable-wedge-tip-across-the-earlier-cap-split-to-the-cap-near-parallel-chain-smoke7-28-piece0.repro");
  CHECK(tally.pieces == 2);
  CHECK(tally.wedges == 1);
  CHECK(tally.collapsed == 0);
  CHECK(tally.refused == 0);
}

TEST_CASE("regression: a wedge tip across the earlier cap of a staircase, split at every face meeting the cap (corpus 4060)",
          "[plane][round][regression]") {
  // The same repair on a 16-triangle piece of a near-parallel chain on
  // staircase-4 as written, cut by the chain's next plane (refused before:
  // 2 self-intersecting pairs): the small case of the one above, which CI runs.
  const RoundingTally tally = round_reproducer_pieces(
      "unroundable-wedge-tip-across-the-earlier-cap-split-to-the-cap-near-parallel-chain-corpus-4060.repro");
  CHECK(tally.pieces == 2);
  CHECK(tally.wedges == 1);
  CHECK(tally.refused == 0);
}

TEST_CASE("round_solid: the widened wedge split certifies cuts ulps over a wedge's tip and along a fan, -4 to 4 ulps",
          "[plane][round][heavy]") {
  // [heavy]: about a minute of CPU (18 cuts; the 7 refused before this repair
  // reach it only after every other round has failed).
  // Corpus cases 364 and 988's pieces cut by their planes moved by -4 to 4 ulps
  // of the offset (on 364 each ulp moves the cap 0.14 of the rounding move, from
  // under the tip of the wedge between the earlier caps to over it; before the
  // widened split, offsets 0 to 4 of 364 and 0 and 4 of 988 were refused). Every
  // piece is checked (check_rounding: valid as written, or vanished within its
  // bound; the volume the split and merge moved measured exactly and within it).
  const char* const files[] = {
      "unroundable-wedge-tip-under-the-cap-widened-split-near-parallel-chain-corpus-364.repro",
      "unroundable-fan-ulps-over-the-cap-widened-split-near-parallel-chain-corpus-988.repro",
  };
  RoundingTally tally;
  for (const char* file : files) {
    const SliceCase c = read_slice_reproducer(file);
    const PlaneInput input = prepare_plane_input(c.mesh);
    for (int ulps = -4; ulps <= 4; ++ulps) {
      INFO(file << ", plane offset by " << ulps << " ulps");
      check_cut_rounding(input, offset_by_ulps(c.plane, ulps), tally);
    }
  }
  INFO("pieces " << tally.pieces << ", vanished " << tally.collapsed << ", wedges split " << tally.wedges
                 << ", refused " << tally.refused);
  CHECK(tally.wedges >= 6);  // the repair is met, so the test cannot pass by testing nothing
  CHECK(tally.refused == 0);
}
