// The linear certificate of a rounded piece (kernel/certify.hpp) against the full
// validator: every mesh certify_piece accepts, validate_mesh finds valid. Over
// the pieces of successive random cuts of generated, degenerate and corpus
// meshes (seeds 1 to 4), each rounded as first triangulated (not repaired, so
// some are invalid) and as round_solid writes it; over those meshes with one
// vertex thrown across the piece (mostly invalid); and over surfaces made to
// fool a certificate that trusted its preconditions (two crossing shells each
// star-shaped around one centre, a surface winding twice, open and inward ones).
// How often it declines (the full check decides then) is counted, and a floor
// on what it accepts keeps the property from holding vacuously.

#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "shatter/kernel/certify.hpp"
#include "shatter/kernel/error.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/validate.hpp"
#include "shatter/triangulate/solid_mesh.hpp"
#include "shatter/generators/corpus.hpp"
#include "shatter/generators/random.hpp"
#include "shatter/generators/solids.hpp"
#include "support/plane_pieces.hpp"

using namespace shatter;
using namespace shatter::test;

namespace {

struct Tally {
  std::size_t meshes = 0, accepted = 0, declined = 0, valid_declined = 0, accepted_not_convex = 0;
};

// certify_piece on one mesh: accepted only if validate_mesh finds it valid.
// `sound_by_construction`: a triangulation of a piece's exact faces over their
// own vertices (moved or not), whose topology round_solid does not check:
// checked here, and the certificate told so must decide as the one that checks.
void check_certificate(const Mesh& mesh, bool convex, Tally& tally, bool sound_by_construction = false) {
  ++tally.meshes;
  const bool accepted = certify_piece(mesh);
  if (sound_by_construction) {
    CHECK(is_closed_oriented_manifold(mesh));
    CHECK(certify_piece(mesh, true) == accepted);
  }
  if (accepted) {
    ++tally.accepted;
    tally.accepted_not_convex += !convex;
    CHECK(validate_mesh(mesh).summary() == "valid");
  } else {
    ++tally.declined;
    tally.valid_declined += validate_mesh(mesh).valid();
  }
}

// The mesh with vertex v moved to the mirror image of its position through the
// vertex average: thrown across the piece, which leaves most meshes invalid.
Mesh thrown_across(const Mesh& mesh, std::size_t v) {
  Mesh moved = mesh;
  Vec3 average;
  for (const Vec3& p : mesh.positions) average = average + p;
  average = average * (1.0 / static_cast<double>(mesh.positions.size()));
  moved.positions[v] = average * 2.0 - mesh.positions[v];
  return moved;
}

}  // namespace

TEST_CASE("certify_piece accepts only meshes the full validator finds valid, over the pieces of random cuts",
          "[certify][plane][property]") {
  Tally tally;
  const std::size_t counts_before = certify_counts().attempts;
  for (const NamedMesh& mesh : part_test_meshes(3000)) {
    for (const std::uint64_t seed : {1, 2, 3, 4}) {
      Random random(seed * 7919);
      for (const PlanePiece& piece : plane_pieces(mesh, seed, 5, 10)) {
        INFO(piece.name << " seed " << seed << " depth " << piece.depth);
        const PlaneSet set = piece.set();
        Mesh first;
        try {
          first = triangulate_solid(set, piece.solid);
        } catch (const UnsupportedGeometryError&) {
          continue;  // a face that cannot be triangulated: nothing to certify
        }
        check_certificate(first, piece.solid.convex, tally, true);
        const RoundedSolid rounded = round_solid(set, piece.solid);
        if (rounded.valid) check_certificate(rounded.mesh, piece.solid.convex, tally);
        if (!first.positions.empty()) {
          check_certificate(thrown_across(first, random.index(first.positions.size())), piece.solid.convex, tally, true);
        }
      }
    }
  }
  INFO(tally.meshes << " meshes: " << tally.accepted << " accepted (" << tally.accepted_not_convex
                    << " of pieces not known convex), " << tally.declined << " declined (" << tally.valid_declined
                    << " of them valid: the full check decides those)");
  CHECK(certify_counts().attempts - counts_before >= tally.meshes);
  // Floors at about two thirds of what this matrix measured (2026-12-06: 3,120
  // meshes, 1,082 accepted, 484 of them of pieces not known convex; 2,038
  // declined. Before the kernel's deepest point was tried as a third centre,
  // 2026-12-03: 790 accepted, 214 not known convex; 2,330 declined, 1,411 of
  // those valid).
  CHECK(tally.accepted >= 720);
  CHECK(tally.accepted_not_convex >= 320);
  CHECK(tally.declined >= 1350);
}

TEST_CASE("certify_piece declines surfaces that only a check of its preconditions tells from a solid",
          "[certify]") {
  // Two ellipsoids around one centre, crossing each other: each alone is
  // star-shaped around the centre and winds once around every ray, so only the
  // connectivity check tells the two from one solid.
  const Mesh crossing = merge({ellipsoid({0, 0, 0}, {2, 1, 1}, 16, 12), ellipsoid({0, 0, 0}, {1, 2, 1}, 16, 12)});
  REQUIRE_FALSE(validate_mesh(crossing).valid());
  CHECK_FALSE(certify_piece(crossing));
  CHECK_FALSE(connected_surface(crossing));
  // Nested shells, both facing out: the same.
  const Mesh nested = merge({ellipsoid({0, 0, 0}, {2, 2, 2}, 16, 12), ellipsoid({0, 0, 0}, {1, 1, 1}, 16, 12)});
  CHECK_FALSE(certify_piece(nested));
  // Told the topology is sound (it is, shell by shell), the certificate still
  // finds two shells: the ray meets two cones, or the walk's connectivity test fails.
  REQUIRE(is_closed_oriented_manifold(crossing));
  CHECK_FALSE(certify_piece(crossing, true));
  CHECK_FALSE(certify_piece(nested, true));
  // Open: a triangle removed from a valid star-shaped solid.
  Mesh open = ellipsoid({0.5, 0, 0}, {1, 2, 3}, 16, 12);
  REQUIRE(certify_piece(open));
  open.triangles.pop_back();
  open.surfaces.pop_back();
  CHECK_FALSE(certify_piece(open));
  // Inward: every triangle faces its centre.
  CHECK_FALSE(certify_piece(flipped(ellipsoid({0, 0, 0}, {1, 2, 3}, 16, 12))));
  // Out-of-range indices and non-finite coordinates are declined, not read.
  Mesh broken = box({0, 0, 0}, {1, 1, 1});
  broken.triangles[0][0] = 1000;
  CHECK_FALSE(certify_piece(broken));
  Mesh infinite = box({0, 0, 0}, {1, 1, 1});
  infinite.positions[0].x = INFINITY;
  CHECK_FALSE(certify_piece(infinite));
  // A NaN is declined without raising a floating-point flag (the tests trap the
  // invalid operation an ordered comparison of a NaN raises; it once did here).
  Mesh not_a_number = box({0, 0, 0}, {1, 1, 1});
  not_a_number.positions[3].y = std::numeric_limits<double>::quiet_NaN();
  CHECK_FALSE(certify_piece(not_a_number));
  CHECK_FALSE(certify_piece(Mesh{}));
  // Self-intersecting corpus meshes: never accepted.
  for (const auto& path : self_intersecting_meshes()) {
    INFO(path.filename().string());
    CHECK_FALSE(certify_piece(read_mesh(path)));
  }
  // A torus is valid but star-shaped around no point: declined, for the full check.
  const Mesh ring = torus(3, 1, 16, 8);
  REQUIRE(validate_mesh(ring).valid());
  CHECK_FALSE(certify_piece(ring));
}

// The commands' input check tries the piece certificate before the full
// search: it must pass and refuse exactly what validate_mesh does. Over the
// parts' test meshes (generated, degenerate, corpus), each thrown across itself
// and turned inside out, the corpus's self-intersecting meshes and, read as far
// as they read, its bad ones.
TEST_CASE("require_valid_solid passes exactly the meshes validate_mesh finds valid, certified or not",
          "[certify][validate]") {
  std::vector<NamedMesh> meshes;
  std::vector<NamedMesh> sources = part_test_meshes(3000);
  // Star-shaped ones too, which the certificate is for: ellipsoids of several
  // shapes and places.
  for (int i = 0; i < 12; ++i) {
    const Vec3 centre{0.25 * i, -0.5 * (i % 3), 1e3 * (i % 2)};
    const Vec3 radii{1.0 + 0.3 * i, 2.0 - 0.1 * i, 0.5 + 0.05 * i};
    sources.push_back({"ellipsoid " + std::to_string(i), ellipsoid(centre, radii, 8 + i, 6 + i)});
  }
  for (NamedMesh& named : sources) {
    meshes.push_back({named.name + " thrown across", thrown_across(named.mesh, named.mesh.positions.size() / 2)});
    meshes.push_back({named.name + " inside out", flipped(named.mesh)});
    meshes.push_back(std::move(named));
  }
  for (const auto& path : self_intersecting_meshes()) meshes.push_back({path.filename().string(), read_mesh(path)});
  for (const auto& path : bad_meshes()) {
    try {
      meshes.push_back({path.filename().string(), read_mesh(path)});
    } catch (const std::exception&) {
      // refused by the reader: nothing for the check to see
    }
  }
  std::size_t certified = 0, passed = 0, refused = 0;
  for (const NamedMesh& named : meshes) {
    if (named.mesh.triangles.empty()) continue;
    INFO(named.name);
    const ValidationReport report = validate_mesh(named.mesh);
    certified += certify_piece(named.mesh);
    if (report.valid()) {
      CHECK_NOTHROW(require_valid_solid(named.mesh, named.name, false));
      ++passed;
    } else {
      CHECK_THROWS_AS(require_valid_solid(named.mesh, named.name, false), InvalidMeshError);
      ++refused;
    }
  }
  INFO(meshes.size() << " meshes: " << passed << " passed (" << certified << " certified), " << refused << " refused");
  CHECK(certified >= 15);
  CHECK(passed > certified);  // some valid meshes reach the full check
  CHECK(refused >= 60);
}
